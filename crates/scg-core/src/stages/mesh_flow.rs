//! Flows on CFD meshes: the integration system that moves particles through a
//! [`MeshFlow`] and the boundary system that removes those that left it.
//!
//! Each particle carries a [`CellHint`], the cell holding its centre after the last step.
//! A step locates the predicted mid-step position by walking from the hint
//! ([`MeshFlow::velocity`]), interpolates u there, moves the particle with the same drag
//! laws and integrators as the analytic flows ([`crate::stages::motion`]), then settles the
//! end position on the mesh ([`land`]): inside, the hint becomes its cell; through a patch
//! the patch's [`PatchInteraction`] decides: a rebound reflects it back (restitution and
//! Coulomb friction), a stick or an escape marks it ([`hint::stuck`], [`hint::escaped`]).
//! A particle found in no cell when first located (spawned outside the mesh) is lost
//! ([`hint::LOST`]). The boundary system ([`mesh_boundary`], inlet/outlet stage) removes
//! the marked particles in id order and counts them per group and patch ([`PatchLog`]):
//! escaped through an outlet patch as drained (`Tally::drained`, `OutletLog::drained`),
//! through other patches or lost as `OutletLog::lost`, stuck ones in [`PatchLog::stuck`].

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use bevy_ecs::prelude::*;
use glam::DVec3;

use super::carrier::{CarrierModifier, DisperseStep, DispersionInMove};
use super::erosion::{ErosionLog, Impact};
use super::flow_series::FlowSeries;
use super::outlet::{OutletLog, OutletPart, remove_departed};
use super::table::{bypass, columns_mut};
use crate::checkpoint::records::{Checkpoint, Part, Persist, Persistence};
use crate::components::*;
use crate::exec::par::for_each_piece_heavy;
use crate::physics::carrier::{Body, Carrier, Place, Scheme, WithOffset, advance, start_reynolds};
use crate::physics::drag_factors::{BLOCK, DragBlock};
use crate::physics::flow::Fluid;
use crate::physics::mesh_flow::series::FlowSeriesSpec;
use crate::physics::mesh_flow::{MeshFlow, PatchInteraction, PatchRole, hint, land};
use crate::state::{Health, Motion, SimClock, StepDisplacement, Tally};
use crate::step::{StepBuilder, StepSet, StepSystem};

mod sort;
mod start;
pub(crate) use sort::add_sort;
pub use sort::{SORT_EVERY, sort_by_cell};
use start::{disperse_row, keeps_start, kept_start};

/// A mesh flow as a scene declares it.
#[derive(Clone, Debug)]
pub struct MeshFlowSpec {
    /// The flow (shared by the simulations built from one scene).
    pub flow: Arc<MeshFlow>,
    /// What a particle reaching each patch does (one per patch of the mesh, in its
    /// order; a patch past the list escapes).
    pub interactions: Vec<PatchInteraction>,
    /// Steps between reorderings of the particle table by mesh cell ([`sort_by_cell`]);
    /// 0: never.
    pub sort_every: u64,
    /// An unsteady flow: `flow` is its first snapshot, the others come from here
    /// ([`super::flow_series`]).
    pub series: Option<FlowSeriesSpec>,
}

/// The mesh flow of a simulation (resource).
#[derive(Resource, Debug)]
pub struct MeshFlowState {
    /// The flow and its walls.
    pub spec: MeshFlowSpec,
    /// Particles marked drained or lost by the last integration (the boundary system
    /// skips its scan when none was).
    departures: AtomicU64,
}

impl MeshFlowState {
    /// The state for `spec`.
    pub fn new(spec: MeshFlowSpec) -> Self {
        MeshFlowState {
            spec,
            departures: AtomicU64::new(0),
        }
    }
}

/// The patch log's part of a checkpoint.
struct PatchesPart;

impl Persist for PatchesPart {
    fn part(&self) -> Option<Part> {
        Some(Part::Patches)
    }

    fn save(&self, world: &World, c: &mut Checkpoint) {
        let l = world.resource::<PatchLog>();
        c.patches = Some([l.escaped.clone(), l.stuck.clone()]);
    }

    fn restore(&self, world: &mut World, c: &Checkpoint) -> Result<(), String> {
        let mut log = world.resource_mut::<PatchLog>();
        match &c.patches {
            Some([e, s]) if e.len() == log.escaped.len() => {
                log.escaped.clone_from(e);
                log.stuck.clone_from(s);
                Ok(())
            }
            _ => Err(Part::Patches.mismatch()),
        }
    }
}

