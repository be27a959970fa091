//! Checkpoints: the whole state a run needs to go on bit for bit, taken between two steps
//! and restored into a simulation built from the same scene.
//!
//! What is saved is what the next steps read and cannot re-derive: every particle's
//! identity, original size and scaling (its coarse-grained properties are derived again by
//! the spawn path, exactly), position, velocity, angular velocity, force, torque and wall
//! history and mesh cell, in table order (the order every stage visits them); the clock; the next id;
//! the tally; the outlet log; each feeder's count and random stream; the contact arrays
//! that carry over between steps (Verlet list, its reference positions and drift bound,
//! pair histories); the last step's displacement bound; the measured contact resolution.
//! Scratch buffers, timers and recorders are not state. Reading and writing files is
//! `scg-record`'s job.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::spawn::ParticleSpec;

/// One particle.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParticleRecord {
    /// Id.
    pub id: u32,
    /// The original particle and its scaling, with the current position and velocity (the
    /// coarse-grained properties are derived from it again, exactly, by the spawn path).
    pub spec: ParticleSpec,
    /// Angular velocity, rad/s (when the scene has it).
    pub omega: Option<DVec3>,
    /// Force, N, and torque, N·m (when the scene has walls or contacts).
    pub force_torque: Option<(DVec3, DVec3)>,
    /// Wall contact history (wall key, displacement in m), when the scene has walls.
    pub wall_history: Option<Vec<(u32, DVec3)>>,
    /// The mesh cell found last step, when the flow is on a mesh.
    pub cell: Option<u32>,
}

/// One feeder's state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FeederRecord {
    /// Particles fed so far.
    pub fed: u64,
    /// ChaCha8 seed, stream and word position of its random stream.
    pub seed: [u8; 32],
    /// Stream.
    pub stream: u64,
    /// Word position.
    pub word_pos: u128,
}

/// One candidate pair of the contact list.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairRecord {
    /// Rows i < j.
    pub i: u32,
    /// Second row.
    pub j: u32,
    /// In contact after the last step.
    pub touching: bool,
    /// Periodic image shift, m.
    pub shift: DVec3,
    /// Tangential history, m.
    pub history: DVec3,
}

/// The contact arrays that carry over between steps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactRecord {
    /// Ids of the rows the arrays were gathered for.
    pub ids: Vec<u32>,
    /// Verlet list pairs.
    pub list_pairs: Vec<[u32; 2]>,
    /// Positions at the last list build, m.
    pub reference: Vec<DVec3>,
    /// Builds and exact checks so far.
    pub builds: u64,
    /// Exact displacement checks so far.
    pub checks: u64,
    /// Bound on the displacement since the last build, m.
    pub drift_bound: f64,
    /// Pair states aligned with `list_pairs`.
    pub pairs: Vec<PairRecord>,
    /// Whether the last step summed sparsely, and its contacts in touch.
    pub sparse: bool,
    /// Pairs in contact after the last step.
    pub active: usize,
}

/// Contacts measured so far, per kind: shortest (s), started, under-resolved.
pub type ResolutionRecord = [(Option<f64>, u64, u64); 2];

/// The state of a run between two steps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The scene's TOML text (after overrides), so a restart needs nothing else.
    pub scene: String,
    /// Where the scene came from (`scg run` writes the file's absolute path: its folder
    /// resolves the scene's relative paths on a restart).
    pub scene_file: String,
    /// Steps done.
    pub step: u64,
    /// Time step, s (a restart refuses a scene with another).
    pub dt: f64,
    /// Particle-steps done.
    pub particle_steps: u64,
    /// Next free particle id.
    pub next_id: u32,
    /// Tally: drained, fed and collisions per group.
    pub tally: [Vec<u64>; 3],
    /// Contact resolution measured so far (wall, pair).
    pub resolution: ResolutionRecord,
    /// The last step's largest squared displacement (bits) and whether it was reported.
    pub displacement: (u64, bool),
    /// Particles in table order.
    pub particles: Vec<ParticleRecord>,
    /// Feeders, in scene order.
    pub feeders: Vec<FeederRecord>,
    /// Outlet log: drain and loss times per group, s.
    pub outlet: Option<[Vec<Vec<f64>>; 2]>,
    /// Patch log of a mesh flow: escaped and stuck counts per patch and group.
    pub patches: Option<[Vec<Vec<u64>>; 2]>,
    /// Impulse walls' log: escaped and stuck counts per wall and group.
    pub impulse_walls: Option<[Vec<Vec<u64>>; 2]>,
    /// Contact arrays, when the scene has particle contacts.
    pub contacts: Option<ContactRecord>,
}

