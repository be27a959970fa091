//! Hard cases that must stay numerically stable, each with its pass criterion.
//!
//! Run: `cargo test --release --test hard_cases` (well under a minute). The 10⁶-step
//! elastic box is `#[ignore]`d: `cargo test --release --test hard_cases -- --ignored`.

mod common;

use std::process::Command;

use glam::DVec3;
use scg::core::diagnostics::kinetic_energy_and_momentum;
use scg::core::physics::contact::normal::{OVERLAP_CAP, effective, hertz_stiffness};
use scg::scene::{Scene, check, parse};

fn scene(text: &str, set: &[&str]) -> Scene {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    parse(text, "hard.toml", "hard", &set).unwrap_or_else(|e| panic!("{e}"))
}

fn messages(s: &Scene) -> Vec<String> {
    check::check(s).messages()
}

/// Run the `scg` binary on `text`; (exit code, stderr).
fn scg(args: &[&str], text: &str) -> (i32, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("hard.toml");
    std::fs::write(&path, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(args)
        .arg(&path)
        .current_dir(dir.path())
        .output()
        .unwrap();
    let err =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    assert!(!err.contains("panicked"), "panic: {err}");
    (out.status.code().unwrap_or(-1), err)
}

// ── stiff drag ──────────────────────────────────────────────────────────────────────────

/// 1 µm, 1000 kg/m³ in air: τ = ρd²/(18μ) ≈ 3.09 µs; dt = 1000·τ.
const TAU_1UM: f64 = 1000.0 * 1e-12 / (18.0 * 1.8e-5);

fn stiff_scene(integrator: &str) -> String {
    format!(
        r#"
duration = {dur:e}
dt = {dt:e}
integrator = "{integrator}"
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "uniform"
velocity = [0.01, 0.0, 0.0]
[drag]
law = "stokes"
[[groups]]
name = "p"
diameter = 1e-6
density = 1000.0
positions = [[0.0, 0.0, 0.0]]
"#,
        dt = 1000.0 * TAU_1UM,
        dur = 20.0 * 1000.0 * TAU_1UM,
    )
}

/// Exact solution from rest in a uniform flow u: x(t) = u·(t − τ(1 − e^(−t/τ))).
fn stiff_exact(t: f64) -> f64 {
    0.01 * (t - TAU_1UM * (1.0 - (-t / TAU_1UM).exp()))
}

#[test]
fn stiff_drag_exponential_stays_exact() {
    let s = scene(&stiff_scene("exponential"), &[]);
    let mut sim = s.build(false);
    for k in 1..=20 {
        sim.step().unwrap();
        let p = sim.particles()[0];
        let t = k as f64 * s.dt;
        let x = stiff_exact(t);
        assert!(
            (p.position.x - x).abs() <= 1e-12 * x.abs(),
            "step {k}: x = {:e}, exact {x:e}",
            p.position.x
        );
        assert!((p.velocity.x - 0.01).abs() < 1e-15);
    }
    assert!(
        messages(&s).iter().all(|m| !m.contains("explicit")),
        "{:?}",
        messages(&s)
    );
}

#[test]
fn stiff_drag_explicit_is_substepped_with_a_warning() {
    let text = stiff_scene("explicit");
    let s = scene(&text, &[]);
    let n = scg::core::physics::integrate::explicit_substeps(TAU_1UM, s.dt);
    assert!(n >= 2000, "sub-steps {n}");
    let msgs = messages(&s);
    assert!(
        msgs.iter().any(|m| m.contains("explicit integrator")
            && m.contains("> τ/2")
            && m.contains("sub-steps it 200")
            && m.contains("times per step")),
        "{msgs:?}"
    );
    // The same warning through `scg check`.
    let (code, out) = scg(&["check"], &text);
    assert_eq!(code, 0, "{out}");
    assert!(
        out.contains("warning: group `p`: explicit integrator"),
        "{out}"
    );
    // Stable: sub-stepped explicit Euler relaxes onto the flow, no overshoot, no NaN.
    let mut sim = s.build(false);
    for k in 1..=20 {
        sim.step().unwrap();
        let p = sim.particles()[0];
        assert!(p.velocity.is_finite() && p.position.is_finite());
        assert!(
            p.velocity.x <= 0.01 * (1.0 + 1e-12),
            "overshoot at step {k}"
        );
        let x = stiff_exact(k as f64 * s.dt);
        assert!((p.position.x - x).abs() < 1e-3 * x, "step {k}");
    }
}

// ── head-on impact ──────────────────────────────────────────────────────────────────────

const IMPACT: &str = r#"
duration = 1.2e-5
dt = "auto"
[material]
youngs_modulus = 1e9
poisson_ratio = 0.3
restitution = 0.8
[contacts]
[[groups]]
name = "a"
diameter = 1e-3
density = 2500.0
positions = [[-0.6e-3, 0.0, 0.0], [0.6e-3, 0.0, 0.0]]
velocities = [[25.0, 0.0, 0.0], [-25.0, 0.0, 0.0]]
"#;

/// Elastic energy of the Hertz overlap between two equal particles: (2/5)·K·δ^(5/2).
fn hertz_energy(s: &Scene, a: DVec3, b: DVec3, d: f64, m: f64) -> f64 {
    let _ = m;
    let delta = d - (a - b).length();
    if delta <= 0.0 {
        return 0.0;
    }
    let r_eff = effective(0.5 * d, 0.5 * d);
    let k = hertz_stiffness(s.material.unwrap().effective_modulus(), r_eff);
    // Beyond the cap the force stays at its value there (OVERLAP_CAP).
    let c = OVERLAP_CAP * r_eff;
    if delta <= c {
        0.4 * k * delta.powf(2.5)
    } else {
        0.4 * k * c.powf(2.5) + k * c.powf(1.5) * (delta - c)
    }
}

#[test]
fn head_on_impact_at_50_m_per_s() {
    let s = scene(IMPACT, &[]);
    let mut sim = s.build(false);
    let m = scg::core::physics::scaling::sphere_mass(1e-3, 2500.0);
    let energy = |sim: &mut scg::core::Simulation| {
        let (ke, _) = kinetic_energy_and_momentum(&mut sim.world);
        let p = sim.particles();
        ke + hertz_energy(&s, p[0].position, p[1].position, 1e-3, m)
    };
    let e0 = energy(&mut sim);
    let mut prev = e0;
    let mut touched = false;
    for _ in 0..s.steps() {
        sim.step().unwrap();
        let e = energy(&mut sim);
        assert!(e.is_finite());
        // Energy (kinetic + elastic) never increases: the damped contact only removes it.
        // Tolerance: the elastic energy sampled at the discrete steps of a resolved
        // contact (≈ 50 steps) wiggles by less than 0.1 % of E₀.
        assert!(e <= e0 * (1.0 + 1e-3), "energy above start: {e0:e} → {e:e}");
        assert!(e - prev <= 1e-3 * e0, "energy rose: {prev:e} → {e:e}");
        prev = e;
        let p = sim.particles();
        touched |= (p[0].position - p[1].position).length() < 1e-3;
    }
    assert!(touched);
    let p = sim.particles();
    assert!(
        (p[0].position - p[1].position).length() > 1e-3,
        "separated at the end"
    );
    let rebound = (p[1].velocity - p[0].velocity).x / 50.0;
    assert!(
        (rebound - 0.8).abs() < 0.02 * 0.8,
        "rebound {rebound} vs e = 0.8"
    );
}

// ── initial overlap ─────────────────────────────────────────────────────────────────────

const OVERLAP: &str = r#"
duration = 2e-4
dt = "auto"
[material]
youngs_modulus = 1e8
poisson_ratio = 0.3
restitution = 0.5
[contacts]
[[groups]]
name = "a"
diameter = 1e-3
density = 2500.0
positions = [[0.0, 0.0, 0.0], [0.5e-3, 0.0, 0.0]]
"#;

#[test]
fn particles_started_half_overlapping_separate_with_bounded_speed() {
    let s = scene(OVERLAP, &[]);
    let msgs = messages(&s);
    assert!(
        msgs.iter()
            .any(|m| m.contains("overlap") && m.contains("50.0 %")),
        "{msgs:?}"
    );
    let m = scg::core::physics::scaling::sphere_mass(1e-3, 2500.0);
    let mut sim = s.build(false);
    let p = sim.particles();
    // The stored elastic energy bounds the kinetic energy the contact can release.
    let u0 = hertz_energy(&s, p[0].position, p[1].position, 1e-3, m);
    let vmax = (2.0 * u0 / effective(m, m)).sqrt();
    for _ in 0..s.steps() {
        sim.step().unwrap();
        let (ke, _) = kinetic_energy_and_momentum(&mut sim.world);
        assert!(
            ke.is_finite() && ke <= u0 * (1.0 + 1e-6),
            "ke {ke:e} > {u0:e}"
        );
    }
    let p = sim.particles();
    let dist = (p[0].position - p[1].position).length();
    assert!(dist > 1e-3, "separated: {dist:e}");
    let speed = (p[1].velocity - p[0].velocity).length();
    assert!(speed > 0.0 && speed <= vmax, "speed {speed} vs cap {vmax}");
}

// ── vortex axis, walls, outside ─────────────────────────────────────────────────────────

fn vortex_one(position: &str) -> String {
    let base = scg::scene::DEFAULT_SCENE;
    let head = base.split("[[groups]]").next().unwrap();
    format!(
        "{head}\n[[groups]]\nname = \"p\"\ndiameter = 10e-6\ndensity = 1000.0\npositions = [{position}]\n"
    )
}

#[test]
fn particle_on_the_vortex_axis_stays_there() {
    let text = vortex_one("[0.0, 0.0, 0.0]");
    let s = scene(&text, &["duration=0.01"]);
    assert!(!check::check(&s).has_errors());
    let mut sim = s.build(false);
    sim.run(s.steps(), |_| true).unwrap();
    let p = sim.particles()[0];
    assert_eq!(p.position, DVec3::ZERO, "the flow is zero on the axis");
    assert_eq!(p.velocity, DVec3::ZERO);
}

#[test]
fn particle_exactly_on_the_vessel_wall_is_pushed_inside() {
    let text = vortex_one("[5.0e-4, 0.0, 0.0]");
    let s = scene(&text, &["duration=0.01"]);
    assert!(
        !check::check(&s).has_errors(),
        "centre on the wall is inside"
    );
    let mut sim = s.build(false);
    sim.run(s.steps(), |_| true).unwrap();
    let p = sim.particles()[0];
    assert!(p.position.is_finite() && p.velocity.is_finite());
    let r = (p.position.x.powi(2) + p.position.y.powi(2)).sqrt();
    assert!(r + 5e-6 <= 5e-4 * (1.0 + 1e-3), "r = {r:e}");
}

#[test]
fn particle_outside_the_vessel_is_refused() {
    let text = vortex_one("[6.0e-4, 0.0, 0.0]");
    let s = scene(&text, &[]);
    let r = check::check(&s);
    assert!(r.has_errors());
    let (code, out) = scg(&["run", "--no-record"], &text);
    assert_eq!(code, 2, "{out}");
    assert!(
        out.contains(
            "error: groups[0] (`p`) particle 0 at [0.0006, 0.0, 0.0] starts outside wall `vessel`"
        ),
        "{out}"
    );
    let (code, out) = scg(&["check"], &text);
    assert_eq!(code, 2, "{out}");
}

// ── extreme coarse graining ─────────────────────────────────────────────────────────────

#[test]
fn extreme_coarse_graining_and_light_particles_warn_and_stay_finite() {
    // α = 16 under SCG: ρ = 1000/256 ≈ 3.9 kg/m³; in water (1000 kg/m³) far below the fluid.
    let text = vortex_one("[3.0e-4, 0.0, 0.0]");
    let s = scene(
        &text,
        &["groups.0.alpha=16", "fluid.density=1000.0", "duration=0.05"],
    );
    let msgs = messages(&s);
    assert!(
        msgs.iter()
            .any(|m| m.contains("α = 16") && m.contains("extreme")),
        "{msgs:?}"
    );
    assert!(
        msgs.iter()
            .any(|m| m.contains("below the fluid's") && m.contains("`p`")),
        "{msgs:?}"
    );
    let mut sim = s.build(false);
    sim.run(s.steps(), |_| true).unwrap();
    let p = sim.particles()[0];
    assert!(p.position.is_finite() && p.velocity.is_finite());
    // And through the binary: warnings, exit 0.
    let (code, out) = scg(
        &[
            "check",
            "--set",
            "groups.0.alpha=16",
            "--set",
            "fluid.density=1000.0",
        ],
        &text,
    );
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("warning:") && out.contains("extreme"), "{out}");
}

