//! Mesh generators for tests and benchmarks: boxes of hexahedra, of tetrahedra (each hex
//! split into 6, conforming), and of polyhedra with hanging nodes like snappyHexMesh output.
//!
//! Every generator goes through `assemble`, which matches the faces of the cells into
//! OpenFOAM's layout: internal faces in upper-triangular order (by owner, then neighbour),
//! oriented out of the lower-numbered cell; boundary faces patch by patch.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::{MeshError, Patch, PolyMesh};

/// How the boundary faces of a box are grouped into patches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatchNaming {
    /// One patch per side: `xmin`, `xmax`, `ymin`, `ymax`, `zmin`, `zmax` (type `patch`);
    /// faces exposed by a [`BoxMesh::hole`] go to `hole` (type `wall`).
    Sides,
    /// `inlet` (the low side along `axis`, type `patch`), `outlet` (the high side, type
    /// `patch`) and `walls` (everything else, hole included, type `wall`). `axis` is 0, 1
    /// or 2 for x, y, z.
    InletOutletWalls {
        /// The flow axis.
        axis: usize,
    },
}

/// Which cells fill the box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CellShape {
    /// Hexahedra.
    Hex,
    /// Every hexahedron split into 6 tetrahedra about its main diagonal (the Kuhn
    /// subdivision, conforming across hexahedra).
    Tet,
    /// Hexahedra of which a random fraction (`refine`) is refined into 8; the unrefined
    /// neighbours keep the split points as hanging nodes, so they are polyhedra with up to
    /// 24 faces and faces of 4 to 8 points, as snappyHexMesh makes them.
    Poly {
        /// Fraction of the coarse hexahedra refined, 0..=1.
        refine: f64,
    },
}

/// A box mesh: `n` hexahedra along each axis between `lo` and `hi` (m), then shaped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxMesh {
    /// Low corner, m.
    pub lo: DVec3,
    /// High corner, m.
    pub hi: DVec3,
    /// Hexahedra along x, y, z (for `Poly`, the coarse ones).
    pub n: [usize; 3],
    /// Cell shape.
    pub shape: CellShape,
    /// Patch naming.
    pub naming: PatchNaming,
    /// Random displacement of the points not on the box's surface, as a fraction of the
    /// (finest) lattice spacing along each axis, uniform in ±`perturb`; 0..=0.3.
    pub perturb: f64,
    /// Seed of the perturbation and of the refined cells.
    pub seed: u64,
    /// Cells whose (unperturbed) centre lies in this box (m) are left out, making the
    /// domain concave; the exposed faces form the `hole` patch (or join `walls`).
    pub hole: Option<(DVec3, DVec3)>,
}

impl BoxMesh {
    /// A box of `n` hexahedra, sides named `xmin`…`zmax`, unperturbed.
    pub fn new(lo: DVec3, hi: DVec3, n: [usize; 3]) -> Self {
        BoxMesh {
            lo,
            hi,
            n,
            shape: CellShape::Hex,
            naming: PatchNaming::Sides,
            perturb: 0.0,
            seed: 1,
            hole: None,
        }
    }

    /// The same box with another cell shape.
    pub fn shape(mut self, shape: CellShape) -> Self {
        self.shape = shape;
        self
    }

    /// The same box with a perturbation of its interior points.
    pub fn perturbed(mut self, fraction: f64, seed: u64) -> Self {
        self.perturb = fraction;
        self.seed = seed;
        self
    }

    /// The same box with another patch naming.
    pub fn naming(mut self, naming: PatchNaming) -> Self {
        self.naming = naming;
        self
    }

    /// The same box without the cells whose centre is in `lo..hi`.
    pub fn with_hole(mut self, lo: DVec3, hi: DVec3) -> Self {
        self.hole = Some((lo, hi));
        self
    }

