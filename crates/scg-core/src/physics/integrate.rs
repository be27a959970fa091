//! Time integration kernels (pure functions).
//!
//! A particle obeys dv/dt = (u(x) − v)/τ + a, with u the fluid velocity, τ the drag
//! response time and a the other accelerations (gravity, buoyancy, contacts).
//!
//! * [`exponential_drift`] solves it exactly over one step for frozen u and a:
//!   v' = w + (v − w)·e^(−dt/τ), x' = x + w·dt + (v − w)·τ·(1 − e^(−dt/τ)) with w = u + a·τ.
//!   It is unconditionally stable and exact in a uniform flow, whatever dt/τ.
//! * The `exponential` scheme freezes u at a predicted mid-step position (exponential
//!   midpoint), which makes it second order in a spatially varying flow.
//! * Contact forces enter as a kick before the drift (Lie splitting), which without drag
//!   reduces to symplectic Euler.
//! * [`explicit_euler`] is the plain semi-implicit (symplectic) Euler scheme, first order,
//!   stable only for dt < 2τ; the integration system sub-steps it when dt > τ/2.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Which integrator moves the particles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Integrator {
    /// Exponential (exact-drag) integration with a mid-step flow evaluation. Default.
    #[default]
    Exponential,
    /// Semi-implicit Euler, for comparison.
    Explicit,
}

impl Integrator {
    /// Scene-file name.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Exponential => "exponential",
            Integrator::Explicit => "explicit",
        }
    }
}

/// Precomputed exponential factors for response time `tau` (s) and step `dt` (s):
/// (1 − e^(−dt/τ), τ·(1 − e^(−dt/τ))), both via e^x − 1 for precision
/// ([`crate::physics::elementary::exp_m1`], which a block of particles evaluates in
/// lanes). An infinite τ (no drag) gives (0, dt).
#[inline(always)]
pub fn exponential_factors(tau: f64, dt: f64) -> (f64, f64) {
    let x = dt / tau;
    // e^(−x) − 1 once (the same bits as evaluating it for each factor)
    let em1 = crate::physics::elementary::exp_m1(-x);
    let gain = -em1;
    // τ·(1 − e^(−x)) = dt·(1 − e^(−x))/x, evaluated with exp_m1 to keep precision for small x.
    let relax = -tau * em1;
    // (selections, not a branch: a loop of them runs in lanes)
    let finite = tau.is_finite();
    (
        if finite { gain } else { 0.0 },
        if finite { relax } else { dt },
    )
}

/// Exact solution over one step of dv/dt = (u − v)/τ + a with u and a constant.
///
/// `gain`, `relax` come from [`exponential_factors`]`(tau, dt)`. Returns (x', v').
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn exponential_drift(
    x: DVec3,
    v: DVec3,
    u: DVec3,
    a: DVec3,
    tau: f64,
    gain: f64,
    relax: f64,
    dt: f64,
) -> (DVec3, DVec3) {
    if !tau.is_finite() {
        // Ballistic limit: w·dt + (v − w)·relax with relax = dt and the aτ·(dt − relax) → a·dt²/2.
        return (x + v * dt + 0.5 * a * dt * dt, v + a * dt);
    }
    let w = u + a * tau;
    let dv = v - w;
    // v' = w + (v − w)·e^(−x), written as v + (w − v)·(1 − e^(−x)) so that a slow
    // relaxation (e^(−x) ≈ 1) does not cancel digits.
    (x + w * dt + dv * relax, v - dv * gain)
}

/// One exponential-midpoint step for response time `tau` with factors for dt.
///
/// The fluid velocity is frozen at the predicted mid-step position x + v·dt/2 (one flow
/// evaluation per step); in a uniform flow the result is exact whatever the predictor.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn exponential_midpoint(
    flow: &crate::physics::flow::FlowField,
    x: DVec3,
    v: DVec3,
    a: DVec3,
    tau: f64,
    gain: f64,
    relax: f64,
    dt: f64,
) -> (DVec3, DVec3) {
    let u = flow.velocity(x + v * (0.5 * dt));
    exponential_drift(x, v, u, a, tau, gain, relax, dt)
}

