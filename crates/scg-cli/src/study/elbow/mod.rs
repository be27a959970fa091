//! `scg study elbow`: pneumatic conveying through the 90° elbow (`cases/elbow.toml`), run
//! as the originals, SCG (α = 2, 4), the other scaling laws at α = 2 (unchanged density,
//! parcel) and plain sampling (the originals, α³ = 8 and 64 times fewer, each standing for
//! α³): per size class what reaches the end (penetration), what is still in the pipe and
//! what went back out of the inlet, each with its Wilson interval; the wear (Finnie) in
//! total with its interval, by zone along the pipe with the zones' intervals ([`wear`]),
//! where its maximum sits; the wall time; and the tracer check (fluid tracers leave, mean
//! residence V/Q). Every variant feeds the same powder mass: 1/α³ as many particles.
//!
//! In this dilute, one-way coupled flow with impulse walls a coarse particle under SCG
//! moves as an original does, and so does a sampled original: the two differ only in
//! their random streams. What the study shows is whether each law keeps the originals'
//! answers within the intervals, and what a run costs.

pub mod report;
pub mod wear;

use scg_core::stages::erosion::ErosionLog;
use serde::{Deserialize, Serialize};

use super::cyclone::{CycloneRun, TracerCheck, run_tracers};
use super::{StudyArgs, Variants, run_variants};
use crate::EXIT_BAD_INPUT;
use crate::points::Points;

pub use report::{markdown, report, summary};
pub use wear::Wear;

/// The elbow scene (embedded; its `case = "elbow/coarse"` is resolved against `cases/`,
/// see [`super::case_scene`]).
pub const ELBOW: &str = include_str!("../../../../../cases/elbow.toml");

/// The variants: the cyclone study's (name, α, law); here `sample` is the law itself:
/// originals standing for α³ each, fed 1/α³ as many, as every variant.
pub const VARIANTS: [(&str, f64, &str); 7] = super::cyclone::VARIANTS;

/// Feed scale of the full study (on the scene's 2000 particles per class) and the
/// simulated time, s: 10 000 originals per class.
pub const FULL: (f64, f64) = (5.0, 0.1);
/// The same for `--quick`: 1000 per class.
pub const QUICK: (f64, f64) = (0.5, 0.1);
/// Tracers per second over the scene's 10 ms feed (`--quick`: the second).
pub const TRACERS: (f64, f64) = (2.0e5, 5.0e4);
/// Steps between recorded frames in the study's MCAPs (2.5 ms).
pub const RECORD_EVERY: u64 = 100;

/// One variant: the fates per class (the cyclone study's run) and the wear.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ElbowRun {
    /// Fates per class, timing.
    pub run: CycloneRun,
    /// The wear.
    pub wear: Wear,
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
        format!("name=\"elbow-{name}\""),
        format!("record_every={RECORD_EVERY}"),
    ]
}

/// Run one variant: the fates with every impact kept, then the wear by zone.
pub fn run_variant(
    name: &str,
    text: &str,
    overrides: &[String],
    mcap: Option<&std::path::Path>,
) -> Result<ElbowRun, String> {
    let (mut run, scene, sim) =
        super::cyclone::run::run_variant_with(name, text, overrides, 0.0, mcap, |sim| {
            if let Some(mut log) = sim.world.get_resource_mut::<ErosionLog>() {
                log.keep_impacts();
            }
        })?;
    let log = sim
        .world
        .get_resource::<ErosionLog>()
        .ok_or("the elbow study needs [erosion] in the scene")?;
    let m = scene
        .mesh_flow
        .as_ref()
        .ok_or("the elbow study needs a mesh flow")?;
    let g = m.flow.geometry();
    let entered = run.classes.iter().map(|c| c.fed).sum::<u64>() + scene.initial_count();
    let w = wear::wear(
        log.impacts.as_deref().unwrap_or(&[]),
        |f| {
            (
                g.face_centres[f as usize],
                g.face_areas[f as usize].length(),
            )
        },
        log.total_interval(entered),
        entered,
        sim.time(),
    );
    // the residence times are not reported here (summary.json stays small)
    for c in &mut run.classes {
        c.residence_times.clear();
    }
    Ok(ElbowRun { run, wear: w })
}

/// Run `scg study elbow` with its variants run through `points`; returns the exit status.
pub fn study(a: StudyArgs, points: &dyn Points) -> i32 {
    let (text, out) = match super::start(&a, "elbow", ELBOW, "elbow/coarse", |from| {
        read_summary(from).map(|(runs, tracers)| markdown(&runs, tracers.as_ref()))
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
    if let Err(e) = scg_scene::parse(
        &text,
        "<elbow>",
        "elbow",
        &overrides_of("original", 1.0, "scg"),
    ) {
        eprintln!("error: {e}");
        return EXIT_BAD_INPUT;
    }
    let cost: Vec<f64> = VARIANTS.iter().map(|v| v.1.powi(-3)).collect();
    let runs = match run_variants(points, &cost, |i| {
        let (name, alpha, law) = VARIANTS[i];
        let mcap = (!a.no_record).then(|| out.join(format!("elbow-{name}.mcap")));
        eprintln!("study elbow: running variant `{name}` (α = {alpha}, law {law})…");
        let overrides = overrides_of(name, alpha, law);
        let v = run_variant(name, &text, &overrides, mcap.as_deref())
            .map_err(|e| format!("variant `{name}`: {e}"))?;
        eprintln!(
            "  {name} done in {:.1} s ({} particle-steps, {} impacts)",
            v.run.total_s, v.run.particle_steps, v.wear.impacts
        );
        Ok(v)
    }) {
        Variants::Done(runs) => runs,
        Variants::Elsewhere => return 0,
        Variants::Failed => return 1,
    };
    eprintln!("study elbow: the tracer check…");
    let rate = if a.quick { TRACERS.1 } else { TRACERS.0 };
    let tracers = match run_tracers(&text, &a.set, rate) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: the tracer check: {e}");
            return 1;
        }
    };
    print!("{}", report(&runs, Some(&tracers)));
    let write = |name: &str, text: String| {
        std::fs::write(out.join(name), text)
            .map_err(|e| format!("{}: {e}", out.join(name).display()))
    };
    let json = serde_json::to_string_pretty(&summary(&runs, Some(&tracers), feed, duration))
        .expect("the summary serialises");
    if let Err(e) = write("report.txt", report(&runs, Some(&tracers)))
        .and_then(|_| write("report.md", markdown(&runs, Some(&tracers))))
        .and_then(|_| write("wear.csv", report::csv(&runs)))
        .and_then(|_| write("summary.json", json))
    {
        eprintln!("error: {e}");
        return 1;
    }
    eprintln!(
        "wrote report.txt, report.md, wear.csv and summary.json under {}",
        out.display()
    );
    0
}

/// The runs and the tracer check of a finished study's `summary.json` in `dir`.
pub fn read_summary(dir: &std::path::Path) -> Result<(Vec<ElbowRun>, Option<TracerCheck>), String> {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let s: report::Summary =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((s.variants, s.tracers))
}
