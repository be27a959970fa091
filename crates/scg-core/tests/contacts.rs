//! Particle–particle and particle–wall contacts against theory, on tiny worlds built with
//! `scg_core::Simulation`.
//!
//! Run: `cargo test --release -p scg-core --test contacts -- --nocapture` (prints the
//! measured errors).

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use scg_core::components::*;
use scg_core::diagnostics::kinetic_energy_and_momentum;
use scg_core::physics::contact::normal::{
    effective, hertz_contact_time, hertz_max_overlap, hertz_stiffness,
};
use scg_core::physics::contact::tangential::TangentialStiffness;
use scg_core::physics::contact::{Material, NormalLaw};
use scg_core::physics::flow::FlowField;
use scg_core::physics::integrate::Integrator;
use scg_core::physics::scaling::{CoarseGrainLaw, sphere_mass};
use scg_core::physics::wall_shape::WallShape;
use scg_core::stages::contacts::{ContactConfig, ContactState};
use scg_core::stages::walls::{Wall, WallSet};
use scg_core::state::Tally;
use scg_core::step::StepSystem;
use scg_core::{ParticleSpec, SimConfig, Simulation};

const D: f64 = 1e-3;
const RHO: f64 = 2500.0;
const E: f64 = 1e8;
const NU: f64 = 0.3;

fn material(e: f64, mu: f64) -> Material {
    Material {
        youngs_modulus: E,
        poisson_ratio: NU,
        restitution: e,
        friction: mu,
    }
}

fn contact_cfg(e: f64, mu: f64, periodic: Option<DVec3>) -> ContactConfig {
    ContactConfig {
        law: NormalLaw::hertz(e),
        material: material(e, mu),
        skin: 0.1 * D,
        periodic,
        rolling_friction: 0.0,
        tangential_stiffness: TangentialStiffness::Mindlin,
    }
}

fn config(dt: f64, contacts: Option<ContactConfig>, walls: Option<WallSet>) -> SimConfig {
    SimConfig {
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
        walls,
        contacts,
        record_every: None,
        groups: vec!["p".into()],
        carrier: None,
    }
}

fn spec(x: DVec3, v: DVec3, d: f64) -> ParticleSpec {
    ParticleSpec {
        group: 0,
        diameter: d,
        density: RHO,
        alpha: 1.0,
        law: CoarseGrainLaw::Scg,
        position: x,
        velocity: v,
    }
}

fn e_eff() -> f64 {
    material(1.0, 0.0).effective_modulus()
}

/// The `auto` time step for a pair of identical spheres at approach speed `v`: t_c/50.
fn auto_dt_pair(v: f64) -> f64 {
    let m = sphere_mass(D, RHO);
    hertz_contact_time(0.5 * m, 0.25 * D, e_eff(), v) / 50.0
}

struct HeadOn {
    duration: f64,
    max_overlap: f64,
    max_force: f64,
    ratio: f64,
}

/// Two identical spheres approaching at `v` (each at v/2); duration from the overlap
/// crossings interpolated linearly between steps.
fn head_on(e: f64, v: f64) -> HeadOn {
    let dt = auto_dt_pair(v);
    let mut sim = Simulation::new(config(dt, Some(contact_cfg(e, 0.0, None)), None));
    let gap = 0.05 * D;
    sim.spawn(&spec(
        DVec3::new(-0.5 * (D + gap), 0.0, 0.0),
        DVec3::new(0.5 * v, 0.0, 0.0),
        D,
    ));
    sim.spawn(&spec(
        DVec3::new(0.5 * (D + gap), 0.0, 0.0),
        DVec3::new(-0.5 * v, 0.0, 0.0),
        D,
    ));
    let overlap = |sim: &mut Simulation| {
        let p = sim.particles();
        D - (p[1].position - p[0].position).length()
    };
    let (mut t_in, mut max_overlap, mut max_force) = (None, 0.0_f64, 0.0_f64);
    let mut prev = overlap(&mut sim);
    let mass = RHO * std::f64::consts::PI / 6.0 * D * D * D;
    for _ in 0..100_000 {
        let v0 = sim.particles()[0].velocity;
        sim.step().unwrap();
        let d = overlap(&mut sim);
        let t = sim.time();
        // One pair and no other force: the pair force is m·Δv/dt on either particle.
        let f = (sim.particles()[0].velocity - v0) * mass / dt;
        max_force = max_force.max(f.length());
        max_overlap = max_overlap.max(d);
        if prev <= 0.0 && d > 0.0 {
            t_in = Some(t - dt * d / (d - prev));
        }
        if prev > 0.0 && d <= 0.0 {
            let t_out = t - dt * d / (d - prev);
            let p = sim.particles();
            let ratio = (p[1].velocity - p[0].velocity).length() / v;
            return HeadOn {
                duration: t_out - t_in.unwrap(),
                max_overlap,
                max_force,
                ratio,
            };
        }
        prev = d;
    }
    panic!("no rebound");
}

#[test]
fn hertz_head_on_elastic_matches_theory() {
    let v = 1.0;
    let m = sphere_mass(D, RHO);
    let (m_eff, r_eff) = (0.5 * m, 0.25 * D);
    let tc = hertz_contact_time(m_eff, r_eff, e_eff(), v);
    let dmax = hertz_max_overlap(m_eff, r_eff, e_eff(), v);
    let fmax = hertz_stiffness(e_eff(), r_eff) * dmax.powf(1.5);
    let r = head_on(1.0, v);
    let (et, ed, ef) = (
        (r.duration / tc - 1.0).abs(),
        (r.max_overlap / dmax - 1.0).abs(),
        (r.max_force / fmax - 1.0).abs(),
    );
    eprintln!(
        "t_c error {et:.2e}, δ_max error {ed:.2e}, F_max error {ef:.2e}, e = {:.6}",
        r.ratio
    );
    assert!(et < 0.01, "t_c {} vs {tc}", r.duration);
    assert!(ed < 0.01, "δ_max {} vs {dmax}", r.max_overlap);
    assert!(ef < 0.01, "F_max {} vs {fmax}", r.max_force);
    assert!((r.ratio - 1.0).abs() < 0.01);
}

