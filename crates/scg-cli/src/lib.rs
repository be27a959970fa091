//! The `scg` command line: run, check, bench, replay.

pub mod analysis;
mod bench;
mod chart;
pub mod cost;
pub mod fates;
pub mod points;
pub mod replay;
pub mod run;
mod stem;
pub mod study;

use std::path::PathBuf;

use clap::{Parser, Subcommand};

/// scg — a DEM simulator for dilute particle-laden flows with the simpler coarse-grain model.
#[derive(Parser, Debug)]
#[command(
    name = "scg",
    version,
    about = "scg: DEM of particles carried by a prescribed fluid flow, with the simpler \
             coarse-grain (SCG) model of Kushimoto et al. (Processes 2021, 9, 1098) beside the \
             other coarse-graining laws. Recordings open in the Rerun viewer (.rrd) and as MCAP.",
    long_about = None,
    after_help = "Examples:\n  \
        scg run                                   the paper's vortex case (embedded)\n  \
        scg run cases/classifier.toml --set coarse_grain.alpha=2\n  \
        scg run --plan cases/uniform.toml         the systems a scene runs, in order\n  \
        scg check cases/classifier.toml           derived quantities and warnings\n  \
        scg replay recordings/vortex.mcap --verify\n  \
        scg study classifier --quick              the paper's Section 5, reduced\n  \
        scg study cyclone --quick                 grade efficiency of a real cyclone, five variants\n  \
        scg cost cases/vortex.toml --quick        what accuracy costs in time\n\n\
        Scene format: docs/scenes.md. Threads: --threads N or SCG_THREADS (same bits for any N)."
)]
pub struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Worker threads, the caller included (default: `SCG_THREADS`, else one per core).
    /// Results are bit-identical for any count.
    #[arg(long, global = true, value_name = "N")]
    threads: Option<usize>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scene (the embedded vortex case when no file is given).
    Run(run::RunArgs),
    /// Validate scenes and print derived quantities and warnings.
    Check {
        /// Scene files (each checked in turn, e.g. `scg check cases/*.toml`).
        #[arg(required = true, value_name = "CASE")]
        cases: Vec<PathBuf>,
        /// Override a scene key, e.g. `--set groups.0.alpha=2` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Benchmarks.
    Bench(bench::BenchArgs),
    /// What accuracy costs in time: sweep α, law, dt, integrator and stiffness on a scene.
    Cost(cost::CostArgs),
    /// Studies: `classifier`, `classifier-psd` (paper Section 5, Figs 8–10),
    /// `classifier-cut` (the steady-state cut size) and `cyclone` (grade efficiency of
    /// cases/cyclone.toml in five coarse-graining variants).
    Study(study::StudyArgs),
    /// Work from an MCAP recording: rebuild .rrd, analyse, verify.
    Replay(replay::ReplayArgs),
}

/// Exit status for bad input (scene, arguments, files).
pub const EXIT_BAD_INPUT: i32 = 2;

/// Parse the process arguments and run; returns the exit status.
pub fn main() -> i32 {
    main_with(&Launch {
        run: &run::run,
        points: &points::Local,
        others: true,
        threads: 0,
    })
}

/// How [`main_with`] runs the commands.
pub struct Launch<'a> {
    /// `scg run` (another one runs a simulation decomposed over MPI ranks).
    pub run: &'a dyn Fn(run::RunArgs) -> i32,
    /// Where the independent points of `scg cost` and `scg study` run (another one
    /// spreads them over MPI ranks; those two subcommands run on every rank).
    pub points: &'a dyn points::Points,
    /// Whether the other subcommands run (on one rank of a decomposed run; the others
    /// return 0 without doing anything).
    pub others: bool,
    /// Worker threads when neither `--threads` nor `SCG_THREADS` says (0 = one per core).
    pub threads: usize,
}

/// [`main`], with the commands run as `launch` says.
pub fn main_with(launch: &Launch) -> i32 {
    let (run_cmd, others) = (launch.run, launch.others);
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let _ = e.print();
            return match e.kind() {
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion => 0,
                _ => EXIT_BAD_INPUT,
            };
        }
    };
    // The execution settings are read once, here, before anything runs in parallel.
    let mut exec = scg_core::exec::ExecSettings::from_env();
    if exec.threads == 0 {
        exec.threads = launch.threads;
    }
    if let Some(n) = cli.threads {
        exec.threads = n;
    }
    scg_core::exec::configure(exec);
    match cli.command {
        None => run_cmd(run::RunArgs::default()),
        Some(Command::Run(a)) => run_cmd(a),
        Some(Command::Study(a)) => study::study(a, launch.points),
        Some(Command::Cost(a)) => cost::cost(a, launch.points),
        Some(_) if !others => 0,
        Some(Command::Check { cases, set }) => cases
            .iter()
            .map(|case| check(case, &set))
            .max()
            .unwrap_or(0),
        Some(Command::Bench(a)) => bench::bench(a),
        Some(Command::Replay(a)) => replay::replay(a),
    }
}

fn check(case: &std::path::Path, set: &[String]) -> i32 {
    let scene = match scg_scene::load(case, set) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let report = scg_scene::check::check(&scene);
    print!("{}", scg_scene::check::render(&scene, &report));
    if report.has_errors() {
        EXIT_BAD_INPUT
    } else {
        0
    }
}
