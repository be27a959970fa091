//! `scg study loading`: where SCG pays. The paper's classifier fed at several multiples
//! of its feed rate (the loading), each loading run with the originals (the reference),
//! SCG at α = 2 and 4, and plain sampling at the same particle counts (originals, 1/8 and
//! 1/64 of them). Per loading and method: particle–particle contacts per particle per
//! second beside kinetic theory's scaling, the largest per-class W1 of the radial
//! distributions to the originals' with the W1 sampling noise alone reaches, the cut size
//! with its bootstrap interval, and the wall time.
//!
//! In a dilute one-way coupled flow sampling is exact and as cheap as coarse graining; a
//! coarse-graining law is worth its model error only where particles interact, where
//! sampling α³ fewer originals takes α³ collision partners away from each (the collision
//! frequency of a particle ∝ n·d²: sampling divides it by α³, SCG's α² larger cross section
//! by only α). The sweep finds the loading where that shows beyond the intervals.
//!
//! Every point is a [`crate::cost`] classifier point (same run, timing and error code);
//! `report.rs` writes the table, the CSV and `summary.json`, `plot.rs` the figure.

mod plot;
mod report;

use std::path::PathBuf;

use scg_core::physics::integrate::Integrator;
use scg_core::physics::scaling::CoarseGrainLaw;

use crate::EXIT_BAD_INPUT;
use crate::cost::{Outcome, Point, sweep};
use crate::points::Points;

pub use plot::plot;
pub use report::{Record, csv, markdown, summary, verdicts};

use super::StudyArgs;

/// Loadings (multiples of the scene's feed rate) of the full study.
pub const LOADINGS: [f64; 3] = [1.0, 4.0, 16.0];
/// Loadings of `--quick`.
pub const LOADINGS_QUICK: [f64; 3] = [1.0, 2.0, 4.0];
/// Simulated time of the full study, s (the analysis window is its second half): the
/// classifier's first 30 ms, while the feed builds its hold-up. The cost grows with about
/// the square of the duration: at ×16 the originals take ≈ 10 min on two cores for 30 ms
/// and over an hour for 50 ms (`--set duration=0.05`).
pub const DURATION: f64 = 0.03;
/// Simulated time under `--quick`, s.
pub const DURATION_QUICK: f64 = 0.02;

/// The methods compared at every loading: name, law, α (the originals first).
pub const METHODS: [(&str, Option<CoarseGrainLaw>, f64); 5] = [
    ("original", None, 1.0),
    ("scg2", Some(CoarseGrainLaw::Scg), 2.0),
    ("scg4", Some(CoarseGrainLaw::Scg), 4.0),
    ("sample2", Some(CoarseGrainLaw::Sample), 2.0),
    ("sample4", Some(CoarseGrainLaw::Sample), 4.0),
];

/// One method at one loading.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Row {
    /// Multiple of the scene's feed rate.
    pub loading: f64,
    /// Method name ([`METHODS`]).
    pub method: String,
    /// The point as run, with its measurements and its errors against the originals of
    /// the same loading.
    pub outcome: Outcome,
}

impl Row {
    /// α of the method.
    pub fn alpha(&self) -> f64 {
        self.outcome.point.alpha
    }

    /// The law (`None`: the originals).
    pub fn law(&self) -> Option<CoarseGrainLaw> {
        self.outcome.point.law
    }
}

/// The point of a method (the scene's dt, the exponential integrator, its stiffness).
fn point(law: Option<CoarseGrainLaw>, alpha: f64) -> Point {
    Point {
        law,
        alpha,
        dt_mult: 1,
        integrator: Integrator::Exponential,
        stiffness: 1.0,
    }
}