#[test]
fn particle_restitution_within_1_percent() {
    for e in [0.3, 0.5, 0.8, 0.95] {
        let r = head_on(e, 1.0);
        let err = (r.ratio / e - 1.0).abs();
        eprintln!("e = {e}: measured {:.5} (error {err:.2e})", r.ratio);
        assert!(err < 0.01, "e = {e}: got {}", r.ratio);
    }
}

/// One sphere on the plane z = 0 with (v_t, 0, −v_n); returns (velocity, angular velocity)
/// after the contact, and the contact-point tangential velocity before and after.
fn oblique(e: f64, mu: f64, vt: f64, vn: f64, steps_per_contact: f64) -> (DVec3, DVec3) {
    let m = sphere_mass(D, RHO);
    let dt = hertz_contact_time(m, 0.5 * D, e_eff(), vn) / steps_per_contact;
    let walls = WallSet {
        walls: vec![Wall {
            name: "floor".into(),
            shape: WallShape::Plane {
                point: DVec3::ZERO,
                normal: DVec3::Z,
            },
            motion: Default::default(),
        }],
        law: NormalLaw::hertz(e),
        material: material(e, mu),
    };
    let mut sim = Simulation::new(config(dt, None, Some(walls)));
    assert!(sim.plan().contains(StepSystem::WallContactForces));
    assert!(sim.plan().contains(StepSystem::IntegrateRotation));
    sim.spawn(&spec(
        DVec3::new(0.0, 0.0, 0.51 * D),
        DVec3::new(vt, 0.0, -vn),
        D,
    ));
    let mut touched = false;
    for _ in 0..1_000_000 {
        sim.step().unwrap();
        let p = sim.particles()[0];
        if p.position.z < 0.5 * D {
            touched = true;
        } else if touched {
            let mut q = sim.world.query::<&AngularVelocity>();
            let w = q.single(&sim.world).unwrap().0;
            return (p.velocity, w);
        }
    }
    panic!("no rebound");
}

#[test]
fn oblique_wall_impact_sliding_follows_coulomb_impulse() {
    // Sliding throughout needs v_t > (7/2)·μ·(1 + e)·v_n.
    let (e, mu, vt, vn) = (0.8, 0.3, 3.0, 0.5);
    let (v, w) = oblique(e, mu, vt, vn, 50.0);
    let r = 0.5 * D;
    // Normal impulse J_n = m·(v_n + v_n'); tangential J_t = μ·J_n.
    let en = v.z / vn;
    let dvt = mu * (1.0 + en) * vn;
    let dvt_nominal = mu * (1.0 + e) * vn;
    let got_dvt = vt - v.x;
    // I·ω = r·J_t with I = m·d²/10 = (2/5)·m·r²: ω = 5·Δv_t/(2r), about +y for motion along +x.
    let omega = 5.0 * dvt / (2.0 * r);
    eprintln!(
        "e_n = {en:.4}; Δv_t = {got_dvt:.5} (theory {dvt:.5}, nominal e {dvt_nominal:.5}); ω_y = {:.3} (theory {omega:.3})",
        w.y
    );
    assert!(
        (en / e - 1.0).abs() < 0.01,
        "normal restitution unchanged: {en}"
    );
    assert!((got_dvt / dvt - 1.0).abs() < 0.02);
    assert!((got_dvt / dvt_nominal - 1.0).abs() < 0.02);
    assert!((w.y / omega - 1.0).abs() < 0.02);
    assert!(w.x.abs() < 1e-9 * w.y.abs() && w.z.abs() < 1e-9 * w.y.abs());
    assert!(v.y.abs() < 1e-12);
}

/// Reference: the same no-slip Hertz–Mindlin sphere–wall impact integrated on its own
/// (δ, contact-point slip u, contact-point velocity v_c = v_t − r·ω) with `n` steps per
/// contact; returns v_c after / v_c before.
fn sticking_reference(mu: f64, vt: f64, vn: f64, n: f64) -> f64 {
    let m = sphere_mass(D, RHO);
    let r = 0.5 * D;
    let mat = material(1.0, mu);
    let (es, gs) = (mat.effective_modulus(), mat.effective_shear_modulus());
    let k = hertz_stiffness(es, r);
    let dt = hertz_contact_time(m, r, es, vn) / n;
    let (mut d, mut vd, mut u, mut vc) = (0.0_f64, vn, 0.0_f64, vt);
    loop {
        let fnn = k * d.max(0.0).powf(1.5);
        let kt = 8.0 * gs * (r * d.max(0.0)).sqrt();
        u += vc * dt;
        let mut ft = -kt * u;
        if ft.abs() > mu * fnn {
            ft = (mu * fnn).copysign(ft);
            u = if kt > 0.0 { -ft / kt } else { 0.0 };
        }
        vd -= fnn / m * dt;
        // A tangential force at the contact point changes v_c by (1 + m·r²/I)·F/m = 3.5·F/m.
        vc += 3.5 * ft / m * dt;
        d += vd * dt;
        if d < 0.0 {
            return vc / vt;
        }
    }
}

/// Maw, Barber & Fawcett's parameters for a sphere on a wall of the same material:
/// χ = (1 − ν)/(2 − ν)·(1 + m·r²/I) and the scaled incidence ψ₁ = 2(1 − ν)/(μ(2 − ν))·v_c/v_n
/// (the same scaling gives ψ₂ from the rebound contact-point velocity). Gross sliding
/// throughout the contact starts at ψ₁ = 4χ (e = 1), where ψ₂ = ψ₁ − 4χ.
fn maw_scale(mu: f64) -> (f64, f64) {
    let chi = (1.0 - NU) / (2.0 - NU) * 3.5;
    let psi_per_ratio = 2.0 * (1.0 - NU) / (mu * (2.0 - NU));
    (chi, psi_per_ratio)
}

