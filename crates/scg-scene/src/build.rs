//! Scene → core: the [`SimConfig`], the feeders and the outlet ([`InletOutlet`]), the
//! initial particles, the [`Simulation`], and the [`RunMeta`] (with the walls' outlines)
//! that recorders store.
//!
//! Every number of steps derived from the time step is computed here, from the scene's
//! current `dt`: the run length ([`Scene::steps`]) and the feeders' and the outlet's
//! intervals ([`Scene::interval_steps`]).

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use scg_core::frame::{GroupMeta, Outline, PatchSurface, RunMeta};
use scg_core::physics::contact::{Material, NormalLaw};
use scg_core::physics::wall_shape::WallShape;
use scg_core::sim::InletOutlet;
use scg_core::stages::feeder::{FeederSpec, SizeFeed, Spin};
use scg_core::stages::mesh_flow::MeshFlowSpec;
use scg_core::stages::outlet::OutletSpec;
use scg_core::stages::walls::WallSet;
use scg_core::{ParticleSpec, SimConfig, Simulation};

use crate::model::{Feeder, Outlet, Placement, Region, Scene};

impl Scene {
    /// Number of steps for the duration (rounded to the nearest step).
    pub fn steps(&self) -> u64 {
        (self.duration / self.dt).round().max(1.0) as u64
    }

    /// Particles the scene holds at the start (every group's listed positions or count).
    pub fn initial_count(&self) -> u64 {
        self.groups
            .iter()
            .map(|g| match &g.placement {
                Placement::Explicit { positions, .. } => positions.len() as u64,
                Placement::Random { count, .. } => *count as u64,
            })
            .sum()
    }

    /// Particles feeder `f` has fed after `steps` steps (exact, as the feeder counts them;
    /// a feeder with a release interval releases at most this many).
    pub fn fed_after(&self, f: &Feeder, steps: u64) -> u64 {
        scg_core::stages::feeder::fed_by(f.rate, f.window.0, f.window.1, steps as f64 * self.dt)
    }

    /// Particles the scene has held after `steps` steps if none left: its groups' at the
    /// start plus every feeder's ([`Scene::fed_after`]).
    pub fn particles_after(&self, steps: u64) -> u64 {
        (self.feeders.iter()).fold(self.initial_count(), |n, f| {
            n.saturating_add(self.fed_after(f, steps))
        })
    }

    /// Steps per `interval` seconds at the current `dt` (rounded to the nearest step, at
    /// least 1): how often a feeder releases and the outlet checks.
    pub fn interval_steps(&self, interval: f64) -> u64 {
        ((interval / self.dt).round() as u64).max(1)
    }

    /// The core's view of a feeder.
    fn feeder_spec(&self, f: &Feeder) -> FeederSpec {
        let g = &self.groups[f.group];
        FeederSpec {
            group: f.group as u32,
            diameter: g.diameter,
            density: g.density,
            alpha: g.alpha,
            law: g.law,
            rate: f.rate,
            source: f.source.clone(),
            velocity: f.velocity,
            field_velocity: f.field_velocity,
            spin: self.flow.vortex().filter(|_| f.swirl != 0.0).map(|v| Spin {
                center: v.center,
                omega: v.axis * (v.omega * f.swirl),
            }),
            by_flux: f.by_flux,
            start: f.window.0,
            stop: f.window.1,
            every: self.interval_steps(f.interval),
            size: g.size.as_ref().map(|s| SizeFeed {
                distribution: s.distribution.clone(),
                edges: s.edges.clone(),
                first_group: f.group as u32,
            }),
        }
    }

    /// The core's view of the outlet.
    fn outlet_spec(&self, o: &Outlet) -> OutletSpec {
        OutletSpec {
            geometry: o.geometry,
            every: self.interval_steps(o.interval),
        }
    }

    /// The feeders and outlet for the core.
    pub fn inlet_outlet(&self) -> InletOutlet {
        InletOutlet {
            feeders: self.feeders.iter().map(|f| self.feeder_spec(f)).collect(),
            outlet: self.outlet.as_ref().map(|o| self.outlet_spec(o)),
            seed: self.seed,
            impulse_walls: self.impulse_walls.clone(),
            erosion: self.erosion.clone(),
            collect_zones: self
                .zones
                .iter()
                .filter(|z| z.collects)
                .map(|z| {
                    // whole steps, rounded up: at least the time asked
                    let steps = (z.collects_after / self.dt - 1e-9).ceil().max(0.0) as u64;
                    (z.region.clone(), steps)
                })
                .collect(),
        }
    }

