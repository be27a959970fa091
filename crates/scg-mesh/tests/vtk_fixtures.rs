//! Files written by VTK 9.1 itself (Debian's python3-vtk9; `tests/fixtures/vtk/make.py`):
//! three 0.1 m cubes along x, A as two wedges, B a hexahedron, C six pyramids around its
//! centre, in legacy ASCII (4.2) and binary (5.1) and in five XML encodings (ascii, inline
//! base64, appended raw zlib-compressed — VTK's and ParaView's default —, appended raw
//! uncompressed with UInt32 headers, appended base64); and a polyhedron next to a hexahedron.

mod common;

use std::path::{Path, PathBuf};

use common::{check_orientation, face_geometry, point_mean_centres};
use glam::DVec3;
use scg_mesh::{PolyMesh, vtk};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/vtk")
        .join(name)
}

const MIXED: [&str; 7] = [
    "mixed_ascii42.vtk",
    "mixed_binary.vtk",
    "mixed_ascii.vtu",
    "mixed_base64.vtu",
    "mixed_appended_zlib.vtu",
    "mixed_appended_raw.vtu",
    "mixed_appended_base64.vtu",
];

/// Volume by the divergence theorem over the boundary faces, m³.
fn volume(m: &PolyMesh) -> f64 {
    (m.n_internal_faces()..m.n_faces())
        .map(|f| {
            let (a, c) = face_geometry(m, f);
            a.dot(c) / 3.0
        })
        .sum()
}

#[test]
fn vtk_written_mixed_cells_in_every_encoding() {
    let mut first: Option<PolyMesh> = None;
    for name in MIXED {
        let path = fixture(name);
        // The legacy ASCII writer prints 11 significant digits; the others are exact.
        let tol = if name == "mixed_ascii42.vtk" {
            1e-9
        } else {
            1e-14
        };
        let (m, u) = vtk::read(&path, "U").unwrap_or_else(|e| panic!("{e}"));
        // 2 wedges + 1 hexahedron + 6 pyramids; internal: A's diagonal, A–B, B–C and the 12
        // triangles between C's pyramids; boundary: 4 triangles and 3 quads of A, 4 quads
        // of B, 5 pyramid bases of C.
        assert_eq!(m.n_cells, 9, "{name}");
        assert_eq!(m.n_internal_faces(), 15, "{name}");
        assert_eq!(m.n_faces() - m.n_internal_faces(), 16, "{name}");
        assert_eq!(m.points.len(), 17, "{name}");
        assert!((volume(&m) - 3e-3).abs() < 1e-15, "{name}: {}", volume(&m));
        let (closure, min_dot) = check_orientation(&m);
        assert!(
            closure < 1e-12 && min_dot > 0.0,
            "{name}: {closure} {min_dot}"
        );
        // Cell data U: the affine velocity at the mean of each cell's points.
        let centres = point_mean_centres(&m);
        for (i, (v, c)) in u.cells.iter().zip(&centres).enumerate() {
            assert!(
                v.abs_diff_eq(common::affine_u(*c), tol),
                "{name} cell {i}: {v}"
            );
        }
        assert_eq!(u.patches, vec![None]);
        // Point data Up averaged onto the cells: the same values, since U is affine.
        let (_, up) = vtk::read(&path, "Up").unwrap();
        for (i, (v, c)) in up.cells.iter().zip(&centres).enumerate() {
            assert!(
                v.abs_diff_eq(common::affine_u(*c), tol),
                "{name} cell {i}: {v}"
            );
        }
        assert_eq!(up.patches[0].as_ref().map(Vec::len), Some(16));
        match &first {
            None => first = Some(m),
            Some(f) => {
                assert_eq!(f.face_points, m.face_points, "{name}");
                assert_eq!(f.owner, m.owner, "{name}");
                assert_eq!(f.neighbour, m.neighbour, "{name}");
                for (a, b) in f.points.iter().zip(&m.points) {
                    assert!(a.abs_diff_eq(*b, 1e-12), "{name}: {a} vs {b}");
                }
            }
        }
    }
}

#[test]
fn vtk_written_polyhedron() {
    let (m, u) = vtk::read(fixture("poly.vtk"), "U").unwrap();
    assert_eq!(m.n_cells, 2);
    assert_eq!(m.n_internal_faces(), 1);
    assert_eq!(m.n_faces(), 11);
    assert!((volume(&m) - 2e-3).abs() < 1e-15);
    let (closure, min_dot) = check_orientation(&m);
    assert!(closure < 1e-12 && min_dot > 0.0);
    // The shared face x = 0.1 m points from the hexahedron (cell 0) into the polyhedron.
    let (a, c) = face_geometry(&m, 0);
    assert!((c.x - 0.1).abs() < 1e-15 && a.normalize().abs_diff_eq(DVec3::X, 1e-12));
    assert_eq!(u.cells.len(), 2);
}
