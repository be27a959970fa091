//! VTK unstructured grids: legacy `.vtk` (ASCII and binary, versions up to 5.1) and XML
//! `.vtu` (ASCII, inline base64, appended base64 or raw, zlib-compressed or not), read
//! through the `vtkio` crate. vtkio reads no raw appended data, so that is moved inline as
//! base64 first; declared counts and compressed block headers are bounded by the file size
//! before vtkio allocates, and a panic inside vtkio becomes an error.
//!
//! Volumetric cells (tetra 10, voxel 11, hexahedron 12, wedge 13, pyramid 14, and polyhedron
//! 42 in legacy files, where the connectivity holds the face stream) become faces with
//! outward orientation; faces shared by two cells become internal faces (owner = the lower
//! cell index), the others the single patch `boundary` (type `patch`). Points, lines and
//! surface cells (types 1–9) are skipped; cell numbers in the mesh count volumetric cells
//! only. Polyhedra in XML files need the `faces`/`faceoffsets` arrays, which vtkio does not
//! read: they are rejected.
//!
//! The velocity is the 3-component array named `field_name` ([`read`]), a scalar (`k`,
//! `epsilon`, …) the 1-component array ([`read_scalar`]: legacy `SCALARS name type 1` with
//! its `LOOKUP_TABLE`, a 1-component array of a legacy `FIELD`, an XML `DataArray` with one
//! component): from CELL_DATA if present (then the patch values are `None`, the owner's),
//! else from POINT_DATA, averaged onto each cell as the arithmetic mean of the values at its
//! distinct points, and onto each boundary face as the mean at the face's points (then the
//! patch values are `Some`).

mod appended;
mod cells;
mod guard;
mod pvd;

pub use pvd::read_pvd;

use std::path::Path;

use glam::DVec3;
use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataSet, ElementType, Piece,
    UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};

pub use cells::{assemble, cell_faces, face_area_centre, signed_volume};

use crate::{CellField, MeshError, PolyMesh, ScalarField};

/// Read the unstructured grid of `path` (`.vtk` legacy, `.vtu` XML) and its vector array
/// `field_name` (m/s for a velocity). See the module documentation for the conversion.
pub fn read(path: impl AsRef<Path>, field_name: &str) -> Result<(PolyMesh, CellField), MeshError> {
    let path = path.as_ref();
    let raw = read_raw(path, field_name, 3)?;
    let vectors = |v: &[f64]| -> Vec<DVec3> {
        v.chunks_exact(3)
            .map(|c| DVec3::new(c[0], c[1], c[2]))
            .collect()
    };
    let field = CellField {
        cells: vectors(&raw.cells),
        patches: raw
            .patches
            .iter()
            .map(|p| p.as_deref().map(vectors))
            .collect(),
    };
    if let Some((i, v)) = field.cells.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(MeshError::invalid(
            path,
            format!("{}/{field_name}[{i}]", raw.entry),
            format!("not finite: {v}"),
        ));
    }
    Ok((raw.mesh, field))
}

/// Read the scalar array `array_name` (1 component) of the unstructured grid of `path`
/// (`.vtk` legacy, `.vtu` XML), on the mesh [`read`] reads from the same file (the same
/// mesh, rebuilt): cell data as the cell values (patch values `None`), point data averaged
/// onto cells and boundary faces, as for a velocity. Every cell value must be finite;
/// negative values are accepted ([`ScalarField::check_non_negative`]).
pub fn read_scalar(path: impl AsRef<Path>, array_name: &str) -> Result<ScalarField, MeshError> {
    let path = path.as_ref();
    let raw = read_raw(path, array_name, 1)?;
    if let Some((i, v)) = raw.cells.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(MeshError::invalid(
            path,
            format!("{}/{array_name}[{i}]", raw.entry),
            format!("not finite: {v}"),
        ));
    }
    Ok(ScalarField {
        cells: raw.cells,
        patches: raw.patches,
    })
}

/// The mesh of a VTK file and an array of `nc` components on it, flat (`nc` numbers per
/// cell or face).
struct Raw {
    mesh: PolyMesh,
    /// `nc` values per cell.
    cells: Vec<f64>,
    /// Per patch, `nc` values per face (point data) or `None` (cell data).
    patches: Vec<Option<Vec<f64>>>,
    /// `CELL_DATA` or `POINT_DATA`: where the array was found.
    entry: &'static str,
}

