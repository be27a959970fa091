//! The whole simulation step in one place.
//!
//! A step runs these system sets, in this order:
//!
//! 1. [`StepSet::Scaling`] — coarse graining. Particles enter the world already
//!    coarse-grained ([`crate::spawn`]: diameter, density, mass, fluid coupling, drag
//!    factors from the scaling law), so no system runs here per step;
//! 2. [`StepSet::NeighbourSearch`] — rebuild the Verlet neighbour list when needed;
//! 3. [`StepSet::Forces`] — contact forces (particle pairs, walls);
//! 4. [`StepSet::Integration`] — contact kicks, drag and gravity move the particles; the
//!    clock advances;
//! 5. [`StepSet::InletOutlet`] — feeders spawn, outlets drain, the non-finite guard checks;
//! 6. [`StepSet::Recording`] — frames go to the recorders.
//!
//! Each stage module (see [`crate::stages`]) adds its systems to these sets only when the
//! scene declares its effect; [`Plan`] lists what was added, by [`StepSystem`], and
//! `scg run --plan` prints it. Every set starts with a timer mark, so [`StageTimers`] gives
//! the wall time per set.

use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{ScheduleConfigs, SingleThreadedExecutor};
use bevy_ecs::system::ScheduleSystem;

/// The ordered stages of a step.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StepSet {
    /// Coarse graining (done at spawn).
    Scaling,
    /// Neighbour list maintenance.
    NeighbourSearch,
    /// Contact forces.
    Forces,
    /// Drag and motion.
    Integration,
    /// Feeders, outlets and the state guard.
    InletOutlet,
    /// Recorders.
    Recording,
}

impl StepSet {
    /// All sets in execution order (the one place the order is written).
    pub const ORDER: [StepSet; 6] = [
        StepSet::Scaling,
        StepSet::NeighbourSearch,
        StepSet::Forces,
        StepSet::Integration,
        StepSet::InletOutlet,
        StepSet::Recording,
    ];

    /// Number of sets.
    pub const COUNT: usize = Self::ORDER.len();

    /// Short lower-case name for reports.
    pub fn name(self) -> &'static str {
        match self {
            StepSet::Scaling => "scaling",
            StepSet::NeighbourSearch => "neighbour_search",
            StepSet::Forces => "forces",
            StepSet::Integration => "integration",
            StepSet::InletOutlet => "inlet_outlet",
            StepSet::Recording => "recording",
        }
    }

    /// Position in [`StepSet::ORDER`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// The systems a step can run: the typed handle a [`Plan`] is queried with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StepSystem {
    /// Rebuild the Verlet list when needed (contacts).
    MaintainNeighbourList,
    /// Particle–particle contact forces (contacts).
    ParticleContactForces,
    /// Normal wall forces only (walls without friction).
    WallNormalForces,
    /// Normal and tangential wall forces and torques (walls with friction).
    WallContactForces,
    /// Contact forces and torques applied as kicks (contacts).
    ApplyContactKicks,
    /// Bring the snapshots of an unsteady mesh flow around the step's mid time into
    /// memory (`[flow] series`).
    AdvanceFlowSeries,
    /// Write each particle's carrier offset (carrier modifiers).
    ModifyCarrier,
    /// Relax the spin and kick by the rotational lift (`[forces] rubinow_keller`).
    RotationalLift,
    /// No fluid: kick, then the exact drift under gravity.
    IntegrateBallistic,
    /// Stokes drag, exponential scheme, precomputed factors.
    IntegrateStokesExponential,
    /// Reynolds-dependent drag, exponential scheme.
    IntegrateDragExponential,
    /// Any drag law, semi-implicit Euler with sub-steps.
    IntegrateDragExplicit,
    /// Drag through a flow on a CFD mesh (locate, interpolate, move, settle on the mesh).
    IntegrateMeshFlow,
    /// Angular velocity from the wall torques.
    IntegrateRotation,
    /// Advance the step counter.
    AdvanceClock,
    /// Remove drained and lost particles.
    DrainParticles,
    /// Remove particles that entered a collecting zone.
    CollectParticles,
    /// Remove particles that left a mesh flow through an outlet or lost patch.
    MeshBoundary,
    /// Rebound, stick or escape at walls that act as impulses.
    ImpulseWalls,
    /// Spawn fed particles.
    FeedParticles,
    /// Reorder the particle table by mesh cell (mesh flows without contacts).
    SortByCell,
    /// Stop on a non-finite state.
    CheckFiniteState,
    /// Hand a frame to the recorders.
    RecordFrame,
}

