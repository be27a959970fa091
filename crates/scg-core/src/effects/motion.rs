//! Drag and motion: the integration stage.
//!
//! Which system moves the particles depends on the scene: the exponential scheme with
//! precomputed Stokes factors (the fast path), the exponential scheme with a
//! Reynolds-dependent drag law, the explicit scheme, or plain ballistic motion when the
//! scene has no fluid. Contact forces (when a scene has contacts or walls) enter as a kick
//! before the drift; gravity and buoyancy as a constant acceleration inside it.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use bevy_ecs::prelude::*;
use glam::DVec3;

use crate::components::*;
use crate::drag::{DragLaw, particle_reynolds};
use crate::effects::guard::Health;
use crate::flow::{FlowField, Fluid};
use crate::integrate::{
    Integrator, angular_kick, explicit_euler, explicit_substeps, exponential_drift,
    exponential_factors, linear_kick,
};
use crate::step::{StepBuilder, StepSet};

/// Simulation clock (resource): t = step·dt, never the wall clock.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct SimClock {
    /// Steps completed.
    pub step: u64,
    /// Time step, s.
    pub dt: f64,
    /// Particle-steps done so far (Σ over steps of the particles moved).
    pub particle_steps: u64,
}

impl SimClock {
    /// Simulation time, s.
    pub fn time(&self) -> f64 {
        self.step as f64 * self.dt
    }
}

/// How particles move (resource); see [`crate::sim::SimConfig`] for the meaning.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// Time step, s.
    pub dt: f64,
    /// Integrator.
    pub integrator: Integrator,
    /// Drag law, `None` without fluid drag.
    pub drag: Option<DragLaw>,
    /// Gravity, m/s² (zero without the gravity effect).
    pub gravity: DVec3,
    /// Reduce gravity by buoyancy: a = g·(1 − ρ_f/ρ_p).
    pub buoyancy: bool,
}

/// The largest distance any particle moved in the last integration step (resource,
/// present when the scene has contacts). Every integrator records into it; the neighbour
/// stage takes it to bound displacements without a pass over all particles.
#[derive(Resource, Debug, Default)]
pub struct StepDisplacement {
    /// Bits of the largest squared step displacement, m² (non-negative floats order
    /// like their bits).
    max2_bits: AtomicU64,
    /// Set by an integrator that recorded every particle this step.
    reported: AtomicBool,
}

impl StepDisplacement {
    /// Record a squared displacement, m².
    #[inline]
    pub fn record(&self, d2: f64) {
        let b = d2.to_bits();
        if b > self.max2_bits.load(Ordering::Relaxed) {
            self.max2_bits.fetch_max(b, Ordering::Relaxed);
        }
    }

    /// Mark the step as fully recorded.
    pub fn mark_reported(&self) {
        self.reported.store(true, Ordering::Relaxed);
    }

    /// The largest displacement of the step, m, if an integrator reported one; resets.
    pub fn take(&self) -> Option<f64> {
        let reported = self.reported.swap(false, Ordering::Relaxed);
        let bits = self.max2_bits.swap(0, Ordering::Relaxed);
        reported.then(|| f64::from_bits(bits).sqrt())
    }
}

/// Constant body acceleration of a particle (gravity, reduced by buoyancy), m/s².
/// Present only when the scene declares gravity.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct BodyAcceleration(pub DVec3);

/// Add the motion systems the scene needs (with `rotation`, the angular velocity is
/// integrated from the contact torques), and the clock.
pub fn plugin(b: &mut StepBuilder, motion: &Motion, rotation: bool) {
    match (motion.drag, motion.integrator) {
        (None, _) => b.add(
            StepSet::Integration,
            "motion",
            "integrate_ballistic",
            integrate_ballistic,
        ),
        (Some(DragLaw::Stokes), Integrator::Exponential) => b.add(
            StepSet::Integration,
            "drag:stokes",
            "integrate_stokes_exponential",
            integrate_stokes_exponential,
        ),
        (Some(law), Integrator::Exponential) => b.add(
            StepSet::Integration,
            drag_effect_name(law),
            "integrate_drag_exponential",
            integrate_drag_exponential,
        ),
        (Some(law), Integrator::Explicit) => b.add(
            StepSet::Integration,
            drag_effect_name(law),
            "integrate_drag_explicit",
            integrate_drag_explicit,
        ),
    }
    if rotation {
        b.add(
            StepSet::Integration,
            "contacts",
            "integrate_rotation",
            integrate_rotation,
        );
    }
    b.add(
        StepSet::Integration,
        "clock",
        "advance_clock",
        advance_clock,
    );
}

