//! Collecting zones: a particle whose centre enters a zone that collects (a cyclone's dust
//! bin below the apex, a hopper) is removed and counted there as collected, per zone and
//! group, with the time it entered. The zone stands for a sink the air field does not
//! resolve: what reaches it does not come back (scenes: `[[zones]] collects = true`).
//!
//! A zone may wait (`collects_after`): a particle is collected only once its centre has
//! stayed inside for that many whole steps without leaving — what settles is taken, what
//! the air carries through (or re-entrains) is not. The particles waiting are kept with
//! the step they entered, and checkpoints carry them.

use bevy_ecs::prelude::*;

use crate::checkpoint::records::{Checkpoint, Part, Persist, Persistence};
use crate::components::*;
use crate::region::Region;
use crate::state::SimClock;
use crate::step::{StepBuilder, StepSet, StepSystem};

/// The collecting zones, in the scene's order of them, each with the steps a particle's
/// centre must stay inside before it is collected (0: on entry) (resource).
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct CollectZones(pub Vec<(Region, u64)>);

/// Collection times per zone and group, s, in order (resource): `collected[zone][group]`.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct CollectLog {
    /// Times the particles were collected, s.
    pub collected: Vec<Vec<Vec<f64>>>,
    /// Ids of the particles collected in the last step, in id order (scratch: cleared
    /// every step, not in checkpoints), for callers that follow particles by id.
    pub last_step_ids: Vec<u32>,
    /// Particles waiting in a zone that waits: id → (zone, step they entered).
    pub inside: std::collections::BTreeMap<u32, (u32, u64)>,
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
        let log = world.resource::<CollectLog>();
        c.collected = Some(log.collected.clone());
        c.collect_inside = log
            .inside
            .iter()
            .map(|(id, (z, s))| (*id, *z, *s))
            .collect();
    }

    fn restore(&self, world: &mut World, c: &Checkpoint) -> Result<(), String> {
        let mut log = world.resource_mut::<CollectLog>();
        match &c.collected {
            Some(z) if z.len() == log.collected.len() => {
                log.collected.clone_from(z);
                log.inside = c
                    .collect_inside
                    .iter()
                    .map(|(id, z, s)| (*id, (*z, *s)))
                    .collect();
                Ok(())
            }
            _ => Err(Part::Collect.mismatch()),
        }
    }
}

/// Add the collecting system (inlet/outlet stage, after the departures through patches,
/// walls and the outlet) and its resources.
pub fn plugin(world: &mut World, b: &mut StepBuilder, zones: Vec<(Region, u64)>, groups: usize) {
    let n = zones.len();
    world.insert_resource(CollectZones(zones));
    Persistence::register(world, CollectPart);
    world.insert_resource(CollectLog {
        collected: vec![vec![Vec::new(); groups]; n],
        last_step_ids: Vec::new(),
        inside: Default::default(),
    });
    b.add(
        StepSet::InletOutlet,
        "collect",
        StepSystem::CollectParticles,
        collect_particles,
    );
}

/// The first zone of `zones` holding `x`, if any.
pub fn zone_of(zones: &[(Region, u64)], x: glam::DVec3) -> Option<usize> {
    zones.iter().position(|z| z.0.contains(x))
}

/// Whether a particle in zone `zone` at `step`, found there before as `before` (zone,
/// step it entered), is collected now, and the step it entered (a particle that changed
/// zones enters anew).
pub fn settled(zone: usize, wait: u64, before: Option<(u32, u64)>, step: u64) -> (bool, u64) {
    let entered = match before {
        Some((z, s)) if z as usize == zone => s,
        _ => step,
    };
    (step - entered >= wait, entered)
}

/// Remove the particles whose centre is in a collecting zone (that has held it for the
/// zone's wait), in id order (so the log is deterministic), logging each in the first
/// zone holding it with the time it entered.
pub fn collect_particles(
    mut commands: Commands,
    clock: Res<SimClock>,
    zones: Res<CollectZones>,
    mut log: ResMut<CollectLog>,
    q: Query<(Entity, &ParticleId, &GroupId, &Position)>,
) {
    let mut found: Vec<(u32, u32, Entity, usize)> = q
        .iter()
        .filter_map(|(e, id, g, x)| zone_of(&zones.0, x.0).map(|z| (id.0, g.0, e, z)))
        .collect();
    log.last_step_ids.clear();
    if found.is_empty() && log.inside.is_empty() {
        return;
    }
    found.sort_unstable_by_key(|g| g.0);
    let step = clock.step;
    // who waits now: the particles found in a zone that waits and not yet due (a
    // particle gone from the zones or from the domain is forgotten)
    let mut inside = std::collections::BTreeMap::new();
    for (id, g, e, z) in found {
        let wait = zones.0[z].1;
        let (due, entered) = settled(z, wait, log.inside.get(&id).copied(), step);
        if !due {
            inside.insert(id, (z as u32, entered));
            continue;
        }
        log.last_step_ids.push(id);
        let t = entered as f64 * clock.dt;
        if let Some(v) = log.collected.get_mut(z).and_then(|z| z.get_mut(g as usize)) {
            v.push(t);
        }
        commands.entity(e).despawn();
    }
    log.inside = inside;
}

#[cfg(test)]
mod tests {
    use super::settled;

    #[test]
    fn a_particle_is_collected_after_its_wait_in_one_zone() {
        // on entry without a wait
        assert_eq!(settled(0, 0, None, 7), (true, 7));
        // entered at step 10, a wait of 5: due at step 15, not before
        assert_eq!(settled(1, 5, None, 10), (false, 10));
        assert_eq!(settled(1, 5, Some((1, 10)), 14), (false, 10));
        assert_eq!(settled(1, 5, Some((1, 10)), 15), (true, 10));
        // moved on to another zone: it enters anew
        assert_eq!(settled(2, 5, Some((1, 10)), 15), (false, 15));
    }
}
