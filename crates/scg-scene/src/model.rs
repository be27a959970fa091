//! The validated scene: what a scene file says, in SI units, checked and resolved (names
//! mapped to the core's laws, defaults filled in, `dt = "auto"` chosen). Times stay in
//! seconds; numbers of steps are derived from `dt` when the simulation is built
//! (see [`crate::build`]), so editing `dt` after loading keeps them consistent.

use glam::DVec3;

use scg_core::physics::contact::{Material, NormalLaw};
use scg_core::physics::drag::DragLaw;
use scg_core::physics::flow::{FlowField, Fluid};
use scg_core::physics::forces::ExtraForces;
use scg_core::physics::integrate::Integrator;
use scg_core::physics::scaling::CoarseGrainLaw;
use scg_core::physics::size_distribution::{Basis, SizeDistribution};
pub use scg_core::region::Region;
use scg_core::stages::contacts::ContactConfig;
pub use scg_core::stages::feeder::FeedSource;
use scg_core::stages::outlet::OutletGeometry;
use scg_core::stages::walls::Wall;

/// Where the particles of a group start.
#[derive(Clone, Debug, PartialEq)]
pub enum Placement {
    /// Listed positions and velocities.
    Explicit {
        /// Centres, m.
        positions: Vec<DVec3>,
        /// Velocities, m/s (same length as `positions`).
        velocities: Vec<DVec3>,
    },
    /// `count` particles at uniformly random positions in a region, all with `velocity`.
    Random {
        /// Number of particles.
        count: usize,
        /// Region.
        region: Region,
        /// Initial velocity, m/s.
        velocity: DVec3,
    },
}

/// A particle group (one size class or one bin of a size distribution, one coarse-graining
/// law).
#[derive(Clone, Debug, PartialEq)]
pub struct Group {
    /// Name.
    pub name: String,
    /// Original diameter, m.
    pub diameter: f64,
    /// Original density, kg/m³.
    pub density: f64,
    /// Coarse-graining ratio α.
    pub alpha: f64,
    /// Coarse-graining law.
    pub law: CoarseGrainLaw,
    /// Display colour.
    pub color: [u8; 3],
    /// Initial placement.
    pub placement: Placement,
    /// A report bin of a size distribution (`groups[i].size`): the group's particles are
    /// the distribution's sizes in the bin, `diameter` their mean-volume size.
    pub size: Option<SizeBin>,
}

/// One report bin of a size distribution. A `[[groups]]` entry with `size` becomes one
/// group per bin (named `<name>-<k>`, k from 1 at the finest), fed by the entry's feeders.
#[derive(Clone, Debug, PartialEq)]
pub struct SizeBin {
    /// The `[[groups]]` entry's name.
    pub parent: String,
    /// The distribution of original sizes.
    pub distribution: std::sync::Arc<SizeDistribution>,
    /// The bins' edges, m (every bin of the distribution).
    pub edges: Vec<f64>,
    /// This bin's index (0 = finest).
    pub index: usize,
}

impl SizeBin {
    /// This bin's smallest and largest size, m.
    pub fn range(&self) -> (f64, f64) {
        (self.edges[self.index], self.edges[self.index + 1])
    }

    /// The original mass share of this bin in the distribution.
    pub fn mass_share(&self) -> f64 {
        let (lo, hi) = self.range();
        self.distribution.share(lo, hi, Basis::Mass)
    }
}

impl Group {
    /// Largest original diameter of the group's particles, m (a size bin's upper edge).
    pub fn max_diameter(&self) -> f64 {
        self.size.as_ref().map_or(self.diameter, |s| s.range().1)
    }

    /// Smallest original diameter of the group's particles, m.
    pub fn min_diameter(&self) -> f64 {
        self.size.as_ref().map_or(self.diameter, |s| s.range().0)
    }

    /// The original powder's volume one particle a feeder of this group feeds stands for,
    /// m³: α³ originals (under every law, `sample` too) of `diameter`, or of a size
    /// distribution's mean particle (its feeders feed every bin).
    pub fn fed_volume(&self) -> f64 {
        let d = self
            .size
            .as_ref()
            .map_or(self.diameter, |s| s.distribution.mean_d3().cbrt());
        scg_core::physics::scaling::represented_volume(self.alpha, d)
    }

    /// Number of particles at the start.
    pub fn count(&self) -> usize {
        match &self.placement {
            Placement::Explicit { positions, .. } => positions.len(),
            Placement::Random { count, .. } => *count,
        }
    }
}

/// How the time step was chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DtChoice {
    /// Given in the scene.
    Fixed,
    /// `auto` (see [`crate::check::auto_dt`]).
    Auto,
}

