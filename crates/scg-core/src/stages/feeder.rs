//! Feeders: particles of one group enter at a constant rate, at random positions in a
//! region or on a boundary patch of a mesh flow, with a given velocity or the flow's.
//!
//! A patch feeder ([`FeedSource::Patch`]) samples points uniformly by area on the patch
//! ([`PatchSampler`]) and starts each particle its simulated radius inward of the face,
//! with the cell hint of the cell holding it ([`settle`]). With [`FeederSpec::by_flux`]
//! the points are weighted by the flow's inward flux u·n there instead (rejection from the
//! area-uniform draw against twice the largest u·n at the patch's face centres): the
//! particles of air that enters at a uniform concentration, as fluid tracers are.
//!
//! With a size distribution ([`SizeFeed`]) each particle's original size is drawn from
//! the feeder's stream before its position, and it joins the group of the report bin
//! holding that size (the fates and grade curves are then per bin).
//!
//! The count is exact: after the step ending at time t a feeder has fed
//! ⌊rate·(min(t, stop) − start)⌋ particles ([`fed_by`]), so fractional particles carry
//! over between steps. Positions come from a ChaCha8 stream seeded by the scene seed and
//! the feeder index, so a run is reproducible and feeders are independent.

use std::sync::Arc;

use bevy_ecs::prelude::*;
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::flow_series::FlowSeries;
use crate::checkpoint::records::{Checkpoint, Part, Persist, Persistence};
use crate::physics::inlet::{PatchSampler, settle};
use crate::physics::mesh_flow::MeshFlow;
use crate::physics::mesh_flow::hint;
use crate::physics::mesh_flow::series::blend as series_blend;
use crate::physics::scaling::{CoarseGrainLaw, coarse_grain};
use crate::physics::size_distribution::SizeDistribution;
use crate::region::Region;
use crate::spawn::{ParticleSpec, SpawnRules, spawn_particle_deferred_in};
use crate::stages::mesh_flow::MeshFlowState;
use crate::state::{NextParticleId, SimClock, Tally};
use crate::step::{StepBuilder, StepSet, StepSystem};

/// One feeder as the scene declares it.
#[derive(Clone, Debug, PartialEq)]
pub struct FeederSpec {
    /// Group index of the particles fed.
    pub group: u32,
    /// Original diameter, m.
    pub diameter: f64,
    /// Original density, kg/m³.
    pub density: f64,
    /// Coarse-graining ratio α.
    pub alpha: f64,
    /// Coarse-graining law.
    pub law: CoarseGrainLaw,
    /// Simulated particles per second.
    pub rate: f64,
    /// Where particles appear.
    pub source: FeedSource,
    /// Their velocity, m/s (unless `field_velocity`).
    pub velocity: DVec3,
    /// Take each particle's velocity from the mesh flow at its start instead (patch
    /// feeders on a mesh flow).
    pub field_velocity: bool,
    /// A rigid rotation added to `velocity` at each particle's position (e.g. entering
    /// co-rotating with a vortex), or none.
    pub spin: Option<Spin>,
    /// Patch feeders: positions weighted by the flow's inward flux u·n at each point
    /// (particles carried in by the air at a uniform concentration; fluid tracers), not
    /// uniformly by area.
    pub by_flux: bool,
    /// Feeding starts at this time, s.
    pub start: f64,
    /// Feeding stops at this time, s.
    pub stop: f64,
    /// Steps between releases (≥ 1): particles due are released together every `every`
    /// steps, so the particle set (and the neighbour list) changes less often.
    pub every: u64,
    /// A size distribution instead of the one `diameter`: each particle's original size
    /// drawn from it, its group the report bin holding the size.
    pub size: Option<SizeFeed>,
}

/// A feeder's size distribution and its report bins.
#[derive(Clone, Debug, PartialEq)]
pub struct SizeFeed {
    /// The distribution of original sizes.
    pub distribution: Arc<SizeDistribution>,
    /// The bins' edges, m (one more than the bins), spanning the distribution.
    pub edges: Vec<f64>,
    /// The group of the first (finest) bin; bin k feeds group `first_group + k`.
    pub first_group: u32,
}

