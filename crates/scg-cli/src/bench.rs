//! `scg bench`: throughput benchmarks (particle-steps per second).

use std::time::Instant;

use clap::{Args, ValueEnum};

use crate::EXIT_BAD_INPUT;

/// What to benchmark.
#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum BenchKind {
    /// Drag only (Stokes, exponential scheme) in the paper's vortex flow, no recording.
    Drag,
    /// A dilute cloud (solid fraction 0.01) in a periodic box: Stokes drag in still air and
    /// Hertz–Mindlin contacts (neighbour lists built, few contacts).
    Dilute,
    /// A dense chute-like bed: simple cubic packing on a floor, gravity tilted by 26°,
    /// periodic in x and y, Hertz–Mindlin contacts everywhere.
    Dense,
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

/// Diameter (m), density (kg/m³), Young's modulus (Pa), Poisson ratio, restitution,
/// friction and time step (s) shared by the contact benchmarks and their LIGGGHTS and LAMMPS
/// twins (bench/liggghts/in.*, bench/lammps/in.*, bench/peers.py; run by bench/vs-peers.sh).
pub const CONTACT_BENCH: (f64, f64, f64, f64, f64, f64, f64) =
    (1e-3, 2500.0, 1e8, 0.3, 0.9, 0.5, 1e-6);

fn material_toml() -> String {
    let (_, _, e, nu, rest, mu, _) = CONTACT_BENCH;
    format!(
        "[material]\nyoungs_modulus = {e:e}\npoisson_ratio = {nu}\nrestitution = {rest}\nfriction = {mu}\n"
    )
}

fn positions_toml(ps: &[[f64; 3]]) -> String {
    let items: Vec<String> = ps
        .iter()
        .map(|p| format!("[{:e}, {:e}, {:e}]", p[0], p[1], p[2]))
        .collect();
    format!("[{}]", items.join(", "))
}

/// The dilute benchmark: `n` particles on a jittered cubic lattice (no initial overlaps)
/// at solid fraction 0.01 in a periodic cube, random velocities in ±0.1 m/s.
pub fn dilute_scene(n: u64, steps: u64) -> String {
    use rand::{Rng, SeedableRng};
    let (d, rho, _, _, _, _, dt) = CONTACT_BENCH;
    let phi = 0.01;
    let side = (n as f64).cbrt().ceil() as u64;
    let l = (n as f64 * std::f64::consts::PI / 6.0 * d * d * d / phi).cbrt();
    let a = l / side as f64;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let jitter = 0.45 * (a - d);
    let (mut ps, mut vs) = (Vec::new(), Vec::new());
    'fill: for i in 0..side {
        for j in 0..side {
            for k in 0..side {
                if ps.len() as u64 == n {
                    break 'fill;
                }
                let c = |q: u64| (q as f64 + 0.5) * a;
                let mut jit = || rng.random_range(-jitter..=jitter);
                ps.push([c(i) + jit(), c(j) + jit(), c(k) + jit()]);
                vs.push([
                    rng.random_range(-0.1..=0.1),
                    rng.random_range(-0.1..=0.1),
                    rng.random_range(-0.1..=0.1),
                ]);
            }
        }
    }
    format!(
        "name = \"bench-dilute\"\nduration = {dur:e}\ndt = {dt:e}\nseed = 7\n[fluid]\ndensity = 1.2\nviscosity = 1.8e-5\n[flow]\nkind = \"still\"\n[drag]\nlaw = \"stokes\"\n{mat}[contacts]\nskin = {skin:e}\nperiodic = [{l:e}, {l:e}, {l:e}]\n[[groups]]\nname = \"p\"\ndiameter = {d:e}\ndensity = {rho}\npositions = {p}\nvelocities = {v}\n",
        dur = (steps + 5) as f64 * dt,
        mat = material_toml(),
        skin = 0.1 * d,
        p = positions_toml(&ps),
        v = positions_toml(&vs),
    )
}

/// The dense benchmark: `n` particles in a simple cubic packing (spacing d, solid fraction
/// 0.52) 40 × 40 wide on a floor, periodic in x and y, gravity 9.81 m/s² tilted 26°.
pub fn dense_scene(n: u64, steps: u64) -> String {
    let (d, rho, _, _, _, _, dt) = CONTACT_BENCH;
    let w = 40u64;
    let layers = n.div_ceil(w * w);
    let mut ps = Vec::new();
    'fill: for k in 0..layers {
        for j in 0..w {
            for i in 0..w {
                if ps.len() as u64 == n {
                    break 'fill;
                }
                ps.push([
                    (i as f64 + 0.5) * d,
                    (j as f64 + 0.5) * d,
                    (k as f64 + 0.5) * d,
                ]);
            }
        }
    }
    let l = w as f64 * d;
    let lz = 4.0 * layers as f64 * d + 10.0 * d;
    let theta = 26f64.to_radians();
    format!(
        "name = \"bench-dense\"\nduration = {dur:e}\ndt = {dt:e}\nseed = 7\n[gravity]\nacceleration = [{gx:e}, 0.0, {gz:e}]\n{mat}[contacts]\nskin = {skin:e}\nperiodic = [{l:e}, {l:e}, {lz:e}]\n[[walls]]\nname = \"floor\"\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n[[groups]]\nname = \"p\"\ndiameter = {d:e}\ndensity = {rho}\npositions = {p}\n",
        dur = (steps + 5) as f64 * dt,
        gx = 9.81 * theta.sin(),
        gz = -9.81 * theta.cos(),
        mat = material_toml(),
        skin = 0.1 * d,
        p = positions_toml(&ps),
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
        BenchKind::Dilute => dilute_scene(a.particles, a.steps),
        BenchKind::Dense => dense_scene(a.particles, a.steps),
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
    let threads = scg_core::exec::settings().team_size();
    println!(
        "bench {:?}: {} particles × {} steps in {:.3} s on {} threads ({:.3e} s per particle-step)",
        a.kind,
        a.particles,
        a.steps,
        wall,
        threads,
        wall / ps
    );
    if std::env::var_os("SCG_BENCH_PLAN").is_some() {
        print!("{}", sim.plan().render());
    }
    for (set, d) in sim.timers().by_set() {
        if d.as_nanos() > 0 {
            println!("  {:<18} {:>9.3} s", set.name(), d.as_secs_f64());
        }
    }
    if let Some(c) = sim
        .world
        .get_resource::<scg_core::stages::contacts::ContactState>()
    {
        println!("  neighbour list: {}", c.summary());
    }
    println!("particle-steps/s: {:.4e}", ps / wall);
    0
}
