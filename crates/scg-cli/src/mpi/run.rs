//! `mpirun -np N scg run CASE`: the command line of a decomposed run — the options
//! checked, the recorders made (rank 0's, or every rank's part with `--per-rank`), the
//! run handed to [`scg_mpi::driver::Decomposed`] and its report printed.

use std::io::Write;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use scg_core::frame::{FrameSink, RunMeta};
use scg_core::stages::recording::RecordingParams;
use scg_mpi::comm::Comm;
use scg_mpi::driver::{CheckpointPlan, Decomposed, Decomposition, Options, all_ok};

use super::checkpoints::{self, Ckpt};
use crate::EXIT_BAD_INPUT;
use crate::run::{RunArgs, ensure_writable, extra_sinks};

/// Run `scg run` over the ranks of `comm`; returns the exit status (the same on every
/// rank).
pub fn run(comm: &Comm, args: RunArgs) -> i32 {
    let root = comm.rank() == 0;
    let (scene, report) = match crate::run::load_checked(&args, root) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let record = !args.no_record;
    if args.plan {
        if root {
            let sim = scene.build(record);
            println!(
                "schedule of scene `{}` ({} systems, on each of {} MPI ranks):",
                scene.name,
                sim.plan().systems.len(),
                comm.size()
            );
            print!("{}", sim.plan().render());
        }
        return 0;
    }
    // Written per rank, a frame is never whole anywhere: the formats that need it are
    // made from the set afterwards.
    let per_rank = args.per_rank && comm.size() > 1 && record;
    if per_rank && (args.vtk.is_some() || args.frames_csv.is_some()) {
        if root {
            eprintln!(
                "error: --per-rank writes no whole frame, so no --vtk or --frames-csv during the run: make them from the recording with `scg replay <stem>.mcap --vtk DIR` (or --frames-csv DIR)"
            );
        }
        return EXIT_BAD_INPUT;
    }
    // The recording stage is the driver's (gathered on rank 0, or each rank's own part
    // with --per-rank), not the schedule's.
    let mut sim = scene.build(false);
    let Ckpt {
        every,
        path: checkpoint_path,
        stem,
    } = match checkpoints::prepare(comm, &args, &scene, &mut sim) {
        Ok(c) => c,
        Err(code) => return code,
    };
    let how = match decomposition_from_env() {
        Ok(h) => h,
        Err(e) => {
            if root {
                eprintln!("error: {e}");
            }
            return EXIT_BAD_INPUT;
        }
    };

    // Sinks on rank 0; every rank learns whether they could be made.
    let mut sinks: Option<Box<dyn FrameSink>> = None;
    let mut paths = Vec::new();
    let mut made = Ok(());
    if per_rank {
        made = make_part_sink(&scene, &args, &report, &stem, comm, &mut paths)
            .map(|s| sinks = Some(s));
        if let Err((e, _)) = &made {
            eprintln!("error: rank {}: {e}", comm.rank());
        }
    } else if root && record {
        made = make_sinks(&scene, &args, &report, &stem, comm.size(), &mut paths)
            .map(|s| sinks = Some(s));
        if let Err((e, _)) = &made {
            eprintln!("error: {e}");
        }
    }
    if !all_ok(comm, made.is_ok()) {
        // The ranks that failed know why; the others stop with the same status.
        let code = match &made {
            Err((_, c)) => *c as u64,
            Ok(()) => 0,
        };
        return comm.all_gather_u64(&[code]).into_iter().max().unwrap_or(1) as i32;
    }

    let mut d = match Decomposed::new(comm, sim, &scene, how) {
        Ok(d) => d,
        Err(e) => {
            if root {
                eprintln!("error: {e}");
            }
            return EXIT_BAD_INPUT;
        }
    };
    let opts = Options {
        recording: record.then(|| RecordingParams {
            every: scene.record_every.max(1),
            groups: scene.sim_config(true).groups,
        }),
        per_rank,
        checkpoint: every.map(|every| CheckpointPlan {
            every,
            path: checkpoint_path.clone(),
            scene: scene.source.clone(),
            scene_file: scene.absolute_file(),
        }),
        count_every_step: std::env::var_os("SCG_MPI_COUNTS").is_some(),
    };
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let _ = signal_hook::flag::register(sig, Arc::clone(&stop));
    }
    let steps = scene.steps();
    if root {
        let n0 = scene.groups.iter().map(|g| g.count()).sum::<usize>();
        eprintln!(
            "running `{}` on {} MPI ranks × {} threads: {} particles, {} steps of {:.3e} s, particles {}",
            scene.name,
            comm.size(),
            scg_core::exec::settings().team_size(),
            n0,
            steps,
            scene.dt,
            d.describe()
        );
    }
    // `SCG_MPI_COUNTS=FILE`: rank 0 writes the step, the particle count and an
    // order-independent digest of the ids after every step (tests: no particle lost or
    // duplicated).
    let mut counts_log = match std::env::var_os("SCG_MPI_COUNTS") {
        Some(p) if root => match std::fs::File::create(&p) {
            Ok(f) => Some(std::io::BufWriter::new(f)),
            Err(e) => {
                eprintln!("error: SCG_MPI_COUNTS {}: {e}", p.to_string_lossy());
                None
            }
        },
        _ => None,
    };
    let particle_steps0 = d.sim.particle_steps();
    let out = d.run(
        steps,
        &opts,
        sinks.as_deref_mut().map(|s| s as &mut dyn FrameSink),
        &stop,
        counts_log.as_mut().map(|l| l as &mut dyn Write),
    );
    if let Some(mut log) = counts_log.take() {
        let _ = log.flush();
    }
    let lines = d.report(&out);
    let fin = sinks.as_mut().map_or(Ok(()), |s| s.finish());
    for l in lines.iter().flatten() {
        eprintln!("{l}");
    }
    if root {
        for p in &paths {
            eprintln!("wrote {}", p.display());
        }
        if let Some(n) = out.checkpointed {
            eprintln!("checkpoint {} at step {n}", checkpoint_path.display());
        }
    }
    let tables = end_tables(comm, &mut d, &scene, &args, &out, particle_steps0);
    if let Some(e) = &out.sink_error {
        eprintln!("error: recorder failed on rank {}: {e}", comm.rank());
    }
    if let Err(e) = &fin {
        eprintln!("error: rank {}: {e}", comm.rank());
    }
    let code =
        u64::from(out.failure.is_some() || out.sink_error.is_some() || fin.is_err() || !tables);
    let any_code = comm.all_gather_u64(&[code]).into_iter().max().unwrap_or(0);
    if any_code != 0 {
        return any_code as i32;
    }
    if out.interrupted { 130 } else { 0 }
}

