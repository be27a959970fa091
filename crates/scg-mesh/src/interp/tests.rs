//! Tests of [`super`] (interp).

use super::*;
use crate::MeshGeometry;
use crate::build::BoxMesh;

#[test]
fn uniform_field_is_reproduced_and_bad_fields_rejected() {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [3, 3, 3])
        .perturbed(0.2, 1)
        .build()
        .unwrap();
    let g = MeshGeometry::new(&m).unwrap();
    let loc = Locator::new(&m, &g).unwrap();
    let u = DVec3::new(1.0, -2.0, 0.5);
    let field = CellField {
        cells: vec![u; m.n_cells],
        patches: vec![None; m.patches.len()],
    };
    let it = Interpolator::new(&loc, &field, Interpolation::CellPoint).unwrap();
    for x in [DVec3::splat(0.5), DVec3::new(0.01, 0.99, 0.3)] {
        let c = loc.find_cell(x).unwrap();
        assert!((it.velocity(c, x) - u).length() < 1e-14);
    }
    assert!(it.velocity(1000, DVec3::ZERO).is_nan());
    let short = CellField {
        cells: vec![u; 3],
        patches: vec![],
    };
    assert!(Interpolator::new(&loc, &short, Interpolation::CellPoint).is_err());
    let mut nan = field.clone();
    nan.cells[4] = DVec3::NAN;
    assert!(Interpolator::new(&loc, &nan, Interpolation::CellValue).is_err());
    let mut wrong = field.clone();
    wrong.patches[0] = Some(vec![u; 1]);
    assert!(Interpolator::new(&loc, &wrong, Interpolation::CellPoint).is_err());
}
