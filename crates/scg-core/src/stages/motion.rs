//! Drag and motion: the integration stage.
//!
//! Which system moves the particles depends on the scene: the exponential scheme with
//! precomputed Stokes factors (the fast path), the exponential scheme with a
//! Reynolds-dependent drag law, the explicit scheme, or plain ballistic motion when the
//! scene has no fluid. Wall forces enter as a kick before the drift (particle contacts
//! kick the velocities themselves, see [`super::contacts`]); gravity and buoyancy as a
//! constant acceleration inside it. Every system reads the particle table's columns in
//! place ([`super::table`]) and cuts them into pieces for the team.

use bevy_ecs::prelude::*;
use glam::DVec3;

use super::contacts::ContactState;
use super::move_lanes::{
    BallisticDrift, ClassifierFlow, Drift, Lanes, MovePiece, Mover, PlanarZ, StokesDrift,
    move_piece, scalar_rows,
};
use super::table::{bypass, columns_mut};
use super::walls::WallCandidates;
use crate::components::*;
use crate::exec::par::{Rows, Split, for_each_piece};
use crate::physics::carrier::{Body, Place, Scheme, WithOffset, advance};
use crate::physics::drag::DragLaw;
use crate::physics::flow::{Affine, FlowField, Fluid};
use crate::physics::integrate::{Integrator, angular_kick};
use crate::state::{Health, SimClock, StepDisplacement};
use crate::step::{StepBuilder, StepSet, StepSystem};

pub use crate::state::Motion;

/// Add the motion systems the scene needs (with `rotation`, the angular velocity is
/// integrated from the wall torques), and the clock. With `mesh`, the flow is on a CFD
/// mesh and [`super::mesh_flow`]'s plugin adds the system that moves the particles
/// whatever the drag law.
pub fn plugin(b: &mut StepBuilder, motion: &Motion, rotation: bool, mesh: bool) {
    use StepSystem::*;
    let set = StepSet::Integration;
    match (motion.drag, motion.integrator) {
        _ if mesh => {}
        (None, _) => b.add(set, "motion", IntegrateBallistic, integrate_ballistic),
        (Some(DragLaw::Stokes), Integrator::Exponential) => b.add(
            set,
            motion
                .forces
                .map_or("drag:stokes", |_| "drag:stokes+forces"),
            IntegrateStokesExponential,
            integrate_stokes_exponential,
        ),
        (Some(law), Integrator::Exponential) => b.add(
            set,
            drag_effect_name(law),
            IntegrateDragExponential,
            integrate_drag_exponential,
        ),
        (Some(law), Integrator::Explicit) => b.add(
            set,
            drag_effect_name(law),
            IntegrateDragExplicit,
            integrate_drag_explicit,
        ),
    }
    if rotation {
        b.add(set, "walls", IntegrateRotation, integrate_rotation);
    }
    b.add(set, "clock", AdvanceClock, advance_clock);
}

fn drag_effect_name(law: DragLaw) -> &'static str {
    match law {
        DragLaw::Stokes => "drag:stokes",
        DragLaw::SchillerNaumann => "drag:schiller_naumann",
        DragLaw::Putnam => "drag:putnam",
    }
}

/// Angular velocity from the wall torque (paper eq. 3): ω += T·dt/I with the solid
/// sphere's I = m·d²/10.
pub fn integrate_rotation(
    clock: Res<SimClock>,
    contacts: Option<Res<ContactState>>,
    candidates: Option<Res<WallCandidates>>,
    mut q: Query<(&mut AngularVelocity, &Torque, &Mass, &Diameter)>,
) {
    let dt = clock.dt;
    let Some((ws, ts, ms, ds)) = columns_mut(&mut q) else {
        return;
    };
    // Only the wall stage's candidates can have a torque when it listed them.
    let current = candidates
        .as_deref()
        .and_then(|w| w.current(contacts.as_deref()));
    let rows = Rows(0..ws.len());
    for_each_piece((bypass(ws), ts, ms, ds, rows), |(ws, ts, ms, ds, rows)| {
        let visit = |i: usize| {
            // Most particles touch no wall: skip the division for a zero torque.
            if ts[i].0 != DVec3::ZERO {
                ws[i].0 = angular_kick(ws[i].0, ts[i].0, ms[i].0, ds[i].0, dt);
            }
        };
        rows.visit(current, visit);
    });
}