/// The recorder of this rank's part of a recording written per rank
/// (`<stem>.rank<k>.mcap`); rank 0 also writes the index `<stem>.mcap` naming the parts.
/// `Err` holds the message and the exit status.
fn make_part_sink(
    scene: &scg_scene::Scene,
    args: &RunArgs,
    report: &scg_scene::check::Report,
    stem: &str,
    comm: &Comm,
    paths: &mut Vec<std::path::PathBuf>,
) -> Result<Box<dyn FrameSink>, (String, i32)> {
    ensure_writable(&args.out).map_err(|e| (e, EXIT_BAD_INPUT))?;
    let meta = run_meta(scene, report, comm.size());
    let io = |e: scg_record::RecordError| (e.to_string(), 1);
    let part = |k: usize| format!("{stem}.rank{k}.mcap");
    if comm.rank() == 0 {
        let index = args.out.join(format!("{stem}.mcap"));
        let meta = RunMeta {
            parts: (0..comm.size()).map(part).collect(),
            ..meta.clone()
        };
        scg_record::McapSink::create(&index, &meta)
            .and_then(|mut s| s.close())
            .map_err(io)?;
        paths.push(index);
    }
    let path = args.out.join(part(comm.rank()));
    let sink = scg_record::McapSink::create(&path, &meta).map_err(io)?;
    if comm.rank() == 0 {
        paths.push(
            args.out
                .join(format!("{stem}.rank*.mcap ({} parts)", comm.size())),
        );
    }
    Ok(Box::new(scg_record::Background::spawn(vec![Box::new(
        sink,
    )])))
}

