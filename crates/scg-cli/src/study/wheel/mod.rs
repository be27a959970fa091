//! `scg study wheel`: the deflector-wheel classifier (`cases/wheel.toml`), tracked in the
//! wheel's rotating frame through OpenFOAM's SRF air flow, run as the originals, SCG
//! (α = 2, 4), the other scaling laws at α = 2 (unchanged density, parcel) and plain
//! sampling (the originals, α³ = 8 and 64 times fewer, each standing for α³). Per size
//! class: the share that passed the wheel to the fines outlet, the share still outside
//! the wheel at the end (rejected: in the machine it is flung to the housing and falls to
//! the coarse outlet) and the share between the blades (undecided), each with its Wilson
//! interval; the cut size (where the fines share falls through 50 %) with its bootstrap
//! interval; the equilibrium cut d50 = √(18·μ·v_r·R / (ρ_p·u_θ²)) at the wheel radius R
//! with the field's own v_r and u_θ ([`theory`]), with the nominal ones (Q/(2πRH), Ω·R),
//! and on every circle from the fines outlet to the inlet; the wall time; the tracer check
//! (fluid tracers leave, mean residence V/Q); and the originals once more through the same
//! wheel as a frozen rotor (`cases/wheel-mrf.toml`: OpenFOAM's MRF solution, the absolute
//! frame, the blades' faces moving but the blades staying), beside the SRF's.
//! Every variant feeds the same powder mass: 1/α³ as many particles.

pub mod report;

use serde::{Deserialize, Serialize};

use super::cyclone::{CycloneRun, run_tracers};
use super::{StudyArgs, Variants, run_variants};
use crate::EXIT_BAD_INPUT;
use crate::points::Points;

pub use report::{markdown, report, summary};

/// The wheel scene (embedded; its `case = "wheel/coarse"` is resolved against `cases/`,
/// see [`super::case_scene`]).
pub const WHEEL: &str = include_str!("../../../../../cases/wheel.toml");
/// The same wheel as a frozen rotor (OpenFOAM's MRF solution, the absolute frame).
pub const WHEEL_MRF: &str = include_str!("../../../../../cases/wheel-mrf.toml");

/// The variants: the cyclone study's (name, α, law).
pub const VARIANTS: [(&str, f64, &str); 7] = super::cyclone::VARIANTS;

/// Feed scale of the full study (on the scene's 500 particles per class) and the simulated
/// time, s: 5 000 originals per class.
pub const FULL: (f64, f64) = (10.0, 1.0);
/// The same for `--quick`: 500 per class.
pub const QUICK: (f64, f64) = (1.0, 1.0);
/// Tracers per second over the scene's 20 ms feed (`--quick`: the second).
pub const TRACERS: (f64, f64) = (1.0e5, 2.5e4);
/// Steps between recorded frames in the study's MCAPs (5 ms).
pub const RECORD_EVERY: u64 = 250;
/// Points on the circle at the wheel radius where the field is averaged.
pub const CIRCLE_POINTS: usize = 3600;

/// One variant: the fates per class (the cyclone study's run: `escaped` are the fines,
/// `held` those still inside, `lost` any that left through the inlet) and, of the held,
/// those outside the wheel at the end.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct WheelRun {
    /// Fates per class, timing.
    pub run: CycloneRun,
    /// Per class: held particles farther than the wheel radius from the axis at the end.
    pub outside: Vec<u64>,
    /// Per class: the median distance from the axis of the held particles at the end, m
    /// (`None` when none is held).
    pub held_radius: Vec<Option<f64>>,
}

