//! A polyhedral mesh in OpenFOAM's face-based layout, and cell-centred fields on it.

use glam::DVec3;

use crate::MeshError;

/// A named group of boundary faces (`constant/polyMesh/boundary` in OpenFOAM).
#[derive(Clone, Debug, PartialEq)]
pub struct Patch {
    /// Patch name, e.g. `walls`, `inlet`, `outlet`.
    pub name: String,
    /// Patch type as the source names it (`wall`, `patch`, `empty`, `symmetry`, …).
    pub kind: String,
    /// First face of the patch (faces `start..start + size`).
    pub start: usize,
    /// Number of faces.
    pub size: usize,
}

/// Patch kinds that constrain the flow instead of bounding it (OpenFOAM's constraint
/// types): nothing crosses them, and a particle reaching one is mirrored.
pub const CONSTRAINT_KINDS: [&str; 4] = ["empty", "symmetry", "symmetryPlane", "wedge"];

impl Patch {
    /// Whether the patch's kind is one of [`CONSTRAINT_KINDS`].
    pub fn is_constraint(&self) -> bool {
        CONSTRAINT_KINDS.contains(&self.kind.as_str())
    }
}

/// An unstructured mesh of arbitrary polyhedral cells.
///
/// Faces are stored compressed: face `f` has the points
/// `face_points[face_offsets[f]..face_offsets[f + 1]]`, ordered so that the right-hand
/// normal points out of the owner cell (into the neighbour). Internal faces come first
/// (`0..neighbour.len()`), then the boundary faces patch by patch, as in OpenFOAM.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct PolyMesh {
    /// Point coordinates, m.
    pub points: Vec<DVec3>,
    /// Offsets into `face_points`, one per face plus one.
    pub face_offsets: Vec<u32>,
    /// Point indices of all faces, concatenated.
    pub face_points: Vec<u32>,
    /// Owner cell of every face.
    pub owner: Vec<u32>,
    /// Neighbour cell of every internal face.
    pub neighbour: Vec<u32>,
    /// Boundary patches, in face order.
    pub patches: Vec<Patch>,
    /// Number of cells.
    pub n_cells: usize,
}

impl PolyMesh {
    /// Number of faces.
    pub fn n_faces(&self) -> usize {
        self.owner.len()
    }

    /// Number of internal faces (the first ones).
    pub fn n_internal_faces(&self) -> usize {
        self.neighbour.len()
    }

    /// Point indices of face `f`.
    #[inline]
    pub fn face(&self, f: usize) -> &[u32] {
        let (a, b) = (
            self.face_offsets[f] as usize,
            self.face_offsets[f + 1] as usize,
        );
        &self.face_points[a..b]
    }

    /// Index of the patch holding boundary face `f`, if `f` is a boundary face.
    pub fn patch_of_face(&self, f: usize) -> Option<usize> {
        self.patches
            .iter()
            .position(|p| f >= p.start && f < p.start + p.size)
    }

    /// Check that the arrays are consistent (sizes, index ranges, patches covering exactly
    /// the boundary faces, every cell with at least four faces). `file` names the source in
    /// the error.
    pub fn check(&self, file: &std::path::Path) -> Result<(), MeshError> {
        let bad = |entry: &str, message: String| Err(MeshError::invalid(file, entry, message));
        let nf = self.n_faces();
        if self.face_offsets.len() != nf + 1 {
            return bad(
                "faces",
                format!(
                    "{} faces but {} owners",
                    self.face_offsets.len().saturating_sub(1),
                    nf
                ),
            );
        }
        if self.face_offsets.first() != Some(&0)
            || *self.face_offsets.last().unwrap() as usize != self.face_points.len()
        {
            return bad("faces", "face offsets do not span the point list".into());
        }
        for f in 0..nf {
            let (a, b) = (self.face_offsets[f], self.face_offsets[f + 1]);
            if b < a || b - a < 3 {
                return bad(
                    &format!("faces[{f}]"),
                    "a face needs at least 3 points".into(),
                );
            }
        }
        let np = self.points.len();
        if let Some(p) = self.face_points.iter().find(|&&p| p as usize >= np) {
            return bad("faces", format!("point index {p} out of range (0..{np})"));
        }
        if let Some((i, p)) = self.points.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return bad(&format!("points[{i}]"), format!("not finite: {p}"));
        }
        if self.neighbour.len() > nf {
            return bad(
                "neighbour",
                format!("{} neighbours for {nf} faces", self.neighbour.len()),
            );
        }
        let nc = self.n_cells;
        for (name, list) in [("owner", &self.owner), ("neighbour", &self.neighbour)] {
            if let Some((i, c)) = list.iter().enumerate().find(|(_, c)| **c as usize >= nc) {
                return bad(
                    &format!("{name}[{i}]"),
                    format!("cell {c} out of range (0..{nc})"),
                );
            }
        }
        let mut next = self.n_internal_faces();
        for p in &self.patches {
            if p.start != next {
                return bad(
                    &format!("boundary/{}", p.name),
                    format!("startFace {} where {next} was expected", p.start),
                );
            }
            next += p.size;
        }
        if next != nf {
            return bad(
                "boundary",
                format!("patches end at face {next}, the mesh has {nf} faces"),
            );
        }
        let mut faces_of = vec![0u32; nc];
        for &c in self.owner.iter().chain(&self.neighbour) {
            faces_of[c as usize] += 1;
        }
        if let Some((c, n)) = faces_of.iter().enumerate().find(|(_, n)| **n < 4) {
            return bad(
                &format!("cell {c}"),
                format!("{n} faces; a cell needs at least 4"),
            );
        }
        Ok(())
    }
}

