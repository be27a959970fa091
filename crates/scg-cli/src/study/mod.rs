//! `scg study classifier|classifier-psd`: the paper's Section 5 end to end. Runs the four
//! variants (original, CG α = 2 with SCG, CG α = 2 without SCG, and the sampling control:
//! originals, 8 times fewer), then writes the radial
//! distributions (Fig. 10), top-view snapshots (Fig. 9), drained fractions and the
//! partition curves with both cut sizes (finite-time drained, steady-state fates), the computing time for 0.1 s (Fig. 8), the normalised W1
//! distances to the original, and `summary.json`. `scg study cyclone` ([`cyclone`]): grade
//! efficiency of the OpenFOAM cyclone in seven variants, beside cyclone theory and OpenFOAM.
//! `scg study loading` ([`loading`]): the classifier at several feed rates, SCG against
//! sampling where particles collide.

pub mod cyclone;
pub mod elbow;
pub mod loading;
pub(crate) mod plot;
mod report;
mod run;
pub mod wheel;

use std::path::{Path, PathBuf};

use clap::Args;

use crate::EXIT_BAD_INPUT;
use crate::points::{Points, map};

/// W1 of each class to the reference variant (lives in [`crate::analysis`]).
pub use crate::analysis::w1_to;
pub use plot::{plot_partition, plot_radial, plot_snapshot, plot_time, write_plots};
pub use report::{report, summary, write_tables};
pub use run::{VariantRun, run_variant};

/// The classifier scene (embedded so the study runs from any directory).
pub const CLASSIFIER: &str = include_str!("../../../../cases/classifier.toml");
/// The classifier with a continuous size distribution.
pub const CLASSIFIER_PSD: &str = include_str!("../../../../cases/classifier-psd.toml");
/// The classifier with its classes concentrated at the cut (steady-state d50).
pub const CLASSIFIER_CUT: &str = include_str!("../../../../cases/classifier-cut.toml");

/// Arguments of `scg study`.
#[derive(Args, Debug)]
pub struct StudyArgs {
    /// `classifier` (paper Table 3), `classifier-psd` (size distribution, partition curve),
    /// `classifier-cut` (classes at the cut: the steady-state d50), `cyclone` (grade
    /// efficiency of cases/cyclone.toml in seven variants and the tracer check), `elbow`
    /// (pneumatic conveying through cases/elbow.toml: penetration per class and where the
    /// bend wears, in seven variants, and the tracer check), `loading` (the classifier
    /// at several feed rates: SCG against sampling where particles collide) or `wheel`
    /// (the deflector-wheel classifier cases/wheel.toml in its rotating frame: fines,
    /// rejected and orbiting per class, the cut size beside the equilibrium cut, seven
    /// variants, the tracer check).
    pub study: String,
    /// Fewer particles (feed rates scaled down): a few minutes in all.
    #[arg(long)]
    pub quick: bool,
    /// Output folder (default `recordings/study-<study>[-quick]`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Do not write an MCAP recording per variant.
    #[arg(long)]
    pub no_record: bool,
    /// Extra scene overrides applied to every variant (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// `cyclone` only: OpenFOAM's grade curve (`grade.json` of cases/cyclone/vs-openfoam.sh)
    /// to add as a column and a curve.
    #[arg(long, value_name = "FILE")]
    pub openfoam: Option<PathBuf>,
    /// `cyclone`: do not run; re-write the tables and plots of the finished study in this
    /// folder (its summary.json and MCAPs) into `--out`, e.g. with `--openfoam`. `loading`,
    /// `elbow` and `wheel`: with `--markdown`, print the finished study's table.
    #[arg(long, value_name = "DIR")]
    pub from: Option<PathBuf>,
    /// `cyclone` only: run just these variants (comma-separated: original, scg2, scg4,
    /// none2, parcel2, sample2, sample4), replacing those read with `--from`.
    #[arg(long, value_name = "NAMES")]
    pub run: Option<String>,
    /// `cyclone` only: feed the coarse-grained variants this many times the same-mass
    /// count (more particles: less sampling noise, no longer the same cost).
    #[arg(long, value_name = "F", default_value_t = 1.0)]
    pub cg_feed: f64,
    /// `cyclone`, `elbow`, `loading` and `wheel`, with `--from` (and no `--run`): print the study's tables in
    /// Markdown (as docs/ quotes them) and write nothing.
    #[arg(long)]
    pub markdown: bool,
    /// `loading` only: multiples of the classifier's feed rate to run (default 1,4,16;
    /// e.g. `--loadings 1,4,16,64` for the dense end, ≈ 1 h more).
    #[arg(long, value_delimiter = ',', value_name = "L")]
    pub loadings: Option<Vec<f64>>,
    /// `cyclone` only: run the study on this scene file instead of the embedded
    /// cases/cyclone.toml (e.g. cases/cyclone-les.toml, the unsteady LES series); its
    /// relative `flow.case` is resolved from the file's folder.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
}

