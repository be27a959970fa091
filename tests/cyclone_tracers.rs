//! The cyclone's sanity check (cases/cyclone-tracers.toml): fluid tracers (0.1 µm,
//! τ = 6e-8 s ≪ dt) fed over the inlet behave as the air. With turbulent dispersion
//! (Langevin, k and ω of the CFD) and the wall function (the log law below the
//! wall-adjacent cells' centres), all of them leave through the outlet within 5·V/Q, and
//! the inlet carries the boundary condition's Q = 0.800 m³/s (0.710 without the wall
//! function: the interpolation ramped to the no-slip zero across the inlet's edge cells).
//!
//! Their mean residence time should be V/Q (exact for a fluid tracer in a steady
//! volume-conserving flow). It comes out 12 % longer (1.60 ± 0.05 s against 1.43 s): the
//! CFD's cell velocities do not conserve volume cell by cell (`scg check` prints their
//! imbalance, 3.2·Q into the converging cells — a collocated solver conserves volume
//! through its Rhie–Chow face fluxes, not its cell values), and tracers collect where the
//! interpolated field converges. The test bounds the ratio so that a regression shows;
//! the 5 % is not met (docs/cyclone.md).
//!
//! Run: `cargo test --release --test cyclone_tracers -- --nocapture`.

mod common;

use scg::core::stages::feeder::FeedSource;
use scg::core::stages::outlet::OutletLog;
use scg::core::state::Tally;

#[test]
fn cyclone_tracers_leave_within_five_residence_times() {
    let scene = common::case("cyclone-tracers", &[]);
    let m = scene.mesh_flow.as_ref().expect("a mesh flow");
    let volume: f64 = m.flow.geometry().cell_volumes.iter().sum();
    let FeedSource::Patch(inlet) = &scene.feeders[0].source else {
        panic!("fed on the inlet patch");
    };
    let q = inlet.flux(&m.flow).inflow;
    let v_over_q = volume / q;
    println!("V = {volume:.4} m³, Q = {q:.4} m³/s, V/Q = {v_over_q:.4} s");
    assert!(
        (q - 0.8).abs() < 0.008,
        "inlet Q = {q} m³/s, the CFD's is 0.800"
    );
    assert!(scene.duration >= 5.0 * v_over_q - 1e-9);
    let mut sim = scene.build(false);
    sim.run(scene.steps(), |_| true).unwrap();
    let tally = sim.world.resource::<Tally>().clone();
    let log = sim.world.resource::<OutletLog>().clone();
    let fed = tally.fed[0];
    let times = &log.drained[0];
    let within: usize = times.iter().filter(|&&t| t <= 5.0 * v_over_q).count();
    // fed uniformly from 0 to `stop`: the mean feed time is stop/2
    let (start, stop) = scene.feeders[0].window;
    assert_eq!(start, 0.0);
    let n = times.len() as f64;
    let mean = times.iter().sum::<f64>() / n - 0.5 * stop;
    let sd = (times
        .iter()
        .map(|t| (t - 0.5 * stop - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0))
        .sqrt();
    let se = sd / n.sqrt();
    println!(
        "fed {fed}, escaped {} ({within} within 5·V/Q), lost {}, mean residence {mean:.4} ± {:.4} s (95 %) = {:.3}·V/Q",
        times.len(),
        log.lost[0].len(),
        1.96 * se,
        mean / v_over_q
    );
    assert_eq!(fed, 500);
    assert!(within as f64 >= 0.98 * fed as f64, "{within} of {fed}");
    assert!(log.lost[0].is_empty());
    let ratio = mean / v_over_q;
    assert!(
        (0.95..1.25).contains(&ratio),
        "mean residence {mean} s = {ratio}·V/Q"
    );
}

/// Bad `[flow.wall_function]` input is an error naming the file, the key and the line.
#[test]
fn bad_wall_function_input_names_file_key_and_line() {
    let text = std::fs::read_to_string(common::repo("cases/cyclone.toml")).unwrap();
    let good = "[flow.wall_function]\nmodel = \"log_law\"\nk = \"kMean\"\n";
    assert!(text.contains(good));
    for (bad, key) in [
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
        let err = scg::scene::parse_in(
            &text.replace(good, bad),
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