    /// The core configuration.
    pub fn sim_config(&self, record: bool) -> SimConfig {
        SimConfig {
            dt: self.dt,
            integrator: self.integrator,
            drag: self.drag,
            fluid: self.fluid,
            flow: self.flow,
            mesh_flow: self.mesh_flow.as_ref().map(|m| MeshFlowSpec {
                flow: m.flow.clone(),
                interactions: self.patch_models.iter().map(|p| p.interaction).collect(),
                sort_every: m.sort_every,
                series: m.series.as_ref().map(|s| s.spec.clone()),
            }),
            gravity: self.gravity,
            buoyancy: self.buoyancy,
            scg_at_original: self.scg_at_original,
            extra_forces: self.extra_forces,
            walls: (self.contact_walls().next().is_some()).then(|| WallSet {
                walls: self.contact_walls().cloned().collect(),
                law: self.normal_law.unwrap_or(NormalLaw::hertz(1.0)),
                material: self.material.unwrap_or(Material {
                    youngs_modulus: 1e7,
                    poisson_ratio: 0.3,
                    restitution: 1.0,
                    friction: 0.0,
                }),
            }),
            contacts: self.contacts,
            record_every: record.then_some(self.record_every),
            groups: self.groups.iter().map(|g| g.name.clone()).collect(),
            carrier: self
                .dispersion
                .clone()
                .map(scg_core::stages::carrier::CarrierModifier::Dispersion),
        }
    }

    /// The particles at the start, in spawn order (ids follow this order).
    pub fn initial_particles(&self) -> Vec<ParticleSpec> {
        let mut out = Vec::new();
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        for (gi, g) in self.groups.iter().enumerate() {
            let spec = |position: DVec3, velocity: DVec3| ParticleSpec {
                group: gi as u32,
                diameter: g.diameter,
                density: g.density,
                alpha: g.alpha,
                law: g.law,
                position,
                velocity,
            };
            match &g.placement {
                Placement::Explicit {
                    positions,
                    velocities,
                } => {
                    for (p, v) in positions.iter().zip(velocities) {
                        out.push(spec(*p, *v));
                    }
                }
                Placement::Random {
                    count,
                    region,
                    velocity,
                } => {
                    for _ in 0..*count {
                        out.push(spec(region.sample(&mut rng), *velocity));
                    }
                }
            }
        }
        out
    }

    /// Build the simulation with its particles (recording stage included when `record`).
    pub fn build(&self, record: bool) -> Simulation {
        let mut sim = Simulation::with_inlet_outlet(self.sim_config(record), self.inlet_outlet());
        for p in self.initial_particles() {
            sim.spawn(&p);
        }
        sim
    }

    /// The absolute folder of the scene's relative paths ([`Scene::base_dir`]; the working
    /// folder when it is empty), as recordings store it; empty when it cannot be resolved.
    pub fn scene_dir(&self) -> String {
        let base = if self.base_dir.as_os_str().is_empty() {
            std::path::Path::new(".")
        } else {
            self.base_dir.as_path()
        };
        std::fs::canonicalize(base)
            .map(|p| p.display().to_string())
            .unwrap_or_default()
    }

    /// The scene file's absolute path, as checkpoints store it (its folder resolves the
    /// relative paths on a restart from any working folder); [`Scene::file`] as is when it
    /// names no file (the embedded scene).
    pub fn absolute_file(&self) -> String {
        std::fs::canonicalize(&self.file)
            .map(|p| p.display().to_string())
            .unwrap_or_else(|_| self.file.clone())
    }