/// The equilibrium cut at the wheel radius: a particle orbits at R where the centrifugal
/// force on it, ρ_p·(π/6)·d³·u_θ²/R, balances the Stokes drag of the inward air,
/// 3π·μ·d·v_r: d50 = √(18·μ·v_r·R / (ρ_p·u_θ²)).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Theory {
    /// The wheel radius R (the blades' outer edge), m.
    pub radius: f64,
    /// Where the field is averaged: just outside the blades, m.
    pub sampled_at: f64,
    /// The frame's rate Ω, rad/s.
    pub omega: f64,
    /// The field's inward radial velocity averaged over the circle, m/s.
    pub v_r: f64,
    /// The field's absolute tangential velocity (relative + Ω·r) averaged there, m/s.
    pub u_theta: f64,
    /// The nominal inward velocity Q/(2π·r·H) (Q the inlet's flow by the CFD's own face
    /// values, H the slice), m/s.
    pub v_r_nominal: f64,
    /// That Q, m³/s, and the same flow of the interpolated field at the face centres (what
    /// the feeders and the tracer check's V/Q use).
    pub inflow: (f64, f64),
    /// Particle density, kg/m³.
    pub density: f64,
    /// Air viscosity, Pa·s.
    pub viscosity: f64,
    /// d50 with the field's v_r and u_θ, m.
    pub d50_field: f64,
    /// d50 with the nominal v_r and u_θ = Ω·R, m.
    pub d50_nominal: f64,
    /// The same balance on circles from the fines outlet to the inlet: (r m, v_r m/s,
    /// u_θ m/s, d50 m); a particle reaches the fines outlet only if it is finer than the
    /// smallest of them (the inner vortex between the blades and the outlet included).
    pub profile: Vec<(f64, f64, f64, f64)>,
}

impl Theory {
    /// The smallest equilibrium cut of [`Theory::profile`] and its radius, m.
    pub fn critical(&self) -> Option<(f64, f64)> {
        self.profile
            .iter()
            .filter(|p| p.3.is_finite())
            .min_by(|a, b| a.3.total_cmp(&b.3))
            .map(|p| (p.0, p.3))
    }
}

/// Radii of [`Theory::profile`], m: every millimetre from just outside the fines outlet
/// (20.5 mm) to just inside the inlet (99.5 mm).
pub fn profile_radii() -> impl Iterator<Item = f64> {
    (20..=99).map(|mm| mm as f64 * 1e-3 + 5e-4)
}

/// The equilibrium cut, m: √(18·μ·v_r·r / (ρ_p·u_θ²)).
pub fn equilibrium_cut(viscosity: f64, v_r: f64, r: f64, density: f64, u_theta: f64) -> f64 {
    (18.0 * viscosity * v_r * r / (density * u_theta * u_theta)).sqrt()
}

/// The wheel radius of cases/wheel/blockmesh.py, m.
pub const WHEEL_RADIUS: f64 = 0.05;

/// [`Theory`] of the wheel scene `text` (with the study's `set` overrides): the field
/// averaged over [`CIRCLE_POINTS`] on the circle r = 1.01·R in the mid-plane of the slice,
/// about the frame's axis; Q from the first feeder's patch.
pub fn theory(text: &str, set: &[String]) -> Result<Theory, String> {
    use scg_core::stages::feeder::FeedSource;
    let scene = scg_scene::parse(text, "<wheel>", "wheel", set).map_err(|e| e.to_string())?;
    let m = scene
        .mesh_flow
        .as_ref()
        .ok_or("the wheel study needs a mesh flow")?;
    let frame = scene
        .extra_forces
        .frame
        .ok_or("the wheel study needs a rotating [frame]")?;
    let fluid = scene.fluid.ok_or("the wheel study needs [fluid]")?;
    let f = scene
        .feeders
        .first()
        .ok_or("the wheel study needs a feeder")?;
    let FeedSource::Patch(inlet) = &f.source else {
        return Err("the wheel study needs a feeder on the inlet patch".into());
    };
    let density = scene
        .groups
        .first()
        .map(|g| g.density)
        .ok_or("the wheel study needs a group")?;
    let omega = frame.omega.length();
    let axis = frame.omega / omega;
    let [lo, hi] = m.flow.geometry().bounds();
    let height = (hi - lo).dot(axis).abs();
    let mid = frame.centre + axis * (0.5 * (lo + hi) - frame.centre).dot(axis);
    let e1 = axis.any_orthonormal_vector();
    let e2 = axis.cross(e1);
    // the circle's averages of the inward and the absolute tangential velocity
    let circle = |r: f64| -> Result<(f64, f64), String> {
        let (mut v_r, mut u_t, mut n) = (0.0, 0.0, 0usize);
        for k in 0..CIRCLE_POINTS {
            let phi = std::f64::consts::TAU * (k as f64 + 0.5) / CIRCLE_POINTS as f64;
            let radial = e1 * phi.cos() + e2 * phi.sin();
            let x = mid + r * radial;
            let Some(c) = m.flow.find_cell(x) else {
                continue;
            };
            let Some(u) = m.flow.velocity_in(c, x) else {
                continue;
            };
            v_r -= u.dot(radial);
            u_t += u.dot(axis.cross(radial)) + omega * r;
            n += 1;
        }
        if n < CIRCLE_POINTS / 2 {
            return Err(format!(
                "the circle r = {r} m about the frame's axis is mostly outside the mesh \
                 ({n} of {CIRCLE_POINTS} points inside)"
            ));
        }
        Ok((v_r / n as f64, u_t / n as f64))
    };
    let mu = fluid.viscosity;
    let r = 1.01 * WHEEL_RADIUS;
    let (v_r, u_theta) = circle(r)?;
    let mut profile = Vec::new();
    for rr in profile_radii() {
        // the blades' circles are partly solid: fewer points inside is fine there
        if let Ok((v, u)) = circle(rr) {
            profile.push((rr, v, u, equilibrium_cut(mu, v, rr, density, u)));
        }
    }
    let q_interp = inlet.flux(&m.flow).inflow;
    let q = cfd_inflow(&scene, inlet.patch).unwrap_or(q_interp);
    let v_r_nominal = q / (std::f64::consts::TAU * r * height);
    Ok(Theory {
        radius: WHEEL_RADIUS,
        sampled_at: r,
        omega,
        v_r,
        u_theta,
        v_r_nominal,
        density,
        viscosity: mu,
        d50_field: equilibrium_cut(mu, v_r, r, density, u_theta),
        d50_nominal: equilibrium_cut(mu, v_r_nominal, r, density, omega * r),
        profile,
        inflow: (q, q_interp),
    })
}