fn read_raw(path: &Path, field_name: &str, nc: usize) -> Result<Raw, MeshError> {
    let bad = |entry: &str, message: String| MeshError::invalid(path, entry, message);
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if ext != "vtk" && ext != "vtu" {
        return Err(bad(
            "file",
            format!("extension '.{ext}': expected .vtk (legacy) or .vtu (XML)"),
        ));
    }
    let bytes = std::fs::read(path).map_err(|e| MeshError::Io {
        file: path.to_path_buf(),
        source: e,
    })?;
    // vtkio reads appended data only base64-encoded: raw appended data (ParaView's
    // default) is re-encoded inline first.
    let bytes = if ext == "vtu" {
        let b = appended::inline_raw_appended(&bytes).map_err(|m| bad("AppendedData", m))?;
        guard::check_xml(&b).map_err(|m| bad("file", m))?;
        b
    } else {
        guard::check_legacy(&bytes).map_err(|m| bad("file", m))?;
        bytes
    };
    // vtkio is third-party: a panic inside it on malformed input becomes an error here.
    let imported = std::panic::catch_unwind(|| {
        if ext == "vtu" {
            Vtk::parse_xml(&bytes[..])
        } else {
            Vtk::parse_legacy_be(&bytes[..])
        }
    })
    .map_err(|_| bad("file", "the VTK parser (vtkio) failed on this file".into()))?;
    let vtk = imported.map_err(|e| bad("file", format!("cannot parse: {e}")))?;
    let pieces = match vtk.data {
        DataSet::UnstructuredGrid { pieces, .. } => pieces,
        _ => return Err(bad("DATASET", "not an unstructured grid".into())),
    };
    let mut points: Vec<DVec3> = Vec::new();
    let mut cell_faces_all: Vec<Vec<Vec<u32>>> = Vec::new();
    let mut cell_points: Vec<Vec<u32>> = Vec::new();
    let mut cell_values: Option<Vec<f64>> = Some(Vec::new());
    let mut point_values: Option<Vec<f64>> = Some(Vec::new());
    for (k, piece) in pieces.into_iter().enumerate() {
        let piece: UnstructuredGridPiece = match piece {
            Piece::Inline(p) => *p,
            other => other
                .into_loaded_piece_data(Some(path))
                .map_err(|e| bad(&format!("Piece[{k}]"), format!("cannot load: {e}")))?,
        };
        let base = points.len() as u64;
        let coords: Vec<f64> = piece
            .points
            .cast_into()
            .ok_or_else(|| bad("Points", "coordinates are not numbers".into()))?;
        if !coords.len().is_multiple_of(3) {
            return Err(bad(
                "Points",
                format!("{} coordinates, not a multiple of 3", coords.len()),
            ));
        }
        let first_point = points.len();
        points.extend(coords.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])));
        if let Some((i, p)) = points
            .iter()
            .enumerate()
            .skip(first_point)
            .find(|(_, p)| !p.is_finite())
        {
            return Err(bad(&format!("Points[{i}]"), format!("not finite: {p}")));
        }
        let n_pts = (points.len() - first_point) as u64;
        let conn = connectivity(&piece.cells).map_err(|m| bad("Cells", m))?;
        let mut volumetric = Vec::new();
        for (c, (kind, verts)) in conn.into_iter().enumerate() {
            if cells::is_lower_dimensional(kind) {
                continue;
            }
            if kind == cells::VTK_POLYHEDRON && ext == "vtu" {
                return Err(bad(
                    &format!("Cells[{c}]"),
                    "polyhedron cells in .vtu files are not supported (vtkio does not read the faces arrays); use a legacy .vtk file".into(),
                ));
            }
            let shifted = verts
                .iter()
                .enumerate()
                .map(|(i, &v)| {
                    // A polyhedron's face stream mixes counts and points: shift points only.
                    if kind == cells::VTK_POLYHEDRON && is_count(&verts, i) {
                        return u32::try_from(v).map_err(|_| ());
                    }
                    if v >= n_pts {
                        return Err(());
                    }
                    u32::try_from(v + base).map_err(|_| ())
                })
                .collect::<Result<Vec<u32>, ()>>()
                .map_err(|_| {
                    bad(
                        &format!("Cells[{c}]"),
                        format!("point index out of range (0..{n_pts})"),
                    )
                })?;
            let faces = cell_faces(kind, &shifted).map_err(|m| bad(&format!("Cells[{c}]"), m))?;
            let mut pts: Vec<u32> = faces.iter().flatten().copied().collect();
            pts.sort_unstable();
            pts.dedup();
            cell_faces_all.push(faces);
            cell_points.push(pts);
            volumetric.push(c);
        }
        let n_vtk_cells = piece.cells.types.len();
        cell_values = match (cell_values, array(&piece.data, false, field_name, nc)) {
            (Some(mut acc), Some(v)) => {
                let v = v.map_err(|m| bad(&format!("CELL_DATA/{field_name}"), m))?;
                if v.len() / nc != n_vtk_cells {
                    return Err(bad(
                        &format!("CELL_DATA/{field_name}"),
                        format!("{} values for {n_vtk_cells} cells", v.len() / nc),
                    ));
                }
                for &c in &volumetric {
                    acc.extend_from_slice(&v[c * nc..(c + 1) * nc]);
                }
                Some(acc)
            }
            _ => None,
        };
        point_values = match (point_values, array(&piece.data, true, field_name, nc)) {
            (Some(mut acc), Some(v)) => {
                let v = v.map_err(|m| bad(&format!("POINT_DATA/{field_name}"), m))?;
                if (v.len() / nc) as u64 != n_pts {
                    return Err(bad(
                        &format!("POINT_DATA/{field_name}"),
                        format!("{} values for {n_pts} points", v.len() / nc),
                    ));
                }
                acc.extend(v);
                Some(acc)
            }
            _ => None,
        };
    }
    let mesh = assemble(points, cell_faces_all).map_err(|m| bad("Cells", m))?;
    mesh.check(path)?;
    if let Some(cells) = cell_values {
        return Ok(Raw {
            patches: vec![None; mesh.patches.len()],
            mesh,
            cells,
            entry: "CELL_DATA",
        });
    }
    let Some(pv) = point_values else {
        return Err(bad(
            field_name,
            format!("no {nc}-component cell or point array of this name"),
        ));
    };
    // the mean of the values at `pts`, appended to `out`
    let mean = |pts: &[u32], out: &mut Vec<f64>| {
        for j in 0..nc {
            let sum: f64 = pts.iter().map(|&p| pv[p as usize * nc + j]).sum();
            out.push(sum / pts.len() as f64);
        }
    };
    let mut cells = Vec::with_capacity(cell_points.len() * nc);
    for p in &cell_points {
        mean(p, &mut cells);
    }
    let patches = mesh
        .patches
        .iter()
        .map(|p| {
            let mut v = Vec::with_capacity(p.size * nc);
            for f in p.start..p.start + p.size {
                mean(mesh.face(f), &mut v);
            }
            Some(v)
        })
        .collect();
    Ok(Raw {
        mesh,
        cells,
        patches,
        entry: "POINT_DATA",
    })
}

