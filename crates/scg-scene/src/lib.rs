//! scg-scene: scene files (TOML) → a validated [`Scene`] → a runnable simulation.
//!
//! Validation happens once, up front; every rejection is a [`SceneError`] that names the
//! file, the key and (when the key is in the file) its line. Bad input never panics.

pub mod check;
pub mod error;
mod raw;

use std::path::Path;

use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use scg_core::frame::{GroupMeta, Outline, RunMeta};
use scg_core::physics::contact::tangential::TangentialStiffness;
use scg_core::physics::contact::{Material, NormalLaw};
use scg_core::physics::drag::DragLaw;
use scg_core::physics::flow::{FlowField, Fluid, Vortex, rpm_to_rad_per_s};
use scg_core::physics::integrate::Integrator;
use scg_core::physics::scaling::CoarseGrainLaw;
use scg_core::physics::wall_shape::WallShape;
use scg_core::sim::InletOutlet;
use scg_core::stages::contacts::ContactConfig;
use scg_core::stages::feeder::FeederSpec;
use scg_core::stages::outlet::OutletSpec;
use scg_core::stages::walls::{Wall, WallSet};
use scg_core::{ParticleSpec, SimConfig, Simulation};

pub use error::SceneError;
use raw::*;

/// The embedded default scene (the paper's vortex case), run by `scg run` with no file.
pub const DEFAULT_SCENE: &str = include_str!("../../../cases/vortex.toml");

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

pub use scg_core::region::Region;

/// A particle group (one size class, one coarse-graining law).
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
}

impl Group {
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
    /// `auto` (see [`check::auto_dt`]).
    Auto,
}

/// A validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Scene name (file stem unless `name` is set).
    pub name: String,
    /// Where it came from (path, `<embedded>`…).
    pub file: String,
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
    /// Flow field.
    pub flow: FlowField,
    /// Drag law, if the drag effect is declared.
    pub drag: Option<DragLaw>,
    /// Gravity, if declared, m/s².
    pub gravity: Option<DVec3>,
    /// Buoyancy with gravity.
    pub buoyancy: bool,
    /// Contact material (required with walls).
    pub material: Option<Material>,
    /// Normal contact law derived from the material.
    pub normal_law: Option<NormalLaw>,
    /// Walls.
    pub walls: Vec<Wall>,
    /// Particle–particle contacts (`[contacts]`), if declared.
    pub contacts: Option<ContactConfig>,
    /// Groups.
    pub groups: Vec<Group>,
    /// Feeders (`[[feeders]]`), in file order.
    pub feeders: Vec<Feeder>,
    /// The outlet (`[outlet]`), if declared.
    pub outlet: Option<OutletSpec>,
}

/// A feeder: particles of one group enter at a constant rate.
#[derive(Clone, Debug, PartialEq)]
pub struct Feeder {
    /// Index of the group fed.
    pub group: usize,
    /// Simulated particles per second (from `rate`, or `volume_rate` / simulated volume).
    pub rate: f64,
    /// Where particles appear.
    pub region: Region,
    /// Their velocity, m/s.
    pub velocity: DVec3,
    /// Added co-rotation with the flow's vortex, as a fraction of its local speed ω·r
    /// (dimensionless; 0 = none, 1 = entering co-rotating with the vortex).
    pub swirl: f64,
    /// Start and stop time, s.
    pub window: (f64, f64),
    /// Time between releases, s (0 = every step).
    pub interval: f64,
}

const PALETTE: [[u8; 3]; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

struct Ctx<'a> {
    file: &'a str,
    text: &'a str,
}

