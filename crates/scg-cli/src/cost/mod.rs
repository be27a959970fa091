//! `scg cost`: what accuracy costs in time.
//!
//! A sweep over the knobs that trade accuracy for speed — coarse-grain ratio α, the
//! coarse-graining law, a time-step multiplier, the drag integrator and (with wall or
//! particle contacts) a Young's-modulus reduction factor — on one scene. Every point is
//! run to the end and timed; its error is measured against a reference run.
//!
//! # The original particle and the points
//!
//! * **Single-particle mode** (the scene's original group holds exactly one particle, as in
//!   `cases/uniform.toml` and `cases/vortex.toml`): the *original* is the scene's first
//!   group with α = 1 (the first group when none has α = 1). Every point runs a
//!   *population* standing for the same number `N_orig` of original particles
//!   (`--represented`, default [`population::REPRESENTED_DEFAULT`], under `--quick`
//!   [`population::REPRESENTED_QUICK`]): `N_orig / α³` particles of that group with the
//!   point's α and law, particle 0 at the original's start, the others spread over the
//!   region the scene's particles live in (`population`). The other groups of the file
//!   (which only show the paper's CG variants side by side) are dropped.
//! * **Population mode** (any other scene): every group is given the point's α and law and
//!   its random particle count is divided by α³ (a CG particle stands for α³ originals).
//!   No error is computed there yet (see [`population_error_note`]), except on classifier
//!   scenes (per-class W1 and d50; feeders keep the solid volume rate).
//!
//! The points are not the full factorial product: for every (law, α) pair the *base point*
//! uses the first value of each of `--dt-mult`, `--integrators` and `--stiffness`, and each
//! further value of one knob is run with the other knobs at their base value (one knob at
//! a time). α = 1 is the same for every law and runs once, under the law name `original`.
//!
//! # Error
//!
//! The reference is α = 1 with the smallest dt multiplier, the exponential integrator and
//! the largest stiffness factor. The trajectory error of a point is measured on particle 0
//! (the one that starts where the scene's original does) against particle 0 of the
//! reference population: the RMS over common sample times t_k of
//! `|(x(t_k) − x(0)) − (x_ref(t_k) − x_ref(0))| / L`, each particle measured from its own
//! start, with `L` the reference particle's largest displacement from its start. (The
//! maximum over t_k saturates once a particle sits on a wall, which hides how much earlier
//! it got there; the RMS does not.) In the uniform flow and the vortex every particle of a
//! population follows particle 0's path shifted or rotated (the particles do not touch
//! each other), so its error is every particle's. Errors below [`ERROR_FLOOR`] are clamped
//! to it in the plot (log axes cannot show 0); the CSV keeps the measured value.
//!
//! # Timing
//!
//! Points run one after another on the simulator's thread pool (never in parallel), so
//! that each wall time is not distorted by another run. Under `mpirun -np N` (the MPI
//! build) the points are spread over the N ranks ([`crate::points`], balanced by their
//! estimated particle-steps), each rank running its share one after another on its share
//! of the cores, and rank 0 writes the same files; every number but the times is the same
//! bits as on one process (each point is deterministic and runs whole on one rank). The wall time of a point is the
//! whole run of its population, so the speed-up is measured: `wall_ref / wall`, both
//! standing for the same `N_orig` originals. The old estimate — one particle alone timed,
//! multiplied by the originals it stands for — is kept beside it as
//! `est_speedup_alpha3 = (wall_alone_ref / wall_alone) · n / n_ref`, with n = α³ originals
//! per CG particle for `scg`, `none`, `parcel` and 1 for `mass` (whose particle keeps one
//! original's mass). A single particle's run is dominated by the per-step overhead, so
//! that estimate is roughly α³ × the dt multiplier whatever the step costs; it is never
//! the main number.
//!
//! # Files
//!
//! `sweep.rs` designs the points, `population.rs` places a point's population, `run.rs` runs and measures them, `report.rs` writes the
//! CSV and Markdown tables, `plot.rs` the SVG.

mod nan;
mod plot;
mod population;
mod report;
mod run;
mod sweep;

use std::path::PathBuf;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use crate::EXIT_BAD_INPUT;
use crate::points::Points;

