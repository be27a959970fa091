//! The `scg` command line: run, check, bench, replay.

pub mod analysis;
mod bench;
mod chart;
pub mod cost;
pub mod distribution;
pub mod erosion;
pub mod fates;
#[cfg(feature = "mpi")]
pub mod mpi;
pub mod points;
pub mod replay;
pub mod run;
mod stem;
pub mod study;
pub mod tables;

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
    #[command(after_help = "Examples:\n  \
        scg run                                    the paper's vortex case (embedded) into recordings/\n  \
        scg run cases/squarebend.toml --out out    a CFD case: out/squarebend.rrd and .mcap\n  \
        scg run cases/classifier.toml --set coarse_grain.alpha=2 --set duration=0.05\n  \
        scg run --plan cases/duct.toml             the systems the scene runs, in order\n  \
        scg run cases/cyclone.toml --no-record --summary-json s.json --fates-csv fates.csv\n  \
        scg run cases/vortex.toml --vtk vtk        also VTK frames for ParaView\n  \
        scg run cases/cyclone.toml --checkpoint-every 0.5\n  \
        scg run --restart recordings/cyclone.ckpt --set duration=6\n\n\
        The scene keys: docs/scenes.md; what a run writes: docs/cli.md, docs/recordings.md.")]
    Run(run::RunArgs),
    /// Validate scenes and print derived quantities and warnings.
    #[command(after_help = "Examples:\n  \
        scg check cases/*.toml                     every shipped scene\n  \
        scg check cases/cyclone.toml --set dt=1e-4  dt/τ, eddy lifetimes, patches, feeders at another dt\n\n\
        Exit status 2 names the file, key and line of the first bad input.")]
    Check {
        /// Scene files (each checked in turn, e.g. `scg check cases/*.toml`).
        #[arg(required = true, value_name = "CASE")]
        cases: Vec<PathBuf>,
        /// Override a scene key, e.g. `--set groups.0.alpha=2` (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Benchmarks.
    #[command(after_help = "Examples:\n  \
        scg bench drag --particles 1000000 --steps 300\n  \
        scg bench mesh --cells 100000 --particles 300000 --steps 100 --dispersion stochastic-ras\n  \
        scg bench dense --particles 32000 --threads 1\n  \
        scg bench dilute --scene-out dilute.toml   the scene, e.g. for mpirun -np 2 scg run dilute.toml\n\n\
        The last line is `particle-steps/s: N`. Peers: docs/performance.md; earlier figures: CHANGELOG.md.")]
    Bench(bench::BenchArgs),
    /// What accuracy costs in time: sweep α, law, dt, integrator and stiffness on a scene.
    #[command(after_help = "Examples:\n  \
        scg cost cases/vortex.toml --quick         a reduced sweep (CI)\n  \
        scg cost cases/uniform.toml --alphas 1,2,4 --laws scg,none --dt-mult 1,2\n  \
        scg cost cases/classifier.toml --out cost-classifier\n\n\
        Writes cost.md, cost.csv and cost.svg into --out.")]
    Cost(cost::CostArgs),
    /// Studies: `classifier`, `classifier-psd` (paper Section 5, Figs 8–10),
    /// `classifier-cut` (the steady-state cut size) and `cyclone` (grade efficiency of
    /// cases/cyclone.toml in seven variants: coarse-graining laws and sampling).
    #[command(after_help = "Examples:\n  \
        scg study classifier --quick               the paper's Table 3, reduced (minutes)\n  \
        scg study classifier-psd                   size distribution and partition curve\n  \
        scg study cyclone --quick                  grade efficiency, seven variants\n  \
        scg study cyclone --from recordings/study-cyclone --openfoam /tmp/scg-cyclone-vs-openfoam/grade.json\n  \
        scg study cyclone --run scg2 --from recordings/study-cyclone   re-run one variant\n  \
        scg study cyclone --from docs/data/cyclone-study --markdown   the tables docs/cyclone.md quotes\n\n\
        What each study writes: docs/cli.md; the cyclone study: docs/cyclone.md.")]
    Study(study::StudyArgs),
    /// Work from an MCAP recording: rebuild .rrd, analyse, verify.
    #[command(after_help = "Examples:\n  \
        scg replay recordings/vortex.mcap --verify  re-run the embedded scene, compare every frame\n  \
        scg replay recordings/vortex.mcap --rrd vortex.rrd --spawn\n  \
        scg replay recordings/vortex.mcap --analyze --from 1 --to 3\n  \
        scg replay recordings/cyclone.mcap --vtk vtk   frames for ParaView\n  \
        scg replay recordings/cyclone.mcap.partial --rrd cyclone.rrd   a killed run's frames")]
    Replay(replay::ReplayArgs),
}

/// Exit status for bad input (scene, arguments, files).
pub const EXIT_BAD_INPUT: i32 = 2;

/// Parse the process arguments and run; returns the exit status.
pub fn main() -> i32 {
    #[cfg(feature = "mpi")]
    {
        mpi::main()
    }
    #[cfg(not(feature = "mpi"))]
    {
        local_main()
    }
}

/// [`main`] on this process alone (no MPI).
pub fn local_main() -> i32 {
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
    if let Err(e) = scg_core::stages::flow_series::keep_bytes_from_env() {
        eprintln!("error: {e}");
        return EXIT_BAD_INPUT;
    }
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

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::{CommandFactory, Parser};

    /// Every example of `scg --help` and `scg <command> --help` parses as the command
    /// line it shows (the text after two spaces is its description).
    #[test]
    fn every_help_example_parses() {
        let mut root = Cli::command();
        let mut texts = vec![root.render_help().to_string()];
        for sub in root.get_subcommands_mut() {
            texts.push(sub.render_help().to_string());
        }
        let mut n = 0;
        for text in &texts {
            for line in text.lines().filter(|l| l.starts_with("  scg ")) {
                let cmd = line.trim().split("  ").next().unwrap();
                let args: Vec<&str> = cmd.split_whitespace().collect();
                if let Err(e) = Cli::try_parse_from(&args) {
                    panic!("`{cmd}`: {e}");
                }
                n += 1;
            }
        }
        assert!(n >= 30, "{n} examples");
    }
}