impl Ctx<'_> {
    fn err(&self, key: &str, message: impl Into<String>) -> SceneError {
        SceneError {
            file: self.file.to_string(),
            key: Some(key.to_string()),
            line: error::locate(self.text, key),
            message: message.into(),
        }
    }
    fn finite(&self, key: &str, x: f64) -> Result<f64, SceneError> {
        if x.is_finite() {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be a finite number, got {x}")))
        }
    }
    fn positive(&self, key: &str, x: f64) -> Result<f64, SceneError> {
        if x.is_finite() && x > 0.0 {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be a finite number > 0, got {x}")))
        }
    }
    fn non_negative(&self, key: &str, x: f64) -> Result<f64, SceneError> {
        if x.is_finite() && x >= 0.0 {
            Ok(x)
        } else {
            Err(self.err(key, format!("must be a finite number ≥ 0, got {x}")))
        }
    }
    fn vec3(&self, key: &str, v: [f64; 3]) -> Result<DVec3, SceneError> {
        if v.iter().all(|c| c.is_finite()) {
            Ok(DVec3::from_array(v))
        } else {
            Err(self.err(key, format!("must hold finite numbers, got {v:?}")))
        }
    }
    fn unit(&self, key: &str, v: [f64; 3]) -> Result<DVec3, SceneError> {
        let d = self.vec3(key, v)?;
        let l = d.length();
        if l > 0.0 && l.is_finite() {
            Ok(d / l)
        } else {
            Err(self.err(key, "must be a non-zero direction"))
        }
    }
    fn need<T: Clone>(&self, key: &str, v: &Option<T>) -> Result<T, SceneError> {
        v.clone()
            .ok_or_else(|| self.err(key, "is required here".to_string()))
    }
}

/// Read a scene file.
pub fn load(path: &Path, overrides: &[String]) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        file: file.clone(),
        key: None,
        line: None,
        message: format!("cannot read scene file: {e}"),
    })?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    parse(&text, &file, &stem, overrides)
}

/// Apply `key=value` overrides (TOML values, dotted keys, `groups.0.alpha=2`) to `text`.
pub fn apply_overrides(text: &str, file: &str, overrides: &[String]) -> Result<String, SceneError> {
    if overrides.is_empty() {
        return Ok(text.to_string());
    }
    let bad = |key: &str, message: String| SceneError {
        file: format!("{file} (--set)"),
        key: Some(key.to_string()),
        line: None,
        message,
    };
    let doc: toml::Table = toml::from_str(text).map_err(|e| SceneError {
        file: file.to_string(),
        key: None,
        line: e.span().map(|s| error::line_of(text, s.start)),
        message: e.message().to_string(),
    })?;
    let mut root = toml::Value::Table(doc);
    for o in overrides {
        let Some((key, value)) = o.split_once('=') else {
            return Err(bad(o, "expected key=value".into()));
        };
        let key = key.trim();
        let value: toml::Value = match toml::from_str::<toml::Table>(&format!("v = {value}")) {
            Ok(mut t) => t
                .remove("v")
                .unwrap_or(toml::Value::String(value.to_string())),
            // Bare words (e.g. `law=none`) are strings.
            Err(_) => toml::Value::String(value.trim().to_string()),
        };
        let parts: Vec<&str> = key.split('.').collect();
        let mut cur: &mut toml::Value = &mut root;
        for (i, p) in parts.iter().enumerate() {
            let last = i + 1 == parts.len();
            cur = match cur {
                toml::Value::Table(t) => {
                    if last {
                        t.insert(p.to_string(), value.clone());
                        break;
                    }
                    t.entry(p.to_string())
                        .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                }
                toml::Value::Array(a) => {
                    let idx: usize = p
                        .parse()
                        .map_err(|_| bad(key, format!("`{p}` is not an index")))?;
                    let len = a.len();
                    let slot = a
                        .get_mut(idx)
                        .ok_or_else(|| bad(key, format!("index {idx} out of range (len {len})")))?;
                    if last {
                        *slot = value.clone();
                        break;
                    }
                    slot
                }
                _ => return Err(bad(key, format!("`{p}` is inside a plain value"))),
            };
        }
    }
    toml::to_string(&root).map_err(|e| bad("", e.to_string()))
}

/// Parse and validate scene text. `file` names it in errors, `stem` is the default name.
pub fn parse(
    text: &str,
    file: &str,
    stem: &str,
    overrides: &[String],
) -> Result<Scene, SceneError> {
    let text = apply_overrides(text, file, overrides)?;
    let raw: RawScene = toml::from_str(&text).map_err(|e| {
        let pos = e.span().map(|s| s.start);
        SceneError {
            file: file.to_string(),
            key: pos.and_then(|p| error::key_at(&text, p)),
            line: pos.map(|p| error::line_of(&text, p)),
            message: e.message().trim().to_string(),
        }
    })?;
    let cx = Ctx { file, text: &text };
    validate(raw, &cx, stem)
}