    /// Build the mesh.
    pub fn build(&self) -> Result<PolyMesh, MeshError> {
        let bad = |entry: &str, message: String| Err(MeshError::invalid("<box>", entry, message));
        if !(self.lo.is_finite() && self.hi.is_finite()) || self.hi.cmple(self.lo).any() {
            return bad(
                "lo/hi",
                format!("need lo < hi, got {} and {}", self.lo, self.hi),
            );
        }
        let fine = if matches!(self.shape, CellShape::Poly { .. }) {
            2
        } else {
            1
        };
        let lattice: Vec<usize> = self.n.iter().map(|&k| k * fine + 1).collect();
        if self.n.contains(&0) || lattice.iter().product::<usize>() > u32::MAX as usize / 8 {
            return bad(
                "n",
                format!(
                    "{:?} cells: each must be at least 1, the total not huge",
                    self.n
                ),
            );
        }
        if !(0.0..=0.3).contains(&self.perturb) {
            return bad("perturb", format!("{} not in 0..=0.3", self.perturb));
        }
        if let CellShape::Poly { refine } = self.shape
            && !(0.0..=1.0).contains(&refine)
        {
            return bad("refine", format!("{refine} not in 0..=1"));
        }
        if let PatchNaming::InletOutletWalls { axis } = self.naming
            && axis > 2
        {
            return bad("axis", format!("{axis} is not 0, 1 or 2"));
        }
        let [lx, ly, lz] = [lattice[0], lattice[1], lattice[2]];
        let h = (self.hi - self.lo) / DVec3::new((lx - 1) as f64, (ly - 1) as f64, (lz - 1) as f64);
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut points = Vec::with_capacity(lx * ly * lz);
        for k in 0..lz {
            for j in 0..ly {
                for i in 0..lx {
                    let mut p = self.lo + h * DVec3::new(i as f64, j as f64, k as f64);
                    let inner = [(i, lx), (j, ly), (k, lz)]
                        .iter()
                        .all(|&(a, n)| a > 0 && a + 1 < n);
                    if inner && self.perturb > 0.0 {
                        let r = DVec3::new(
                            rng.random_range(-1.0..=1.0),
                            rng.random_range(-1.0..=1.0),
                            rng.random_range(-1.0..=1.0),
                        );
                        p += r * h * self.perturb;
                    }
                    points.push(p);
                }
            }
        }
        let id = |i: usize, j: usize, k: usize| (i + lx * (j + ly * k)) as u32;
        let [nx, ny, nz] = self.n;
        let coarse_h = (self.hi - self.lo) / DVec3::new(nx as f64, ny as f64, nz as f64);
        let keep = |i: usize, j: usize, k: usize| match self.hole {
            None => true,
            Some((a, b)) => {
                let c =
                    self.lo + coarse_h * DVec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5);
                !(c.cmpgt(a).all() && c.cmplt(b).all())
            }
        };
        let mut cells = CellList::default();
        match self.shape {
            CellShape::Hex => {
                for k in 0..nz {
                    for j in 0..ny {
                        for i in 0..nx {
                            if keep(i, j, k) {
                                let v = hex_vertices(|a, b, c| id(i + a, j + b, k + c));
                                cells.push_hex(&v);
                            }
                        }
                    }
                }
            }
            CellShape::Tet => {
                for k in 0..nz {
                    for j in 0..ny {
                        for i in 0..nx {
                            if keep(i, j, k) {
                                let v = hex_vertices(|a, b, c| id(i + a, j + b, k + c));
                                cells.push_kuhn_tets(&v, &points);
                            }
                        }
                    }
                }
            }
            CellShape::Poly { refine } => {
                let refined: Vec<bool> = (0..nx * ny * nz)
                    .map(|_| refine > 0.0 && rng.random_bool(refine))
                    .collect();
                let kept: Vec<bool> = (0..nx * ny * nz)
                    .map(|c| keep(c % nx, (c / nx) % ny, c / (nx * ny)))
                    .collect();
                // Points used by refined cells (their whole 3×3×3 lattice).
                let mut used = vec![false; points.len()];
                for k in 0..nz {
                    for j in 0..ny {
                        for i in 0..nx {
                            let c = i + nx * (j + ny * k);
                            if refined[c] && kept[c] {
                                for (a, b, d) in cube3() {
                                    used[id(2 * i + a, 2 * j + b, 2 * k + d) as usize] = true;
                                }
                            }
                        }
                    }
                }
                for k in 0..nz {
                    for j in 0..ny {
                        for i in 0..nx {
                            let c = i + nx * (j + ny * k);
                            if !kept[c] {
                                continue;
                            }
                            if refined[c] {
                                for (a, b, d) in cube2() {
                                    let v = hex_vertices(|p, q, r| {
                                        id(2 * i + a + p, 2 * j + b + q, 2 * k + d + r)
                                    });
                                    cells.push_hex(&v);
                                }
                            } else {
                                let lat = |a: usize, b: usize, d: usize| {
                                    id(2 * i + a, 2 * j + b, 2 * k + d)
                                };
                                cells.push_hanging_hex(lat, &used);
                            }
                        }
                    }
                }
            }
        }
        let naming = self.naming;
        let (lo, hi) = (self.lo, self.hi);
        let tol = 1e-9 * (hi - lo).max_element();
        let names: Vec<(&str, &str)> = match naming {
            PatchNaming::Sides => vec![
                ("xmin", "patch"),
                ("xmax", "patch"),
                ("ymin", "patch"),
                ("ymax", "patch"),
                ("zmin", "patch"),
                ("zmax", "patch"),
                ("hole", "wall"),
            ],
            PatchNaming::InletOutletWalls { .. } => {
                vec![("inlet", "patch"), ("outlet", "patch"), ("walls", "wall")]
            }
        };
        let classify = move |c: DVec3| -> usize {
            let side = (0..3).flat_map(|a| [(a, 0), (a, 1)]).find(|&(a, s)| {
                let edge = if s == 0 { lo[a] } else { hi[a] };
                (c[a] - edge).abs() < tol
            });
            match (naming, side) {
                (PatchNaming::Sides, Some((a, s))) => 2 * a + s,
                (PatchNaming::Sides, None) => 6,
                (PatchNaming::InletOutletWalls { axis }, Some((a, s))) if a == axis => s,
                (PatchNaming::InletOutletWalls { .. }, _) => 2,
            }
        };
        let mut mesh = assemble(points, &cells, &names, classify)?;
        // Drop empty patches (e.g. `hole` without a hole) and unused points.
        mesh.patches.retain(|p| p.size > 0);
        compact_points(&mut mesh);
        Ok(mesh)
    }
}