impl StepSystem {
    /// The system's name, as `scg run --plan` prints it.
    pub fn name(self) -> &'static str {
        match self {
            StepSystem::MaintainNeighbourList => "maintain_neighbour_list",
            StepSystem::ParticleContactForces => "particle_contact_forces",
            StepSystem::WallNormalForces => "wall_normal_forces",
            StepSystem::WallContactForces => "wall_contact_forces",
            StepSystem::ApplyContactKicks => "apply_contact_kicks",
            StepSystem::AdvanceFlowSeries => "advance_flow_series",
            StepSystem::ModifyCarrier => "modify_carrier",
            StepSystem::RotationalLift => "rotational_lift",
            StepSystem::IntegrateBallistic => "integrate_ballistic",
            StepSystem::IntegrateStokesExponential => "integrate_stokes_exponential",
            StepSystem::IntegrateDragExponential => "integrate_drag_exponential",
            StepSystem::IntegrateDragExplicit => "integrate_drag_explicit",
            StepSystem::IntegrateMeshFlow => "integrate_mesh_flow",
            StepSystem::IntegrateRotation => "integrate_rotation",
            StepSystem::AdvanceClock => "advance_clock",
            StepSystem::DrainParticles => "drain_particles",
            StepSystem::CollectParticles => "collect_particles",
            StepSystem::MeshBoundary => "mesh_boundary",
            StepSystem::ImpulseWalls => "impulse_walls",
            StepSystem::FeedParticles => "feed_particles",
            StepSystem::SortByCell => "sort_by_cell",
            StepSystem::CheckFiniteState => "check_finite_state",
            StepSystem::RecordFrame => "record_frame",
        }
    }
}

impl StepSystem {
    /// The step table: every system with its set, in execution order. The builder places
    /// each system by its row here (whatever order the plugins add them in) and refuses a
    /// system added to another set; `scg run --plan` lists a scene's rows in this order.
    pub const TABLE: [(StepSet, StepSystem); 23] = {
        use StepSet::*;
        use StepSystem::*;
        [
            (NeighbourSearch, MaintainNeighbourList),
            (Forces, ParticleContactForces),
            (Forces, WallNormalForces),
            (Forces, WallContactForces),
            // Contact kicks change the velocities the integrator starts from.
            (Integration, ApplyContactKicks),
            // The snapshots of an unsteady flow the step reads.
            (Integration, AdvanceFlowSeries),
            // The carrier offsets the integrator adds to the fluid velocity.
            (Integration, ModifyCarrier),
            // The rotational lift reads the offsets and kicks before the particles move.
            (Integration, RotationalLift),
            (Integration, IntegrateBallistic),
            (Integration, IntegrateStokesExponential),
            (Integration, IntegrateDragExponential),
            (Integration, IntegrateDragExplicit),
            (Integration, IntegrateMeshFlow),
            (Integration, IntegrateRotation),
            (Integration, AdvanceClock),
            // Departures first (mesh patches, impulse walls, the outlet, collecting
            // zones), then arrivals.
            (InletOutlet, MeshBoundary),
            (InletOutlet, ImpulseWalls),
            (InletOutlet, DrainParticles),
            (InletOutlet, CollectParticles),
            (InletOutlet, FeedParticles),
            // After the feeders: the new particles are sorted in too.
            (InletOutlet, SortByCell),
            (InletOutlet, CheckFiniteState),
            (Recording, RecordFrame),
        ]
    };

    /// This system's row in [`StepSystem::TABLE`] and its set.
    pub fn row(self) -> (usize, StepSet) {
        let i = Self::TABLE
            .iter()
            .position(|r| r.1 == self)
            .expect("every system has a row in StepSystem::TABLE");
        (i, Self::TABLE[i].0)
    }
}

impl std::fmt::Display for StepSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One position inside a [`StepSet`]: the set's timer mark, then its systems in the order
/// of their rows in [`StepSystem::TABLE`].
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Slot {
    /// The timer mark that opens a set.
    Mark(StepSet),
    /// A row of the step table.
    Row(usize),
}