pub use plot::plot;
pub use population::{REPRESENTED_DEFAULT, REPRESENTED_QUICK, simulated_count};
pub use report::{csv, markdown};
pub use run::{
    ClassErrors, Outcome, PlanSets, SetTimes, Sweep, est_speedup_alpha3, pareto,
    population_error_note, speedup, sweep,
};
pub use sweep::{
    Design, Point, design, is_classifier, original_group, point_scene, points, single_particle,
};

/// Smallest error shown on the log–log plot.
pub const ERROR_FLOOR: f64 = 1e-16;

/// Arguments of `scg cost`.
#[derive(Args, Debug, Clone)]
pub struct CostArgs {
    /// Scene file.
    pub case: PathBuf,
    /// Output folder for cost.md, cost.csv and cost.svg.
    #[arg(long, default_value = "cost")]
    pub out: PathBuf,
    /// Reduced sweep for CI: a tenth of the duration (at most 0.3 s of simulated time),
    /// laws scg,none,mass,sample, dt multipliers 1,2, the first integrator and stiffness only.
    #[arg(long)]
    pub quick: bool,
    /// Coarse-grain ratios α.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8")]
    pub alphas: Vec<f64>,
    /// Coarse-graining laws.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "scg,none,mass,parcel,sample"
    )]
    pub laws: Vec<String>,
    /// Time-step multipliers (positive integers) applied to the scene's dt.
    #[arg(long = "dt-mult", value_delimiter = ',', default_value = "1,2,4")]
    pub dt_mult: Vec<u32>,
    /// Drag integrators.
    #[arg(long, value_delimiter = ',', default_value = "exponential,explicit")]
    pub integrators: Vec<String>,
    /// Young's-modulus factors (only with walls or contacts).
    #[arg(long, value_delimiter = ',', default_value = "1,0.1")]
    pub stiffness: Vec<f64>,
    /// Single-particle scenes: original particles every point stands for (α = 1 simulates
    /// them all, α simulates N/α³). Default 10000, under `--quick` 2000.
    #[arg(long, value_name = "N")]
    pub represented: Option<usize>,
    /// Override a scene key before the sweep (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// Run `scg cost` with its points run through `points` (every process that shares them
/// calls this; the one that receives the results writes the files); returns the exit
/// status.
pub fn cost(a: CostArgs, points: &dyn Points) -> i32 {
    let mut base = match scg_scene::load(&a.case, &a.set) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let bad = |m: String| {
        eprintln!("error: {m}");
        EXIT_BAD_INPUT
    };
    let d = match design(&a, &mut base) {
        Ok(d) => d,
        Err(m) => return bad(m),
    };
    let (pts, reference) = (&d.points, d.reference);
    if let Err(e) = crate::run::ensure_writable(&a.out) {
        return bad(e);
    }
    let n = 1 + pts.iter().filter(|p| **p != reference).count();
    let (writer, procs) = (points.writer(), points.processes());
    let how = if procs > 1 {
        format!(
            "spread over {procs} processes, each running its points one after another for \
             honest timings"
        )
    } else {
        "run sequentially for honest timings".to_string()
    };
    if writer {
        eprintln!(
            "scg cost `{}`: {} points of {} s simulated each, {how}{}",
            base.name,
            n,
            base.duration,
            if single_particle(&base) {
                format!(
                    " (single-particle scene: every point runs a population standing for {} \
                     originals, N/α³ particles, and times one particle alone for the α³ \
                     estimate)",
                    d.represented
                )
            } else {
                " (population mode)".to_string()
            }
        );
    }
    let bar = if procs == 1 {
        ProgressBar::new(n as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} points  {elapsed_precise} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let swept = sweep(&base, pts, reference, d.represented, points, |o| {
        let msg = format!(
            "{} α={} {:.1e}s {} particles {:.2} s",
            o.point.law_name(),
            o.point.alpha,
            o.dt,
            o.particles().round(),
            o.wall_s
        );
        if procs > 1 {
            eprintln!("  point {msg}");
        }
        bar.set_message(msg);
        bar.inc(1);
    });
    bar.finish_and_clear();
    let Some(s) = swept else {
        return 0;
    };
    let md = markdown(&s);
    let files = [
        (a.out.join("cost.md"), md.clone()),
        (a.out.join("cost.csv"), csv(&s)),
    ];
    crate::run::write_report(&files, &a.out.join("cost.svg"), |p| plot(&s, p), &md)
}
