//! VTK cells → faces → a [`PolyMesh`]: pure geometry and topology, no I/O.

use std::collections::HashMap;

use glam::DVec3;

use crate::{Patch, PolyMesh};

/// VTK cell type numbers handled here.
pub const VTK_TETRA: u8 = 10;
/// VTK_VOXEL (an axis-aligned hexahedron with VTK's voxel point order).
pub const VTK_VOXEL: u8 = 11;
/// VTK_HEXAHEDRON.
pub const VTK_HEXAHEDRON: u8 = 12;
/// VTK_WEDGE (a triangular prism).
pub const VTK_WEDGE: u8 = 13;
/// VTK_PYRAMID.
pub const VTK_PYRAMID: u8 = 14;
/// VTK_POLYHEDRON (its connectivity is a face stream `nFaces, n0, p.., n1, p.., …`).
pub const VTK_POLYHEDRON: u8 = 42;

// Faces of the linear cells, from VTK's vtkTetra/vtkHexahedron/vtkWedge/vtkPyramid
// face arrays: each consistently ordered (every edge appears once in each direction), with
// right-hand normals pointing out of a positively oriented cell.
const TETRA: &[&[usize]] = &[&[0, 1, 3], &[1, 2, 3], &[2, 0, 3], &[0, 2, 1]];
const HEXAHEDRON: &[&[usize]] = &[
    &[0, 4, 7, 3],
    &[1, 2, 6, 5],
    &[0, 1, 5, 4],
    &[3, 7, 6, 2],
    &[0, 3, 2, 1],
    &[4, 5, 6, 7],
];
const WEDGE: &[&[usize]] = &[
    &[0, 1, 2],
    &[3, 5, 4],
    &[0, 3, 4, 1],
    &[1, 4, 5, 2],
    &[2, 5, 3, 0],
];
const PYRAMID: &[&[usize]] = &[
    &[0, 3, 2, 1],
    &[0, 1, 4],
    &[1, 2, 4],
    &[2, 3, 4],
    &[3, 0, 4],
];
/// Voxel point order → hexahedron point order.
const VOXEL_TO_HEX: [usize; 8] = [0, 1, 3, 2, 4, 5, 7, 6];

/// True for the VTK types of points, lines and surfaces (1–9), which bound no volume.
pub fn is_lower_dimensional(kind: u8) -> bool {
    (1..=9).contains(&kind)
}

/// The faces of one VTK cell of type `kind` with connectivity `conn`, in VTK's order
/// (orientation is fixed later by [`assemble`]).
pub fn cell_faces(kind: u8, conn: &[u32]) -> Result<Vec<Vec<u32>>, String> {
    let table = |t: &[&[usize]], n: usize, conn: &[u32]| {
        if conn.len() != n {
            return Err(format!(
                "cell type {kind} needs {n} points, the cell has {}",
                conn.len()
            ));
        }
        Ok(t.iter()
            .map(|f| f.iter().map(|&i| conn[i]).collect())
            .collect())
    };
    match kind {
        VTK_TETRA => table(TETRA, 4, conn),
        VTK_HEXAHEDRON => table(HEXAHEDRON, 8, conn),
        VTK_VOXEL => {
            if conn.len() != 8 {
                return table(HEXAHEDRON, 8, conn);
            }
            let hex: Vec<u32> = VOXEL_TO_HEX.iter().map(|&i| conn[i]).collect();
            table(HEXAHEDRON, 8, &hex)
        }
        VTK_WEDGE => table(WEDGE, 6, conn),
        VTK_PYRAMID => table(PYRAMID, 5, conn),
        VTK_POLYHEDRON => {
            let (&nf, mut rest) = conn.split_first().ok_or("empty polyhedron face stream")?;
            let mut faces = Vec::with_capacity(nf as usize);
            for k in 0..nf {
                let (&n, r) = rest
                    .split_first()
                    .ok_or(format!("polyhedron face stream ends before face {k}"))?;
                if r.len() < n as usize {
                    return Err(format!("polyhedron face {k} runs past the face stream"));
                }
                faces.push(r[..n as usize].to_vec());
                rest = &r[n as usize..];
            }
            if !rest.is_empty() {
                return Err(format!(
                    "{} values after the {nf} faces of the polyhedron face stream",
                    rest.len()
                ));
            }
            Ok(faces)
        }
        k => Err(format!(
            "VTK cell type {k} is not supported (tetra 10, voxel 11, hexahedron 12, wedge 13, pyramid 14, polyhedron 42)"
        )),
    }
}