/// One system of the plan.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlannedSystem {
    /// The set it runs in.
    pub set: StepSet,
    /// The effect that added it (`drag:stokes`, `walls`, …).
    pub effect: &'static str,
    /// The system.
    pub system: StepSystem,
}

/// The systems a scene produced, in execution order (resource).
#[derive(Resource, Clone, Debug, Default, PartialEq, Eq)]
pub struct Plan {
    /// Systems in order.
    pub systems: Vec<PlannedSystem>,
    /// Models that act inside other systems, listed under their set: applied once per
    /// particle as it enters (scaling: a slip correction of its response time), or
    /// evaluated in the integration's step (forces: pressure gradient, lift).
    pub notes: Vec<(StepSet, String)>,
}

impl Plan {
    /// True when the plan runs `system`.
    pub fn contains(&self, system: StepSystem) -> bool {
        self.systems.iter().any(|s| s.system == system)
    }

    /// Position of `system` in the execution order, if planned.
    pub fn position(&self, system: StepSystem) -> Option<usize> {
        self.systems.iter().position(|s| s.system == system)
    }

    /// The systems of one set.
    pub fn in_set(&self, set: StepSet) -> impl Iterator<Item = &PlannedSystem> {
        self.systems.iter().filter(move |s| s.set == set)
    }

    /// Human-readable listing, one set per block.
    pub fn render(&self) -> String {
        let mut out = String::new();
        for set in StepSet::ORDER {
            let systems: Vec<_> = self.in_set(set).collect();
            out.push_str(&format!("{}. {}\n", set.index() + 1, set.name()));
            let notes: Vec<_> = self.notes.iter().filter(|n| n.0 == set).collect();
            for (_, n) in &notes {
                out.push_str(&format!("     {n}\n"));
            }
            if systems.is_empty() && notes.is_empty() {
                out.push_str(match set {
                    StepSet::Scaling => "     (at spawn: particles enter coarse-grained)\n",
                    _ => "     (nothing)\n",
                });
            }
            for s in systems {
                out.push_str(&format!("     {:<34} [{}]\n", s.system.name(), s.effect));
            }
        }
        out
    }
}

/// Wall time spent in each [`StepSet`] (resource).
#[derive(Resource, Clone, Debug, Default)]
pub struct StageTimers {
    /// Accumulated time per set, indexed like [`StepSet::ORDER`].
    pub total: [Duration; StepSet::COUNT],
    /// Accumulated time per system, indexed by its row of [`StepSystem::TABLE`] (from the
    /// mark before it to the next mark: the set's own mark is not in any row).
    pub rows: [Duration; StepSystem::TABLE.len()],
    /// Steps timed.
    pub steps: u64,
    open: Option<(usize, Instant)>,
    open_row: Option<(usize, Instant)>,
}

impl StageTimers {
    fn mark(&mut self, set: Option<usize>) {
        let now = Instant::now();
        if let Some((i, t0)) = self.open.take() {
            self.total[i] += now - t0;
        }
        if let Some((r, t0)) = self.open_row.take() {
            self.rows[r] += now - t0;
        }
        match set {
            Some(i) => self.open = Some((i, now)),
            None => self.steps += 1,
        }
    }

    fn mark_row(&mut self, row: usize) {
        let now = Instant::now();
        if let Some((r, t0)) = self.open_row.replace((row, now)) {
            self.rows[r] += now - t0;
        }
    }

    /// Time per system of `plan`, in its order.
    pub fn by_system(&self, plan: &Plan) -> Vec<(PlannedSystem, Duration)> {
        plan.systems
            .iter()
            .map(|s| (s.clone(), self.rows[s.system.row().0]))
            .collect()
    }

    /// Time per set, with the set names.
    pub fn by_set(&self) -> Vec<(StepSet, Duration)> {
        StepSet::ORDER
            .iter()
            .map(|s| (*s, self.total[s.index()]))
            .collect()
    }

    /// Sum over the sets.
    pub fn sum(&self) -> Duration {
        self.total.iter().sum()
    }
}

/// Collects the systems of a scene into a [`Schedule`] in the fixed set order, each set's
/// systems in the order of [`StepSystem::TABLE`].
pub struct StepBuilder {
    schedule: Schedule,
    plan: Plan,
}

