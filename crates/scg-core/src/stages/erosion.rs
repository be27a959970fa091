//! Wall erosion (`[erosion]`): every impact of a particle on a wall patch of the mesh
//! flow, or on a `[[walls]]` entry (STL or analytic), that rebounds or sticks, worn into
//! the face (the STL triangle; an analytic wall is one face) it hit by the scene's
//! [`ErosionModel`], with the original powder's mass the particle stands for (α³
//! originals under every coarse-graining law).
//!
//! The mesh integration hands over the step's impacts ([`WallImpact`] from the landing,
//! the first of each particle's step), the impulse walls theirs; they are summed per face
//! in a canonical order (face, then the impact's bits), so the log is the same whatever
//! the thread count. Contact-law walls (whose impacts last several steps) are not logged.

use std::collections::BTreeMap;

use bevy_ecs::prelude::*;
use glam::DVec3;

use crate::checkpoint::records::{Checkpoint, Part, Persist, Persistence};
use crate::components::CoarseGrain;
use crate::frame::{WearMap, WearPatch};
use crate::physics::erosion::{ErosionModel, impact_angle};
use crate::physics::mesh_flow::WallImpact;
use crate::physics::scaling::represented_volume;
use crate::physics::wall_shape::WallShape;
use crate::stages::impulse_walls::ImpulseWalls;
use crate::stages::mesh_flow::MeshFlowState;

/// What one face has taken.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FaceWear {
    /// Impacts (simulated particles).
    pub impacts: u64,
    /// Original powder's mass of those impacts, kg.
    pub mass: f64,
    /// Wall volume removed, m³.
    pub volume: f64,
    /// Σ m·θ over the impacts: mass-weighted impact angle to the wall plane, kg·rad.
    pub angle_mass: f64,
    /// Σ m·v_n: mass-weighted normal (into the wall) impact speed, kg·m/s.
    pub normal_mass: f64,
    /// Σ m·|v_t|: mass-weighted tangential impact speed, kg·m/s.
    pub tangential_mass: f64,
}

impl FaceWear {
    /// Σ m·x over the powder mass that struck (0 where none did).
    fn mean(&self, sum: f64) -> f64 {
        if self.mass > 0.0 {
            sum / self.mass
        } else {
            0.0
        }
    }

    /// Mean impact angle to the wall plane over the powder mass that struck, rad (0
    /// where none did).
    pub fn mean_angle(&self) -> f64 {
        self.mean(self.angle_mass)
    }

    /// Mean normal impact speed over the powder mass that struck, m/s (0 where none did).
    pub fn mean_normal_speed(&self) -> f64 {
        self.mean(self.normal_mass)
    }

    /// Mean tangential impact speed over the powder mass that struck, m/s (0 where none
    /// did).
    pub fn mean_tangential_speed(&self) -> f64 {
        self.mean(self.tangential_mass)
    }
}

/// What `[erosion]` logs: the model, per patch of the mesh flow and per impulse wall
/// (`[[walls]]` that rebound, stick or escape, in their order) whether it is logged.
#[derive(Clone, Debug, PartialEq)]
pub struct ErosionSpec {
    /// The model.
    pub model: ErosionModel,
    /// Per patch of the mesh flow (empty without one).
    pub patches: Vec<bool>,
    /// Per impulse wall.
    pub walls: Vec<bool>,
}

/// The erosion log (resource, with `[erosion]`).
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct ErosionLog {
    /// The model.
    pub model: ErosionModel,
    /// Per patch of the mesh: logged or not.
    pub patches: Vec<bool>,
    /// Per impulse wall: logged or not.
    pub walls: Vec<bool>,
    /// Per mesh face hit.
    pub faces: BTreeMap<u32, FaceWear>,
    /// Per impulse-wall face hit: (wall, triangle; 0 for an analytic wall).
    pub wall_faces: BTreeMap<(u32, u32), FaceWear>,
    /// Per particle that wore a wall: its id and the volume it removed, m³ (the
    /// interval of the total resamples particles).
    pub by_particle: BTreeMap<u32, f64>,
    /// Every impact as (particle id, face, volume removed m³), in the log's order, when
    /// asked for ([`ErosionLog::keep_impacts`]): a study's per-region shares resample
    /// particles from it. Not in checkpoints (a restored run keeps the impacts after it).
    pub impacts: Option<Vec<(u32, u32, f64)>>,
}

/// One impact as the integration reports it: the face, the particle's velocity and the
/// face's normal (into the fluid), the original mass it stands for (kg) and its id.
pub type Impact = (u32, DVec3, DVec3, f64, u32);

/// One impact on an impulse wall: (wall, triangle), then as [`Impact`].
pub type WallHit = ((u32, u32), DVec3, DVec3, f64, u32);

