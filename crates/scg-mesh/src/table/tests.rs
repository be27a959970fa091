//! Tests of [`super`] (table).

use super::*;
use crate::build::{BoxMesh, CellShape};
use crate::interp::Interpolation;
use crate::locate::{Location, Locator};
use crate::{CellField, MeshGeometry};
use rand::{Rng, SeedableRng};

/// Every interpolation scheme.
const ALL_SCHEMES: [Interpolation; 4] = [
    Interpolation::CellPoint,
    Interpolation::CellPointIdw,
    Interpolation::CellValue,
    Interpolation::Conservative,
];

/// A unit box of n³ perturbed cells of `shape`, its geometry and a smooth field.
fn perturbed_box(shape: CellShape, n: usize) -> (crate::PolyMesh, MeshGeometry, CellField) {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::ONE, [n, n, n])
        .shape(shape)
        .perturbed(0.2, 4)
        .build()
        .unwrap();
    let g = MeshGeometry::new(&m).unwrap();
    let field = CellField::at_cell_centres(&m, &g, |c| {
        DVec3::new(c.y * c.z, (3.0 * c.x).sin(), c.x * c.x)
    });
    (m, g, field)
}

/// `f` on the table of a perturbed 5³ box of each cell shape (hex, tet, polyhedra) and each
/// of `schemes` (all patches outflow for the conservative scheme): the shape, the scheme,
/// the mesh, its geometry, the locator, the interpolator and the table.
fn for_each_table(
    schemes: &[Interpolation],
    mut f: impl FnMut(
        CellShape,
        Interpolation,
        &crate::PolyMesh,
        &MeshGeometry,
        &Locator,
        &crate::Interpolator,
        &CellTable,
    ),
) {
    for shape in [
        CellShape::Hex,
        CellShape::Tet,
        CellShape::Poly { refine: 0.3 },
    ] {
        let (m, g, field) = perturbed_box(shape, 5);
        let loc = Locator::new(&m, &g).unwrap();
        for &scheme in schemes {
            let outflow = vec![true; m.patches.len()];
            let it = crate::Interpolator::with_outflow(&loc, &field, scheme, &outflow).unwrap();
            let t = CellTable::new(&it).unwrap();
            f(shape, scheme, &m, &g, &loc, &it, &t);
        }
    }
}

/// At random points of perturbed hex, tet and polyhedral boxes, the table finds the
/// point in the cell the locator finds (or declines) and interpolates the locator's
/// value to rounding, for every scheme; it declines for another cell.
#[test]
fn table_agrees_with_the_locator_and_interpolator() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    for_each_table(&ALL_SCHEMES, |shape, scheme, m, g, loc, it, t| {
        {
            let (simple, none) = t.counts();
            assert_eq!(none, 0);
            if shape == CellShape::Tet && scheme != Interpolation::Conservative {
                assert_eq!(simple, m.n_cells);
            } else {
                assert_eq!(simple, 0);
            }
            let (mut found, mut n) = (0, 0);
            for _ in 0..2000 {
                let x = DVec3::new(rng.random(), rng.random(), rng.random());
                let Location::Inside(h) = loc.track(0, x) else {
                    continue;
                };
                n += 1;
                if let Some(u) = t.velocity_in(h.cell, x) {
                    found += 1;
                    let want = it.at(&h);
                    assert!(
                        (u - want).length() <= 1e-12 * (1.0 + want.length()),
                        "{shape:?} {scheme:?}: {u} vs {want}"
                    );
                }
                // another cell (far enough): declines
                let other = (h.cell + m.n_cells as u32 / 2) % m.n_cells as u32;
                if (g.cell_centres[other as usize] - x).length() > 0.5 {
                    assert!(t.velocity_in(other, x).is_none());
                }
            }
            println!("{shape:?} {scheme:?}: table found {found} of {n}");
            assert!(
                found as f64 >= 0.999 * n as f64,
                "{shape:?}: {found} of {n}"
            );
            assert!(t.velocity_in(u32::MAX, DVec3::ZERO).is_none());
        }
    });
}

