//! The scene file as written (serde structs, every key documented in docs/scenes.md).
//!
//! Names given as strings (laws, kinds, models) deserialize into the enums at the end of
//! this file; an unknown name is a parse error that names the key, its line and the
//! accepted values.
#![allow(missing_docs)]

use serde::de::IntoDeserializer;
use serde::de::value::StringDeserializer;
use serde::{Deserialize, Deserializer};

use scg_core::physics::drag::DragLaw;
use scg_core::physics::integrate::Integrator;
use scg_core::physics::patch_interaction::WallFriction;
use scg_core::physics::scaling::CoarseGrainLaw;

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawScene {
    pub name: Option<String>,
    pub description: Option<String>,
    pub duration: f64,
    pub dt: RawDt,
    pub record_every: Option<i64>,
    pub seed: Option<i64>,
    #[serde(default, deserialize_with = "some_name")]
    pub integrator: Option<RawIntegrator>,
    pub fluid: Option<RawFluid>,
    pub flow: Option<RawFlow>,
    pub drag: Option<RawDrag>,
    pub forces: Option<RawForces>,
    pub frame: Option<RawFrame>,
    pub erosion: Option<RawErosion>,
    pub gravity: Option<RawGravity>,
    pub material: Option<RawMaterial>,
    pub contacts: Option<RawContacts>,
    #[serde(default)]
    pub walls: Vec<RawWall>,
    #[serde(default)]
    pub groups: Vec<RawGroup>,
    pub coarse_grain: Option<RawCoarseGrain>,
    pub feed_scale: Option<f64>,
    #[serde(default)]
    pub feeders: Vec<RawFeeder>,
    pub outlet: Option<RawOutlet>,
    pub checks: Option<RawChecks>,
    pub dispersion: Option<RawDispersion>,
    #[serde(default)]
    pub zones: Vec<RawZone>,
}

/// `[[zones]]`: a named region the fates count the particles in at the end.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawZone {
    pub name: String,
    /// The particles in it at the end are collected (a dust bin, a hopper).
    #[serde(default)]
    pub collects: bool,
    /// With `collects`: a particle is collected once its centre has stayed in the region
    /// this long, s (default 0: on entry).
    pub collects_after: Option<f64>,
    pub region: RawRegion,
}

/// `[dispersion]`: turbulent dispersion (docs/dispersion.md).
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawDispersion {
    #[serde(deserialize_with = "name")]
    pub model: RawDispersionModel,
    /// m²/s² (a number, analytic flows) or a field name (mesh flows).
    pub k: Option<RawTurbulenceValue>,
    /// m²/s³ or a field name.
    pub epsilon: Option<RawTurbulenceValue>,
    /// 1/s or a field name (ε = 0.09·k·ω).
    pub omega: Option<RawTurbulenceValue>,
    /// langevin: Kolmogorov's Lagrangian constant C₀.
    pub c0: Option<f64>,
    /// langevin: Csanady's β of the crossing-trajectories correction (absent: none).
    pub csanady: Option<f64>,
    pub profile: Option<RawProfile>,
}

/// `dispersion.k`, `.epsilon`, `.omega`: a value or a field name.
#[derive(Deserialize, Debug, Clone)]
#[serde(untagged)]
pub enum RawTurbulenceValue {
    Value(f64),
    Field(String),
}

/// `[dispersion.profile]`: k and ε (or ω) tabulated along one axis.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawProfile {
    pub axis: String,
    pub at: Vec<f64>,
    pub k: Vec<f64>,
    pub epsilon: Option<Vec<f64>>,
    pub omega: Option<Vec<f64>>,
    pub periodic: Option<bool>,
}

/// `dispersion.model`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawDispersionModel {
    StochasticRas,
    Langevin,
}

/// `[checks]`: warnings of `scg check` the scene accepts knowingly.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawChecks {
    #[serde(default)]
    pub allow: Vec<crate::model::Allow>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawCoarseGrain {
    pub alpha: Option<f64>,
    #[serde(default, deserialize_with = "some_name")]
    pub law: Option<RawLaw>,
    /// Where an SCG particle's Reynolds-dependent drag correction and buoyancy are
    /// evaluated: for the original particle or for the simulated sphere.
    #[serde(default, deserialize_with = "some_name")]
    pub forces_at: Option<RawForcesAt>,
}