/// The flow into the mesh through patch `patch` by the face values of the case's own
/// field (OpenFOAM's boundary values: −Σ u_f·A_f), m³/s; `None` when the flow is not an
/// OpenFOAM case or the patch has no face values.
fn cfd_inflow(scene: &scg_scene::Scene, patch: usize) -> Option<f64> {
    let m = scene.mesh_flow.as_ref()?;
    let Some(scg_scene::FieldReader::Foam { case, time }) = &m.reader else {
        return None;
    };
    let mesh = m.flow.mesh();
    let field = scg_mesh::foam::read_vector_field(case, mesh, *time, &m.field).ok()?;
    let values = field.patches.get(patch)?.as_ref()?;
    let p = &mesh.patches[patch];
    let areas = &m.flow.geometry().face_areas;
    Some(
        -values
            .iter()
            .enumerate()
            .map(|(k, u)| u.dot(areas[p.start + k]))
            .sum::<f64>(),
    )
}

/// The overrides of one variant: α, law, feed scaled by `feed / α³`, duration.
pub fn variant_overrides(
    name: &str,
    alpha: f64,
    law: &str,
    feed: f64,
    duration: f64,
) -> Vec<String> {
    vec![
        format!("coarse_grain.alpha={alpha}"),
        format!("coarse_grain.law=\"{law}\""),
        format!("feed_scale={:e}", feed / alpha.powi(3)),
        format!("duration={duration}"),
        format!("name=\"wheel-{name}\""),
        format!("record_every={RECORD_EVERY}"),
    ]
}

/// Run one variant of the wheel scene `text` for `duration` s: the fates, and of the
/// particles still inside at the end those outside the wheel radius (about the frame's
/// axis). The snapshot and the residence times are dropped (summary.json stays small).
pub fn run_variant(
    name: &str,
    text: &str,
    overrides: &[String],
    duration: f64,
    mcap: Option<&std::path::Path>,
) -> Result<WheelRun, String> {
    let (mut run, scene, _) =
        super::cyclone::run::run_variant_with(name, text, overrides, duration, mcap, |_| {})?;
    let (axis, centre) = wheel_axis(&scene)?;
    let mut radii = vec![Vec::new(); run.classes.len()];
    for (x, g) in &run.snapshot.1 {
        let d = *x - centre;
        if let Some(r) = radii.get_mut(*g as usize) {
            r.push((d - axis * d.dot(axis)).length());
        }
    }
    let outside = radii
        .iter()
        .map(|r| r.iter().filter(|&&r| r > WHEEL_RADIUS).count() as u64)
        .collect();
    let held_radius = radii
        .iter_mut()
        .map(|r| {
            r.sort_by(f64::total_cmp);
            r.get(r.len() / 2).copied()
        })
        .collect();
    run.snapshot.1.clear();
    for c in &mut run.classes {
        c.residence_times.clear();
    }
    Ok(WheelRun {
        run,
        outside,
        held_radius,
    })
}

