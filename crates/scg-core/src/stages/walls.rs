//! Walls: normal contact forces between particles and rigid walls.
//!
//! A wall is treated as a body of the same material with infinite radius and mass, so a
//! contact has R* = d/2, m* = m and E* from the material. When the material has friction
//! (or the contacts effect sets rolling friction) [`wall_contact_forces`] replaces
//! [`wall_normal_forces`]: the same normal force plus the tangential Mindlin spring with
//! per-particle history ([`WallHistory`]), the Coulomb limit, and the torque −r·n × F_t.
//!
//! A mesh wall ([`WallShape::Mesh`]) may touch a particle in several places (a sphere in
//! a corner touches two faces): each contact gets the same law. Its tangential history is
//! keyed by (wall, flat region): a particle sliding from one triangle to the next of a flat
//! region keeps its spring. History keys ([`history_keys`]): analytic wall `i` has key
//! `i`; mesh walls' regions take the keys after the last wall, in wall order.

use bevy_ecs::prelude::*;
use glam::DVec3;

use super::contacts::ContactState;
use super::table::{bypass, columns_mut};
use crate::checkpoint::records::{Checkpoint, Part, Persist, Persistence};
use crate::components::*;
use crate::exec::par::{Rows, for_each_listed_piece};
use crate::physics::contact::model::{ContactModel, wall_geometry};
use crate::physics::contact::{Material, NormalLaw, TangentialLaw};
use crate::physics::trimesh::{MeshContact, MeshScratch};
use crate::physics::wall_motion::{Pose, WallMotion};
use crate::physics::wall_shape::{WallShape, WallTouch};
use crate::state::{ContactResolution, SimClock};
use crate::step::{StepBuilder, StepSet, StepSystem};

/// A named wall.
#[derive(Clone, Debug, PartialEq)]
pub struct Wall {
    /// Name (for recordings and messages).
    pub name: String,
    /// Geometry (where the wall is at t = 0: its rest frame).
    pub shape: WallShape,
    /// Its prescribed motion ([`WallMotion::FIXED`] for a wall at rest).
    pub motion: WallMotion,
}

impl WallSet {
    /// True when some wall moves.
    pub fn any_moving(&self) -> bool {
        self.walls.iter().any(|w| !w.motion.is_fixed())
    }

    /// Each wall's pose at time `t` (s); `None` for a wall at rest.
    pub fn poses(&self, t: f64) -> Vec<Option<Pose>> {
        self.walls
            .iter()
            .map(|w| (!w.motion.is_fixed()).then(|| w.motion.pose(t)))
            .collect()
    }

    /// True when the sphere at `x` (m) of radius `r` (m) is surely clear of every wall
    /// (posed by `poses`, [`WallSet::poses`]).
    #[inline(always)]
    fn surely_clear(&self, poses: &[Option<Pose>], x: DVec3, r: f64) -> bool {
        self.walls.iter().zip(poses).all(|(w, p)| match p {
            None => w.shape.surely_clear(x, r),
            Some(p) => w.shape.surely_clear(p.to_rest(x), r),
        })
    }
}

/// The scene's walls and their contact law (resource).
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct WallSet {
    /// The walls.
    pub walls: Vec<Wall>,
    /// Normal contact law.
    pub law: NormalLaw,
    /// Wall material (also the particles' when the scene has no particle contacts).
    pub material: Material,
}

/// Tangential law of wall contacts (resource; present only when it is active).
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct WallTangential {
    /// The law.
    pub law: TangentialLaw,
    /// Effective shear modulus G* (particle against wall), Pa.
    pub g_eff: f64,
}

impl WallTangential {
    /// The tangential law of wall contacts: the wall material's friction, with the rolling
    /// friction and stiffness rule of the particle contacts' law when the scene declares
    /// contacts (`particles`), and the wall's own damping factor.
    pub fn new(walls: &WallSet, particles: Option<TangentialLaw>) -> Self {
        let friction = walls.material.friction;
        let law = match particles {
            Some(p) => TangentialLaw { friction, ..p },
            None => TangentialLaw::new(walls.law, friction, 0.0),
        };
        WallTangential {
            law: TangentialLaw {
                damping: crate::physics::contact::tangential::damping_factor(walls.law),
                ..law
            },
            // A wall of the same material: G* = G/(2(2 − ν)).
            g_eff: walls.material.effective_shear_modulus(),
        }
    }
}