/// True when entry `i` of a polyhedron face stream is a count (nFaces or a face's size).
fn is_count(stream: &[u64], i: usize) -> bool {
    if i == 0 {
        return true;
    }
    let mut k = 1;
    while k < stream.len() {
        if k == i {
            return true;
        }
        k = k.saturating_add(1).saturating_add(stream[k] as usize);
        if k > i {
            return false;
        }
    }
    false
}

/// (type, connectivity) of every cell.
fn connectivity(cells: &Cells) -> Result<Vec<(u8, Vec<u64>)>, String> {
    let types = &cells.types;
    let mut out = Vec::with_capacity(types.len());
    match &cells.cell_verts {
        VertexNumbers::Legacy {
            num_cells,
            vertices,
        } => {
            if *num_cells as usize != types.len() {
                return Err(format!("{num_cells} cells but {} cell types", types.len()));
            }
            let mut pos = 0usize;
            for (c, t) in types.iter().enumerate() {
                let n = *vertices
                    .get(pos)
                    .ok_or(format!("the connectivity ends before cell {c}"))?
                    as usize;
                let v = vertices
                    .get(pos + 1..pos + 1 + n)
                    .ok_or(format!("cell {c}: the connectivity ends inside the cell"))?;
                out.push((*t as u8, v.iter().map(|&x| x as u64).collect()));
                pos += 1 + n;
            }
        }
        VertexNumbers::XML {
            connectivity,
            offsets,
        } => {
            // Offsets are the end of each cell, possibly after a leading 0.
            let ends: &[u64] = if offsets.len() == types.len() + 1 && offsets.first() == Some(&0) {
                &offsets[1..]
            } else {
                offsets
            };
            if ends.len() != types.len() {
                return Err(format!(
                    "{} offsets but {} cell types",
                    offsets.len(),
                    types.len()
                ));
            }
            let mut start = 0u64;
            for (c, (t, &end)) in types.iter().zip(ends).enumerate() {
                let v = connectivity
                    .get(start as usize..end as usize)
                    .filter(|_| end >= start)
                    .ok_or(format!(
                        "cell {c}: offsets {start}..{end} out of the connectivity"
                    ))?;
                out.push((*t as u8, v.to_vec()));
                start = end;
            }
        }
    }
    Ok(out)
}