/// Add the mesh-flow integration and boundary systems and their resources.
pub fn plugin(world: &mut World, b: &mut StepBuilder, spec: MeshFlowSpec, groups: usize) {
    // a dispersion model the move runs (the carrier plugin's `fuse`): named beside it
    let effect = match world.get_resource::<CarrierModifier>() {
        Some(m) if world.contains_resource::<DispersionInMove>() => m.in_move_name(),
        _ => "mesh_flow",
    };
    add_integration(b, effect);
    if let Some(series) = &spec.series {
        let s = super::flow_series::FlowSeries::new(series.clone(), Arc::clone(&spec.flow));
        super::flow_series::plugin(world, b, s);
    }
    world.insert_resource(PatchLog::new(spec.flow.mesh().patches.len(), groups));
    Persistence::register(world, PatchesPart);
    Persistence::register(world, OutletPart);
    world.insert_resource(MeshFlowState::new(spec));
    if !world.contains_resource::<OutletLog>() {
        world.insert_resource(OutletLog {
            drained: vec![Vec::new(); groups],
            lost: vec![Vec::new(); groups],
        });
    }
    b.add(
        StepSet::InletOutlet,
        "mesh_flow",
        StepSystem::MeshBoundary,
        mesh_boundary,
    );
}

/// Add the integration system of a mesh flow.
fn add_integration(b: &mut StepBuilder, effect: &'static str) {
    b.add(
        StepSet::Integration,
        effect,
        StepSystem::IntegrateMeshFlow,
        integrate_mesh_flow,
    );
}

type MeshMoveQuery<'w, 's> = Query<
    'w,
    's,
    (
        &'static mut Position,
        &'static mut Velocity,
        (&'static StokesFactors, &'static FluidCoupling),
        &'static Mass,
        Option<&'static Force>,
        Option<&'static BodyAcceleration>,
        (
            &'static mut CellHint,
            &'static mut TetHint,
            &'static mut FlowAtCentre,
        ),
        (
            Option<&'static mut CarrierOffset>,
            Option<&'static mut Eddy>,
        ),
        (&'static CoarseGrain, &'static ParticleId),
    ),
>;

/// What the mesh integration reads besides the particles.
#[derive(bevy_ecs::system::SystemParam)]
pub struct MeshInputs<'w> {
    clock: Res<'w, SimClock>,
    motion: Res<'w, Motion>,
    fluid: Option<Res<'w, Fluid>>,
    health: Res<'w, Health>,
    disp: Option<Res<'w, StepDisplacement>>,
    state: Res<'w, MeshFlowState>,
    carrier: Option<Res<'w, CarrierModifier>>,
    fused: Option<Res<'w, DispersionInMove>>,
    erosion: Option<ResMut<'w, ErosionLog>>,
    series: Option<Res<'w, FlowSeries>>,
}

