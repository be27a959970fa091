//! The paper's vortex case (Table 2, Figs 4–6), end to end.

mod common;

use glam::DVec3;
use scg::core::physics::flow::rpm_to_rad_per_s;

const R_VESSEL: f64 = 5e-4;

fn xy(p: [f64; 3]) -> DVec3 {
    DVec3::new(p[0], p[1], 0.0)
}

/// Independent RK4 solution of dv/dt = (u(x) − v)/τ, dx/dt = v for the original particle,
/// sampled every `every` steps of `h` (index k ↔ time k·every·h).
fn rk4_reference(t_end: f64, h: f64, every: u64) -> Vec<DVec3> {
    let omega = rpm_to_rad_per_s(300.0);
    let tau = 1000.0 * 1e-10 / (18.0 * 1.8e-5);
    let u = |x: DVec3| omega * (DVec3::new(-x.y, x.x, 0.0) - 0.1 * x);
    let f = |x: DVec3, v: DVec3| (v, (u(x) - v) / tau);
    let (mut x, mut v) = (DVec3::new(3e-4, 0.0, 0.0), DVec3::ZERO);
    let n = (t_end / h).round() as u64;
    let mut out = vec![x];
    for i in 0..n {
        let (k1x, k1v) = f(x, v);
        let (k2x, k2v) = f(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
        let (k3x, k3v) = f(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
        let (k4x, k4v) = f(x + h * k3x, v + h * k3v);
        x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if (i + 1) % every == 0 {
            out.push(x);
        }
    }
    out
}

/// Groups of cases/vortex.toml: 0 original 10 µm, 1–3 scg 20/40/80 µm, 4–6 none 20/40/80 µm.
#[test]
fn vortex_case_matches_paper_and_theory() {
    let scene = common::case("vortex", &[]);
    let (mut sim, frames) = common::run_frames(&scene);
    assert!(frames.len() > 100);

    // SCG trajectories equal the original's (x–y plane; they start at other heights),
    // 1e-9 relative, at every frame; no SCG particle ever touches the wall.
    let mut worst: f64 = 0.0;
    for f in &frames {
        let o = xy(f.position[0]);
        for k in 1..=3 {
            let d = (xy(f.position[k]) - o).length() / o.length();
            worst = worst.max(d);
            assert!(xy(f.position[k]).length() + 0.5 * f.diameter[k] < R_VESSEL);
        }
    }
    eprintln!("SCG vs original, worst relative deviation: {worst:e}");
    assert!(worst < 1e-9, "SCG deviates from the original by {worst:e}");

    // The original's trajectory against RK4 at a tiny step (a quarter of the scene's dt),
    // at every recorded frame and after 3 s: within 1e-6 of the vessel radius.
    let every = scene.record_every * 4;
    let reference = rk4_reference(3.0, scene.dt / 4.0, every);
    assert_eq!(reference.len(), frames.len());
    let mut err: f64 = 0.0;
    for (f, r) in frames.iter().zip(&reference) {
        err = err.max((DVec3::from_array(f.position[0]) - *r).length());
    }
    let end = (sim.particles()[0].position - reference[reference.len() - 1]).length();
    eprintln!(
        "original vs RK4: max over frames {err:e} m = {:e} R; at 3 s {end:e} m",
        err / R_VESSEL
    );
    assert!(
        err < 1e-6 * R_VESSEL && end < 1e-6 * R_VESSEL,
        "original vs RK4: {err:e} m"
    );

    // Without SCG: 20 µm spirals in; 40 and 80 µm move outward and reach the wall.
    let r0 = 3e-4;
    let rmax = |k: usize| {
        frames
            .iter()
            .map(|f| xy(f.position[k]).length())
            .fold(0.0, f64::max)
    };
    let rend = |k: usize| xy(frames.last().unwrap().position[k]).length();
    assert!(rend(0) < 0.01 * r0, "original spirals in: {}", rend(0));
    assert!(rend(4) < r0, "none 20 µm spirals in: {}", rend(4));
    for (k, d) in [(5, 40e-6), (6, 80e-6)] {
        let reach = rmax(k) + 0.5 * d;
        assert!(
            reach >= R_VESSEL * 0.999,
            "none group {k} reaches the wall: {reach:e}"
        );
        assert!(rend(k) > r0, "none group {k} ends outside its start");
    }
}