/// Advance the step counter (the last system of the integration stage).
pub fn advance_clock(mut clock: ResMut<SimClock>, q: Query<(), With<ParticleId>>) {
    clock.step += 1;
    clock.particle_steps += q.iter().len() as u64;
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

/// The columns of a move query as plain slices; `S` the drag columns.
type Columns<'a, S> = (
    &'a mut [Position],
    &'a mut [Velocity],
    S,
    &'a [Mass],
    Option<&'a [Force]>,
    Option<&'a [BodyAcceleration]>,
);

/// The particle table's columns of a move query as [`Columns`] (`None`: no particle).
fn move_columns<'a, 's, S>(
    q: &'a mut MoveQuery<'_, 's, S>,
) -> Option<Columns<'a, <S as bevy_ecs::query::ContiguousQueryData>::Contiguous<'a, 's>>>
where
    S: bevy_ecs::query::ContiguousQueryData,
{
    columns_mut(q).map(|(xs, vs, drag, ms, fs, gs)| (bypass(xs), bypass(vs), drag, ms, fs, gs))
}

/// The moves of a pass over the particle table's columns (`None`: no particle), in
/// pieces on the team: `run` moves a piece (given its drag columns) and returns the
/// largest squared displacement and whether every result is finite; a non-finite one
/// raises the guard, and the step's displacements are then complete.
fn piece_pass<'a, S: Split + 'a>(
    columns: Option<Columns<'a, S>>,
    health: &Health,
    disp: Option<&StepDisplacement>,
    run: impl Fn(MovePiece, S) -> (f64, bool) + Sync,
) {
    if let Some(columns) = columns {
        for_each_piece(columns, |(x, v, drag, m, f, a)| {
            let (d2max, finite) = run(MovePiece { x, v, m, f, a }, drag);
            if !finite {
                health.raise();
            }
            if let Some(d) = disp {
                d.record(d2max);
            }
        });
    }
    if let Some(d) = disp {
        d.mark_reported();
    }
}

/// The drag columns of the schemes that take the carrier through [`advance`]: Stokes
/// factors, fluid couplings and, with a carrier modifier, the particles' offsets.
type CarrierColumns<'a> = (
    &'a [StokesFactors],
    &'a [FluidCoupling],
    Option<&'a [CarrierOffset]>,
);

/// [`piece_pass`] one particle at a time through the carrier-velocity seam: each
/// particle's step is [`advance`] under `scheme` in `flow`, plus the particle's
/// [`CarrierOffset`] when the scene has a carrier modifier.
fn carrier_pass<'a>(
    columns: Option<Columns<'a, CarrierColumns<'a>>>,
    health: &Health,
    disp: Option<&StepDisplacement>,
    scheme: &Scheme,
    flow: &FlowField,
) {
    piece_pass(columns, health, disp, |mut p, (sfs, fcs, offs)| {
        let n = p.x.len();
        let body = |i: usize, m: Mover| Body {
            x: m.x,
            v: m.v,
            m: m.m,
            force: m.force,
            a: m.a,
            fc: &fcs[i],
            sf: &sfs[i],
        };
        match offs {
            None => scalar_rows(&mut p, 0..n, |i, m| {
                let (x, v, _) = advance(scheme, flow, &body(i, m), Place::cell(0), None, None);
                (x, v)
            }),
            Some(offs) => scalar_rows(&mut p, 0..n, |i, m| {
                let carrier = WithOffset {
                    inner: flow,
                    du: offs[i].0,
                };
                let (x, v, _) = advance(scheme, &carrier, &body(i, m), Place::cell(0), None, None);
                (x, v)
            }),
        }
    });
}

/// [`piece_pass`] with the moves of [`super::move_lanes`]: each piece moved by
/// [`move_piece`] (four particles at a time) with the drift `drift` makes of the piece's
/// drag columns.
fn lanes_pass<'a, S: Split + 'a, D: Drift>(
    columns: Option<Columns<'a, S>>,
    health: &Health,
    disp: Option<&StepDisplacement>,
    dt: f64,
    drift: impl Fn(S) -> D + Sync,
) {
    piece_pass(columns, health, disp, |p, drag| {
        move_piece(p, drift(drag), dt)
    });
}

