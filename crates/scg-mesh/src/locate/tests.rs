//! Tests of [`super`] (locate).
use super::*;
use crate::build::BoxMesh;

#[test]
fn unit_cube_cells_by_index() {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [4, 4, 4])
        .build()
        .unwrap();
    let g = MeshGeometry::new(&m).unwrap();
    let loc = Locator::new(&m, &g).unwrap();
    let x = DVec3::new(0.3, 0.6, 0.9);
    // cells are numbered i + 4 (j + 4 k)
    assert_eq!(loc.find_cell(x), Some(1 + 4 * (2 + 4 * 3)));
    assert_eq!(loc.find_cell(DVec3::new(1.1, 0.5, 0.5)), None);
    assert_eq!(loc.find_cell(DVec3::NAN), None);
    match loc.track(0, x) {
        Location::Inside(h) => {
            assert_eq!(h.cell, 57);
            assert!(h.weights.iter().all(|&w| w >= -1e-12));
            assert!((h.weights.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            // the weights reproduce x
            let y = h.weights[0] * g.cell_centres[57]
                + (0..3)
                    .map(|k| h.weights[k + 1] * loc.node(h.nodes[k]))
                    .sum::<DVec3>();
            assert!((y - x).length() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
    // leaving through x max
    match loc.track(57, DVec3::new(1.5, 0.6, 0.9)) {
        Location::Left { patch, .. } => assert_eq!(m.patches[patch as usize].name, "xmax"),
        other => panic!("{other:?}"),
    }
    // a walk cut short by the cap falls back to the grid
    let mut short = loc.clone();
    short.max_steps = 1;
    match short.track(0, x) {
        Location::Inside(h) => assert_eq!(h.cell, 57),
        other => panic!("{other:?}"),
    }
    // a geometry of another mesh, a broken mesh: errors
    let other = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [2, 2, 2])
        .build()
        .unwrap();
    assert!(Locator::new(&other, &g).is_err());
    let mut broken = m.clone();
    broken.owner[3] = 10_000;
    assert!(MeshGeometry::new(&broken).is_err());
    // bad hints do not panic
    assert_eq!(loc.probe(9999, x), Probe::Fail);
    let mut bad = loc.find(x).unwrap();
    bad.nodes[1] = u32::MAX;
    assert!(matches!(loc.track_from(&bad, x), Location::Inside(h) if h.cell == 57));
    assert!(matches!(loc.track(9999, x), Location::Inside(_)));
    assert_eq!(loc.track(3, DVec3::NAN), Location::Outside);
}
