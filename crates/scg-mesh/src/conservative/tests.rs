//! Tests of [`super`] (the conservative scheme).

use super::*;
use crate::build::{BoxMesh, CellShape, PatchNaming};
use crate::interp::{Interpolation, Interpolator};
use crate::locate::Locator;
use std::collections::HashMap;

const SHAPES: [CellShape; 3] = [
    CellShape::Hex,
    CellShape::Tet,
    CellShape::Poly { refine: 0.3 },
];

/// A perturbed duct along x (inlet, outlet, walls) of `shape`, a field that is far from
/// conserving volume (a swirl whose speed grows along x, plus a wobble), and its outflow
/// flags (the outlet).
fn duct(shape: CellShape, n: usize) -> (PolyMesh, MeshGeometry, CellField, Vec<bool>) {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::new(2.0, 1.0, 1.0), [2 * n, n, n])
        .shape(shape)
        .naming(PatchNaming::InletOutletWalls { axis: 0 })
        .perturbed(0.2, 7)
        .build()
        .unwrap();
    let g = MeshGeometry::new(&m).unwrap();
    let mut field = CellField::at_cell_centres(&m, &g, |c| {
        let r = DVec3::new(0.0, c.y - 0.5, c.z - 0.5);
        DVec3::new(1.0 + 0.3 * (4.0 * c.y).sin(), 0.0, 0.0)
            + (1.0 + c.x) * DVec3::X.cross(r)
            + DVec3::new(0.0, 0.2 * c.x, -0.1 * (3.0 * c.z).cos())
    });
    // the inlet's values: 1 m/s along x; walls: no slip
    for (pi, p) in m.patches.iter().enumerate() {
        field.patches[pi] = match p.name.as_str() {
            "inlet" => Some(vec![DVec3::X; p.size]),
            "walls" => Some(vec![DVec3::ZERO; p.size]),
            _ => None,
        };
    }
    let outflow = m.patches.iter().map(|p| p.name == "outlet").collect();
    (m, g, field, outflow)
}

/// The balanced fluxes close every cell to rounding, keep the inlet's and the walls'
/// fluxes, and carry the inflow out through the outlet.
#[test]
fn projection_balances_every_cell() {
    for shape in SHAPES {
        let (m, g, field, outflow) = duct(shape, 4);
        let (phi, p) = face_fluxes(&m, &g, &field, &outflow).unwrap();
        let scale = 1.0; // inflow 1 m³/s
        assert!((p.inflow - 1.0).abs() < 1e-12, "{shape:?}: {p:?}");
        assert!(
            p.imbalance_before > 0.1,
            "{shape:?}: the test field conserves: {p:?}"
        );
        let div = divergence(&m, &phi);
        let worst = div.iter().fold(0.0f64, |a, d| a.max(d.abs()));
        assert!(worst < 1e-11 * scale, "{shape:?}: {worst:e}");
        assert!((p.outflow_after - 1.0).abs() < 1e-11, "{shape:?}: {p:?}");
        for (pi, patch) in m.patches.iter().enumerate() {
            for f in patch.start..patch.start + patch.size {
                let want = field.patches[pi]
                    .as_ref()
                    .map(|v| v[f - patch.start].dot(g.face_areas[f]));
                if let (Some(w), false) = (want, outflow[pi]) {
                    assert_eq!(phi[f], w, "{shape:?} {}", patch.name);
                }
            }
        }
        println!("{shape:?}: {p:?}");
    }
}

/// A closed box keeps its balance (one p pinned); a closed box whose boundary values
/// carry a net flow in is refused, naming the need of an outflow patch.
#[test]
fn closed_domains() {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [4, 4, 4])
        .perturbed(0.2, 2)
        .build()
        .unwrap();
    let g = MeshGeometry::new(&m).unwrap();
    let mut field = CellField::at_cell_centres(&m, &g, |c| DVec3::new(c.y, c.z * c.x, c.x));
    for (pi, p) in m.patches.iter().enumerate() {
        field.patches[pi] = Some(vec![DVec3::ZERO; p.size]);
    }
    let shut = vec![false; m.patches.len()];
    let (phi, _) = face_fluxes(&m, &g, &field, &shut).unwrap();
    let worst = divergence(&m, &phi)
        .iter()
        .fold(0.0f64, |a, d| a.max(d.abs()));
    assert!(worst < 1e-12, "{worst:e}");
    field.patches[0] = Some(vec![DVec3::X; m.patches[0].size]);
    let e = face_fluxes(&m, &g, &field, &shut).unwrap_err().to_string();
    assert!(e.contains("needs an outflow patch"), "{e}");
}