/// Contact-point tangential velocity (along x) of a sphere resting on z = 0.
fn contact_point_velocity(v: DVec3, w: DVec3) -> f64 {
    (v + w.cross(DVec3::new(0.0, 0.0, -0.5 * D))).x
}

#[test]
fn oblique_wall_impact_sticking_reverses_the_contact_point_velocity() {
    // Below gross sliding (ψ₁ < 4χ ≈ 5.8 for ν = 0.3) the contact sticks over most of
    // the impact and the Mindlin spring (k_t = 8·G*·√(R*·δ)) stores tangential energy
    // and gives it back: the contact point leaves with its tangential velocity reversed
    // (ψ₂ < 0), the behaviour Maw, Barber & Fawcett (1976) predict and measured rebound
    // angles show (Kharaz, Gorham & Salman 2001), where rigid-body friction would give a
    // rolling exit (ψ₂ = 0) or a forward one. Each case is also checked against the same
    // Hertz–Mindlin impact integrated on its own with 20 000 steps per contact, and the
    // angular momentum about the contact point, which contact forces cannot change.
    let (e, mu, vn) = (1.0, 0.3, 0.5);
    let (chi, scale) = maw_scale(mu);
    let m = sphere_mass(D, RHO);
    let r = 0.5 * D;
    for ratio in [1.0, 1.5] {
        let vt = ratio * vn;
        let psi1 = scale * ratio;
        assert!(
            psi1 > 1.5 && psi1 < 4.0 * chi,
            "ψ₁ = {psi1} in the sticking range"
        );
        let reference = sticking_reference(mu, vt, vn, 20_000.0);
        let (v, w) = oblique(e, mu, vt, vn, 500.0);
        let out = contact_point_velocity(v, w) / vt;
        let psi2 = psi1 * out;
        eprintln!(
            "ψ₁ = {psi1:.3}: v_c'/v_c = {out:.4} (reference {reference:.4}), ψ₂ = {psi2:.3}, gross-slip line ψ₁ − 4χ = {:.3}",
            psi1 - 4.0 * chi
        );
        assert!(out < -0.1, "contact-point velocity reversed: {out}");
        assert!((out - reference).abs() < 0.02, "{out} vs {reference}");
        // Less tangential impulse than sliding throughout would apply.
        assert!(psi2 > psi1 - 4.0 * chi);
        let (l0, l1) = (m * r * vt, m * r * v.x + 0.4 * m * r * r * w.y);
        assert!(
            (l1 / l0 - 1.0).abs() < 1e-3,
            "L about the contact point {l1} vs {l0}"
        );
    }
}

#[test]
fn oblique_wall_impact_small_angle_follows_mindlin_no_slip() {
    // Very small incidence (ψ₁ ≈ 0.1): the contact stays stuck apart from micro-slip as
    // the load vanishes. With ν = 0.3 (k_t/k_n = 2(1−ν)/(2−ν) ≈ 0.82) the Mindlin spring's
    // tangential oscillation runs through close to a full period during the contact, so
    // the contact point leaves *forward* (ratio ≈ +0.955 converged). That is this
    // spring model's no-slip limit (LAMMPS `gran/hertz/history` behaves the same); the
    // full Mindlin–Deresiewicz micro-slip history would return less of it. The test
    // checks the model against its own converged solution and the angular momentum about
    // the contact point.
    let (e, mu, vt, vn) = (1.0, 0.8, 0.05, 0.5);
    let reference = sticking_reference(mu, vt, vn, 20_000.0);
    let (v, w) = oblique(e, mu, vt, vn, 500.0);
    let r = 0.5 * D;
    let out = contact_point_velocity(v, w) / vt;
    eprintln!(
        "contact point tangential velocity ratio {out:.4}, reference {reference:.4}; v = {v:?}, w = {w:?}"
    );
    assert!((out - reference).abs() < 0.01);
    let m = sphere_mass(D, RHO);
    let l0 = m * r * vt;
    let l1 = m * r * v.x + 0.4 * m * r * r * w.y;
    assert!(
        (l1 / l0 - 1.0).abs() < 1e-3,
        "L about the contact point {l1} vs {l0}"
    );
}

/// A periodic box of `n` polydisperse particles with random velocities.
fn periodic_box(n: usize, e: f64, mu: f64, seed: u64) -> (Simulation, f64) {
    periodic_box_sized(n, e, mu, seed, 12.0 * D)
}

/// Same in a box of edge `l` (10.5·D for 1000 particles: ~6 candidate pairs each).
fn periodic_box_sized(n: usize, e: f64, mu: f64, seed: u64, l: f64) -> (Simulation, f64) {
    let mut cfg = contact_cfg(e, mu, Some(DVec3::splat(l)));
    cfg.skin = 0.2 * D;
    let v = 0.5;
    let dt = hertz_contact_time(0.5 * sphere_mass(0.8 * D, RHO), 0.2 * D, e_eff(), 4.0 * v) / 50.0;
    let mut sim = Simulation::new(config(dt, Some(cfg), None));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Particles on a jittered lattice (no initial overlaps), diameters 0.8..1.0·D.
    let k = (n as f64).cbrt().ceil() as usize;
    let a = l / k as f64;
    let mut placed = 0;
    'outer: for i in 0..k {
        for j in 0..k {
            for h in 0..k {
                if placed == n {
                    break 'outer;
                }
                let x = DVec3::new(i as f64, j as f64, h as f64) * a
                    + DVec3::new(
                        rng.random_range(0.0..0.1),
                        rng.random_range(0.0..0.1),
                        rng.random_range(0.0..0.1),
                    ) * a;
                let vel = DVec3::new(
                    rng.random_range(-v..v),
                    rng.random_range(-v..v),
                    rng.random_range(-v..v),
                ) + DVec3::new(0.05, -0.02, 0.01);
                sim.spawn(&spec(x, vel, D * rng.random_range(0.8..1.0)));
                placed += 1;
            }
        }
    }
    (sim, dt)
}

