//! `scg study cyclone`: grade efficiency of the OpenFOAM cyclone (`cases/cyclone.toml`) in
//! seven variants (original, SCG α = 2 and 4, no SCG α = 2, parcel α = 2, and the sampling
//! controls: originals at 1/8 and 1/64 of the feed), the coarse-grained feeding the same
//! mass (1/α³ as many particles), with the scene's wall
//! function, turbulent dispersion and collecting dust outlet: per class the collected,
//! escaped and undecided shares with Wilson intervals, residence times, the cut size
//! beside cyclone theory and, optionally, OpenFOAM's grade curve on the same field
//! (`--openfoam grade.json` of `cases/cyclone/vs-openfoam.sh`).
//!
//! * `theory.rs`: Lapple and Barth–Muschelknautz cut sizes;
//! * `grade.rs`: per-class counts, efficiency, d50, residence-time W1, `grade.json`;
//! * `run.rs`: one variant, every particle tracked from feed to escape;
//! * `report.rs`: `report.txt`, `summary.json`, `grade.csv`, the criteria;
//! * `plot.rs`: the partition curves, residence times, top and side views;
//! * `tracers.rs`: the sanity check, fluid tracers with the study's models.

pub mod grade;
mod plot;
mod report;
pub mod run;
pub mod theory;
pub mod tracers;

use std::path::PathBuf;

pub use grade::{ClassGrade, ExternalGrade, cut_size, cut_size95, efficiency, residence_w1};
pub use plot::write_plots;
pub use report::{Criteria, classes_beyond, criteria, markdown, report, summary, write_tables};
pub use run::{CycloneRun, Tracker, run_variant};
pub use theory::Cyclone;
pub use tracers::{TracerCheck, run_tracers};

use super::{StudyArgs, Variants, run_variants};
use crate::EXIT_BAD_INPUT;
use crate::points::Points;

/// The cyclone scene (embedded so the study runs from any directory; its `flow.case` is
/// resolved against `cases/`, see [`scene_text`]).
pub const CYCLONE: &str = include_str!("../../../../../cases/cyclone.toml");

/// The variants: name, α, law. Law `sample` is the sampling control: originals (α = 1)
/// fed at 1/α³ of the rate, as many simulated particles as the coarse-grained variant of
/// that α, no model error (SCG pays only where it beats this).
pub const VARIANTS: [(&str, f64, &str); 7] = [
    ("original", 1.0, "scg"),
    ("scg2", 2.0, "scg"),
    ("scg4", 4.0, "scg"),
    ("none2", 2.0, "none"),
    ("parcel2", 2.0, "parcel"),
    ("sample2", 2.0, "sample"),
    ("sample4", 4.0, "sample"),
];

/// Feed scale of the full study (on the scene's 200 particles/s per class for 1 s) and
/// its simulated duration, s.
pub const FULL: (f64, f64) = (10.0, 12.0);
/// The same for `--quick`.
pub const QUICK: (f64, f64) = (0.5, 2.0);
/// Tracers per second over the feed window in the study's tracer check (`--quick`: the
/// second).
pub const TRACERS: f64 = 1000.0;
/// The same for `--quick`.
pub const TRACERS_QUICK: f64 = 100.0;
/// Steps between recorded frames in the study's MCAPs (0.1 s).
pub const RECORD_EVERY: u64 = 500;
/// Time of the top / side view snapshot, s (the end of the feed: the spiral is full).
pub const SNAPSHOT_AT: f64 = 1.0;

/// The scene overrides of one variant: α, law, feed scaled by `feed / α³`, duration.
/// Law `sample`: α = 1 (originals) at the same `feed / α³`.
pub fn variant_overrides(alpha: f64, law: &str, feed: f64, duration: f64) -> Vec<String> {
    let (a, l) = if law == "sample" {
        (1.0, "scg")
    } else {
        (alpha, law)
    };
    vec![
        format!("coarse_grain.alpha={a}"),
        format!("coarse_grain.law=\"{l}\""),
        format!("feed_scale={:e}", feed / alpha.powi(3)),
        format!("duration={duration}"),
    ]
}