// ── dense elastic box ───────────────────────────────────────────────────────────────────

/// 125 particles of 1 mm on a 5³ lattice (spacing 1.2 mm) in a 6 mm periodic box (30 %
/// solids), elastic (e = 1), frictionless, pseudo-random velocities up to 1 m/s.
fn box_scene() -> String {
    let mut seed: u64 = 12345;
    let mut rnd = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let (mut pos, mut vel) = (Vec::new(), Vec::new());
    for i in 0..5 {
        for j in 0..5 {
            for k in 0..5 {
                let p = [i, j, k].map(|n| 0.6e-3 + 1.2e-3 * n as f64);
                pos.push(format!("[{:e}, {:e}, {:e}]", p[0], p[1], p[2]));
                vel.push(format!("[{:e}, {:e}, {:e}]", rnd(), rnd(), rnd()));
            }
        }
    }
    format!(
        r#"
duration = 10.0
dt = 2e-6
[material]
youngs_modulus = 1e7
poisson_ratio = 0.3
restitution = 1.0
[contacts]
periodic = [0.006, 0.006, 0.006]
[[groups]]
name = "g"
diameter = 1e-3
density = 2500.0
positions = [{}]
velocities = [{}]
"#,
        pos.join(", "),
        vel.join(", ")
    )
}

