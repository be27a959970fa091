//! Walls that act as impulses instead of contact laws (`[[walls]] model = "rebound" |
//! "stick" | "escape"`): the patch interaction models of a mesh flow's patches
//! ([`crate::physics::patch_interaction`]) for STL and analytic walls. After the
//! integration, a particle whose sphere touches such a wall rebounds (its centre pushed
//! back to touching distance, its velocity by [`rebound_velocity`]), sticks (removed,
//! counted as stuck on the wall) or escapes (removed, counted as escaped through it).
//! No contact time is resolved, so the time step follows the drag. With `[erosion]` the
//! rebounds and sticks on logged walls wear them ([`ErosionLog::add_walls`]).

use bevy_ecs::prelude::*;

use crate::checkpoint::records::{Checkpoint, Part, Persist, Persistence};
use crate::components::*;
use crate::physics::patch_interaction::{PatchInteraction, rebound_velocity};
use crate::physics::wall_motion::Pose;
use crate::physics::wall_shape::WallTouch;
use crate::stages::erosion::{ErosionLog, WallHit, represented_mass};
use crate::stages::walls::Wall;
use crate::state::SimClock;
use crate::step::{StepBuilder, StepSet, StepSystem};

/// A wall and what a particle touching it does.
#[derive(Clone, Debug, PartialEq)]
pub struct ImpulseWall {
    /// The wall.
    pub wall: Wall,
    /// Rebound, stick or escape.
    pub model: PatchInteraction,
}

impl ImpulseWall {
    /// Where the wall is at time `t` (s): `None` for a wall at rest.
    pub fn pose(&self, t: f64) -> Option<Pose> {
        (!self.wall.motion.is_fixed()).then(|| self.wall.motion.pose(t))
    }
}

/// The scene's impulse walls (resource).
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct ImpulseWalls(pub Vec<ImpulseWall>);

/// Particles removed at each impulse wall, per group (resource): `escaped[wall][group]`,
/// `stuck[wall][group]`, counts of simulated particles.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct WallLog {
    /// Escaped through the wall (an `escape` wall).
    pub escaped: Vec<Vec<u64>>,
    /// Stuck on the wall (a `stick` wall).
    pub stuck: Vec<Vec<u64>>,
}

/// The impulse walls' log's part of a checkpoint.
struct WallLogPart;

impl Persist for WallLogPart {
    fn part(&self) -> Option<Part> {
        Some(Part::ImpulseWalls)
    }

    fn save(&self, world: &World, c: &mut Checkpoint) {
        let l = world.resource::<WallLog>();
        c.impulse_walls = Some([l.escaped.clone(), l.stuck.clone()]);
    }

    fn restore(&self, world: &mut World, c: &Checkpoint) -> Result<(), String> {
        let mut log = world.resource_mut::<WallLog>();
        match &c.impulse_walls {
            Some([e, s]) if e.len() == log.escaped.len() => {
                log.escaped.clone_from(e);
                log.stuck.clone_from(s);
                Ok(())
            }
            _ => Err(Part::ImpulseWalls.mismatch()),
        }
    }
}

/// Add the impulse-wall system (inlet/outlet stage, before the outlets) and its resources.
pub fn plugin(world: &mut World, b: &mut StepBuilder, walls: Vec<ImpulseWall>, groups: usize) {
    let n = walls.len();
    world.insert_resource(ImpulseWalls(walls));
    Persistence::register(world, WallLogPart);
    world.insert_resource(WallLog {
        escaped: vec![vec![0; groups]; n],
        stuck: vec![vec![0; groups]; n],
    });
    b.add(
        StepSet::InletOutlet,
        "impulse_walls",
        StepSystem::ImpulseWalls,
        impulse_walls,
    );
}

/// What touching a wall does: the rebound's new position and velocity, or the model
/// (stick, escape) that removes the particle.
pub type Outcome = Result<(glam::DVec3, glam::DVec3), PatchInteraction>;

