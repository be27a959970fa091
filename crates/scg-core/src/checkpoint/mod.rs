//! Checkpoints: the whole state a run needs to go on bit for bit, taken between two steps
//! and restored into a simulation built from the same scene.
//!
//! What is saved is what the next steps read and cannot re-derive: every particle's
//! identity, original size and scaling (its coarse-grained properties are derived again by
//! the spawn path, exactly), position, velocity, angular velocity, force, torque and wall
//! history, mesh cell, carrier offset and dispersion state, in table order (the order every stage visits them); the clock; the next id;
//! the tally; the outlet log; each feeder's count and random stream; the contact arrays
//! that carry over between steps (Verlet list, its reference positions and drift bound,
//! pair histories); the last step's displacement bound; the measured contact resolution.
//! Scratch buffers, timers and recorders are not state. Reading and writing files is
//! `scg-record`'s job.

pub mod records;

pub use records::*;

use bevy_ecs::prelude::*;
use glam::DVec3;

use crate::components::*;
use crate::sim::Simulation;
use crate::spawn::{ParticleSpec, spawn_particle_with_id};
use crate::state::{ContactCount, ContactResolution, NextParticleId, SimClock, Tally};

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
    Option<&'a CarrierOffset>,
    Option<&'a Eddy>,
);

/// The record of one particle, from its components.
fn record_of((id, g, cg, x, v, w, f, t, h, cell, off, eddy): RecordQuery) -> ParticleRecord {
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
        carrier_offset: off.map(|o| o.0),
        eddy: eddy.map(|e| (e.age, e.sigma)),
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
    match (p.carrier_offset, ent.get_mut::<CarrierOffset>()) {
        (Some(o), Some(mut a)) => a.0 = o,
        (None, None) => {}
        _ => return Err(mismatch()),
    }
    match (p.eddy, ent.get_mut::<Eddy>()) {
        (Some((age, sigma)), Some(mut a)) => *a = Eddy { age, sigma },
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

    /// Put the particle table in id order (rows by ascending id; nothing when it is):
    /// the order a single-rank run keeps its placed and fed particles in until some
    /// leave, and so the neighbour locality of its rows. A decomposed run calls it after
    /// its particles changed hands: a rank's rows are else scattered by the swaps that
    /// fill the rows of the particles that left, and the contact stage's sums cover
    /// the particles of a pair's rows far apart (measured on the dense bed: the kicks
    /// 2.4× slower). Changes the rows alone, and so, with particle contacts, the order
    /// a particle's pair forces are summed in (the list is rebuilt, histories by id).
    pub fn sort_particles_by_id(&mut self) {
        let mut q = self.world.query::<&ParticleId>();
        let ids: Vec<u32> = q.iter(&self.world).map(|id| id.0).collect();
        if ids.is_sorted() {
            return;
        }
        let mut perm: Vec<u32> = (0..ids.len() as u32).collect();
        perm.sort_unstable_by_key(|&i| ids[i as usize]);
        crate::stages::table::reorder_particles(&mut self.world, &perm, |_| true);
    }

    /// Number of particles.
    pub fn particle_count(&mut self) -> usize {
        let mut q = self.world.query::<&ParticleId>();
        q.iter(&self.world).len()
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
        let mut c = Checkpoint {
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
            displacement: (0, false),
            particles,
            feeders: Vec::new(),
            outlet: None,
            patches: None,
            impulse_walls: None,
            contacts: None,
            collected: None,
            collect_inside: Vec::new(),
            erosion: None,
        };
        if let Some(reg) = w.get_resource::<Persistence>() {
            for p in reg.iter() {
                p.save(w, &mut c);
            }
        }
        c
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
        // Every part the checkpoint holds has a stage in this scene to take it (and each
        // stage's restore refuses a checkpoint without its part).
        let registered: Vec<Option<Part>> = w
            .get_resource::<Persistence>()
            .map_or_else(Vec::new, |r| r.iter().map(|p| p.part()).collect());
        if let Some(p) = c
            .held_parts()
            .into_iter()
            .find(|p| !registered.contains(&Some(*p)))
        {
            return Err(p.mismatch());
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
        // Each stage's part (the particles are in place).
        w.resource_scope(|w, reg: Mut<Persistence>| reg.iter().try_for_each(|p| p.restore(w, c)))?;
        Ok(())
    }
}
