//! Recording stage: every `every` steps, a [`Frame`] of all particles goes to the
//! recorders ([`Recorders`]).

use bevy_ecs::prelude::*;

use crate::components::*;
use crate::frame::{Frame, Recorders};
use crate::state::{SimClock, Tally};
use crate::stats::Stat;
use crate::step::{StepBuilder, StepSet, StepSystem};

/// Recording parameters (resource).
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct RecordingParams {
    /// Steps between frames (≥ 1).
    pub every: u64,
    /// Group names, indexed by [`GroupId`].
    pub groups: Vec<String>,
}

/// Add the recording system.
pub fn plugin(b: &mut StepBuilder) {
    b.add(
        StepSet::Recording,
        "recording",
        StepSystem::RecordFrame,
        record_frame,
    );
}

type FrameQuery<'w, 's> = Query<
    'w,
    's,
    (
        &'static ParticleId,
        &'static GroupId,
        &'static Position,
        &'static Velocity,
        &'static Diameter,
        &'static Density,
        &'static Mass,
    ),
>;

/// Build the frame of the current state, particles sorted by id, with the standard stats.
pub fn build_frame(
    clock: &SimClock,
    params: &RecordingParams,
    tally: &Tally,
    q: &FrameQuery,
) -> Frame {
    let mut rows: Vec<_> = q.iter().collect();
    rows.sort_unstable_by_key(|r| r.0.0);
    let n = rows.len();
    let mut fr = Frame::with_capacity(clock.step, clock.time(), n);
    let ng = params.groups.len();
    let mut count = vec![0u64; ng];
    let (mut speed_sum, mut ke) = (0.0, 0.0);
    for (id, g, x, v, d, rho, m) in rows {
        fr.id.push(id.0);
        fr.group.push(g.0);
        fr.position.push(x.0.to_array());
        fr.velocity.push(v.0.to_array());
        fr.diameter.push(d.0);
        fr.density.push(rho.0);
        if let Some(c) = count.get_mut(g.0 as usize) {
            *c += 1;
        }
        speed_sum += v.0.length();
        ke += 0.5 * m.0 * v.0.length_squared();
    }
    for (i, name) in params.groups.iter().enumerate() {
        fr.stats.push((Stat::Count(name).key(), count[i] as f64));
        let drained = tally.drained.get(i).copied().unwrap_or(0);
        fr.stats.push((Stat::Drained(name).key(), drained as f64));
        if let Some(c) = tally.collisions.get(i) {
            fr.stats.push((Stat::Collisions(name).key(), *c as f64));
        }
    }
    let mean_speed = if n > 0 { speed_sum / n as f64 } else { 0.0 };
    fr.stats.push((Stat::MeanSpeed.key(), mean_speed));
    fr.stats.push((Stat::KineticEnergy.key(), ke));
    fr
}

/// Record a frame when the step is a multiple of `every`.
pub fn record_frame(
    clock: Res<SimClock>,
    params: Res<RecordingParams>,
    tally: Res<Tally>,
    mut recorders: ResMut<Recorders>,
    q: FrameQuery,
) {
    if !clock.step.is_multiple_of(params.every)
        || recorders.error.is_some()
        || recorders.sinks.is_empty()
    {
        return;
    }
    let frame = build_frame(&clock, &params, &tally, &q);
    let recorders = &mut *recorders;
    for s in recorders.sinks.iter_mut() {
        if let Err(e) = s.write_frame(&frame) {
            recorders.error = Some(e);
            return;
        }
    }
}