fn validate(raw: RawScene, cx: &Ctx, stem: &str) -> Result<Scene, SceneError> {
    let duration = cx.positive("duration", raw.duration)?;
    let integrator = match raw.integrator.as_deref() {
        None | Some("exponential") => Integrator::Exponential,
        Some("explicit") => Integrator::Explicit,
        Some(o) => {
            return Err(cx.err(
                "integrator",
                format!("unknown integrator `{o}` (exponential, explicit)"),
            ));
        }
    };
    let seed = match raw.seed {
        None => 0,
        Some(s) if s >= 0 => s as u64,
        Some(s) => return Err(cx.err("seed", format!("must be ≥ 0, got {s}"))),
    };
    let fluid = match &raw.fluid {
        Some(f) => Some(Fluid {
            density: cx.non_negative("fluid.density", f.density)?,
            viscosity: cx.positive("fluid.viscosity", f.viscosity)?,
        }),
        None => None,
    };
    let flow = match &raw.flow {
        None => FlowField::Still,
        Some(f) => flow_field(f, cx)?,
    };
    let drag = match &raw.drag {
        None => None,
        Some(d) => {
            if fluid.is_none() {
                return Err(cx.err("drag", "the drag effect needs a [fluid] table"));
            }
            Some(match d.law.as_str() {
                "stokes" => DragLaw::Stokes,
                "schiller_naumann" => DragLaw::SchillerNaumann,
                o => {
                    return Err(cx.err(
                        "drag.law",
                        format!("unknown drag law `{o}` (stokes, schiller_naumann)"),
                    ));
                }
            })
        }
    };
    let (gravity, buoyancy) = match &raw.gravity {
        None => (None, false),
        Some(g) => {
            if g.buoyancy && fluid.is_none() {
                return Err(cx.err("gravity.buoyancy", "buoyancy needs a [fluid] table"));
            }
            (
                Some(cx.vec3("gravity.acceleration", g.acceleration)?),
                g.buoyancy,
            )
        }
    };
    let (material, normal_law) = match &raw.material {
        None => (None, None),
        Some(m) => {
            let mat = Material {
                youngs_modulus: cx.positive("material.youngs_modulus", m.youngs_modulus)?,
                poisson_ratio: cx.finite("material.poisson_ratio", m.poisson_ratio)?,
                restitution: cx.positive("material.restitution", m.restitution)?,
                friction: cx.non_negative("material.friction", m.friction)?,
            };
            if !(-1.0 < mat.poisson_ratio && mat.poisson_ratio < 0.5) {
                return Err(cx.err("material.poisson_ratio", "must lie in (−1, 0.5)"));
            }
            if mat.restitution > 1.0 {
                return Err(cx.err("material.restitution", "must lie in (0, 1]"));
            }
            let law = match m.normal_model.as_deref() {
                None | Some("hertz") => NormalLaw::hertz(mat.restitution),
                Some("linear") => {
                    let k = cx.need("material.linear_stiffness", &m.linear_stiffness)?;
                    NormalLaw::linear(
                        cx.positive("material.linear_stiffness", k)?,
                        mat.restitution,
                    )
                }
                Some(o) => {
                    return Err(cx.err(
                        "material.normal_model",
                        format!("unknown model `{o}` (hertz, linear)"),
                    ));
                }
            };
            (Some(mat), Some(law))
        }
    };
    let mut walls = Vec::new();
    for (i, w) in raw.walls.iter().enumerate() {
        walls.push(wall(w, i, cx)?);
    }
    if !walls.is_empty() && material.is_none() {
        return Err(cx.err("walls", "walls need a [material] table (contact law)"));
    }
    let contacts_raw = raw.contacts.clone();
    if contacts_raw.is_some() && material.is_none() {
        return Err(cx.err(
            "contacts",
            "particle contacts need a [material] table (contact law)",
        ));
    }
    if raw.groups.is_empty() {
        return Err(cx.err("groups", "a scene needs at least one [[groups]] entry"));
    }
    let mut groups = Vec::new();
    let fed: Vec<&str> = raw.feeders.iter().map(|f| f.group.as_str()).collect();
    for (i, g) in raw.groups.iter().enumerate() {
        let mut grp = group(g, i, cx, fed.contains(&g.name.as_str()))?;
        if let Some(c) = &raw.coarse_grain {
            if let Some(a) = c.alpha {
                grp.alpha = cx.positive("coarse_grain.alpha", a)?;
            }
            if let Some(l) = &c.law {
                grp.law = CoarseGrainLaw::from_name(l).ok_or_else(|| {
                    cx.err(
                        "coarse_grain.law",
                        format!("unknown law `{l}` (scg, none, mass, parcel)"),
                    )
                })?;
            }
        }
        if groups.iter().any(|o: &Group| o.name == grp.name) {
            return Err(cx.err(
                &format!("groups[{i}].name"),
                format!("duplicate group name `{}`", grp.name),
            ));
        }
        groups.push(grp);
    }
    let feed_scale = cx.non_negative("feed_scale", raw.feed_scale.unwrap_or(1.0))?;
    let mut feeders = Vec::new();
    for (i, f) in raw.feeders.iter().enumerate() {
        let mut fd = feeder(f, i, &groups, duration, cx)?;
        if fd.swirl != 0.0 && flow.vortex().is_none() {
            return Err(cx.err(
                &format!("feeders[{i}].swirl"),
                "needs a rotating flow (flow.kind = \"vortex\" or \"classifier\")",
            ));
        }
        fd.rate *= feed_scale;
        feeders.push(fd);
    }
    let (outlet, outlet_interval) = match &raw.outlet {
        None => (None, 0.0),
        Some(o) => {
            let (s, i) = outlet(o, cx)?;
            (Some(s), i)
        }
    };
    let mut scene = Scene {
        name: raw.name.clone().unwrap_or_else(|| stem.to_string()),
        file: cx.file.to_string(),
        source: cx.text.to_string(),
        description: raw.description.clone().unwrap_or_default(),
        duration,
        dt: 0.0,
        dt_choice: DtChoice::Fixed,
        record_every: 1,
        seed,
        integrator,
        fluid,
        flow,
        drag,
        gravity,
        buoyancy,
        material,
        normal_law,
        walls,
        contacts: None,
        groups,
        feeders,
        outlet,
    };
    if let (Some(c), Some(mat), Some(law)) = (&contacts_raw, material, normal_law) {
        scene.contacts = Some(contacts(c, mat, law, &scene.groups, cx)?);
    }
    if scene.name.is_empty() || scene.name.contains(['/', '\\']) {
        return Err(cx.err("name", "must be a non-empty name without path separators"));
    }
    match &raw.dt {
        RawDt::Fixed(dt) => {
            scene.dt = cx.positive("dt", *dt)?;
            if scene.dt > duration {
                return Err(cx.err(
                    "dt",
                    format!("dt = {} s exceeds the duration {duration} s", scene.dt),
                ));
            }
        }
        RawDt::Word(w) if w == "auto" => {
            scene.dt = check::auto_dt(&scene);
            scene.dt_choice = DtChoice::Auto;
        }
        RawDt::Word(w) => {
            return Err(cx.err(
                "dt",
                format!("expected a number of seconds or \"auto\", got \"{w}\""),
            ));
        }
    }
    if let Some(o) = &mut scene.outlet {
        o.every = interval_steps(outlet_interval, scene.dt);
    }
    let steps = scene.steps();
    if steps > 10_000_000_000 {
        return Err(cx.err("dt", format!("{steps} steps is more than scg will run")));
    }
    scene.record_every = match raw.record_every {
        None => (steps / 200).max(1),
        Some(n) if n >= 1 => n as u64,
        Some(n) => return Err(cx.err("record_every", format!("must be ≥ 1, got {n}"))),
    };
    Ok(scene)
}

