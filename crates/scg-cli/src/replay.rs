//! `scg replay`: work from an MCAP recording without re-simulating.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use clap::Args;

use scg_core::frame::{Frame, FrameSink};
use scg_record::{Recording, read_mcap, write_rrd};

use crate::EXIT_BAD_INPUT;
use crate::analysis::{self, recording_scene};

/// Arguments of `scg replay`.
#[derive(Args, Debug)]
pub struct ReplayArgs {
    /// The MCAP recording (a `.partial` file of a killed run works too).
    pub recording: PathBuf,
    /// Rebuild a Rerun recording at this path, with the live layout.
    #[arg(long, value_name = "OUT.rrd")]
    pub rrd: Option<PathBuf>,
    /// Print per-group statistics of the radial distance from the flow axis, and write CSV.
    #[arg(long)]
    pub analyze: bool,
    /// Analysis window start, s.
    #[arg(long, default_value_t = 0.0)]
    pub from: f64,
    /// Analysis window end, s.
    #[arg(long, default_value_t = f64::INFINITY)]
    pub to: f64,
    /// CSV output of `--analyze` (default: next to the recording, `<stem>.analysis.csv`).
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Re-run the embedded scene and check every recorded frame bit for bit.
    #[arg(long)]
    pub verify: bool,
    /// Open the Rerun viewer on the rebuilt (or a sibling) .rrd when `rerun` is installed.
    #[arg(long)]
    pub spawn: bool,
    /// Write every frame as VTK for ParaView (`<case>_<step>.vtu`, `<case>.pvd`,
    /// `<case>_geometry.vtu`) into this folder.
    #[arg(long, value_name = "DIR")]
    pub vtk: Option<PathBuf>,
    /// Write every frame as CSV (`<case>_<step>.csv`) into this folder.
    #[arg(long, value_name = "DIR")]
    pub frames_csv: Option<PathBuf>,
}