/// A validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Scene name (file stem unless `name` is set).
    pub name: String,
    /// Where it came from (path, `<embedded>`…).
    pub file: String,
    /// The folder its relative paths (a CFD case, STL walls) were resolved from.
    pub base_dir: std::path::PathBuf,
    /// The TOML text (after `--set` overrides).
    pub source: String,
    /// Free text.
    pub description: String,
    /// Simulated duration, s.
    pub duration: f64,
    /// Time step, s (resolved when `auto`).
    pub dt: f64,
    /// Whether dt was given or chosen.
    pub dt_choice: DtChoice,
    /// Steps between recorded frames.
    pub record_every: u64,
    /// Random seed.
    pub seed: u64,
    /// Integrator.
    pub integrator: Integrator,
    /// Fluid, if any.
    pub fluid: Option<Fluid>,
    /// Flow field (`Still` when the flow is on a mesh).
    pub flow: FlowField,
    /// A flow read from a CFD case or VTK file (`flow.kind = "openfoam"` or `"vtk"`).
    pub mesh_flow: Option<SceneMeshFlow>,
    /// Drag law, if the drag effect is declared.
    pub drag: Option<DragLaw>,
    /// Gravity, if declared, m/s².
    pub gravity: Option<DVec3>,
    /// Buoyancy with gravity.
    pub buoyancy: bool,
    /// SCG particles' Reynolds-dependent drag correction and buoyancy as the original's
    /// (`[coarse_grain] forces_at = "original"`, the default; `"coarse"`: as the
    /// simulated sphere's).
    pub scg_at_original: bool,
    /// `[forces]`: forces besides drag and gravity, each for the original particle.
    pub extra_forces: ExtraForces,
    /// `[erosion]`: the wear model and, per patch of the mesh flow and per impulse wall,
    /// whether it is logged.
    pub erosion: Option<scg_core::stages::erosion::ErosionSpec>,
    /// Contact material (required with walls).
    pub material: Option<Material>,
    /// Normal contact law derived from the material.
    pub normal_law: Option<NormalLaw>,
    /// Walls (`[[walls]]`).
    pub walls: Vec<Wall>,
    /// The wall patches of a mesh flow as a contact wall (`flow.patches.wall_model =
    /// "contact"`, the default with `[material]`); `None` when they only rebound.
    pub patch_walls: Option<PatchWalls>,
    /// `[[walls]]` with `model = "rebound" | "stick" | "escape"`: impulses, no contact law
    /// (in file order; `walls` holds the contact walls).
    pub impulse_walls: Vec<scg_core::stages::impulse_walls::ImpulseWall>,
    /// What particles do at each patch of the mesh flow, in mesh order (empty without a
    /// mesh flow).
    pub patch_models: Vec<PatchModel>,
    /// Particle–particle contacts (`[contacts]`), if declared.
    pub contacts: Option<ContactConfig>,
    /// Groups.
    pub groups: Vec<Group>,
    /// Feeders (`[[feeders]]`), in file order.
    pub feeders: Vec<Feeder>,
    /// The outlet (`[outlet]`), if declared.
    pub outlet: Option<Outlet>,
    /// Warnings the scene accepts knowingly (`[checks] allow`).
    pub allow: Vec<Allow>,
    /// Turbulent dispersion (`[dispersion]`), if declared.
    pub dispersion: Option<scg_core::stages::carrier::Dispersion>,
    /// How the dispersion's turbulence was obtained (for `scg check`): e.g. "k and ε from
    /// fields `k`, `epsilon`", "ε = 0.09·k·ω from field `omega`".
    pub dispersion_source: String,
    /// Named regions the fates count the particles in at the end (`[[zones]]`).
    pub zones: Vec<Zone>,
}

/// A named region of the fates (`[[zones]]`): a particle in the domain at the end is
/// counted in the first zone holding its centre.
#[derive(Clone, Debug, PartialEq)]
pub struct Zone {
    /// Name.
    pub name: String,
    /// Whether the particles in it count as collected (a dust bin, a hopper).
    pub collects: bool,
    /// A collecting zone takes a particle once its centre has stayed inside this long, s
    /// (0: on entry).
    pub collects_after: f64,
    /// Where.
    pub region: Region,
}

/// A `scg check` warning a scene may accept knowingly (`[checks] allow = [...]`), e.g. a
/// paper case that uses Stokes drag beyond its range on purpose. Allowed warnings are
/// counted in one note instead of printed.
#[derive(serde::Deserialize, Clone, Copy, Debug, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Allow {
    /// Stokes drag at a particle Reynolds number above 0.1.
    StokesReynolds,
    /// A simulated density below ten times the fluid's (added mass, buoyancy neglected).
    LightParticles,
    /// An unsteady series whose snapshots are farther apart than a group's τ or the
    /// field's median cell crossing time (a CFD written coarsely in time, on purpose).
    SeriesSpacing,
}

impl Allow {
    /// The name used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Allow::StokesReynolds => "stokes_reynolds",
            Allow::LightParticles => "light_particles",
            Allow::SeriesSpacing => "series_spacing",
        }
    }
}

