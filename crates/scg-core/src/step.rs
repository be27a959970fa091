//! The whole simulation step in one place.
//!
//! A step runs these system sets, in this order:
//!
//! 1. [`StepSet::Scaling`] — coarse-grain newly spawned particles (diameter, density,
//!    mass, drag factors);
//! 2. [`StepSet::NeighbourSearch`] — rebuild the Verlet neighbour list when needed;
//! 3. [`StepSet::Forces`] — clear and accumulate contact forces (particles, walls);
//! 4. [`StepSet::Integration`] — drag + other forces move the particles; the clock advances;
//! 5. [`StepSet::InletOutlet`] — feeders spawn, outlets drain, the non-finite guard checks;
//! 6. [`StepSet::Recording`] — frames go to the recorders.
//!
//! Each effect (see [`crate::effects`]) adds its systems to these sets only when the
//! scene declares it; [`Plan`] lists what was added and `scg run --plan` prints it.
//! Every set starts with a timer mark, so [`StageTimers`] gives the wall time per set.

use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::{ScheduleConfigs, SingleThreadedExecutor};
use bevy_ecs::system::ScheduleSystem;

/// The ordered stages of a step.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StepSet {
    /// Coarse graining of new particles.
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
    /// All sets in execution order.
    pub const ORDER: [StepSet; 6] = [
        StepSet::Scaling,
        StepSet::NeighbourSearch,
        StepSet::Forces,
        StepSet::Integration,
        StepSet::InletOutlet,
        StepSet::Recording,
    ];

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

    fn index(self) -> usize {
        self as usize
    }
}

/// One position inside a [`StepSet`]: systems added to the same set run in the order they
/// were added (slot 0 is the set's timer mark).
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Slot(StepSet, usize);

/// One system of the plan.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlannedSystem {
    /// The set it runs in.
    pub set: StepSet,
    /// The effect that added it.
    pub effect: &'static str,
    /// The system's name.
    pub system: &'static str,
}

/// The systems a scene produced, in execution order (resource).
#[derive(Resource, Clone, Debug, Default, PartialEq, Eq)]
pub struct Plan {
    /// Systems in order.
    pub systems: Vec<PlannedSystem>,
}

impl Plan {
    /// True when any system of the plan has this name.
    pub fn contains(&self, system: &str) -> bool {
        self.systems.iter().any(|s| s.system == system)
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
            if systems.is_empty() {
                out.push_str("     (nothing)\n");
            }
            for s in systems {
                out.push_str(&format!("     {:<34} [{}]\n", s.system, s.effect));
            }
        }
        out
    }
}

/// Wall time spent in each [`StepSet`] (resource).
#[derive(Resource, Clone, Debug, Default)]
pub struct StageTimers {
    /// Accumulated time per set, indexed like [`StepSet::ORDER`].
    pub total: [Duration; 6],
    /// Steps timed.
    pub steps: u64,
    open: Option<(usize, Instant)>,
}

impl StageTimers {
    fn mark(&mut self, set: Option<usize>) {
        let now = Instant::now();
        if let Some((i, t0)) = self.open.take() {
            self.total[i] += now - t0;
        }
        match set {
            Some(i) => self.open = Some((i, now)),
            None => self.steps += 1,
        }
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

fn timer_mark<const I: usize>(mut timers: ResMut<StageTimers>) {
    timers.mark(Some(I));
}

fn timer_end(mut timers: ResMut<StageTimers>) {
    timers.mark(None);
}

/// Collects the systems of a scene into a [`Schedule`] in the fixed set order.
pub struct StepBuilder {
    schedule: Schedule,
    plan: Plan,
    next_slot: [usize; 6],
}

impl Default for StepBuilder {
    fn default() -> Self {
        Self::new()
    }
}

impl StepBuilder {
    /// A schedule with the six sets chained and their timer marks in place.
    pub fn new() -> Self {
        let mut schedule = Schedule::default();
        // One thread runs the systems in a fixed order; the systems themselves use both
        // cores through parallel queries. This keeps results independent of thread count.
        schedule.set_executor(SingleThreadedExecutor::new());
        schedule.configure_sets(
            (
                StepSet::Scaling,
                StepSet::NeighbourSearch,
                StepSet::Forces,
                StepSet::Integration,
                StepSet::InletOutlet,
                StepSet::Recording,
            )
                .chain(),
        );
        let mut b = StepBuilder {
            schedule,
            plan: Plan::default(),
            next_slot: [0; 6],
        };
        b.add_internal(StepSet::Scaling, timer_mark::<0>);
        b.add_internal(StepSet::NeighbourSearch, timer_mark::<1>);
        b.add_internal(StepSet::Forces, timer_mark::<2>);
        b.add_internal(StepSet::Integration, timer_mark::<3>);
        b.add_internal(StepSet::InletOutlet, timer_mark::<4>);
        b.add_internal(StepSet::Recording, timer_mark::<5>);
        b.schedule.add_systems(timer_end.after(StepSet::Recording));
        b
    }

    fn add_internal<M>(
        &mut self,
        set: StepSet,
        system: impl IntoScheduleConfigs<ScheduleSystem, M>,
    ) {
        let i = set.index();
        let slot = self.next_slot[i];
        self.next_slot[i] += 1;
        let configs: ScheduleConfigs<ScheduleSystem> =
            system.into_configs().in_set(set).in_set(Slot(set, slot));
        self.schedule.add_systems(configs);
        if slot > 0 {
            self.schedule
                .configure_sets(Slot(set, slot).after(Slot(set, slot - 1)));
        }
    }

    /// Add `system` (named `name` in the plan) for `effect` at the end of `set`.
    pub fn add<M>(
        &mut self,
        set: StepSet,
        effect: &'static str,
        name: &'static str,
        system: impl IntoScheduleConfigs<ScheduleSystem, M>,
    ) {
        self.add_internal(set, system);
        self.plan.systems.push(PlannedSystem {
            set,
            effect,
            system: name,
        });
    }

    /// The plan so far.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// Finish: the schedule and its plan, systems listed in execution order.
    pub fn build(self) -> (Schedule, Plan) {
        let mut plan = self.plan;
        // Stable sort by set keeps the insertion order inside a set.
        plan.systems.sort_by_key(|s| s.set);
        (self.schedule, plan)
    }
}
