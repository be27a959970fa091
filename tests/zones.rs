//! `[[zones]]` with the real step: particles falling freely (gravity, no fluid; the
//! ballistic step is exact for constant g) into a collecting box are removed at the first
//! step whose end puts their centre inside it, at the analytic time; a zone that does not
//! collect counts the particles inside at the end; the collect log survives a checkpoint
//! bit for bit.
//!
//! Run: `cargo test --release --test zones`.

use scg::core::stages::collect::CollectLog;

const SCENE: &str = r#"
name = "zones"
duration = 1.0
dt = 1.0e-3
record_every = 100

[gravity]
acceleration = [0.0, 0.0, -9.81]

[[zones]]
name = "bin"
collects = true
region = { kind = "box", min = [-1.0, -1.0, -2.0], max = [1.0, 1.0, 0.0] }

[[zones]]
name = "shelf"
region = { kind = "box", min = [5.0, -1.0, -10.0], max = [7.0, 1.0, 2.0] }

[[groups]]
name = "a"
diameter = 1.0e-3
density = 1000.0
positions = [[0.0, 0.0, 0.5], [0.0, 0.0, 1.0], [0.0, 0.0, 8.0], [6.0, 0.0, 1.0]]
"#;

fn scene() -> scg::scene::Scene {
    scg::scene::parse(SCENE, "zones.toml", "zones", &[]).expect("scene")
}

#[test]
fn falling_particles_are_collected_at_the_analytic_step() {
    let scene = scene();
    let mut sim = scene.build(false);
    assert!(
        sim.plan()
            .contains(scg::core::step::StepSystem::CollectParticles)
    );
    sim.run(scene.steps(), |_| true).unwrap();
    let log = sim.world.resource::<CollectLog>().clone();
    let (g, dt) = (9.81, scene.dt);
    // the first step n with z0 − g·(n·dt)²/2 ≤ 0 (the bin's top)
    let expect = |z0: f64| ((2.0 * z0 / g).sqrt() / dt).ceil() * dt;
    assert_eq!(log.collected.len(), 1);
    let t = &log.collected[0][0];
    assert_eq!(t.len(), 2, "{t:?}");
    for (got, z0) in t.iter().zip([0.5, 1.0]) {
        assert!(
            (got - expect(z0)).abs() < 1e-9,
            "z0 {z0}: {got} vs {}",
            expect(z0)
        );
    }
    let notes = scg::scene::check::check(&scene).messages().join("\n");
    assert!(
        notes.contains("zone `bin`: collects") && notes.contains("zone `shelf`: counts"),
        "{notes}"
    );
    let fates = scg::cli::fates::fates(&scene, &mut sim);
    let f = &fates[0];
    assert_eq!(f.collected(), 2);
    assert_eq!(f.zones[1], ("shelf".to_string(), false, 1));
    assert_eq!(f.airborne, 1); // the one from z = 8 is at 3.1 m, in no zone
    assert_eq!(f.accounted(), 4);
}

#[test]
fn the_collect_log_survives_a_checkpoint() {
    let scene = scene();
    let steps = scene.steps();
    let mut whole = scene.build(false);
    whole.run(steps, |_| true).unwrap();
    let mut a = scene.build(false);
    a.run(400, |_| true).unwrap(); // the first particle is collected by then, not the second
    assert_eq!(a.world.resource::<CollectLog>().count(0), 1);
    let c = a.checkpoint();
    assert!(c.collected.is_some());
    let mut b = scene.build(false);
    b.restore(&c).unwrap();
    b.run(steps - 400, |_| true).unwrap();
    assert_eq!(
        b.world.resource::<CollectLog>().collected,
        whole.world.resource::<CollectLog>().collected
    );
    assert_eq!(b.particles(), whole.particles());
    // a checkpoint of a scene without the zone is refused by this one
    let mut other = scg::scene::parse(
        SCENE,
        "zones.toml",
        "zones",
        &["zones.0.collects=false".into()],
    )
    .unwrap()
    .build(false);
    other.run(10, |_| true).unwrap();
    let mut d = scene.build(false);
    assert!(d.restore(&other.checkpoint()).is_err());
}

/// `collects_after`: no gravity, no fluid (constant velocities). A particle at rest in the
/// bin is collected after the wait, logged at the time it entered; one crossing the bin's
/// 2 m in 0.2 s (10 m/s) is collected too, at its entry time 0.05 s; one crossing it in
/// 0.05 s (40 m/s) is not: it leaves before the wait of 0.1 s. A checkpoint taken while
/// one waits restores the wait.
#[test]
fn a_zone_that_waits_takes_what_stays() {
    const WAITS: &str = r#"
name = "waits"
duration = 1.0
dt = 1.0e-3

[[zones]]
name = "bin"
collects = true
collects_after = 0.1
region = { kind = "box", min = [-1.0, -1.0, -2.0], max = [1.0, 1.0, 0.0] }

[[groups]]
name = "a"
diameter = 1.0e-3
density = 1000.0
positions = [[0.0, 0.0, -1.0], [0.0, 0.0, 0.5], [0.5, 0.0, 0.5]]
velocities = [[0.0, 0.0, 0.0], [0.0, 0.0, -10.0], [0.0, 0.0, -40.0]]
"#;
    let scene = scg::scene::parse(WAITS, "waits.toml", "waits", &[]).expect("scene");
    let notes = scg::scene::check::check(&scene).messages().join("\n");
    assert!(notes.contains("stays in it 0.1 s (100 steps)"), "{notes}");
    let mut sim = scene.build(false);
    sim.run(99, |_| true).unwrap();
    // the resting one entered at the first step and has waited 98 steps, the 10 m/s one
    // entered at step 50: both still there, waiting
    assert_eq!(sim.particles().len(), 3);
    assert_eq!(sim.world.resource::<CollectLog>().count(0), 0);
    let c = sim.checkpoint();
    assert_eq!(c.collect_inside, vec![(0, 0, 1), (1, 0, 50)]);
    sim.run(scene.steps() - 99, |_| true).unwrap();
    let log = sim.world.resource::<CollectLog>().clone();
    let t = &log.collected[0][0];
    assert_eq!(t.len(), 2, "{t:?}");
    assert!((t[0] - scene.dt).abs() < 1e-12, "{t:?}");
    assert!((t[1] - 0.05).abs() <= scene.dt + 1e-12, "{t:?}");
    let left = sim.particles();
    assert_eq!(left.len(), 1);
    assert!(left[0].position.z < -30.0, "{:?}", left[0].position);
    // restored mid-wait, the run ends the same
    let mut b = scene.build(false);
    b.restore(&c).unwrap();
    b.run(scene.steps() - 99, |_| true).unwrap();
    assert_eq!(b.world.resource::<CollectLog>().collected, log.collected);
    // without the wait all three are collected on entry
    let now = scg::scene::parse(
        WAITS,
        "waits.toml",
        "waits",
        &["zones.0.collects_after=0".into()],
    )
    .unwrap();
    let mut sim = now.build(false);
    sim.run(now.steps(), |_| true).unwrap();
    assert_eq!(sim.world.resource::<CollectLog>().count(0), 3);
    // a wait on a zone that does not collect names the key
    let e = scg::scene::parse(
        WAITS,
        "waits.toml",
        "waits",
        &["zones.0.collects=false".into()],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("zones[0].collects_after"), "{e}");
}