/// The original powder's mass a particle stands for: α³ originals, kg.
#[inline]
pub fn represented_mass(cg: &CoarseGrain) -> f64 {
    cg.original_density * represented_volume(cg.alpha, cg.original_diameter)
}

impl ErosionLog {
    /// A log of `spec.model` on the patches and walls it flags.
    pub fn new(spec: ErosionSpec) -> Self {
        ErosionLog {
            model: spec.model,
            patches: spec.patches,
            walls: spec.walls,
            faces: BTreeMap::new(),
            wall_faces: BTreeMap::new(),
            by_particle: BTreeMap::new(),
            impacts: None,
        }
    }

    /// Keep every impact from now on ([`ErosionLog::impacts`]).
    pub fn keep_impacts(&mut self) {
        self.impacts.get_or_insert_with(Vec::new);
    }

    /// The impact of a landing worth logging: on a logged patch (`patch_of` gives a face's
    /// patch).
    pub fn wants(&self, patch: u32) -> bool {
        self.patches.get(patch as usize).copied().unwrap_or(false)
    }

    /// Whether impulse wall `wall`'s impacts are logged.
    pub fn wants_wall(&self, wall: usize) -> bool {
        self.walls.get(wall).copied().unwrap_or(false)
    }

    /// Add a step's impacts on mesh faces (in any order: they are sorted first).
    pub fn add(&mut self, mut impacts: Vec<Impact>) {
        impacts.sort_unstable_by_key(|i| (i.0, bits(i)));
        for (face, v, n, m, id) in impacts {
            let q = wear(self.model, self.faces.entry(face).or_default(), v, n, m);
            *self.by_particle.entry(id).or_default() += q;
            if let Some(v) = &mut self.impacts {
                v.push((id, face, q));
            }
        }
    }

    /// Add a step's impacts on impulse walls (in any order: they are sorted first).
    pub fn add_walls(&mut self, mut hits: Vec<WallHit>) {
        hits.sort_unstable_by_key(|i| (i.0, bits(i)));
        for (key, v, n, m, id) in hits {
            let q = wear(self.model, self.wall_faces.entry(key).or_default(), v, n, m);
            *self.by_particle.entry(id).or_default() += q;
        }
    }

    /// The total volume (m³) and its 95 % interval over `fed` particles (every particle
    /// that entered, the ones that wore nothing as zeros): the total is N times the mean
    /// wear per particle, whose standard error is the particles' standard deviation over
    /// √N (a normal interval: N in the thousands).
    pub fn total_interval(&self, fed: u64) -> (f64, f64, f64) {
        let total = self.total_volume();
        let n = fed.max(self.by_particle.len() as u64) as f64;
        if n < 2.0 {
            return (total, f64::NAN, f64::NAN);
        }
        let mean = self.by_particle.values().sum::<f64>() / n;
        let ss: f64 = self
            .by_particle
            .values()
            .map(|q| (q - mean).powi(2))
            .sum::<f64>()
            + (n - self.by_particle.len() as f64) * mean * mean;
        let se = (ss / (n - 1.0)).sqrt() * n.sqrt();
        (total, (total - 1.96 * se).max(0.0), total + 1.96 * se)
    }

    /// Total volume removed, m³.
    pub fn total_volume(&self) -> f64 {
        self.faces
            .values()
            .chain(self.wall_faces.values())
            .map(|w| w.volume)
            .sum()
    }
}

/// The bits of an impact after its face: the canonical order within a face.
fn bits<K>(i: &(K, DVec3, DVec3, f64, u32)) -> ([u64; 3], [u64; 3], u64, u32) {
    (
        i.1.to_array().map(f64::to_bits),
        i.2.to_array().map(f64::to_bits),
        i.3.to_bits(),
        i.4,
    )
}

/// Wear one impact of original mass `m` at `v` on a face of normal `n` (into the fluid)
/// into `w`; returns the volume removed, m³.
fn wear(model: ErosionModel, w: &mut FaceWear, v: DVec3, n: DVec3, m: f64) -> f64 {
    let q = model.volume(m, v, n);
    let vn = -v.dot(n);
    let vt = (v + vn * n).length();
    w.impacts += 1;
    w.mass += m;
    w.volume += q;
    w.angle_mass += m * impact_angle(v, n);
    w.normal_mass += m * vn;
    w.tangential_mass += m * vt;
    q
}

/// The record of a [`WallImpact`] for the log.
#[inline]
pub fn impact(w: &WallImpact, cg: &CoarseGrain, id: u32) -> Impact {
    (w.face, w.velocity, w.normal, represented_mass(cg), id)
}

struct ErosionPart;

impl Persist for ErosionPart {
    fn part(&self) -> Option<Part> {
        Some(Part::Erosion)
    }