/// Move every particle through the mesh flow (see the module documentation): the one
/// per-particle step of every scheme ([`advance`]) with the mesh flow as the carrier (plus
/// each particle's [`CarrierOffset`] when the scene has a carrier modifier), then the
/// landing on the mesh ([`land`]).
pub fn integrate_mesh_flow(mut d: MeshInputs, mut q: MeshMoveQuery) {
    let disp = d.disp.as_deref();
    let departures = &d.state.departures;
    departures.store(0, Ordering::Relaxed);
    let Some((xs, vs, drag, ms, fs, gs, (hs, ts, us), (offs, eddies), (cgs, ids))) =
        columns_mut(&mut q)
    else {
        if let Some(dd) = disp {
            dd.mark_reported();
        }
        return;
    };
    let columns = (
        bypass(xs),
        bypass(vs),
        drag,
        ms,
        fs,
        gs,
        (bypass(hs), bypass(ts), bypass(us)),
        ((offs.map(bypass), eddies.map(bypass)), (cgs, ids)),
    );
    // an unsteady flow: the step's two snapshots (one mesh: either locates)
    let blend = d.series.as_deref().map(FlowSeries::blend);
    let flow: &MeshFlow = blend.map_or(&*d.state.spec.flow, |b| b.a);
    let sink = d.erosion.as_ref().map(|_| Mutex::new(Vec::new()));
    let scheme = Scheme {
        dt: d.clock.dt,
        law: d.motion.drag,
        integrator: d.motion.integrator,
        fluid: d.fluid.as_deref().copied().unwrap_or(Scheme::NO_FLUID),
        forces: d.motion.forces,
    };
    let step = MeshStep {
        scheme,
        flow,
        later: blend.map(|b| (b.b, b.w)),
        // a new pair of snapshots: what the last landing kept is of the old one
        stale: d.series.as_deref().is_some_and(FlowSeries::changed),
        models: &d.state.spec.interactions,
        n_cells: flow.mesh().n_cells as u32,
        health: &d.health,
        erosion: d.erosion.as_deref().zip(sink.as_ref()),
        disperse: d
            .carrier
            .as_deref()
            .and_then(CarrierModifier::dispersion)
            .filter(|_| d.fused.is_some())
            .map(|m| DisperseStep::new(m, &d.clock, d.series.as_deref())),
    };
    // The schemes that never read the start's fluid velocity run a loop without it
    // (unless the dispersion model reads it). An unsteady flow keeps both snapshots'
    // values and blends them at the step's weight.
    let keep_start = keeps_start(&d.motion, d.carrier.as_deref());
    for_each_piece_heavy(columns, |piece| {
        let (d2max, gone) = match blend {
            None => step.advance_in(piece, keep_start, flow),
            Some(b) => step.advance_in(piece, keep_start, b),
        };
        if gone > 0 {
            departures.fetch_add(gone, Ordering::Relaxed);
        }
        if let Some(dd) = disp {
            dd.record(d2max);
        }
    });
    if let Some(dd) = disp {
        dd.mark_reported();
    }
    // (`step` borrows the log: its last use is above)
    if let (Some(log), Some(sink)) = (d.erosion.as_deref_mut(), sink) {
        log.add(sink.into_inner().unwrap_or_else(|e| e.into_inner()));
    }
}

/// A piece of the particle table as the mesh integration reads it.
type MeshPiece<'a> = (
    &'a mut [Position],
    &'a mut [Velocity],
    (&'a [StokesFactors], &'a [FluidCoupling]),
    &'a [Mass],
    Option<&'a [Force]>,
    Option<&'a [BodyAcceleration]>,
    (
        &'a mut [CellHint],
        &'a mut [TetHint],
        &'a mut [FlowAtCentre],
    ),
    (
        (Option<&'a mut [CarrierOffset]>, Option<&'a mut [Eddy]>),
        (&'a [CoarseGrain], &'a [ParticleId]),
    ),
);

/// One step of the mesh integration: what every particle's step reads besides its own
/// state.
struct MeshStep<'a> {
    scheme: Scheme,
    flow: &'a MeshFlow,
    /// An unsteady flow's later snapshot (`flow` the earlier) and its weight: its values
    /// are loaded ahead too, and kept at each landing beside the earlier one's.
    later: Option<(&'a MeshFlow, f64)>,
    /// The values kept at the last landings are of another pair of snapshots.
    stale: bool,
    models: &'a [PatchInteraction],
    n_cells: u32,
    health: &'a Health,
    /// With `[erosion]`: the log (which patches) and where the step's impacts go.
    erosion: Option<(&'a ErosionLog, &'a Mutex<Vec<Impact>>)>,
    /// The dispersion the move runs, particle by particle before each moves
    /// ([`DispersionInMove`]).
    disperse: Option<DisperseStep<'a>>,
}