/// The `k`-component array `name` among the point (`point`) or cell attributes, if
/// present: `k` numbers per entry, flat.
fn array(data: &Attributes, point: bool, name: &str, k: usize) -> Option<Result<Vec<f64>, String>> {
    let attrs = if point { &data.point } else { &data.cell };
    for a in attrs {
        let (n_comp, buf) = match a {
            Attribute::DataArray(d) if d.name == name => (d.elem.num_comp() as usize, &d.data),
            Attribute::Field { data_array, .. } => {
                match data_array.iter().find(|f| f.name == name) {
                    Some(f) => (f.elem as usize, &f.data),
                    None => continue,
                }
            }
            _ => continue,
        };
        if n_comp != k {
            return Some(Err(format!(
                "{n_comp} components where {k} {} needed",
                if k == 1 { "is" } else { "are" }
            )));
        }
        let Some(mut v) = buf.cast_into::<f64>() else {
            return Some(Err("values are not numbers".into()));
        };
        v.truncate(v.len() / k * k);
        return Some(Ok(v));
    }
    None
}

/// Write `mesh` and `field` as a legacy VTK file (`.vtk`; binary big-endian or ASCII), every
/// cell a VTK_POLYHEDRON (its face stream from the mesh's faces, oriented outwards), the
/// cell values as the CELL_DATA vectors `name`. Readable by [`read`] and ParaView.
pub fn write_legacy(
    path: impl AsRef<Path>,
    mesh: &PolyMesh,
    name: &str,
    field: &CellField,
    binary: bool,
) -> Result<(), MeshError> {
    let path = path.as_ref();
    mesh.check(path)?;
    if field.cells.len() != mesh.n_cells {
        return Err(MeshError::invalid(
            path,
            name,
            format!("{} values for {} cells", field.cells.len(), mesh.n_cells),
        ));
    }
    let mut cell_faces: Vec<Vec<usize>> = vec![Vec::new(); mesh.n_cells];
    for f in 0..mesh.n_faces() {
        cell_faces[mesh.owner[f] as usize].push(f);
        if f < mesh.n_internal_faces() {
            cell_faces[mesh.neighbour[f] as usize].push(f);
        }
    }
    let mut vertices: Vec<u32> = Vec::new();
    for (c, faces) in cell_faces.iter().enumerate() {
        let mut stream = vec![faces.len() as u32];
        for &f in faces {
            let pts = mesh.face(f);
            stream.push(pts.len() as u32);
            if mesh.owner[f] as usize == c {
                stream.extend_from_slice(pts);
            } else {
                stream.extend(pts.iter().rev());
            }
        }
        vertices.push(stream.len() as u32);
        vertices.extend(stream);
    }
    let coords: Vec<f64> = mesh.points.iter().flat_map(|p| p.to_array()).collect();
    let values: Vec<f64> = field.cells.iter().flat_map(|p| p.to_array()).collect();
    let vtk = Vtk {
        version: Version::new_legacy(4, 2),
        title: "scg-mesh".into(),
        byte_order: ByteOrder::BigEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: coords.into(),
            cells: Cells {
                cell_verts: VertexNumbers::Legacy {
                    num_cells: mesh.n_cells as u32,
                    vertices,
                },
                types: vec![CellType::Polyhedron; mesh.n_cells],
            },
            data: Attributes {
                point: Vec::new(),
                cell: vec![Attribute::DataArray(vtkio::model::DataArray {
                    name: name.into(),
                    elem: ElementType::Vectors,
                    data: values.into(),
                })],
            },
        }),
    };
    let res = if binary {
        vtk.export_be(path)
    } else {
        vtk.export_ascii(path)
    };
    res.map_err(|e| MeshError::invalid(path, "file", format!("cannot write: {e}")))
}
