//! Outlet: particles that leave through the outlet nozzle are removed and counted per
//! group with their exit time; particles that leave the domain any other way are removed
//! and counted as lost.

use bevy_ecs::prelude::*;
use glam::DVec3;

use crate::checkpoint::records::{Checkpoint, Part, Persist, Persistence};
use crate::components::*;
use crate::state::{SimClock, Tally};
use crate::step::{StepBuilder, StepSet, StepSystem};

/// Outlet geometry: a disc of radius `nozzle_radius` about the axis at axial coordinate
/// `plane` (from `center` along `axis`), crossed toward +axis; and the domain, a cylinder
/// of radius `domain_radius` between the axial coordinates `domain_height`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutletGeometry {
    /// A point on the axis, m.
    pub center: DVec3,
    /// Unit axis; particles drain moving along +axis.
    pub axis: DVec3,
    /// Nozzle radius, m.
    pub nozzle_radius: f64,
    /// Axial coordinate of the outlet plane, m.
    pub plane: f64,
    /// Domain radius, m.
    pub domain_radius: f64,
    /// Axial range of the domain, m.
    pub domain_height: (f64, f64),
}

/// The outlet as the step runs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutletSpec {
    /// Where particles drain or are lost.
    pub geometry: OutletGeometry,
    /// Steps between checks (≥ 1).
    pub every: u64,
}

/// Where a particle is with respect to the outlet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fate {
    /// Still inside.
    Inside,
    /// Drained through the nozzle.
    Drained,
    /// Left the domain some other way.
    Lost,
}

impl OutletGeometry {
    /// The fate of a particle centred at `x`.
    pub fn fate(&self, x: DVec3) -> Fate {
        let rel = x - self.center;
        let h = rel.dot(self.axis);
        let r2 = (rel - h * self.axis).length_squared();
        if !(h.is_finite() && r2.is_finite()) {
            return Fate::Inside; // the guard reports it
        }
        if h >= self.plane && r2 < self.nozzle_radius * self.nozzle_radius {
            Fate::Drained
        } else if r2 > self.domain_radius * self.domain_radius
            || h < self.domain_height.0
            || h > self.domain_height.1
        {
            Fate::Lost
        } else {
            Fate::Inside
        }
    }
}

/// Exit times per group (resource): analysis computes drained fractions over windows.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct OutletLog {
    /// Exit times of drained particles, s, per group, in order.
    pub drained: Vec<Vec<f64>>,
    /// Times particles were lost, s, per group.
    pub lost: Vec<Vec<f64>>,
}

/// The outlet (resource).
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct Outlet(pub OutletSpec);

/// The outlet log's part of a checkpoint (also a mesh flow's: it drains through patches).
pub(crate) struct OutletPart;

impl Persist for OutletPart {
    fn part(&self) -> Option<Part> {
        Some(Part::Outlet)
    }

    fn save(&self, world: &World, c: &mut Checkpoint) {
        let l = world.resource::<OutletLog>();
        c.outlet = Some([l.drained.clone(), l.lost.clone()]);
    }

    fn restore(&self, world: &mut World, c: &Checkpoint) -> Result<(), String> {
        let Some([d, l]) = &c.outlet else {
            return Err(Part::Outlet.mismatch());
        };
        let mut log = world.resource_mut::<OutletLog>();
        log.drained.clone_from(d);
        log.lost.clone_from(l);
        Ok(())
    }
}

/// Add the outlet system.
pub fn plugin(world: &mut World, b: &mut StepBuilder, spec: OutletSpec, groups: usize) {
    world.insert_resource(Outlet(spec));
    Persistence::register(world, OutletPart);
    world.insert_resource(OutletLog {
        drained: vec![Vec::new(); groups],
        lost: vec![Vec::new(); groups],
    });
    b.add(
        StepSet::InletOutlet,
        "outlet",
        StepSystem::DrainParticles,
        drain_particles,
    );
}

/// Remove drained and lost particles, in id order so the log is deterministic.
pub fn drain_particles(
    mut commands: Commands,
    clock: Res<SimClock>,
    outlet: Res<Outlet>,
    mut log: ResMut<OutletLog>,
    mut tally: ResMut<Tally>,
    q: Query<(Entity, &ParticleId, &GroupId, &Position)>,
) {
    if !clock.step.is_multiple_of(outlet.0.every.max(1)) {
        return;
    }
    let gone = q
        .iter()
        .filter_map(|(e, id, g, x)| match outlet.0.geometry.fate(x.0) {
            Fate::Inside => None,
            f => Some((id.0, g.0, e, f == Fate::Drained)),
        })
        .collect();
    remove_departed(&mut commands, &mut log, &mut tally, clock.time(), gone);
}

/// Despawn the particles `gone` (id, group, entity, drained rather than lost) in id order,
/// so the log is deterministic, logging each at time `t` (s) and counting the drained
/// ones per group. Shared by the outlet and the mesh-flow boundary.
pub fn remove_departed(
    commands: &mut Commands,
    log: &mut OutletLog,
    tally: &mut Tally,
    t: f64,
    mut gone: Vec<(u32, u32, Entity, bool)>,
) {
    gone.sort_unstable_by_key(|g| g.0);
    for (_, g, e, drained) in gone {
        let gi = g as usize;
        if drained {
            if let Some(c) = tally.drained.get_mut(gi) {
                *c += 1;
            }
            if let Some(v) = log.drained.get_mut(gi) {
                v.push(t);
            }
        } else if let Some(v) = log.lost.get_mut(gi) {
            v.push(t);
        }
        commands.entity(e).despawn();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fates() {
        let o = OutletGeometry {
            center: DVec3::ZERO,
            axis: DVec3::Z,
            nozzle_radius: 0.01,
            plane: 0.05,
            domain_radius: 0.03,
            domain_height: (-0.001, 0.061),
        };
        assert_eq!(o.fate(DVec3::new(0.005, 0.0, 0.051)), Fate::Drained);
        assert_eq!(o.fate(DVec3::new(0.005, 0.0, 0.049)), Fate::Inside);
        assert_eq!(o.fate(DVec3::new(0.02, 0.0, 0.055)), Fate::Inside);
        assert_eq!(o.fate(DVec3::new(0.04, 0.0, 0.01)), Fate::Lost);
        assert_eq!(o.fate(DVec3::new(0.0, 0.0, -0.01)), Fate::Lost);
    }
}