/// Largest simulated (coarse-grained) diameter over the groups, m.
fn max_simulated_diameter(groups: &[Group]) -> f64 {
    groups
        .iter()
        .map(|g| {
            scg_core::physics::scaling::coarse_grain(g.law, g.alpha, g.diameter, g.density).diameter
        })
        .fold(0.0, f64::max)
}

fn contacts(
    c: &RawContacts,
    mat: Material,
    law: NormalLaw,
    groups: &[Group],
    cx: &Ctx,
) -> Result<ContactConfig, SceneError> {
    let dmax = max_simulated_diameter(groups);
    let skin = match c.skin {
        Some(s) => cx.positive("contacts.skin", s)?,
        None => 0.1 * dmax,
    };
    let rolling_friction = cx.non_negative("contacts.rolling_friction", c.rolling_friction)?;
    let periodic = match c.periodic {
        None => None,
        Some(l) => {
            for (a, x) in l.iter().enumerate() {
                cx.positive("contacts.periodic", *x)?;
                // Minimum image needs every cut-off below half the box.
                if *x < 2.0 * (dmax + skin) {
                    return Err(cx.err(
                        "contacts.periodic",
                        format!(
                            "box length {x} m along axis {a} is below 2·(d_max + skin) = {:.4e} m",
                            2.0 * (dmax + skin)
                        ),
                    ));
                }
            }
            Some(DVec3::from_array(l))
        }
    };
    let tangential_stiffness = match c.tangential_stiffness_ratio {
        None => TangentialStiffness::Mindlin,
        Some(r) => {
            TangentialStiffness::Ratio(cx.positive("contacts.tangential_stiffness_ratio", r)?)
        }
    };
    Ok(ContactConfig {
        law,
        material: mat,
        skin,
        periodic,
        rolling_friction,
        tangential_stiffness,
    })
}

