//! Tests of [`super`] (build).

use super::*;

fn count_faces_by_size(m: &PolyMesh) -> Vec<usize> {
    let mut n = vec![0; 10];
    for f in 0..m.n_faces() {
        n[m.face(f).len().min(9)] += 1;
    }
    n
}

#[test]
fn hex_box_counts_and_patches() {
    let m = hex_box(
        DVec3::ZERO,
        DVec3::new(3.0, 2.0, 1.0),
        [3, 2, 1],
        PatchNaming::Sides,
    )
    .unwrap();
    let t = tet_box(DVec3::ZERO, DVec3::ONE, [1, 1, 1], PatchNaming::Sides).unwrap();
    assert_eq!(t.n_cells, 6);
    let p = poly_box(DVec3::ZERO, DVec3::ONE, [2, 2, 2], PatchNaming::Sides, 1.0).unwrap();
    assert_eq!(p.n_cells, 64);
    m.check("t".as_ref()).unwrap();
    assert_eq!(m.n_cells, 6);
    assert_eq!(m.points.len(), 4 * 3 * 2);
    // internal faces: (nx-1)ny nz + nx(ny-1)nz + nx ny(nz-1)
    assert_eq!(m.n_internal_faces(), 2 * 2 + 3);
    let sizes: Vec<(&str, usize)> = m
        .patches
        .iter()
        .map(|p| (p.name.as_str(), p.size))
        .collect();
    assert_eq!(
        sizes,
        [
            ("xmin", 2),
            ("xmax", 2),
            ("ymin", 3),
            ("ymax", 3),
            ("zmin", 6),
            ("zmax", 6)
        ]
    );
    // upper-triangular order
    for f in 1..m.n_internal_faces() {
        assert!((m.owner[f - 1], m.neighbour[f - 1]) < (m.owner[f], m.neighbour[f]));
    }
}

#[test]
fn grouped_naming_and_tets() {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [2, 2, 2])
        .shape(CellShape::Tet)
        .naming(PatchNaming::InletOutletWalls { axis: 0 })
        .perturbed(0.2, 3)
        .build()
        .unwrap();
    m.check("t".as_ref()).unwrap();
    assert_eq!(m.n_cells, 48);
    let sizes: Vec<(&str, usize)> = m
        .patches
        .iter()
        .map(|p| (p.name.as_str(), p.size))
        .collect();
    // 4 quads per side, 2 triangles each
    assert_eq!(sizes, [("inlet", 8), ("outlet", 8), ("walls", 32)]);
    // every face a triangle; 4 faces per tet: 2·internal + boundary = 4·cells
    assert_eq!(2 * m.n_internal_faces() + 48, 4 * 48);
}

#[test]
fn poly_box_has_polygons_and_hanging_nodes() {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [4, 4, 4])
        .shape(CellShape::Poly { refine: 0.3 })
        .perturbed(0.15, 7)
        .build()
        .unwrap();
    m.check("t".as_ref()).unwrap();
    let sizes = count_faces_by_size(&m);
    assert!(sizes[5] + sizes[6] + sizes[7] + sizes[8] > 0, "{sizes:?}");
    assert!(m.n_cells > 64, "some cells refined");
    let mut faces_of = vec![0; m.n_cells];
    for &c in m.owner.iter().chain(&m.neighbour) {
        faces_of[c as usize] += 1;
    }
    assert!(
        faces_of.iter().any(|&n| n > 6),
        "cells with more than 6 faces"
    );
}

#[test]
fn bad_input_is_an_error() {
    let b = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [0, 1, 1]);
    assert!(b.build().is_err());
    assert!(
        BoxMesh::new(DVec3::ONE, DVec3::ZERO, [1, 1, 1])
            .build()
            .is_err()
    );
    assert!(
        BoxMesh::new(DVec3::ZERO, DVec3::ONE, [1, 1, 1])
            .perturbed(0.6, 1)
            .build()
            .is_err()
    );
    assert!(
        BoxMesh::new(DVec3::ZERO, DVec3::splat(f64::NAN), [1, 1, 1])
            .build()
            .is_err()
    );
    let b = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [1, 1, 1]).shape(CellShape::Poly { refine: 2.0 });
    assert!(b.build().is_err());
}

#[test]
fn hole_makes_a_wall_patch() {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [4, 4, 1])
        .with_hole(DVec3::new(0.5, 0.5, -1.0), DVec3::new(2.0, 2.0, 2.0))
        .build()
        .unwrap();
    m.check("t".as_ref()).unwrap();
    assert_eq!(m.n_cells, 12);
    let hole = m.patches.iter().find(|p| p.name == "hole").unwrap();
    assert_eq!(hole.size, 4);
}
