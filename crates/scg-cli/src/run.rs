//! `scg run`.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};

use scg_core::frame::{FrameSink, RunMeta};
use scg_core::step::StepSet;
use scg_scene::Scene;

use crate::EXIT_BAD_INPUT;

/// Arguments of `scg run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scene file; the embedded vortex case when omitted.
    pub case: Option<PathBuf>,
    /// Output folder for recordings.
    #[arg(long, default_value = "recordings")]
    pub out: PathBuf,
    /// Override a scene key, e.g. `--set dt=1e-5` or `--set groups.0.alpha=2` (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Print the schedule the scene produces and exit without running.
    #[arg(long)]
    pub plan: bool,
    /// Do not write the .rrd and .mcap recordings (`--vtk` and `--frames-csv` still
    /// write their frames).
    #[arg(long)]
    pub no_record: bool,
    /// Also write every frame as VTK for ParaView (`<name>_<step>.vtu`, `<name>.pvd`,
    /// `<name>_geometry.vtu`) into this folder.
    #[arg(long, value_name = "DIR")]
    pub vtk: Option<PathBuf>,
    /// Also write every frame as CSV (`<name>_<step>.csv`) into this folder.
    #[arg(long, value_name = "DIR")]
    pub frames_csv: Option<PathBuf>,
    /// Write a checkpoint every T seconds of simulated time, at the end, and when
    /// interrupted (to `--checkpoint`, default `<out>/<name>.ckpt`, replaced atomically).
    #[arg(long, value_name = "T")]
    pub checkpoint_every: Option<f64>,
    /// Checkpoint file (default `<out>/<name>.ckpt`).
    #[arg(long, value_name = "FILE")]
    pub checkpoint: Option<PathBuf>,
    /// Go on from a checkpoint: its scene (with `--set` applied, e.g. a longer
    /// `duration`), its particles and state; the result is bit-identical to the
    /// uninterrupted run. Recordings start at the checkpoint's step (`<name>-from<step>`).
    #[arg(long, value_name = "FILE", conflicts_with = "case")]
    pub restart: Option<PathBuf>,
    /// Write a machine-readable summary of the run (JSON) to FILE: per group the
    /// particles fed, drained (outlets), lost, still held at the end and the drained and
    /// lost times; steps, dt, particle-steps and the wall time of the steps.
    #[arg(long, value_name = "FILE")]
    pub summary_json: Option<PathBuf>,
    /// Write the fates of every group (entered, escaped and stuck per patch, lost,
    /// airborne; counts, shares and the original powder's mass) as CSV to FILE.
    #[arg(long, value_name = "FILE")]
    pub fates_csv: Option<PathBuf>,
    /// With `[erosion]`: write every face hit (patch, face, centre, area, impacts, mass,
    /// volume removed, depth rate) as CSV to FILE.
    #[arg(long, value_name = "FILE")]
    pub erosion_csv: Option<PathBuf>,
    /// With `[erosion]`: write the logged wall patches with the wear per face (volume,
    /// depth rate, impacts) as a legacy-VTK surface to FILE (ParaView).
    #[arg(long, value_name = "FILE")]
    pub erosion_vtk: Option<PathBuf>,
    /// Over MPI ranks: every rank writes its own particles of every frame
    /// (`<stem>.rank<k>.mcap`) and rank 0 the index `<stem>.mcap`, which `scg replay`
    /// (`--verify`, `--rrd`, `--vtk`) and the analyses read as one recording; no rank
    /// holds a whole frame, and no `.rrd` is written (`scg replay <stem>.mcap --rrd FILE`
    /// makes one). On one rank, the ordinary recording.
    #[arg(long)]
    pub per_rank: bool,
}

impl Default for RunArgs {
    /// What `scg` with no subcommand runs: the embedded scene, recorded to `recordings/`.
    fn default() -> Self {
        RunArgs {
            case: None,
            out: PathBuf::from("recordings"),
            set: Vec::new(),
            plan: false,
            no_record: false,
            vtk: None,
            frames_csv: None,
            checkpoint_every: None,
            checkpoint: None,
            restart: None,
            summary_json: None,
            fates_csv: None,
            erosion_csv: None,
            erosion_vtk: None,
            per_rank: false,
        }
    }
}