impl SizeFeed {
    /// The group of a particle of original size `d` (m).
    pub fn group_of(&self, d: f64) -> u32 {
        let bins = self.edges.len() - 1;
        let k = self.edges.partition_point(|e| *e <= d).clamp(1, bins) - 1;
        self.first_group + k as u32
    }
}

/// Where a feeder's particles appear.
#[derive(Clone, Debug, PartialEq)]
pub enum FeedSource {
    /// Uniformly in a region.
    Region(Region),
    /// Uniformly by area on a boundary patch of the mesh flow, the simulated radius
    /// inward.
    Patch(Arc<PatchSampler>),
}

/// A rigid-body rotation about an axis through `center`: velocity ω × (x − center).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spin {
    /// A point on the axis, m.
    pub center: DVec3,
    /// Angular velocity vector, rad/s.
    pub omega: DVec3,
}

impl Spin {
    /// Velocity of the rotation at `x`, m/s.
    #[inline]
    pub fn velocity_at(&self, x: DVec3) -> DVec3 {
        self.omega.cross(x - self.center)
    }
}

/// Number of particles a feeder of `rate` particles/s active over [start, stop) has fed
/// by time `t` (exact integer count, fractional parts carried over).
pub fn fed_by(rate: f64, start: f64, stop: f64, t: f64) -> u64 {
    let active = t.min(stop) - start;
    if active <= 0.0 || rate <= 0.0 {
        return 0;
    }
    (rate * active).floor() as u64
}