/// The drag-only loop of the fast path (no forces, no body acceleration): returns the sum
/// of all new positions and velocities (non-finite iff one of them is) and, with `TRACK`,
/// the largest squared step displacement, m².
///
/// Kept out of line: inlined into the piece closure, LLVM computed the affine flow in
/// scalar registers with spills (3.2·10^8 → 2.2·10^8 particle-steps/s on one thread for
/// 10^5 particles, `SCG_THREADS=1 scg bench drag --particles 100000 --steps 5000`); on its
/// own it keeps the x–y pair packed.
#[inline(never)]
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

/// A flow the Stokes fast path runs in ([`Lanes`]: its velocity at a point, also four
/// at a time), and the drag-only loop over a piece of the particle table (the scalar
/// [`drag_only_loop`] unless the flow has a faster one with the same bits).
trait StokesFlow: Lanes {
    /// [`drag_only_loop`] in this flow.
    fn drag_only<const TRACK: bool>(
        self,
        xs: &mut [Position],
        vs: &mut [Velocity],
        sfs: &[StokesFactors],
        dt: f64,
    ) -> (DVec3, f64) {
        drag_only_loop::<TRACK, _>(xs, vs, sfs, dt, move |x| self.velocity(x))
    }
}

impl StokesFlow for Affine {}
impl StokesFlow for ClassifierFlow {}
impl StokesFlow for FlowField {}

impl StokesFlow for PlanarZ {
    fn drag_only<const TRACK: bool>(
        self,
        xs: &mut [Position],
        vs: &mut [Velocity],
        sfs: &[StokesFactors],
        dt: f64,
    ) -> (DVec3, f64) {
        drag_only_planar::<TRACK>(xs, vs, sfs, dt, self)
    }
}

/// [`drag_only_loop`] in a planar flow: four particles at a time where the CPU has AVX2
/// (the same operations per particle, so the same bits; the running sum is only a
/// finiteness test and may be added in another order), else the scalar loop.
fn drag_only_planar<const TRACK: bool>(
    xs: &mut [Position],
    vs: &mut [Velocity],
    sfs: &[StokesFactors],
    dt: f64,
    flow: PlanarZ,
) -> (DVec3, f64) {
    #[cfg(target_arch = "x86_64")]
    if crate::exec::lanes() {
        // SAFETY: the CPU supports AVX2 (`exec::lanes` checked it).
        return unsafe { drag_only_planar_avx2::<TRACK>(xs, vs, sfs, dt, flow) };
    }
    drag_only_loop::<TRACK, _>(xs, vs, sfs, dt, move |x| flow.velocity(x))
}

/// The four-lane body of [`drag_only_planar`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn drag_only_planar_avx2<const TRACK: bool>(
    xs: &mut [Position],
    vs: &mut [Velocity],
    sfs: &[StokesFactors],
    dt: f64,
    flow: PlanarZ,
) -> (DVec3, f64) {
    use crate::simd::{F4, V4};
    use core::arch::x86_64::*;
    let n = xs.len().min(vs.len()).min(sfs.len());
    let n4 = n / 4 * 4;
    let (half_dt, dtv) = (F4::splat(0.5 * dt), F4::splat(dt));
    let mut sum = V4::zero();
    let mut d2max = F4::zero();
    for k in (0..n4).step_by(4) {
        let xp = xs[k..k + 4].as_mut_ptr() as *mut f64;
        let vp = vs[k..k + 4].as_mut_ptr() as *mut f64;
        let sp = sfs[k..k + 4].as_ptr() as *const f64;
        // SAFETY: four consecutive `Position`s / `Velocity`s (transparent DVec3s) are 12
        // f64; four `StokesFactors` (repr(C): gain, relax) are 8.
        let (x0, v0, gain, relax) = unsafe {
            let (s0, s1) = (_mm256_loadu_pd(sp), _mm256_loadu_pd(sp.add(4)));
            (
                V4::load_aos(xp),
                V4::load_aos(vp),
                // [g0 g2 g1 g3] → [g0 g1 g2 g3], and the same for relax.
                F4(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_unpacklo_pd(
                    s0, s1,
                ))),
                F4(_mm256_permute4x64_pd::<0b11_01_10_00>(_mm256_unpackhi_pd(
                    s0, s1,
                ))),
            )
        };
        let u = flow.velocity4(x0 + v0.scale(half_dt));
        let dv = v0 - u;
        let dx = u.scale(dtv) + dv.scale(relax);
        let (x1, v1) = (x0 + dx, v0 - dv.scale(gain));
        sum = sum + (x1 + v1);
        if TRACK {
            d2max = d2max.max_keep(dx.dot(dx));
        }
        // SAFETY: as for the loads.
        unsafe {
            x1.store_aos(xp);
            v1.store_aos(vp);
        }
    }
    let (mut total, mut top) =
        drag_only_loop::<TRACK, _>(&mut xs[n4..], &mut vs[n4..], &sfs[n4..], dt, move |x| {
            flow.velocity(x)
        });
    let [sx, sy, sz] = [sum.x, sum.y, sum.z].map(|c| c.to_array().iter().sum::<f64>());
    total += DVec3::new(sx, sy, sz);
    for d2 in d2max.to_array() {
        if d2 > top {
            top = d2;
        }
    }
    (total, top)
}

