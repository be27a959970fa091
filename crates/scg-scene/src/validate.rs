//! Scene text → validated [`Scene`]: `--set` overrides, TOML → the raw model (`raw`), then
//! every value checked and resolved. Each rejection is a [`SceneError`] naming the
//! file, the key and (when the key is in the file) its line.

mod dispersion;
mod frame;
mod mrf;
mod particles;
mod patches;
mod physics;
mod series;
mod size;
mod walls;

use std::path::Path;

use glam::DVec3;

use scg_core::physics::drag::DragLaw;
use scg_core::physics::flow::{FlowField, Fluid};
use scg_core::physics::integrate::Integrator;

use crate::check;
use crate::error::{self, SceneError};
use crate::model::{DtChoice, Group, Placement, Scene};
use crate::overrides::apply_overrides;
use crate::raw::{RawDt, RawScene};
use particles::{feeder, group};
use patches::{patch_models, patch_walls};
use physics::{contacts, flow_field, material, mesh_flow, outlet};
use scg_core::stages::impulse_walls::ImpulseWall;
use walls::wall;

/// The embedded default scene (the paper's vortex case), run by `scg run` with no file.
pub const DEFAULT_SCENE: &str = include_str!("../../../cases/vortex.toml");

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

/// Parse and validate scene text. `file` names it in errors, and its folder is the one
/// relative paths (a CFD case, STL walls) are resolved from; `stem` is the default name.
pub fn parse(
    text: &str,
    file: &str,
    stem: &str,
    overrides: &[String],
) -> Result<Scene, SceneError> {
    let base = Path::new(file).parent().unwrap_or(Path::new(""));
    parse_in(text, file, base, stem, overrides)
}

/// [`parse`] with relative paths resolved from `base` (e.g. the folder a recording's
/// scene came from).
pub fn parse_in(
    text: &str,
    file: &str,
    base: &Path,
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
    let cx = Ctx {
        file,
        base,
        text: &text,
    };
    validate(raw, &cx, stem)
}

impl Scene {
    /// Parse the embedded default scene.
    pub fn embedded(overrides: &[String]) -> Result<Scene, SceneError> {
        parse(DEFAULT_SCENE, "<embedded vortex.toml>", "vortex", overrides)
    }
}

/// The most particles a scene may hold over its run: its groups at the start plus all
/// its feeders feed (at roughly 350–500 bytes each, 5·10^7 fill a 24 GB machine).
pub const MAX_PARTICLES: u64 = 50_000_000;

/// Rejects a scene whose groups and feeders together would hold more than
/// [`MAX_PARTICLES`] over its run (at `dt`, up to the last step), naming the key of the
/// largest contributor.
fn particle_budget(scene: &Scene, cx: &Ctx) -> Result<(), SceneError> {
    let steps = scene.steps();
    let total = scene.particles_after(steps);
    let mut largest = (0, String::new());
    for (i, g) in scene.groups.iter().enumerate() {
        if let Placement::Random { count, .. } = g.placement
            && count as u64 > largest.0
        {
            largest = (count as u64, format!("groups[{i}].count"));
        }
    }
    for (i, f) in scene.feeders.iter().enumerate() {
        let fed = scene.fed_after(f, steps);
        if fed > largest.0 {
            largest = (fed, format!("feeders[{i}].rate"));
        }
    }
    if total > MAX_PARTICLES {
        return Err(cx.err(
            &largest.1,
            format!(
                "the scene would hold {total} particles over its run (this key: {}), more than \
                 scg's limit of {MAX_PARTICLES}",
                largest.0
            ),
        ));
    }
    Ok(())
}

/// `[[zones]]`: names non-empty and distinct, regions as the feeders'.
fn zones(raw: &[crate::raw::RawZone], cx: &Ctx) -> Result<Vec<crate::model::Zone>, SceneError> {
    let mut out: Vec<crate::model::Zone> = Vec::new();
    for (i, z) in raw.iter().enumerate() {
        if z.name.trim().is_empty() {
            return Err(cx.err(&format!("zones[{i}].name"), "must be a non-empty name"));
        }
        if out.iter().any(|o| o.name == z.name) {
            return Err(cx.err(
                &format!("zones[{i}].name"),
                format!("zone `{}` is declared twice", z.name),
            ));
        }
        let after = match z.collects_after {
            None => 0.0,
            Some(_) if !z.collects => {
                return Err(cx.err(
                    &format!("zones[{i}].collects_after"),
                    "goes with `collects = true`",
                ));
            }
            Some(t) => cx.non_negative(&format!("zones[{i}].collects_after"), t)?,
        };
        out.push(crate::model::Zone {
            name: z.name.clone(),
            collects: z.collects,
            collects_after: after,
            region: particles::region(&z.region, &format!("zones[{i}].region"), cx)?,
        });
    }
    Ok(out)
}