/// Angular velocity from the contact torque (paper eq. 3): ω += T·dt/I with the solid
/// sphere's I = m·d²/10.
pub fn integrate_rotation(
    motion: Res<Motion>,
    mut q: Query<(&mut AngularVelocity, &Torque, &Mass, &Diameter)>,
) {
    let dt = motion.dt;
    type Item<'a> = (
        bevy_ecs::change_detection::ContiguousMut<'a, AngularVelocity>,
        &'a [Torque],
        &'a [Mass],
        &'a [Diameter],
    );
    // Most particles touch no wall: skip the division for a zero torque.
    let one = move |w: &mut DVec3, t: DVec3, m: f64, d: f64| {
        if t != DVec3::ZERO {
            *w = angular_kick(*w, t, m, d, dt);
        }
    };
    type Parts<'a> = (
        &'a mut [AngularVelocity],
        &'a [Torque],
        &'a [Mass],
        &'a [Diameter],
    );
    fn parts<'a>((ws, ts, ms, ds): Item<'a>) -> Parts<'a> {
        (crate::par::bypass(ws), ts, ms, ds)
    }
    let body = move |(ws, ts, ms, ds): Parts| {
        for i in 0..ws.len() {
            one(&mut ws[i].0, ts[i].0, ms[i].0, ds[i].0);
        }
    };
    let contiguous = crate::par::for_each_split(&mut q, parts, body);
    if !contiguous {
        crate::par::for_each_mut(&mut q, |(mut w, t, m, d)| one(&mut w.0, t.0, m.0, d.0));
    }
}

fn drag_effect_name(law: DragLaw) -> &'static str {
    match law {
        DragLaw::Stokes => "drag:stokes",
        DragLaw::SchillerNaumann => "drag:schiller_naumann",
    }
}

/// Advance the step counter (the last system of the integration stage).
pub fn advance_clock(mut clock: ResMut<SimClock>, q: Query<(), With<ParticleId>>) {
    clock.step += 1;
    clock.particle_steps += q.iter().len() as u64;
}

/// Velocity after the contact kick: v + F/m·dt (unchanged without contact forces).
#[inline]
fn kick(v: DVec3, f: Option<&Force>, m: f64, dt: f64) -> DVec3 {
    match f {
        Some(f) => linear_kick(v, f.0, m, dt),
        None => v,
    }
}

/// One exponential-midpoint step for response time `tau` with factors for dt.
///
/// The fluid velocity is frozen at the predicted mid-step position x + v·dt/2 (one flow
/// evaluation per step); in a uniform flow the result is exact whatever the predictor.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn exponential_midpoint(
    flow: &FlowField,
    x: DVec3,
    v: DVec3,
    a: DVec3,
    tau: f64,
    gain: f64,
    relax: f64,
    dt: f64,
) -> (DVec3, DVec3) {
    let u = flow.velocity(x + v * (0.5 * dt));
    exponential_drift(x, v, u, a, tau, gain, relax, dt)
}

type MoveQuery<'w, 's, T> = Query<
    'w,
    's,
    (
        &'static mut Position,
        &'static mut Velocity,
        T,
        &'static Mass,
        Option<&'static Force>,
        Option<&'static BodyAcceleration>,
    ),
>;

