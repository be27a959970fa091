//! Running one variant of the cyclone study: the simulation stepped with every particle's
//! feed and escape tracked by id (residence times exact to one step), timed.

use std::path::Path;
use std::time::Instant;

use glam::DVec3;
use scg_core::components::{GroupId, ParticleId};
use scg_core::sim::Simulation;
use scg_core::stages::collect::CollectLog;
use scg_core::stages::outlet::OutletLog;
use scg_core::state::Tally;
use scg_scene::Scene;

use super::grade::ClassGrade;

/// Follows particles by id from one step to the next: when each was first seen (fed) and,
/// paired with the outlet log, when the escaped ones left.
///
/// Each step, every present particle is shown to [`Tracker::observe`] with the outlet log.
/// A particle seen for the first time was fed that step; one seen before and absent now
/// left that step. The log says how many of each group escaped and how many were lost in
/// the step, and the collect log which ids were collected; when a group's other departures
/// are only escapes (or only losses) the departed ids are unambiguous, else (escapes and
/// losses of one group in the same step, or counts that do not match) their residence times
/// are left out and counted in `unmatched`.
#[derive(Clone, Debug, Default)]
pub struct Tracker {
    fed_at: Vec<f64>,
    group: Vec<u32>,
    stamp: Vec<u64>,
    alive: Vec<u32>,
    epoch: u64,
    drained_seen: Vec<usize>,
    lost_seen: Vec<usize>,
    /// Feed-to-escape times per group, s, in order of escape.
    pub residence: Vec<Vec<f64>>,
    /// Departed particles whose escape could not be told from a loss.
    pub unmatched: u64,
}

impl Tracker {
    /// A tracker for `groups` groups.
    pub fn new(groups: usize) -> Self {
        Tracker {
            drained_seen: vec![0; groups],
            lost_seen: vec![0; groups],
            residence: vec![Vec::new(); groups],
            ..Default::default()
        }
    }

    /// The particles `present` (id, group) after a step ending at time `t`, the outlet
    /// log then and the ids collected in the step (`&[]` without collecting zones).
    pub fn observe(
        &mut self,
        t: f64,
        present: impl Iterator<Item = (u32, u32)>,
        log: &OutletLog,
        collected: &[u32],
    ) {
        self.epoch += 1;
        for (id, g) in present {
            let k = id as usize;
            if self.fed_at.len() <= k {
                self.fed_at.resize(k + 1, f64::NAN);
                self.group.resize(k + 1, 0);
                self.stamp.resize(k + 1, 0);
            }
            if self.stamp[k] == 0 {
                self.fed_at[k] = t;
                self.group[k] = g;
                self.alive.push(id);
            }
            self.stamp[k] = self.epoch;
        }
        let mut gone: Vec<Vec<u32>> = vec![Vec::new(); self.residence.len()];
        let epoch = self.epoch;
        self.alive.retain(|&id| {
            let k = id as usize;
            if self.stamp[k] == epoch {
                true
            } else if collected.binary_search(&id).is_ok() {
                false // collected: no residence time, nothing to pair
            } else {
                if let Some(v) = gone.get_mut(self.group[k] as usize) {
                    v.push(id);
                }
                false
            }
        });
        for (g, ids) in gone.iter().enumerate() {
            let drained = log
                .drained
                .get(g)
                .map_or(&[][..], |v| &v[self.drained_seen[g]..]);
            let lost = log.lost.get(g).map_or(0, |v| v.len() - self.lost_seen[g]);
            if ids.len() == drained.len() + lost && (lost == 0 || drained.is_empty()) {
                for (id, td) in ids.iter().zip(drained) {
                    self.residence[g].push(td - self.fed_at[*id as usize]);
                }
            } else {
                self.unmatched += ids.len() as u64;
            }
            self.drained_seen[g] += drained.len();
            self.lost_seen[g] += lost;
        }
    }
}

