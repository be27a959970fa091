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

/// What a frame reads of a particle.
pub(crate) type FrameData = (
    &'static ParticleId,
    &'static GroupId,
    &'static Position,
    &'static Velocity,
    &'static Diameter,
    &'static Density,
    &'static Mass,
    Option<(&'static Eddy, &'static CarrierOffset)>,
);

type FrameQuery<'w, 's> = Query<'w, 's, FrameData>;

/// The frame row of one particle's [`FrameData`].
pub(crate) fn frame_row(
    (id, g, x, v, d, rho, m, turb): bevy_ecs::query::QueryItem<'_, '_, FrameData>,
) -> FrameRow {
    FrameRow {
        id: id.0,
        group: g.0,
        position: x.0.to_array(),
        velocity: v.0.to_array(),
        diameter: d.0,
        density: rho.0,
        mass: m.0,
        fluctuation: turb.map(|(_, u)| u.0.length()),
    }
}

/// One particle as a frame records it (with its mass, for the kinetic energy): what a
/// rank of a decomposed run sends to the rank that writes the recordings.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrameRow {
    /// Particle id.
    pub id: u32,
    /// Group.
    pub group: u32,
    /// Position, m.
    pub position: [f64; 3],
    /// Velocity, m/s.
    pub velocity: [f64; 3],
    /// Diameter as simulated, m.
    pub diameter: f64,
    /// Density as simulated, kg/m³.
    pub density: f64,
    /// Mass as simulated, kg.
    pub mass: f64,
    /// |u′| of the dispersion model's fluctuation, m/s (`None`: no dispersion).
    #[serde(default)]
    pub fluctuation: Option<f64>,
}

/// Build the frame of the current state, particles sorted by id, with the standard stats.
pub fn build_frame(
    clock: &SimClock,
    params: &RecordingParams,
    tally: &Tally,
    q: &FrameQuery,
) -> Frame {
    let rows: Vec<FrameRow> = q.iter().map(frame_row).collect();
    frame_from_rows(clock.step, clock.time(), params, tally, rows)
}

/// The frame of `rows` (any order: they are sorted by id here) at `step` and `time` (s),
/// with the standard stats; `tally` gives the drained and collision counts.
pub fn frame_from_rows(
    step: u64,
    time: f64,
    params: &RecordingParams,
    tally: &Tally,
    mut rows: Vec<FrameRow>,
) -> Frame {
    rows.sort_unstable_by_key(|r| r.id);
    let n = rows.len();
    let mut fr = Frame::with_capacity(step, time, n);
    let turbulent = rows.iter().any(|r| r.fluctuation.is_some());
    if turbulent {
        fr.fluctuation.reserve(n);
    }
    let ng = params.groups.len();
    let mut count = vec![0u64; ng];
    let (mut speed_sum, mut ke) = (0.0, 0.0);
    for r in rows {
        let v = glam::DVec3::from_array(r.velocity);
        fr.id.push(r.id);
        fr.group.push(r.group);
        fr.position.push(r.position);
        fr.velocity.push(r.velocity);
        fr.diameter.push(r.diameter);
        fr.density.push(r.density);
        if turbulent {
            fr.fluctuation.push(r.fluctuation.unwrap_or(0.0));
        }
        if let Some(c) = count.get_mut(r.group as usize) {
            *c += 1;
        }
        speed_sum += v.length();
        ke += 0.5 * r.mass * v.length_squared();
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

/// The rows of a recorded frame, in its order: what [`frame_from_rows`] makes it from
/// again, bit for bit (a particle's simulated mass is
/// [`crate::physics::scaling::sphere_mass`] of its simulated diameter and density, as at
/// spawn).
pub fn rows_of_frame(f: &Frame) -> Vec<FrameRow> {
    (0..f.len())
        .map(|i| FrameRow {
            id: f.id[i],
            group: f.group[i],
            position: f.position[i],
            velocity: f.velocity[i],
            diameter: f.diameter[i],
            density: f.density[i],
            mass: crate::physics::scaling::sphere_mass(f.diameter[i], f.density[i]),
            fluctuation: f.fluctuation.get(i).copied(),
        })
        .collect()
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
