//! Particle–particle contacts through scene files: the `[contacts]` table, the `auto` time
//! step, `scg check` warnings and a run through the `scg` binary with 1 and 2 threads.
//! (The physics against theory is in crates/scg-core/tests/contacts.rs.)

use scg::core::physics::contact::normal::{effective, hertz_contact_time};
use scg::core::physics::scaling::sphere_mass;
use scg::core::step::{StepSet, StepSystem};
use scg::scene::{check, parse};

const SCENE: &str = r#"
name = "contact_box"
duration = 2e-4
dt = "auto"

[material]
youngs_modulus = 1e8
poisson_ratio = 0.3
restitution = 0.7
friction = 0.3

[contacts]
periodic = [0.012, 0.012, 0.012]

[[groups]]
name = "small"
diameter = 1e-3
density = 2500.0
count = 300
velocity = [0.2, -0.1, 0.3]
region = { kind = "box", min = [0.0, 0.0, 0.0], max = [0.012, 0.012, 0.012] }

[[groups]]
name = "big"
diameter = 2e-3
density = 2500.0
count = 20
velocity = [-0.3, 0.2, 0.1]
region = { kind = "box", min = [0.0, 0.0, 0.0], max = [0.012, 0.012, 0.012] }
"#;

#[test]
fn contacts_table_wires_the_effect() {
    let scene = parse(SCENE, "contact_box.toml", "contact_box", &[]).unwrap();
    let c = scene.contacts.expect("contacts declared");
    assert!(
        (c.skin - 0.1 * 2e-3).abs() < 1e-15,
        "default skin = 0.1·d_max"
    );
    assert_eq!(c.rolling_friction, 0.0);
    let sim = scene.build(false);
    let plan = sim.plan();
    assert_eq!(
        plan.in_set(StepSet::NeighbourSearch).count(),
        1,
        "{}",
        plan.render()
    );
    let names: Vec<_> = plan.in_set(StepSet::Forces).map(|s| s.system).collect();
    assert_eq!(names, [StepSystem::ParticleContactForces]);
    // Contact forces and torques are applied as kicks before the drift; the rotation
    // pass exists only for wall torques.
    assert!(plan.contains(StepSystem::ApplyContactKicks));
    assert!(!plan.contains(StepSystem::IntegrateRotation));
}

#[test]
fn auto_dt_resolves_the_stiffest_pair() {
    let scene = parse(SCENE, "contact_box.toml", "contact_box", &[]).unwrap();
    let mat = scene.material.unwrap();
    // Small–small pair at the rule's approach speed: every particle starts with the same
    // velocity, so the largest known speed (the measured approach speeds are the run's).
    let m = sphere_mass(1e-3, 2500.0);
    let v = (0.3f64 * 0.3 + 0.2 * 0.2 + 0.1 * 0.1).sqrt();
    let tc = hertz_contact_time(effective(m, m), 0.25e-3, mat.effective_modulus(), v);
    assert!(
        scene.dt <= tc / 50.0 * 1.0001,
        "dt {} vs t_c/50 {}",
        scene.dt,
        tc / 50.0
    );
    assert!(check::particle_contact_time(&scene).is_some());
    let r = check::check(&scene);
    assert!(
        !r.messages()
            .iter()
            .any(|m| m.contains("per particle–particle contact"))
    );
    // A coarse fixed dt is warned about.
    let coarse = parse(
        SCENE,
        "contact_box.toml",
        "contact_box",
        &["dt=1e-5".into()],
    )
    .unwrap();
    let r = check::check(&coarse);
    assert!(
        r.messages()
            .iter()
            .any(|m| m.contains("per particle–particle contact")),
        "{:?}",
        r.messages()
    );
}

#[test]
fn bad_contacts_tables_are_rejected_with_key() {
    let no_material = SCENE.replace("[material]", "[unused]");
    let no_material = no_material
        .lines()
        .filter(|l| {
            ![
                "youngs_modulus",
                "poisson_ratio",
                "restitution",
                "friction",
                "[unused]",
            ]
            .iter()
            .any(|k| l.starts_with(k))
        })
        .collect::<Vec<_>>()
        .join("\n");
    let e = parse(&no_material, "x.toml", "x", &[]).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contacts"), "{e}");
    let e = parse(
        SCENE,
        "x.toml",
        "x",
        &["contacts.periodic=[0.003, 0.012, 0.012]".into()],
    )
    .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contacts.periodic"), "{e}");
    let e = parse(SCENE, "x.toml", "x", &["contacts.skin=-1".into()]).unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contacts.skin"), "{e}");
    let e = parse(
        SCENE,
        "x.toml",
        "x",
        &["contacts.rolling_friction=-0.1".into()],
    )
    .unwrap_err();
    assert_eq!(e.key.as_deref(), Some("contacts.rolling_friction"), "{e}");
    let e = parse(SCENE, "x.toml", "x", &["contacts.bogus=1".into()]).unwrap_err();
    assert!(e.to_string().contains("bogus"), "{e}");
}

#[test]
fn contact_scene_runs_and_counts_collisions() {
    let scene = parse(SCENE, "contact_box.toml", "contact_box", &[]).unwrap();
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    let tally = sim.world.resource::<scg::core::state::Tally>();
    eprintln!(
        "collisions per group: {:?} in {} steps",
        tally.collisions,
        scene.steps()
    );
    assert!(tally.collisions[0] > 0);
}

/// `scg run` of the scene with SCG_THREADS = 1 and 2. The binary's summary carries no
/// state digest, so this only checks that both runs succeed with contacts on; the
/// bit-for-bit thread-count comparison is in crates/scg-core/tests/contacts.rs
/// (`one_and_two_threads_give_identical_results`, child processes of the test binary).
#[test]
fn binary_runs_contact_scene_with_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("contact_box.toml");
    std::fs::write(&path, SCENE).unwrap();
    for threads in ["1", "2"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_scg"))
            .args(["run", path.to_str().unwrap(), "--no-record"])
            .env("SCG_THREADS", threads)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "threads {threads}: {err}");
        assert!(err.contains("done:"), "{err}");
    }
}