/// Seed of feeder `index` for the scene seed `seed`.
pub fn feeder_seed(seed: u64, index: usize) -> u64 {
    // SplitMix64 of (seed, index): independent streams for different feeders.
    let mut z = seed
        .wrapping_add(0x9E37_79B9_7F4A_7C15u64.wrapping_mul(index as u64 + 1))
        .wrapping_add(0xF00D);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

struct FeederState {
    spec: FeederSpec,
    rng: ChaCha8Rng,
    fed: u64,
    /// Simulated (coarse-grained) radius of the particles fed, m (one size; the particles
    /// of a size distribution take each their own).
    radius: f64,
    /// Flux-weighted patch feeders: the bound of u·n the draws are accepted against, m/s
    /// (found at the first feed, from the flow).
    flux_bound: Option<f64>,
}

/// Draws before a flux-weighted feeder gives up on a patch with (nearly) no inflow and
/// takes the area-uniform point.
const FLUX_TRIES: usize = 10_000;

/// Twice the largest inward u·n at the face centres of patch `p` in `flow`, m/s (the
/// interpolated u·n inside a face can exceed its centre's; a draw above the bound is
/// accepted as at it).
fn flux_bound(
    p: &crate::physics::inlet::PatchSampler,
    flow: &crate::physics::mesh_flow::MeshFlow,
) -> f64 {
    2.0 * p
        .faces()
        .iter()
        .map(|f| flow.velocity(f.owner, f.centre).0.dot(f.inward))
        .fold(0.0, f64::max)
}

/// The scene's feeders and their state (resource).
#[derive(Resource)]
pub struct Feeders {
    list: Vec<FeederState>,
}

impl Feeders {
    /// Feeders with their random streams seeded from `seed`.
    pub fn new(specs: &[FeederSpec], seed: u64) -> Self {
        Feeders {
            list: specs
                .iter()
                .enumerate()
                .map(|(i, s)| FeederState {
                    spec: s.clone(),
                    rng: ChaCha8Rng::seed_from_u64(feeder_seed(seed, i)),
                    fed: 0,
                    radius: 0.5 * coarse_grain(s.law, s.alpha, s.diameter, s.density).diameter,
                    flux_bound: None,
                })
                .collect(),
        }
    }
}

impl Feeders {
    /// Each feeder's count and random stream (checkpoints).
    pub fn records(&self) -> Vec<crate::checkpoint::records::FeederRecord> {
        self.list
            .iter()
            .map(|f| crate::checkpoint::records::FeederRecord {
                fed: f.fed,
                seed: f.rng.get_seed(),
                stream: f.rng.get_stream(),
                word_pos: f.rng.get_word_pos(),
            })
            .collect()
    }

    /// Restore the counts and random streams saved by [`Feeders::records`].
    pub fn restore(
        &mut self,
        records: &[crate::checkpoint::records::FeederRecord],
    ) -> Result<(), String> {
        if records.len() != self.list.len() {
            return Err(format!(
                "the checkpoint has {} feeders, the scene {}",
                records.len(),
                self.list.len()
            ));
        }
        for (f, r) in self.list.iter_mut().zip(records) {
            let mut rng = ChaCha8Rng::from_seed(r.seed);
            rng.set_stream(r.stream);
            rng.set_word_pos(r.word_pos);
            f.rng = rng;
            f.fed = r.fed;
        }
        Ok(())
    }
}

/// The feeders' part of a checkpoint: counts and random streams.
struct FeedersPart;

impl Persist for FeedersPart {
    fn part(&self) -> Option<Part> {
        Some(Part::Feeders)
    }

    fn save(&self, world: &World, c: &mut Checkpoint) {
        c.feeders = world.resource::<Feeders>().records();
    }

    fn restore(&self, world: &mut World, c: &Checkpoint) -> Result<(), String> {
        world.resource_mut::<Feeders>().restore(&c.feeders)
    }
}

/// Add the feeder system (only when the scene has feeders).
pub fn plugin(world: &mut World, b: &mut StepBuilder, specs: &[FeederSpec], seed: u64) {
    if specs.is_empty() {
        return;
    }
    world.insert_resource(Feeders::new(specs, seed));
    Persistence::register(world, FeedersPart);
    b.add(
        StepSet::InletOutlet,
        "feeders",
        StepSystem::FeedParticles,
        feed_particles,
    );
}

/// Which fed particles this process spawns (resource; a run decomposed over processes,
/// `scg-mpi`): every process runs every feeder from the scene's seed (the same ids,
/// positions and random streams everywhere) and spawns only the particles `keep` gives
/// it, so that no process scans its particles for strangers after a feed. Without this
/// resource every fed particle is spawned.
#[derive(Resource, Clone)]
pub struct SpawnOwner {
    /// Whether this process owns a particle with this id fed at this position (m).
    pub keep: Arc<dyn Fn(u32, DVec3) -> bool + Send + Sync>,
    /// Fed particles spawned here so far.
    pub kept: u64,
}

/// Spawn the particles due at the end of this step (coarse-grained at spawn, so the frame
/// recorded this step shows their simulated diameter and density).
#[allow(clippy::too_many_arguments)]
pub fn feed_particles(
    mut commands: Commands,
    clock: Res<SimClock>,
    rules: Res<SpawnRules>,
    mut feeders: ResMut<Feeders>,
    mut next: ResMut<NextParticleId>,
    mut tally: ResMut<Tally>,
    mesh: Option<Res<MeshFlowState>>,
    mut owner: Option<ResMut<SpawnOwner>>,
    mut series: Option<ResMut<FlowSeries>>,
) {
    let t = clock.time();
    // an unsteady flow: its snapshots at the feeding time
    if let Some(s) = series.as_deref_mut() {
        s.advance(t);
    }
    let blend = series.as_deref().map(FlowSeries::blend);
    let flow = mesh
        .as_deref()
        .map(|m| blend.map_or(&*m.spec.flow, |b| b.a));
    // where a particle starting at x next to a face of cell `owner` is, and the fluid
    // velocity there
    let settle_at = |flow: &MeshFlow, owner: u32, x: DVec3| {
        let (cell, u) = settle(flow, owner, x);
        match blend {
            None => (cell, u),
            Some(b) => {
                let h = if cell < flow.mesh().n_cells as u32 {
                    cell
                } else {
                    owner
                };
                (cell, series_blend(u, b.b.velocity(h, x).0, b.w))
            }
        }
    };
    for f in feeders.list.iter_mut() {
        if !clock.step.is_multiple_of(f.spec.every.max(1)) {
            continue;
        }
        let due = fed_by(f.spec.rate, f.spec.start, f.spec.stop, t);
        while f.fed < due {
            // the size first (the start point sits its radius inward of a patch)
            let (group, diameter, radius) = match &f.spec.size {
                None => (f.spec.group, f.spec.diameter, f.radius),
                Some(s) => {
                    let d = s.distribution.sample(&mut f.rng);
                    let r =
                        0.5 * coarse_grain(f.spec.law, f.spec.alpha, d, f.spec.density).diameter;
                    (s.group_of(d), d, r)
                }
            };
            let (position, cell, u) = match (&f.spec.source, flow) {
                (FeedSource::Region(r), _) => (r.sample(&mut f.rng), hint::UNLOCATED, None),
                (FeedSource::Patch(p), Some(flow)) => {
                    // (an unsteady flow's bound: the larger of its two snapshots')
                    let bound = f.spec.by_flux.then(|| match blend {
                        None => *f.flux_bound.get_or_insert_with(|| flux_bound(p, flow)),
                        Some(b) => flux_bound(p, b.a).max(flux_bound(p, b.b)),
                    });
                    let mut tries = 0;
                    loop {
                        let s = p.sample(&mut f.rng, radius);
                        let (cell, u) = settle_at(flow, p.faces()[s.face].owner, s.centre);
                        let accept = match bound {
                            None => true,
                            Some(b) => {
                                tries += 1;
                                let un = u.dot(p.faces()[s.face].inward);
                                tries >= FLUX_TRIES || f.rng.random::<f64>() * b < un.min(b)
                            }
                        };
                        if accept {
                            break (s.centre, cell, Some(u));
                        }
                    }
                }
                // (the scene rejects a patch without a mesh flow)
                (FeedSource::Patch(p), None) => {
                    (p.sample(&mut f.rng, radius).centre, hint::UNLOCATED, None)
                }
            };
            let given = match u {
                Some(u) if f.spec.field_velocity => u,
                _ => f.spec.velocity,
            };
            let velocity = given + f.spec.spin.map_or(DVec3::ZERO, |s| s.velocity_at(position));
            let spec = ParticleSpec {
                group,
                diameter,
                density: f.spec.density,
                alpha: f.spec.alpha,
                law: f.spec.law,
                position,
                velocity,
            };
            let id = next.take();
            let mine = match owner.as_deref_mut() {
                Some(o) if !(o.keep)(id, position) => false,
                Some(o) => {
                    o.kept += 1;
                    true
                }
                None => true,
            };
            if mine {
                spawn_particle_deferred_in(&mut commands, &rules, &spec, id, clock.dt, cell);
            }
            f.fed += 1;
            if let Some(c) = tally.fed.get_mut(group as usize) {
                *c += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn count_is_exact_over_steps() {
        // 333.3 particles/s over 0.3 s in steps of 1e-3 s: ⌊100.0⌋ (up to rounding) fed.
        let dt = 1e-3;
        let mut total = 0;
        let mut prev = 0;
        for k in 1..=300 {
            let now = fed_by(1000.0 / 3.0, 0.0, 10.0, k as f64 * dt);
            assert!(now >= prev);
            total += now - prev;
            prev = now;
        }
        assert!((99..=100).contains(&total));
        assert_eq!(fed_by(100.0, 0.1, 0.2, 0.05), 0);
        assert_eq!(fed_by(100.0, 0.1, 0.2, 1.0), 10);
    }

    #[test]
    fn spin_is_tangential_and_proportional_to_radius() {
        let s = Spin {
            center: DVec3::new(1.0, 0.0, 0.0),
            omega: DVec3::new(0.0, 0.0, 2.0),
        };
        // 0.5 m from the axis along +x, 3 m up: 1 m/s along +y, nothing axial or radial.
        assert_eq!(
            s.velocity_at(DVec3::new(1.5, 0.0, 3.0)),
            DVec3::new(0.0, 1.0, 0.0)
        );
        assert_eq!(s.velocity_at(DVec3::new(1.0, 0.0, -4.0)), DVec3::ZERO);
    }

    #[test]
    fn seeds_differ_per_feeder() {
        assert_ne!(feeder_seed(1, 0), feeder_seed(1, 1));
        assert_ne!(feeder_seed(1, 0), feeder_seed(2, 0));
    }
}
