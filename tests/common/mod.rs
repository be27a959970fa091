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