/// Elastic energy stored in the touching pairs (Hertz normal: (2/5)·K·δ^(5/2)), J.
fn stored_energy(sim: &mut Simulation) -> f64 {
    // Current positions in the contact arrays' order (the arrays keep positions of the
    // last list build only).
    let now: std::collections::HashMap<u32, DVec3> =
        sim.particles().iter().map(|p| (p.id, p.position)).collect();
    let st = sim.world.resource::<ContactState>();
    let pos: Vec<DVec3> = st.ids.iter().map(|id| now[id]).collect();
    let ee = e_eff();
    let mut u = 0.0;
    for &[i, j] in &st.list.pairs {
        let (i, j) = (i as usize, j as usize);
        let d = scg_core::physics::periodic::separation(pos[i], pos[j], st.list.periodic.as_ref());
        let delta = st.radius[i] + st.radius[j] - d.length();
        if delta > 0.0 {
            let k = hertz_stiffness(ee, effective(st.radius[i], st.radius[j]));
            u += 0.4 * k * delta * delta * delta.sqrt();
        }
    }
    u
}

fn momentum_scale(sim: &mut Simulation) -> f64 {
    sim.particles()
        .iter()
        .map(|p| sphere_mass(p.diameter, p.density) * p.velocity.length())
        .sum()
}

#[test]
fn periodic_box_conserves_momentum_and_dissipates() {
    let (mut sim, _) = periodic_box(1000, 0.7, 0.3, 1);
    let (ke0, p0) = kinetic_energy_and_momentum(&mut sim.world);
    let scale = momentum_scale(&mut sim);
    let mut ke_prev = ke0;
    let mut worst_dp: f64 = 0.0;
    let mut worst_rise: f64 = 0.0;
    let steps = 3000;
    for _ in 0..steps {
        // Symplectic Euler (kick, then drift): the energy checked pairs the elastic energy
        // at the positions the step's forces came from (x_n) with the kinetic energy after
        // the kick (v_n+1).
        let elastic = stored_energy(&mut sim);
        sim.step().unwrap();
        let (ke, p) = kinetic_energy_and_momentum(&mut sim.world);
        worst_dp = worst_dp.max((p - p0).length() / scale);
        // Kinetic energy between collisions never rises; inside a collision the springs
        // give back stored energy, so compare the total mechanical energy: kinetic +
        // normal elastic (tangential springs are dissipative-bounded and small).
        let total = ke + elastic;
        worst_rise = worst_rise.max((total - ke_prev) / ke0);
        ke_prev = total;
    }
    let (ke, _) = kinetic_energy_and_momentum(&mut sim.world);
    let collisions = sim.world.resource::<Tally>().collisions[0];
    eprintln!(
        "1000 particles, {steps} steps: {collisions} contacts started, KE {ke0:.4e} → {ke:.4e}, worst |ΔP|/Σm|v| {worst_dp:.2e}, worst per-step rise of E/E0 {worst_rise:.2e}"
    );
    assert!(
        collisions > 500,
        "too few collisions to test anything: {collisions}"
    );
    assert!(worst_dp < 1e-12);
    assert!(ke < 0.9 * ke0);
    // Measured: the total never rose in any step (worst rise 0).
    assert!(
        worst_rise <= 1e-12,
        "energy rose by {worst_rise:e}·E0 in one step"
    );
}

/// Relative drift of total energy (kinetic + Hertz elastic) of an elastic, frictionless
/// periodic box over `steps` steps.
fn elastic_drift(steps: u64) -> (f64, u64) {
    let (mut sim, _) = periodic_box(1000, 1.0, 0.0, 2);
    let (ke0, _) = kinetic_energy_and_momentum(&mut sim.world);
    let e0 = ke0 + stored_energy(&mut sim);
    let mut worst: f64 = 0.0;
    for k in 0..steps {
        let sample = k % 10 == 0 || k + 1 == steps;
        // Symplectic Euler staggers velocities and positions by half a step: the kinetic
        // energy after the kick is paired with the elastic energy averaged over the
        // positions before and after the drift.
        let before = if sample { stored_energy(&mut sim) } else { 0.0 };
        sim.step().unwrap();
        if sample {
            let (ke, _) = kinetic_energy_and_momentum(&mut sim.world);
            let e = ke + 0.5 * (before + stored_energy(&mut sim));
            worst = worst.max((e / e0 - 1.0).abs());
        }
    }
    (worst, sim.world.resource::<Tally>().collisions[0])
}

#[test]
fn elastic_energy_drift_is_bounded() {
    // The 10⁵ steps (≈ 6 s in release, ~10⁵ contacts started). Symplectic Euler
    // keeps the energy of the Hertz contacts bounded rather than drifting: measured worst
    // |E/E0 − 1| = 2.9e-5 (dt = t_c/50 at 4× the rms speed), with the energy measured at
    // the half step (see `elastic_drift`). Asserted: the 1e-4.
    let (worst, collisions) = elastic_drift(100_000);
    eprintln!("elastic box: 1e5 steps, {collisions} contacts, worst |E/E0 − 1| = {worst:.3e}");
    assert!(worst < 1e-4);
}

fn state_bits(sim: &mut Simulation) -> Vec<u64> {
    let mut out = Vec::new();
    let mut q = sim
        .world
        .query::<(&ParticleId, &Position, &Velocity, &AngularVelocity)>();
    let mut rows: Vec<_> = q
        .iter(&sim.world)
        .map(|(i, x, v, w)| (i.0, x.0, v.0, w.0))
        .collect();
    rows.sort_by_key(|r| r.0);
    for (_, x, v, w) in rows {
        for c in [x, v, w] {
            out.extend(c.to_array().map(f64::to_bits));
        }
    }
    out
}

fn run_box_bits(steps: u64) -> Vec<u64> {
    let (mut sim, _) = periodic_box_sized(1000, 0.8, 0.3, 3, 10.5 * D);
    sim.run(steps, |_| true).unwrap();
    state_bits(&mut sim)
}