/// One variant's run.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct CycloneRun {
    /// Variant name.
    pub name: String,
    /// Coarse-graining ratio α.
    pub alpha: f64,
    /// Coarse-graining law (scene name).
    pub law: String,
    /// Per class.
    pub classes: Vec<ClassGrade>,
    /// Wall time of the whole run, s.
    pub total_s: f64,
    /// CPU time of the process over the run (all threads), s, where the OS tells
    /// ([`process_cpu_s`]): on a shared machine the wall time also counts the others' load.
    pub cpu_s: Option<f64>,
    /// Particle-steps integrated.
    pub particle_steps: u64,
    /// Simulated time, s.
    pub duration: f64,
    /// Held particles still moving faster than [`MOVING`] at the end, per class.
    pub held_moving: Vec<u64>,
    /// Escapes during the last [`LATE`] of the run, per class (is the count settled?).
    pub escaped_late: Vec<u64>,
    /// Departed particles whose residence time could not be paired (see [`Tracker`]).
    pub unmatched: u64,
    /// Time of the snapshot, s, and the particles then (position, group).
    pub snapshot: (f64, Vec<(DVec3, u32)>),
}

use crate::run::process_cpu_s;

/// A held particle faster than this at the end is "still moving", m/s (a tenth of the
/// inlet velocity; particles resting on a wall move at mm/s to cm/s).
pub const MOVING: f64 = 1.0;
/// The last part of the run in which escapes are counted as late, s.
pub const LATE: f64 = 1.0;

/// Run the cyclone scene `text` with `overrides` as variant `name`; take the snapshot at
/// `snapshot_at` s; record to `mcap` when given.
pub fn run_variant(
    name: &str,
    text: &str,
    overrides: &[String],
    snapshot_at: f64,
    mcap: Option<&Path>,
) -> Result<CycloneRun, String> {
    run_variant_with(name, text, overrides, snapshot_at, mcap, |_| {}).map(|(r, _, _)| r)
}