impl StudyArgs {
    /// `scg study NAME` with every flag at its command-line default.
    pub fn new(study: &str) -> Self {
        StudyArgs {
            study: study.to_string(),
            quick: false,
            out: None,
            no_record: false,
            set: Vec::new(),
            openfoam: None,
            from: None,
            run: None,
            cg_feed: 1.0,
            markdown: false,
            loadings: None,
            scene: None,
        }
    }
}

/// One study: its scene and windows.
#[derive(Clone, Debug)]
pub struct StudySpec {
    /// Name.
    pub name: &'static str,
    /// Scene text.
    pub scene: &'static str,
    /// Analysis window (distributions), s; the computing time is measured over its last
    /// 0.1 s, the drained fraction over the particles fed up to half of `to`.
    pub window: (f64, f64),
    /// Feed-rate scale of `--quick`.
    pub quick_scale: f64,
}

/// The studies.
pub fn spec(name: &str) -> Option<StudySpec> {
    match name {
        "classifier" => Some(StudySpec {
            name: "classifier",
            scene: CLASSIFIER,
            window: (0.2, 0.3),
            quick_scale: 1.0 / 12.0,
        }),
        "classifier-psd" => Some(StudySpec {
            name: "classifier-psd",
            scene: CLASSIFIER_PSD,
            window: (0.5, 0.6),
            quick_scale: 1.0 / 4.0,
        }),
        "classifier-cut" => Some(StudySpec {
            name: "classifier-cut",
            scene: CLASSIFIER_CUT,
            window: (0.9, 1.0),
            quick_scale: 1.0 / 2.0,
        }),
        _ => None,
    }
}

/// The variants: name and the overrides that select them. `sample` is the control a
/// coarse-graining law must beat: originals, α³ = 8 times fewer (the count `scg` runs).
pub const VARIANTS: [(&str, [&str; 2]); 4] = [
    ("original", ["coarse_grain.alpha=1", "coarse_grain.law=scg"]),
    ("scg", ["coarse_grain.alpha=2", "coarse_grain.law=scg"]),
    ("none", ["coarse_grain.alpha=2", "coarse_grain.law=none"]),
    (
        "sample",
        ["coarse_grain.alpha=2", "coarse_grain.law=sample"],
    ),
];

/// How a mesh-case study (`elbow`, `wheel`) starts.
pub enum Start {
    /// Nothing to run: exit with this status (`--markdown` printed a finished study, or
    /// the arguments were refused).
    Exit(i32),
    /// Run: the embedded scene with its case made absolute, and the output folder (made).
    Run {
        /// The scene text.
        text: String,
        /// The output folder.
        out: PathBuf,
    },
}

