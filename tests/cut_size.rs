//! The steady-state cut size (issue 18): a reduced `classifier-cut` run (7 classes 164–188 µm,
//! 4 µm apart) decides each particle's fate (fine at the nozzle radius or drained, coarse in
//! the wall zone) and its d50 must match the Stokes equilibrium τ·ω = k:
//! d50 = √(18·μ·k/(ρ·ω)) = 175.9 µm.
//!
//! Tolerance: d50 is interpolated between the last class decided all fine and the first
//! decided all coarse. Near the cut the radial rate σ ≈ 52·Δd/d per second is too slow for
//! the 172 and 176 µm classes to decide within this run (the 176 µm class is neutral: σ ≈
//! 0.03 /s), so the bracket is 168–180 µm at worst, whose interpolated d50 lies in
//! 170–178 µm; with the class fates asserted on both sides, 3 % (5.3 µm) is what the class
//! spacing resolves, and the study (`scg study classifier-cut`) gives 176.0 µm.

use scg::cli::analysis as classify;
use scg::cli::study::{self, VARIANTS};

fn theory() -> f64 {
    let (mu, rho, k) = (1.8e-5, 100.0, 5.0);
    let omega = 5000.0 * std::f64::consts::PI / 30.0;
    (18.0 * mu * k / (rho * omega)).sqrt()
}

#[test]
fn fate_based_d50_matches_the_stokes_equilibrium() {
    assert!((theory() * 1e6 - 175.9).abs() < 0.05, "{}", theory());
    for variant in [0, 1] {
        let mut o: Vec<String> = VARIANTS[variant].1.iter().map(|s| s.to_string()).collect();
        // 0.7 s: the 168 µm class (σ ≈ −2.4 /s) reaches the nozzle from most feed radii.
        let scale = if variant == 0 { 0.1 } else { 0.4 };
        o.extend([
            "duration=0.7".to_string(),
            // Ten times the case's dt (under-resolved contacts, which the few particle
            // contacts of this dilute run barely feel) for a tenth of the run time.
            "dt=2e-6".to_string(),
            format!("feed_scale={scale}"),
            "record_every=1000".to_string(),
        ]);
        let v = study::run_variant(
            VARIANTS[variant].0,
            study::CLASSIFIER_CUT,
            &o,
            (0.6, 0.7),
            None,
        )
        .expect("run");
        let r = &v.result;
        print!("{}", study::report(std::slice::from_ref(&v)));
        for c in &r.classes {
            let d = c.diameter * 1e6;
            if d < 170.0 {
                assert!(
                    c.fates.fine > 0 && c.fates.coarse == 0,
                    "{}: {:?}",
                    v.name,
                    c
                );
            }
            if d > 178.0 {
                assert!(
                    c.fates.coarse > 0 && c.fates.fine == 0,
                    "{}: {:?}",
                    v.name,
                    c
                );
            }
        }
        let d50 = classify::steady_cut_size(r).expect("steady d50") * 1e6;
        let finite = classify::cut_size(r).map(|d| d * 1e6);
        println!(
            "{}: d50 steady {d50:.1} µm, drained {finite:?} µm, {} undecided, {:.1} s",
            v.name,
            classify::undecided(r),
            v.total_s
        );
        assert!(
            (d50 - 175.9).abs() <= 0.03 * 175.9,
            "{}: d50 steady {d50} µm",
            v.name
        );
    }
}
