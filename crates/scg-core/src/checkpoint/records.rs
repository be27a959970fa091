//! The records of a checkpoint (pure data, serialised by `scg-record`): what each part of
//! the state looks like between two steps. A leaf: it names no stage; each stage that
//! holds state fills and reads its own part ([`super::Persist`]).

use bevy_ecs::prelude::{Resource, World};
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
    /// The carrier offset, m/s (the turbulent fluctuation), when the scene has a carrier
    /// modifier.
    pub carrier_offset: Option<DVec3>,
    /// The dispersion state (eddy age, s; σ, m/s), when the scene has dispersion.
    pub eddy: Option<(f64, f64)>,
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
    /// Collecting zones' log: collection times per zone and group, s.
    pub collected: Option<Vec<Vec<Vec<f64>>>>,
    /// Particles inside a collecting zone that waits (`collects_after`): (id, zone, step
    /// they entered), in id order.
    pub collect_inside: Vec<(u32, u32, u64)>,
    /// Erosion log: (face key, (impacts, sums)) per face hit, in key order; (particle id,
    /// volume m³) per particle that wore a wall, in id order.
    pub erosion: Option<ErosionRecord>,
}

/// The erosion log in a checkpoint: per face ((u32::MAX, mesh face) or (impulse wall,
/// triangle), (impacts, [represented mass kg, volume m³, Σ m·θ, Σ m·v_n, Σ m·v_t])), per
/// particle (id, volume m³).
pub type ErosionRecord = (Vec<((u32, u32), (u64, [f64; 5]))>, Vec<(u32, f64)>);

/// A stage's part of a checkpoint: the stage that holds the state saves and restores it.
/// Its plugin registers it ([`Persistence::register`]); `Simulation::checkpoint` and
/// `Simulation::restore` save the particles, the clock and the tally and then call
/// every registered part, naming no stage.
pub trait Persist: Send + Sync + 'static {
    /// The part of [`Checkpoint`] it fills ([`Checkpoint::held_parts`] names them), or
    /// `None` for a stage that only resets scratch state on a restore.
    fn part(&self) -> Option<Part>;
    /// Fill its part of `c` from `world`.
    fn save(&self, world: &World, c: &mut Checkpoint);
    /// Restore its part of `c` into `world` (after the particles were restored).
    fn restore(&self, world: &mut World, c: &Checkpoint) -> Result<(), String>;
}

/// The optional parts of a [`Checkpoint`], each owned by one stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// Feeders' counts and random streams.
    Feeders,
    /// The outlet log.
    Outlet,
    /// A mesh flow's patch log.
    Patches,
    /// The impulse walls' log.
    ImpulseWalls,
    /// The contact arrays and the step displacement.
    Contacts,
    /// The collecting zones' log.
    Collect,
    /// The erosion log.
    Erosion,
}

impl Part {
    /// The error when the scene and the checkpoint differ in this part.
    pub fn mismatch(self) -> String {
        match self {
            Part::Feeders => "the scene and the checkpoint differ in the feeders".into(),
            Part::Outlet => "the scene and the checkpoint differ in the outlet".into(),
            Part::Patches => {
                "the scene and the checkpoint differ in the mesh flow's patches".into()
            }
            Part::ImpulseWalls => "the scene and the checkpoint differ in the impulse walls".into(),
            Part::Contacts => "the scene and the checkpoint differ in particle contacts".into(),
            Part::Collect => "the scene and the checkpoint differ in the collecting zones".into(),
            Part::Erosion => "the scene and the checkpoint differ in [erosion]".into(),
        }
    }
}

impl Checkpoint {
    /// The optional parts this checkpoint holds.
    pub fn held_parts(&self) -> Vec<Part> {
        [
            (Part::Feeders, !self.feeders.is_empty()),
            (Part::Outlet, self.outlet.is_some()),
            (Part::Patches, self.patches.is_some()),
            (Part::ImpulseWalls, self.impulse_walls.is_some()),
            (Part::Contacts, self.contacts.is_some()),
            (Part::Collect, self.collected.is_some()),
            (Part::Erosion, self.erosion.is_some()),
        ]
        .into_iter()
        .filter_map(|(p, held)| held.then_some(p))
        .collect()
    }
}

/// The registered parts of a simulation's state (resource).
#[derive(Resource, Default)]
pub struct Persistence(Vec<Box<dyn Persist>>);

impl Persistence {
    /// The registered parts, in registration order.
    pub fn iter(&self) -> impl Iterator<Item = &dyn Persist> {
        self.0.iter().map(|p| &**p)
    }

    /// Register `p` in `world` (once per part: a second stage holding the same part, such
    /// as the outlet log kept by both the outlet and a mesh flow, adds nothing).
    pub fn register(world: &mut World, p: impl Persist) {
        let mut reg = world.get_resource_or_insert_with(Persistence::default);
        if p.part().is_none() || reg.0.iter().all(|q| q.part() != p.part()) {
            reg.0.push(Box::new(p));
        }
    }
}