/// The cyclone scene with its mesh case as an absolute path (see [`super::case_scene`]).
pub fn scene_text() -> Result<String, String> {
    super::case_scene(CYCLONE, "cyclone/coarse")
}

/// The study's scene text and the overrides every run takes: the embedded cyclone scene
/// ([`scene_text`]) and `--set`, or with `--scene FILE` that file's text, its relative
/// `flow.case` made absolute from the file's folder (an override before `--set`'s).
pub fn study_scene(a: &StudyArgs) -> Result<(String, Vec<String>), String> {
    let Some(path) = &a.scene else {
        return Ok((scene_text()?, a.set.clone()));
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| format!("--scene {}: {e}", path.display()))?;
    let table: toml::Table =
        toml::from_str(&text).map_err(|e| format!("--scene {}: {e}", path.display()))?;
    let case = table
        .get("flow")
        .and_then(|f| f.get("case"))
        .and_then(|c| c.as_str())
        .ok_or_else(|| format!("--scene {}: no [flow] case (a mesh case)", path.display()))?;
    let dir = path
        .parent()
        .unwrap_or(std::path::Path::new("."))
        .join(case);
    let dir = dir.canonicalize().map_err(|e| {
        format!(
            "--scene {}: flow.case {}: {e}",
            path.display(),
            dir.display()
        )
    })?;
    let mut set = vec![format!("flow.case={:?}", dir.display().to_string())];
    set.extend(a.set.iter().cloned());
    Ok((text, set))
}

/// The cyclone scene's air field on Barth–Muschelknautz's control surface (the roof at
/// z = 1 m), 64 × 64 points, (v_θ, v_r) in m/s; `None` without a mesh flow. For an
/// unsteady series, the mean over its snapshots (equally spaced: the time average; the
/// surface mean is linear in the velocity, so this is the swirl of the mean field).
pub fn field_swirl(scene: &scg_scene::Scene) -> Option<(f64, f64)> {
    let m = scene.mesh_flow.as_ref()?;
    let at = |flow: &scg_core::physics::mesh_flow::MeshFlow| {
        Cyclone::OPENFOAM_TUTORIAL.control_surface(1.0, 64, |x| {
            flow.find_cell(x).and_then(|c| flow.velocity_in(c, x))
        })
    };
    let Some(series) = &m.series else {
        return at(&m.flow);
    };
    let n = series.times.len();
    let (mut vt, mut vr) = (0.0, 0.0);
    for k in 0..n {
        let (t, r) = match k {
            0 => at(&m.flow)?,
            1 => at(&series.spec.second.flow)?,
            _ => at(&(series.spec.load)(k).ok()?.flow)?,
        };
        vt += t;
        vr += r;
    }
    Some((vt / n as f64, vr / n as f64))
}

/// The tracer check of a finished study's `summary.json` in `dir`, if it has one.
pub fn read_tracers(dir: &std::path::Path) -> Option<TracerCheck> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let s: serde_json::Value = serde_json::from_str(&text).ok()?;
    serde_json::from_value(s.get("tracers")?.clone()).ok()
}