/// The tetrahedra's velocities: a uniform field is kept exactly; on a field far from
/// conserving volume, every triangle of the decomposition carries the same flux seen
/// from both of its tetrahedra (inner triangles within a cell, face triangles between
/// cells), and the face triangles of a mesh face add up to its balanced flux.
#[test]
fn tetrahedra_carry_the_balanced_fluxes() {
    for shape in SHAPES {
        let (m, g, field, outflow) = duct(shape, 3);
        let loc = Locator::new(&m, &g).unwrap();
        // uniform: reproduced
        let u0 = DVec3::new(0.7, -0.2, 0.4);
        let mut uniform = field.clone();
        uniform.cells.fill(u0);
        for (pi, p) in m.patches.iter().enumerate() {
            uniform.patches[pi] = Some(vec![u0; p.size]);
        }
        let it = Interpolator::with_outflow(&loc, &uniform, Interpolation::Conservative, &outflow)
            .unwrap();
        assert_eq!(it.projection().unwrap().unbalanced_cells, 0);
        let k_all = g.cell_faces.len();
        for k in 0..k_all {
            let mut i = 0;
            while let Some(u) = it.tet_velocity(k, i) {
                assert!((u - u0).length() < 1e-12, "{shape:?}: {u} vs {u0}");
                i += 1;
            }
        }
        // non-conserving field
        let it = Interpolator::with_outflow(&loc, &field, Interpolation::Conservative, &outflow)
            .unwrap();
        let (phi, _) = face_fluxes(&m, &g, &field, &outflow).unwrap();
        assert_eq!(it.projection().unwrap().unbalanced_cells, 0);
        let np = m.points.len() as u32;
        let node = |n: u32| loc.node(n);
        // per mesh face: the flux of its triangles from each side
        let mut face_sum: HashMap<(u32, usize), f64> = HashMap::new();
        let mut tri_flux: HashMap<(u32, usize), Vec<f64>> = HashMap::new();
        let mut worst_inner: f64 = 0.0;
        for c in 0..m.n_cells {
            let cc = g.cell_centres[c];
            // inner triangles of this cell: edge key → outward fluxes seen by its two tets
            let mut inner: HashMap<(u32, u32), Vec<f64>> = HashMap::new();
            for (j, &f) in g.faces_of(c).iter().enumerate() {
                let k = g.cell_face_offsets[c] as usize + j;
                let pts = m.face(f as usize);
                let owner = m.owner[f as usize] as usize == c;
                let tris: Vec<[u32; 3]> = if pts.len() == 3 {
                    let (a, b) = if owner {
                        (pts[1], pts[2])
                    } else {
                        (pts[2], pts[1])
                    };
                    vec![[pts[0], a, b]]
                } else {
                    (0..pts.len())
                        .map(|i| {
                            let (pa, pb) = (pts[i], pts[(i + 1) % pts.len()]);
                            let (a, b) = if owner { (pa, pb) } else { (pb, pa) };
                            [np + f, a, b]
                        })
                        .collect()
                };
                for (i, t) in tris.iter().enumerate() {
                    let u = it.tet_velocity(k, i).unwrap();
                    let (a, b, cn) = (node(t[0]), node(t[1]), node(t[2]));
                    let s = 0.5 * (b - a).cross(cn - a);
                    let q = u.dot(s) * if owner { 1.0 } else { -1.0 };
                    *face_sum.entry((f, usize::from(owner))).or_default() += q;
                    tri_flux.entry((f, i)).or_default().push(q);
                    for e in 0..3 {
                        let (x, y) = (t[e], t[(e + 1) % 3]);
                        let third = node(t[(e + 2) % 3]);
                        let mut si = 0.5 * (node(x) - cc).cross(node(y) - cc);
                        if si.dot(third - cc) > 0.0 {
                            si = -si;
                        }
                        // the flux out of this tetrahedron
                        inner
                            .entry((x.min(y), x.max(y)))
                            .or_default()
                            .push(u.dot(si));
                    }
                }
            }
            for (key, v) in inner {
                assert_eq!(v.len(), 2, "{shape:?}: cell {c} edge {key:?}");
                // out of one = into the other
                worst_inner = worst_inner.max((v[0] + v[1]).abs());
            }
        }
        assert!(worst_inner < 1e-12, "{shape:?}: inner {worst_inner:e}");
        for ((f, i), v) in &tri_flux {
            if v.len() == 2 {
                assert!(
                    (v[0] - v[1]).abs() < 1e-12,
                    "{shape:?}: face {f} triangle {i}: {v:?}"
                );
            }
        }
        for ((f, _), q) in &face_sum {
            assert!(
                (q - phi[*f as usize]).abs() < 1e-12,
                "{shape:?}: face {f}: {q} vs {}",
                phi[*f as usize]
            );
        }
    }
}
