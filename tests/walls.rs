//! Particle–wall normal contact against theory: restitution and Hertz contact time.

mod common;

use glam::DVec3;
use scg::core::physics::contact::normal::{hertz_contact_time, hertz_max_overlap};
use scg::core::physics::contact::{Material, NormalLaw};
use scg::core::physics::flow::FlowField;
use scg::core::physics::integrate::Integrator;
use scg::core::physics::scaling::{CoarseGrainLaw, sphere_mass};
use scg::core::physics::wall_shape::WallShape;
use scg::core::stages::walls::{Wall, WallSet};
use scg::core::{ParticleSpec, SimConfig, Simulation};

const D: f64 = 1e-3;
const RHO: f64 = 2500.0;
const V: f64 = 0.5;

fn material(e: f64) -> Material {
    Material {
        youngs_modulus: 1e8,
        poisson_ratio: 0.3,
        restitution: e,
        friction: 0.0,
    }
}

/// Drop one sphere on a plane at speed V; returns (rebound speed, contact steps, max overlap).
fn bounce(
    law: NormalLaw,
    mat: Material,
    dt: f64,
    shape: WallShape,
    x0: DVec3,
    v0: DVec3,
) -> (f64, u64, f64) {
    let mut sim = Simulation::new(SimConfig {
        dt,
        integrator: Integrator::Exponential,
        drag: None,
        fluid: None,
        flow: FlowField::Still,
        mesh_flow: None,
        gravity: None,
        buoyancy: false,
        scg_at_original: false,
        extra_forces: Default::default(),
        contacts: None,
        walls: Some(WallSet {
            walls: vec![Wall {
                name: "w".into(),
                shape: shape.clone(),
                motion: Default::default(),
            }],
            law,
            material: mat,
        }),
        record_every: None,
        groups: vec!["p".into()],
        carrier: None,
    });
    sim.spawn(&ParticleSpec {
        group: 0,
        diameter: D,
        density: RHO,
        alpha: 1.0,
        law: CoarseGrainLaw::Scg,
        position: x0,
        velocity: v0,
    });
    let (mut steps_in, mut max_overlap, mut touched) = (0u64, 0.0_f64, false);
    for _ in 0..1_000_000 {
        sim.step().unwrap();
        let p = sim.particles()[0];
        match shape.touch(p.position, 0.5 * D) {
            Some(t) => {
                touched = true;
                steps_in += 1;
                max_overlap = max_overlap.max(t.overlap);
            }
            None if touched => return (p.velocity.length(), steps_in, max_overlap),
            None => {}
        }
    }
    panic!("no rebound");
}

fn plane() -> WallShape {
    WallShape::Plane {
        point: DVec3::ZERO,
        normal: DVec3::Z,
    }
}

#[test]
fn hertz_wall_restitution_within_1_percent() {
    for e in [0.3, 0.5, 0.8, 0.95] {
        let m = material(e);
        let (v, _, _) = bounce(
            NormalLaw::hertz(e),
            m,
            2e-7,
            plane(),
            DVec3::new(0.0, 0.0, 0.51e-3),
            DVec3::new(0.0, 0.0, -V),
        );
        assert!(((v / V) - e).abs() < 0.01 * e, "e = {e}: got {}", v / V);
    }
}

#[test]
fn linear_wall_restitution_within_1_percent() {
    for e in [0.3, 0.5, 0.8, 0.95] {
        let (v, _, _) = bounce(
            NormalLaw::linear(1e4, e),
            material(e),
            // t_c ≈ 38 µs: dt = 1e-7 s gives ~380 steps per contact (the kick–drift
            // scheme's damping error is first order in dt).
            1e-7,
            plane(),
            DVec3::new(0.0, 0.0, 0.51e-3),
            DVec3::new(0.0, 0.0, -V),
        );
        assert!(((v / V) - e).abs() < 0.01 * e, "e = {e}: got {}", v / V);
    }
}

/// Elastic Hertz impact on a wall: contact time and maximum overlap within 1 %.
#[test]
fn hertz_wall_contact_time_and_overlap() {
    let mat = material(1.0);
    let dt = 2e-7;
    let (v, steps, overlap) = bounce(
        NormalLaw::hertz(1.0),
        mat,
        dt,
        plane(),
        DVec3::new(0.0, 0.0, 0.51e-3),
        DVec3::new(0.0, 0.0, -V),
    );
    let m = sphere_mass(D, RHO);
    let e_eff = mat.effective_modulus();
    let tc = hertz_contact_time(m, 0.5 * D, e_eff, V);
    let dmax = hertz_max_overlap(m, 0.5 * D, e_eff, V);
    assert!((v / V - 1.0).abs() < 1e-3);
    assert!(
        ((steps as f64 * dt) / tc - 1.0).abs() < 0.01,
        "t_c {} vs {tc}",
        steps as f64 * dt
    );
    assert!(
        (overlap / dmax - 1.0).abs() < 0.01,
        "δ_max {overlap} vs {dmax}"
    );
}

/// The inside of a cylinder bounces a particle back toward the axis.
#[test]
fn cylinder_wall_rebound() {
    let shape = WallShape::CylinderInside {
        center: DVec3::ZERO,
        axis: DVec3::Z,
        radius: 0.01,
        extent: None,
    };
    let (v, _, _) = bounce(
        NormalLaw::hertz(0.8),
        material(0.8),
        2e-7,
        shape,
        DVec3::new(0.0095 - 0.01e-3, 0.0, 0.0),
        DVec3::new(V, 0.0, 0.0),
    );
    assert!((v / V - 0.8).abs() < 0.008, "{}", v / V);
}