/// A finished study read back from `dir`: the runs of its `summary.json`, each with the
/// snapshot frame (nearest [`SNAPSHOT_AT`]) of its MCAP when there is one. For re-writing
/// the tables and plots (`scg study cyclone --from DIR`) without running again.
pub fn read_study(dir: &std::path::Path) -> Result<Vec<CycloneRun>, String> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let s: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let bad = |what: &str| format!("{}: no {what}", path.display());
    let vars = s["variants"].as_object().ok_or_else(|| bad("variants"))?;
    let mut runs = Vec::new();
    for (name, _, _) in VARIANTS {
        let Some(v) = vars.get(name) else { continue };
        let cls = v["classes"].as_array().ok_or_else(|| bad("classes"))?;
        let classes: Vec<ClassGrade> = cls
            .iter()
            .map(|c| {
                serde_json::from_value(c.clone()).map_err(|e| format!("{}: {e}", path.display()))
            })
            .collect::<Result<_, _>>()?;
        let count = |k: &str| cls.iter().map(|c| c[k].as_u64().unwrap_or(0)).collect();
        let mut snapshot = (0.0, Vec::new());
        let mcap = dir.join(format!("cyclone-{name}.mcap"));
        if mcap.is_file() {
            let rec =
                scg_record::read_mcap(&mcap).map_err(|e| format!("{}: {e}", mcap.display()))?;
            if let Some(f) = rec.frames.iter().min_by(|a, b| {
                (a.time - SNAPSHOT_AT)
                    .abs()
                    .total_cmp(&(b.time - SNAPSHOT_AT).abs())
            }) {
                snapshot = (
                    f.time,
                    f.position
                        .iter()
                        .zip(&f.group)
                        .map(|(p, g)| (glam::DVec3::from_array(*p), *g))
                        .collect(),
                );
            }
        }
        runs.push(CycloneRun {
            name: name.to_string(),
            alpha: v["alpha"].as_f64().ok_or_else(|| bad("alpha"))?,
            law: v["law"].as_str().unwrap_or("").to_string(),
            classes,
            total_s: v["total_s"].as_f64().ok_or_else(|| bad("total_s"))?,
            cpu_s: v["cpu_s"].as_f64(),
            particle_steps: v["particle_steps"].as_u64().unwrap_or(0),
            duration: v["duration_s"].as_f64().unwrap_or(f64::NAN),
            held_moving: count("held_moving"),
            escaped_late: count("escaped_in_last_s"),
            unmatched: v["unmatched_departures"].as_u64().unwrap_or(0),
            snapshot,
        });
    }
    if runs.first().is_none_or(|r| r.name != "original") {
        return Err(bad("original variant"));
    }
    Ok(runs)
}