use bevy_ecs::prelude::*;

use crate::components::*;
use crate::sim::Simulation;
use crate::spawn::spawn_particle_with_id;
use crate::stages::contacts::ContactState;
use crate::stages::feeder::Feeders;
use crate::stages::impulse_walls::WallLog;
use crate::stages::mesh_flow::PatchLog;
use crate::stages::outlet::OutletLog;
use crate::state::{
    ContactCount, ContactResolution, NextParticleId, SimClock, StepDisplacement, Tally,
};

type RecordQuery<'a> = (
    &'a ParticleId,
    &'a GroupId,
    &'a CoarseGrain,
    &'a Position,
    &'a Velocity,
    Option<&'a AngularVelocity>,
    Option<&'a Force>,
    Option<&'a Torque>,
    Option<&'a WallHistory>,
    Option<&'a CellHint>,
);

/// The record of one particle, from its components.
fn record_of((id, g, cg, x, v, w, f, t, h, cell): RecordQuery) -> ParticleRecord {
    ParticleRecord {
        id: id.0,
        spec: ParticleSpec {
            group: g.0,
            diameter: cg.original_diameter,
            density: cg.original_density,
            alpha: cg.alpha,
            law: cg.law,
            position: x.0,
            velocity: v.0,
        },
        omega: w.map(|w| w.0),
        force_torque: f.zip(t).map(|(f, t)| (f.0, t.0)),
        wall_history: h.map(|h| h.0.clone()),
        cell: cell.map(|c| c.0),
    }
}

/// Spawn the particle of `p` with its whole state (the spawn path derives its
/// coarse-grained properties again, exactly). Errors when its components differ from what
/// the world's spawn rules give.
fn insert_record(w: &mut World, p: &ParticleRecord) -> Result<Entity, String> {
    let e = spawn_particle_with_id(w, &p.spec, p.id);
    let mut ent = w.entity_mut(e);
    let mismatch = || format!("particle {}: its components differ from the scene's", p.id);
    match (p.omega, ent.get_mut::<AngularVelocity>()) {
        (Some(o), Some(mut a)) => a.0 = o,
        (None, None) => {}
        _ => return Err(mismatch()),
    }
    match (p.force_torque, ent.contains::<Force>()) {
        (Some((f, t)), true) => {
            ent.get_mut::<Force>().ok_or_else(mismatch)?.0 = f;
            ent.get_mut::<Torque>().ok_or_else(mismatch)?.0 = t;
        }
        (None, false) => {}
        _ => return Err(mismatch()),
    }
    match (&p.wall_history, ent.get_mut::<WallHistory>()) {
        (Some(h), Some(mut a)) => a.0.clone_from(h),
        (None, None) => {}
        _ => return Err(mismatch()),
    }
    match (p.cell, ent.get_mut::<CellHint>()) {
        (Some(c), Some(mut a)) => a.0 = c,
        (None, None) => {}
        _ => return Err(mismatch()),
    }
    Ok(e)
}

