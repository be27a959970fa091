//! The carrier-velocity seam: a constant-offset carrier modifier (the slot turbulent
//! dispersion fills) changes every scheme's trajectory exactly as the analytic solution in
//! the shifted flow says, on analytic flows and on a CFD mesh alike.
//!
//! Run: `cargo test --release --test carrier_seam`.

use std::path::Path;

use glam::DVec3;
use scg::core::physics::drag::DragLaw;
use scg::core::physics::flow::{FlowField, Fluid};
use scg::core::physics::integrate::Integrator;
use scg::core::physics::scaling::CoarseGrainLaw;
use scg::core::stages::carrier::CarrierModifier;
use scg::core::step::StepSystem;
use scg::core::{ParticleSpec, SimConfig, Simulation};
use scg_mesh::build::{BoxMesh, CellShape, PatchNaming};
use scg_mesh::foam::{Format, write_case};
use scg_mesh::{CellField, MeshGeometry};

const RHO: f64 = 1000.0;
const D: f64 = 10e-6;
const MU: f64 = 1.8e-5;
const U: DVec3 = DVec3::new(1.0, -0.5, 0.25);
const DU: DVec3 = DVec3::new(-0.3, 0.8, 0.1);
const V0: DVec3 = DVec3::new(-2.0, 0.0, 3.0);

fn tau() -> f64 {
    RHO * D * D / (18.0 * MU)
}

fn spec(position: DVec3) -> ParticleSpec {
    ParticleSpec {
        group: 0,
        diameter: D,
        density: RHO,
        alpha: 1.0,
        law: CoarseGrainLaw::Scg,
        position,
        velocity: V0,
    }
}

fn config(
    dt: f64,
    law: DragLaw,
    integrator: Integrator,
    flow: FlowField,
    carrier: Option<CarrierModifier>,
) -> SimConfig {
    SimConfig {
        dt,
        integrator,
        drag: Some(law),
        fluid: Some(Fluid {
            density: 1.2,
            viscosity: MU,
        }),
        flow,
        mesh_flow: None,
        gravity: None,
        buoyancy: false,
        scg_at_original: false,
        extra_forces: Default::default(),
        walls: None,
        contacts: None,
        record_every: None,
        groups: vec!["p".into()],
        carrier,
    }
}

/// The particle's (x, v) after each of `steps` steps.
fn trajectory(mut s: Simulation, steps: usize) -> Vec<(DVec3, DVec3)> {
    (0..steps)
        .map(|_| {
            s.step().unwrap();
            let p = s.particles()[0];
            (p.position, p.velocity)
        })
        .collect()
}

/// Stokes relaxation toward U + δ from `x0`: the exact (x, v) at time t.
fn exact(x0: DVec3, t: f64) -> (DVec3, DVec3) {
    let w = U + DU;
    let e = (-t / tau()).exp();
    (x0 + w * t + (V0 - w) * tau() * (1.0 - e), w + (V0 - w) * e)
}

fn close(a: DVec3, b: DVec3, rel: f64) -> bool {
    (a - b).length() <= rel * b.length().max(1e-30)
}

/// Stokes drag, exponential scheme, in a uniform flow U with a constant offset δ: the
/// trajectory is the exact relaxation toward U + δ (1e-12 relative), at dt = τ/4 and 10·τ;
/// without the modifier it relaxes toward U (and the plan shows the modifier only with it).
#[test]
fn a_constant_offset_shifts_the_stokes_relaxation_exactly() {
    for dt in [0.25 * tau(), 10.0 * tau()] {
        let cfg = config(
            dt,
            DragLaw::Stokes,
            Integrator::Exponential,
            FlowField::Uniform(U),
            Some(CarrierModifier::ConstantOffset(DU)),
        );
        let mut s = Simulation::new(cfg.clone());
        assert!(s.plan().contains(StepSystem::ModifyCarrier));
        assert!(
            s.plan().position(StepSystem::ModifyCarrier)
                < s.plan().position(StepSystem::IntegrateStokesExponential)
        );
        s.spawn(&spec(DVec3::ZERO));
        for (k, (x, v)) in trajectory(s, 12).into_iter().enumerate() {
            let (xe, ve) = exact(DVec3::ZERO, (k + 1) as f64 * dt);
            assert!(close(v, ve, 1e-12), "dt {dt:e}, step {k}: v {v} vs {ve}");
            assert!(close(x, xe, 1e-12), "dt {dt:e}, step {k}: x {x} vs {xe}");
        }
        let mut plain = Simulation::new(SimConfig {
            carrier: None,
            ..cfg
        });
        assert!(!plain.plan().contains(StepSystem::ModifyCarrier));
        plain.spawn(&spec(DVec3::ZERO));
        let (_, v) = *trajectory(plain, 12).last().unwrap();
        assert!(close(v, U + (V0 - U) * (-12.0 * dt / tau()).exp(), 1e-12));
    }
}

