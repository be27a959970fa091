//! The cyclone's sanity check (cases/cyclone-tracers.toml): fluid tracers (0.1 µm,
//! τ = 6e-8 s ≪ dt) fed over the inlet behave as the air. With the volume-conserving
//! interpolation (`conservative`: the cell field's face fluxes made divergence-free, a
//! constant velocity per tetrahedron) and turbulent dispersion (Langevin, k and ω of the
//! CFD), all of them leave through the outlet within 5·V/Q, their mean residence time is
//! V/Q within 5 % (exact for a fluid tracer in a steady volume-conserving flow), and the
//! inlet carries the boundary condition's Q = 0.800 m³/s.
//!
//! With `cell_point` instead, the tracers collect where the interpolated field converges
//! (the CFD's cell velocities conserve volume only through its Rhie–Chow face fluxes) and
//! stay 1.2·V/Q; the second test keeps that measurement, so that the first cannot pass by
//! a scheme that changes nothing.
//!
//! Run: `cargo test --release --test cyclone_tracers -- --nocapture`.

mod common;

use scg::core::stages::feeder::FeedSource;
use scg::core::stages::outlet::OutletLog;
use scg::core::state::Tally;

/// What the tracers did: fed, escaped within 5·V/Q, lost, and the mean residence over
/// V/Q with its 95 % half-width.
struct Tracers {
    fed: u64,
    within: usize,
    escaped: usize,
    lost: usize,
    ratio: f64,
    half_width: f64,
}

fn run_tracers(set: &[&str]) -> Tracers {
    let scene = common::case("cyclone-tracers", set);
    let m = scene.mesh_flow.as_ref().expect("a mesh flow");
    let volume: f64 = m.flow.geometry().cell_volumes.iter().sum();
    let FeedSource::Patch(inlet) = &scene.feeders[0].source else {
        panic!("fed on the inlet patch");
    };
    let q = inlet.flux(&m.flow).inflow;
    // the mean residence V/Q is with the boundary condition's Q
    let v_over_q = volume / 0.8;
    println!("{set:?}: V = {volume:.4} m³, inlet Q = {q:.4} m³/s, V/Q = {v_over_q:.4} s");
    assert!(scene.duration >= 5.0 * v_over_q - 1e-9);
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    let tally = sim.world.resource::<Tally>().clone();
    let log = sim.world.resource::<OutletLog>().clone();
    let fed = tally.fed[0];
    let times = &log.drained[0];
    // fed uniformly from 0 to `stop`: the mean feed time is stop/2
    let (start, stop) = scene.feeders[0].window;
    assert_eq!(start, 0.0);
    let within: usize = times
        .iter()
        .filter(|&&t| t - 0.5 * stop <= 5.0 * v_over_q)
        .count();
    let n = times.len() as f64;
    let mean = times.iter().sum::<f64>() / n - 0.5 * stop;
    let sd = (times
        .iter()
        .map(|t| (t - 0.5 * stop - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0))
        .sqrt();
    let t = Tracers {
        fed,
        within,
        escaped: times.len(),
        lost: log.lost[0].len(),
        ratio: mean / v_over_q,
        half_width: 1.96 * sd / n.sqrt() / v_over_q,
    };
    println!(
        "fed {fed}, escaped {} ({within} within 5·V/Q), lost {}, mean residence {:.3} ± {:.3}·V/Q (95 %)",
        t.escaped, t.lost, t.ratio, t.half_width
    );
    t
}

#[test]
fn cyclone_tracers_leave_with_mean_residence_v_over_q() {
    let t = run_tracers(&[]);
    assert_eq!(t.fed, 2000);
    assert!(
        t.within as f64 >= 0.98 * t.fed as f64,
        "{} of {}",
        t.within,
        t.fed
    );
    assert_eq!(t.lost, 0);
    assert!(t.half_width < 0.035, "±{}", t.half_width);
    assert!(
        (t.ratio - 1.0).abs() <= 0.05,
        "mean residence {}·V/Q",
        t.ratio
    );
    // and the inlet's flow is the boundary condition's: the conservative field keeps it
    let scene = common::case("cyclone-tracers", &[]);
    let m = scene.mesh_flow.as_ref().unwrap();
    let p = m.flow.projection().expect("the conservative scheme");
    println!("{p:?}");
    assert!((p.inflow - 0.8).abs() < 1e-3, "{p:?}");
    assert!(
        (p.outflow_after - p.inflow).abs() < 1e-9 * p.inflow,
        "{p:?}"
    );
}

/// The same tracers in the cell-point interpolation of the same field: they collect where
/// it converges and stay longer (and the inlet carries 0.71 m³/s).
#[test]
fn cell_point_tracers_overstay() {
    let t = run_tracers(&["flow.interpolation=\"cell_point\"", "feeders.0.rate=2000"]);
    assert!(t.ratio > 1.1, "mean residence {}·V/Q", t.ratio);
}

/// Bad `[flow.wall_function]` input is an error naming the file, the key and the line.
#[test]
fn bad_wall_function_input_names_file_key_and_line() {
    let scene = std::fs::read_to_string(common::repo("cases/cyclone.toml")).unwrap();
    let line = scene
        .lines()
        .find(|l| l.starts_with("interpolation = \"conservative\""))
        .expect("the scene's interpolation");
    let good = "[flow.wall_function]\nmodel = \"log_law\"\nk = \"kMean\"\n";
    // the wall function with the cell-point interpolation
    let text = scene.replace(line, good);
    // with the conservative one: refused
    let both = scene.replace(line, &format!("{line}\n{good}"));
    for (bad, key) in [
        (good, "flow.wall_function"),
        (
            "[flow.wall_function]\nmodel = \"spalding\"\n",
            "flow.wall_function.model",
        ),
        (
            "[flow.wall_function]\nmodel = \"log_law\"\nk = \"nope\"\n",
            "flow.wall_function.k",
        ),
        (
            "[flow.wall_function]\nmodel = \"none\"\nkappa = 0.4\n",
            "flow.wall_function.kappa",
        ),
        (
            "[flow.wall_function]\nmodel = \"log_law\"\ne = 0.5\n",
            "flow.wall_function.e",
        ),
        (
            "[flow.wall_function]\nmodel = \"log_law\"\ny = 1\n",
            "flow.wall_function",
        ),
    ] {
        let input = if key == "flow.wall_function" && bad == good {
            both.clone()
        } else {
            text.replace(good, bad)
        };
        let err = scg::scene::parse_in(
            &input,
            "cases/cyclone.toml",
            &common::repo("cases"),
            "cyclone",
            &[],
        )
        .err()
        .unwrap_or_else(|| panic!("{bad} accepted"))
        .to_string();
        println!("{err}");
        assert!(err.contains("cases/cyclone.toml:"), "{err}");
        assert!(err.contains(key), "{key}: {err}");
    }
}