fn flow_field(f: &RawFlow, cx: &Ctx) -> Result<FlowField, SceneError> {
    let vortex = |cx: &Ctx| -> Result<Vortex, SceneError> {
        Ok(Vortex {
            center: cx.vec3("flow.center", f.center.unwrap_or([0.0; 3]))?,
            axis: cx.unit("flow.axis", f.axis.unwrap_or([0.0, 0.0, 1.0]))?,
            omega: rpm_to_rad_per_s(cx.finite("flow.rpm", cx.need("flow.rpm", &f.rpm)?)?),
            inflow_ratio: cx.finite("flow.inflow_ratio", f.inflow_ratio.unwrap_or(0.0))?,
        })
    };
    Ok(match f.kind.as_str() {
        "still" => FlowField::Still,
        "uniform" => {
            FlowField::Uniform(cx.vec3("flow.velocity", cx.need("flow.velocity", &f.velocity)?)?)
        }
        "vortex" => FlowField::Vortex(vortex(cx)?),
        "classifier" => FlowField::Classifier {
            vortex: vortex(cx)?,
            nozzle_radius: cx.positive(
                "flow.nozzle_radius",
                cx.need("flow.nozzle_radius", &f.nozzle_radius)?,
            )?,
            axial_speed: cx.finite(
                "flow.axial_speed",
                cx.need("flow.axial_speed", &f.axial_speed)?,
            )?,
        },
        o => {
            return Err(cx.err(
                "flow.kind",
                format!("unknown flow `{o}` (still, uniform, vortex, classifier)"),
            ));
        }
    })
}

