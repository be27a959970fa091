//! An unsteady mesh flow ([`crate::physics::mesh_flow::series`]): before each step's
//! integration the clock's two snapshots around the step's mid time are in memory, and
//! the one the clock reaches next is read on a background thread.
//!
//! Every snapshot is a pure function of its index (the loader), so which thread read it
//! and when changes nothing: a run is bit-identical whatever the timing. Snapshots once
//! read are kept while they fit in [`keep_bytes`] (1 GiB unless `SCG_SERIES_KEEP_MB`
//! says otherwise), so a cycling window that fits is read once, not once per cycle; past
//! that budget the series streams, two snapshots and the one read ahead at a time.

use std::sync::Arc;
use std::thread::JoinHandle;

use bevy_ecs::prelude::*;

use crate::physics::dispersion::Local;
use crate::physics::mesh_flow::MeshFlow;
use crate::physics::mesh_flow::series::{
    Blend, FlowSeriesSpec, Interval, Snapshot, blend_turbulence,
};
use crate::state::SimClock;
use crate::step::{StepBuilder, StepSet, StepSystem};

/// The snapshots of an unsteady flow in memory (resource).
#[derive(Resource)]
pub struct FlowSeries {
    spec: FlowSeriesSpec,
    /// The pair of the current interval: snapshots `now.a` and `now.b`.
    pair: [(usize, Snapshot); 2],
    now: Interval,
    /// The snapshot being read ahead.
    ahead: Option<(usize, JoinHandle<Result<Snapshot, String>>)>,
    /// Snapshots read so far (including the first, given).
    reads: usize,
    /// Snapshots kept after use (index → snapshot), within `keep_budget` bytes.
    kept: Vec<Option<Snapshot>>,
    /// Bytes of `kept`.
    kept_bytes: usize,
    /// Most bytes `kept` may hold.
    keep_budget: usize,
    /// The last [`FlowSeries::advance`] changed the pair.
    changed: bool,
    /// A snapshot that could not be read: the run stops ([`crate::sim::SimError::Flow`]).
    pub failure: Option<String>,
}

impl FlowSeries {
    /// The series of `spec` whose first snapshot is `first` (the scene's flow).
    pub fn new(spec: FlowSeriesSpec, first: Arc<MeshFlow>) -> Self {
        let first = Snapshot {
            flow: first,
            turbulence: spec.first_turbulence.clone(),
        };
        let second = spec.second.clone();
        let n = spec.clock.len();
        let mut s = FlowSeries {
            spec,
            pair: [(0, first.clone()), (1, second.clone())],
            now: Interval { a: 0, b: 1, w: 0.0 },
            ahead: None,
            reads: 2,
            kept: vec![None; n],
            kept_bytes: 0,
            keep_budget: keep_bytes(),
            changed: false,
            failure: None,
        };
        s.keep(0, &first);
        s.keep(1, &second);
        s
    }

    /// Keep snapshot `k` for later use when it fits in the budget.
    fn keep(&mut self, k: usize, snap: &Snapshot) {
        let bytes = snapshot_bytes(snap);
        if let Some(slot) = self.kept.get_mut(k)
            && slot.is_none()
            && self.kept_bytes + bytes <= self.keep_budget
        {
            *slot = Some(snap.clone());
            self.kept_bytes += bytes;
        }
    }

    /// The clock.
    pub fn clock(&self) -> &crate::physics::mesh_flow::series::SeriesClock {
        &self.spec.clock
    }

    /// The interval of the last [`FlowSeries::advance`].
    pub fn interval(&self) -> Interval {
        self.now
    }

    /// Snapshots read so far.
    pub fn reads(&self) -> usize {
        self.reads
    }

    /// True when the last [`FlowSeries::advance`] made another pair of snapshots current
    /// (what a particle kept of the last pair no longer holds).
    pub fn changed(&self) -> bool {
        self.changed
    }