fn validate(raw: RawScene, cx: &Ctx, stem: &str) -> Result<Scene, SceneError> {
    let duration = cx.positive("duration", raw.duration)?;
    let integrator = raw
        .integrator
        .map_or(Integrator::Exponential, Integrator::from);
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
    let rotors = frame::case_frame(&raw, cx)?;
    let mut mesh_flow = match &raw.flow {
        Some(f) => mesh_flow(f, fluid.as_ref(), &rotors, cx)?,
        None => None,
    };
    if let Some(s) = mesh_flow.as_ref().and_then(|m| m.series.as_ref()) {
        series::supported(&raw, s, duration, cx)?;
    }
    let drag = match &raw.drag {
        None => None,
        Some(d) => {
            if fluid.is_none() {
                return Err(cx.err("drag", "the drag effect needs a [fluid] table"));
            }
            Some(DragLaw::from(d.law))
        }
    };
    let (dispersion, dispersion_source) = match &raw.dispersion {
        None => (None, String::new()),
        Some(d) => {
            if drag.is_none() {
                return Err(cx.err(
                    "dispersion",
                    "turbulent dispersion acts through the drag: it needs a [drag] table",
                ));
            }
            let (d, src, fields) = dispersion::dispersion(d, mesh_flow.as_ref(), seed, cx)?;
            // an unsteady series reads the same fields from every snapshot
            if let (Some(m), Some(fields)) = (mesh_flow.as_mut(), fields)
                && m.series.is_some()
            {
                series::with_turbulence(m, &d, fields, cx)?;
            }
            (Some(d), src)
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
            let (mat, law) = material(m, cx)?;
            (Some(mat), Some(law))
        }
    };
    let patch_models = match (&raw.flow, &mesh_flow) {
        (Some(f), Some(m)) => patch_models(f, m, material, cx)?,
        _ => Vec::new(),
    };
    if let Some(m) = &mesh_flow {
        mrf::no_contact_on_rotors(m, &patch_models, cx)?;
    }
    let patch_walls = match &mesh_flow {
        Some(m) => patch_walls(m, &patch_models, cx)?,
        None => None,
    };
    let mut walls = Vec::new();
    let mut impulse_walls = Vec::new();
    for (i, w) in raw.walls.iter().enumerate() {
        let shape = wall(w, i, cx)?;
        match patches::wall_model(w, i, material, cx)? {
            None => walls.push(shape),
            Some(model) => impulse_walls.push(ImpulseWall { wall: shape, model }),
        }
    }
    if !walls.is_empty() && material.is_none() {
        return Err(cx.err(
            "walls",
            "contact walls need a [material] table (the contact law); or give each wall a \
             `model = \"rebound\"` (with restitution and friction), \"stick\" or \"escape\"",
        ));
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
        let is_fed = fed.contains(&g.name.as_str());
        let made = match &g.size {
            None => vec![group(g, i, cx, is_fed)?],
            Some(s) => size::size_groups(g, s, i, groups.len(), cx, is_fed)?,
        };
        for mut grp in made {
            if let Some(c) = &raw.coarse_grain {
                if let Some(a) = c.alpha {
                    grp.alpha = cx.positive("coarse_grain.alpha", a)?;
                }
                if let Some(l) = c.law {
                    grp.law = l.into();
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
    }
    let feed_scale = cx.non_negative("feed_scale", raw.feed_scale.unwrap_or(1.0))?;
    let mut feeders = Vec::new();
    for (i, f) in raw.feeders.iter().enumerate() {
        let mut fd = feeder(f, i, &groups, mesh_flow.as_ref(), cx)?;
        if fd.swirl != 0.0 && flow.vortex().is_none() {
            return Err(cx.err(
                &format!("feeders[{i}].swirl"),
                "needs a rotating flow (flow.kind = \"vortex\" or \"classifier\")",
            ));
        }
        fd.rate *= feed_scale;
        feeders.push(fd);
    }
    let outlet = match &raw.outlet {
        None => None,
        Some(o) => Some(outlet(o, cx)?),
    };
    let erosion = match &raw.erosion {
        None => None,
        Some(e) => Some(patches::erosion(
            e,
            mesh_flow.as_ref(),
            &patch_models,
            &impulse_walls,
            cx,
        )?),
    };
    let mut scene = Scene {
        name: raw.name.clone().unwrap_or_else(|| stem.to_string()),
        file: cx.file.to_string(),
        base_dir: cx.base.to_path_buf(),
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
        mesh_flow,
        drag,
        gravity,
        buoyancy,
        scg_at_original: raw
            .coarse_grain
            .as_ref()
            .and_then(|c| c.forces_at)
            .is_none_or(|f| f == crate::raw::RawForcesAt::Original),
        extra_forces: physics::forces(&raw, drag, cx)?,
        erosion,
        material,
        normal_law,
        walls,
        patch_walls,
        patch_models,
        impulse_walls,
        contacts: None,
        groups,
        feeders,
        outlet,
        allow: raw
            .checks
            .as_ref()
            .map(|c| c.allow.clone())
            .unwrap_or_default(),
        dispersion,
        dispersion_source,
        zones: zones(&raw.zones, cx)?,
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
    let steps = scene.steps();
    if steps > 10_000_000_000 {
        return Err(cx.err("dt", format!("{steps} steps is more than scg will run")));
    }
    particle_budget(&scene, cx)?;
    scene.record_every = match raw.record_every {
        None => (steps / 200).max(1),
        Some(n) if n >= 1 => n as u64,
        Some(n) => return Err(cx.err("record_every", format!("must be ≥ 1, got {n}"))),
    };
    Ok(scene)
}

/// Where errors point: the file's name and its text (after `--set`).
struct Ctx<'a> {
    file: &'a str,
    /// The folder relative paths are resolved from.
    base: &'a Path,
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

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = "duration = 1.0\ndt = 0.1\n[flow]\nkind = \"swirl\"\n[[groups]]\nname = \"a\"\ndiameter = 1e-3\ndensity = 1e3\npositions = [[0.0, 0.0, 0.0]]\n";

    #[test]
    fn unknown_names_give_key_line_and_the_accepted_names() {
        let e = parse(SCENE, "s.toml", "s", &[]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("flow.kind"));
        assert_eq!(e.line, Some(4));
        for name in ["swirl", "still", "uniform", "vortex", "classifier"] {
            assert!(e.message.contains(&format!("`{name}`")), "{e}");
        }
        let e = parse(SCENE, "s.toml", "s", &["flow.kind=3".into()]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("flow.kind"));
        assert!(e.message.contains("expected a string"), "{e}");
        for (set, key) in [
            ("integrator=\"rk4\"", "integrator"),
            ("groups.0.law=\"x\"", "groups[0].law"),
            ("coarse_grain.law=\"x\"", "coarse_grain.law"),
        ] {
            let sets = ["flow.kind=\"still\"".to_string(), set.to_string()];
            let e = parse(SCENE, "s.toml", "s", &sets).unwrap_err();
            assert_eq!(e.key.as_deref(), Some(key), "{e}");
            assert!(
                e.line.is_some() && e.message.contains("unknown variant"),
                "{e}"
            );
        }
    }

    /// The particle limit counts every group and every feeder together, over the steps
    /// the run takes: feeders of 3 and 4·10^7 per second over 1 s are too many, over half a second they are not, and the
    /// error names the largest contributor's key and line.
    #[test]
    fn particle_limit_counts_groups_and_feeders_together() {
        let scene = |rate2: f64| {
            format!(
                "duration = 1.0\ndt = 0.25\n[[groups]]\nname = \"a\"\ndiameter = 1e-3\n\
                 density = 1e3\ncount = 1000\nregion = {{ kind = \"box\", min = [0.0, 0.0, 0.0], \
                 max = [1.0, 1.0, 1.0] }}\n\
                 [[feeders]]\ngroup = \"a\"\nrate = 3e7\n\
                 region = {{ kind = \"box\", min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }}\n\
                 [[feeders]]\ngroup = \"a\"\nrate = {rate2:e}\n\
                 region = {{ kind = \"box\", min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }}\n"
            )
        };
        let s = parse(&scene(1.0), "s.toml", "s", &[]).unwrap();
        // Four steps of 0.25 s: the run ends at 1 s.
        assert_eq!(s.fed_after(&s.feeders[0], s.steps()), 30_000_000);
        assert_eq!(s.initial_count(), 1000);
        let e = parse(&scene(4e7), "s.toml", "s", &[]).unwrap_err();
        assert_eq!(e.key.as_deref(), Some("feeders[1].rate"), "{e}");
        assert_eq!(e.line, Some(15), "{e}");
        assert!(e.message.contains("70001000 particles"), "{e}");
        // The same feeders over a shorter run fit.
        parse(&scene(1.9e7), "s.toml", "s", &[]).unwrap();
        parse(&scene(4e7), "s.toml", "s", &["duration=0.5".into()]).unwrap();
        // A group's count counts too.
        let e = parse(
            &scene(1.0),
            "s.toml",
            "s",
            &["groups.0.count=40000000".into()],
        )
        .unwrap_err();
        assert_eq!(e.key.as_deref(), Some("groups[0].count"), "{e}");
    }

    #[test]
    fn names_map_to_the_core() {
        let s = parse(
            SCENE,
            "s.toml",
            "s",
            &[
                "flow.kind=\"uniform\"".into(),
                "flow.velocity=[1.0, 0.0, 0.0]".into(),
                "integrator=\"explicit\"".into(),
                "groups.0.law=\"parcel\"".into(),
            ],
        )
        .unwrap();
        assert_eq!(s.integrator, Integrator::Explicit);
        assert_eq!(
            s.groups[0].law,
            scg_core::physics::scaling::CoarseGrainLaw::Parcel
        );
        assert!(matches!(s.flow, FlowField::Uniform(_)));
    }
}