/// Run `scg study cyclone` with its variants run through `points` (see
/// [`super::study`]); returns the exit status.
pub fn study(a: StudyArgs, points: &dyn Points) -> i32 {
    let openfoam = match &a.openfoam {
        Some(p) => match ExternalGrade::read(p) {
            Ok(g) => Some(g),
            Err(e) => {
                eprintln!("error: --openfoam {e}");
                return EXIT_BAD_INPUT;
            }
        },
        None => None,
    };
    let (text, set) = match study_scene(&a) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    if a.markdown {
        let (Some(from), None) = (&a.from, &a.run) else {
            eprintln!("error: --markdown prints a finished study: give --from DIR, without --run");
            return EXIT_BAD_INPUT;
        };
        return match read_study(from) {
            Ok(runs) => {
                print!("{}", markdown(&runs));
                0
            }
            Err(e) => {
                eprintln!("error: --from {e}");
                EXIT_BAD_INPUT
            }
        };
    }
    let out = a.out.clone().unwrap_or_else(|| {
        PathBuf::from(format!(
            "recordings/study-cyclone{}",
            if a.quick { "-quick" } else { "" }
        ))
    });
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("error: cannot create {}: {e}", out.display());
        return EXIT_BAD_INPUT;
    }
    let (feed, duration) = if a.quick { QUICK } else { FULL };
    let mut runs = Vec::new();
    if let Some(from) = &a.from {
        match read_study(from) {
            Ok(r) => runs = r,
            Err(e) => {
                eprintln!("error: --from {e}");
                return EXIT_BAD_INPUT;
            }
        }
    }
    // The variants to run: `--run`, else all (none with `--from`).
    let to_run: Vec<(&str, f64, &str)> = match &a.run {
        Some(list) => {
            let mut v = Vec::new();
            for n in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
                match VARIANTS.iter().find(|x| x.0 == n) {
                    Some(x) => v.push(*x),
                    None => {
                        eprintln!(
                            "error: --run: unknown variant `{n}` ({})",
                            VARIANTS.map(|x| x.0).join(", ")
                        );
                        return EXIT_BAD_INPUT;
                    }
                }
            }
            v
        }
        None if a.from.is_some() => Vec::new(),
        None => VARIANTS.to_vec(),
    };
    if a.from.is_none() && to_run.first().is_none_or(|v| v.0 != "original") {
        eprintln!("error: --run without --from must include `original` first (the reference)");
        return EXIT_BAD_INPUT;
    }
    if !(a.cg_feed.is_finite() && a.cg_feed > 0.0) {
        eprintln!("error: --cg-feed must be a number > 0, got {}", a.cg_feed);
        return EXIT_BAD_INPUT;
    }
    let overrides_of = |name: &str, alpha: f64, law: &str| {
        let f = if alpha == 1.0 { feed } else { feed * a.cg_feed };
        let mut o = variant_overrides(alpha, law, f, duration);
        o.push(format!("name=\"cyclone-{name}\""));
        o.push(format!("record_every={RECORD_EVERY}"));
        o.extend(set.iter().cloned());
        o
    };
    // Bad `--set` values are bad input (exit 2), found before anything runs.
    if let Some((name, alpha, law)) = to_run.first().copied()
        && let Err(e) = scg_scene::parse(&text, "<cyclone>", name, &overrides_of(name, alpha, law))
    {
        eprintln!("error: {e}");
        return EXIT_BAD_INPUT;
    }
    // The variants are independent: spread over processes by `points` (estimated cost
    // 1/α³ of the original's, the same mass fed), the results in `to_run` order.
    let cost: Vec<f64> = to_run.iter().map(|v| v.1.powi(-3)).collect();
    let done = match run_variants(points, &cost, |i| {
        let (name, alpha, law) = to_run[i];
        let overrides = overrides_of(name, alpha, law);
        let mcap = (!a.no_record).then(|| out.join(format!("cyclone-{name}.mcap")));
        eprintln!("study cyclone: running variant `{name}` (α = {alpha}, law {law})…");
        let v = run_variant(name, &text, &overrides, SNAPSHOT_AT, mcap.as_deref())
            .map_err(|e| format!("variant `{name}`: {e}"))?;
        eprintln!(
            "  {name} done in {:.1} s ({} particle-steps, fed {}, escaped {}, held {}, lost {})",
            v.total_s,
            v.particle_steps,
            v.classes.iter().map(|c| c.fed).sum::<u64>(),
            v.classes.iter().map(|c| c.escaped).sum::<u64>(),
            v.classes.iter().map(|c| c.held).sum::<u64>(),
            v.classes.iter().map(|c| c.lost).sum::<u64>(),
        );
        Ok(v)
    }) {
        Variants::Done(v) => v,
        Variants::Elsewhere => return 0,
        Variants::Failed => return 1,
    };
    for v in done {
        runs.retain(|r: &CycloneRun| r.name != v.name);
        runs.push(v);
    }
    // In the order of VARIANTS (the original first).
    runs.sort_by_key(|r| VARIANTS.iter().position(|v| v.0 == r.name));
    // the scene as the variants ran it: its field's swirl, its outline for the plots
    let scene = match scg_scene::parse(&text, "<cyclone>", "cyclone", &set) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return 1;
        }
    };
    let mut theory = Cyclone::OPENFOAM_TUTORIAL;
    theory.field_swirl = field_swirl(&scene);
    // The tracer check: read back with `--from` when no variant runs, else run.
    let mut tracers = if to_run.is_empty() {
        a.from.as_ref().and_then(|d| read_tracers(d))
    } else {
        None
    };
    if tracers.is_none() {
        eprintln!("study cyclone: the tracer check…");
        let rate = if a.quick { TRACERS_QUICK } else { TRACERS };
        match run_tracers(&text, &set, rate) {
            Ok(t) => {
                eprintln!("  tracers done in {:.1} s", t.total_s);
                tracers = Some(t);
            }
            Err(e) => {
                eprintln!("error: the tracer check: {e}");
                return 1;
            }
        }
    }
    print!(
        "{}",
        report(&runs, &theory, openfoam.as_ref(), tracers.as_ref())
    );
    let outline = scene.patch_surfaces();
    if let Err(e) = write_tables(&runs, &theory, openfoam.as_ref(), tracers.as_ref(), &out)
        .and_then(|_| write_plots(&runs, openfoam.as_ref(), &theory, &outline, &out))
    {
        eprintln!("error: {e}");
        return 1;
    }
    eprintln!(
        "wrote report.txt, summary.json, grade.csv and the plots under {}",
        out.display()
    );
    0
}
