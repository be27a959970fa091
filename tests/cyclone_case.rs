//! cases/cyclone.toml: the OpenFOAM cyclone (cases/cyclone/coarse, built by
//! cases/cyclone/build.sh and committed, so no OpenFOAM is needed) loads with its patches,
//! and a short run separates: fines leave through the vortex finder (`outlet`), coarse
//! particles stay in the cyclone, nothing is blown back out of the inlet.
//!
//! Run: `cargo test --release --test cyclone_case -- --nocapture`.

mod common;

use scg::core::stages::outlet::OutletLog;
use scg::core::state::Tally;
use scg::core::step::StepSystem;

#[test]
fn cyclone_separates_fines_from_coarse() {
    // A quarter of the feed (100 particles per group) and 1.6 s: the first 2 µm reach the
    // outlet after about 0.8 s.
    let scene = common::case("cyclone", &["feed_scale=0.25", "duration=1.6"]);
    let mut sim = scene.build(false);
    assert!(sim.plan().contains(StepSystem::IntegrateMeshFlow));
    assert!(sim.plan().contains(StepSystem::MeshBoundary));
    sim.run(scene.steps(), |_| true).unwrap();
    let ps = sim.particles();
    let resident: Vec<usize> = (0..4)
        .map(|g| ps.iter().filter(|p| p.group == g).count())
        .collect();
    let tally = sim.world.resource::<Tally>().clone();
    let log = sim.world.resource::<OutletLog>().clone();
    let lost: Vec<usize> = log.lost.iter().map(Vec::len).collect();
    println!(
        "cyclone: resident {resident:?}, drained {:?}, lost {lost:?}, fed {:?}",
        tally.drained, tally.fed
    );
    for g in 0..4 {
        assert_eq!(tally.fed[g], 100, "group {g}");
        assert_eq!(
            tally.fed[g],
            resident[g] as u64 + tally.drained[g] + lost[g] as u64
        );
        assert_eq!(lost[g], 0, "group {g}: blown back through the inlet");
    }
    // 2 µm (below the cut size, 4–8 µm) escape; 10 and 20 µm are all held.
    assert!(tally.drained[0] > 0, "no 2 µm particle escaped");
    assert!(tally.drained[0] >= tally.drained[1]);
    assert_eq!((tally.drained[2], tally.drained[3]), (0, 0));
    // Every resident particle is inside the cyclone (bounds of the mesh).
    for p in &ps {
        let x = p.position;
        assert!(x.z > -1.0 && x.z < 1.1 && x.x.hypot(x.y) < 0.56, "{x:?}");
    }
}
