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

/// What the recording system keeps between frames so that building one allocates
/// nothing once the buffers have grown: the masses (for the kinetic energy), the id
/// order and the gather buffers of a table that is not in id order.
#[derive(Default)]
pub struct FrameScratch {
    mass: Vec<f64>,
    order: Vec<u32>,
    slots: Vec<u32>,
    keys: Vec<u64>,
    tmp_u32: Vec<u32>,
    tmp_f64: Vec<f64>,
    tmp_vec: Vec<[f64; 3]>,
}

/// Fill `fr` (its buffers reused) with the frame of the particles of `q` at `step` and
/// `time` (s), sorted by id, with the standard stats; the same frame, bit for bit, as
/// [`frame_from_rows`] makes of the same particles' `frame_row`s.
pub fn fill_frame(
    fr: &mut Frame,
    (step, time): (u64, f64),
    params: &RecordingParams,
    tally: &Tally,
    q: &FrameQuery,
    s: &mut FrameScratch,
) {
    fr.clear();
    fr.step = step;
    fr.time = time;
    s.mass.clear();
    let mut sums = Sums::new(params.groups.len());
    // Whole columns of each storage table at once (a scene's particles are in one). While
    // the rows so far are in id order, the stats are summed in the pass that copies the
    // velocities; after the first row out of order, once the frame is in id order.
    let mut in_order = true;
    let tables = q
        .contiguous_iter()
        .expect("a frame's components are all in table storage");
    for (ids, gs, xs, vs, ds, rhos, ms, turb) in tables {
        let k = fr.id.len();
        fr.id.extend(ids.iter().map(|i| i.0));
        in_order = in_order && fr.id[k.saturating_sub(1)..].is_sorted();
        if in_order {
            fr.velocity.reserve(vs.len());
            for ((v, m), g) in vs.iter().zip(ms).zip(gs) {
                fr.velocity.push(v.0.to_array());
                sums.add(g.0, m.0, v.0);
            }
        } else {
            fr.velocity.extend(vs.iter().map(|v| v.0.to_array()));
        }
        fr.group.extend(gs.iter().map(|g| g.0));
        fr.position.extend(xs.iter().map(|x| x.0.to_array()));
        fr.diameter.extend(ds.iter().map(|d| d.0));
        fr.density.extend(rhos.iter().map(|r| r.0));
        s.mass.extend(ms.iter().map(|m| m.0));
        if let Some((_, us)) = turb {
            // the rows before the first with a fluctuation have none: 0 (as a row's
            // `fluctuation: None` in `frame_from_rows`)
            fr.fluctuation.resize(k, 0.0);
            fr.fluctuation.extend(us.iter().map(|u| u.0.length()));
        }
    }
    if !fr.fluctuation.is_empty() {
        fr.fluctuation.resize(fr.id.len(), 0.0);
    }
    if !in_order {
        id_order(&fr.id, s);
        let FrameScratch {
            order,
            tmp_u32,
            tmp_f64,
            tmp_vec,
            mass,
            ..
        } = s;
        permute(&mut fr.id, order, tmp_u32);
        permute(&mut fr.group, order, tmp_u32);
        permute(&mut fr.position, order, tmp_vec);
        permute(&mut fr.velocity, order, tmp_vec);
        permute(&mut fr.diameter, order, tmp_f64);
        permute(&mut fr.density, order, tmp_f64);
        permute(mass, order, tmp_f64);
        if !fr.fluctuation.is_empty() {
            permute(&mut fr.fluctuation, order, tmp_f64);
        }
        sums = Sums::new(params.groups.len());
        for ((g, v), m) in fr.group.iter().zip(&fr.velocity).zip(mass.iter()) {
            sums.add(*g, *m, glam::DVec3::from_array(*v));
        }
    }
    sums.push(fr, params, tally);
}

/// What a frame's standard stats sum over its particles, in id order.
struct Sums {
    /// Particles per group.
    count: Vec<u64>,
    /// Σ |v|, m/s.
    speed: f64,
    /// Σ m·|v|²/2, J.
    ke: f64,
}

impl Sums {
    fn new(groups: usize) -> Self {
        Sums {
            count: vec![0; groups],
            speed: 0.0,
            ke: 0.0,
        }
    }

