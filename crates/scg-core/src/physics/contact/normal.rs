//! Normal contact laws (pure kernels): Hertz with Tsuji-type damping, and the linear
//! spring–dashpot. Both take their damping from a coefficient of restitution e and
//! reproduce it exactly for a binary collision (no attraction clamp, contact ends when the
//! overlap returns to zero).

use std::f64::consts::PI;

/// Effective modulus E* of two bodies: 1/E* = (1 − ν₁²)/E₁ + (1 − ν₂²)/E₂, Pa.
pub fn effective_modulus(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2)
}

/// Effective value 1/(1/a + 1/b) (radius or mass); an infinite `b` (a wall) gives `a`.
#[inline]
pub fn effective(a: f64, b: f64) -> f64 {
    if b.is_infinite() { a } else { a * b / (a + b) }
}

/// Hertz stiffness K = (4/3)·E*·√R*, so that F = K·δ^(3/2) (N/m^1.5).
#[inline]
pub fn hertz_stiffness(e_eff: f64, r_eff: f64) -> f64 {
    4.0 / 3.0 * e_eff * r_eff.sqrt()
}

/// Hertz contact duration of an elastic collision, s:
/// t_c = 2.868·(m*²/(R*·E*²·v))^(1/5) at approach speed `v` (m/s).
pub fn hertz_contact_time(m_eff: f64, r_eff: f64, e_eff: f64, v: f64) -> f64 {
    2.868 * (m_eff * m_eff / (r_eff * e_eff * e_eff * v)).powf(0.2)
}

/// Hertz maximum overlap of an elastic collision, m: δ_max = (15·m*·v²/(16·E*·√R*))^(2/5).
pub fn hertz_max_overlap(m_eff: f64, r_eff: f64, e_eff: f64, v: f64) -> f64 {
    (15.0 * m_eff * v * v / (16.0 * e_eff * r_eff.sqrt())).powf(0.4)
}

/// Dimensionless damping γ of the Tsuji et al. (1992) Hertz dashpot
/// F_d = −γ·√(m*·K)·δ^(1/4)·v_n that gives restitution `e`: γ = √5·|ln e|/√(ln²e + π²).
///
/// With δ scaled by (m*v²/K)^(2/5) the collision obeys x'' = −x^(3/2) − γ·x^(1/4)·x'. The
/// time change dσ = x^(1/4)·dt and x = w^(4/5) turn it into the linear oscillator
/// ẅ + γ·ẇ + (5/4)·w = 0, whose impact and exit speeds are those of x (x' = (4/5)·ẇ at
/// x = 0), so e = exp(−π·ζ/√(1 − ζ²)) with ζ = γ/√5 exactly: γ = √5 times the linear
/// damping ratio of e. (The same as LIGGGHTS's Hertz damping 2·√(5/6)·β·√(S_n·m*).) The
/// test `crates/scg-core/tests/golden_tsuji.rs` checks it against an independent
/// integration of the collision.
pub fn tsuji_damping(e: f64) -> f64 {
    if e >= 1.0 || e.is_nan() {
        return 0.0;
    }
    5f64.sqrt() * linear_damping_ratio(e.max(1e-3))
}

/// Restitution of the dimensionless Hertz–Tsuji collision x'' = −x^(3/2) − γ·x^(1/4)·x',
/// x(0) = 0, x'(0) = 1: the separation speed when x returns to 0, by RK4 (a numerical
/// check of [`tsuji_damping`]; about 1e-7 off, limited by the x^(1/4) singularity at the
/// ends).
pub fn hertz_restitution(gamma: f64) -> f64 {
    let f = |x: f64, v: f64| {
        let xp = x.max(0.0);
        -xp * xp.sqrt() - gamma * xp.sqrt().sqrt() * v
    };
    let h = 2e-5;
    let (mut x, mut v) = (0.0_f64, 1.0_f64);
    for _ in 0..100_000_000 {
        let (k1x, k1v) = (v, f(x, v));
        let (k2x, k2v) = (v + 0.5 * h * k1v, f(x + 0.5 * h * k1x, v + 0.5 * h * k1v));
        let (k3x, k3v) = (v + 0.5 * h * k2v, f(x + 0.5 * h * k2x, v + 0.5 * h * k2v));
        let (k4x, k4v) = (v + h * k3v, f(x + h * k3x, v + h * k3v));
        let xn = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        let vn = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if xn <= 0.0 && vn < 0.0 {
            // Interpolate the crossing linearly in x for the exit speed.
            let s = x / (x - xn);
            return -(v + s * (vn - v));
        }
        if vn >= 0.0 && xn <= 0.0 {
            return 0.0;
        }
        x = xn;
        v = vn;
    }
    0.0
}

/// Damping ratio ζ of a linear spring–dashpot with restitution e:
/// ζ = −ln e / √(π² + ln² e).
pub fn linear_damping_ratio(e: f64) -> f64 {
    if e >= 1.0 {
        return 0.0;
    }
    let l = e.max(1e-6).ln();
    -l / (PI * PI + l * l).sqrt()
}