/// Run `scg replay`; returns the exit status.
pub fn replay(a: ReplayArgs) -> i32 {
    let rec = match read_mcap(&a.recording) {
        Ok(r) => r,
        // the reader's error names the file
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    eprintln!(
        "{}: case `{}`, {} frames{}",
        a.recording.display(),
        rec.meta.case,
        rec.frames.len(),
        if rec.complete {
            ""
        } else {
            " recovered from an incomplete file"
        }
    );
    let mut status = 0;
    if let Some(out) = &a.rrd {
        match write_rrd(&rec, out) {
            Ok(n) => eprintln!("wrote {} ({n} frames)", out.display()),
            Err(e) => {
                eprintln!("error: {e}");
                return 1;
            }
        }
    }
    if a.vtk.is_some() || a.frames_csv.is_some() {
        let written = crate::run::extra_sinks(&a.vtk, &a.frames_csv, &rec.meta)
            .map_err(|e| e.to_string())
            .and_then(|mut sinks| {
                for s in sinks.iter_mut() {
                    for f in &rec.frames {
                        s.write_frame(f)?;
                    }
                    if let Some(w) = &rec.wear {
                        s.write_wear(w)?;
                    }
                    s.finish()?;
                }
                Ok(())
            });
        if let Err(e) = written {
            eprintln!("error: {e}");
            return 1;
        }
        for dir in a.vtk.iter().chain(&a.frames_csv) {
            eprintln!("wrote {} frames to {}", rec.frames.len(), dir.display());
        }
    }
    if a.analyze {
        let csv = a
            .csv
            .clone()
            .unwrap_or_else(|| a.recording.with_extension("analysis.csv"));
        match analysis::group_stats(&rec, a.from, a.to) {
            Ok((text, table)) => {
                print!("{text}");
                if let Err(e) = std::fs::write(&csv, table) {
                    eprintln!("error: cannot write {}: {e}", csv.display());
                    return 1;
                }
                eprintln!("wrote {}", csv.display());
            }
            Err(e) => {
                eprintln!("error: {e}");
                return EXIT_BAD_INPUT;
            }
        }
        if let Err(code) = classify_recording(&rec, &a) {
            return code;
        }
    }
    if a.verify {
        match verify(&rec) {
            Ok(n) => println!("verify: {n} frames bit-identical"),
            Err(e) => {
                println!("verify: FAILED: {e}");
                status = 1;
            }
        }
    }
    if a.spawn {
        let target = a
            .rrd
            .clone()
            .unwrap_or_else(|| a.recording.with_extension("rrd"));
        match std::process::Command::new("rerun").arg(&target).spawn() {
            Ok(_) => eprintln!("opened the Rerun viewer on {}", target.display()),
            Err(e) => eprintln!("cannot start the Rerun viewer (`rerun` not installed?): {e}"),
        }
    }
    status
}

/// For a recording with an outlet (the classifier): the per-class radial distributions,
/// drained fractions and histogram of `scg study`, written to `<stem>.radial.csv` (the same
/// text as the study's `radial-<variant>.csv` for the same window).
fn classify_recording(rec: &Recording, a: &ReplayArgs) -> Result<(), i32> {
    let Ok(scene) = recording_scene(rec) else {
        return Ok(()); // `group_stats` already reported it
    };
    if scene.outlet.is_none() {
        return Ok(());
    }
    let last = rec.frames.last().map_or(0.0, |f| f.time);
    let r = analysis::analyze_recording(rec, a.from, a.to.min(last)).map_err(|e| {
        eprintln!("error: {e}");
        EXIT_BAD_INPUT
    })?;
    let path = a.recording.with_extension("radial.csv");
    std::fs::write(&path, analysis::radial_csv(&r)).map_err(|e| {
        eprintln!("error: cannot write {}: {e}", path.display());
        1
    })?;
    println!(
        "classifier: {:<10} {:>12} {:>9} {:>10} {:>7} {:>7} {:>7}",
        "class", "mean_r[m]", "drained", "samples", "fine", "coarse", "undec"
    );
    for c in &r.classes {
        println!(
            "classifier: {:<10} {:>12.5e} {:>9.4} {:>10} {:>7} {:>7} {:>7}",
            c.name,
            c.mean_r,
            c.drained_fraction,
            c.radii.len(),
            c.fates.fine,
            c.fates.coarse,
            c.fates.undecided
        );
    }
    let um = |d: Option<f64>| d.map_or("—".to_string(), |d| format!("{:.1} µm", d * 1e6));
    println!(
        "classifier: d50 drained (cohort fed by {} s, gone by {} s) {}; d50 steady (decided fates) {}, {} undecided",
        r.params.cohort_until,
        r.last_time,
        um(analysis::cut_size(&r)),
        um(analysis::steady_cut_size(&r)),
        analysis::undecided(&r)
    );
    eprintln!("wrote {}", path.display());
    Ok(())
}

/// Compares regenerated frames with recorded ones.
struct VerifySink {
    recorded: Arc<Vec<Frame>>,
    next: usize,
    mismatch: Arc<Mutex<Option<String>>>,
}

fn first_difference(a: &Frame, b: &Frame) -> Option<String> {
    if a.step != b.step || a.time.to_bits() != b.time.to_bits() {
        return Some(format!(
            "step/time {} {} vs {} {}",
            a.step, a.time, b.step, b.time
        ));
    }
    if a.len() != b.len() {
        return Some(format!("particle count {} vs {}", a.len(), b.len()));
    }
    if a.fluctuation.is_empty() != b.fluctuation.is_empty() {
        return Some(format!(
            "fluctuation recorded {} vs {}",
            !a.fluctuation.is_empty(),
            !b.fluctuation.is_empty()
        ));
    }
    let fluct = |f: &Frame, i: usize| f.fluctuation.get(i).map(|u| u.to_bits());
    for i in 0..a.len() {
        let bits = |v: [f64; 3]| v.map(f64::to_bits);
        let fields: [(&str, bool); 7] = [
            ("id", a.id[i] == b.id[i]),
            ("group", a.group[i] == b.group[i]),
            ("position", bits(a.position[i]) == bits(b.position[i])),
            ("velocity", bits(a.velocity[i]) == bits(b.velocity[i])),
            (
                "diameter",
                a.diameter[i].to_bits() == b.diameter[i].to_bits(),
            ),
            ("density", a.density[i].to_bits() == b.density[i].to_bits()),
            ("fluctuation", fluct(a, i) == fluct(b, i)),
        ];
        if let Some((f, _)) = fields.iter().find(|(_, ok)| !ok) {
            return Some(format!("particle {} field {f}", a.id[i]));
        }
    }
    None
}

impl FrameSink for VerifySink {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), String> {
        let Some(rec) = self.recorded.get(self.next) else {
            return Ok(());
        };
        if let Some(d) = first_difference(rec, frame) {
            let mut m = self.mismatch.lock().map_err(|e| e.to_string())?;
            if m.is_none() {
                *m = Some(format!("frame {} (step {}): {d}", self.next, rec.step));
            }
            return Err("mismatch".into());
        }
        self.next += 1;
        Ok(())
    }
    fn finish(&mut self) -> Result<(), String> {
        Ok(())
    }
}

/// Re-run the recording's scene and compare every frame; returns the frames checked.
pub fn verify(rec: &Recording) -> Result<usize, String> {
    let scene = recording_scene(rec)?;
    if rec.meta.ranks > 1 && scene.contacts.is_some() {
        return Err(format!(
            "recorded on {} MPI ranks with particle contacts, whose force sums run in another order than on one rank: it agrees with a one-rank run statistically, not bit for bit, so it cannot be verified by re-running it (docs/scaling.md, \"Bits\")",
            rec.meta.ranks
        ));
    }
    let Some(last) = rec.frames.last() else {
        return Err("the recording holds no frame".into());
    };
    let recorded = Arc::new(rec.frames.clone());
    let mismatch = Arc::new(Mutex::new(None));
    let mut sim = scene.build(true);
    sim.add_recorder(Box::new(VerifySink {
        recorded: recorded.clone(),
        next: 0,
        mismatch: mismatch.clone(),
    }));
    let run = sim
        .record_now()
        .and_then(|_| sim.run(last.step, |_| true).map(|_| ()));
    if let Some(m) = mismatch.lock().map_err(|e| e.to_string())?.take() {
        return Err(m);
    }
    run.map_err(|e| e.to_string())?;
    Ok(recorded.len())
}