    fn save(&self, world: &World, c: &mut Checkpoint) {
        let l = world.resource::<ErosionLog>();
        let sums = |w: &FaceWear| {
            let s = [
                w.mass,
                w.volume,
                w.angle_mass,
                w.normal_mass,
                w.tangential_mass,
            ];
            (w.impacts, s)
        };
        c.erosion = Some((
            l.faces
                .iter()
                .map(|(f, w)| ((u32::MAX, *f), sums(w)))
                .chain(l.wall_faces.iter().map(|(k, w)| (*k, sums(w))))
                .collect(),
            l.by_particle.iter().map(|(i, q)| (*i, *q)).collect(),
        ));
    }

    fn restore(&self, world: &mut World, c: &Checkpoint) -> Result<(), String> {
        let Some((rows, particles)) = &c.erosion else {
            return Err(Part::Erosion.mismatch());
        };
        let mut l = world.resource_mut::<ErosionLog>();
        let face = |impacts, [mass, volume, angle_mass, normal_mass, tangential_mass]: [f64; 5]| {
            FaceWear {
                impacts,
                mass,
                volume,
                angle_mass,
                normal_mass,
                tangential_mass,
            }
        };
        l.faces.clear();
        l.wall_faces.clear();
        for &((wall, f), (impacts, sums)) in rows {
            if wall == u32::MAX {
                l.faces.insert(f, face(impacts, sums));
            } else {
                l.wall_faces.insert((wall, f), face(impacts, sums));
            }
        }
        l.by_particle = particles.iter().copied().collect();
        Ok(())
    }
}

/// The wear of the logged patches and STL walls for the recorders (`None` without
/// `[erosion]`), summed up to `step` at `time` s: each mesh patch's faces fanned from
/// their first point, each STL wall's triangles as its faces, with volume, depth rate,
/// impacts and the impacts' mean angle and speeds per face. Analytic walls have no faces
/// to draw and are left out (their wear is in the log).
pub fn wear_map(world: &World, step: u64, time: f64) -> Option<WearMap> {
    let log = world.get_resource::<ErosionLog>()?;
    let t = time.max(f64::MIN_POSITIVE);
    let mut patches = Vec::new();
    let push = |w: &mut WearPatch, face: u32, wear: FaceWear, area: f64| {
        w.faces.push(face);
        w.volume.push(wear.volume);
        w.depth_rate.push(wear.volume / (area * t));
        w.impacts.push(wear.impacts);
        w.angle.push(wear.mean_angle());
        w.normal_speed.push(wear.mean_normal_speed());
        w.tangential_speed.push(wear.mean_tangential_speed());
    };
    if let Some(state) = world.get_resource::<MeshFlowState>() {
        let flow = &state.spec.flow;
        let (mesh, g) = (flow.mesh(), flow.geometry());
        for (p, _) in mesh.patches.iter().zip(&log.patches).filter(|(_, on)| **on) {
            let mut w = WearPatch {
                name: p.name.clone(),
                ..Default::default()
            };
            let mut index = std::collections::HashMap::new();
            for (k, f) in (p.start..p.start + p.size).enumerate() {
                let ids: Vec<u32> = mesh
                    .face(f)
                    .iter()
                    .map(|&q| {
                        *index.entry(q).or_insert_with(|| {
                            w.vertices.push(mesh.points[q as usize].to_array());
                            (w.vertices.len() - 1) as u32
                        })
                    })
                    .collect();
                for j in 1..ids.len().saturating_sub(1) {
                    w.triangles.push([ids[0], ids[j], ids[j + 1]]);
                    w.triangle_face.push(k as u32);
                }
                let wear = log.faces.get(&(f as u32)).copied().unwrap_or_default();
                push(&mut w, f as u32, wear, g.face_areas[f].length());
            }
            patches.push(w);
        }
    }
    if let Some(walls) = world.get_resource::<ImpulseWalls>() {
        for (k, iw) in walls.0.iter().enumerate() {
            let WallShape::Mesh(m) = &iw.wall.shape else {
                continue;
            };
            if !log.wants_wall(k) {
                continue;
            }
            let mut w = WearPatch {
                name: iw.wall.name.clone(),
                vertices: m.vertices().iter().map(|v| v.to_array()).collect(),
                triangles: m.triangles().to_vec(),
                ..Default::default()
            };
            for j in 0..m.triangles().len() as u32 {
                let wear = log.wall_faces.get(&(k as u32, j)).copied();
                let (_, area) = iw.wall.shape.face(j).expect("a mesh wall's triangle");
                w.triangle_face.push(j);
                push(&mut w, j, wear.unwrap_or_default(), area);
            }
            patches.push(w);
        }
    }
    Some(WearMap {
        model: log.model.name().to_string(),
        step,
        time,
        patches,
    })
}

/// Add the erosion log (the mesh integration and the impulse walls fill it).
pub fn plugin(world: &mut World, log: ErosionLog) {
    world.insert_resource(log);
    Persistence::register(world, ErosionPart);
}