/// The rows that may touch a wall until the particle contacts' neighbour list is next
/// rebuilt (resource): a wall list riding on the Verlet list, as LIGGGHTS keeps one for
/// its mesh walls.
///
/// Between two builds of the neighbour list no particle moves more than half its skin
/// (the list's rebuild rule), and walls at rest do not move (with a moving wall no rows
/// are listed: every particle is visited every step). So a particle whose sphere,
/// grown by half the skin, was surely clear of every wall when the list was built, and
/// whose wall history was empty, touches no wall until the next build: its wall force,
/// torque and history stay zero and empty, and the wall stage passes it by. At the first
/// wall stage after each build (or a change of the particle table, which rebuilds the
/// list) every particle is visited, as without contacts, and the candidates are listed
/// again. Scenes without particle contacts visit every particle every step.
#[derive(Resource, Debug, Default)]
pub struct WallCandidates {
    /// The neighbour list's build count when the rows were listed (`None`: not yet).
    built_at: Option<u64>,
    /// Rows of the particle table that may touch a wall, ascending.
    rows: Vec<u32>,
}

impl WallCandidates {
    /// The candidate rows, when the scene has particle contacts (`contacts`) and they were
    /// listed since the last build of its neighbour list; `None`: visit every row.
    pub fn current(&self, contacts: Option<&ContactState>) -> Option<&[u32]> {
        let list = &contacts?.list;
        (self.built_at == Some(list.builds)).then_some(&self.rows[..])
    }

    /// After a wall stage that visited every particle (no [`WallCandidates::current`]
    /// rows) in a scene with particle contacts, list the candidates: the rows with a
    /// wall history (`busy`) or whose sphere grown by half the neighbour list's skin is
    /// not surely clear of every wall. Does nothing otherwise.
    fn refresh(
        &mut self,
        contacts: Option<&ContactState>,
        walls: &WallSet,
        xs: &[Position],
        ds: &[Diameter],
        busy: impl Fn(usize) -> bool,
    ) {
        let Some(list) = contacts.map(|c| &c.list) else {
            return;
        };
        // Moving walls come to the particles: every particle is visited every step.
        if self.built_at == Some(list.builds) || walls.any_moving() {
            return;
        }
        let half = 0.5 * list.skin;
        self.rows.clear();
        for i in 0..xs.len() {
            // A relative 1e-6 on top: the rounding of positions and of the clearance
            // test never decides.
            let reach = (0.5 * ds[i].0 + half) * (1.0 + 1e-6);
            if busy(i)
                || !walls
                    .walls
                    .iter()
                    .all(|w| w.shape.surely_clear(xs[i].0, reach))
            {
                self.rows.push(i as u32);
            }
        }
        self.built_at = Some(list.builds);
    }
}

/// On a restore the wall candidates are listed again at the first step (the restored
/// neighbour list's build count may equal the one they were listed at); nothing is saved.
struct CandidatesReset;

impl Persist for CandidatesReset {
    fn part(&self) -> Option<Part> {
        None
    }

    fn save(&self, _: &World, _: &mut Checkpoint) {}

    fn restore(&self, world: &mut World, _: &Checkpoint) -> Result<(), String> {
        *world.resource_mut::<WallCandidates>() = WallCandidates::default();
        Ok(())
    }
}

/// Add the wall systems: normal forces only, or with the tangential law when given.
pub fn plugin(world: &mut World, b: &mut StepBuilder, tangential: Option<WallTangential>) {
    world.insert_resource(WallCandidates::default());
    Persistence::register(world, CandidatesReset);
    match tangential {
        Some(t) if t.law.active() => {
            world.insert_resource(t);
            b.add(
                StepSet::Forces,
                "walls",
                StepSystem::WallContactForces,
                wall_contact_forces,
            );
        }
        _ => b.add(
            StepSet::Forces,
            "walls",
            StepSystem::WallNormalForces,
            wall_normal_forces,
        ),
    }
}

