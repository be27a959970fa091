//! Golden test of `tsuji_damping` (issue 18, item 1).
//!
//! Run: `cargo test --release -p scg-core --test golden_tsuji -- --nocapture`
//! (prints the measured numbers next to the references).
//!
//! # What the function returns, and what the closed form means
//!
//! `tsuji_damping(e)` returns the dimensionless γ of the Hertz dashpot
//! F = K·δ^(3/2) + γ·√(m*·K)·δ^(1/4)·δ', K = (4/3)·E*·√R*. With δ in units of
//! (m*·v²/K)^(2/5) and t in units of that length over v, a collision is
//!
//! ```text
//! x'' = −x^(3/2) − γ·x^(1/4)·x',   x(0) = 0, x'(0) = 1,   e = −x'(t_end) where x(t_end) = 0,
//! ```
//!
//! so e depends on γ alone. The closed form γ_cf(e) = √5·|ln e|/√(ln²e + π²) is in the same
//! normalisation (it is also the LIGGGHTS Hertz damping 2·√(5/6)·β·√(S_n·m*),
//! β = ln e/√(ln²e + π²), S_n = 2E*·√(R*·δ) = (3/2)·K·√δ), and it is **exact** for this
//! equation:
//!
//! * change time to dσ = x^(1/4)·dt (′ = d/dt, ˙ = d/dσ): x' = x^(1/4)·ẋ and
//!   x'' = x^(1/2)·ẍ + x^(−1/2)·ẋ²/4, so the equation becomes ẍ + ẋ²/(4x) + γ·ẋ + x = 0;
//! * put x = w^p: the ẇ² terms cancel when p·(p − 1) + p²/4 = 0, i.e. p = 4/5, leaving
//!   the linear damped oscillator ẅ + γ·ẇ + (5/4)·w = 0 (ω₀ = √5/2, ζ = γ/(2ω₀) = γ/√5);
//! * x = 0 ⇔ w = 0 and x' = x^(1/4)·(4/5)·w^(−1/5)·ẇ = (4/5)·ẇ, so e is the linear
//!   oscillator's restitution e = exp(−π·ζ/√(1 − ζ²)), i.e. γ = √5·ζ = γ_cf(e) (ζ < 1).
//!
//! The tests check the closed form against an independent integration of the *original*
//! equation (not the transformed one), then `tsuji_damping` against the closed form.

use scg_core::physics::contact::normal::{hertz_restitution, tsuji_damping};
use std::f64::consts::PI;
use std::time::Instant;

/// The closed form √5·|ln e|/√(ln²e + π²).
fn closed_form(e: f64) -> f64 {
    let l = e.ln();
    5f64.sqrt() * l.abs() / (l * l + PI * PI).sqrt()
}

/// The 200 values of e of the issue: e ∈ [0.05, 0.99], evenly spaced.
fn restitutions() -> impl Iterator<Item = f64> {
    let n = 200;
    (0..n).map(move |i| 0.05 + (0.99 - 0.05) * i as f64 / (n - 1) as f64)
}

/// Restitution of x'' = −x^(3/2) − γ·x^(1/4)·x', x(0) = 0, x'(0) = 1, by classical RK4 with
/// the step h = min(h0, c·x) (at least 1e-12 on the way in): geometric refinement towards
/// x = 0, where the right-hand side is not smooth (x^(1/4)), so that the RK4 error stays
/// at round-off level there; the run stops when x < 1e-13 on the way out (the speed
/// would still change by O(γ·x^(5/4)) ≈ 1e-16).
fn reference_restitution(gamma: f64, h0: f64, c: f64) -> f64 {
    let f = |x: f64, v: f64| {
        let x = x.max(0.0);
        -x * x.sqrt() - gamma * x.sqrt().sqrt() * v
    };
    let (mut x, mut v) = (0.0_f64, 1.0_f64);
    let mut steps = 0u64;
    loop {
        // The floor only on the way in (x = 0 at the start); on the way out the step
        // shrinks with x until the stop.
        let floor = if v > 0.0 { 1e-12 } else { 0.0 };
        let h = h0.min((c * x).max(floor));
        let (k1x, k1v) = (v, f(x, v));
        let (k2x, k2v) = (v + 0.5 * h * k1v, f(x + 0.5 * h * k1x, v + 0.5 * h * k1v));
        let (k3x, k3v) = (v + 0.5 * h * k2v, f(x + 0.5 * h * k2x, v + 0.5 * h * k2v));
        let (k4x, k4v) = (v + h * k3v, f(x + h * k3x, v + h * k3v));
        x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        steps += 1;
        assert!(x > 0.0, "graded step overshot x = 0 (γ = {gamma})");
        if v < 0.0 && x < 1e-13 {
            return -v;
        }
        assert!(steps < 50_000_000, "no exit (γ = {gamma})");
    }
}