/// Walking on the table from a cell near x ends in the locator's cell with the
/// interpolator's value, or declines; toward a point outside the mesh it meets the
/// boundary face the ray crosses, or declines.
#[test]
fn table_walk_ends_where_the_locator_does() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for shape in [
        CellShape::Tet,
        CellShape::Hex,
        CellShape::Poly { refine: 0.3 },
    ] {
        let (m, g, field) = perturbed_box(shape, 6);
        let loc = Locator::new(&m, &g).unwrap();
        let it = crate::Interpolator::new(&loc, &field, Interpolation::CellPoint).unwrap();
        let t = CellTable::new(&it).unwrap();
        let (mut walked, mut n, mut boundary) = (0, 0, 0);
        for _ in 0..4000 {
            let x = DVec3::new(rng.random(), rng.random(), rng.random());
            // start from the cell of a point up to ~1.5 cells away
            let off = DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5;
            let Location::Inside(s) = loc.track(0, x + off * 0.5) else {
                continue;
            };
            let Location::Inside(h) = loc.track(0, x) else {
                continue;
            };
            n += 1;
            match t.walk(s.cell, NO_TET, x, 4) {
                TableWalk::Inside { cell, value, .. } => {
                    if cell != s.cell {
                        walked += 1;
                    }
                    assert_eq!(cell, h.cell, "{shape:?}: x {x}");
                    let want = it.at(&h);
                    assert!((value - want).length() <= 1e-12 * (1.0 + want.length()));
                }
                TableWalk::Boundary { .. } => panic!("{shape:?}: x {x} is inside"),
                TableWalk::Unknown => {}
            }
            // beyond the box's x = 1 side: never inside, and the boundary face met
            // is one of that side's (its centre at x = 1)
            let out = DVec3::new(1.0 + 0.1 * rng.random::<f64>(), x.y, x.z);
            match t.walk(h.cell, NO_TET, out, 64) {
                TableWalk::Inside { .. } => panic!("{shape:?}: {out} is outside"),
                TableWalk::Boundary { cell, face } => {
                    boundary += 1;
                    assert_eq!(m.owner[face as usize], cell);
                    assert!((g.face_centres[face as usize].x - 1.0).abs() < 1e-9);
                    assert_ne!(loc.patch_of(face), u32::MAX);
                    assert!(face as usize >= m.n_internal_faces());
                }
                TableWalk::Unknown => {}
            }
        }
        println!("{shape:?}: walked to another cell for {walked} of {n}");
        assert!(walked as f64 > 0.2 * n as f64, "{walked} of {n}");
        assert!(boundary as f64 > 0.5 * n as f64, "{boundary} of {n}");
    }
}

/// The tetrahedron hint changes what a query reads, never its answer: at points on and
/// next to every side of the tetrahedra (within 10^-12 to 10^-6 of it, where a tolerance
/// decides) and along short moves, the hinted query gives the unhinted one's cell,
/// tetrahedron and value bit for bit, for every scheme and cell shape; and the hint alone
/// answers most steps of a move (the fast path is taken).
#[test]
fn tet_hints_change_no_answer() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let schemes = [
        Interpolation::CellPoint,
        Interpolation::CellPointIdw,
        Interpolation::Conservative,
    ];
    for_each_table(&schemes, |shape, scheme, _, _, loc, _, t| {
        {
            let bits = |w: TableWalk| match w {
                TableWalk::Inside { cell, tet, value } => {
                    Some((cell, tet, value.to_array().map(f64::to_bits)))
                }
                _ => None,
            };
            // next to the sides: a random tetrahedron record, a point on one of its
            // sides (or at a corner) moved off it by up to 1e-6 of the cell
            let mut near = 0;
            for _ in 0..if t.r.tets.is_empty() { 0 } else { 20_000 } {
                let k = rng.random_range(0..t.r.tets.len());
                let r = &t.r.tets[k];
                let c = r.cell;
                let cc = t.r.cells[c as usize].cc;
                let inv = glam::DMat3::from_cols(r.m[0], r.m[1], r.m[2])
                    .transpose()
                    .inverse();
                let mut w: [f64; 3] = [rng.random(), rng.random(), rng.random()];
                let s: f64 = w.iter().sum();
                w = w.map(|x| x / s * rng.random::<f64>());
                w[rng.random_range(0..3)] = 0.0;
                let scale = 10f64.powf(rng.random_range(-12.0..-6.0));
                let jiggle = DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5;
                let x = cc + inv * DVec3::from(w) + jiggle * scale;
                let plain = bits(t.walk(c, NO_TET, x, 0));
                let hinted = bits(t.walk(c, k as u32, x, 0));
                assert_eq!(plain, hinted, "{shape:?} {scheme:?}: tet {k}, x {x}");
                // hinted by a sibling, and by the tetrahedron across (from the next cell)
                let sibling = r.links[rng.random_range(0..3)];
                assert_eq!(
                    plain,
                    bits(t.walk(c, sibling, x, 0)),
                    "{shape:?}: {sibling}"
                );
                if let Some(a) = t.r.tets.get(r.across as usize) {
                    let from_next = t.walk(a.cell, r.across, x, 2);
                    assert_eq!(bits(from_next), bits(t.walk(a.cell, NO_TET, x, 2)));
                }
                if matches!(t.view(Own).hinted(c, &t.r.cells[c as usize], k as u32, x - cc), Some(Query::Inside(_, h)) if h == k as u32)
                {
                    near += 1;
                }
            }
            // along moves of 1 % of a cell per step, each query hinted by the last
            let (mut steps, mut fast) = (0, 0);
            for _ in 0..200 {
                let mut x = DVec3::new(rng.random(), rng.random(), rng.random()) * 0.8 + 0.1;
                let Location::Inside(h) = loc.track(0, x) else {
                    continue;
                };
                let (mut c, mut tet) = (h.cell, NO_TET);
                let dir = (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 0.004;
                for _ in 0..100 {
                    x += dir;
                    let plain = t.walk(c, NO_TET, x, 4);
                    let hinted = t.walk(c, tet, x, 4);
                    assert_eq!(bits(plain), bits(hinted), "{shape:?} {scheme:?}: x {x}");
                    if let Some(r) = t.r.tets.get(tet as usize)
                        && r.cell == c
                        && t.view(Own)
                            .hinted(c, &t.r.cells[c as usize], tet, x - t.r.cells[c as usize].cc)
                            .is_some()
                    {
                        fast += 1;
                    }
                    steps += 1;
                    match hinted {
                        TableWalk::Inside { cell, tet: k, .. } => (c, tet) = (cell, k),
                        _ => break,
                    }
                }
            }
            println!(
                "{shape:?} {scheme:?}: hint alone {fast} of {steps} steps, {near} of 20000 next to a side"
            );
            if t.counts().0 == 0 {
                assert!(
                    fast as f64 > 0.8 * steps as f64,
                    "{shape:?} {scheme:?}: {fast} of {steps}"
                );
            }
        }
    });
}