/// The recorders of rank 0: one `.rrd`, one `.mcap` and the VTK/CSV frames asked for
/// (one writer thread). `Err` holds the message and the exit status.
fn make_sinks(
    scene: &scg_scene::Scene,
    args: &RunArgs,
    report: &scg_scene::check::Report,
    stem: &str,
    ranks: usize,
    paths: &mut Vec<std::path::PathBuf>,
) -> Result<Box<dyn FrameSink>, (String, i32)> {
    ensure_writable(&args.out).map_err(|e| (e, EXIT_BAD_INPUT))?;
    let stem = stem.to_string();
    let meta = run_meta(scene, report, ranks);
    let rrd = args.out.join(format!("{stem}.rrd"));
    let mcap = args.out.join(format!("{stem}.mcap"));
    let io = |e: scg_record::RecordError| (e.to_string(), 1);
    let mut sinks: Vec<Box<dyn FrameSink>> = vec![
        Box::new(scg_record::RrdSink::create(&rrd, &meta).map_err(io)?),
        Box::new(scg_record::McapSink::create(&mcap, &meta).map_err(io)?),
    ];
    sinks.extend(
        extra_sinks(&args.vtk, &args.frames_csv, &RunMeta { case: stem, ..meta }).map_err(io)?,
    );
    paths.push(rrd);
    paths.push(mcap);
    paths.extend(args.vtk.iter().cloned());
    paths.extend(args.frames_csv.iter().cloned());
    Ok(Box::new(scg_record::Background::spawn(sinks)))
}

/// The description a decomposed run's recorders store: the scene's, with the rank count.
fn run_meta(scene: &scg_scene::Scene, report: &scg_scene::check::Report, ranks: usize) -> RunMeta {
    RunMeta {
        ranks: ranks as u32,
        ..scene.run_meta(report.messages())
    }
}

/// The decomposition the environment asks for: `SCG_MPI_DECOMP` = `auto` (the default),
/// `slabs`, `bisection` or `ids`; `SCG_MPI_AXIS` = `x`, `y` or `z` the slab axis (slabs).
/// Any other value is an error naming the variable and the value.
fn decomposition_from_env() -> Result<Decomposition, String> {
    let var = |k: &str| std::env::var(k).ok();
    let axis = match var("SCG_MPI_AXIS").as_deref() {
        None => None,
        Some("x") => Some(0),
        Some("y") => Some(1),
        Some("z") => Some(2),
        Some(v) => return Err(format!("SCG_MPI_AXIS = {v:?}: expected x, y or z")),
    };
    match (var("SCG_MPI_DECOMP").as_deref(), axis) {
        (None | Some("auto"), None) => Ok(Decomposition::Auto),
        (None | Some("auto") | Some("slabs"), a) => Ok(Decomposition::Slabs(a)),
        (Some("bisection"), None) => Ok(Decomposition::Bisection),
        (Some("ids"), None) => Ok(Decomposition::Ids),
        (Some(d @ ("bisection" | "ids")), Some(_)) => Err(format!(
            "SCG_MPI_AXIS is for slabs, not SCG_MPI_DECOMP = {d:?}"
        )),
        (Some(v), _) => Err(format!(
            "SCG_MPI_DECOMP = {v:?}: expected auto, slabs, bisection or ids"
        )),
    }
}

/// The tables and files a one-rank run ends with from logs and particles each rank holds
/// its share of (`--summary-json`, `--fates-csv`, `[erosion]` and its files): when asked
/// for, every rank's state is merged on rank 0 as a checkpoint is
/// ([`Decomposed::gather_whole`]: every particle on one node, once), rank 0's simulation
/// takes it (the run is over) and prints and writes them as one rank does. A collective;
/// false when a file could not be written (rank 0).
fn end_tables(
    comm: &Comm,
    d: &mut Decomposed,
    scene: &scg_scene::Scene,
    args: &RunArgs,
    out: &scg_mpi::driver::Outcome,
    particle_steps0: u64,
) -> bool {
    let asked = args.summary_json.is_some()
        || args.fates_csv.is_some()
        || args.erosion_csv.is_some()
        || args.erosion_vtk.is_some()
        || scene.erosion.is_some();
    if !asked {
        return true;
    }
    let run_steps: u64 = comm
        .all_gather_u64(&[d.sim.particle_steps() - particle_steps0])
        .iter()
        .sum();
    let Some(whole) = d.gather_whole() else {
        return true;
    };
    if let Err(e) = d.sim.restore(&whole) {
        eprintln!("error: the merged state of the ranks: {e}");
        return false;
    }
    let Some((fates, by_mass)) = crate::tables::end_tables(scene, args, &mut d.sim) else {
        return false;
    };
    let run = crate::tables::RunFigures {
        steps: out.steps,
        dt: scene.dt,
        time: d.sim.time(),
        particle_steps: run_steps,
        wall_s: out.wall,
        threads: scg_core::exec::settings().team_size() * comm.size(),
    };
    crate::tables::write_summary(scene, args, &mut d.sim, &fates, &by_mass, &run)
}
