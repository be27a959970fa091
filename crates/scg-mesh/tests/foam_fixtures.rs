//! Cases written by OpenFOAM itself (v1912, Debian's `openfoam` package): the same 3×3×3
//! blockMesh box in ASCII, in binary (faceCompactList, raw lists) and in compressed ASCII
//! (`*.gz`). See `tests/fixtures/foam/README.md` for how they were made.

use std::path::{Path, PathBuf};

use glam::DVec3;
use scg_mesh::foam::{self, TimeSel};
use scg_mesh::{CellField, PolyMesh};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/foam")
        .join(name)
}

fn read(name: &str) -> (PolyMesh, CellField) {
    let case = fixture(name);
    let mesh = foam::read_mesh(&case).unwrap_or_else(|e| panic!("{name}: {e}"));
    let u = foam::read_vector_field(&case, &mesh, TimeSel::Latest, "U")
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    (mesh, u)
}

#[test]
fn ascii_case_matches_check_mesh() {
    let (mesh, _) = read("ascii");
    // Expected values printed by OpenFOAM v1912 `checkMesh` on this case
    // (tests/fixtures/foam/ascii/checkMesh.log, "Mesh stats" and "Checking geometry").
    assert_eq!(mesh.points.len(), 64); // points:           64
    assert_eq!(mesh.n_faces(), 108); // faces:            108
    assert_eq!(mesh.n_internal_faces(), 54); // internal faces:   54
    assert_eq!(mesh.n_cells, 27); // cells:            27
    assert_eq!(mesh.patches.len(), 3); // boundary patches: 3
    let sizes: Vec<(&str, &str, usize)> = mesh
        .patches
        .iter()
        .map(|p| (p.name.as_str(), p.kind.as_str(), p.size))
        .collect();
    // Patch table of checkMesh (walls 36, inlet 9, outlet 9 faces) and blockMesh's types.
    assert_eq!(
        sizes,
        [
            ("walls", "wall", 36),
            ("inlet", "patch", 9),
            ("outlet", "patch", 9)
        ]
    );
    // "Overall domain bounding box (0 0 0) (0.30000000000000004 0.60000000000000009
    // 0.90000000000000024)": checkMesh prints 17 significant digits, so compare to 1e-15 m.
    let lo = mesh.points.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = mesh
        .points
        .iter()
        .fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    assert!(lo.abs_diff_eq(DVec3::ZERO, 1e-15), "{lo}");
    assert!(
        hi.abs_diff_eq(
            // checkMesh's 0.60000000000000009 and 0.90000000000000024 are these f64 values
            // (the nearest doubles to the printed decimals).
            DVec3::new(0.30000000000000004, 0.6000000000000001, 0.9000000000000002),
            1e-15
        ),
        "{hi}"
    );
    // Every face has 4 points (faces per cell: 6, all hexahedra).
    assert!((0..mesh.n_faces()).all(|f| mesh.face(f).len() == 4));
    // "Total volume = 0.16200000000000006": the divergence theorem over the boundary faces.
    let vol: f64 = (mesh.n_internal_faces()..mesh.n_faces())
        .map(|f| {
            let pts: Vec<DVec3> = mesh
                .face(f)
                .iter()
                .map(|&i| mesh.points[i as usize])
                .collect();
            let c = pts.iter().sum::<DVec3>() / pts.len() as f64;
            (0..pts.len())
                .map(|k| (pts[k] - c).cross(pts[(k + 1) % pts.len()] - c) * 0.5)
                .sum::<DVec3>()
                .dot(c)
                / 3.0
        })
        .sum();
    assert!((vol - 0.16200000000000006).abs() < 1e-14, "{vol}");
}

#[test]
fn ascii_binary_and_gzip_cases_read_the_same() {
    let (m_a, u_a) = read("ascii");
    let (m_b, u_b) = read("binary");
    let (m_z, u_z) = read("ascii_gz");
    assert_eq!(m_a, m_b);
    assert_eq!(m_a, m_z);
    // OpenFOAM wrote the ASCII U with 17 significant digits (writePrecision 17 in the
    // hand-written file), so ASCII and binary agree bit for bit.
    assert_eq!(u_a, u_b);
    assert_eq!(u_a, u_z);
}

#[test]
fn velocity_is_the_hand_written_field() {
    let (mesh, u) = read("binary");
    assert_eq!(u.cells.len(), 27);
    // 0/U was written by hand: cell i has (0.1 i, 1 - 0.01 i, sin i rounded to 12 decimals).
    for (i, v) in u.cells.iter().enumerate() {
        let x = i as f64;
        let want = DVec3::new(0.1 * x, 1.0 - 0.01 * x, x.sin());
        assert!(v.abs_diff_eq(want, 1e-12), "cell {i}: {v} vs {want}");
    }
    // walls: fixedValue uniform (0 0 0); inlet: fixedValue nonuniform, face k has
    // (0, 0, 0.5 + 0.125 k); outlet: zeroGradient, no value.
    assert_eq!(u.patches.len(), mesh.patches.len());
    assert_eq!(u.patches[0], Some(vec![DVec3::ZERO; 36]));
    let inlet: Vec<DVec3> = (0..9)
        .map(|k| DVec3::new(0.0, 0.0, 0.5 + 0.125 * k as f64))
        .collect();
    assert_eq!(u.patches[1], Some(inlet));
    assert_eq!(u.patches[2], None);
}

#[test]
fn time_selection() {
    let case = fixture("ascii");
    let dirs = foam::time_dirs(&case).unwrap();
    assert_eq!(dirs.len(), 1);
    assert_eq!(dirs[0].0, 0.0);
    let mesh = foam::read_mesh(&case).unwrap();
    assert!(foam::read_vector_field(&case, &mesh, TimeSel::Time(0.0), "U").is_ok());
    let e = foam::read_vector_field(&case, &mesh, TimeSel::Time(0.5), "U").unwrap_err();
    assert!(e.to_string().contains("t = 0.5"), "{e}");
}