/// The start every mesh-case study shares: `--openfoam`, `--run`, `--cg-feed` and
/// `--loadings` are refused; `--markdown --from DIR` prints `markdown(DIR)` (a finished
/// study's tables) and exits, `--markdown` needs `--from` and `--from` needs `--markdown`;
/// else the embedded `scene` with its mesh `case` ([`case_scene`]) and the output folder
/// (`--out`, default `recordings/study-<study>[-quick]`), created.
pub fn start(
    a: &StudyArgs,
    study: &str,
    scene: &str,
    case: &str,
    markdown: impl FnOnce(&Path) -> Result<String, String>,
) -> Start {
    if a.openfoam.is_some() || a.run.is_some() || a.cg_feed != 1.0 || a.loadings.is_some() {
        eprintln!(
            "error: --openfoam, --run, --cg-feed and --loadings are not for `scg study {study}`"
        );
        return Start::Exit(EXIT_BAD_INPUT);
    }
    if a.markdown {
        let Some(from) = &a.from else {
            eprintln!("error: --markdown prints a finished study: give --from DIR");
            return Start::Exit(EXIT_BAD_INPUT);
        };
        return match markdown(from) {
            Ok(text) => {
                print!("{text}");
                Start::Exit(0)
            }
            Err(e) => {
                eprintln!("error: --from {e}");
                Start::Exit(EXIT_BAD_INPUT)
            }
        };
    }
    if a.from.is_some() {
        eprintln!("error: `scg study {study} --from DIR` needs --markdown");
        return Start::Exit(EXIT_BAD_INPUT);
    }
    let text = match case_scene(scene, case) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("error: {e}");
            return Start::Exit(EXIT_BAD_INPUT);
        }
    };
    let out = a.out.clone().unwrap_or_else(|| {
        PathBuf::from(format!(
            "recordings/study-{study}{}",
            if a.quick { "-quick" } else { "" }
        ))
    });
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("error: cannot create {}: {e}", out.display());
        return Start::Exit(EXIT_BAD_INPUT);
    }
    Start::Run { text, out }
}

/// An embedded scene `text` whose mesh case `case = "<case>"` (relative to `cases/`) is
/// made an absolute path, found under `SCG_CASES`, else `./cases`, else the `cases/` of
/// the source tree the executable was built from.
pub fn case_scene(text: &str, case: &str) -> Result<String, String> {
    let built = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../cases");
    let candidates: Vec<PathBuf> = match std::env::var_os("SCG_CASES") {
        Some(c) => vec![PathBuf::from(c)],
        None => vec![PathBuf::from("cases"), built],
    };
    let Some(dir) = candidates
        .iter()
        .map(|c| c.join(case))
        .find(|d| d.join("constant/polyMesh").is_dir())
    else {
        return Err(format!(
            "the mesh case is not at {} (set SCG_CASES to the repository's cases/ folder)",
            candidates[0].join(case).display()
        ));
    };
    let dir = dir.canonicalize().map_err(|e| e.to_string())?;
    let key = format!("case = \"{case}\"");
    if !text.contains(&key) {
        return Err(format!("the embedded scene has no `{key}`"));
    }
    Ok(text.replacen(&key, &format!("case = {:?}", dir.display().to_string()), 1))
}

/// What [`run_variants`] gives the process that called it.
pub enum Variants<T> {
    /// Every variant's result, in order (the process that gathers them).
    Done(Vec<T>),
    /// Another process gathers the results: nothing to write here.
    Elsewhere,
    /// A variant failed (its error printed): the study stops, exit status 1.
    Failed,
}

/// Run `cost.len()` independent variants through `points` (`cost`: each one's estimated
/// cost, to spread them over processes), `job(i)` running variant `i` and printing its
/// own progress; a variant that fails prints its error and stops this process's share
/// (the rest is not run).
pub fn run_variants<T: serde::Serialize + serde::de::DeserializeOwned>(
    points: &dyn Points,
    cost: &[f64],
    mut job: impl FnMut(usize) -> Result<T, String>,
) -> Variants<T> {
    let mut failed = false;
    let results = map(points, cost.len(), cost, |i| {
        if failed {
            return Err(String::new());
        }
        let r = job(i);
        if let Err(e) = &r {
            failed = true;
            eprintln!("error: {e}");
        }
        r
    });
    match results {
        None => Variants::Elsewhere,
        Some(r) => match r.into_iter().collect::<Result<Vec<T>, String>>() {
            Ok(v) => Variants::Done(v),
            Err(_) => Variants::Failed,
        },
    }
}

/// Write every table and plot of a study into `out`; returns the text report.
pub fn write_outputs(runs: &[VariantRun], nozzle: f64, out: &Path) -> Result<String, String> {
    let text = write_tables(runs, out)?;
    write_plots(runs, nozzle, out)?;
    Ok(text)
}