/// `coarse_grain.forces_at`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawForcesAt {
    Original,
    Coarse,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawFeeder {
    pub group: String,
    pub rate: Option<f64>,
    pub volume_rate: Option<f64>,
    /// Mass flow of the original powder, kg/s.
    pub mass_rate: Option<f64>,
    pub region: Option<RawRegion>,
    /// A boundary patch of a mesh flow to feed from (instead of `region`).
    pub patch: Option<String>,
    pub velocity: Option<RawFeedVelocity>,
    pub swirl: Option<f64>,
    pub start: Option<f64>,
    pub stop: Option<f64>,
    pub interval: Option<f64>,
    /// Patch feeders: `"area"` (default) or `"flux"`.
    pub weight: Option<String>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawOutlet {
    pub center: Option<[f64; 3]>,
    pub axis: Option<[f64; 3]>,
    pub nozzle_radius: f64,
    pub plane: f64,
    pub domain_radius: f64,
    pub domain_height: [f64; 2],
    pub interval: Option<f64>,
}

/// `feeders[i].velocity`: `[x, y, z]` m/s or `"field"`.
#[derive(Deserialize, Debug, Clone)]
#[serde(untagged)]
pub enum RawFeedVelocity {
    Given([f64; 3]),
    Word(String),
}

#[derive(Deserialize, Debug, Clone)]
#[serde(untagged)]
pub enum RawDt {
    Fixed(f64),
    Word(String),
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawFluid {
    pub density: f64,
    pub viscosity: f64,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawFlow {
    #[serde(deserialize_with = "name")]
    pub kind: RawFlowKind,
    pub velocity: Option<[f64; 3]>,
    pub center: Option<[f64; 3]>,
    pub axis: Option<[f64; 3]>,
    pub rpm: Option<f64>,
    pub inflow_ratio: Option<f64>,
    pub nozzle_radius: Option<f64>,
    pub axial_speed: Option<f64>,
    /// openfoam: the case folder, relative to the scene file.
    pub case: Option<String>,
    /// vtk: the file, relative to the scene file.
    pub file: Option<String>,
    /// openfoam: `"latest"` or a time, s.
    pub time: Option<RawTime>,
    /// openfoam: the time directories of a window as one unsteady field.
    pub series: Option<RawSeries>,
    pub field: Option<String>,
    #[serde(default, deserialize_with = "some_name")]
    pub interpolation: Option<RawInterpolation>,
    pub scale: Option<f64>,
    pub translate: Option<[f64; 3]>,
    pub patches: Option<RawPatches>,
    /// Steps between reorderings of the particles by mesh cell (0: never).
    pub sort_every: Option<i64>,
    /// The near-wall velocity in wall-adjacent cells.
    pub wall_function: Option<RawWallFunction>,
}

/// `[flow.wall_function]`.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawWallFunction {
    #[serde(deserialize_with = "name")]
    pub model: RawWallFunctionModel,
    /// The turbulent kinetic energy field for u_τ = C_μ^¼·√k (else u_τ from the velocity).
    pub k: Option<String>,
    pub kappa: Option<f64>,
    pub e: Option<f64>,
    pub c_mu: Option<f64>,
}

/// `flow.wall_function.model`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawWallFunctionModel {
    /// The interpolation to the wall patches' own values (no-slip: zero).
    None,
    /// The log law of the wall below the wall-adjacent cell's centre.
    LogLaw,
}

/// `flow.series`: the case's time directories from `start` to `end` (s, CFD time; default
/// all), linear in time between two; `cycle` repeats the window.
#[derive(Deserialize, Debug, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct RawSeries {
    pub start: Option<f64>,
    pub end: Option<f64>,
    #[serde(default)]
    pub cycle: bool,
}

/// `flow.time`: a name (`"latest"`) or a number.
#[derive(Deserialize, Debug, Clone)]
#[serde(untagged)]
pub enum RawTime {
    Number(f64),
    Name(String),
}