/// A table of another field on shared records ([`CellTable::for_field`]) answers every
/// query and walk, hinted or not, bit for bit as a table built from scratch for that field,
/// on every cell shape and scheme, and holds less; a table on another mesh is refused.
#[test]
fn a_table_for_another_field_answers_as_its_own_table() {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let bits = |w: TableWalk| match w {
        TableWalk::Inside { cell, tet, value } => (cell, tet, value.to_array().map(f64::to_bits)),
        TableWalk::Boundary { cell, face } => (cell, face, [0; 3]),
        TableWalk::Unknown => (u32::MAX, u32::MAX, [0; 3]),
    };
    for_each_table(&ALL_SCHEMES, |shape, scheme, m, g, loc, _, t| {
        let other = CellField::at_cell_centres(m, g, |c| {
            DVec3::new((2.0 * c.z).cos(), c.x - c.y * c.y, 0.3 * c.y)
        });
        let outflow = vec![true; m.patches.len()];
        let it = crate::Interpolator::with_outflow(loc, &other, scheme, &outflow).unwrap();
        let fresh = CellTable::new(&it).unwrap();
        let shared = t.for_field(&it).unwrap();
        assert!(shared.shares_records(t) && !fresh.shares_records(t));
        assert!(shared.bytes() < fresh.bytes(), "{shape:?} {scheme:?}");
        let (mut inside, mut hinted) = (0, 0);
        for _ in 0..3000 {
            let x = DVec3::new(rng.random(), rng.random(), rng.random());
            let c = rng.random_range(0..m.n_cells as u32);
            let a = fresh.walk(c, NO_TET, x, 6);
            assert_eq!(
                bits(a),
                bits(shared.walk(c, NO_TET, x, 6)),
                "{shape:?} {scheme:?}"
            );
            assert_eq!(fresh.velocity_in(c, x), shared.velocity_in(c, x));
            if let TableWalk::Inside { cell, tet, .. } = a {
                inside += 1;
                // a small move from there, hinted
                let y = x + (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 0.01;
                let (p, q) = (fresh.walk(cell, tet, y, 2), shared.walk(cell, tet, y, 2));
                assert_eq!(bits(p), bits(q), "{shape:?} {scheme:?}: hinted");
                hinted += usize::from(matches!(p, TableWalk::Inside { .. }));
            }
        }
        assert!(inside > 300 && hinted > 250, "{shape:?}: {inside} {hinted}");
    });
    // another mesh (other cell count): refused
    let (m, g, field) = perturbed_box(CellShape::Hex, 4);
    let loc = Locator::new(&m, &g).unwrap();
    let it = crate::Interpolator::new(&loc, &field, Interpolation::CellPoint).unwrap();
    let (m5, g5, f5) = perturbed_box(CellShape::Hex, 5);
    let loc5 = Locator::new(&m5, &g5).unwrap();
    let it5 = crate::Interpolator::new(&loc5, &f5, Interpolation::CellPoint).unwrap();
    assert!(CellTable::new(&it5).unwrap().for_field(&it).is_none());
}