/// A compressed packing: 22³ = 10 648 spheres on a simple cubic lattice of spacing 0.995·D
/// in a periodic box, with random velocities, so every particle touches its six
/// neighbours from the first step (the force stage's dense path, in several slots, and
/// the kicks in parallel chunks).
fn dense_packing(seed: u64) -> Simulation {
    let k = 22;
    let a = 0.995 * D;
    let mut cfg = contact_cfg(0.6, 0.4, Some(DVec3::splat(k as f64 * a)));
    cfg.skin = 0.1 * D;
    cfg.rolling_friction = 0.05;
    let dt = hertz_contact_time(0.5 * sphere_mass(D, RHO), 0.25 * D, e_eff(), 1.0) / 50.0;
    let mut sim = Simulation::new(config(dt, Some(cfg), None));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for i in 0..k {
        for j in 0..k {
            for l in 0..k {
                let x = DVec3::new(i as f64, j as f64, l as f64) * a + DVec3::splat(0.5 * a);
                let v = DVec3::new(
                    rng.random_range(-0.2..0.2),
                    rng.random_range(-0.2..0.2),
                    rng.random_range(-0.2..0.2),
                );
                sim.spawn(&spec(x, v, D));
            }
        }
    }
    sim
}

fn run_dense_bits(steps: u64) -> Vec<u64> {
    let mut sim = dense_packing(5);
    sim.run(steps, |_| true).unwrap();
    state_bits(&mut sim)
}

#[test]
fn same_run_twice_is_bit_identical() {
    assert_eq!(run_box_bits(300), run_box_bits(300));
    assert_eq!(run_dense_bits(30), run_dense_bits(30));
}

#[test]
fn dense_packing_conserves_momentum_in_every_particle_contact() {
    let mut sim = dense_packing(5);
    let (_, p0) = kinetic_energy_and_momentum(&mut sim.world);
    let scale = momentum_scale(&mut sim);
    sim.run(100, |_| true).unwrap();
    let st = sim.world.resource::<ContactState>();
    let n = st.ids.len();
    eprintln!(
        "dense packing: {n} particles, {} in contact, {}",
        st.active,
        st.summary()
    );
    // Each particle touches its six neighbours, across the periodic faces too.
    assert_eq!(st.active, 3 * n, "{} contacts", st.active);
    assert!(st.slot_count() >= 4, "{} slots", st.slot_count());
    let (_, p) = kinetic_energy_and_momentum(&mut sim.world);
    let scale = scale.max(momentum_scale(&mut sim));
    let err = (p - p0).length() / scale;
    eprintln!("|ΔP|/Σm|v| = {err:.2e}");
    assert!(err < 1e-12);
}

/// A component the simulator does not know: tagging some particles with it would move
/// them to a second storage table. Every particle lives in one table (the contact arrays
/// index its rows), so the step refuses to run on a split world, naming the invariant,
/// instead of summing the pairs in some other order.
#[derive(bevy_ecs::component::Component)]
struct Tagged;

#[test]
fn particles_split_over_two_tables_are_refused() {
    let mut two = dense_packing(3);
    two.run(2, |_| true).unwrap();
    let every_third: Vec<bevy_ecs::entity::Entity> = {
        let mut q = two.world.query::<(bevy_ecs::entity::Entity, &ParticleId)>();
        q.iter(&two.world)
            .filter(|(_, id)| id.0 % 3 == 0)
            .map(|(e, _)| e)
            .collect()
    };
    for e in every_third {
        two.world.entity_mut(e).insert(Tagged);
    }
    let err = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let _ = two.run(1, |_| true);
    }))
    .expect_err("a split particle table must stop the step");
    let msg = err
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| err.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_default();
    assert!(msg.contains("more than one storage table"), "{msg}");
}

/// Digests of the final state of the dilute box, of the dense packing and of the walled
/// packing (wall candidates cut into pieces), as `STATE_DIGEST_<name>=<hex>`.
fn state_digests() -> Vec<String> {
    let walled = {
        let (mut sim, _) = walled_packing();
        sim.run(400, |_| true).unwrap();
        state_bits(&mut sim)
    };
    [
        ("box", run_box_bits(300)),
        ("dense", run_dense_bits(60)),
        ("walled", walled),
    ]
    .into_iter()
    .map(|(name, bits)| {
        let mut h: u64 = 0xcbf29ce484222325;
        for b in bits {
            h = (h ^ b).wrapping_mul(0x100000001b3);
        }
        format!("STATE_DIGEST_{name}={h:016x}")
    })
    .collect()
}

#[test]
fn one_and_two_threads_give_identical_results() {
    // Each thread count runs in this process with its own team
    // (`scg_core::exec::with_settings`).
    let digests = |threads: usize, parallel_min: usize, portable: bool| {
        let s = scg_core::exec::ExecSettings {
            threads,
            parallel_min,
            portable,
            ..Default::default()
        };
        scg_core::exec::with_settings(s, state_digests)
    };
    // Two threads twice: with the default threshold, and with every per-particle pass
    // split over the threads (parallel_min = 1: the test scenes are small); and the
    // portable kernels (no AVX2 lanes) on two threads.
    let default_min = scg_core::exec::par::PARALLEL_THRESHOLD;
    let a = digests(1, default_min, false);
    let b = digests(2, default_min, false);
    let c = digests(2, 1, false);
    let d = digests(2, 1, true);
    eprintln!("{a:?}");
    assert_eq!(a, b);
    assert_eq!(a, c);
    assert_eq!(a, d, "portable kernels");
    // Same physics, same bits: the digests pin the contact stages. They held unchanged
    // (box 11c6cbcb6723b63e, dense 6827178b20903004) through the new core layout; they
    // changed once since, on purpose, when the Tsuji damping became its exact closed form
    // (γ moved in the 6th digit). The walled packing's digest was added with the wall
    // candidates (its full-scan twin: `wall_candidates_give_the_full_scans_bits`). x86-64 only: other targets may round libm functions
    // differently.
    #[cfg(target_arch = "x86_64")]
    assert_eq!(
        a,
        [
            "STATE_DIGEST_box=436ab1b4e5eea940",
            "STATE_DIGEST_dense=098ae4bc77de8c81",
            "STATE_DIGEST_walled=998b151c99be45a0"
        ]
    );
}