impl MeshStep<'_> {
    /// [`MeshStep::advance`] in `carrier`, with each particle's offset when the piece has
    /// them.
    #[inline(always)]
    fn advance_in<C: Carrier + Copy>(
        &self,
        piece: MeshPiece,
        keep_start: bool,
        carrier: C,
    ) -> (f64, u64) {
        let with = |du| WithOffset { inner: carrier, du };
        match (keep_start, piece.7.0.0.is_some()) {
            (true, false) => self.advance::<true, _, _>(piece, carrier, |_| carrier),
            (false, false) => self.advance::<false, _, _>(piece, carrier, |_| carrier),
            (true, true) => self.advance::<true, _, _>(piece, carrier, with),
            (false, true) => self.advance::<false, _, _>(piece, carrier, with),
        }
    }

    /// Advance the particles of a piece in the carrier `carrier(du)` gives a row with offset
    /// `du` (`base` without one: the mean flow a fused dispersion reads); the largest
    /// squared displacement and the number of particles that left the mesh.
    /// `KEEP`: the scheme reads the fluid velocity at the start of the step
    /// ([`Scheme::reads_start`]), so it is read from and written to [`FlowAtCentre`];
    /// otherwise that column is left alone. (With an offset, the value kept is the mean
    /// flow's and the offset is added to it.)
    #[inline(always)]
    fn advance<const KEEP: bool, B: Carrier, C: Carrier>(
        &self,
        piece: MeshPiece,
        base: B,
        carrier: impl Fn(DVec3) -> C,
    ) -> (f64, u64) {
        let (xs, vs, (sfs, fcs), ms, fs, gs, (hs, ts, us), ((mut offs, mut eddies), (cgs, ids))) =
            piece;
        let MeshStep {
            scheme,
            flow,
            later,
            stale,
            models,
            n_cells,
            health,
            erosion,
            disperse,
        } = *self;
        let mut impacts = Vec::new();
        let mut d2max = 0.0_f64;
        let mut gone = 0u64;
        // A Reynolds-dependent exponential step whose start velocity is kept: its drag
        // factors are computed a block of particles at a time, in lanes ([`DragBlock`]).
        let lanes_law = if KEEP { scheme.reynolds_law() } else { None };
        let mut block = DragBlock::default();
        // the block's start velocities, found once for the factors and the steps
        let mut starts = [None::<DVec3>; BLOCK];
        for i in 0..xs.len() {
            let j = i % BLOCK;
            if j == 0
                && let Some(law) = lanes_law
            {
                let n = BLOCK.min(xs.len() - i);
                block.fill(law, scheme.dt, n, |j| {
                    let i = i + j;
                    disperse_row(
                        disperse,
                        &base,
                        later.is_some(),
                        i,
                        (xs, vs, hs, us, ids),
                        (&mut offs, &mut eddies),
                    );
                    let body = Body {
                        x: xs[i].0,
                        v: vs[i].0,
                        m: ms[i].0,
                        force: fs.map(|f| f[i].0),
                        a: DVec3::ZERO,
                        fc: &fcs[i],
                        sf: &sfs[i],
                    };
                    let u0 = kept_start(
                        &us[i],
                        body.x,
                        later,
                        stale,
                        offs.as_deref().map(|o| o[i].0),
                    );
                    starts[j] = u0;
                    (
                        fcs[i].tau,
                        u0.and_then(|u0| start_reynolds(&scheme, &body, u0)),
                    )
                });
            }
            // Memory latency dominates on large meshes: start loading a later particle's
            // records now (its cell 16 ahead; 8 ahead its tetrahedron when hinted, else
            // the cell's faces; without a hint the tetrahedron holding it 4 ahead, with one
            // the later snapshot's values of it).
            if let Some(h) = hs.get(i + 16) {
                flow.prefetch(h.0, false);
            }
            if let (Some(h), Some(t)) = (hs.get(i + 8), ts.get(i + 8)) {
                if !flow.prefetch_tet(t.0) {
                    flow.prefetch(h.0, true);
                }
                if let Some((b, _)) = later
                    && !b.prefetch_tet(t.0)
                {
                    b.prefetch(h.0, true);
                }
            }
            if let (Some(h), Some(t)) = (hs.get(i + 4), ts.get(i + 4)) {
                if t.0 == scg_mesh::NO_TET {
                    flow.prefetch_at(h.0, xs[i + 4].0);
                } else if let Some((b, _)) = later {
                    b.prefetch_tet_values(t.0);
                }
            }
            if lanes_law.is_none() {
                disperse_row(
                    disperse,
                    &base,
                    later.is_some(),
                    i,
                    (xs, vs, hs, us, ids),
                    (&mut offs, &mut eddies),
                );
            }
            let x0 = xs[i].0;
            let mut h0 = Place {
                cell: hs[i].0,
                tet: ts[i].0,
            };
            if h0.cell >= n_cells {
                match flow.find_cell(x0) {
                    Some(c) => h0 = Place::cell(c),
                    None => {
                        hs[i].0 = hint::LOST;
                        gone += 1;
                        continue;
                    }
                }
            }
            let body = Body {
                x: x0,
                v: vs[i].0,
                m: ms[i].0,
                force: fs.map(|f| f[i].0),
                a: gs.map_or(DVec3::ZERO, |g| g[i].0),
                fc: &fcs[i],
                sf: &sfs[i],
            };
            // The fluid velocity at the start, from the last landing when it found it.
            let start = match (KEEP, lanes_law) {
                (true, Some(_)) => starts[j],
                (true, None) => {
                    kept_start(&us[i], x0, later, stale, offs.as_deref().map(|o| o[i].0))
                }
                (false, _) => None,
            };
            let drag = lanes_law.and_then(|_| block.factors(j));
            let du = offs.as_deref().map_or(DVec3::ZERO, |o| o[i].0);
            let (x1, v1, h_end) = advance(&scheme, &carrier(du), &body, h0, start, drag);
            if !(x1 + v1).element_sum().is_finite() {
                health.raise();
                xs[i].0 = x1;
                vs[i].0 = v1;
                if KEEP {
                    us[i] = FlowAtCentre::UNKNOWN;
                }
                continue;
            }
            let l = land(flow, x0, h0.cell, h_end, x1, v1, models);
            if let (Some(w), Some((log, _))) = (&l.impact, erosion)
                && log.wants(flow.patch_of(w.face))
            {
                impacts.push(super::erosion::impact(w, &cgs[i], ids[i].0));
            }
            if l.hint >= n_cells {
                gone += 1;
            }
            let d2 = (l.x - x0).length_squared();
            if d2 > d2max {
                d2max = d2;
            }
            xs[i].0 = l.x;
            vs[i].0 = l.v;
            hs[i].0 = l.hint;
            ts[i].0 = l.tet;
            if KEEP {
                us[i] = match l.u {
                    Some(u) => FlowAtCentre {
                        at: l.x,
                        u,
                        // the later snapshot at the same place, as the blend reads it
                        later: later.map_or(DVec3::NAN, |(b, _)| {
                            let here = Place {
                                cell: l.hint,
                                tet: l.tet,
                            };
                            b.velocity_at(here, l.x).0
                        }),
                    },
                    None => FlowAtCentre::UNKNOWN,
                };
            }
        }
        if let Some((_, sink)) = erosion
            && !impacts.is_empty()
        {
            sink.lock()
                .unwrap_or_else(|e| e.into_inner())
                .extend(impacts);
        }
        (d2max, gone)
    }
}