    /// Add a particle of group `g`, mass `m` (kg) and velocity `v` (m/s).
    #[inline(always)]
    fn add(&mut self, g: u32, m: f64, v: glam::DVec3) {
        if let Some(c) = self.count.get_mut(g as usize) {
            *c += 1;
        }
        self.speed += v.length();
        self.ke += 0.5 * m * v.length_squared();
    }

    /// The standard stats of `fr` (whose particles were added): counts per group, drained
    /// and collision counts from `tally`, mean speed and kinetic energy.
    fn push(self, fr: &mut Frame, params: &RecordingParams, tally: &Tally) {
        let n = fr.id.len();
        for (i, name) in params.groups.iter().enumerate() {
            fr.stats
                .push((Stat::Count(name).key(), self.count[i] as f64));
            let drained = tally.drained.get(i).copied().unwrap_or(0);
            fr.stats.push((Stat::Drained(name).key(), drained as f64));
            if let Some(c) = tally.collisions.get(i) {
                fr.stats.push((Stat::Collisions(name).key(), *c as f64));
            }
        }
        let mean_speed = if n > 0 { self.speed / n as f64 } else { 0.0 };
        fr.stats.push((Stat::MeanSpeed.key(), mean_speed));
        fr.stats.push((Stat::KineticEnergy.key(), self.ke));
    }
}

/// `s.order`: the rows of `ids` (unique) in increasing id order. Ids spanning a range
/// not much wider than their number are placed in slots (linear time); others sorted.
fn id_order(ids: &[u32], s: &mut FrameScratch) {
    let n = ids.len();
    let (lo, hi) = ids
        .iter()
        .fold((u32::MAX, 0), |(lo, hi), &i| (lo.min(i), hi.max(i)));
    s.order.clear();
    if n > 0 && ((hi - lo) as usize) < 4 * n + 1024 {
        s.slots.clear();
        s.slots.resize((hi - lo) as usize + 1, u32::MAX);
        for (k, &id) in ids.iter().enumerate() {
            s.slots[(id - lo) as usize] = k as u32;
        }
        s.order
            .extend(s.slots.iter().copied().filter(|&k| k != u32::MAX));
        if s.order.len() == n {
            return;
        }
        s.order.clear(); // a repeated id: sort instead
    }
    s.keys.clear();
    s.keys.extend(
        ids.iter()
            .enumerate()
            .map(|(k, &id)| (u64::from(id) << 32) | k as u64),
    );
    s.keys.sort_unstable();
    s.order.extend(s.keys.iter().map(|&k| k as u32));
}