#[test]
fn no_contacts_no_neighbour_search() {
    let sim = Simulation::new(config(1e-5, None, None));
    assert_eq!(
        sim.plan()
            .in_set(scg_core::step::StepSet::NeighbourSearch)
            .count(),
        0
    );
    assert!(!sim.plan().contains(StepSystem::IntegrateRotation));
    let sim = Simulation::new(config(1e-5, Some(contact_cfg(0.5, 0.3, None)), None));
    let pos = |n: StepSystem| sim.plan().position(n).unwrap();
    use StepSystem::*;
    assert!(pos(MaintainNeighbourList) < pos(ParticleContactForces));
    assert!(pos(ParticleContactForces) < pos(ApplyContactKicks));
    assert!(pos(ApplyContactKicks) < pos(IntegrateBallistic));
    assert!(pos(IntegrateBallistic) < pos(AdvanceClock));
    // Contacts kick the spin themselves: no rotation pass without walls.
    assert!(!sim.plan().contains(StepSystem::IntegrateRotation));
}

#[test]
fn rolling_resistance_decelerates_a_rolling_sphere() {
    // A sphere rolling on a floor under gravity with rolling friction μ_r: the constant
    // torque μ_r·F_n·r (F_n = m·g) against the rolling motion, with the contact point held
    // by the tangential spring, gives dv/dt = −μ_r·g/(1 + I/(m·r²)) = −μ_r·g/1.4.
    let (mu_r, g, v0) = (0.1, 9.81, 0.05);
    let mut c = contact_cfg(0.5, 0.5, None);
    c.rolling_friction = mu_r;
    let walls = WallSet {
        walls: vec![Wall {
            name: "floor".into(),
            shape: WallShape::Plane {
                point: DVec3::ZERO,
                normal: DVec3::Z,
            },
            motion: Default::default(),
        }],
        law: NormalLaw::hertz(0.5),
        material: material(0.5, 0.5),
    };
    let dt = 2e-7;
    let mut cfg = config(dt, Some(c), Some(walls));
    cfg.gravity = Some(DVec3::new(0.0, 0.0, -g));
    let mut sim = Simulation::new(cfg);
    let m = sphere_mass(D, RHO);
    let r = 0.5 * D;
    let k = hertz_stiffness(e_eff(), r);
    let delta = (m * g / k).powf(2.0 / 3.0);
    sim.spawn(&spec(
        DVec3::new(0.0, 0.0, r - delta),
        DVec3::new(v0, 0.0, 0.0),
        D,
    ));
    {
        let mut q = sim.world.query::<&mut AngularVelocity>();
        q.single_mut(&mut sim.world).unwrap().0 = DVec3::new(0.0, v0 / r, 0.0);
    }
    let t = 0.02;
    sim.run((t / dt) as u64, |_| true).unwrap();
    let v = sim.particles()[0].velocity.x;
    let expect = v0 - mu_r * g / 1.4 * t;
    eprintln!("rolling: v = {v:.5} m/s after {t} s (theory {expect:.5})");
    assert!((v / expect - 1.0).abs() < 0.03);
}

/// An oblique, frictional contact whose tangential history matters: the pair's result is
/// the same to the last bit whether the neighbour list is rebuilt every step (tiny skin)
/// or never during the contact (wide skin), and whether or not an unrelated particle is
/// despawned mid-contact (the set changes, table rows move, the history is carried over by
/// id).
#[test]
fn tangential_history_survives_rebuilds_and_set_changes() {
    let v = 0.5;
    let dt = auto_dt_pair(v);
    // (skin, despawn the far particle on the 5th step of the contact).
    let run = |skin: f64, despawn: bool| -> (Vec<u64>, f64) {
        let mut cfg = contact_cfg(0.7, 0.5, None);
        cfg.skin = skin;
        let mut sim = Simulation::new(config(dt, Some(cfg), None));
        // Far away and first in the table: despawning it moves the last row into its place.
        let far = sim.spawn(&spec(DVec3::new(0.0, 0.0, 1.0), DVec3::ZERO, D));
        sim.spawn(&spec(DVec3::ZERO, DVec3::ZERO, D));
        // Oblique approach: 0.3 of the speed along the line of centres at first touch.
        sim.spawn(&spec(
            DVec3::new(1.02 * D, 0.0, 0.0),
            DVec3::new(-0.3 * v, 0.9 * v, 0.0),
            D,
        ));
        let mut history_at_despawn = 0.0;
        let mut touching_steps = 0;
        for _ in 0..600 {
            let h = sim
                .world
                .resource::<ContactState>()
                .pairs
                .state
                .iter()
                .map(|p| p.history.length())
                .fold(0.0, f64::max);
            if h > 0.0 {
                touching_steps += 1;
            }
            if despawn && touching_steps == 5 {
                history_at_despawn = h;
                let e = sim
                    .world
                    .query::<(bevy_ecs::entity::Entity, &ParticleId)>()
                    .iter(&sim.world)
                    .find(|(_, id)| id.0 == far)
                    .unwrap()
                    .0;
                sim.world.despawn(e);
            }
            sim.step().unwrap();
        }
        let mut q = sim
            .world
            .query::<(&ParticleId, &Position, &Velocity, &AngularVelocity)>();
        let mut rows: Vec<_> = q
            .iter(&sim.world)
            .filter(|r| r.0.0 != far)
            .map(|(i, x, v, w)| (i.0, x.0, v.0, w.0))
            .collect();
        rows.sort_by_key(|r| r.0);
        let bits = rows
            .iter()
            .flat_map(|(_, x, v, w)| [x, v, w].map(|c| c.to_array().map(f64::to_bits)))
            .flatten()
            .collect();
        (bits, history_at_despawn)
    };
    let (reference, _) = run(0.5 * D, false);
    let (every_step, _) = run(1e-9 * D, false);
    assert_eq!(
        reference, every_step,
        "rebuilding every step changed the result"
    );
    let (despawned, h) = run(0.5 * D, true);
    assert!(h > 0.0, "no tangential history at the despawn");
    assert_eq!(
        reference, despawned,
        "despawning another particle changed the result"
    );
    // The spin shows the tangential force acted.
    let spin_bits = &reference[reference.len() - 3..];
    assert!(spin_bits.iter().any(|b| f64::from_bits(*b) != 0.0));
}