/// What touching wall `w`, at `pose` (`None` for a wall at rest; [`ImpulseWall::pose`]),
/// does to a sphere of radius `r` at `x` moving at `v`: `None` when it does not touch;
/// else the touch (its normal in the world, the triangle), the wall's surface velocity at
/// the contact point (m/s; zero for a wall at rest), and `Ok((x', v'))` after a rebound or
/// `Err(model)` when it sticks or escapes. A moving wall is touched in its rest frame
/// ([`crate::physics::wall_motion`]) and rebounds the velocity relative to its surface:
/// v' = V + rebound(v − V).
#[inline]
pub fn impulse(
    w: &ImpulseWall,
    pose: Option<Pose>,
    x: glam::DVec3,
    v: glam::DVec3,
    r: f64,
) -> Option<(WallTouch, glam::DVec3, Outcome)> {
    let xr = pose.map_or(x, |p| p.to_rest(x));
    if w.wall.shape.surely_clear(xr, r) {
        return None;
    }
    let mut t = w.wall.shape.touch(xr, r)?;
    let surface = match pose {
        None => glam::DVec3::ZERO,
        Some(p) => {
            t.normal = p.to_world_direction(t.normal);
            p.velocity_at(x - r * t.normal)
        }
    };
    let outcome = match w.model {
        // t.normal points from the wall to the centre: the wall's outward normal, as
        // rebound_velocity takes it, is −t.normal. The push back to touching distance is
        // made in the wall's frame: a turning wall carries the particle's velocity along
        // (+ ω × δ), so the motion relative to the wall is the same seen from either frame.
        PatchInteraction::Rebound { e, mu, friction } => {
            let push = t.overlap * t.normal;
            let carried = pose.map_or(glam::DVec3::ZERO, |p| p.angular_velocity.cross(push));
            Ok((
                x + push,
                surface + rebound_velocity(v - surface, -t.normal, e, mu, friction) + carried,
            ))
        }
        m => Err(m),
    };
    Some((t, surface, outcome))
}