/// A box of `n` hexahedra between `lo` and `hi` (m), patches named by `naming`.
pub fn hex_box(
    lo: DVec3,
    hi: DVec3,
    n: [usize; 3],
    naming: PatchNaming,
) -> Result<PolyMesh, MeshError> {
    BoxMesh::new(lo, hi, n).naming(naming).build()
}

/// A box of `n` hexahedra each split into 6 tetrahedra (conforming).
pub fn tet_box(
    lo: DVec3,
    hi: DVec3,
    n: [usize; 3],
    naming: PatchNaming,
) -> Result<PolyMesh, MeshError> {
    BoxMesh::new(lo, hi, n)
        .naming(naming)
        .shape(CellShape::Tet)
        .build()
}

/// A box of `n` coarse hexahedra of which the fraction `refine` is refined into 8, the
/// others polyhedra with hanging nodes.
pub fn poly_box(
    lo: DVec3,
    hi: DVec3,
    n: [usize; 3],
    naming: PatchNaming,
    refine: f64,
) -> Result<PolyMesh, MeshError> {
    BoxMesh::new(lo, hi, n)
        .naming(naming)
        .shape(CellShape::Poly { refine })
        .build()
}

fn cube2() -> impl Iterator<Item = (usize, usize, usize)> {
    (0..8).map(|c| (c & 1, (c >> 1) & 1, c >> 2))
}

fn cube3() -> impl Iterator<Item = (usize, usize, usize)> {
    (0..27).map(|c| (c % 3, (c / 3) % 3, c / 9))
}

/// The 8 vertices of a hexahedron in OpenFOAM's order (0–3 the bottom anticlockwise from
/// the low corner, 4–7 above them).
fn hex_vertices(at: impl Fn(usize, usize, usize) -> u32) -> [u32; 8] {
    HEX_CORNERS.map(|[a, b, c]| at(a, b, c))
}

/// Corners of a hexahedron in OpenFOAM's order, as (x, y, z) bits.
const HEX_CORNERS: [[usize; 3]; 8] = [
    [0, 0, 0],
    [1, 0, 0],
    [1, 1, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 0, 1],
    [1, 1, 1],
    [0, 1, 1],
];

/// Outward faces of a hexahedron (local vertex numbers): x−, x+, y−, y+, z−, z+.
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 4, 7, 3],
    [1, 2, 6, 5],
    [0, 1, 5, 4],
    [3, 7, 6, 2],
    [0, 3, 2, 1],
    [4, 5, 6, 7],
];