/// `[flow.patches]`: patch names by role; the others are `lost`.
#[derive(Deserialize, Debug, Clone, Default)]
#[serde(deny_unknown_fields)]
pub struct RawPatches {
    #[serde(default)]
    pub walls: Vec<String>,
    #[serde(default)]
    pub outlets: Vec<String>,
    #[serde(default)]
    pub inlets: Vec<String>,
    /// What the wall patches do: `contact` (default with `[material]`), `rebound`, `stick`
    /// or `escape`.
    #[serde(default, deserialize_with = "some_name")]
    pub wall_model: Option<RawWallModel>,
    /// Normal restitution of `rebound` walls (default `material.restitution`, else 1).
    pub restitution: Option<f64>,
    /// Friction coefficient of `rebound` walls (default 0).
    pub friction: Option<f64>,
    /// What `friction` means: `coulomb` (default) or `openfoam_fraction`.
    #[serde(default, deserialize_with = "some_name")]
    pub friction_model: Option<WallFriction>,
    /// Per-patch models by patch name (OpenFOAM's `localInteraction`), overriding the
    /// role's default.
    #[serde(default)]
    pub interaction: std::collections::BTreeMap<String, RawInteraction>,
}

/// `flow.patches.interaction.<patch>`.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawInteraction {
    #[serde(deserialize_with = "name")]
    pub model: RawWallModel,
    pub restitution: Option<f64>,
    pub friction: Option<f64>,
    #[serde(default, deserialize_with = "some_name")]
    pub friction_model: Option<WallFriction>,
}

/// `flow.patches.wall_model`, `flow.patches.interaction.<patch>.model`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawWallModel {
    /// The contact law of `[material]` against the patches' faces (a mesh wall).
    Contact,
    /// The impulse rebound of the centre: restitution and Coulomb friction.
    Rebound,
    /// Deposits: the particle stays where it reached the patch (removed, counted).
    Stick,
    /// Leaves through the patch (removed, counted).
    Escape,
}

