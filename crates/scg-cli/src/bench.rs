//! `scg bench`: throughput benchmarks (particle-steps per second).

use std::time::Instant;

use clap::{Args, ValueEnum};

use crate::EXIT_BAD_INPUT;

/// What to benchmark.
#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum BenchKind {
    /// Drag only (Stokes, exponential scheme) in the paper's vortex flow, no recording.
    Drag,
}

/// Arguments of `scg bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Benchmark.
    pub kind: BenchKind,
    /// Number of particles.
    #[arg(long, default_value_t = 1_000_000)]
    pub particles: u64,
    /// Number of timed steps (after 5 warm-up steps).
    #[arg(long, default_value_t = 200)]
    pub steps: u64,
}

/// The drag benchmark scene: `n` 10 µm particles spread over the paper's vortex vessel.
pub fn drag_scene(n: u64) -> String {
    format!(
        r#"
name = "bench-drag"
duration = 1.0
dt = 1.0e-5
seed = 7
[fluid]
density = 1.2
viscosity = 1.8e-5
[flow]
kind = "vortex"
rpm = 300.0
inflow_ratio = 0.1
[drag]
law = "stokes"
[[groups]]
name = "p"
diameter = 10.0e-6
density = 1000.0
count = {n}
region = {{ kind = "cylinder", radius_max = 5.0e-4, height = [0.0, 1.0e-3] }}
"#
    )
}

/// Run a benchmark; the last line printed is `particle-steps/s: <number>`.
pub fn bench(a: BenchArgs) -> i32 {
    if a.particles == 0 || a.steps == 0 {
        eprintln!("error: --particles and --steps must be ≥ 1");
        return EXIT_BAD_INPUT;
    }
    let text = match a.kind {
        BenchKind::Drag => drag_scene(a.particles),
    };
    let scene = match scg_scene::parse(&text, "<bench>", "bench", &[]) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let mut sim = scene.build(false);
    for _ in 0..5 {
        if let Err(e) = sim.step() {
            eprintln!("error: {e}");
            return 1;
        }
    }
    let ps0 = sim.particle_steps();
    let t0 = Instant::now();
    if let Err(e) = sim.run(a.steps, |_| true) {
        eprintln!("error: {e}");
        return 1;
    }
    let wall = t0.elapsed().as_secs_f64();
    let ps = (sim.particle_steps() - ps0) as f64;
    let threads = bevy_tasks_threads();
    println!(
        "bench drag: {} particles × {} steps in {:.3} s on {} threads",
        a.particles, a.steps, wall, threads
    );
    for (set, d) in sim.timers().by_set() {
        if d.as_nanos() > 0 {
            println!("  {:<18} {:>9.3} s", set.name(), d.as_secs_f64());
        }
    }
    println!("particle-steps/s: {:.4e}", ps / wall);
    0
}

fn bevy_tasks_threads() -> usize {
    std::env::var("SCG_THREADS")
        .ok()
        .and_then(|s| s.parse().ok())
        .filter(|n| *n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}
