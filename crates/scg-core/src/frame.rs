//! What a run hands to its recorders: snapshots of the particle state ([`Frame`]) and a
//! description of the run ([`RunMeta`]). The core does no I/O; a recorder (see the
//! `scg-record` crate) implements [`FrameSink`] and is inserted as a [`Recorders`] resource.

use bevy_ecs::prelude::Resource;

/// One recorded snapshot of every live particle, sorted by particle id.
///
/// All vectors have the same length (one entry per particle).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Frame {
    /// Step counter at which the frame was taken (t = step·dt).
    pub step: u64,
    /// Simulation time, s (= step·dt).
    pub time: f64,
    /// Stable particle id (unique over the run, never reused).
    pub id: Vec<u32>,
    /// Index of the particle's group in [`RunMeta::groups`].
    pub group: Vec<u32>,
    /// Centre position, m.
    pub position: Vec<[f64; 3]>,
    /// Translational velocity, m/s.
    pub velocity: Vec<[f64; 3]>,
    /// Diameter as simulated (after coarse graining), m.
    pub diameter: Vec<f64>,
    /// Density as simulated (after coarse graining), kg/m³.
    pub density: Vec<f64>,
    /// Magnitude |u′| of the turbulent fluctuation the dispersion model adds to the
    /// carrier velocity each particle sees, m/s; empty when the run has no dispersion.
    pub fluctuation: Vec<f64>,
    /// Scalars measured at this frame, e.g. `("count/small", 12.0)`; see [`crate::stats`].
    pub stats: Vec<(String, f64)>,
}

impl Frame {
    /// An empty frame at `step` and `time` (s) with room for `n` particles.
    pub fn with_capacity(step: u64, time: f64, n: usize) -> Self {
        Frame {
            step,
            time,
            id: Vec::with_capacity(n),
            group: Vec::with_capacity(n),
            position: Vec::with_capacity(n),
            velocity: Vec::with_capacity(n),
            diameter: Vec::with_capacity(n),
            density: Vec::with_capacity(n),
            fluctuation: Vec::new(),
            stats: Vec::new(),
        }
    }

    /// Number of particles in the frame.
    pub fn len(&self) -> usize {
        self.id.len()
    }
    /// True when the frame holds no particle.
    pub fn is_empty(&self) -> bool {
        self.id.is_empty()
    }

    /// Empty every column and the stats, keeping the buffers (step and time unchanged).
    pub fn clear(&mut self) {
        self.id.clear();
        self.group.clear();
        self.position.clear();
        self.velocity.clear();
        self.diameter.clear();
        self.density.clear();
        self.fluctuation.clear();
        self.stats.clear();
    }
}

/// Description of one particle group, as recorded.
#[derive(Clone, Debug, PartialEq)]
pub struct GroupMeta {
    /// Group name from the scene (used in entity paths and topics).
    pub name: String,
    /// Coarse-graining law name: `scg`, `none`, `mass` or `parcel`.
    pub law: String,
    /// Coarse-graining ratio α (1 = original particles).
    pub alpha: f64,
    /// Original (un-coarse-grained) diameter, m; for a size distribution, its mean.
    pub original_diameter: f64,
    /// Display colour, sRGB.
    pub color: [u8; 3],
}

/// A static line strip that draws part of the scene's geometry (m).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Outline {
    /// Name of the geometry item (e.g. `vessel`, `nozzle`, `floor`).
    pub name: String,
    /// Line strips, each a list of points, m.
    pub strips: Vec<Vec<[f64; 3]>>,
    /// A surface's vertices, m (mesh walls; empty otherwise).
    pub vertices: Vec<[f64; 3]>,
    /// The surface's triangles, as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
    /// The wall's prescribed motion: the strips and surface are where the wall is at rest
    /// (t = 0); a recorder moves them by [`WallMotion::pose`](crate::physics::wall_motion::WallMotion::pose)
    /// at each frame's time. [`WallMotion::FIXED`](crate::physics::wall_motion::WallMotion::FIXED)
    /// for still geometry.
    pub motion: crate::physics::wall_motion::WallMotion,
}

/// A boundary patch of a flow mesh, to draw: its faces as triangles (m).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct PatchSurface {
    /// Patch name from the mesh.
    pub name: String,
    /// Its role in the scene: `wall`, `outlet`, `inlet` or `lost`.
    pub role: String,
    /// Vertices, m.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles, as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

/// Description of a run, written once at the start of each recording.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct RunMeta {
    /// Case name (the scene file's stem), used for file names.
    pub case: String,
    /// scg version that made the recording.
    pub scg_version: String,
    /// Random seed of the scene.
    pub seed: u64,
    /// Time step, s.
    pub dt: f64,
    /// Steps between recorded frames.
    pub record_every: u64,
    /// Particle groups, indexed by [`Frame::group`].
    pub groups: Vec<GroupMeta>,
    /// The scene file's text, stored so a recording can be re-run.
    pub scene_toml: String,
    /// The absolute folder the scene's relative paths (a CFD case, STL walls) are
    /// resolved from, so a recording re-runs from any working folder; empty when unknown
    /// (recordings made before it was stored).
    pub scene_dir: String,
    /// Geometry to draw once, as static line strips.
    pub outlines: Vec<Outline>,
    /// The boundary patches of a flow mesh (empty without one), drawn once.
    pub patches: Vec<PatchSurface>,
    /// Warnings from the scene check (`scg check`), logged as text.
    pub warnings: Vec<String>,
    /// A recording written per MPI rank: the files of its parts, one per rank in rank
    /// order, relative to this file's folder, each holding that rank's particles of every
    /// frame; this file (the index) holds no frame. Empty otherwise.
    pub parts: Vec<String>,
    /// The MPI ranks the run was decomposed over (0 or 1: one process). With particle
    /// contacts such a run is one rank's statistically, not bit for bit, so it cannot be
    /// verified by re-running it on one.
    pub ranks: u32,
}