/// Cells as lists of outward faces, flattened.
#[derive(Default)]
struct CellList {
    /// Per cell, offsets into `faces` (one more than cells).
    cell_offsets: Vec<u32>,
    /// Per face, offsets into `points`.
    face_offsets: Vec<u32>,
    points: Vec<u32>,
}

impl CellList {
    fn n_cells(&self) -> usize {
        self.cell_offsets.len().saturating_sub(1)
    }

    fn begin_cell(&mut self) {
        if self.cell_offsets.is_empty() {
            self.cell_offsets.push(0);
            self.face_offsets.push(0);
        }
    }

    fn face(&mut self, pts: &[u32]) {
        self.points.extend_from_slice(pts);
        self.face_offsets.push(self.points.len() as u32);
    }

    fn end_cell(&mut self) {
        self.cell_offsets.push(self.face_offsets.len() as u32 - 1);
    }

    fn push_hex(&mut self, v: &[u32; 8]) {
        self.begin_cell();
        for f in HEX_FACES {
            self.face(&f.map(|i| v[i]));
        }
        self.end_cell();
    }

    /// The 6 tetrahedra of the Kuhn subdivision: 0 → 0+e_a → 0+e_a+e_b → 6 for each
    /// permutation (a, b, c) of the axes. Faces oriented outward from the actual points.
    fn push_kuhn_tets(&mut self, v: &[u32; 8], points: &[DVec3]) {
        let corner = |x: usize, y: usize, z: usize| {
            v[HEX_CORNERS
                .iter()
                .position(|&c| c == [x, y, z])
                .unwrap_or(0)]
        };
        let perms = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        for p in perms {
            let mut bits = [0usize; 3];
            let mut t = [corner(0, 0, 0); 4];
            for (s, &axis) in p.iter().enumerate() {
                bits[axis] = 1;
                t[s + 1] = corner(bits[0], bits[1], bits[2]);
            }
            let [a, b, c, d] = t;
            let pa = points[a as usize];
            let vol = (points[b as usize] - pa)
                .dot((points[c as usize] - pa).cross(points[d as usize] - pa));
            let (b, c) = if vol < 0.0 { (c, b) } else { (b, c) };
            self.begin_cell();
            self.face(&[a, c, b]);
            self.face(&[a, b, d]);
            self.face(&[a, d, c]);
            self.face(&[b, c, d]);
            self.end_cell();
        }
    }

    /// An unrefined coarse hexahedron on the fine lattice `lat(0..=2, 0..=2, 0..=2)`: a
    /// face whose centre point is used (the neighbour across is refined) becomes 4 quads;
    /// any other face one polygon through its corners and the used edge midpoints.
    fn push_hanging_hex(&mut self, lat: impl Fn(usize, usize, usize) -> u32, used: &[bool]) {
        self.begin_cell();
        for f in HEX_FACES {
            let c: Vec<[usize; 3]> = f.iter().map(|&i| HEX_CORNERS[i].map(|x| 2 * x)).collect();
            let mid = |a: [usize; 3], b: [usize; 3]| {
                [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2]
            };
            let at = |p: [usize; 3]| lat(p[0], p[1], p[2]);
            let centre = mid(c[0], c[2]);
            let m: Vec<[usize; 3]> = (0..4).map(|e| mid(c[e], c[(e + 1) % 4])).collect();
            if used[at(centre) as usize] {
                for e in 0..4 {
                    self.face(&[at(c[e]), at(m[e]), at(centre), at(m[(e + 3) % 4])]);
                }
            } else {
                let mut poly = Vec::with_capacity(8);
                for e in 0..4 {
                    poly.push(at(c[e]));
                    if used[at(m[e]) as usize] {
                        poly.push(at(m[e]));
                    }
                }
                self.face(&poly);
            }
        }
        self.end_cell();
    }
}

/// A face's key: its three smallest point numbers, its size and the sum of its points.
type FaceKey = ([u32; 3], usize, u64);

