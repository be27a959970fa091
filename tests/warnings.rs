//! Warnings that mean something (issue 17): contacts are resolved when the run measures
//! them resolved, `scg check` estimates from the speeds it knows before the run, the
//! shipped cases and the default run print no warning, and a truly under-resolved scene
//! warns both before and after its run.

use std::process::Command;

use scg::core::physics::contact::normal::{effective_modulus, hertz_contact_time};
use scg::core::physics::scaling::sphere_mass;
use scg::scene::{check, parse};

/// A 1 mm glass sphere thrown at 0.5 m/s onto a floor (no fluid, no gravity).
const THROW: &str = r#"
name = "throw"
duration = 2.0e-3
dt = 1.0e-7

[material]
youngs_modulus = 1.0e8
poisson_ratio = 0.3
restitution = 0.9

[[walls]]
name = "floor"
kind = "plane"
point = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]

[[groups]]
name = "p"
diameter = 1.0e-3
density = 2500.0
positions = [[0.0, 0.0, 0.6e-3]]
velocities = [[0.0, 0.0, -0.5]]
"#;

fn run(set: &[&str]) -> (Vec<String>, scg::core::sim::Resolved) {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    let scene = parse(THROW, "throw.toml", "throw", &set).unwrap();
    let warnings = check::check(&scene).messages();
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    (warnings, sim.contact_resolution())
}

#[test]
fn measured_contact_time_is_hertz_at_the_impact_speed() {
    let (warnings, r) = run(&[]);
    assert!(warnings.is_empty(), "{warnings:?}");
    // No force acts before the contact: it starts at exactly 0.5 m/s, so the measured
    // duration is Hertz's t_c for m* = m, R* = d/2 (a wall) to rounding.
    let m = sphere_mass(1e-3, 2500.0);
    let e_eff = 1.0 / (2.0 * (1.0 - 0.09) / 1.0e8);
    assert!((e_eff - effective_modulus(1e8, 0.3, 1e8, 0.3)).abs() < 1e-6 * e_eff);
    let tc = hertz_contact_time(m, 0.5e-3, e_eff, 0.5);
    let w = r.wall;
    assert_eq!(w.contacts, 1, "{w:?}");
    let got = w.shortest.unwrap();
    assert!(
        (got - tc).abs() < 1e-12 * tc,
        "measured {got} vs Hertz {tc}"
    );
    assert_eq!(w.under_resolved, 0);
    assert!(r.warnings().is_empty());
    assert_eq!(r.pair.contacts, 0);
}

#[test]
fn an_under_resolved_throw_warns_before_and_after_the_run() {
    // t_c ≈ 38 µs: dt = 5 µs gives ~8 steps.
    let (warnings, r) = run(&["dt=5e-6"]);
    assert!(
        warnings
            .iter()
            .any(|m| m.starts_with("warning: group `p`") && m.contains("per wall contact")),
        "{warnings:?}"
    );
    assert_eq!(r.wall.under_resolved, 1, "{r:?}");
    let after = r.warnings();
    assert_eq!(after.len(), 1, "{after:?}");
    assert!(
        after[0].contains("1 of 1 particle–wall contacts"),
        "{after:?}"
    );
}

/// Particles at rest in a vortex whose inflow keeps them off the wall: nothing is known
/// to hit the wall before the run, so `scg check` does not guess from the flow speed.
#[test]
fn flow_speed_alone_raises_no_contact_warning() {
    let scene = parse(
        scg::scene::DEFAULT_SCENE,
        "vortex.toml",
        "vortex",
        &["dt=1e-5".into()],
    )
    .unwrap();
    let msgs = check::check(&scene).messages();
    assert!(
        !msgs.iter().any(|m| m.contains("per wall contact")),
        "{msgs:?}"
    );
}

#[test]
fn shipped_cases_and_the_default_run_print_no_warning() {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut cases: Vec<_> = std::fs::read_dir(format!("{root}/cases"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    cases.sort();
    assert!(cases.len() >= 5);
    // `scg check cases/*.toml`, all at once.
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .arg("check")
        .args(&cases)
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}");
    assert_eq!(text.matches("scene `").count(), cases.len(), "{text}");
    assert!(!text.contains("warning:"), "{text}");
    // The default run (the vortex), measured: every wall contact resolved.
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(["run", "--no-record"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{text}");
    assert!(!text.contains("warning:"), "{text}");
    assert!(text.contains("particle–wall contacts:"), "{text}");
}

/// An unknown `[checks] allow` name is an error naming the key and line.
#[test]
fn unknown_allowance_is_rejected() {
    let text = format!("{THROW}\n[checks]\nallow = [\"everything\"]\n");
    let err = parse(&text, "throw.toml", "throw", &[])
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("throw.toml:") && err.contains("everything"),
        "{err}"
    );
}