/// Particles that left through each patch, per group (resource of a mesh flow):
/// `escaped[patch][group]` and `stuck[patch][group]`, counts of simulated particles.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct PatchLog {
    /// Escaped through the patch (an outlet drains, an inlet or other patch loses).
    pub escaped: Vec<Vec<u64>>,
    /// Stuck on the patch (a `stick` patch).
    pub stuck: Vec<Vec<u64>>,
}

impl PatchLog {
    /// Zero counts for `patches` patches and `groups` groups.
    pub fn new(patches: usize, groups: usize) -> Self {
        PatchLog {
            escaped: vec![vec![0; groups]; patches],
            stuck: vec![vec![0; groups]; patches],
        }
    }

    fn add(v: &mut [Vec<u64>], patch: u32, group: u32) {
        if let Some(c) = v
            .get_mut(patch as usize)
            .and_then(|g| g.get_mut(group as usize))
        {
            *c += 1;
        }
    }
}

/// Remove the particles the integration marked as departed, in id order (so the log is
/// deterministic), counting them per group and per patch: escaped through an outlet patch
/// as drained (`Tally::drained`, `OutletLog::drained`), escaped through any other patch or
/// lost outside the mesh as lost (`OutletLog::lost`), stuck on a patch in
/// [`PatchLog::stuck`] alone.
pub fn mesh_boundary(
    mut commands: Commands,
    clock: Res<SimClock>,
    state: Res<MeshFlowState>,
    mut log: ResMut<OutletLog>,
    mut tally: ResMut<Tally>,
    mut patches: ResMut<PatchLog>,
    q: Query<(Entity, &ParticleId, &GroupId, &CellHint)>,
) {
    use hint::Departure;
    if state.departures.swap(0, Ordering::Relaxed) == 0 {
        return;
    }
    let mut gone: Vec<(u32, u32, Entity, Departure)> = q
        .iter()
        .filter_map(|(e, id, g, h)| hint::departure(h.0).map(|d| (id.0, g.0, e, d)))
        .collect();
    gone.sort_unstable_by_key(|g| g.0);
    let flow = &state.spec.flow;
    let mut removed = Vec::with_capacity(gone.len());
    for (id, g, e, d) in gone {
        match d {
            Departure::Stuck(p) => {
                PatchLog::add(&mut patches.stuck, p, g);
                commands.entity(e).despawn();
            }
            Departure::Escaped(p) => {
                PatchLog::add(&mut patches.escaped, p, g);
                removed.push((id, g, e, flow.role(p) == PatchRole::Outlet));
            }
            Departure::Lost => removed.push((id, g, e, false)),
        }
    }
    remove_departed(&mut commands, &mut log, &mut tally, clock.time(), removed);
}
