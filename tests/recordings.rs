//! Recordings end to end through the `scg` binary: replay --verify, determinism across
//! thread counts, and clean files after SIGINT / recoverable files after SIGKILL.

mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

use scg::core::frame::FrameSink;
use scg::record::{McapSink, read_mcap};

fn scg() -> Command {
    Command::new(env!("CARGO_BIN_EXE_scg"))
}

/// `scg run SCENE --out OUT --set …` from the repository on `threads` threads.
fn run_case(scene: &str, out: &Path, threads: &str, sets: &[&str]) {
    let mut cmd = scg();
    cmd.env("SCG_THREADS", threads)
        .args(["run", scene, "--out"])
        .arg(out)
        .current_dir(common::repo(""));
    for s in sets {
        cmd.args(["--set", s]);
    }
    let st = cmd.output().unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
}

fn run_vortex(out: &Path, threads: &str, duration: &str) {
    run_case(
        "cases/vortex.toml",
        out,
        threads,
        &[&format!("duration={duration}")],
    );
}

#[test]
fn replay_verify_passes_and_catches_one_altered_value() {
    let dir = tempfile::tempdir().unwrap();
    run_vortex(dir.path(), "2", "0.02");
    let mcap = dir.path().join("vortex.mcap");
    common::assert_replays_bit_identical(&mcap);

    // Alter one coordinate of one particle in frame 3 by one ulp and write it back.
    let mut rec = read_mcap(&mcap).unwrap();
    assert!(rec.complete && rec.frames.len() > 5);
    let x = &mut rec.frames[3].position[2][0];
    *x = f64::from_bits(x.to_bits() + 1);
    let bad = dir.path().join("tampered.mcap");
    let mut sink = McapSink::create(&bad, &rec.meta).unwrap();
    for f in &rec.frames {
        sink.write_frame(f).unwrap();
    }
    sink.finish().unwrap();
    let out = scg()
        .arg("replay")
        .arg(&bad)
        .arg("--verify")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{text}");
    let id = rec.frames[3].id[2];
    assert!(
        text.contains("frame 3")
            && text.contains(&format!("particle {id}"))
            && text.contains("position"),
        "{text}"
    );
}

/// A scene whose CFD case is a path relative to the scene file (cases/cyclone.toml's
/// `cyclone/coarse`), recorded from the repository and re-run by `replay --verify` from
/// another working folder: the recording stores the scene's folder.
#[test]
fn replay_verify_resolves_relative_paths_from_the_scenes_folder() {
    let dir = tempfile::tempdir().unwrap();
    run_case(
        "cases/cyclone.toml",
        dir.path(),
        "2",
        &["duration=0.06", "feed_scale=0.25"],
    );
    // `feed_scale` changes the run, so the recording's name says so (`duration` does not)
    let mcap = dir.path().join("cyclone-feed_scale=0.25.mcap");
    let rec = read_mcap(&mcap).unwrap();
    let cases = std::fs::canonicalize(common::repo("cases")).unwrap();
    assert_eq!(Path::new(&rec.meta.scene_dir), cases);
    assert!(rec.frames.iter().any(|f| !f.id.is_empty()));
    let out = scg()
        .arg("replay")
        .arg(&mcap)
        .arg("--verify")
        .current_dir(dir.path())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("bit-identical"),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn one_and_two_threads_record_identical_data() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    run_vortex(a.path(), "1", "0.02");
    run_vortex(b.path(), "2", "0.02");
    let ra = read_mcap(&a.path().join("vortex.mcap")).unwrap();
    let rb = read_mcap(&b.path().join("vortex.mcap")).unwrap();
    assert_eq!(ra.frames.len(), rb.frames.len());
    for (fa, fb) in ra.frames.iter().zip(&rb.frames) {
        let bits = |f: &scg::core::frame::Frame| {
            f.position
                .iter()
                .chain(&f.velocity)
                .flat_map(|v| v.map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(fa), bits(fb), "frame at step {}", fa.step);
    }
}

fn spawn_long_run(out: &Path) -> std::process::Child {
    scg()
        .args(["run", "cases/vortex.toml", "--out"])
        .arg(out)
        .args(["--set", "duration=60.0"])
        .current_dir(common::repo(""))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap()
}

#[test]
fn sigint_leaves_complete_recordings() {
    let dir = tempfile::tempdir().unwrap();
    let mut child = spawn_long_run(dir.path());
    std::thread::sleep(Duration::from_millis(2500));
    let st = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(st.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "interrupted runs exit with 130");
    let rec = read_mcap(&dir.path().join("vortex.mcap")).unwrap();
    assert!(rec.complete && !rec.frames.is_empty());
    assert!(dir.path().join("vortex.rrd").exists());
    assert!(!dir.path().join("vortex.mcap.partial").exists());
}

#[test]
fn sigkill_leaves_a_recoverable_partial_file_beside_the_old_one() {
    let dir = tempfile::tempdir().unwrap();
    // An earlier good recording stays in place.
    run_vortex(dir.path(), "2", "0.01");
    let good = read_mcap(&dir.path().join("vortex.mcap")).unwrap();
    let mut child = spawn_long_run(dir.path());
    std::thread::sleep(Duration::from_millis(3500));
    child.kill().unwrap();
    child.wait().unwrap();
    let partial = dir.path().join("vortex.mcap.partial");
    assert!(partial.exists());
    let rec = read_mcap(&partial).unwrap();
    assert!(
        !rec.complete && !rec.frames.is_empty(),
        "recovered {} frames",
        rec.frames.len()
    );
    for f in &rec.frames {
        assert_eq!(f.len(), 7, "every recovered frame is complete");
    }
    let still = read_mcap(&dir.path().join("vortex.mcap")).unwrap();
    assert_eq!(still.frames.len(), good.frames.len());
    let out = scg().arg("replay").arg(&partial).output().unwrap();
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("recovered from an incomplete file"));
}

/// `scg` with no arguments runs the embedded vortex case and records it under recordings/.
#[test]
fn no_arguments_runs_the_embedded_scene_into_recordings() {
    let dir = tempfile::tempdir().unwrap();
    let out = scg().current_dir(dir.path()).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rec = read_mcap(&dir.path().join("recordings/vortex.mcap")).unwrap();
    assert!(rec.complete);
    assert_eq!(rec.meta.case, "vortex");
    assert!((rec.frames.last().unwrap().time - 3.0).abs() < 1e-9);
    assert!(dir.path().join("recordings/vortex.rrd").is_file());
}