/// Relative drift of the total (kinetic + elastic) energy of the elastic box after
/// `steps` steps.
fn box_drift(steps: u64) -> f64 {
    let s = scene(&box_scene(), &[]);
    let mut sim = s.build(false);
    let m = scg::core::physics::scaling::sphere_mass(1e-3, 2500.0);
    let energy = |sim: &mut scg::core::Simulation| {
        let (ke, _) = kinetic_energy_and_momentum(&mut sim.world);
        let p = sim.particles();
        let l = 0.006;
        let mut u = 0.0;
        for i in 0..p.len() {
            for j in i + 1..p.len() {
                let mut d = p[i].position - p[j].position;
                d -= (d / l).round() * l;
                u += hertz_energy(&s, d, DVec3::ZERO, 1e-3, m);
            }
        }
        ke + u
    };
    let e0 = energy(&mut sim);
    assert!(e0 > 0.0);
    sim.run(steps, |_| true).unwrap();
    let e = energy(&mut sim);
    assert!(e.is_finite());
    let drift = ((e - e0) / e0).abs();
    eprintln!("elastic box: {steps} steps, |ΔE|/E₀ = {drift:.3e}");
    drift
}

/// Documented bound (docs/scenes.md, "Stability"): |ΔE|/E₀ < 1 % over the run of a dense
/// elastic box at ≥ 50 steps per contact.
#[test]
fn dense_elastic_box_energy_drift_short() {
    let drift = box_drift(20_000);
    assert!(drift < 0.01, "drift {drift:e}");
}