impl Default for StepBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl StepBuilder {
    /// A schedule with the sets chained in [`StepSet::ORDER`] and their timer marks in
    /// place.
    pub fn new() -> Self {
        let mut schedule = Schedule::default();
        // One thread runs the systems in a fixed order; the systems themselves use every
        // core through the team (crate::exec). Results do not depend on the thread count.
        schedule.set_executor(SingleThreadedExecutor::new());
        for pair in StepSet::ORDER.windows(2) {
            schedule.configure_sets(pair[1].after(pair[0]));
        }
        for set in StepSet::ORDER {
            let i = set.index();
            schedule.add_systems(
                (move |mut t: ResMut<StageTimers>| t.mark(Some(i)))
                    .in_set(set)
                    .in_set(Slot::Mark(set)),
            );
        }
        let last = StepSet::ORDER[StepSet::COUNT - 1];
        schedule.add_systems((|mut t: ResMut<StageTimers>| t.mark(None)).after(last));
        StepBuilder {
            schedule,
            plan: Plan::default(),
        }
    }

    /// Add `system` (planned as `name`) for `effect`, at its row of
    /// [`StepSystem::TABLE`] in `set`.
    ///
    /// # Panics
    /// When the table puts `name` in another set, or it was added already (a plugin
    /// error, not a scene's).
    pub fn add<M>(
        &mut self,
        set: StepSet,
        effect: &'static str,
        name: StepSystem,
        system: impl IntoScheduleConfigs<ScheduleSystem, M>,
    ) {
        let (row, table_set) = name.row();
        assert_eq!(
            table_set,
            set,
            "{name} belongs to the {} set (StepSystem::TABLE), not {}",
            table_set.name(),
            set.name()
        );
        assert!(!self.plan.contains(name), "{name} was added twice");
        // a timer mark before the system: StageTimers::rows
        let mark = (move |mut t: ResMut<StageTimers>| t.mark_row(row)).into_configs();
        let configs: ScheduleConfigs<ScheduleSystem> = (mark, system.into_configs())
            .chain()
            .in_set(set)
            .in_set(Slot::Row(row));
        self.schedule.add_systems(configs);
        self.plan.systems.push(PlannedSystem {
            set,
            effect,
            system: name,
        });
    }

    /// The plan so far (in the order the systems were added).
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// Finish: the schedule and its plan, systems listed in execution order (the sets in
    /// order, each set's systems by their table rows after its timer mark).
    pub fn build(self) -> (Schedule, Plan) {
        let (mut schedule, mut plan) = (self.schedule, self.plan);
        plan.systems.sort_by_key(|s| s.system.row().0);
        for set in StepSet::ORDER {
            let mut prev = Slot::Mark(set);
            for s in plan.in_set(set) {
                let slot = Slot::Row(s.system.row().0);
                schedule.configure_sets(slot.after(prev));
                prev = slot;
            }
        }
        (schedule, plan)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every system has exactly one row, and the rows run through the sets in order.
    #[test]
    fn the_step_table_is_complete_and_ordered() {
        let rows = StepSystem::TABLE;
        for (i, (_, s)) in rows.iter().enumerate() {
            assert_eq!(s.row().0, i, "{s} has one row");
        }
        assert!(rows.windows(2).all(|w| w[0].0 <= w[1].0), "sets in order");
    }

    /// The plan lists a set's systems by their table rows, whatever order they were added
    /// in; a system added to another set than its row's is refused.
    #[test]
    fn the_builder_orders_by_the_table() {
        let mut b = StepBuilder::new();
        let set = StepSet::Integration;
        b.add(set, "clock", StepSystem::AdvanceClock, || {});
        b.add(set, "motion", StepSystem::IntegrateBallistic, || {});
        b.add(set, "contacts", StepSystem::ApplyContactKicks, || {});
        let (_, plan) = b.build();
        let names: Vec<_> = plan.systems.iter().map(|s| s.system).collect();
        assert_eq!(
            names,
            [
                StepSystem::ApplyContactKicks,
                StepSystem::IntegrateBallistic,
                StepSystem::AdvanceClock
            ]
        );
        let wrong = std::panic::catch_unwind(|| {
            let mut b = StepBuilder::new();
            b.add(StepSet::Forces, "clock", StepSystem::AdvanceClock, || {});
        });
        assert!(wrong.is_err());
    }
}