/// Apply the impulse walls to every particle, in wall order; remove the ones that stick or
/// escape in id order, counting them per wall and group. With `[erosion]`, every rebound
/// and stick on a logged wall wears the triangle it touched.
pub fn impulse_walls(
    mut commands: Commands,
    walls: Res<ImpulseWalls>,
    mut log: ResMut<WallLog>,
    clock: Res<SimClock>,
    erosion: Option<ResMut<ErosionLog>>,
    mut q: Query<(
        Entity,
        &ParticleId,
        &GroupId,
        &mut Position,
        &mut Velocity,
        &Diameter,
        &CoarseGrain,
    )>,
) {
    let mut gone: Vec<(u32, u32, Entity, usize, PatchInteraction)> = Vec::new();
    let mut hits: Vec<WallHit> = Vec::new();
    // the walls where they are at the end of the step (this stage follows the move)
    let poses: Vec<Option<Pose>> = walls.0.iter().map(|w| w.pose(clock.time())).collect();
    for (e, id, g, mut x, mut v, d, cg) in q.iter_mut() {
        let r = 0.5 * d.0;
        for (k, w) in walls.0.iter().enumerate() {
            let Some((t, surface, outcome)) = impulse(w, poses[k], x.0, v.0, r) else {
                continue;
            };
            let wears = !matches!(outcome, Err(PatchInteraction::Escape));
            if wears && erosion.as_ref().is_some_and(|l| l.wants_wall(k)) {
                let key = (k as u32, t.element);
                hits.push((key, v.0 - surface, t.normal, represented_mass(cg), id.0));
            }
            match outcome {
                Ok((x1, v1)) => {
                    x.0 = x1;
                    v.0 = v1;
                }
                Err(m) => {
                    gone.push((id.0, g.0, e, k, m));
                    break;
                }
            }
        }
    }
    if let Some(mut l) = erosion
        && !hits.is_empty()
    {
        l.add_walls(hits);
    }
    gone.sort_unstable_by_key(|g| g.0);
    for (_, g, e, k, m) in gone {
        let list = if m == PatchInteraction::Stick {
            &mut log.stuck
        } else {
            &mut log.escaped
        };
        if let Some(c) = list.get_mut(k).and_then(|w| w.get_mut(g as usize)) {
            *c += 1;
        }
        commands.entity(e).despawn();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::patch_interaction::{WallFriction, coulomb_rebound};
    use crate::physics::wall_shape::WallShape;
    use glam::DVec3;

    fn floor(model: PatchInteraction) -> ImpulseWall {
        ImpulseWall {
            wall: Wall {
                name: "floor".into(),
                shape: WallShape::Plane {
                    point: DVec3::ZERO,
                    normal: DVec3::Z,
                },
                motion: Default::default(),
            },
            model,
        }
    }

    /// A sphere overlapping a floor by 0.3 r leaves it at touching distance with the
    /// impulse rebound's velocity; stick and escape report their model; a sphere clear of
    /// the floor is left alone.
    #[test]
    fn a_touching_sphere_rebounds_to_touching_distance() {
        let w = floor(PatchInteraction::Rebound {
            e: 0.5,
            mu: 0.2,
            friction: WallFriction::Coulomb,
        });
        let (x, v) = (DVec3::new(1.0, 2.0, 0.7e-3), DVec3::new(3.0, 0.0, -2.0));
        let Some((t, surface, Ok((x1, v1)))) = impulse(&w, None, x, v, 1e-3) else {
            panic!()
        };
        assert_eq!(surface, DVec3::ZERO);
        assert_eq!((t.normal, t.element), (DVec3::Z, 0));
        assert!((x1 - DVec3::new(1.0, 2.0, 1e-3)).length() < 1e-15);
        assert_eq!(v1, coulomb_rebound(v, -DVec3::Z, 0.5, 0.2));
        assert!((v1.z - 1.0).abs() < 1e-12);
        assert_eq!(impulse(&w, None, DVec3::new(0.0, 0.0, 2e-3), v, 1e-3), None);
        let s = floor(PatchInteraction::Stick);
        assert_eq!(
            impulse(&s, None, x, v, 1e-3).map(|o| o.2),
            Some(Err(PatchInteraction::Stick))
        );
    }

    /// A floor rising at 2 m/s and turning about z at 50 rad/s through the origin: a sphere
    /// touching it at t = 10 ms (the floor at z = 20 mm) rebounds the velocity relative to
    /// the surface at the contact point, V = (0, 5, 2) m/s: (v' − V)·n = −e·(v − V)·n, the
    /// relative tangential velocity kept (μ = 0), and leaves at touching distance.
    #[test]
    fn a_moving_wall_rebounds_the_relative_velocity() {
        use crate::physics::wall_motion::WallMotion;
        let mut w = floor(PatchInteraction::frictionless(0.6));
        w.wall.motion = WallMotion {
            velocity: DVec3::new(0.0, 0.0, 2.0),
            angular_velocity: DVec3::new(0.0, 0.0, 50.0),
            centre: DVec3::ZERO,
        };
        let (x, v) = (
            DVec3::new(0.1, 0.0, 0.02 + 0.7e-3),
            DVec3::new(1.0, 0.0, -3.0),
        );
        let Some((t, surface, Ok((x1, v1)))) = impulse(&w, w.pose(0.01), x, v, 1e-3) else {
            panic!()
        };
        assert!((t.normal - DVec3::Z).length() < 1e-15);
        assert!(
            (surface - DVec3::new(0.0, 5.0, 2.0)).length() < 1e-12,
            "{surface}"
        );
        assert!(((v1 - surface).z + 0.6 * (v - surface).z).abs() < 1e-12);
        assert!((v1 - DVec3::new(1.0, 0.0, 5.0)).length() < 1e-12, "{v1}");
        assert!((x1 - DVec3::new(0.1, 0.0, 0.021)).length() < 1e-15);
        // at t = 0 the same sphere is 20 mm above the floor
        assert_eq!(impulse(&w, w.pose(0.0), x, v, 1e-3), None);
    }
}