/// The rows and the simulated duration of a finished study (its `summary.json` in `dir`).
pub fn read_study(dir: &std::path::Path) -> Result<(Vec<Record>, f64), String> {
    let p = dir.join("summary.json");
    let text = std::fs::read_to_string(&p).map_err(|e| format!("{}: {e}", p.display()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", p.display()))?;
    // the records; or, from a summary that has only the points, the records of them
    let rows: Vec<Record> = match (v.get("records"), v.get("points").or(v.get("rows"))) {
        (Some(r), _) => serde_json::from_value(r.clone())
            .map_err(|e| format!("{}: records: {e}", p.display()))?,
        (None, Some(points)) => serde_json::from_value::<Vec<Row>>(points.clone())
            .map_err(|e| format!("{}: points: {e}", p.display()))?
            .iter()
            .map(Record::of)
            .collect(),
        (None, None) => Vec::new(),
    };
    let duration = v
        .get("duration_s")
        .and_then(serde_json::Value::as_f64)
        .ok_or_else(|| format!("{}: no duration_s", p.display()))?;
    if rows.is_empty() {
        return Err(format!("{}: no records", p.display()));
    }
    Ok((rows, duration))
}

/// Run `scg study loading`; returns the exit status.
pub fn study(a: StudyArgs, points: &dyn Points) -> i32 {
    if a.markdown || a.from.is_some() {
        let (Some(from), true) = (&a.from, a.markdown) else {
            eprintln!(
                "error: `scg study loading` prints a finished study with --from DIR --markdown \
                 (both)"
            );
            return EXIT_BAD_INPUT;
        };
        return match read_study(from) {
            Ok((rows, duration)) => {
                print!("{}", markdown(&rows, duration));
                0
            }
            Err(e) => {
                eprintln!("error: --from {e}");
                EXIT_BAD_INPUT
            }
        };
    }
    let loadings: Vec<f64> = match &a.loadings {
        Some(l) => l.clone(),
        None if a.quick => LOADINGS_QUICK.to_vec(),
        None => LOADINGS.to_vec(),
    };
    if loadings.is_empty() || loadings.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
        eprintln!("error: --loadings must be positive numbers, got {loadings:?}");
        return EXIT_BAD_INPUT;
    }
    let duration = if a.quick { DURATION_QUICK } else { DURATION };
    let out = a.out.clone().unwrap_or_else(|| {
        PathBuf::from(format!(
            "recordings/study-loading{}",
            if a.quick { "-quick" } else { "" }
        ))
    });
    if let Err(e) = crate::run::ensure_writable(&out) {
        eprintln!("error: {e}");
        return EXIT_BAD_INPUT;
    }
    let writer = points.writer();
    let reference = point(None, 1.0);
    let others: Vec<Point> = METHODS[1..].iter().map(|m| point(m.1, m.2)).collect();
    let mut rows = Vec::new();
    for &l in &loadings {
        let mut sets = vec![
            format!("duration={duration:e}"),
            format!("feed_scale={l:e}"),
        ];
        sets.extend(a.set.iter().cloned());
        let base = match scg_scene::parse(super::CLASSIFIER, "<study>", "classifier", &sets) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {e}");
                return EXIT_BAD_INPUT;
            }
        };
        if writer {
            eprintln!(
                "study loading: ×{l} the paper's feed, {} s simulated, {} methods…",
                base.duration,
                METHODS.len()
            );
        }
        let progress = |o: &Outcome| {
            if points.processes() == 1 {
                eprintln!(
                    "  {} α={} {:.0} particles, {} pair contacts, {:.1} s",
                    o.point.law_name(),
                    o.point.alpha,
                    o.particles(),
                    o.pair_contacts,
                    o.wall_s
                );
            }
        };
        let Some(s) = sweep(&base, &others, reference, 1, points, progress) else {
            // not the writer: its points are done
            continue;
        };
        for (m, o) in METHODS.iter().zip(s.outcomes) {
            rows.push(Row {
                loading: l,
                method: m.0.to_string(),
                outcome: o,
            });
        }
    }
    if !writer {
        return 0;
    }
    let records: Vec<Record> = rows.iter().map(Record::of).collect();
    let md = format!(
        "# Where SCG pays: the classifier at several loadings\n\n{}\nPlot: `loading.svg` (W1/R \
         against wall time, one curve per method family, one panel per loading; hollow markers \
         agree with the originals within the intervals).\n",
        markdown(&records, duration)
    );
    let files = [
        (out.join("loading.md"), md.clone()),
        (out.join("loading.csv"), csv(&records)),
        (
            out.join("summary.json"),
            serde_json::to_string_pretty(&summary(&rows, duration)).unwrap_or_default(),
        ),
    ];
    crate::run::write_report(&files, &out.join("loading.svg"), |p| plot(&records, p), &md)
}