/// The scene of `scg run` (its file, the embedded case or a checkpoint's), with the
/// overrides; `Err` holds the exit status after the message was printed.
pub fn load(args: &RunArgs) -> Result<Scene, i32> {
    if let Some(path) = &args.restart {
        let c = scg_record::checkpoint::read_checkpoint(path).map_err(|e| {
            eprintln!("error: {e}");
            EXIT_BAD_INPUT
        })?;
        let stem = Path::new(&c.scene_file)
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        let mut scene =
            scg_scene::parse(&c.scene, &c.scene_file, &stem, &args.set).map_err(|e| {
                eprintln!("error: {e}");
                EXIT_BAD_INPUT
            })?;
        // `dt = "auto"` is resolved by a rule that may change between versions: the run
        // goes on with the checkpoint's own dt.
        scene.dt = c.dt;
        return Ok(scene);
    }
    let r = match &args.case {
        Some(p) => scg_scene::load(p, &args.set),
        None => Scene::embedded(&args.set),
    };
    r.map_err(|e| {
        eprintln!("error: {e}");
        EXIT_BAD_INPUT
    })
}

/// `--checkpoint-every T` in steps of `dt` (at least one), `None` without it; `Err` for a
/// time that is not positive and finite.
pub fn checkpoint_interval(every: Option<f64>, dt: f64) -> Result<Option<u64>, String> {
    match every {
        None => Ok(None),
        Some(t) if t.is_finite() && t > 0.0 => Ok(Some(((t / dt).round() as u64).max(1))),
        Some(t) => Err(format!(
            "--checkpoint-every must be a positive time in seconds, not {t}"
        )),
    }
}