/// The wear of a run's walls (`[erosion]`), handed to the recorders once, at the end of
/// the run, before they finish.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WearMap {
    /// Erosion model (`finnie`, `dnv`).
    pub model: String,
    /// Step and time (s) the wear was summed up to.
    pub step: u64,
    /// Time, s.
    pub time: f64,
    /// The logged patches.
    pub patches: Vec<WearPatch>,
}

/// One patch's wear, face by face.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WearPatch {
    /// Patch name.
    pub name: String,
    /// The mesh points the faces use, m.
    pub vertices: Vec<[f64; 3]>,
    /// The faces fanned into triangles (indices into `vertices`).
    pub triangles: Vec<[u32; 3]>,
    /// The face (index into the per-face vectors) of each triangle.
    pub triangle_face: Vec<u32>,
    /// The mesh's face index (an STL wall's triangle index) of each face.
    pub faces: Vec<u32>,
    /// Volume removed per face, m³.
    pub volume: Vec<f64>,
    /// Mean depth rate per face over the run, m/s: volume / (area · time).
    pub depth_rate: Vec<f64>,
    /// Impacts per face (simulated particles).
    pub impacts: Vec<u64>,
    /// Mean impact angle to the wall per face (mass-weighted), rad; 0 where none struck.
    pub angle: Vec<f64>,
    /// Mean normal impact speed per face (mass-weighted), m/s; 0 where none struck.
    pub normal_speed: Vec<f64>,
    /// Mean tangential impact speed per face (mass-weighted), m/s; 0 where none struck.
    pub tangential_speed: Vec<f64>,
}

impl WearPatch {
    /// Each face's polygon (indices into `vertices`), rebuilt from its fan: the first
    /// triangle's three corners, then each further triangle's last corner.
    pub fn polygons(&self) -> Vec<Vec<u32>> {
        let mut out: Vec<Vec<u32>> = vec![Vec::new(); self.faces.len()];
        for (t, &f) in self.triangles.iter().zip(&self.triangle_face) {
            let p = &mut out[f as usize];
            if p.is_empty() {
                p.extend_from_slice(t);
            } else {
                p.push(t[2]);
            }
        }
        out
    }
}

impl WearMap {
    /// The deepest face: (patch index, face index in it, depth rate m/s), if any wore.
    pub fn deepest(&self) -> Option<(usize, usize, f64)> {
        self.patches
            .iter()
            .enumerate()
            .flat_map(|(p, w)| {
                w.depth_rate
                    .iter()
                    .enumerate()
                    .map(move |(f, &r)| (p, f, r))
            })
            .filter(|x| x.2 > 0.0)
            .max_by(|a, b| a.2.total_cmp(&b.2))
    }
}

/// Something that stores frames: a file writer, an in-memory buffer in tests…
pub trait FrameSink: Send + Sync {
    /// Store one frame. An error stops the run.
    fn write_frame(&mut self, frame: &Frame) -> Result<(), String>;
    /// Store one frame that the sink may keep (without copying it) past the call: the
    /// recording system hands frames this way, and refills a frame's buffers only when
    /// no sink kept it. By default, [`FrameSink::write_frame`].
    fn write_shared(&mut self, frame: &std::sync::Arc<Frame>) -> Result<(), String> {
        self.write_frame(frame)
    }
    /// Store the wear of the run's walls (called once before [`FrameSink::finish`] when
    /// the run logs erosion). By default, ignored.
    fn write_wear(&mut self, _wear: &WearMap) -> Result<(), String> {
        Ok(())
    }
    /// Flush and close; called exactly once at the end of a run (also after an interrupt).
    fn finish(&mut self) -> Result<(), String>;
}

/// The recorders of a run (resource). The recording system builds a [`Frame`] every
/// `record_every` steps and hands it to each sink in order.
#[derive(Resource, Default)]
pub struct Recorders {
    /// The sinks, written in order.
    pub sinks: Vec<Box<dyn FrameSink>>,
    /// The first error a sink returned, if any (the run loop stops on it).
    pub error: Option<String>,
    /// The last frame handed to the sinks: refilled for the next when none kept it.
    pub spare: Option<std::sync::Arc<Frame>>,
}

/// A sink that keeps every frame in memory (tests, analysis of a live run).
#[derive(Clone, Debug, Default)]
pub struct MemorySink {
    /// Frames received so far.
    pub frames: std::sync::Arc<std::sync::Mutex<Vec<Frame>>>,
    /// The wear of the walls, once the run hands it over.
    pub wear: std::sync::Arc<std::sync::Mutex<Option<WearMap>>>,
}

impl FrameSink for MemorySink {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), String> {
        self.frames
            .lock()
            .map_err(|e| e.to_string())?
            .push(frame.clone());
        Ok(())
    }

    fn write_wear(&mut self, wear: &WearMap) -> Result<(), String> {
        *self.wear.lock().map_err(|e| e.to_string())? = Some(wear.clone());
        Ok(())
    }
    fn finish(&mut self) -> Result<(), String> {
        Ok(())
    }
}