/// Stokes drag, exponential scheme, precomputed factors: the fast path. One tight loop
/// per piece of the particle table, on every core, with the flow in affine form where it
/// has one. With a carrier modifier, the general step through the carrier seam.
pub fn integrate_stokes_exponential(
    d: DragInputs,
    mut q: MoveQuery<(
        &'static StokesFactors,
        &'static FluidCoupling,
        Option<&'static CarrierOffset>,
    )>,
) {
    let flow = *d.flow;
    let disp = d.disp.as_deref();
    let health = &*d.health;
    let dt = d.clock.dt;
    let columns = move_columns(&mut q);
    if columns.as_ref().is_some_and(|c| c.2.2.is_some()) || d.motion.forces.is_some() {
        let scheme = d.scheme();
        return carrier_pass(columns, health, disp, &scheme, &flow);
    }
    match flow.affine() {
        // A flow in the x–y plane that does not depend on z (e.g. a vortex about z): 2×2.
        Some(aff) if aff.is_planar_z() => {
            let planar = PlanarZ {
                m: [
                    aff.m.x_axis.x,
                    aff.m.y_axis.x,
                    aff.m.x_axis.y,
                    aff.m.y_axis.y,
                ],
                b: [aff.b.x, aff.b.y],
            };
            stokes_kernel(columns, dt, health, disp, planar)
        }
        Some(aff) => stokes_kernel(columns, dt, health, disp, aff),
        // Only the classifier is not affine (its nozzle makes it piecewise).
        None => match ClassifierFlow::of(&flow) {
            Some(c) => stokes_kernel(columns, dt, health, disp, c),
            None => stokes_kernel(columns, dt, health, disp, flow),
        },
    }
}

/// The fast-path loop for a flow given as a function of position.
fn stokes_kernel<U: StokesFlow>(
    columns: Option<Columns<'_, CarrierColumns<'_>>>,
    dt: f64,
    health: &Health,
    disp: Option<&StepDisplacement>,
    flow: U,
) {
    let drag_only = columns
        .as_ref()
        .is_some_and(|c| c.4.is_none() && c.5.is_none());
    if !drag_only {
        // No particle, or wall forces or gravity: the general step, four at a time.
        return lanes_pass(columns, health, disp, dt, |(factors, couplings, _)| {
            StokesDrift {
                flow,
                factors,
                couplings,
            }
        });
    }
    let Some(columns) = columns else { return };
    // Drag only: the common case, kept free of per-particle branches.
    for_each_piece(columns, move |(xs, vs, (sfs, _, _), ..)| {
        // Any NaN or infinity makes the running sum non-finite: one test per piece.
        let (sum, d2max) = match disp {
            Some(_) => flow.drag_only::<true>(xs, vs, sfs, dt),
            None => flow.drag_only::<false>(xs, vs, sfs, dt),
        };
        if !sum.is_finite() {
            health.raise();
        }
        if let Some(d) = disp {
            d.record(d2max);
        }
    });
    if let Some(d) = disp {
        d.mark_reported();
    }
}

/// What the Reynolds-dependent drag systems read besides the particles.
#[derive(bevy_ecs::system::SystemParam)]
pub struct DragInputs<'w> {
    clock: Res<'w, SimClock>,
    motion: Res<'w, Motion>,
    flow: Res<'w, FlowField>,
    fluid: Option<Res<'w, Fluid>>,
    health: Res<'w, Health>,
    disp: Option<Res<'w, StepDisplacement>>,
}