/// Ghost rows stand in for the particles another process owns (the MPI driver's
/// protocol, without MPI): a jittered lattice of 64 touching spheres with friction and
/// random velocities, plus a pair that crosses the cut one after the other while in a
/// sliding contact, run whole in one simulation and split at a cut into two whose
/// particles are each other's ghosts, particles migrating (with their touching pairs'
/// histories) when they cross it. The two halves together follow the whole one to
/// rounding (the force sums may run in another order), count the same collisions, and
/// the test sees local–ghost contacts, migrations and histories carried along.
#[test]
fn ghosts_and_migration_follow_the_whole_simulation() {
    let sets = ghosts_follow_the_whole(false);
    assert_eq!(sets, 4000, "a new ghost set every step");
}

/// The same with the driver's protocol since issue 39 (LAMMPS's): a new ghost set, and
/// migration, only on the steps where either half's `RebuildCheck` asks for one
/// (one of its particles moved more than half the skin, or its table changed); the
/// ghosts' states forwarded row for row between (`forward_ghosts`, no list rebuild).
#[test]
fn forwarded_ghosts_follow_the_whole_simulation() {
    let sets = ghosts_follow_the_whole(true);
    assert!(
        (2..1000).contains(&sets),
        "{sets} ghost sets in 4000 steps: the protocol shows nothing"
    );
}

/// Runs the lattice below whole and split in two; returns the ghost sets given.
fn ghosts_follow_the_whole(forward: bool) -> usize {
    use scg_core::stages::contacts::ghosts::{Due, RebuildCheck, TableStates, table_rows};
    let v = 0.5;
    let dt = auto_dt_pair(v);
    let cfg = || config(dt, Some(contact_cfg(0.7, 0.5, None)), None);
    // The cut runs through the middle of a lattice column: particles cross it.
    let cut = 0.505 * D;
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut specs = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            for k in 0..4 {
                let x = DVec3::new(i as f64 - 1.5, j as f64, k as f64) * 1.01 * D;
                let jitter = DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5;
                let u = DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5;
                specs.push(spec(x + 0.004 * D * jitter, u * v, D));
            }
        }
    }
    // Side by side along y, just touching, closing at 0.05 m/s and sliding past each
    // other along z, both moving across the cut at 0.5 m/s: the first crosses while the
    // contact lasts, so its history must go with it.
    let y = 10.0 * D;
    specs.push(spec(
        DVec3::new(cut - 2e-6, y, 0.0),
        DVec3::new(0.5, -0.025, 0.1),
        D,
    ));
    specs.push(spec(
        DVec3::new(cut - 12e-6, y - D, 0.0),
        DVec3::new(0.5, 0.025, -0.1),
        D,
    ));
    let mut whole = Simulation::new(cfg());
    let mut halves = [Simulation::new(cfg()), Simulation::new(cfg())];
    for s in &specs {
        whole.spawn(s);
        for h in &mut halves {
            h.spawn(s);
        }
    }
    let side = |x: DVec3| usize::from(x.x >= cut);
    for (k, h) in halves.iter_mut().enumerate() {
        drop(h.extract_particles(|_, x| side(x) != k));
    }
    let (mut migrated, mut carried, mut ghost_contacts, mut sets) = (0, 0, 0, 0);
    let mut checks = halves.each_mut().map(|h| RebuildCheck::new(&mut h.world));
    for step in 0..4000 {
        let due = !forward
            || step == 0
            || halves
                .iter_mut()
                .zip(&mut checks)
                .map(|(h, c)| c.due(&mut h.world))
                .any(|d| d != Due::No);
        if due {
            sets += 1;
            let rows = [
                table_rows(&mut halves[0].world),
                table_rows(&mut halves[1].world),
            ];
            for k in 0..2 {
                halves[k]
                    .world
                    .resource_mut::<ContactState>()
                    .set_ghosts(rows[1 - k].sorted_by_id());
            }
        } else {
            // The other half's particles in the order of the set (sorted by id).
            let mut states = [Vec::new(), Vec::new()];
            for (k, h) in halves.iter_mut().enumerate() {
                let rows = table_rows(&mut h.world);
                let mut order: Vec<u32> = (0..rows.len() as u32).collect();
                order.sort_unstable_by_key(|&r| rows.ids[r as usize]);
                TableStates::new(&mut h.world).append(&h.world, &order, &mut states[k]);
            }
            for k in 0..2 {
                let mut st = halves[k].world.resource_mut::<ContactState>();
                assert_eq!(st.put_ghost_states(0, &states[1 - k]), st.ghosts().len());
            }
        }
        whole.step().unwrap();
        for h in &mut halves {
            h.step().unwrap();
            let st = h.world.resource::<ContactState>();
            let local = st.local_rows() as u32;
            ghost_contacts += (st.pairs.in_contact(&st.list.pairs))
                .filter(|([_, j], _)| *j >= local)
                .count();
        }
        // Migration: every step, or (forwarding) only before a new ghost set, that is
        // after a step where a half asks for one.
        if forward
            && !halves
                .iter_mut()
                .zip(&mut checks)
                .map(|(h, c)| c.due(&mut h.world))
                .any(|d| d != Due::No)
        {
            continue;
        }
        let mut moving = Vec::new();
        for (k, h) in halves.iter_mut().enumerate() {
            let out = h.extract_particles(|_, x| side(x) != k);
            let ids: Vec<u32> = out.iter().map(|p| p.id).collect();
            let hist = h
                .world
                .resource::<ContactState>()
                .histories_of(|id| ids.contains(&id));
            moving.push((out, hist));
        }
        for (k, (out, hist)) in moving.into_iter().enumerate() {
            migrated += out.len();
            carried += hist.len();
            let to = &mut halves[1 - k];
            to.insert_particles(&out).unwrap();
            to.world
                .resource_mut::<ContactState>()
                .receive_histories(hist);
        }
    }
    let mut split: Vec<_> = halves.iter_mut().flat_map(|h| h.particles()).collect();
    split.sort_by_key(|p| p.id);
    let reference = whole.particles();
    assert_eq!(split.len(), reference.len());
    let mut worst: f64 = 0.0;
    for (a, b) in split.iter().zip(&reference) {
        assert_eq!(a.id, b.id);
        worst = worst.max((a.position - b.position).length());
    }
    let tally = |s: &Simulation| s.world.resource::<Tally>().collisions[0];
    let (c_whole, c_split) = (tally(&whole), tally(&halves[0]) + tally(&halves[1]));
    eprintln!(
        "largest distance from the whole run {worst:.3e} m; collisions {c_whole} and {c_split}; {migrated} migrations carrying {carried} histories; {ghost_contacts} local–ghost contacts over the steps; {sets} ghost sets"
    );
    assert!(migrated > 5 && carried > 0 && ghost_contacts > 100);
    assert!(c_whole > 50);
    assert_eq!(c_whole, c_split);
    assert!(worst < 1e-9 * D, "{worst:.3e} m");
    sets
}