/// A feeder: particles of one group enter at a constant rate.
#[derive(Clone, Debug, PartialEq)]
pub struct Feeder {
    /// Index of the group fed.
    pub group: usize,
    /// Simulated particles per second (from `rate`, or `volume_rate` / simulated volume).
    pub rate: f64,
    /// Where particles appear: a region, or a patch of the mesh flow.
    pub source: FeedSource,
    /// Their velocity, m/s (unless `field_velocity`).
    pub velocity: DVec3,
    /// `velocity = "field"`: each particle starts with the mesh flow's velocity at its
    /// centre.
    pub field_velocity: bool,
    /// Added co-rotation with the flow's vortex, as a fraction of its local speed ω·r
    /// (dimensionless; 0 = none, 1 = entering co-rotating with the vortex).
    pub swirl: f64,
    /// Start and stop time, s.
    pub window: (f64, f64),
    /// Time between releases, s (0 = every step).
    pub interval: f64,
    /// Patch feeders: positions weighted by the inward flux u·n (`weight = "flux"`)
    /// instead of uniformly by area.
    pub by_flux: bool,
}

/// The outlet: removes particles that drain through the nozzle or leave the domain.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outlet {
    /// Where particles drain or are lost.
    pub geometry: OutletGeometry,
    /// Time between checks, s (0 = every step).
    pub interval: f64,
}

/// A flow on a CFD mesh, read once when the scene is loaded.
#[derive(Clone, Debug)]
pub struct SceneMeshFlow {
    /// The flow, shared by every simulation built from the scene.
    pub flow: std::sync::Arc<scg_core::physics::mesh_flow::MeshFlow>,
    /// What was read: the case folder or VTK file, and for a case the time folder.
    pub source: String,
    /// The field's name.
    pub field: String,
    /// Steps between reorderings of the particle table by mesh cell (0: never; with
    /// particle contacts never).
    pub sort_every: u64,
    /// Where more fields of the same time (turbulence for `[dispersion]`) are read from
    /// (`None`: a generated flow).
    pub reader: Option<FieldReader>,
    /// The frozen-rotor zones of an MRF case (their moving faces are in `flow`).
    pub rotors: Vec<RotorZone>,
    /// An unsteady field (`[flow] series`): `flow` is its first snapshot.
    pub series: Option<SceneSeries>,
}

/// An unsteady field as read (`[flow] series`).
#[derive(Clone, Debug)]
pub struct SceneSeries {
    /// The clock, the loader and the second snapshot.
    pub spec: scg_core::physics::mesh_flow::series::FlowSeriesSpec,
    /// The CFD time of every snapshot, s (the first is simulation time 0).
    pub times: Vec<f64>,
    /// The time directories, in order.
    pub dirs: Vec<std::path::PathBuf>,
    /// With `cycle`: ‖U_last − U_first‖/‖U_first‖ over the cells (the change across the
    /// seam).
    pub seam: Option<f64>,
}

impl SceneSeries {
    /// The CFD time of the first snapshot (simulation time 0), s.
    pub fn start(&self) -> f64 {
        self.times[0]
    }
}

/// One rotor zone as read (for `scg check`).
#[derive(Clone, Debug, PartialEq)]
pub struct RotorZone {
    /// The MRFProperties entry.
    pub name: String,
    /// Its cell zone and how many cells it has.
    pub cell_zone: String,
    /// Cells in the zone.
    pub cells: usize,
    /// Angular velocity, rad/s.
    pub omega: glam::DVec3,
    /// A point on the axis, m (placed like the mesh).
    pub origin: glam::DVec3,
    /// The moving faces per patch: (patch name, faces).
    pub faces: Vec<(String, usize)>,
}

/// Where the fields of a mesh flow come from.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldReader {
    /// An OpenFOAM case and its time directory.
    Foam {
        /// The case folder.
        case: std::path::PathBuf,
        /// The time read.
        time: scg_mesh::foam::TimeSel,
    },
    /// A legacy VTK file.
    Vtk {
        /// The file.
        file: std::path::PathBuf,
    },
}

/// What a particle does at one patch of a mesh flow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchModel {
    /// At the particle's centre: rebound, stick or escape (for a `contact` patch, the
    /// rebound that guards the contact law).
    pub interaction: scg_core::physics::mesh_flow::PatchInteraction,
    /// The patch is a contact wall (Hertz–Mindlin with the `[material]`).
    pub contact: bool,
}

impl PatchModel {
    /// The model's name in scene files.
    pub fn name(&self) -> &'static str {
        if self.contact {
            "contact"
        } else {
            self.interaction.name()
        }
    }
}

/// The wall patches of a mesh flow as one mesh wall: every face of every wall patch,
/// polygons split into triangles about their centres, points shared, so that a particle
/// crossing from one face or patch to the next of a flat surface feels one contact.
#[derive(Clone, Debug)]
pub struct PatchWalls {
    /// The wall (`WallShape::Mesh`), named [`PatchWalls::NAME`].
    pub wall: Wall,
    /// (patch index in the mesh, its triangles) for every wall patch.
    pub per_patch: Vec<(usize, usize)>,
}

impl PatchWalls {
    /// The wall's name (messages, contact histories).
    pub const NAME: &'static str = "flow.patches.walls";
}

impl Scene {
    /// Every wall particles touch with the contact law: the `[[walls]]`, then the wall
    /// patches when they are a contact wall.
    pub fn contact_walls(&self) -> impl Iterator<Item = &Wall> {
        self.walls
            .iter()
            .chain(self.patch_walls.as_ref().map(|p| &p.wall))
    }
}