impl DragInputs<'_> {
    /// The per-particle scheme: dt, the drag law, the integrator and the fluid.
    fn scheme(&self) -> Scheme {
        Scheme {
            dt: self.clock.dt,
            law: Some(self.motion.drag.unwrap_or_default()),
            integrator: self.motion.integrator,
            fluid: self.fluid.as_deref().copied().unwrap_or(Scheme::NO_FLUID),
            forces: self.motion.forces,
        }
    }
}

/// The drag columns of the Reynolds-dependent schemes' query.
type CarrierQuery = (
    &'static StokesFactors,
    &'static FluidCoupling,
    Option<&'static CarrierOffset>,
);

/// Reynolds-dependent drag (e.g. Schiller–Naumann), exponential scheme: τ is evaluated
/// from the slip at the start of the step and held over it ([`advance`]).
pub fn integrate_drag_exponential(d: DragInputs, mut q: MoveQuery<CarrierQuery>) {
    let scheme = d.scheme();
    let columns = move_columns(&mut q);
    carrier_pass(columns, &d.health, d.disp.as_deref(), &scheme, &d.flow);
}

/// Any drag law, semi-implicit Euler; sub-stepped so that every sub-step has dt ≤ τ/2
/// ([`advance`]).
pub fn integrate_drag_explicit(d: DragInputs, mut q: MoveQuery<CarrierQuery>) {
    let scheme = d.scheme();
    let columns = move_columns(&mut q);
    carrier_pass(columns, &d.health, d.disp.as_deref(), &scheme, &d.flow);
}

/// No fluid: wall kick, then the exact drift under gravity (free fall is exact; with
/// contacts alone this is symplectic Euler).
pub fn integrate_ballistic(
    clock: Res<SimClock>,
    health: Res<Health>,
    disp: Option<Res<StepDisplacement>>,
    mut q: MoveQuery<()>,
) {
    let dt = clock.dt;
    let columns = move_columns(&mut q);
    lanes_pass(columns, &health, disp.as_deref(), dt, |()| BallisticDrift);
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The four-lane drag loop gives the scalar loop's bits for every particle (the tail
    /// after the last four included), the same largest step and a sum that is finite
    /// exactly when the scalar one is.
    #[test]
    fn planar_drag_lanes_give_the_scalar_loops_bits() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let n = 103;
        let v3 = |rng: &mut rand::rngs::StdRng, s: f64| {
            (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * s
        };
        let xs: Vec<Position> = (0..n).map(|_| Position(v3(&mut rng, 2.0))).collect();
        let vs: Vec<Velocity> = (0..n).map(|_| Velocity(v3(&mut rng, 10.0))).collect();
        let sfs: Vec<StokesFactors> = (0..n)
            .map(|_| StokesFactors {
                gain: rng.random(),
                relax: rng.random::<f64>() * 1e-3,
            })
            .collect();
        let flow = PlanarZ {
            m: [0.3, -1.7, 1.9, 0.2],
            b: [0.5, -0.25],
        };
        for bad in [false, true] {
            let (mut xa, mut va) = (xs.clone(), vs.clone());
            if bad {
                va[101].0.y = f64::NAN;
            }
            let (mut xb, mut vb) = (xa.clone(), va.clone());
            let a = drag_only_loop::<true, _>(&mut xa, &mut va, &sfs, 1e-3, |x| flow.velocity(x));
            let b = drag_only_planar::<true>(&mut xb, &mut vb, &sfs, 1e-3, flow);
            let bits = |x: &[Position], v: &[Velocity]| -> Vec<u64> {
                (x.iter().map(|p| p.0).chain(v.iter().map(|p| p.0)))
                    .flat_map(|d| d.to_array().map(f64::to_bits))
                    .collect()
            };
            assert_eq!(bits(&xa, &va), bits(&xb, &vb));
            assert_eq!(a.1.to_bits(), b.1.to_bits());
            assert_eq!(a.0.is_finite(), b.0.is_finite());
            assert_eq!(b.0.is_finite(), !bad);
            assert!((a.0 - b.0).length() <= 1e-9 * a.0.length().max(1.0) || bad);
        }
    }
}