fn wall(w: &RawWall, i: usize, cx: &Ctx) -> Result<Wall, SceneError> {
    let k = |s: &str| format!("walls[{i}].{s}");
    let extent = match w.extent {
        None => None,
        Some([a, b]) => {
            let (a, b) = (cx.finite(&k("extent"), a)?, cx.finite(&k("extent"), b)?);
            if a >= b {
                return Err(cx.err(&k("extent"), "must be [from, to] with from < to"));
            }
            Some((a, b))
        }
    };
    let shape = match w.kind.as_str() {
        "plane" => WallShape::Plane {
            point: cx.vec3(&k("point"), cx.need(&k("point"), &w.point)?)?,
            normal: cx.unit(&k("normal"), cx.need(&k("normal"), &w.normal)?)?,
        },
        "cylinder_inside" | "cylinder_outside" => {
            let center = cx.vec3(&k("center"), w.center.unwrap_or([0.0; 3]))?;
            let axis = cx.unit(&k("axis"), w.axis.unwrap_or([0.0, 0.0, 1.0]))?;
            let radius = cx.positive(&k("radius"), cx.need(&k("radius"), &w.radius)?)?;
            if w.kind == "cylinder_inside" {
                WallShape::CylinderInside {
                    center,
                    axis,
                    radius,
                    extent,
                }
            } else {
                WallShape::CylinderOutside {
                    center,
                    axis,
                    radius,
                    extent,
                }
            }
        }
        o => {
            return Err(cx.err(
                &k("kind"),
                format!("unknown wall `{o}` (plane, cylinder_inside, cylinder_outside)"),
            ));
        }
    };
    Ok(Wall {
        name: w.name.clone().unwrap_or_else(|| format!("wall{i}")),
        shape,
    })
}

fn feeder(
    f: &RawFeeder,
    i: usize,
    groups: &[Group],
    duration: f64,
    cx: &Ctx,
) -> Result<Feeder, SceneError> {
    let k = |s: &str| format!("feeders[{i}].{s}");
    let group = groups
        .iter()
        .position(|g| g.name == f.group)
        .ok_or_else(|| cx.err(&k("group"), format!("no group named `{}`", f.group)))?;
    let g = &groups[group];
    let rate = match (f.rate, f.volume_rate) {
        (Some(r), None) => cx.non_negative(&k("rate"), r)?,
        (None, Some(v)) => {
            let v = cx.non_negative(&k("volume_rate"), v)?;
            let d = scg_core::physics::scaling::coarse_grain(g.law, g.alpha, g.diameter, g.density)
                .diameter;
            v / (std::f64::consts::PI / 6.0 * d * d * d)
        }
        (Some(_), Some(_)) => {
            return Err(cx.err(&k("volume_rate"), "give `rate` or `volume_rate`, not both"));
        }
        (None, None) => return Err(cx.err(&k("rate"), "a feeder needs `rate` or `volume_rate`")),
    };
    if rate * duration > 5.0e7 {
        return Err(cx.err(
            &k("rate"),
            format!(
                "{:.3e} particles over the run is more than scg will feed",
                rate * duration
            ),
        ));
    }
    let start = cx.non_negative(&k("start"), f.start.unwrap_or(0.0))?;
    let stop = cx.finite(&k("stop"), f.stop.unwrap_or(f64::MAX))?;
    if stop < start {
        return Err(cx.err(&k("stop"), "must be ≥ start"));
    }
    Ok(Feeder {
        group,
        rate,
        region: region(&f.region, &k("region"), cx)?,
        velocity: cx.vec3(&k("velocity"), f.velocity.unwrap_or([0.0; 3]))?,
        swirl: cx.finite(&k("swirl"), f.swirl.unwrap_or(0.0))?,
        window: (start, stop),
        interval: cx.non_negative(&k("interval"), f.interval.unwrap_or(0.0))?,
    })
}

/// Steps per `interval` seconds (at least 1).
fn interval_steps(interval: f64, dt: f64) -> u64 {
    ((interval / dt).round() as u64).max(1)
}

fn outlet(o: &RawOutlet, cx: &Ctx) -> Result<(OutletSpec, f64), SceneError> {
    let interval = cx.non_negative("outlet.interval", o.interval.unwrap_or(0.0))?;
    let nozzle_radius = cx.positive("outlet.nozzle_radius", o.nozzle_radius)?;
    let domain_radius = cx.positive("outlet.domain_radius", o.domain_radius)?;
    let [h0, h1] = o.domain_height;
    let (h0, h1) = (
        cx.finite("outlet.domain_height", h0)?,
        cx.finite("outlet.domain_height", h1)?,
    );
    if h0 >= h1 {
        return Err(cx.err("outlet.domain_height", "must be [from, to] with from < to"));
    }
    let plane = cx.finite("outlet.plane", o.plane)?;
    if !(h0..=h1).contains(&plane) {
        return Err(cx.err("outlet.plane", "must lie inside domain_height"));
    }
    if nozzle_radius > domain_radius {
        return Err(cx.err("outlet.nozzle_radius", "must be ≤ domain_radius"));
    }
    Ok((
        OutletSpec {
            center: cx.vec3("outlet.center", o.center.unwrap_or([0.0; 3]))?,
            axis: cx.unit("outlet.axis", o.axis.unwrap_or([0.0, 0.0, 1.0]))?,
            nozzle_radius,
            plane,
            domain_radius,
            domain_height: (h0, h1),
            every: 1,
        },
        interval,
    ))
}