/// Normal force of every wall on every particle touching it.
pub fn wall_normal_forces(
    walls: Res<WallSet>,
    clock: Res<SimClock>,
    resolution: Res<ContactResolution>,
    contacts: Option<Res<ContactState>>,
    mut candidates: ResMut<WallCandidates>,
    mut q: Query<(&Position, &Velocity, &Diameter, &Mass, &mut Force)>,
) {
    let walls = &*walls;
    let resolution = &*resolution;
    let dt = clock.dt;
    let e_eff = walls.material.effective_modulus();
    let Some((xs, vs, ds, ms, fs)) = columns_mut(&mut q) else {
        return;
    };
    let keys = history_keys(&walls.walls);
    let poses = walls.poses(clock.time());
    let contacts = contacts.as_deref();
    let current = candidates.current(contacts);
    let columns = (xs, vs, ds, ms, bypass(fs), Rows(0..xs.len()));
    for_each_listed_piece(columns, current, |(xs, vs, ds, ms, fs, rows)| {
        let (mut scratch, mut found) = (MeshScratch::default(), Vec::new());
        let visit = |i: usize| {
            let (x, v, r, m) = (xs[i].0, vs[i].0, 0.5 * ds[i].0, ms[i].0);
            let mut sum = DVec3::ZERO;
            let touches = Touches {
                walls,
                keys: &keys,
                poses: &poses,
            };
            touches.each(x, r, &mut scratch, &mut found, |t, _, wall_velocity| {
                let vn = (v - wall_velocity).dot(t.normal);
                if vn < 0.0 && t.overlap <= -vn * dt {
                    // No history here: the contact started within the last step (one
                    // step ago, at this speed, the sphere was clear of the wall).
                    resolution.note_wall(walls.law.contact_time(m, r, e_eff, -vn));
                }
                let (fn_, _) = walls.law.force(t.overlap, vn, e_eff, r, m);
                sum += fn_ * t.normal;
            });
            // The walls are the only writer of Force: set, not accumulate (no clearing
            // pass).
            fs[i].0 = sum;
        };
        // With candidates, the others' forces are zero since the last visit of every
        // particle.
        rows.visit(current, visit);
    });
    candidates.refresh(contacts, walls, xs, ds, |_| false);
}

/// The walls as the force systems visit them: their history keys ([`history_keys`]) and
/// poses at this step ([`WallSet::poses`]).
struct Touches<'a> {
    walls: &'a WallSet,
    keys: &'a [u32],
    poses: &'a [Option<Pose>],
}

impl Touches<'_> {
    /// Every touch of the sphere at `x` (m) of radius `r` (m) with the walls, with its
    /// history key and the wall's surface velocity at the contact point (m/s; zero at
    /// rest): one per touched analytic wall, one per touched feature of a mesh wall. A
    /// moving wall is touched in its rest frame and the touch turned back into the world.
    /// Always inlined: the wall stages' loops are mostly this.
    #[inline(always)]
    fn each(
        &self,
        x: DVec3,
        r: f64,
        scratch: &mut MeshScratch,
        found: &mut Vec<MeshContact>,
        mut f: impl FnMut(WallTouch, u32, DVec3),
    ) {
        for ((wall, &key), pose) in self.walls.walls.iter().zip(self.keys).zip(self.poses) {
            let xr = match pose {
                None => x,
                Some(p) => p.to_rest(x),
            };
            // A touch in the rest frame, in the world: its normal turned, the surface
            // velocity at the contact point (−r·n from the centre).
            let mut world = |t: WallTouch, key: u32| match pose {
                None => f(t, key, DVec3::ZERO),
                Some(p) => {
                    let normal = p.to_world_direction(t.normal);
                    let v = p.velocity_at(x - r * normal);
                    f(
                        WallTouch {
                            overlap: t.overlap,
                            normal,
                            element: t.element,
                        },
                        key,
                        v,
                    )
                }
            };
            match &wall.shape {
                WallShape::Mesh(mesh) => {
                    if mesh.surely_clear(xr, r) {
                        continue;
                    }
                    mesh.contacts(xr, r, scratch, found);
                    for c in found.iter() {
                        let t = WallTouch {
                            overlap: c.overlap,
                            normal: c.normal,
                            element: c.triangle,
                        };
                        world(t, key + c.region);
                    }
                }
                shape => {
                    if let Some(t) = shape.touch(xr, r) {
                        world(t, key);
                    }
                }
            }
        }
    }
}

/// History key of each wall's first contact: analytic wall `i` → `i`; a mesh wall's
/// region `k` → its entry + `k`, mesh walls' regions numbered from `walls.len()` on.
pub fn history_keys(walls: &[Wall]) -> Vec<u32> {
    let mut next = walls.len() as u32;
    walls
        .iter()
        .enumerate()
        .map(|(i, w)| match &w.shape {
            WallShape::Mesh(m) => {
                let k = next;
                next += m.region_count();
                k
            }
            _ => i as u32,
        })
        .collect()
}

type WallQuery<'w, 's> = Query<
    'w,
    's,
    (
        &'static Position,
        &'static Velocity,
        &'static AngularVelocity,
        &'static Diameter,
        &'static Mass,
        &'static mut Force,
        &'static mut Torque,
        &'static mut WallHistory,
    ),