impl Simulation {
    /// Remove the particles for which `leave(id, position)` is true and return their
    /// whole state, in table order (the particles migrating to another rank of a
    /// decomposed run). `leave` must depend on its arguments alone: it is asked twice
    /// when somebody leaves. With particle contacts the neighbour stage rebuilds its list
    /// for the changed table (the pair histories travel separately: scg-mpi).
    pub fn extract_particles(
        &mut self,
        mut leave: impl FnMut(u32, DVec3) -> bool,
    ) -> Vec<ParticleRecord> {
        // Most calls take nobody (a decomposed run asks every step): ids and positions
        // alone first, the whole record only when somebody leaves.
        let mut ids = self.world.query::<(&ParticleId, &Position)>();
        if !ids.iter(&self.world).any(|(id, x)| leave(id.0, x.0)) {
            return Vec::new();
        }
        let mut q = self.world.query::<(Entity, RecordQuery)>();
        let mut out = Vec::new();
        let mut gone = Vec::new();
        for (e, item) in q.iter(&self.world) {
            if leave(item.0.0, item.3.0) {
                gone.push(e);
                out.push(record_of(item));
            }
        }
        for e in gone {
            self.world.despawn(e);
        }
        out
    }

    /// Add particles with their whole state (from [`Simulation::extract_particles`] of
    /// another simulation built from the same scene).
    pub fn insert_particles(&mut self, particles: &[ParticleRecord]) -> Result<(), String> {
        for p in particles {
            insert_record(&mut self.world, p)?;
        }
        Ok(())
    }

    /// The particles as a frame records them, in table order.
    pub fn frame_rows(&mut self) -> Vec<crate::stages::recording::FrameRow> {
        let mut q = self.world.query::<crate::stages::recording::FrameData>();
        q.iter(&self.world)
            .map(crate::stages::recording::frame_row)
            .collect()
    }

    /// The run's state between two steps (`scene` and `scene_file` are left empty for
    /// the caller, who knows the scene text).
    pub fn checkpoint(&mut self) -> Checkpoint {
        let mut q = self.world.query::<RecordQuery>();
        // Table order: the order in which every stage visits the particles.
        let particles = q.iter(&self.world).map(record_of).collect();
        let w = &self.world;
        let clock = w.resource::<SimClock>();
        let tally = w.resource::<Tally>();
        let res = w.resource::<ContactResolution>();
        let kind = |c: ContactCount| (c.shortest, c.contacts, c.under_resolved);
        Checkpoint {
            scene: String::new(),
            scene_file: String::new(),
            step: clock.step,
            dt: clock.dt,
            particle_steps: clock.particle_steps,
            next_id: w.resource::<NextParticleId>().0,
            tally: [
                tally.drained.clone(),
                tally.fed.clone(),
                tally.collisions.clone(),
            ],
            resolution: [kind(res.wall()), kind(res.pair())],
            displacement: w
                .get_resource::<StepDisplacement>()
                .map_or((0, false), |d| d.raw()),
            particles,
            feeders: w
                .get_resource::<Feeders>()
                .map_or_else(Vec::new, |f| f.records()),
            outlet: w
                .get_resource::<OutletLog>()
                .map(|l| [l.drained.clone(), l.lost.clone()]),
            patches: w
                .get_resource::<PatchLog>()
                .map(|l| [l.escaped.clone(), l.stuck.clone()]),
            impulse_walls: w
                .get_resource::<WallLog>()
                .map(|l| [l.escaped.clone(), l.stuck.clone()]),
            contacts: w.get_resource::<ContactState>().map(|c| c.record()),
        }
    }