/// Stokes drag, exponential scheme, precomputed factors: the fast path. Iterates over
/// contiguous component slices (one tight loop per table chunk, on every core), with the
/// flow in affine form where it has one.
pub fn integrate_stokes_exponential(
    motion: Res<Motion>,
    flow: Res<FlowField>,
    health: Res<Health>,
    disp: Option<Res<StepDisplacement>>,
    q: MoveQuery<(&'static StokesFactors, &'static FluidCoupling)>,
) {
    let flow = *flow;
    let disp = disp.as_deref();
    match flow.affine() {
        // A flow in the x–y plane that does not depend on z (e.g. a vortex about z): 2×2.
        Some(aff) if aff.is_planar_z() => {
            let (m00, m01, m10, m11) = (
                aff.m.x_axis.x,
                aff.m.y_axis.x,
                aff.m.x_axis.y,
                aff.m.y_axis.y,
            );
            let (b0, b1) = (aff.b.x, aff.b.y);
            stokes_kernel(q, motion.dt, &health, disp, move |x: DVec3| {
                DVec3::new(m00 * x.x + m01 * x.y + b0, m10 * x.x + m11 * x.y + b1, 0.0)
            })
        }
        Some(aff) => stokes_kernel(q, motion.dt, &health, disp, move |x| aff.velocity(x)),
        None => stokes_kernel(q, motion.dt, &health, disp, move |x| flow.velocity(x)),
    }
}

/// The columns of a move query's table; `S` the drag columns (none for `()`).
type ChunkItem<'a, S = (&'a [StokesFactors], &'a [FluidCoupling])> = (
    bevy_ecs::change_detection::ContiguousMut<'a, Position>,
    bevy_ecs::change_detection::ContiguousMut<'a, Velocity>,
    S,
    &'a [Mass],
    Option<&'a [Force]>,
    Option<&'a [BodyAcceleration]>,
);

/// [`ChunkItem`] as plain slices (nothing filters on changes of position or velocity:
/// the tick writes are skipped).
type ChunkParts<'a, S = (&'a [StokesFactors], &'a [FluidCoupling])> = (
    &'a mut [Position],
    &'a mut [Velocity],
    S,
    &'a [Mass],
    Option<&'a [Force]>,
    Option<&'a [BodyAcceleration]>,
);