/// [`run_variant`] for any scene with fates by patch (the elbow's too), with `setup`
/// called on the built simulation before the first step; also returns the scene and the
/// simulation as they ended (their logs: erosion…).
pub fn run_variant_with(
    name: &str,
    text: &str,
    overrides: &[String],
    snapshot_at: f64,
    mcap: Option<&Path>,
    setup: impl FnOnce(&mut Simulation),
) -> Result<(CycloneRun, Scene, Simulation), String> {
    let scene =
        scg_scene::parse(text, &format!("<{name}>"), name, overrides).map_err(|e| e.to_string())?;
    let ng = scene.groups.len();
    let mut sim = scene.build(mcap.is_some());
    setup(&mut sim);
    if let Some(p) = mcap {
        let meta = scene.run_meta(scg_scene::check::check(&scene).messages());
        let sink = scg_record::McapSink::create(p, &meta).map_err(|e| e.to_string())?;
        sim.add_recorder(Box::new(sink));
    }
    let steps = scene.steps();
    let snap_step = ((snapshot_at / scene.dt).round() as u64).min(steps);
    let mut tracker = Tracker::new(ng);
    let mut query = sim.world.query::<(&ParticleId, &GroupId)>();
    let mut snapshot = (0.0, Vec::new());
    let t0 = Instant::now();
    let cpu0 = process_cpu_s();
    if mcap.is_some() {
        sim.record_now().map_err(|e| e.to_string())?;
    }
    for step in 1..=steps {
        sim.step().map_err(|e| e.to_string())?;
        let t = sim.time();
        let collected = sim
            .world
            .get_resource::<CollectLog>()
            .map_or(&[][..], |l| &l.last_step_ids);
        let present = query.iter(&sim.world).map(|(id, g)| (id.0, g.0));
        tracker.observe(t, present, sim.world.resource::<OutletLog>(), collected);
        if step == snap_step {
            snapshot = (
                t,
                sim.particles()
                    .iter()
                    .map(|p| (p.position, p.group))
                    .collect(),
            );
        }
    }
    let total_s = t0.elapsed().as_secs_f64();
    let cpu_s = process_cpu_s().zip(cpu0).map(|(b, a)| b - a);
    sim.finish_recorders().map_err(|e| e.to_string())?;
    let log = sim.world.resource::<OutletLog>().clone();
    let fed = sim.world.resource::<Tally>().fed.clone();
    let collect = sim.world.get_resource::<CollectLog>().cloned();
    let end = sim.time();
    let ps = sim.particles();
    let mut held = vec![0u64; ng];
    let mut held_moving = vec![0u64; ng];
    for p in &ps {
        let g = p.group as usize;
        held[g] += 1;
        if p.velocity.length() > MOVING {
            held_moving[g] += 1;
        }
    }
    let classes = scene
        .groups
        .iter()
        .enumerate()
        .map(|(g, grp)| {
            let c = ClassGrade::new(
                &grp.name,
                grp.diameter,
                grp.density,
                [
                    fed[g],
                    log.drained[g].len() as u64,
                    held[g],
                    log.lost[g].len() as u64,
                ],
                std::mem::take(&mut tracker.residence[g]),
            );
            match &collect {
                Some(l) => c.with_collected(l.count(g)),
                None => c,
            }
        })
        .collect();
    let escaped_late = log
        .drained
        .iter()
        .map(|v| v.iter().filter(|&&t| t > end - LATE).count() as u64)
        .collect();
    let g0 = &scene.groups[0];
    let sampled = g0.alpha == 1.0 && name.starts_with("sample");
    let run = CycloneRun {
        name: name.to_string(),
        alpha: g0.alpha,
        law: if sampled {
            "sample".to_string()
        } else {
            g0.law.name().to_string()
        },
        classes,
        total_s,
        cpu_s,
        particle_steps: sim.particle_steps(),
        duration: end,
        held_moving,
        escaped_late,
        unmatched: tracker.unmatched,
        snapshot,
    };
    Ok((run, scene, sim))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracker_pairs_feeds_with_escapes() {
        let mut log = OutletLog {
            drained: vec![Vec::new(); 2],
            lost: vec![Vec::new(); 2],
        };
        let mut tr = Tracker::new(2);
        // t = 1: ids 0 (group 0), 1 (group 1) fed.
        tr.observe(1.0, [(0, 0), (1, 1)].into_iter(), &log, &[]);
        // t = 2: id 2 (group 0) fed.
        tr.observe(2.0, [(0, 0), (1, 1), (2, 0)].into_iter(), &log, &[]);
        // t = 3: id 0 escaped.
        log.drained[0].push(3.0);
        tr.observe(3.0, [(1, 1), (2, 0)].into_iter(), &log, &[]);
        assert_eq!(tr.residence[0], vec![2.0]);
        // t = 4: id 1 lost (no residence time), id 3 (group 1) fed.
        log.lost[1].push(4.0);
        tr.observe(4.0, [(2, 0), (3, 1)].into_iter(), &log, &[]);
        assert!(tr.residence[1].is_empty());
        assert_eq!(tr.unmatched, 0);
        // t = 5: id 2 escaped and id 3 escaped (different groups, both unambiguous).
        log.drained[0].push(5.0);
        log.drained[1].push(5.0);
        tr.observe(5.0, std::iter::empty(), &log, &[]);
        assert_eq!(tr.residence[0], vec![2.0, 3.0]);
        assert_eq!(tr.residence[1], vec![1.0]);
        // t = 6, 7: ids 4, 5 of group 0 fed; t = 8: one escapes and one is lost in the
        // same step: which is which is unknown, both unmatched.
        tr.observe(6.0, [(4, 0)].into_iter(), &log, &[]);
        tr.observe(7.0, [(4, 0), (5, 0)].into_iter(), &log, &[]);
        log.drained[0].push(8.0);
        log.lost[0].push(8.0);
        tr.observe(8.0, std::iter::empty(), &log, &[]);
        assert_eq!(tr.unmatched, 2);
        assert_eq!(tr.residence[0].len(), 2);
        // Later steps go on pairing from where the log was.
        tr.observe(9.0, [(6, 0)].into_iter(), &log, &[]);
        log.drained[0].push(9.5);
        tr.observe(9.5, std::iter::empty(), &log, &[]);
        assert_eq!(tr.residence[0], vec![2.0, 3.0, 0.5]);
        // t = 10: id 7 fed; t = 11: it is collected (no residence time, not unmatched);
        // t = 12: ids 8, 9 fed; t = 13: 8 escapes while 9 is collected: told apart by id.
        tr.observe(10.0, [(7, 0)].into_iter(), &log, &[]);
        tr.observe(11.0, std::iter::empty(), &log, &[7]);
        assert_eq!((tr.unmatched, tr.residence[0].len()), (2, 3));
        tr.observe(12.0, [(8, 0), (9, 0)].into_iter(), &log, &[]);
        log.drained[0].push(13.0);
        tr.observe(13.0, std::iter::empty(), &log, &[9]);
        assert_eq!(tr.unmatched, 2);
        assert_eq!(tr.residence[0], vec![2.0, 3.0, 0.5, 1.0]);
    }
}
