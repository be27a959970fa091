//! Tests of [`super`] (neighbour).

use super::*;
use proptest::prelude::*;

type Cloud = (Vec<(f64, f64, f64, f64)>, f64, bool);

fn cloud() -> impl Strategy<Value = Cloud> {
    (
        prop::collection::vec((0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64), 0..250),
        0.0..0.05f64,
        any::<bool>(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    #[test]
    fn matches_brute_force((pts, skin, periodic) in cloud()) {
        // Box 1 × 0.8 × 1.3, diameters 0.01..0.08 (1:8), positions partly outside the
        // box to exercise wrapping.
        let l = DVec3::new(1.0, 0.8, 1.3);
        let pos: Vec<DVec3> = pts
            .iter()
            .map(|p| DVec3::new(p.0 * 1.5 - 0.25, p.1 * 0.8, p.2 * 2.0 - 0.5))
            .collect();
        let radius: Vec<f64> = pts.iter().map(|p| 0.5 * (0.01 + 0.07 * p.3)).collect();
        let pb = periodic.then_some(PeriodicBox::new(l));
        let mut list = NeighbourList::new(skin, pb);
        list.build(&pos, &radius);
        let expect = brute_force_pairs(&pos, &radius, skin, pb.as_ref());
        prop_assert_eq!(&list.pairs, &expect);
    }

    #[test]
    fn dense_polydisperse_matches_brute_force(pts in prop::collection::vec((0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64), 2..400), periodic in any::<bool>()) {
        // A small box packed with particles (many neighbours per particle, few cells
        // per axis in the periodic case).
        let l = DVec3::new(0.3, 0.25, 0.2);
        let pos: Vec<DVec3> = pts.iter().map(|p| DVec3::new(p.0, p.1, p.2) * l).collect();
        let radius: Vec<f64> = pts.iter().map(|p| 0.5 * (0.005 + 0.035 * p.3)).collect();
        let pb = periodic.then_some(PeriodicBox::new(l));
        let mut list = NeighbourList::new(0.004, pb);
        list.build(&pos, &radius);
        prop_assert_eq!(&list.pairs, &brute_force_pairs(&pos, &radius, 0.004, pb.as_ref()));
    }
}

#[test]
fn rebuild_only_after_half_skin() {
    let mut pos = vec![DVec3::ZERO, DVec3::new(0.1, 0.0, 0.0)];
    let r = vec![0.05, 0.05];
    let mut l = NeighbourList::new(0.02, None);
    assert!(l.update(&pos, &r, None));
    pos[0].x += 0.009;
    assert!(!l.update(&pos, &r, None));
    pos[0].x += 0.002;
    assert!(l.update(&pos, &r, None));
    assert_eq!(l.builds, 2);
}

#[test]
fn drift_bound_skips_exact_checks_until_it_may_matter() {
    let mut pos = vec![DVec3::ZERO, DVec3::new(0.1, 0.0, 0.0)];
    let r = vec![0.05, 0.05];
    let mut l = NeighbourList::new(0.02, None);
    assert!(l.update(&pos, &r, Some(0.0)));
    // Bound 0.004 + 0.004 ≤ 0.01: no exact check.
    for _ in 0..2 {
        pos[0].x += 0.004;
        assert!(!l.update(&pos, &r, Some(0.004)));
    }
    assert_eq!(l.checks, 0);
    // A conservative report (the particle stood still): bound 0.012 > 0.01, so an
    // exact check finds 0.008, no rebuild, and the bound becomes 0.008.
    assert!(!l.update(&pos, &r, Some(0.004)));
    assert_eq!((l.checks, l.builds), (1, 1));
    // 0.008 + 0.003 > 0.01 → exact check → 0.011 > 0.01 → rebuild.
    pos[0].x += 0.003;
    assert!(l.update(&pos, &r, Some(0.003)));
    assert_eq!((l.checks, l.builds), (2, 2));
}

/// Above the block size the list is built in parallel blocks: still exactly the
/// brute-force pairs, in the same order, with and without periodicity.
#[test]
fn parallel_build_matches_brute_force() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let n = 12_000;
    let pos: Vec<DVec3> = (0..n)
        .map(|_| {
            DVec3::new(
                rng.random::<f64>(),
                rng.random::<f64>(),
                rng.random::<f64>(),
            )
        })
        .collect();
    let radius: Vec<f64> = (0..n).map(|_| rng.random_range(0.002..0.016)).collect();
    for periodic in [None, Some(PeriodicBox::new(DVec3::ONE))] {
        let mut list = NeighbourList::new(0.004, periodic);
        list.build(&pos, &radius);
        let want = brute_force_pairs(&pos, &radius, 0.004, periodic.as_ref());
        assert!(want.len() > 1000);
        assert_eq!(list.pairs, want);
    }
}

/// An even cloud in a box far larger than the particles need gets the coarse grid;
/// the same cloud split into two far-apart clusters gets hashed cells; a packed box
/// the dense grid. All three give the brute-force pairs, in order, also above the
/// parallel block size.
#[test]
fn each_grid_gives_the_brute_force_pairs() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let n = 8_000;
    let mut unit = || DVec3::new(rng.random(), rng.random(), rng.random());
    // 8000 spheres of 3 mm, skin 1 mm (cut-off 4 mm), in a 0.635 m cube: cells of
    // (0.256 / 32 000)^(1/3) = 20 mm, five cut-offs.
    let spread: Vec<DVec3> = (0..n).map(|_| unit() * 0.635).collect();
    let radius = vec![0.0015; n];
    let clustered: Vec<DVec3> = spread
        .iter()
        .enumerate()
        .map(|(k, x)| x * 0.08 + DVec3::splat(if k % 2 == 0 { 0.0 } else { 100.0 }))
        .collect();
    let packed: Vec<DVec3> = spread.iter().map(|x| x * 0.25).collect();
    for (pos, kind) in [
        (&spread, GridKind::Coarse),
        (&clustered, GridKind::Hashed),
        (&packed, GridKind::Dense),
    ] {
        let mut list = NeighbourList::new(0.001, None);
        list.build(pos, &radius);
        assert_eq!(list.grid, kind);
        let want = brute_force_pairs(pos, &radius, 0.001, None);
        assert!(want.len() > 10, "{kind:?}: {} pairs", want.len());
        assert_eq!(list.pairs, want, "{kind:?}");
    }
}