/// [`ChunkItem`] → [`ChunkParts`].
fn chunk_parts<S>((xs, vs, s, ms, fs, gs): ChunkItem<'_, S>) -> ChunkParts<'_, S> {
    (
        crate::par::bypass(xs),
        crate::par::bypass(vs),
        s,
        ms,
        fs,
        gs,
    )
}

/// The fast-path loop for a flow given as a function of position.
fn stokes_kernel<U: Fn(DVec3) -> DVec3 + Sync + Send + Copy>(
    mut q: MoveQuery<(&'static StokesFactors, &'static FluidCoupling)>,
    dt: f64,
    health: &Health,
    disp: Option<&StepDisplacement>,
    flow: U,
) {
    // Returns the squared displacement.
    let step =
        move |x: &mut DVec3, v: &mut DVec3, sf: &StokesFactors, tau: f64, vk: DVec3, a: DVec3| {
            let u = flow(*x + vk * (0.5 * dt));
            let (x1, v1) = exponential_drift(*x, vk, u, a, tau, sf.gain, sf.relax, dt);
            // One test catches any NaN or infinity among the six numbers.
            if !(x1 + v1).element_sum().is_finite() {
                health.raise();
            }
            let d2 = (x1 - *x).length_squared();
            *x = x1;
            *v = v1;
            d2
        };
    let chunk = move |(xs, vs, (sfs, fcs), ms, fs, gs): ChunkParts| {
        // Local copies: the loop then keeps the flow and dt in registers instead of
        // reloading them through the closure on every particle.
        let (step, dt, flow) = (step, dt, flow);
        let n = xs.len().min(vs.len()).min(sfs.len());
        let (xs, vs, sfs) = (&mut xs[..n], &mut vs[..n], &sfs[..n]);
        if fs.is_none() && gs.is_none() {
            // Drag only: the common case, kept free of per-particle branches.
            // Any NaN or infinity makes the running sum non-finite: one test per chunk.
            let (sum, d2max) = match disp {
                Some(_) => drag_only_loop::<true, U>(xs, vs, sfs, dt, flow),
                None => drag_only_loop::<false, U>(xs, vs, sfs, dt, flow),
            };
            if !sum.is_finite() {
                health.raise();
            }
            if let Some(d) = disp {
                d.record(d2max);
            }
            return;
        }
        let mut d2max = 0.0_f64;
        for i in 0..n {
            let v = vs[i].0;
            let vk = kick(v, fs.map(|f| &f[i]), ms[i].0, dt);
            let a = gs.map_or(DVec3::ZERO, |g| g[i].0);
            d2max = d2max.max(step(&mut xs[i].0, &mut vs[i].0, &sfs[i], fcs[i].tau, vk, a));
        }
        if let Some(d) = disp {
            d.record(d2max);
        }
    };
    let contiguous = crate::par::for_each_split(&mut q, chunk_parts, chunk);
    if !contiguous {
        // Sparse storage somewhere in the query: per-entity iteration.
        crate::par::for_each_mut(&mut q, |(mut x, mut v, (sf, fc), m, f, g)| {
            let vk = kick(v.0, f, m.0, dt);
            let a = g.map_or(DVec3::ZERO, |g| g.0);
            let d2 = step(&mut x.0, &mut v.0, sf, fc.tau, vk, a);
            if let Some(d) = disp {
                d.record(d2);
            }
        });
    }
    if let Some(d) = disp {
        d.mark_reported();
    }
}

/// The drag-only loop of the fast path (no forces, no body acceleration): returns the sum
/// of all new positions and velocities (non-finite iff one of them is) and, with `TRACK`,
/// the largest squared step displacement, m².
#[inline(always)]
fn drag_only_loop<const TRACK: bool, U: Fn(DVec3) -> DVec3>(
    xs: &mut [Position],
    vs: &mut [Velocity],
    sfs: &[StokesFactors],
    dt: f64,
    flow: U,
) -> (DVec3, f64) {
    let mut sum = DVec3::ZERO;
    let mut d2max = 0.0_f64;
    for ((x, v), sf) in xs.iter_mut().zip(vs.iter_mut()).zip(sfs) {
        // exponential_drift with a = 0: w = u.
        let (x0, v0) = (x.0, v.0);
        let u = flow(x0 + v0 * (0.5 * dt));
        let dv = v0 - u;
        let dx = u * dt + dv * sf.relax;
        let (x1, v1) = (x0 + dx, v0 - dv * sf.gain);
        sum += x1 + v1;
        if TRACK {
            let d2 = dx.length_squared();
            if d2 > d2max {
                d2max = d2;
            }
        }
        x.0 = x1;
        v.0 = v1;
    }
    (sum, d2max)
}

/// Response time under `law` for the current slip, s.
#[inline]
fn effective_tau(law: DragLaw, tau: f64, fc: &FluidCoupling, fluid: &Fluid, slip: f64) -> f64 {
    let re = particle_reynolds(fc.drag_diameter, slip, fluid.density, fluid.viscosity);
    tau / law.correction(re)
}

/// Reynolds-dependent drag (e.g. Schiller–Naumann), exponential scheme: τ is evaluated
/// from the slip at the start of the step and held over it.
pub fn integrate_drag_exponential(
    motion: Res<Motion>,
    flow: Res<FlowField>,
    fluid: Res<Fluid>,
    health: Res<Health>,
    disp: Option<Res<StepDisplacement>>,
    mut q: MoveQuery<&'static FluidCoupling>,
) {
    let disp = disp.as_deref();
    let (dt, law) = (motion.dt, motion.drag.unwrap_or_default());
    let (flow, fluid) = (*flow, *fluid);
    let health = &*health;
    crate::par::for_each_mut(&mut q, |(mut x, mut v, fc, m, f, g)| {
        let a = g.map_or(DVec3::ZERO, |g| g.0);
        let vk = kick(v.0, f, m.0, dt);
        let slip = (flow.velocity(x.0) - vk).length();
        let tau = effective_tau(law, fc.tau, fc, &fluid, slip);
        let (gain, relax) = exponential_factors(tau, dt);
        let (x1, v1) = exponential_midpoint(&flow, x.0, vk, a, tau, gain, relax, dt);
        if !(x1.is_finite() && v1.is_finite()) {
            health.raise();
        }
        if let Some(d) = disp {
            d.record((x1 - x.0).length_squared());
        }
        x.0 = x1;
        v.0 = v1;
    });
    if let Some(d) = disp {
        d.mark_reported();
    }
}

/// Any drag law, semi-implicit Euler; sub-stepped so that every sub-step has dt ≤ τ/2.
pub fn integrate_drag_explicit(
    motion: Res<Motion>,
    flow: Res<FlowField>,
    fluid: Res<Fluid>,
    health: Res<Health>,
    disp: Option<Res<StepDisplacement>>,
    mut q: MoveQuery<&'static FluidCoupling>,
) {
    let disp = disp.as_deref();
    let (dt, law) = (motion.dt, motion.drag.unwrap_or_default());
    let (flow, fluid) = (*flow, *fluid);
    let health = &*health;
    crate::par::for_each_mut(&mut q, |(mut x, mut v, fc, m, f, g)| {
        let mut a = g.map_or(DVec3::ZERO, |g| g.0);
        if let Some(f) = f {
            a += f.0 / m.0;
        }
        let (mut xi, mut vi) = (x.0, v.0);
        let slip0 = (flow.velocity(xi) - vi).length();
        let n = explicit_substeps(effective_tau(law, fc.tau, fc, &fluid, slip0), dt);
        let h = dt / n as f64;
        for _ in 0..n {
            let u = flow.velocity(xi);
            let tau = effective_tau(law, fc.tau, fc, &fluid, (u - vi).length());
            (xi, vi) = explicit_euler(xi, vi, u, a, tau, h);
        }
        if !(xi.is_finite() && vi.is_finite()) {
            health.raise();
        }
        if let Some(d) = disp {
            d.record((xi - x.0).length_squared());
        }
        x.0 = xi;
        v.0 = vi;
    });
    if let Some(d) = disp {
        d.mark_reported();
    }
}

/// No fluid: contact kick, then the exact drift under gravity (free fall is exact;
/// with contacts alone this is symplectic Euler). Iterates over contiguous component
/// slices on every core.
pub fn integrate_ballistic(
    motion: Res<Motion>,
    health: Res<Health>,
    disp: Option<Res<StepDisplacement>>,
    mut q: MoveQuery<()>,
) {
    let dt = motion.dt;
    let health = &*health;
    let disp = disp.as_deref();
    let one = move |x: &mut DVec3, v: &mut DVec3, f: Option<&Force>, m: f64, a: DVec3| -> f64 {
        let vk = kick(*v, f, m, dt);
        let x1 = *x + vk * dt + 0.5 * a * dt * dt;
        let v1 = vk + a * dt;
        if !(x1 + v1).element_sum().is_finite() {
            health.raise();
        }
        let d2 = (x1 - *x).length_squared();
        *x = x1;
        *v = v1;
        d2
    };
    let chunk = move |(xs, vs, (), ms, fs, gs): ChunkParts<()>| {
        let mut d2max = 0.0_f64;
        for i in 0..xs.len() {
            let a = gs.map_or(DVec3::ZERO, |g| g[i].0);
            let d2 = one(&mut xs[i].0, &mut vs[i].0, fs.map(|f| &f[i]), ms[i].0, a);
            if d2 > d2max {
                d2max = d2;
            }
        }
        if let Some(d) = disp {
            d.record(d2max);
        }
    };
    let contiguous = crate::par::for_each_split(&mut q, chunk_parts::<()>, chunk);
    if !contiguous {
        crate::par::for_each_mut(&mut q, |(mut x, mut v, (), m, f, g)| {
            let a = g.map_or(DVec3::ZERO, |g| g.0);
            let d2 = one(&mut x.0, &mut v.0, f, m.0, a);
            if let Some(d) = disp {
                d.record(d2);
            }
        });
    }
    if let Some(d) = disp {
        d.mark_reported();
    }
}