fn group(g: &RawGroup, i: usize, cx: &Ctx, fed: bool) -> Result<Group, SceneError> {
    let k = |s: &str| format!("groups[{i}].{s}");
    if g.name.is_empty()
        || !g
            .name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-".contains(c))
    {
        return Err(cx.err(
            &k("name"),
            "must be non-empty and use only letters, digits, `_` and `-`",
        ));
    }
    let diameter = cx.positive(&k("diameter"), g.diameter)?;
    let density = cx.positive(&k("density"), g.density)?;
    let alpha = cx.positive(&k("alpha"), g.alpha.unwrap_or(1.0))?;
    let law = match g.law.as_deref() {
        None => CoarseGrainLaw::Scg,
        Some(s) => CoarseGrainLaw::from_name(s).ok_or_else(|| {
            cx.err(
                &k("law"),
                format!("unknown law `{s}` (scg, none, mass, parcel)"),
            )
        })?,
    };
    let color = match g.color {
        None => PALETTE[i % PALETTE.len()],
        Some(c) => {
            if c.iter().any(|v| !(0..=255).contains(v)) {
                return Err(cx.err(&k("color"), "components must lie in 0..=255"));
            }
            [c[0] as u8, c[1] as u8, c[2] as u8]
        }
    };
    let velocity = cx.vec3(&k("velocity"), g.velocity.unwrap_or([0.0; 3]))?;
    let placement = match (&g.positions, &g.region) {
        (Some(_), Some(_)) => {
            return Err(cx.err(
                &k("region"),
                "give either `positions` or `count` + `region`, not both",
            ));
        }
        (Some(ps), None) => {
            if g.count.is_some() {
                return Err(cx.err(
                    &k("count"),
                    "`count` goes with `region`, not with `positions`",
                ));
            }
            if ps.is_empty() {
                return Err(cx.err(&k("positions"), "must list at least one position"));
            }
            let positions = ps
                .iter()
                .map(|p| cx.vec3(&k("positions"), *p))
                .collect::<Result<Vec<_>, _>>()?;
            let velocities = match &g.velocities {
                None => vec![velocity; positions.len()],
                Some(vs) => {
                    if vs.len() != positions.len() {
                        return Err(cx.err(
                            &k("velocities"),
                            format!("has {} entries for {} positions", vs.len(), positions.len()),
                        ));
                    }
                    vs.iter()
                        .map(|v| cx.vec3(&k("velocities"), *v))
                        .collect::<Result<Vec<_>, _>>()?
                }
            };
            Placement::Explicit {
                positions,
                velocities,
            }
        }
        (None, Some(r)) => {
            let count = cx.need(&k("count"), &g.count)?;
            if !(0..=50_000_000).contains(&count) {
                return Err(cx.err(
                    &k("count"),
                    format!("must lie in 0..=50000000, got {count}"),
                ));
            }
            Placement::Random {
                count: count as usize,
                region: region(r, &k("region"), cx)?,
                velocity,
            }
        }
        // A group that a feeder feeds may start empty.
        (None, None) if fed && g.count.is_none() => Placement::Explicit {
            positions: Vec::new(),
            velocities: Vec::new(),
        },
        (None, None) => {
            return Err(cx.err(
                &k("positions"),
                "a group needs `positions` or `count` + `region` (or a feeder)",
            ));
        }
    };
    Ok(Group {
        name: g.name.clone(),
        diameter,
        density,
        alpha,
        law,
        color,
        placement,
    })
}