/// The reference e(γ) and its error estimate (the difference to the run with twice the
/// steps everywhere).
fn reference_with_error(gamma: f64) -> (f64, f64) {
    let fine = reference_restitution(gamma, 5e-4, 0.025);
    let coarse = reference_restitution(gamma, 1e-3, 0.05);
    (fine, (fine - coarse).abs())
}

/// The closed form is the exact inverse of e(γ): the independent integration of the
/// original equation at γ_cf(e) returns e within 1e-10 at each of the 200 points (its own
/// step-halving error estimate must be below 1e-11).
#[test]
fn closed_form_is_exact_for_the_hertz_tsuji_dashpot() {
    let t0 = Instant::now();
    let (mut worst, mut worst_step) = ((0.0_f64, 0.0_f64), 0.0_f64);
    println!(
        "{:>8} {:>16} {:>18} {:>10}",
        "e", "γ_cf(e)", "e(γ_cf) reference", "diff"
    );
    for (i, e) in restitutions().enumerate() {
        let g = closed_form(e);
        let (e_ref, step) = reference_with_error(g);
        let d = e_ref - e;
        if d.abs() > worst.1.abs() {
            worst = (e, d);
        }
        worst_step = worst_step.max(step);
        if i % 20 == 0 || i == 199 {
            println!("{e:8.4} {g:16.12} {e_ref:18.15} {d:+10.2e}");
        }
    }
    println!(
        "worst |e(γ_cf(e)) − e| = {:.2e} at e = {:.4} (tolerance 1e-10); \
         reference step-halving error {worst_step:.1e} (tolerance 1e-11); {:.2} s",
        worst.1.abs(),
        worst.0,
        t0.elapsed().as_secs_f64()
    );
    assert!(
        worst_step < 1e-11,
        "reference not converged: {worst_step:e}"
    );
    assert!(
        worst.1.abs() < 1e-10,
        "closed form at e = {}: {:e}",
        worst.0,
        worst.1
    );
}

/// `tsuji_damping(e)` against the exact closed form over the 200 points, within 1e-6
/// relative in γ (the issue's tolerance), and the true restitution of the returned γ
/// (independent integrator) within 1e-9 of e.
///
/// Until 2026-11-30 the function inverted e(γ) on an RK4 solution at h = 2e-4 through the
/// x^(1/4) singularity and was 5.5e-6 off (its restitution 1.6e-6 off); it now returns
/// the closed form.
#[test]
fn tsuji_damping_matches_exact_closed_form() {
    let t0 = Instant::now();
    let (mut worst_rel, mut worst_abs, mut worst_e) = ((0.0_f64, 0.0_f64), 0.0_f64, 0.0_f64);
    println!(
        "{:>8} {:>16} {:>16} {:>10} {:>12}",
        "e", "γ (code)", "γ_cf (exact)", "rel", "e(γ_code)−e"
    );
    for (i, e) in restitutions().enumerate() {
        let g = tsuji_damping(e);
        let cf = closed_form(e);
        let rel = (g - cf) / cf;
        if rel.abs() > worst_rel.1.abs() {
            worst_rel = (e, rel);
        }
        worst_abs = worst_abs.max((g - cf).abs());
        // The true restitution of the code's γ (independent integrator).
        let (e_true, _) = reference_with_error(g);
        worst_e = worst_e.max((e_true - e).abs());
        if i % 20 == 0 || i == 199 {
            println!(
                "{e:8.4} {g:16.12} {cf:16.12} {rel:+10.2e} {:+12.2e}",
                e_true - e
            );
        }
        // The code's own round trip (what its unit test checks), for comparison.
        assert!((hertz_restitution(g) - e).abs() < 1e-6);
    }
    println!(
        "worst: γ relative {:+.2e} at e = {:.4} (tolerance 1e-6), γ absolute {worst_abs:.2e}; \
         true e of γ_code off by {worst_e:.2e}; {:.2} s",
        worst_rel.1,
        worst_rel.0,
        t0.elapsed().as_secs_f64()
    );
    assert!(
        worst_rel.1.abs() < 1e-6,
        "tsuji_damping vs closed form: {:e} at e = {}",
        worst_rel.1,
        worst_rel.0
    );
    assert!(
        worst_e < 1e-9,
        "true restitution of tsuji_damping off by {worst_e:e}"
    );
}