    /// The carrier of the current interval.
    pub fn blend(&self) -> Blend<'_> {
        Blend {
            a: &self.pair[0].1.flow,
            b: &self.pair[1].1.flow,
            w: self.now.w,
        }
    }

    /// k, ε and ∇σ of mesh cell `cell` at the current weight, when the snapshots carry
    /// turbulence (`[dispersion]` by the CFD's fields).
    #[inline]
    pub fn turbulence(&self, cell: u32) -> Option<Local> {
        match (&self.pair[0].1.turbulence, &self.pair[1].1.turbulence) {
            (Some(a), Some(b)) => Some(blend_turbulence(a.local(cell), b.local(cell), self.now.w)),
            _ => None,
        }
    }

    /// Snapshot `k`: one of the pair, one kept, the one read ahead, or read now.
    fn get(&mut self, k: usize) -> Result<Snapshot, String> {
        if let Some((_, f)) = self.pair.iter().find(|(i, _)| *i == k) {
            return Ok(f.clone());
        }
        if let Some(Some(f)) = self.kept.get(k) {
            return Ok(f.clone());
        }
        let r = if self.ahead.as_ref().is_some_and(|(i, _)| *i == k) {
            let (_, h) = self.ahead.take().expect("checked");
            match h.join() {
                Ok(r) => r,
                Err(_) => Err(format!("reading snapshot {k} panicked")),
            }
        } else {
            self.reads += 1;
            (self.spec.load)(k)
        };
        if let Ok(snap) = &r {
            self.keep(k, snap);
        }
        r
    }

    /// Make the two snapshots around simulation time `t` (s) current, and start reading
    /// the next one.
    pub fn advance(&mut self, t: f64) {
        if self.failure.is_some() {
            return;
        }
        let iv = self.spec.clock.at(t);
        self.changed = (self.pair[0].0, self.pair[1].0) != (iv.a, iv.b);
        if self.changed {
            match (self.get(iv.a), self.get(iv.b)) {
                (Ok(a), Ok(b)) => self.pair = [(iv.a, a), (iv.b, b)],
                (Err(e), _) | (_, Err(e)) => {
                    self.failure = Some(e);
                    return;
                }
            }
        }
        self.now = iv;
        let next = self.spec.clock.after(iv);
        // a read ahead the clock no longer heads for (a restart elsewhere) is dropped
        if self.ahead.as_ref().is_some_and(|(i, _)| Some(*i) != next) {
            self.ahead = None;
        }
        if let Some(k) = next
            && self.ahead.is_none()
            && self.pair.iter().all(|(i, _)| *i != k)
            && self.kept.get(k).is_none_or(Option::is_none)
        {
            let load = Arc::clone(&self.spec.load);
            self.reads += 1;
            self.ahead = Some((k, std::thread::spawn(move || load(k))));
        }
    }
}

/// `SCG_SERIES_KEEP_MB` when it is not set, MB.
const KEEP_MB: usize = 1024;

/// Most bytes of snapshots a series keeps in memory for later use: `SCG_SERIES_KEEP_MB`
/// (MB; 0 keeps none beyond the pair), default `KEEP_MB` (1024) (also when the value is not a
/// whole number: [`keep_bytes_from_env`] is the check that refuses it, the command line's).
pub fn keep_bytes() -> usize {
    keep_bytes_from_env().unwrap_or(KEEP_MB << 20)
}

/// [`keep_bytes`], or an error naming the variable and its value when it is not a whole
/// number of MB.
pub fn keep_bytes_from_env() -> Result<usize, String> {
    match std::env::var("SCG_SERIES_KEEP_MB") {
        Err(_) => Ok(KEEP_MB << 20),
        Ok(v) => v
            .trim()
            .parse::<usize>()
            .map(|mb| mb.saturating_mul(1 << 20))
            .map_err(|_| format!("SCG_SERIES_KEEP_MB = {v:?}: expected a whole number of MB")),
    }
}

/// The bytes of a snapshot of its own (flow values and tables, turbulence per cell).
fn snapshot_bytes(s: &Snapshot) -> usize {
    s.flow.bytes()
        + s.turbulence.as_ref().map_or(0, |t| {
            (t.k.len() + t.epsilon.len()) * size_of::<f64>()
                + t.grad_sigma.len() * size_of::<glam::DVec3>()
        })
}

/// Add the series' system (before the carrier modifiers and the integration).
pub fn plugin(world: &mut World, b: &mut StepBuilder, series: FlowSeries) {
    world.insert_resource(series);
    b.add(
        StepSet::Integration,
        "flow_series",
        StepSystem::AdvanceFlowSeries,
        advance_flow_series,
    );
}

/// Bring the snapshots around the coming step's mid time into memory.
pub fn advance_flow_series(clock: Res<SimClock>, mut s: ResMut<FlowSeries>) {
    s.advance((clock.step as f64 + 0.5) * clock.dt);
}