    /// Put the state of `c` into this simulation, built from the same scene: the
    /// particles spawned at build time are replaced by the checkpoint's. Errors say what
    /// does not match the scene.
    pub fn restore(&mut self, c: &Checkpoint) -> Result<(), String> {
        let w = &mut self.world;
        {
            let clock = w.resource::<SimClock>();
            if clock.dt != c.dt {
                return Err(format!(
                    "the checkpoint was taken with dt = {} s, the scene has {} s",
                    c.dt, clock.dt
                ));
            }
        }
        let groups = w.resource::<Tally>().drained.len();
        if c.tally.iter().any(|t| t.len() != groups) {
            return Err(format!(
                "the scene has {groups} groups, the checkpoint another count"
            ));
        }
        if c.particles.iter().any(|p| p.spec.group as usize >= groups) {
            return Err("a particle of the checkpoint has no group in the scene".into());
        }
        if c.contacts.is_some() != w.contains_resource::<ContactState>() {
            return Err("the scene and the checkpoint differ in particle contacts".into());
        }
        if c.outlet.is_some() != w.contains_resource::<OutletLog>() {
            return Err("the scene and the checkpoint differ in the outlet".into());
        }
        if let Some(f) = w.get_resource_mut::<Feeders>().as_deref_mut() {
            f.restore(&c.feeders)?;
        } else if !c.feeders.is_empty() {
            return Err("the checkpoint has feeders, the scene none".into());
        }
        // Replace the particles, in the checkpoint's (table) order.
        let old: Vec<Entity> = w
            .query_filtered::<Entity, With<ParticleId>>()
            .iter(w)
            .collect();
        for e in old {
            w.despawn(e);
        }
        for p in &c.particles {
            insert_record(w, p)?;
        }
        w.resource_mut::<NextParticleId>().0 = c.next_id;
        {
            let mut clock = w.resource_mut::<SimClock>();
            clock.step = c.step;
            clock.particle_steps = c.particle_steps;
        }
        {
            let mut t = w.resource_mut::<Tally>();
            let [d, f, k] = c.tally.clone();
            (t.drained, t.fed, t.collisions) = (d, f, k);
        }
        let kind = |(shortest, contacts, under_resolved)| ContactCount {
            shortest,
            contacts,
            under_resolved,
        };
        w.resource::<ContactResolution>()
            .restore(kind(c.resolution[0]), kind(c.resolution[1]));
        if let Some(d) = w.get_resource::<StepDisplacement>() {
            d.restore(c.displacement);
        }
        // The wall candidates are listed again at the first step (the restored neighbour
        // list's build count may equal the one they were listed at).
        if let Some(mut wc) = w.get_resource_mut::<crate::stages::walls::WallCandidates>() {
            *wc = Default::default();
        }
        if let (Some([d, l]), Some(mut log)) = (&c.outlet, w.get_resource_mut::<OutletLog>()) {
            log.drained.clone_from(d);
            log.lost.clone_from(l);
        }
        match (&c.patches, w.get_resource_mut::<PatchLog>()) {
            (Some([e, s]), Some(mut log)) if e.len() == log.escaped.len() => {
                log.escaped.clone_from(e);
                log.stuck.clone_from(s);
            }
            (None, None) => {}
            _ => {
                return Err(
                    "the scene and the checkpoint differ in the mesh flow's patches".into(),
                );
            }
        }
        match (&c.impulse_walls, w.get_resource_mut::<WallLog>()) {
            (Some([e, s]), Some(mut log)) if e.len() == log.escaped.len() => {
                log.escaped.clone_from(e);
                log.stuck.clone_from(s);
            }
            (None, None) => {}
            _ => return Err("the scene and the checkpoint differ in the impulse walls".into()),
        }
        if let Some(rec) = &c.contacts {
            let dt = c.dt;
            let mut q = w.query::<(&ParticleId, &GroupId, &Diameter, &Mass)>();
            let rows: Vec<(ParticleId, GroupId, Diameter, Mass)> =
                q.iter(w).map(|(a, b, d, m)| (*a, *b, *d, *m)).collect();
            let ids: Vec<ParticleId> = rows.iter().map(|r| r.0).collect();
            let groups: Vec<GroupId> = rows.iter().map(|r| r.1).collect();
            let ds: Vec<Diameter> = rows.iter().map(|r| r.2).collect();
            let ms: Vec<Mass> = rows.iter().map(|r| r.3).collect();
            w.resource_mut::<ContactState>()
                .restore(rec, &ids, &groups, &ds, &ms, dt)?;
        }
        Ok(())
    }
}