/// Fail early when `dir` cannot take files.
pub fn ensure_writable(dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("cannot create output folder {}: {e}", dir.display()))?;
    let probe = dir.join(format!(".scg-write-test-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .map_err(|e| format!("output folder {} is not writable: {e}", dir.display()))?;
    let _ = std::fs::remove_file(probe);
    Ok(())
}

/// [`load`], then the scene's checks (the report goes into the recordings' metadata):
/// their messages printed when `print` (one rank of a decomposed run prints them),
/// `Err(EXIT_BAD_INPUT)` when one is an error.
pub fn load_checked(args: &RunArgs, print: bool) -> Result<(Scene, scg_scene::check::Report), i32> {
    let scene = load(args)?;
    let report = scg_scene::check::check(&scene);
    if print {
        for m in report.messages() {
            eprintln!("{m}");
        }
    }
    if report.has_errors() {
        return Err(EXIT_BAD_INPUT);
    }
    Ok((scene, report))
}

/// Run `scg run`; returns the exit status.
/// CPU time (user + system) of this process so far, all threads, s: `/proc/self/stat`
/// (Linux; clock ticks of 1/100 s); `None` elsewhere.
pub fn process_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: count from the
    // last ')'. utime and stime are fields 14 and 15, i.e. the 12th and 13th after it.
    let rest = &stat[stat.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

pub fn run(args: RunArgs) -> i32 {
    let (scene, report) = match load_checked(&args, true) {
        Ok(s) => s,
        Err(code) => return code,
    };
    let record = !args.no_record;
    if args.plan {
        let sim = scene.build(record);
        println!(
            "schedule of scene `{}` ({} systems):",
            scene.name,
            sim.plan().systems.len()
        );
        print!("{}", sim.plan().render());
        return 0;
    }
    if record && let Err(e) = ensure_writable(&args.out) {
        eprintln!("error: {e}");
        return EXIT_BAD_INPUT;
    }
    // `--vtk` and `--frames-csv` record frames with or without the .rrd/.mcap pair.
    let frames = record || args.vtk.is_some() || args.frames_csv.is_some();
    let mut sim = scene.build(frames);
    if let Some(path) = &args.restart {
        let restored = scg_record::checkpoint::read_checkpoint(path).and_then(|c| {
            sim.restore(&c)
                .map_err(|e| format!("{}: {e}", path.display()))
        });
        if let Err(e) = restored {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
        eprintln!(
            "restarting `{}` from {} at step {} (t = {:.6} s)",
            scene.name,
            path.display(),
            sim.step_count(),
            sim.time()
        );
    }
    let base = format!("{}{}", recording_stem(&scene), set_suffix(&args.set));
    let mut stem = base.clone();
    if args.restart.is_some() {
        stem = format!("{stem}-from{}", sim.step_count());
    }
    let checkpoint_path = args
        .checkpoint
        .clone()
        .unwrap_or_else(|| args.out.join(format!("{base}.ckpt")));
    let checkpoint_every = match checkpoint_interval(args.checkpoint_every, scene.dt) {
        Ok(e) => e,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    if checkpoint_every.is_some()
        && let Some(dir) = checkpoint_path
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
        && let Err(e) = ensure_writable(dir)
    {
        eprintln!("error: {e}");
        return EXIT_BAD_INPUT;
    }
    // Checkpoints name the scene file absolutely (resolved once).
    let scene_file = scene.absolute_file();
    let mut paths = Vec::new();
    if frames {
        let meta = scene.run_meta(report.messages());
        let sinks = match frame_sinks(&meta, &args.out, &stem, record, &args.vtk, &args.frames_csv)
        {
            Ok((sinks, written)) => {
                paths = written;
                sinks
            }
            Err(e) => {
                eprintln!("error: {e}");
                return 1;
            }
        };
        // Encoding and compression run on a writer thread, overlapping the simulation.
        sim.add_recorder(Box::new(scg_record::Background::spawn(sinks)));
    }

    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        let _ = signal_hook::flag::register(sig, Arc::clone(&stop));
    }
    let steps = scene.steps();
    let n0 = scene.groups.iter().map(|g| g.count()).sum::<usize>();
    eprintln!(
        "running `{}`: {} particles, {} steps of {:.3e} s",
        scene.name, n0, steps, scene.dt
    );
    let bar = ProgressBar::new(steps);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {elapsed_precise} eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let t0 = Instant::now();
    let cpu0 = process_cpu_s();
    let particle_steps0 = sim.particle_steps();
    let mut result = sim.record_now().map(|_| 0);
    let mut saved = Ok(());
    // Run in chunks ending at the checkpoint steps (multiples of the interval).
    while result.is_ok() && sim.step_count() < steps {
        let now = sim.step_count();
        let until = checkpoint_every.map_or(steps, |e| ((now / e + 1) * e).min(steps));
        result = sim.run(until - now, |i| {
            if (now + i) % 256 == 0 {
                bar.set_position(now + i);
            }
            !stop.load(Ordering::Relaxed)
        });
        if result.is_err() {
            break;
        }
        if checkpoint_every.is_some() {
            let mut c = sim.checkpoint();
            c.scene.clone_from(&scene.source);
            c.scene_file.clone_from(&scene_file);
            saved = scg_record::checkpoint::write_checkpoint(&checkpoint_path, &c);
            if saved.is_err() {
                break;
            }
        }
        if stop.load(Ordering::Relaxed) {
            break;
        }
    }
    bar.finish_and_clear();
    let wall = t0.elapsed().as_secs_f64();
    // the CPU time of the steps, all threads (the same span as `wall`)
    let cpu = match (cpu0, process_cpu_s()) {
        (Some(a), Some(b)) => format!(" (CPU {:.2} s)", b - a),
        _ => String::new(),
    };
    let done = sim.step_count();
    let particle_steps = sim.particle_steps() - particle_steps0;
    let fin = sim.finish_recorders();
    let interrupted = stop.load(Ordering::Relaxed);
    match &result {
        Ok(_) => eprintln!(
            "{} {done} steps (t = {:.6} s) in {wall:.3} s{cpu}: {:.3e} particle-steps/s",
            if interrupted {
                "interrupted after"
            } else {
                "done:"
            },
            sim.time(),
            particle_steps as f64 / wall.max(1e-12)
        ),
        Err(e) => eprintln!("error: run stopped at step {done}: {e}"),
    }
    let timers = sim.timers();
    let total = timers.sum().as_secs_f64().max(1e-12);
    eprintln!("time per stage:");
    for (set, d) in timers.by_set() {
        if sim.plan().in_set(set).next().is_some() || set == StepSet::Scaling {
            eprintln!(
                "  {:<18} {:>10.3} s  {:>5.1} %",
                set.name(),
                d.as_secs_f64(),
                100.0 * d.as_secs_f64() / total
            );
        }
    }
    if let Some(c) = sim
        .world
        .get_resource::<scg_core::stages::contacts::ContactState>()
    {
        eprintln!("neighbour list: {} at the end", c.summary());
    }
    let Some((fates, by_mass)) = crate::tables::end_tables(&scene, &args, &mut sim) else {
        return 1;
    };
    let resolved = sim.contact_resolution();
    for line in resolved.summary() {
        eprintln!("{line}");
    }
    for w in resolved.warnings() {
        eprintln!("warning: {w}");
    }
    for p in &paths {
        eprintln!("wrote {}", p.display());
    }
    match &saved {
        Ok(()) if checkpoint_every.is_some() => eprintln!(
            "checkpoint {} at step {}",
            checkpoint_path.display(),
            sim.step_count()
        ),
        Ok(()) => {}
        Err(e) => {
            eprintln!("error: {e}");
            return 1;
        }
    }
    if let Err(e) = fin {
        eprintln!("error: {e}");
        return 1;
    }
    let run = RunFigures {
        steps: done,
        dt: scene.dt,
        time: sim.time(),
        particle_steps,
        wall_s: wall,
        threads: scg_core::exec::settings().team_size(),
    };
    if !crate::tables::write_summary(&scene, &args, &mut sim, &fates, &by_mass, &run) {
        return 1;
    }
    if result.is_err() {
        return 1;
    }
    if interrupted { 130 } else { 0 }
}

pub use crate::stem::{recording_stem, set_suffix};

/// Writers of frames, written in order.
pub type Sinks = Vec<Box<dyn FrameSink>>;

/// The writers of a run's frames: with `record`, `<out>/<stem>.rrd` and `.mcap`; the VTK
/// and per-frame CSV folders when given. Returns them with what they write.
pub fn frame_sinks(
    meta: &RunMeta,
    out: &Path,
    stem: &str,
    record: bool,
    vtk: &Option<PathBuf>,
    csv: &Option<PathBuf>,
) -> Result<(Sinks, Vec<PathBuf>), scg_record::RecordError> {
    let mut sinks: Vec<Box<dyn FrameSink>> = Vec::new();
    let mut paths = Vec::new();
    if record {
        let rrd = out.join(format!("{stem}.rrd"));
        let mcap = out.join(format!("{stem}.mcap"));
        sinks.push(Box::new(scg_record::RrdSink::create(&rrd, meta)?));
        sinks.push(Box::new(scg_record::McapSink::create(&mcap, meta)?));
        paths.push(rrd);
        paths.push(mcap);
    }
    let meta = RunMeta {
        case: stem.to_string(),
        ..meta.clone()
    };
    sinks.extend(extra_sinks(vtk, csv, &meta)?);
    paths.extend(vtk.iter().cloned());
    paths.extend(csv.iter().cloned());
    Ok((sinks, paths))
}

/// The VTK and per-frame CSV writers asked for (folders `vtk` and `csv`), named after
/// `meta.case`.
pub fn extra_sinks(
    vtk: &Option<PathBuf>,
    csv: &Option<PathBuf>,
    meta: &RunMeta,
) -> Result<Vec<Box<dyn FrameSink>>, scg_record::RecordError> {
    let mut out: Vec<Box<dyn FrameSink>> = Vec::new();
    if let Some(dir) = vtk {
        out.push(Box::new(scg_record::VtkSink::create(dir, meta)?));
    }
    if let Some(dir) = csv {
        out.push(Box::new(scg_record::CsvSink::create(dir, meta)?));
    }
    Ok(out)
}

pub use crate::fates::GroupCounts;
pub use crate::tables::{RunFigures, summary_json};

/// Write a command's text files and its SVG (drawn by `draw` into the path given), print
/// `md` and list what was written; returns the exit status (1 when a file cannot be
/// written).
pub(crate) fn write_report(
    files: &[(std::path::PathBuf, String)],
    svg: &std::path::Path,
    draw: impl FnOnce(&std::path::Path) -> Result<(), String>,
    md: &str,
) -> i32 {
    for (p, text) in files {
        if let Err(e) = std::fs::write(p, text) {
            eprintln!("error: cannot write {}: {e}", p.display());
            return 1;
        }
    }
    if let Err(e) = draw(svg) {
        eprintln!("error: cannot draw {}: {e}", svg.display());
        return 1;
    }
    print!("{md}");
    for (p, _) in files {
        eprintln!("wrote {}", p.display());
    }
    eprintln!("wrote {}", svg.display());
    0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn process_cpu_time_advances() {
        let Some(a) = process_cpu_s() else {
            return; // not Linux
        };
        let mut x = 0u64;
        let t = Instant::now();
        while t.elapsed().as_secs_f64() < 0.05 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1);
        }
        std::hint::black_box(x);
        let b = process_cpu_s().unwrap();
        assert!(a >= 0.0 && b >= a, "{a} {b}");
    }
}