/// The wheel's axis (unit) and a point on it: the rotating frame's, else the first
/// frozen-rotor zone's.
pub fn wheel_axis(scene: &scg_scene::Scene) -> Result<(glam::DVec3, glam::DVec3), String> {
    if let Some(f) = scene.extra_forces.frame {
        return Ok((f.omega.normalize(), f.centre));
    }
    scene
        .mesh_flow
        .as_ref()
        .and_then(|m| m.rotors.first())
        .map(|z| (z.omega.normalize(), z.origin))
        .ok_or_else(|| "the wheel study needs a rotating [frame] or a frozen-rotor zone".into())
}

/// Run `scg study wheel` with its variants run through `points`; returns the exit status.
pub fn study(a: StudyArgs, points: &dyn Points) -> i32 {
    let (text, out) = match super::start(&a, "wheel", WHEEL, "wheel/coarse", |from| {
        read_summary(from).map(|s| markdown(&s.variants, &s.theory, s.tracers.as_ref()))
    }) {
        super::Start::Exit(code) => return code,
        super::Start::Run { text, out } => (text, out),
    };
    let (feed, duration) = if a.quick { QUICK } else { FULL };
    let overrides_of = |name: &str, alpha: f64, law: &str| {
        let mut o = variant_overrides(name, alpha, law, feed, duration);
        o.extend(a.set.iter().cloned());
        o
    };
    let theory = match theory(&text, &overrides_of("original", 1.0, "scg")) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let cost: Vec<f64> = VARIANTS.iter().map(|v| v.1.powi(-3)).collect();
    let runs = match run_variants(points, &cost, |i| {
        let (name, alpha, law) = VARIANTS[i];
        let mcap = (!a.no_record).then(|| out.join(format!("wheel-{name}.mcap")));
        eprintln!("study wheel: running variant `{name}` (α = {alpha}, law {law})…");
        let overrides = overrides_of(name, alpha, law);
        let v = run_variant(name, &text, &overrides, duration, mcap.as_deref())
            .map_err(|e| format!("variant `{name}`: {e}"))?;
        eprintln!(
            "  {name} done in {:.1} s ({} particle-steps)",
            v.run.total_s, v.run.particle_steps
        );
        Ok(v)
    }) {
        Variants::Done(runs) => runs,
        Variants::Elsewhere => return 0,
        Variants::Failed => return 1,
    };
    eprintln!("study wheel: the tracer check…");
    let rate = if a.quick { TRACERS.1 } else { TRACERS.0 };
    let tracers = match run_tracers(&text, &a.set, rate) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: the tracer check: {e}");
            return 1;
        }
    };
    eprintln!("study wheel: the originals as a frozen rotor (cases/wheel-mrf.toml)…");
    let frozen = match super::case_scene(WHEEL_MRF, "wheel/coarse-mrf").and_then(|t| {
        let o = overrides_of("frozen-rotor", 1.0, "scg");
        run_variant("frozen-rotor", &t, &o, duration, None)
    }) {
        Ok(v) => v,
        Err(e) => {
            eprintln!("error: the frozen rotor: {e}");
            return 1;
        }
    };
    let mut runs = runs;
    runs.push(frozen);
    let text_report = report(&runs, &theory, Some(&tracers));
    print!("{text_report}");
    let write = |name: &str, text: String| {
        std::fs::write(out.join(name), text)
            .map_err(|e| format!("{}: {e}", out.join(name).display()))
    };
    let json =
        serde_json::to_string_pretty(&summary(&runs, &theory, Some(&tracers), feed, duration))
            .expect("the summary serialises");
    if let Err(e) = write("report.txt", text_report)
        .and_then(|_| write("report.md", markdown(&runs, &theory, Some(&tracers))))
        .and_then(|_| write("summary.json", json))
    {
        eprintln!("error: {e}");
        return 1;
    }
    eprintln!(
        "wrote report.txt, report.md and summary.json under {}",
        out.display()
    );
    0
}

/// A finished study's `summary.json` in `dir`.
pub fn read_summary(dir: &std::path::Path) -> Result<report::Summary, String> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}