#[test]
#[ignore = "10^6 steps (minutes): cargo test --release --test hard_cases -- --ignored"]
fn dense_elastic_box_energy_drift_million_steps() {
    let drift = box_drift(1_000_000);
    assert!(drift < 0.01, "drift {drift:e}");
}

// ── the non-finite guard ────────────────────────────────────────────────────────────────

#[test]
fn guard_stops_the_run_naming_step_particle_and_field() {
    // Huge but finite inputs: u − v overflows to −∞ and the velocity turns non-finite.
    let text = r#"
duration = 0.01
dt = 1e-3
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "uniform"
velocity = [-1.7e308, 0.0, 0.0]
[drag]
law = "stokes"
[[groups]]
name = "p"
diameter = 1e-4
density = 1000.0
positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
velocity = [1.7e308, 0.0, 0.0]
"#;
    let s = scene(text, &[]);
    let mut sim = s.build(false);
    let e = sim.run(s.steps(), |_| true).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.starts_with("non-finite ") && msg.contains("of particle 0 at step 1"),
        "{msg}"
    );
    assert_eq!(sim.step_count(), 1, "stopped the moment it happened");
    let (code, out) = scg(&["run", "--no-record"], text);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains("error: run stopped at step 1: non-finite") && out.contains("of particle 0"),
        "{out}"
    );
}