    /// The description recorders store.
    pub fn run_meta(&self, warnings: Vec<String>) -> RunMeta {
        let size = self.extent();
        RunMeta {
            case: self.name.clone(),
            scg_version: env!("CARGO_PKG_VERSION").to_string(),
            seed: self.seed,
            dt: self.dt,
            record_every: self.record_every,
            groups: self
                .groups
                .iter()
                .map(|g| GroupMeta {
                    name: g.name.clone(),
                    law: g.law.name().to_string(),
                    alpha: g.alpha,
                    original_diameter: g.diameter,
                    color: g.color,
                })
                .collect(),
            ranks: 1,
            scene_toml: self.source.clone(),
            parts: Vec::new(),
            scene_dir: self.scene_dir(),
            outlines: self
                .walls
                .iter()
                .chain(self.impulse_walls.iter().map(|w| &w.wall))
                .map(|w| {
                    let (vertices, triangles) = match &w.shape {
                        WallShape::Mesh(m) => (
                            m.vertices().iter().map(|v| v.to_array()).collect(),
                            m.triangles().to_vec(),
                        ),
                        _ => (Vec::new(), Vec::new()),
                    };
                    Outline {
                        name: w.name.clone(),
                        strips: w.shape.outline(size),
                        vertices,
                        triangles,
                        motion: w.motion,
                    }
                })
                .collect(),
            patches: self.patch_surfaces(),
            warnings,
        }
    }

    /// Every boundary patch of the mesh flow with its role, as triangles to draw (polygons
    /// fanned from their first point), but the `empty` ones (the unresolved direction of a
    /// 2-D case: they would cover the slab); empty without a mesh flow.
    pub fn patch_surfaces(&self) -> Vec<PatchSurface> {
        use scg_mesh::surface::{Fan, patch_surface};
        let Some(m) = &self.mesh_flow else {
            return Vec::new();
        };
        let mesh = m.flow.mesh();
        (0..mesh.patches.len())
            .filter(|&i| mesh.patches[i].kind != "empty")
            .map(|i| {
                let s = patch_surface(mesh, &[i], Fan::FirstPoint);
                PatchSurface {
                    name: mesh.patches[i].name.clone(),
                    role: m.flow.role(i as u32).name().to_string(),
                    vertices: s.vertices.iter().map(|v| v.to_array()).collect(),
                    triangles: s.triangles,
                }
            })
            .collect()
    }

    /// A length that spans the scene (for drawing infinite walls), m.
    pub fn extent(&self) -> f64 {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for g in &self.groups {
            match &g.placement {
                Placement::Explicit { positions, .. } => {
                    for p in positions {
                        lo = lo.min(*p);
                        hi = hi.max(*p);
                    }
                }
                Placement::Random {
                    region: Region::Box { min, max },
                    ..
                } => {
                    lo = lo.min(*min);
                    hi = hi.max(*max);
                }
                Placement::Random {
                    region:
                        Region::Cylinder {
                            center, radius_max, ..
                        },
                    ..
                } => {
                    lo = lo.min(*center - DVec3::splat(*radius_max));
                    hi = hi.max(*center + DVec3::splat(*radius_max));
                }
            }
        }
        let mut size = (hi - lo).max_element();
        for w in self
            .walls
            .iter()
            .chain(self.impulse_walls.iter().map(|w| &w.wall))
        {
            if let WallShape::CylinderInside { radius, .. }
            | WallShape::CylinderOutside { radius, .. } = w.shape
            {
                size = size.max(2.0 * radius);
            }
            if let WallShape::Mesh(m) = &w.shape {
                let (lo, hi) = m.bounds();
                size = size.max((hi - lo).max_element());
            }
        }
        if size.is_finite() && size > 0.0 {
            size
        } else {
            1.0
        }
    }
}

#[cfg(test)]
mod tests {
    const CLASSIFIER: &str = include_str!("../../../cases/classifier.toml");

    fn everies(s: &crate::Scene) -> (u64, Vec<u64>) {
        let io = s.inlet_outlet();
        (
            io.outlet.expect("outlet").every,
            io.feeders.iter().map(|f| f.every).collect(),
        )
    }

    #[test]
    fn intervals_follow_dt_set_after_loading() {
        let mut s = crate::parse(CLASSIFIER, "c.toml", "c", &["dt=2e-6".into()]).unwrap();
        // 1e-4 s at dt = 2e-6 s.
        let (outlet, feeders) = everies(&s);
        assert_eq!(outlet, 50);
        assert!(!feeders.is_empty() && feeders.iter().all(|e| *e == 50));
        // `scg cost` scales dt after loading: every interval follows.
        s.dt *= 3.0;
        let (outlet, feeders) = everies(&s);
        assert_eq!(outlet, 17);
        assert!(feeders.iter().all(|e| *e == 17));
        assert_eq!(s.interval_steps(0.0), 1);
        // The same as loading the scene with that dt.
        let t = crate::parse(CLASSIFIER, "c.toml", "c", &["dt=6e-6".into()]).unwrap();
        assert_eq!(everies(&t), everies(&s));
    }
}