>;

/// Normal and tangential force, and torque, of every wall on every particle touching it.
pub fn wall_contact_forces(
    walls: Res<WallSet>,
    tangential: Res<WallTangential>,
    clock: Res<SimClock>,
    resolution: Res<ContactResolution>,
    contacts: Option<Res<ContactState>>,
    mut candidates: ResMut<WallCandidates>,
    mut q: WallQuery,
) {
    let walls = &*walls;
    let dt = clock.dt;
    let resolution = &*resolution;
    let model = ContactModel {
        law: walls.law,
        tangential: tangential.law,
        e_eff: walls.material.effective_modulus(),
        g_eff: tangential.g_eff,
    };
    let keys = history_keys(&walls.walls);
    let poses = walls.poses(clock.time());
    let touches = Touches {
        walls,
        keys: &keys,
        poses: &poses,
    };
    let touches = &touches;
    // One particle: its wall forces and torque, its history updated in place.
    let one = move |x: DVec3,
                    v: DVec3,
                    w: DVec3,
                    d: f64,
                    m: f64,
                    hist: &mut Vec<(u32, DVec3)>,
                    scratch: &mut MeshScratch,
                    found: &mut Vec<MeshContact>|
          -> (DVec3, DVec3) {
        let r = 0.5 * d;
        let (mut fsum, mut tsum) = (DVec3::ZERO, DVec3::ZERO);
        let old_len = hist.len();
        // One contact (history key `key`) with a wall whose surface moves at
        // `wall_velocity` there: the geometry, then the model (normal → damping →
        // tangential → rolling).
        let mut contact = |t: WallTouch,
                           key: u32,
                           wall_velocity: DVec3,
                           hist: &mut Vec<(u32, DVec3)>| {
            let g = wall_geometry(t.normal, t.overlap, r, m, v, w, wall_velocity);
            let prev = match hist[..old_len].iter().find(|h| h.0 == key) {
                Some(h) => h.1,
                None => {
                    // The contact starts: its duration at this approach speed.
                    resolution.note_wall(model.law.contact_time(m, r, model.e_eff, -g.separation));
                    DVec3::ZERO
                }
            };
            let resp = model.response(&g, None, prev, dt);
            fsum += resp.normal * g.normal;
            let mut xi = DVec3::ZERO;
            if let Some(u) = resp.tangential {
                xi = u.history;
                fsum += u.force;
                tsum += (-r * g.normal).cross(u.force);
            }
            if model.tangential.rolling > 0.0 {
                tsum += model.rolling(resp.normal, r, w);
            }
            hist.push((key, xi));
        };
        touches.each(x, r, scratch, found, |t, key, vw| contact(t, key, vw, hist));
        // Keep only the contacts of this step (appended after the old entries).
        if old_len > 0 {
            hist.drain(..old_len);
        }
        (fsum, tsum)
    };
    // The walls are the only writer of Force and Torque: they are set, not accumulated
    // (no clearing pass). A particle whose history is empty touched no wall last step (a
    // touch always leaves an entry), so its force and torque are zero: when it is clear of
    // every wall now it is not written at all. Between builds of the neighbour list only
    // the candidates are visited ([`WallCandidates`]).
    let Some((xs, vs, ws, ds, ms, fs, ts, hs)) = columns_mut(&mut q) else {
        return;
    };
    let contacts = contacts.as_deref();
    let current = candidates.current(contacts);
    let hs = bypass(hs);
    let columns = (
        (xs, vs, ws, ds, ms),
        (bypass(fs), bypass(ts), &mut *hs),
        Rows(0..xs.len()),
    );
    for_each_listed_piece(
        columns,
        current,
        |((xs, vs, ws, ds, ms), (fs, ts, hs), rows)| {
            let (mut scratch, mut found) = (MeshScratch::default(), Vec::new());
            let visit = |i: usize| {
                let r = 0.5 * ds[i].0;
                if hs[i].0.is_empty() && walls.surely_clear(&poses, xs[i].0, r) {
                    return;
                }
                let (f, t) = one(
                    xs[i].0,
                    vs[i].0,
                    ws[i].0,
                    ds[i].0,
                    ms[i].0,
                    &mut hs[i].0,
                    &mut scratch,
                    &mut found,
                );
                fs[i].0 = f;
                ts[i].0 = t;
            };
            rows.visit(current, visit);
        },
    );
    candidates.refresh(contacts, walls, xs, ds, |i| !hs[i].0.is_empty());
}