#[test]
fn far_apart_particles_stay_cheap() {
    // Two clusters 1e6 cell edges apart: hashing keeps memory per occupied cell.
    let pos = vec![DVec3::ZERO, DVec3::new(0.001, 0.0, 0.0), DVec3::splat(1e4)];
    let r = vec![0.001, 0.001, 0.001];
    let mut l = NeighbourList::new(0.0001, None);
    l.build(&pos, &r);
    assert_eq!(l.pairs, vec![[0, 1]]);
}

/// A cloud filling half a periodic box (one rank's region of a decomposed run): its
/// cells are sized by the half it occupies, not by the whole box (twice the candidates
/// per particle on 2 ranks, measured: a rank's dilute-cloud build took as long as the
/// whole cloud's on one rank), and the pairs are the brute-force ones.
#[test]
fn a_periodic_grid_is_sized_by_the_slices_the_particles_occupy() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let b = PeriodicBox::new(DVec3::new(0.4, 0.3, 0.2));
    // x in [0, 0.2) and a sliver across the side, x in [0.39, 0.4) (ghosts).
    let pos: Vec<DVec3> = (0..6000)
        .map(|k| {
            let x = if k % 20 == 0 {
                0.39 + 0.01 * rng.random::<f64>()
            } else {
                0.2 * rng.random::<f64>()
            };
            DVec3::new(x, 0.3 * rng.random::<f64>(), 0.2 * rng.random::<f64>())
        })
        .collect();
    let v = occupied_volume(&pos, &b);
    let whole = 0.4 * 0.3 * 0.2;
    // 32 slices of x below 0.2, and 62 and 63 across the side; y and z whole.
    assert!((v - 34.0 / 64.0 * whole).abs() < 1e-12, "{v}");
    let two = occupied_volume(&[DVec3::ZERO, DVec3::new(0.39, 0.29, 0.19)], &b);
    assert!(
        (two - whole * (2.0f64 / 64.0).powi(3)).abs() < 1e-15,
        "{two}"
    );
    let radius = vec![0.002; pos.len()];
    let mut list = NeighbourList::new(0.001, Some(b));
    list.build(&pos, &radius);
    assert_eq!(list.grid, GridKind::Dense);
    let want = brute_force_pairs(&pos, &radius, 0.001, Some(&b));
    assert!(want.len() > 100, "{} pairs", want.len());
    assert_eq!(list.pairs, want);
}
