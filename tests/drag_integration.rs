//! Drag + integration alone on a tiny World: analytic Stokes relaxation.

mod common;

use glam::DVec3;
use scg::core::physics::drag::DragLaw;
use scg::core::physics::flow::{FlowField, Fluid};
use scg::core::physics::integrate::Integrator;
use scg::core::physics::scaling::CoarseGrainLaw;
use scg::core::{ParticleSpec, SimConfig, Simulation};

const RHO: f64 = 1000.0;
const D: f64 = 10e-6;
const MU: f64 = 1.8e-5;

fn tau() -> f64 {
    RHO * D * D / (18.0 * MU)
}

fn sim(dt: f64, integrator: Integrator, u: DVec3, v0: DVec3) -> Simulation {
    let mut s = Simulation::new(SimConfig {
        dt,
        integrator,
        drag: Some(DragLaw::Stokes),
        fluid: Some(Fluid {
            density: 1.2,
            viscosity: MU,
        }),
        flow: FlowField::Uniform(u),
        mesh_flow: None,
        gravity: None,
        buoyancy: false,
        scg_at_original: false,
        extra_forces: Default::default(),
        walls: None,
        contacts: None,
        record_every: None,
        groups: vec!["p".into()],
        carrier: None,
    });
    s.spawn(&ParticleSpec {
        group: 0,
        diameter: D,
        density: RHO,
        alpha: 1.0,
        law: CoarseGrainLaw::Scg,
        position: DVec3::ZERO,
        velocity: v0,
    });
    s
}

/// v(t) = U + (v0 − U)·e^(−t/τ) to 1e-12 relative at dt = 10·τ, exponential scheme.
#[test]
fn exponential_scheme_is_exact_at_dt_10_tau() {
    let u = DVec3::new(1.0, -0.5, 0.25);
    let v0 = DVec3::new(-2.0, 0.0, 3.0);
    let dt = 10.0 * tau();
    let mut s = sim(dt, Integrator::Exponential, u, v0);
    for k in 1..=5u32 {
        s.step().unwrap();
        let t = k as f64 * dt;
        let p = s.particles()[0];
        let ve = u + (v0 - u) * (-t / tau()).exp();
        let xe = u * t + (v0 - u) * tau() * (1.0 - (-t / tau()).exp());
        assert!(
            (p.velocity - ve).length() <= 1e-12 * ve.length(),
            "v at step {k}"
        );
        assert!(
            (p.position - xe).length() <= 1e-12 * xe.length(),
            "x at step {k}"
        );
    }
}

/// Also at a gentle dt the exponential scheme follows the exact curve.
#[test]
fn exponential_scheme_exact_at_small_dt() {
    let (u, v0) = (DVec3::X, DVec3::ZERO);
    let dt = 0.01 * tau();
    let mut s = sim(dt, Integrator::Exponential, u, v0);
    s.run(300, |_| true).unwrap();
    let t = s.time();
    let ve = u + (v0 - u) * (-t / tau()).exp();
    assert!((s.particles()[0].velocity - ve).length() <= 1e-12 * ve.length());
}

/// The explicit scheme's error at fixed t falls first-order with dt.
#[test]
fn explicit_error_is_first_order() {
    let (u, v0) = (DVec3::X, DVec3::ZERO);
    let t_end = 2.0 * tau();
    let err = |n: u64| {
        let dt = t_end / n as f64;
        let mut s = sim(dt, Integrator::Explicit, u, v0);
        s.run(n, |_| true).unwrap();
        let ve = u + (v0 - u) * (-t_end / tau()).exp();
        (s.particles()[0].velocity - ve).length()
    };
    let (e1, e2, e4) = (err(50), err(100), err(200));
    let (r1, r2) = (e1 / e2, e2 / e4);
    assert!(
        (r1 - 2.0).abs() < 0.1 && (r2 - 2.0).abs() < 0.05,
        "ratios {r1} {r2}"
    );
}

/// The explicit scheme at dt ≫ τ is sub-stepped, so it stays bounded and close.
#[test]
fn explicit_scheme_substeps_stiff_drag() {
    let (u, v0) = (DVec3::X, DVec3::ZERO);
    let mut s = sim(1000.0 * tau(), Integrator::Explicit, u, v0);
    s.run(3, |_| true).unwrap();
    let v = s.particles()[0].velocity;
    assert!((v - u).length() < 1e-6, "{v}");
}