/// `flow.interpolation`.
#[allow(clippy::enum_variant_names)] // the scene file's names
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawInterpolation {
    CellPoint,
    CellPointIdw,
    CellValue,
    CellPointLinearExact,
    Conservative,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawDrag {
    #[serde(deserialize_with = "name")]
    pub law: RawDragLaw,
}

/// `[frame]`: the rotating frame the flow and the walls are given in (OpenFOAM's SRF).
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawFrame {
    /// Rotation rate, rev/min, right-handed about `axis`.
    pub rpm: f64,
    pub axis: [f64; 3],
    /// A point on the axis, m (default the origin).
    pub center: Option<[f64; 3]>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawGravity {
    pub acceleration: [f64; 3],
    #[serde(default)]
    pub buoyancy: bool,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawMaterial {
    pub youngs_modulus: f64,
    pub poisson_ratio: f64,
    pub restitution: f64,
    #[serde(default)]
    pub friction: f64,
    #[serde(default, deserialize_with = "some_name")]
    pub normal_model: Option<RawNormalModel>,
    pub linear_stiffness: Option<f64>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawWall {
    pub name: Option<String>,
    #[serde(deserialize_with = "name")]
    pub kind: RawWallKind,
    pub point: Option<[f64; 3]>,
    pub normal: Option<[f64; 3]>,
    pub center: Option<[f64; 3]>,
    pub axis: Option<[f64; 3]>,
    pub radius: Option<f64>,
    pub extent: Option<[f64; 2]>,
    pub file: Option<String>,
    pub scale: Option<f64>,
    pub translate: Option<[f64; 3]>,
    pub rotate: Option<[f64; 3]>,
    /// `contact` (default: the `[material]` contact law), `rebound`, `stick`, `escape`.
    #[serde(default, deserialize_with = "some_name")]
    pub model: Option<RawWallModel>,
    /// e of a `rebound` wall.
    pub restitution: Option<f64>,
    /// μ of a `rebound` wall.
    pub friction: Option<f64>,
    /// What `friction` means (`coulomb` by default).
    #[serde(default, deserialize_with = "some_name")]
    pub friction_model: Option<WallFriction>,
    /// A prescribed rigid motion.
    pub motion: Option<RawWallMotion>,
}

/// `walls[i].motion`: translation and rotation at constant rates from t = 0.
#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawWallMotion {
    /// Velocity of the wall (of its rotation centre), m/s.
    pub velocity: Option<[f64; 3]>,
    /// Rotation rate, rev/min, about `axis` (right-handed) through `center`.
    pub rpm: Option<f64>,
    pub axis: Option<[f64; 3]>,
    /// The angular velocity vector, rad/s (instead of `rpm` and `axis`).
    pub angular_velocity: Option<[f64; 3]>,
    /// The rotation centre at t = 0, m (default the origin).
    pub center: Option<[f64; 3]>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawGroup {
    pub name: String,
    /// One size, m (or `size`, a distribution).
    pub diameter: Option<f64>,
    /// A size distribution (instead of `diameter`): the group is fed in report bins.
    pub size: Option<RawSize>,
    pub density: f64,
    pub alpha: Option<f64>,
    #[serde(default, deserialize_with = "some_name")]
    pub law: Option<RawLaw>,
    pub color: Option<[i64; 3]>,
    pub positions: Option<Vec<[f64; 3]>>,
    pub velocities: Option<Vec<[f64; 3]>>,
    pub velocity: Option<[f64; 3]>,
    pub count: Option<i64>,
    pub region: Option<RawRegion>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawRegion {
    #[serde(deserialize_with = "name")]
    pub kind: RawRegionKind,
    pub min: Option<[f64; 3]>,
    pub max: Option<[f64; 3]>,
    pub center: Option<[f64; 3]>,
    pub axis: Option<[f64; 3]>,
    pub radius_min: Option<f64>,
    pub radius_max: Option<f64>,
    pub height: Option<[f64; 2]>,
}

#[derive(Deserialize, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct RawContacts {
    pub skin: Option<f64>,
    #[serde(default)]
    pub rolling_friction: f64,
    pub periodic: Option<[f64; 3]>,
    pub tangential_stiffness_ratio: Option<f64>,
}

// ── names ───────────────────────────────────────────────────────────────────────────────

/// A name: a string (anything else is "invalid type: …, expected a string"), then one of
/// the enum's variants ("unknown variant `x`, expected one of …" lists the accepted names).
fn name<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<T, D::Error> {
    let s: StringDeserializer<D::Error> = String::deserialize(d)?.into_deserializer();
    T::deserialize(s)
}

/// An optional name (with `#[serde(default)]`: absent is `None`).
fn some_name<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Option<T>, D::Error> {
    name(d).map(Some)
}

/// `integrator`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawIntegrator {
    Exponential,
    Explicit,
}

impl From<RawIntegrator> for Integrator {
    fn from(i: RawIntegrator) -> Self {
        match i {
            RawIntegrator::Exponential => Integrator::Exponential,
            RawIntegrator::Explicit => Integrator::Explicit,
        }
    }
}

/// `drag.law`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawDragLaw {
    Stokes,
    SchillerNaumann,
    Putnam,
}

impl From<RawDragLaw> for DragLaw {
    fn from(l: RawDragLaw) -> Self {
        match l {
            RawDragLaw::Stokes => DragLaw::Stokes,
            RawDragLaw::SchillerNaumann => DragLaw::SchillerNaumann,
            RawDragLaw::Putnam => DragLaw::Putnam,
        }
    }
}

/// `groups[i].law`, `coarse_grain.law` (the names of [`CoarseGrainLaw::name`]).
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawLaw {
    Scg,
    None,
    Mass,
    Parcel,
    Sample,
}

impl From<RawLaw> for CoarseGrainLaw {
    fn from(l: RawLaw) -> Self {
        match l {
            RawLaw::Scg => CoarseGrainLaw::Scg,
            RawLaw::None => CoarseGrainLaw::None,
            RawLaw::Mass => CoarseGrainLaw::Mass,
            RawLaw::Parcel => CoarseGrainLaw::Parcel,
            RawLaw::Sample => CoarseGrainLaw::Sample,
        }
    }
}

/// `material.normal_model` (the law itself needs the material, see `validate`).
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawNormalModel {
    Hertz,
    Linear,
}

/// `flow.kind`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawFlowKind {
    Still,
    Uniform,
    Vortex,
    Classifier,
    Openfoam,
    Vtk,
}

/// `walls[i].kind`.
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawWallKind {
    Plane,
    CylinderInside,
    CylinderOutside,
    Mesh,
}

/// `region.kind` (groups and feeders).
#[derive(Deserialize, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RawRegionKind {
    Box,
    Cylinder,
}

mod effects;
pub use effects::*;
