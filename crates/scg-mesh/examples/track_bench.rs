//! Particle-steps per second of tracking + cell-point interpolation + a drag update on
//! perturbed tetrahedral (or polyhedral) boxes of about 1e4, 1e5 and 1e6 cells, one thread.
//!
//! ```sh
//! cargo run --release -p scg-mesh --example track_bench                  # tet, 1e5 and 1e6 particles
//! cargo run --release -p scg-mesh --example track_bench -- poly 100000   # polyhedral, 1e5 particles
//! cargo run --release -p scg-mesh --example track_bench -- tet 1000000 0.03  # Courant number 0.03
//! cargo run --release -p scg-mesh --example track_bench -- tet 100000 0.3 --prefetch
//! ```
//!
//! The flow is the paper's vortex about the box's z axis (u = ω(ẑ × r − k r), ω = 100
//! rad/s, k = 0.1) sampled at the cell centres, interpolated by linear-exact cell-point;
//! τ = 1 ms; dt is set so that the fastest particle moves 0.3 cell sizes per step (a
//! Courant number of 0.3 on every mesh, or the third argument; DEM steps limited by
//! contacts are often much shorter).
//! Particles start at random in the box, ordered by cell, then move with
//! `track_from` → `Interpolator::at` → v += (u − v)·dt/τ, x += v·dt; one leaving the box
//! is put back at its previous position with the fluid's velocity. With `--prefetch` the
//! loop calls `Interpolator::prefetch` eight particles ahead. Each case runs three rounds
//! of `steps` steps and reports the fastest (the machine may be shared: the last column is
//! the 1-minute load average after the case; `cpu st/s` and `cpu ns` are the same figures
//! in this thread's CPU time, which other processes disturb less).

use std::time::Instant;

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scg_mesh::build::{BoxMesh, CellShape};
use scg_mesh::geometry::MeshGeometry;
use scg_mesh::interp::{Interpolation, Interpolator};
use scg_mesh::locate::{Hit, Location, Locator};
use scg_mesh::{CellField, PolyMesh};

fn vortex(x: DVec3) -> DVec3 {
    let r = DVec3::new(x.x, x.y, 0.0);
    100.0 * (DVec3::Z.cross(r) - 0.1 * r)
}