fn region(r: &RawRegion, key: &str, cx: &Ctx) -> Result<Region, SceneError> {
    let k = |s: &str| format!("{key}.{s}");
    match r.kind.as_str() {
        "box" => {
            let min = cx.vec3(&k("min"), cx.need(&k("min"), &r.min)?)?;
            let max = cx.vec3(&k("max"), cx.need(&k("max"), &r.max)?)?;
            if !(min.cmple(max).all()) {
                return Err(cx.err(&k("max"), "every component of max must be ≥ min"));
            }
            Ok(Region::Box { min, max })
        }
        "cylinder" => {
            let radius_min = cx.non_negative(&k("radius_min"), r.radius_min.unwrap_or(0.0))?;
            let radius_max =
                cx.positive(&k("radius_max"), cx.need(&k("radius_max"), &r.radius_max)?)?;
            if radius_min > radius_max {
                return Err(cx.err(&k("radius_min"), "must be ≤ radius_max"));
            }
            let [h0, h1] = r.height.unwrap_or([0.0, 0.0]);
            let (h0, h1) = (cx.finite(&k("height"), h0)?, cx.finite(&k("height"), h1)?);
            if h0 > h1 {
                return Err(cx.err(&k("height"), "must be [from, to] with from ≤ to"));
            }
            Ok(Region::Cylinder {
                center: cx.vec3(&k("center"), r.center.unwrap_or([0.0; 3]))?,
                axis: cx.unit(&k("axis"), r.axis.unwrap_or([0.0, 0.0, 1.0]))?,
                radius_min,
                radius_max,
                height: (h0, h1),
            })
        }
        o => Err(cx.err(&k("kind"), format!("unknown region `{o}` (box, cylinder)"))),
    }
}

impl Scene {
    /// Parse the embedded default scene.
    pub fn embedded(overrides: &[String]) -> Result<Scene, SceneError> {
        parse(DEFAULT_SCENE, "<embedded vortex.toml>", "vortex", overrides)
    }

    /// Number of steps for the duration (rounded to the nearest step).
    pub fn steps(&self) -> u64 {
        (self.duration / self.dt).round().max(1.0) as u64
    }

    /// The core configuration.
    pub fn sim_config(&self, record: bool) -> SimConfig {
        SimConfig {
            dt: self.dt,
            integrator: self.integrator,
            drag: self.drag,
            fluid: self.fluid,
            flow: self.flow,
            gravity: self.gravity,
            buoyancy: self.buoyancy,
            walls: (!self.walls.is_empty()).then(|| WallSet {
                walls: self.walls.clone(),
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
        }
    }

    /// The feeders and outlet for the core.
    pub fn inlet_outlet(&self) -> InletOutlet {
        InletOutlet {
            feeders: self
                .feeders
                .iter()
                .map(|f| {
                    let g = &self.groups[f.group];
                    FeederSpec {
                        group: f.group as u32,
                        diameter: g.diameter,
                        density: g.density,
                        alpha: g.alpha,
                        law: g.law,
                        rate: f.rate,
                        region: f.region.clone(),
                        velocity: f.velocity,
                        spin: self.flow.vortex().filter(|_| f.swirl != 0.0).map(|v| {
                            scg_core::stages::feeder::Spin {
                                center: v.center,
                                omega: v.axis * (v.omega * f.swirl),
                            }
                        }),
                        start: f.window.0,
                        stop: f.window.1,
                        every: interval_steps(f.interval, self.dt),
                    }
                })
                .collect(),
            outlet: self.outlet,
            seed: self.seed,
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
            scene_toml: self.source.clone(),
            outlines: self
                .walls
                .iter()
                .map(|w| Outline {
                    name: w.name.clone(),
                    strips: w.shape.outline(size),
                })
                .collect(),
            warnings,
        }
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
        for w in &self.walls {
            if let WallShape::CylinderInside { radius, .. }
            | WallShape::CylinderOutside { radius, .. } = w.shape
            {
                size = size.max(2.0 * radius);
            }
        }
        if size.is_finite() && size > 0.0 {
            size
        } else {
            1.0
        }
    }
}