/// The Reynolds-dependent and explicit schemes take the offset at every evaluation: a
/// uniform flow U with offset δ gives, bit for bit, the trajectory in the uniform flow
/// U + δ (the same sum, formed once), and not the one in U.
#[test]
fn an_offset_is_the_shifted_flow_in_every_scheme() {
    for (law, integrator) in [
        (DragLaw::SchillerNaumann, Integrator::Exponential),
        (DragLaw::SchillerNaumann, Integrator::Explicit),
        (DragLaw::Stokes, Integrator::Explicit),
    ] {
        let run = |flow, carrier| {
            let mut s = Simulation::new(config(0.5 * tau(), law, integrator, flow, carrier));
            s.spawn(&spec(DVec3::ZERO));
            trajectory(s, 20)
        };
        let shifted = run(
            FlowField::Uniform(U),
            Some(CarrierModifier::ConstantOffset(DU)),
        );
        assert_eq!(shifted, run(FlowField::Uniform(U + DU), None), "{law:?}");
        assert_ne!(shifted, run(FlowField::Uniform(U), None), "{law:?}");
    }
}

/// On a CFD mesh (a uniform field U on perturbed hexahedra, zero-gradient patches, so the
/// interpolated field is U everywhere) the offset enters the mesh step the same way: the
/// exact relaxation toward U + δ, under Stokes and Schiller–Naumann drag.
#[test]
fn a_constant_offset_on_a_mesh_flow() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = BoxMesh::new(DVec3::splat(-1.0), DVec3::splat(1.0), [6, 6, 6])
        .shape(CellShape::Hex)
        .perturbed(0.15, 3)
        .naming(PatchNaming::InletOutletWalls { axis: 0 })
        .build()
        .unwrap();
    let n = MeshGeometry::new(&mesh).unwrap().cell_centres.len();
    let field = CellField {
        cells: vec![U; n],
        patches: vec![None; mesh.patches.len()],
    };
    write_case(
        dir.path().join("case"),
        &mesh,
        Some(("U", &field)),
        Format::Ascii,
    )
    .unwrap();
    for law in ["stokes", "schiller_naumann"] {
        let scene = scene(dir.path(), law);
        let mut cfg = scene.sim_config(false);
        cfg.carrier = Some(CarrierModifier::ConstantOffset(DU));
        let mut s = Simulation::with_inlet_outlet(cfg, scene.inlet_outlet());
        assert!(s.plan().contains(StepSystem::IntegrateMeshFlow));
        // The scene's own particle is not spawned: one particle, ours.
        let x0 = DVec3::new(-0.2, 0.1, 0.05);
        s.spawn(&spec(x0));
        let dt = s.dt();
        for (k, (x, v)) in trajectory(s, 10).into_iter().enumerate() {
            let t = (k + 1) as f64 * dt;
            if law == "stokes" {
                let (xe, ve) = exact(x0, t);
                assert!(close(v, ve, 1e-11), "{law} step {k}: v {v} vs {ve}");
                assert!(close(x, xe, 1e-11), "{law} step {k}: x {x} vs {xe}");
            } else {
                // The slip decays, so Re does: v tends to U + δ faster than e^(−t/τ)·|v0 − w|
                // allows only if the offset was taken.
                let w = U + DU;
                assert!(
                    (v - w).length() <= (V0 - w).length() * (-t / tau()).exp() * (1.0 + 1e-9),
                    "{law} step {k}: v {v}"
                );
            }
        }
    }
}

fn scene(dir: &Path, law: &str) -> scg::scene::Scene {
    let dt = 0.5 * tau();
    let text = format!(
        r#"duration = {d:e}
dt = {dt:e}
seed = 1
[fluid]
density = 1.2
viscosity = {MU:e}
[flow]
kind = "openfoam"
case = "case"
time = "latest"
field = "U"
[flow.patches]
walls = ["walls"]
outlets = ["outlet"]
inlets = ["inlet"]
[drag]
law = "{law}"
[[groups]]
name = "p"
diameter = {D:e}
density = {RHO}
positions = [[0.5, 0.5, 0.5]]
"#,
        d = 20.0 * dt,
    );
    let path = dir.join(format!("{law}.toml"));
    std::fs::write(&path, text).unwrap();
    scg::scene::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}