/// A vector field with one value per cell (cell centre values), plus the values on the
/// boundary faces of each patch (`None` where the source gives none, e.g. zeroGradient).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CellField {
    /// Value in every cell, in the field's units (m/s for a velocity).
    pub cells: Vec<DVec3>,
    /// Per patch (same order as [`PolyMesh::patches`]): one value per patch face, if given.
    pub patches: Vec<Option<Vec<DVec3>>>,
}

impl CellField {
    /// `f` at the cell centres of `mesh` (`geometry` its geometry), with no patch values
    /// (the boundary takes the owner cells' values, as zeroGradient).
    pub fn at_cell_centres(
        mesh: &PolyMesh,
        geometry: &crate::MeshGeometry,
        f: impl Fn(DVec3) -> DVec3,
    ) -> CellField {
        CellField {
            cells: geometry.cell_centres.iter().map(|&c| f(c)).collect(),
            patches: vec![None; mesh.patches.len()],
        }
    }
}

/// A scalar field with one value per cell, plus the values on the boundary faces of each
/// patch (`None` where the boundary takes the owner cell's value, e.g. zeroGradient): the
/// scalar counterpart of [`CellField`], with the same conventions. Turbulence fields (`k`
/// m²/s², `epsilon` m²/s³, `omega` 1/s, `nut` m²/s) are read into one by
/// [`crate::foam::read_scalar_field`] and [`crate::vtk::read_scalar`] and used by their
/// cell values (as OpenFOAM's dispersion models read them).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct ScalarField {
    /// Value in every cell, in the field's units.
    pub cells: Vec<f64>,
    /// Per patch (same order as [`PolyMesh::patches`]): one value per patch face, if given.
    pub patches: Vec<Option<Vec<f64>>>,
}

impl ScalarField {
    /// Check that no value is negative, as for the turbulence quantities `k`, `epsilon`,
    /// `omega` and `nut` (a generic scalar may be negative; the readers do not check this).
    /// The error names `file`, the entry (`internalField[i]`, or
    /// `boundaryField/<patch>/value[i]` with the patch names of `mesh`) and the value; `name`
    /// is the field's name (`k`, …) for the message. A value that is not finite is an error
    /// too (the readers never return one).
    pub fn check_non_negative(
        &self,
        file: impl AsRef<std::path::Path>,
        name: &str,
        mesh: &PolyMesh,
    ) -> Result<(), MeshError> {
        let file = file.as_ref();
        let check = |entry: &dyn Fn(usize) -> String, v: &[f64]| match v
            .iter()
            .enumerate()
            .find(|(_, x)| !x.is_finite() || **x < 0.0)
        {
            Some((i, x)) if x.is_finite() => Err(MeshError::invalid(
                file,
                entry(i),
                format!("{name} is negative: {x} (must be >= 0)"),
            )),
            Some((i, x)) => Err(MeshError::invalid(
                file,
                entry(i),
                format!("not finite: {x}"),
            )),
            None => Ok(()),
        };
        check(&|i| format!("internalField[{i}]"), &self.cells)?;
        for (k, vals) in self.patches.iter().enumerate() {
            if let Some(v) = vals {
                let patch = mesh.patches.get(k).map_or("?", |p| p.name.as_str());
                check(&|i| format!("boundaryField/{patch}/value[{i}]"), v)?;
            }
        }
        Ok(())
    }
}