struct Particle {
    x: DVec3,
    v: DVec3,
    hit: Hit,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let shape = args.get(1).map(String::as_str).unwrap_or("tet");
    let counts: Vec<usize> = match args.get(2) {
        Some(s) => s.split(',').filter_map(|n| n.parse().ok()).collect(),
        None => vec![100_000, 1_000_000],
    };
    let cfl: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0.3);
    let prefetch = args.iter().any(|a| a == "--prefetch");
    let (lo, hi) = (DVec3::new(-0.1, -0.1, 0.0), DVec3::new(0.1, 0.1, 0.2));
    println!(
        "shape {shape}, Courant number {cfl}, prefetch {prefetch}; particle-steps/s, one thread"
    );
    println!(
        "{:>9} {:>9} {:>7} {:>9} {:>10} {:>8} {:>10} {:>8} {:>8} {:>6}",
        "cells",
        "particles",
        "steps",
        "setup s",
        "steps/s",
        "ns/step",
        "cpu st/s",
        "cpu ns",
        "same tet",
        "load"
    );
    for target in [10_000usize, 100_000, 1_000_000] {
        let t0 = Instant::now();
        let mesh = build(shape, target, lo, hi);
        let geom = MeshGeometry::new(&mesh).unwrap();
        let loc = Locator::new(&mesh, &geom).unwrap();
        let field = CellField {
            cells: geom.cell_centres.iter().map(|&c| vortex(c)).collect(),
            patches: mesh
                .patches
                .iter()
                .map(|p| {
                    Some(
                        (p.start..p.start + p.size)
                            .map(|f| vortex(geom.face_centres[f]))
                            .collect(),
                    )
                })
                .collect(),
        };
        let it = Interpolator::new(&loc, &field, Interpolation::CellPoint).unwrap();
        let setup = t0.elapsed().as_secs_f64();
        let h = (0.2 * 0.2 * 0.2 / mesh.n_cells as f64).cbrt();
        let umax = vortex(DVec3::new(0.1, 0.1, 0.0)).length();
        let dt = cfl * h / umax;
        let tau = 1e-3;
        for &n in &counts {
            let mut rng = ChaCha8Rng::seed_from_u64(1);
            let mut start: Vec<(DVec3, Hit)> = (0..n)
                .map(|_| {
                    let x = lo + (hi - lo) * DVec3::new(rng.random(), rng.random(), rng.random());
                    (x, loc.find(x).expect("inside"))
                })
                .collect();
            start.sort_by_key(|p| p.1.cell);
            // three rounds, the fastest reported (the machine is shared)
            let steps = (10_000_000 / n).clamp(10, 100);
            let total = (n * steps) as f64;
            let kick = (dt / tau).min(1.0);
            let report = |secs: f64, cpu: f64, same: u64| {
                println!(
                    "{:>9} {:>9} {:>7} {:>9.1} {:>10.3e} {:>8.1} {:>10.3e} {:>8.1} {:>7.0}% {:>6}",
                    mesh.n_cells,
                    n,
                    steps,
                    setup,
                    total / secs,
                    secs / total * 1e9,
                    total / cpu,
                    cpu / total * 1e9,
                    100.0 * same as f64 / total,
                    load()
                );
            };
            let mut ps: Vec<Particle> = start
                .iter()
                .map(|&(x, hit)| Particle {
                    x,
                    v: vortex(x),
                    hit,
                })
                .collect();
            let (mut best, mut best_cpu, mut same) = (f64::INFINITY, f64::INFINITY, 0u64);
            for _round in 0..3 {
                same = 0;
                let t = Instant::now();
                let c0 = cpu_time();
                for _ in 0..steps {
                    for i in 0..n {
                        if prefetch && i + AHEAD < n {
                            it.prefetch(&ps[i + AHEAD].hit);
                        }
                        let p = &mut ps[i];
                        let u = it.at(&p.hit);
                        p.v += (u - p.v) * kick;
                        let x = p.x + p.v * dt;
                        match loc.track_from(&p.hit, x) {
                            Location::Inside(h) => {
                                same += (h.cell == p.hit.cell && h.nodes == p.hit.nodes) as u64;
                                p.hit = h;
                                p.x = x;
                            }
                            _ => p.v = u,
                        }
                    }
                }
                best = best.min(t.elapsed().as_secs_f64());
                best_cpu = best_cpu.min(cpu_time() - c0);
            }
            report(best, best_cpu, same);
        }
    }
}

/// The 1-minute load average of the machine (Linux), to judge the figures by.
fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_owned))
        .unwrap_or_else(|| "?".into())
}

/// CPU time of this thread, s (Linux, 10 ms ticks; NaN elsewhere): the figures in CPU
/// time are less affected by other processes than those in wall time.
fn cpu_time() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/thread-self/stat") else {
        return f64::NAN;
    };
    // the fields after the command name in parentheses; utime and stime are 14 and 15
    let rest = stat.rsplit_once(')').map(|(_, r)| r).unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| {
        f.get(i)
            .and_then(|s| s.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    (ticks(11) + ticks(12)) / 100.0
}

/// How many particles ahead `--prefetch` prefetches.
const AHEAD: usize = 8;

fn build(shape: &str, target: usize, lo: DVec3, hi: DVec3) -> PolyMesh {
    let (per_hex, cshape) = match shape {
        "hex" => (1.0, CellShape::Hex),
        "poly" => (1.0 + 7.0 * 0.3, CellShape::Poly { refine: 0.3 }),
        _ => (6.0, CellShape::Tet),
    };
    // a 1 × 1 × 2 box of n × n × 2n hexahedra
    let n = ((target as f64 / per_hex / 2.0).cbrt().round() as usize).max(1);
    BoxMesh::new(lo, hi, [n, n, 2 * n])
        .shape(cshape)
        .perturbed(0.2, 5)
        .build()
        .expect("mesh")
}