/// Velocity after the force `f` (N) acted for `dt` (s) on mass `m` (kg): v + F·dt/m.
#[inline(always)]
pub fn linear_kick(v: DVec3, f: DVec3, m: f64, dt: f64) -> DVec3 {
    v + f * linear_kick_factor(m, dt)
}

/// dt/m of [`linear_kick`], s/kg (precomputed, it gives the same kick to the last bit).
#[inline(always)]
pub fn linear_kick_factor(m: f64, dt: f64) -> f64 {
    dt / m
}

/// Angular velocity after the torque `t` (N·m) acted for `dt` (s) on a solid sphere of
/// mass `m` (kg) and diameter `d` (m): ω + T·dt/I with I = m·d²/10 (paper eq. 3).
#[inline(always)]
pub fn angular_kick(w: DVec3, t: DVec3, m: f64, d: f64, dt: f64) -> DVec3 {
    w + t * angular_kick_factor(m, d, dt)
}

/// dt/I of [`angular_kick`], s/(kg·m²) (precomputed, the same kick to the last bit).
#[inline(always)]
pub fn angular_kick_factor(m: f64, d: f64, dt: f64) -> f64 {
    dt / (0.1 * m * d * d)
}

/// One semi-implicit Euler step of dv/dt = (u − v)/τ + a: v' = v + dt·((u − v)/τ + a),
/// x' = x + dt·v'. Returns (x', v').
#[inline]
pub fn explicit_euler(x: DVec3, v: DVec3, u: DVec3, a: DVec3, tau: f64, dt: f64) -> (DVec3, DVec3) {
    let acc = if tau.is_finite() {
        (u - v) / tau + a
    } else {
        a
    };
    let v1 = v + acc * dt;
    (x + v1 * dt, v1)
}

/// Number of explicit sub-steps that keep dt_sub ≤ τ/2 (1 when dt already does).
#[inline]
pub fn explicit_substeps(tau: f64, dt: f64) -> u32 {
    if !tau.is_finite() || dt <= 0.5 * tau {
        1
    } else {
        ((dt / (0.5 * tau)).ceil()).min(1.0e6) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_relaxation_for_any_dt() {
        let (u, v0, tau) = (DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 2.0, 0.0), 3e-4);
        for dt_over_tau in [1e-3, 0.1, 1.0, 10.0, 1000.0] {
            let dt = dt_over_tau * tau;
            let (e, r) = exponential_factors(tau, dt);
            let (mut x, mut v) = (DVec3::ZERO, v0);
            for _ in 0..10 {
                (x, v) = exponential_drift(x, v, u, DVec3::ZERO, tau, e, r, dt);
            }
            let t = 10.0 * dt;
            let ve = u + (v0 - u) * (-t / tau).exp();
            let xe = u * t + (v0 - u) * tau * (1.0 - (-t / tau).exp());
            assert!((v - ve).length() <= 1e-13 * ve.length(), "{dt_over_tau}");
            assert!((x - xe).length() <= 1e-12 * xe.length(), "{dt_over_tau}");
        }
    }

    #[test]
    fn ballistic_limit() {
        let a = DVec3::new(0.0, 0.0, -9.81);
        let (e, r) = exponential_factors(f64::INFINITY, 0.01);
        let (x, v) = exponential_drift(
            DVec3::ZERO,
            DVec3::X,
            DVec3::ZERO,
            a,
            f64::INFINITY,
            e,
            r,
            0.01,
        );
        assert_eq!(v, DVec3::X + a * 0.01);
        assert!((x - (DVec3::X * 0.01 + 0.5 * a * 1e-4)).length() < 1e-18);
    }

    #[test]
    fn terminal_velocity_under_gravity() {
        let (tau, g) = (1e-3, DVec3::new(0.0, 0.0, -9.81));
        let (e, r) = exponential_factors(tau, 1.0);
        let (_, v) = exponential_drift(DVec3::ZERO, DVec3::ZERO, DVec3::ZERO, g, tau, e, r, 1.0);
        assert!((v - g * tau).length() < 1e-15);
    }

    #[test]
    fn substeps() {
        assert_eq!(explicit_substeps(1.0, 0.5), 1);
        assert_eq!(explicit_substeps(1.0, 10.0), 20);
        assert_eq!(explicit_substeps(f64::INFINITY, 10.0), 1);
    }
}
