//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

use scg::core::Simulation;
use scg::core::frame::{Frame, MemorySink};
use scg::scene::Scene;

/// Path of a file under the repository root.
pub fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// Load a case from `cases/` with overrides.
pub fn case(name: &str, set: &[&str]) -> Scene {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    scg::scene::load(&repo(&format!("cases/{name}.toml")), &set).expect("case loads")
}

/// Run a scene to the end with an in-memory recorder; returns the frames.
pub fn run_frames(scene: &Scene) -> (Simulation, Vec<Frame>) {
    let mut sim = scene.build(true);
    let sink = MemorySink::default();
    let frames = sink.frames.clone();
    sim.add_recorder(Box::new(sink));
    sim.record_now().expect("initial frame");
    sim.run(scene.steps(), |_| true).expect("run");
    sim.finish_recorders().expect("finish");
    let frames = frames.lock().unwrap().clone();
    (sim, frames)
}

/// Relative difference |a − b| / |b| (absolute when b = 0).
pub fn rel(a: f64, b: f64) -> f64 {
    if b == 0.0 {
        a.abs()
    } else {
        ((a - b) / b).abs()
    }
}

/// FNV-1a over the bits of every particle's position and velocity: a state digest for
/// bit-identity tests.
pub fn state_digest(ps: &[scg::core::sim::ParticleState]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for p in ps {
        for b in [p.position, p.velocity].iter().flat_map(|v| v.to_array()) {
            h = (h ^ b.to_bits()).wrapping_mul(0x100000001b3);
        }
    }
    h
}

/// `digest()` run in this process with `threads` workers, the parallel threshold
/// `parallel_min` and, with `portable`, the portable kernels forced
/// (`scg::core::exec::with_settings`): how the thread tests compare 1 and 2 threads, and
/// the four-lane kernels with the portable ones, in one process.
#[allow(dead_code)]
pub fn digest_with(
    threads: usize,
    parallel_min: usize,
    portable: bool,
    digest: impl FnOnce() -> String,
) -> String {
    let s = scg::core::exec::ExecSettings {
        threads,
        parallel_min,
        portable,
        ..scg::core::exec::ExecSettings::default()
    };
    scg::core::exec::with_settings(s, digest)
}

/// A scene on the 27-cell blockMesh fixture (patches walls, inlet, outlet): inlet-patch
/// feeders (one with the field's velocity, one given), contact wall patches (force,
/// torque, spin and wall history on every particle), an STL wall, gravity,
/// Schiller–Naumann drag; 2 ms.
pub fn cfd_box_scene() -> String {
    let case = repo("crates/scg-mesh/tests/fixtures/foam/ascii");
    let stl = repo("tests/fixtures/mesh-box.stl");
    format!(
        r#"
duration = 2e-3
dt = 1e-4
seed = 3
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "openfoam"
case = "{}"
time = 0
field = "U"
interpolation = "cell_point"
scale = 1.0
translate = [0.0, 0.0, 0.0]
[flow.patches]
walls = ["walls"]
outlets = ["outlet"]
inlets = ["inlet"]
wall_model = "contact"
[material]
youngs_modulus = 1e7
poisson_ratio = 0.3
restitution = 0.5
friction = 0.3
[gravity]
acceleration = [0.0, 0.0, -9.81]
[drag]
law = "schiller_naumann"
[[walls]]
kind = "mesh"
file = "{}"
scale = 0.1
[[groups]]
name = "a"
diameter = 1e-3
density = 1000.0
[[feeders]]
group = "a"
rate = 20000.0
patch = "inlet"
velocity = "field"
stop = 1e-3
[[feeders]]
group = "a"
rate = 2000.0
patch = "inlet"
velocity = [0.0, 0.0, 1.0]
"#,
        case.display(),
        stl.display()
    )
}

/// `scg ARGS` run in `dir` with the environment variables `env` set: its output.
pub fn scg_env(dir: &std::path::Path, args: &[&str], env: &[(&str, &str)]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_scg"))
        .args(args)
        .envs(env.iter().copied())
        .current_dir(dir)
        .output()
        .unwrap()
}

/// `scg ARGS` run in `dir`; asserts that it succeeds (its stderr in the message).
pub fn scg_ok(dir: &std::path::Path, args: &[&str]) {
    let run = scg_env(dir, args, &[]);
    assert!(
        run.status.success(),
        "scg {args:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
}

/// `scg replay MCAP --verify` re-runs the recording's scene frame for frame: asserts that
/// every frame is bit-identical.
pub fn assert_replays_bit_identical(mcap: &std::path::Path) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_scg"))
        .arg("replay")
        .arg(mcap)
        .arg("--verify")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("bit-identical"),
        "{}: {text}",
        mcap.display()
    );
}