/// Reorder `v` to `v[order[0]], v[order[1]], …` (through `tmp`, which keeps the old buffer).
fn permute<T: Copy>(v: &mut Vec<T>, order: &[u32], tmp: &mut Vec<T>) {
    tmp.clear();
    tmp.extend(order.iter().map(|&k| v[k as usize]));
    std::mem::swap(v, tmp);
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
    let mut sums = Sums::new(params.groups.len());
    for r in rows {
        fr.id.push(r.id);
        fr.group.push(r.group);
        fr.position.push(r.position);
        fr.velocity.push(r.velocity);
        fr.diameter.push(r.diameter);
        fr.density.push(r.density);
        sums.add(r.group, r.mass, glam::DVec3::from_array(r.velocity));
        if turbulent {
            fr.fluctuation.push(r.fluctuation.unwrap_or(0.0));
        }
    }
    sums.push(&mut fr, params, tally);
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

/// Record a frame when the step is a multiple of `every`: filled into the frame the sinks
/// handed back last time ([`Recorders::spare`]) when none of them kept it, so that a run's
/// frames reuse one set of buffers; each sink gets it shared ([`FrameSink::write_shared`]).
///
/// [`FrameSink::write_shared`]: crate::frame::FrameSink::write_shared
pub fn record_frame(
    clock: Res<SimClock>,
    params: Res<RecordingParams>,
    tally: Res<Tally>,
    mut recorders: ResMut<Recorders>,
    q: FrameQuery,
    mut scratch: Local<FrameScratch>,
) {
    if !clock.step.is_multiple_of(params.every)
        || recorders.error.is_some()
        || recorders.sinks.is_empty()
    {
        return;
    }
    let recorders = &mut *recorders;
    // the last frame's buffers, unless a sink still holds it
    let mut frame = recorders
        .spare
        .take()
        .and_then(std::sync::Arc::into_inner)
        .unwrap_or_default();
    fill_frame(
        &mut frame,
        (clock.step, clock.time()),
        &params,
        &tally,
        &q,
        &mut scratch,
    );
    let frame = std::sync::Arc::new(frame);
    for s in recorders.sinks.iter_mut() {
        if let Err(e) = s.write_shared(&frame) {
            recorders.error = Some(e);
            return;
        }
    }
    recorders.spare = Some(frame);
}

#[cfg(test)]
mod tests {
    use bevy_ecs::system::RunSystemOnce;
    use glam::DVec3;

    use super::*;

    /// A world of particles with the ids `ids` (in spawn order), the odd ones with a
    /// dispersion fluctuation when `turbulent`.
    fn world(ids: &[u32], turbulent: bool) -> World {
        let mut w = World::new();
        for &id in ids {
            let f = f64::from(id);
            let e = w
                .spawn((
                    ParticleId(id),
                    GroupId(id % 2),
                    Position(DVec3::new(f, -f, 0.5 * f)),
                    Velocity(DVec3::new(0.1 * f, 1.0, -f)),
                    Diameter(1e-6 * (1.0 + f)),
                    Density(1000.0 + f),
                    Mass(1e-12 * (1.0 + f)),
                ))
                .id();
            if turbulent && id % 2 == 1 {
                w.entity_mut(e)
                    .insert((Eddy::default(), CarrierOffset(DVec3::new(f, 0.0, 1.0))));
            }
        }
        w.insert_resource(SimClock::new(1e-3));
        w.insert_resource(RecordingParams {
            every: 1,
            groups: vec!["even".into(), "odd".into()],
        });
        w.insert_resource(Tally::new(2));
        w
    }

    /// The frame `fill_frame` makes (into `reused`) and the one `frame_from_rows` makes of
    /// the same particles' rows.
    fn both(w: &mut World, reused: Frame) -> (Frame, Frame) {
        w.run_system_once(
            move |params: Res<RecordingParams>, tally: Res<Tally>, q: FrameQuery| {
                let mut fr = reused.clone();
                let mut s = FrameScratch::default();
                fill_frame(&mut fr, (7, 7e-3), &params, &tally, &q, &mut s);
                let rows = q.iter().map(frame_row).collect();
                (fr, frame_from_rows(7, 7e-3, &params, &tally, rows))
            },
        )
        .expect("system runs")
    }

    /// Whatever the table's order (in id order, shuffled, ids spread too widely for the
    /// slots, some particles with a fluctuation and some without) and whatever the
    /// frame held before, the frame filled in place is the rows' frame bit for bit.
    #[test]
    fn a_frame_filled_in_place_is_the_rows_frame() {
        let shuffled = [5u32, 3, 9, 0, 8, 1, 7, 2, 6, 4];
        let wide = [4_000_000_000u32, 3, 70_000, 12, 1_000_000, 0];
        let stale = {
            let mut w = world(&[100, 101], true);
            both(&mut w, Frame::default()).0
        };
        for ids in [&[0u32, 1, 2, 3][..], &shuffled, &wide, &[]] {
            for turbulent in [false, true] {
                for reused in [Frame::default(), stale.clone()] {
                    let mut w = world(ids, turbulent);
                    let (filled, rows) = both(&mut w, reused);
                    assert_eq!(filled, rows, "ids {ids:?}, turbulent {turbulent}");
                    assert!(filled.id.is_sorted());
                    assert_eq!(filled.len(), ids.len());
                    assert_eq!(
                        filled.fluctuation.len(),
                        if turbulent && !ids.is_empty() {
                            ids.len()
                        } else {
                            0
                        }
                    );
                }
            }
        }
    }

    /// The id order by slots and by sorting agree (ids 0…n shuffled; with a far id
    /// added the range is too wide for slots).
    #[test]
    fn id_order_by_slots_and_by_sorting_agree() {
        let mut ids: Vec<u32> = (0..5000).map(|k| (k * 7919) % 5000).collect();
        let mut s = FrameScratch::default();
        id_order(&ids, &mut s);
        let by_slots = s.order.clone();
        let mut sorted: Vec<u32> = by_slots.iter().map(|&k| ids[k as usize]).collect();
        assert_eq!(sorted, (0..5000).collect::<Vec<_>>());
        ids.push(u32::MAX);
        id_order(&ids, &mut s);
        assert_eq!(&s.order[..5000], &by_slots[..]);
        sorted = s.order.iter().map(|&k| ids[k as usize]).collect();
        assert!(sorted.is_sorted());
    }
}
