//! Point location against an independent brute force: the generalized winding number of
//! each cell's closed surface (its faces triangulated as the decomposition does), summed
//! from the solid angles of the triangles (Van Oosterom & Strackee 1983). It shares no
//! code with the locator's barycentric probe.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scg_mesh::PolyMesh;
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
use scg_mesh::geometry::MeshGeometry;
use scg_mesh::locate::{Location, Locator};

/// Solid angle of triangle (a, b, c) seen from x (signed, sr).
fn solid_angle(x: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (a, b, c) = (a - x, b - x, c - x);
    let (la, lb, lc) = (a.length(), b.length(), c.length());
    let num = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * num.atan2(den)
}

/// Winding number of cell `c`'s surface about x (1 inside, 0 outside).
fn winding(m: &PolyMesh, g: &MeshGeometry, c: usize, x: DVec3) -> f64 {
    let mut w = 0.0;
    for &f in g.faces_of(c) {
        let f = f as usize;
        let pts: Vec<DVec3> = m.face(f).iter().map(|&p| m.points[p as usize]).collect();
        let sign = if m.owner[f] as usize == c { 1.0 } else { -1.0 };
        if pts.len() == 3 {
            w += sign * solid_angle(x, pts[0], pts[1], pts[2]);
        } else {
            let fc = g.face_centres[f];
            for i in 0..pts.len() {
                w += sign * solid_angle(x, fc, pts[i], pts[(i + 1) % pts.len()]);
            }
        }
    }
    w / (4.0 * std::f64::consts::PI)
}

/// The cells whose winding number about x is above one half.
fn brute(m: &PolyMesh, g: &MeshGeometry, x: DVec3) -> Vec<u32> {
    (0..m.n_cells)
        .filter(|&c| {
            let [lo, hi] = g.cell_bounds[c];
            x.cmpge(lo).all() && x.cmple(hi).all() && winding(m, g, c, x) > 0.5
        })
        .map(|c| c as u32)
        .collect()
}

fn meshes() -> Vec<(&'static str, PolyMesh)> {
    let lo = DVec3::new(-0.5, 0.0, 0.2);
    let hi = DVec3::new(0.5, 0.8, 1.0);
    vec![
        (
            "hex",
            BoxMesh::new(lo, hi, [8, 7, 6])
                .perturbed(0.25, 1)
                .build()
                .unwrap(),
        ),
        (
            "tet",
            BoxMesh::new(lo, hi, [6, 5, 4])
                .shape(CellShape::Tet)
                .perturbed(0.25, 2)
                .build()
                .unwrap(),
        ),
        (
            "poly",
            BoxMesh::new(lo, hi, [5, 5, 4])
                .shape(CellShape::Poly { refine: 0.35 })
                .perturbed(0.2, 3)
                .build()
                .unwrap(),
        ),
    ]
}

fn random_point(rng: &mut ChaCha8Rng, lo: DVec3, hi: DVec3) -> DVec3 {
    lo + (hi - lo) * DVec3::new(rng.random(), rng.random(), rng.random())
}

/// 400 random points per mesh: the grid's cell is the one cell the winding number puts
/// the point in (winding numbers are exactly 0 or 1 away from faces; points within 1e-9
/// of a face may be claimed by both neighbours, and then either answer is accepted).
#[test]
fn find_cell_agrees_with_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    for (name, m) in meshes() {
        let g = MeshGeometry::new(&m).unwrap();
        let loc = Locator::new(&m, &g).unwrap();
        let [lo, hi] = g.bounds();
        let mut checked = 0;
        for _ in 0..400 {
            let x = random_point(&mut rng, lo, hi);
            let want = brute(&m, &g, x);
            assert!(want.len() <= 1, "{name}: {x} in cells {want:?}");
            let got = loc.find_cell(x);
            assert_eq!(got, want.first().copied(), "{name}: {x}");
            checked += 1;
        }
        // points outside the box
        for _ in 0..50 {
            let x = random_point(&mut rng, lo - 0.3, hi + 0.3);
            if x.cmplt(lo).any() || x.cmpgt(hi).any() {
                assert_eq!(loc.find_cell(x), None, "{name}: {x}");
            }
        }
        println!("{name}: {} cells, {checked} points agree", m.n_cells);
    }
}

