//! Collecting zones: a particle whose centre enters a zone that collects (a cyclone's dust
//! bin below the apex, a hopper) is removed and counted there as collected, per zone and
//! group, with the time. The zone stands for a sink the air field does not resolve: what
//! reaches it does not come back (scenes: `[[zones]] collects = true`).

use bevy_ecs::prelude::*;

use crate::checkpoint::records::{Checkpoint, Part, Persist, Persistence};
use crate::components::*;
use crate::region::Region;
use crate::state::SimClock;
use crate::step::{StepBuilder, StepSet, StepSystem};

/// The collecting zones, in the scene's order of them (resource).
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct CollectZones(pub Vec<Region>);

/// Collection times per zone and group, s, in order (resource): `collected[zone][group]`.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct CollectLog {
    /// Times the particles were collected, s.
    pub collected: Vec<Vec<Vec<f64>>>,
    /// Ids of the particles collected in the last step, in id order (scratch: cleared
    /// every step, not in checkpoints), for callers that follow particles by id.
    pub last_step_ids: Vec<u32>,
}

impl CollectLog {
    /// Particles collected so far in group `g`, over all zones.
    pub fn count(&self, g: usize) -> u64 {
        self.collected
            .iter()
            .map(|z| z.get(g).map_or(0, Vec::len) as u64)
            .sum()
    }
}

/// The collect log's part of a checkpoint.
struct CollectPart;

impl Persist for CollectPart {
    fn part(&self) -> Option<Part> {
        Some(Part::Collect)
    }

    fn save(&self, world: &World, c: &mut Checkpoint) {
        c.collected = Some(world.resource::<CollectLog>().collected.clone());
    }

    fn restore(&self, world: &mut World, c: &Checkpoint) -> Result<(), String> {
        let mut log = world.resource_mut::<CollectLog>();
        match &c.collected {
            Some(z) if z.len() == log.collected.len() => {
                log.collected.clone_from(z);
                Ok(())
            }
            _ => Err(Part::Collect.mismatch()),
        }
    }
}

/// Add the collecting system (inlet/outlet stage, after the departures through patches,
/// walls and the outlet) and its resources.
pub fn plugin(world: &mut World, b: &mut StepBuilder, zones: Vec<Region>, groups: usize) {
    let n = zones.len();
    world.insert_resource(CollectZones(zones));
    Persistence::register(world, CollectPart);
    world.insert_resource(CollectLog {
        collected: vec![vec![Vec::new(); groups]; n],
        last_step_ids: Vec::new(),
    });
    b.add(
        StepSet::InletOutlet,
        "collect",
        StepSystem::CollectParticles,
        collect_particles,
    );
}

/// The first zone of `zones` holding `x`, if any.
pub fn zone_of(zones: &[Region], x: glam::DVec3) -> Option<usize> {
    zones.iter().position(|z| z.contains(x))
}

/// Remove the particles whose centre is in a collecting zone, in id order (so the log is
/// deterministic), logging each in the first zone holding it.
pub fn collect_particles(
    mut commands: Commands,
    clock: Res<SimClock>,
    zones: Res<CollectZones>,
    mut log: ResMut<CollectLog>,
    q: Query<(Entity, &ParticleId, &GroupId, &Position)>,
) {
    let mut gone: Vec<(u32, u32, Entity, usize)> = q
        .iter()
        .filter_map(|(e, id, g, x)| zone_of(&zones.0, x.0).map(|z| (id.0, g.0, e, z)))
        .collect();
    log.last_step_ids.clear();
    if gone.is_empty() {
        return;
    }
    gone.sort_unstable_by_key(|g| g.0);
    let t = clock.time();
    for (id, g, e, z) in gone {
        log.last_step_ids.push(id);
        if let Some(v) = log.collected.get_mut(z).and_then(|z| z.get_mut(g as usize)) {
            v.push(t);
        }
        commands.entity(e).despawn();
    }
}
