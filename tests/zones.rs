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