/// Random walks: from the cell of a random start, displacements of up to 4 cell sizes
/// inside the box; `track` ends in the cell brute force finds, and points outside the box
/// are reported as `Left` through the patch of the side they crossed.
#[test]
fn tracking_agrees_with_brute_force_and_reports_the_patch() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for (name, m) in meshes() {
        let g = MeshGeometry::new(&m).unwrap();
        let loc = Locator::new(&m, &g).unwrap();
        let [lo, hi] = g.bounds();
        let h = (hi - lo).max_element() / 6.0;
        let (mut inside, mut left, mut probed, mut grid) = (0, 0, 0, 0);
        let mut x = random_point(&mut rng, lo, hi);
        let mut cell = loc.find_cell(x).unwrap();
        for _ in 0..600 {
            let dir = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let y = x + dir * h * rng.random_range(0.0..4.0);
            let outside_box = y.cmplt(lo).any() || y.cmpgt(hi).any();
            let (location, walk) = loc.track_walk(cell, y);
            probed += walk.cells;
            grid += walk.grid as u32;
            match location {
                Location::Inside(hit) => {
                    assert!(
                        !outside_box,
                        "{name}: {y} outside but found in {}",
                        hit.cell
                    );
                    let want = brute(&m, &g, y);
                    assert_eq!(want, vec![hit.cell], "{name}: from {x} to {y}");
                    inside += 1;
                    x = y;
                    cell = hit.cell;
                }
                Location::Left { face, patch } => {
                    assert!(outside_box, "{name}: {y} inside but left");
                    // the patch is a side the point is beyond
                    let pname = &m.patches[patch as usize].name;
                    let axis = (pname.as_bytes()[0] - b'x') as usize;
                    let beyond = if pname.ends_with("min") {
                        y[axis] < lo[axis]
                    } else {
                        y[axis] > hi[axis]
                    };
                    assert!(beyond, "{name}: {y} left through {pname}");
                    assert_eq!(m.patch_of_face(face as usize), Some(patch as usize));
                    left += 1;
                }
                other => panic!("{name}: {other:?} for {y}"),
            }
        }
        println!(
            "{name}: {inside} moves inside, {left} boundary crossings, {:.1} cells probed per walk, {grid} grid fallbacks",
            probed as f64 / 600.0
        );
        assert_eq!(grid, 0, "{name}: every walk ends by itself");
        assert!(inside > 100 && left > 20, "{name}: both cases exercised");
    }
}

/// A box with a notch (concave): a move around the notch whose end is inside the mesh is
/// reported as `Crossed` on the `walls` patch of the notch, or `Inside` when the walk
/// went around; the end cell is always right.
#[test]
fn concave_boundary_crossing_is_reported() {
    let m = BoxMesh::new(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.25), [8, 8, 2])
        .naming(PatchNaming::InletOutletWalls { axis: 0 })
        .with_hole(DVec3::new(0.25, 0.25, -1.0), DVec3::new(0.75, 0.75, 2.0))
        .perturbed(0.1, 5)
        .build()
        .unwrap();
    let g = MeshGeometry::new(&m).unwrap();
    let loc = Locator::new(&m, &g).unwrap();
    // from the left of the notch to its right, straight through it
    let a = DVec3::new(0.1, 0.5, 0.1);
    let b = DVec3::new(0.9, 0.5, 0.1);
    let ca = loc.find_cell(a).unwrap();
    assert_eq!(
        loc.find_cell(DVec3::new(0.5, 0.5, 0.1)),
        None,
        "the notch is empty"
    );
    match loc.track(ca, b) {
        Location::Crossed { patch, hit, .. } => {
            assert_eq!(m.patches[patch as usize].name, "walls");
            assert_eq!(brute(&m, &g, b), vec![hit.cell]);
        }
        other => panic!("{other:?}"),
    }
}