/// Area vector of a polygon (½ Σ (pᵢ − c) × (pᵢ₊₁ − c) about its point average c), m², and
/// that average, m.
pub fn face_area_centre(points: &[DVec3], face: &[u32]) -> (DVec3, DVec3) {
    let n = face.len();
    let c = face.iter().map(|&i| points[i as usize]).sum::<DVec3>() / n as f64;
    let mut a = DVec3::ZERO;
    for k in 0..n {
        let p = points[face[k] as usize] - c;
        let q = points[face[(k + 1) % n] as usize] - c;
        a += p.cross(q);
    }
    (0.5 * a, c)
}

/// Signed volume of a closed cell from its faces (divergence theorem), m³: positive when the
/// faces' right-hand normals point outwards.
pub fn signed_volume(points: &[DVec3], faces: &[Vec<u32>]) -> f64 {
    faces
        .iter()
        .map(|f| {
            let (a, c) = face_area_centre(points, f);
            a.dot(c)
        })
        .sum::<f64>()
        / 3.0
}

/// Assemble cells given by their faces into a [`PolyMesh`].
///
/// Each cell's faces are first oriented outwards: consecutive repeated points are dropped
/// (degenerate VTK cells), faces left with fewer than 3 points are dropped, and a cell whose
/// signed volume is negative (an inverted point order) has all its faces reversed. Faces
/// with the same set of points in two cells become one internal face, owned by the lower
/// cell index and oriented out of it; internal faces are sorted by (owner, neighbour) as
/// OpenFOAM orders them. The other faces form one patch, `boundary` (type `patch`), in cell
/// order. Errors name the cell at fault.
pub fn assemble(points: Vec<DVec3>, cells: Vec<Vec<Vec<u32>>>) -> Result<PolyMesh, String> {
    let n_cells = cells.len();
    let np = points.len();
    // (owner, oriented points) of every cell face, and its match if any.
    let mut faces: Vec<(u32, Vec<u32>)> = Vec::new();
    for (c, mut cf) in cells.into_iter().enumerate() {
        for f in cf.iter_mut() {
            if let Some(&p) = f.iter().find(|&&p| p as usize >= np) {
                return Err(format!("cell {c}: point index {p} out of range (0..{np})"));
            }
            f.dedup();
            while f.len() > 1 && f.first() == f.last() {
                f.pop();
            }
        }
        cf.retain(|f| f.len() >= 3);
        if signed_volume(&points, &cf) < 0.0 {
            for f in cf.iter_mut() {
                f.reverse();
            }
        }
        faces.extend(cf.into_iter().map(|f| (c as u32, f)));
    }
    let mut first: HashMap<Vec<u32>, usize> = HashMap::with_capacity(faces.len());
    let mut partner = vec![usize::MAX; faces.len()];
    for (i, (c, f)) in faces.iter().enumerate() {
        let mut key = f.clone();
        key.sort_unstable();
        match first.get(&key) {
            None => {
                first.insert(key, i);
            }
            Some(&j) => {
                if partner[j] != usize::MAX {
                    return Err(format!(
                        "cell {c}: a face {f:?} is shared by more than two cells"
                    ));
                }
                if faces[j].0 == *c {
                    return Err(format!(
                        "cell {c}: the face {f:?} appears twice in the cell"
                    ));
                }
                partner[j] = i;
                partner[i] = j;
            }
        }
    }
    let mut internal: Vec<(u32, u32, usize)> = Vec::new();
    let mut boundary: Vec<usize> = Vec::new();
    for (i, &j) in partner.iter().enumerate() {
        if j == usize::MAX {
            boundary.push(i);
        } else if faces[i].0 < faces[j].0 {
            internal.push((faces[i].0, faces[j].0, i));
        }
    }
    internal.sort_unstable();
    let mut mesh = PolyMesh {
        points,
        n_cells,
        ..Default::default()
    };
    mesh.face_offsets.push(0);
    let push = |mesh: &mut PolyMesh, i: usize| {
        mesh.face_points.extend_from_slice(&faces[i].1);
        mesh.face_offsets.push(mesh.face_points.len() as u32);
        mesh.owner.push(faces[i].0);
    };
    for &(_, n, i) in &internal {
        push(&mut mesh, i);
        mesh.neighbour.push(n);
    }
    for &i in &boundary {
        push(&mut mesh, i);
    }
    mesh.patches.push(Patch {
        name: "boundary".into(),
        kind: "patch".into(),
        start: internal.len(),
        size: boundary.len(),
    });
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_hex() -> Vec<DVec3> {
        [
            [0., 0., 0.],
            [1., 0., 0.],
            [1., 1., 0.],
            [0., 1., 0.],
            [0., 0., 1.],
            [1., 0., 1.],
            [1., 1., 1.],
            [0., 1., 1.],
        ]
        .map(DVec3::from_array)
        .to_vec()
    }

    #[test]
    fn tables_give_the_volume_of_each_shape() {
        let p = unit_hex();
        // Volumes of the unit cube and its parts: independent values, 1e-14 m³. The sign is
        // VTK's orientation convention: the base (0 1 2 3, or the tetra's 0 1 2) is
        // counter-clockwise seen from the apex or top, except for the wedge, whose
        // triangle 0 1 2 is clockwise seen from 3 4 5 (VTK's vtkWedge point order).
        let cases: [(u8, Vec<u32>, f64); 6] = [
            (VTK_HEXAHEDRON, (0..8).collect(), 1.0),
            (VTK_VOXEL, vec![0, 1, 3, 2, 4, 5, 7, 6], 1.0),
            (VTK_TETRA, vec![0, 1, 3, 4], 1.0 / 6.0),
            (VTK_WEDGE, vec![0, 3, 1, 4, 7, 5], 0.5),
            (VTK_WEDGE, vec![0, 1, 3, 4, 5, 7], -0.5),
            (VTK_PYRAMID, vec![0, 1, 2, 3, 6], 1.0 / 3.0),
        ];
        for (kind, conn, vol) in cases {
            let f = cell_faces(kind, &conn).unwrap();
            let v = signed_volume(&p, &f);
            assert!((v - vol).abs() < 1e-14, "type {kind}: {v} vs {vol}");
            // The sum of the area vectors of a closed cell vanishes.
            let s: DVec3 = f.iter().map(|f| face_area_centre(&p, f).0).sum();
            assert!(s.length() < 1e-14, "type {kind}: {s}");
        }
    }

    #[test]
    fn polyhedron_stream_and_errors() {
        let stream = [4, 3, 0, 2, 1, 3, 0, 1, 3, 3, 1, 2, 3, 3, 2, 0, 3];
        let f = cell_faces(VTK_POLYHEDRON, &stream).unwrap();
        assert_eq!(f.len(), 4);
        assert!(cell_faces(VTK_POLYHEDRON, &stream[..10]).is_err());
        assert!(cell_faces(VTK_HEXAHEDRON, &[0, 1, 2]).is_err());
        assert!(cell_faces(25, &[0; 20]).is_err());
    }

    #[test]
    fn two_cubes_share_one_face() {
        let mut p = unit_hex();
        p.extend(unit_hex().iter().map(|q| *q + DVec3::X));
        let a: Vec<u32> = (0..8).collect();
        // The second cube reuses the shared points 1, 2, 5, 6 and is given inverted
        // (mirrored point order), which assemble must flip.
        let b: Vec<u32> = vec![1, 9, 10, 2, 5, 13, 14, 6];
        let b_inv: Vec<u32> = vec![b[3], b[2], b[1], b[0], b[7], b[6], b[5], b[4]];
        let cells = vec![
            cell_faces(VTK_HEXAHEDRON, &a).unwrap(),
            cell_faces(VTK_HEXAHEDRON, &b_inv).unwrap(),
        ];
        let m = assemble(p, cells).unwrap();
        m.check(std::path::Path::new("test")).unwrap();
        assert_eq!(m.n_internal_faces(), 1);
        assert_eq!(m.n_faces(), 11);
        assert_eq!((m.owner[0], m.neighbour[0]), (0, 1));
        // The internal face points from cell 0 into cell 1: +x.
        let (a, _) = face_area_centre(&m.points, m.face(0));
        assert!(a.abs_diff_eq(DVec3::X, 1e-14), "{a}");
    }
}