/// Run `scg study` with its variants run through `points` (every process that shares
/// them calls this; the one that receives the results writes the outputs, the MCAPs are
/// written by the process that ran the variant); returns the exit status.
pub fn study(a: StudyArgs, points: &dyn Points) -> i32 {
    if a.loadings.is_some() && a.study != "loading" {
        eprintln!("error: --loadings is for `scg study loading` only");
        return EXIT_BAD_INPUT;
    }
    if a.scene.is_some() && a.study != "cyclone" {
        eprintln!("error: --scene is for `scg study cyclone` only");
        return EXIT_BAD_INPUT;
    }
    if a.study == "cyclone" {
        return cyclone::study(a, points);
    }
    if a.study == "elbow" {
        return elbow::study(a, points);
    }
    if a.study == "wheel" {
        return wheel::study(a, points);
    }
    if a.study == "loading" {
        if a.openfoam.is_some() || a.run.is_some() {
            eprintln!("error: --openfoam and --run are for `scg study cyclone`");
            return EXIT_BAD_INPUT;
        }
        return loading::study(a, points);
    }
    let Some(spec) = spec(&a.study) else {
        eprintln!(
            "error: unknown study `{}` (classifier, classifier-psd, classifier-cut, cyclone, \
             elbow, loading, wheel)",
            a.study
        );
        return EXIT_BAD_INPUT;
    };
    if a.openfoam.is_some() || a.from.is_some() || a.run.is_some() || a.cg_feed != 1.0 || a.markdown
    {
        eprintln!(
            "error: --openfoam, --from, --run, --cg-feed and --markdown are for `scg study cyclone` only"
        );
        return EXIT_BAD_INPUT;
    }
    let out = a.out.clone().unwrap_or_else(|| {
        PathBuf::from(format!(
            "recordings/study-{}{}",
            spec.name,
            if a.quick { "-quick" } else { "" }
        ))
    });
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("error: cannot create {}: {e}", out.display());
        return EXIT_BAD_INPUT;
    }
    let nozzle = scg_scene::parse(spec.scene, "<study>", spec.name, &[])
        .ok()
        .and_then(|s| s.outlet)
        .map_or(0.0, |o| o.geometry.nozzle_radius);
    // The variants are independent: spread over processes by `points` (estimated cost
    // 1/α³: feeders keep the solid volume rate), the results in variant order.
    let cost: Vec<f64> = VARIANTS
        .iter()
        .map(|(_, sets)| {
            sets.iter()
                .find_map(|s| s.strip_prefix("coarse_grain.alpha="))
                .and_then(|a| a.parse::<f64>().ok())
                .map_or(1.0, |a| a.powi(-3))
        })
        .collect();
    let runs = match run_variants(points, &cost, |i| {
        let (name, sets) = VARIANTS[i];
        let mut overrides: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        overrides.push(format!("name=\"{}-{name}\"", spec.name));
        if a.quick {
            overrides.push(format!("feed_scale={}", spec.quick_scale));
        }
        overrides.extend(a.set.iter().cloned());
        let mcap = (!a.no_record).then(|| out.join(format!("{}-{name}.mcap", spec.name)));
        eprintln!("study {}: running variant `{name}`…", spec.name);
        let v = run_variant(name, spec.scene, &overrides, spec.window, mcap.as_deref())
            .map_err(|e| format!("variant `{name}`: {e}"))?;
        eprintln!(
            "  {name} done in {:.1} s ({} resident, 0.1 s took {:.2} s)",
            v.total_s, v.resident, v.time_s
        );
        Ok(v)
    }) {
        Variants::Done(runs) => runs,
        Variants::Elsewhere => return 0,
        Variants::Failed => return 1,
    };
    match write_outputs(&runs, nozzle, &out) {
        Ok(text) => print!("{text}"),
        Err(e) => {
            eprintln!("error: {e}");
            return 1;
        }
    }
    eprintln!(
        "wrote tables, plots and summary.json under {}",
        out.display()
    );
    0
}