/// A cylinder with a floor and a triangle-mesh lid, packed loosely with spheres moving
/// at random under tilted gravity (contacts on, friction, so wall torques too).
fn walled_packing() -> (Simulation, usize) {
    use scg_core::physics::trimesh::TriMesh;
    let rc = 6.0 * D;
    let a = 1.05 * D;
    let layers = 6;
    let top = 0.52 * D + (layers - 1) as f64 * a + 0.56 * D;
    let l = 7.0 * D;
    let lid = TriMesh::new(
        vec![
            DVec3::new(-l, -l, top),
            DVec3::new(l, -l, top),
            DVec3::new(l, l, top),
            DVec3::new(-l, l, top),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
    .unwrap();
    let walls = WallSet {
        walls: vec![
            Wall {
                name: "floor".into(),
                shape: WallShape::Plane {
                    point: DVec3::ZERO,
                    normal: DVec3::Z,
                },
                motion: Default::default(),
            },
            Wall {
                name: "vessel".into(),
                shape: WallShape::CylinderInside {
                    center: DVec3::ZERO,
                    axis: DVec3::Z,
                    radius: rc,
                    extent: None,
                },
                motion: Default::default(),
            },
            Wall {
                name: "lid".into(),
                shape: WallShape::Mesh(std::sync::Arc::new(lid)),
                motion: Default::default(),
            },
        ],
        law: NormalLaw::hertz(0.7),
        material: material(0.7, 0.4),
    };
    let dt = hertz_contact_time(0.5 * sphere_mass(D, RHO), 0.25 * D, e_eff(), 1.0) / 30.0;
    let mut cfg = config(dt, Some(contact_cfg(0.7, 0.4, None)), Some(walls));
    cfg.gravity = Some(DVec3::new(300.0, 0.0, -1000.0));
    let mut sim = Simulation::new(cfg);
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let mut n = 0;
    for k in 0..layers {
        for i in -6..=6 {
            for j in -6..=6 {
                let x = DVec3::new(i as f64 * a, j as f64 * a, 0.52 * D + k as f64 * a);
                if x.truncate().length() > rc - 0.52 * D {
                    continue;
                }
                let v = DVec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                sim.spawn(&spec(x, v, D));
                n += 1;
            }
        }
    }
    (sim, n)
}

/// Between neighbour-list builds the wall stage visits only the particles that may touch
/// a wall (`WallCandidates`): the run gives the bits of one that visits every particle at
/// every step, while skipping most particles at most steps.
#[test]
fn wall_candidates_give_the_full_scans_bits() {
    use scg_core::stages::walls::WallCandidates;
    let steps = 1500;
    let (mut full, n) = walled_packing();
    for _ in 0..steps {
        full.step().unwrap();
        // Forget the candidates: the next wall stage visits every particle.
        *full.world.resource_mut::<WallCandidates>() = WallCandidates::default();
    }
    let (mut listed, _) = walled_packing();
    let (mut skipping_steps, mut rows_seen, mut touched) = (0, 0, 0);
    for _ in 0..steps {
        let builds = listed.world.resource::<ContactState>().list.builds;
        listed.step().unwrap();
        let st = listed.world.resource::<ContactState>();
        let rows = listed
            .world
            .resource::<WallCandidates>()
            .current(Some(st))
            .map(<[u32]>::len);
        if st.list.builds == builds {
            skipping_steps += 1;
            rows_seen = rows_seen.max(rows.unwrap());
        }
        let mut q = listed.world.query::<&Torque>();
        touched = touched.max(q.iter(&listed.world).filter(|t| t.0 != DVec3::ZERO).count());
    }
    let builds = listed.world.resource::<ContactState>().list.builds;
    eprintln!(
        "{n} particles, {steps} steps: {builds} list builds, {skipping_steps} steps on the \
         candidates (at most {rows_seen} rows), at most {touched} particles with a wall torque"
    );
    assert!(
        builds >= 5,
        "{builds} builds: the run should cross several rebuilds"
    );
    assert!(
        skipping_steps > steps / 2,
        "{skipping_steps} steps on the candidates"
    );
    assert!(
        rows_seen < n / 2 && touched > 10,
        "{rows_seen} candidate rows, {touched} touching"
    );
    assert_eq!(state_bits(&mut listed), state_bits(&mut full));
}