/// Match the outward faces of `cells` into a [`PolyMesh`]; boundary faces go to patch
/// `classify(face point average)` of `names` (name, type).
fn assemble(
    points: Vec<DVec3>,
    cells: &CellList,
    names: &[(&str, &str)],
    classify: impl Fn(DVec3) -> usize,
) -> Result<PolyMesh, MeshError> {
    let n_cells = cells.n_cells();
    let n_half = cells.face_offsets.len().saturating_sub(1);
    let face_pts = |h: usize| {
        &cells.points[cells.face_offsets[h] as usize..cells.face_offsets[h + 1] as usize]
    };
    let mut cell_of = vec![0u32; n_half];
    for c in 0..n_cells {
        for h in cells.cell_offsets[c]..cells.cell_offsets[c + 1] {
            cell_of[h as usize] = c as u32;
        }
    }
    // Key: the three smallest point numbers, the number of points and their sum (faces
    // sharing an edge with a hanging node share three points); equal keys are checked to
    // be the same face.
    let mut keys: Vec<(FaceKey, u32)> = (0..n_half)
        .map(|h| {
            let mut k = [u32::MAX; 3];
            for &p in face_pts(h) {
                if p < k[2] {
                    k[2] = p;
                    if k[2] < k[1] {
                        k.swap(1, 2);
                        if k[1] < k[0] {
                            k.swap(0, 1);
                        }
                    }
                }
            }
            let pts = face_pts(h);
            let sum = pts.iter().map(|&p| p as u64).sum::<u64>();
            ((k, pts.len(), sum), h as u32)
        })
        .collect();
    keys.sort_unstable();
    // internal: (owner, neighbour, owner's half face); boundary: (patch, owner, half face)
    let mut internal: Vec<(u32, u32, u32)> = Vec::new();
    let mut boundary: Vec<(u32, u32, u32)> = Vec::new();
    let mut i = 0;
    while i < keys.len() {
        let h = keys[i].1 as usize;
        if i + 1 < keys.len() && keys[i + 1].0 == keys[i].0 {
            let g = keys[i + 1].1 as usize;
            let mut a: Vec<u32> = face_pts(h).to_vec();
            let mut b: Vec<u32> = face_pts(g).to_vec();
            a.sort_unstable();
            b.sort_unstable();
            if a != b || (i + 2 < keys.len() && keys[i + 2].0 == keys[i].0) {
                return Err(MeshError::invalid(
                    "<box>",
                    format!("face {h}"),
                    format!("faces do not match up: {a:?} {b:?}"),
                ));
            }
            let (ch, cg) = (cell_of[h], cell_of[g]);
            if ch < cg {
                internal.push((ch, cg, h as u32));
            } else {
                internal.push((cg, ch, g as u32));
            }
            i += 2;
        } else {
            let pts = face_pts(h);
            let avg = pts.iter().map(|&p| points[p as usize]).sum::<DVec3>() / pts.len() as f64;
            let patch = classify(avg).min(names.len() - 1);
            boundary.push((patch as u32, cell_of[h], h as u32));
            i += 1;
        }
    }
    internal.sort_unstable();
    boundary.sort_unstable();
    let mut mesh = PolyMesh {
        points,
        face_offsets: vec![0],
        n_cells,
        ..Default::default()
    };
    for &(o, n, h) in &internal {
        mesh.face_points.extend_from_slice(face_pts(h as usize));
        mesh.face_offsets.push(mesh.face_points.len() as u32);
        mesh.owner.push(o);
        mesh.neighbour.push(n);
    }
    let mut start = internal.len();
    for (p, &(name, kind)) in names.iter().enumerate() {
        let faces: Vec<_> = boundary.iter().filter(|b| b.0 as usize == p).collect();
        for &&(_, o, h) in &faces {
            mesh.face_points.extend_from_slice(face_pts(h as usize));
            mesh.face_offsets.push(mesh.face_points.len() as u32);
            mesh.owner.push(o);
        }
        mesh.patches.push(Patch {
            name: name.into(),
            kind: kind.into(),
            start,
            size: faces.len(),
        });
        start += faces.len();
    }
    Ok(mesh)
}

/// Remove points no face uses, renumbering the faces.
fn compact_points(mesh: &mut PolyMesh) {
    let mut new = vec![u32::MAX; mesh.points.len()];
    let mut pts = Vec::new();
    for p in &mut mesh.face_points {
        let i = *p as usize;
        if new[i] == u32::MAX {
            new[i] = pts.len() as u32;
            pts.push(mesh.points[i]);
        }
        *p = new[i];
    }
    mesh.points = pts;
}

#[cfg(test)]
mod tests;