/// Contact duration of a linear spring–dashpot, s: π/√(k/m*·(1 − ζ²)).
pub fn linear_contact_time(m_eff: f64, k: f64, zeta: f64) -> f64 {
    PI / (k / m_eff * (1.0 - zeta * zeta)).sqrt()
}

/// Largest overlap the force laws use, as a multiple of the effective radius R*.
///
/// Hertz theory holds for δ ≪ R*; beyond δ = R* (a wall contact with the centre on the
/// wall, two equal spheres overlapping by a quarter of their diameter) the force is held
/// at its value at δ = R* instead of growing without bound. Resolved contacts never get
/// there; the cap only matters for particles started inside each other or a wall, or for
/// contacts the time step does not resolve, which would otherwise gain energy step after
/// step until the state turns non-finite.
pub const OVERLAP_CAP: f64 = 1.0;

/// A normal contact law with its damping set from restitution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NormalLaw {
    /// Hertz F = K·δ^(3/2) − γ·√(m*·K)·δ^(1/4)·v_n; `gamma` from [`tsuji_damping`].
    Hertz {
        /// Dimensionless damping γ.
        gamma: f64,
    },
    /// Linear F = k·δ − 2ζ·√(m*·k)·v_n.
    Linear {
        /// Spring stiffness k, N/m.
        stiffness: f64,
        /// Damping ratio ζ from [`linear_damping_ratio`].
        zeta: f64,
    },
}

impl NormalLaw {
    /// Hertz law with the damping that gives restitution `e`.
    pub fn hertz(e: f64) -> Self {
        NormalLaw::Hertz {
            gamma: tsuji_damping(e),
        }
    }

    /// Linear law of stiffness `k` (N/m) with the damping that gives restitution `e`.
    pub fn linear(k: f64, e: f64) -> Self {
        NormalLaw::Linear {
            stiffness: k,
            zeta: linear_damping_ratio(e),
        }
    }

    /// Duration of an elastic contact, s: Hertz at approach speed `v` (m/s) with effective
    /// mass `m_eff` (kg), radius `r_eff` (m) and modulus `e_eff` (Pa); the linear law's
    /// damped half-period (independent of `v`). Infinite when `v` ≤ 0 for Hertz.
    pub fn contact_time(self, m_eff: f64, r_eff: f64, e_eff: f64, v: f64) -> f64 {
        match self {
            NormalLaw::Hertz { .. } if v > 0.0 => hertz_contact_time(m_eff, r_eff, e_eff, v),
            NormalLaw::Hertz { .. } => f64::INFINITY,
            NormalLaw::Linear { stiffness, zeta } => linear_contact_time(m_eff, stiffness, zeta),
        }
    }

    /// Normal force magnitude (N, positive = repulsive) and normal stiffness (N/m, for the
    /// tangential spring) for overlap `delta` (m, > 0) and normal relative velocity `vn`
    /// (m/s, positive when separating), with effective modulus `e_eff` (Pa), radius `r_eff`
    /// (m) and mass `m_eff` (kg). The overlap is capped at [`OVERLAP_CAP`]·R*.
    #[inline]
    pub fn force(self, delta: f64, vn: f64, e_eff: f64, r_eff: f64, m_eff: f64) -> (f64, f64) {
        let delta = delta.min(OVERLAP_CAP * r_eff);
        match self {
            NormalLaw::Hertz { gamma } => {
                let k = hertz_stiffness(e_eff, r_eff);
                let sd = delta.sqrt();
                let q = sd.sqrt(); // δ^(1/4)
                let elastic = k * delta * sd;
                let damping = gamma * (m_eff * k).sqrt() * q * vn;
                (elastic - damping, 1.5 * k * sd)
            }
            NormalLaw::Linear { stiffness, zeta } => {
                let damping = 2.0 * zeta * (m_eff * stiffness).sqrt() * vn;
                (stiffness * delta - damping, stiffness)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elastic_restitution_is_one() {
        assert!((hertz_restitution(0.0) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn tsuji_inversion_round_trips() {
        for e in [0.1, 0.3, 0.5, 0.8, 0.95, 0.99] {
            let g = tsuji_damping(e);
            assert!((hertz_restitution(g) - e).abs() < 1e-6, "e = {e}: γ = {g}");
        }
    }

    #[test]
    fn linear_damping_gives_restitution() {
        for e in [0.3, 0.5, 0.9] {
            let z = linear_damping_ratio(e);
            let got = (-PI * z / (1.0 - z * z).sqrt()).exp();
            assert!((got - e).abs() < 1e-12);
        }
    }

    #[test]
    fn effective_quantities() {
        assert_eq!(effective(2.0, 2.0), 1.0);
        assert_eq!(effective(3.0, f64::INFINITY), 3.0);
        let e = effective_modulus(1e9, 0.3, 1e9, 0.3);
        assert!((e - 1e9 / (2.0 * 0.91)).abs() < 1.0);
    }
}
