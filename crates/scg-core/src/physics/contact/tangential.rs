//! Tangential contact (pure kernels): a Mindlin spring with per-contact history, a dashpot
//! consistent with the normal one, the Coulomb limit, and an optional constant directional
//! rolling-resistance torque.
//!
//! Per step and contact the history displacement ξ is first rotated onto the current
//! tangent plane (keeping its length), then advanced by v_t·dt; the trial force is
//! F_t = −k_t·ξ − η_t·v_t. When |F_t| > μ_s·|F_n| the contact slides: F_t is cut to the
//! Coulomb limit and ξ is rescaled so that −k_t·ξ − η_t·v_t equals the limited force.

use glam::DVec3;

use super::NormalLaw;

/// Shear modulus G = E/(2(1 + ν)), Pa.
#[inline]
pub fn shear_modulus(e: f64, nu: f64) -> f64 {
    e / (2.0 * (1.0 + nu))
}

/// Effective shear modulus of two bodies: 1/G* = (2 − ν₁)/G₁ + (2 − ν₂)/G₂, Pa.
pub fn effective_shear_modulus(e1: f64, nu1: f64, e2: f64, nu2: f64) -> f64 {
    1.0 / ((2.0 - nu1) / shear_modulus(e1, nu1) + (2.0 - nu2) / shear_modulus(e2, nu2))
}

/// Mindlin tangential stiffness k_t = 8·G*·√(R*·δ), N/m.
#[inline]
pub fn mindlin_stiffness(g_eff: f64, r_eff: f64, delta: f64) -> f64 {
    8.0 * g_eff * (r_eff * delta).sqrt()
}

/// The factor c with η = c·√(m*·k) for the normal dashpot of `law` (η_n = c·√(m*·k_n));
/// the tangential dashpot uses the same c with k_t, so both have the same damping ratio.
///
/// Hertz–Tsuji: η_n = γ·√(m*·K)·δ^(1/4) and k_n = (3/2)·K·√δ, so c = γ/√(3/2).
/// Linear: η_n = 2ζ·√(m*·k), so c = 2ζ.
#[inline]
pub fn damping_factor(law: NormalLaw) -> f64 {
    match law {
        NormalLaw::Hertz { gamma } => gamma / 1.5_f64.sqrt(),
        NormalLaw::Linear { zeta, .. } => 2.0 * zeta,
    }
}

/// How the tangential stiffness is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TangentialStiffness {
    /// Mindlin: k_t = 8·G*·√(R*·δ).
    Mindlin,
    /// A fixed ratio of the normal stiffness: k_t = ratio·k_n.
    Ratio(f64),
}

/// Tangential and rolling contact law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TangentialLaw {
    /// Stiffness rule.
    pub stiffness: TangentialStiffness,
    /// Dashpot factor c (η_t = c·√(m*·k_t)); see [`damping_factor`].
    pub damping: f64,
    /// Sliding friction coefficient μ_s.
    pub friction: f64,
    /// Rolling friction coefficient μ_r (0 = off).
    pub rolling: f64,
}

impl TangentialLaw {
    /// Mindlin stiffness, dashpot consistent with `normal`, friction μ_s and rolling μ_r.
    pub fn new(normal: NormalLaw, friction: f64, rolling: f64) -> Self {
        TangentialLaw {
            stiffness: TangentialStiffness::Mindlin,
            damping: damping_factor(normal),
            friction,
            rolling,
        }
    }

    /// Tangential stiffness, N/m, for effective shear modulus `g_eff`, radius `r_eff`,
    /// overlap `delta` and normal stiffness `kn`.
    #[inline]
    pub fn stiffness(&self, g_eff: f64, r_eff: f64, delta: f64, kn: f64) -> f64 {
        match self.stiffness {
            TangentialStiffness::Mindlin => mindlin_stiffness(g_eff, r_eff, delta),
            TangentialStiffness::Ratio(r) => r * kn,
        }
    }

    /// True when the law can produce any tangential force or rolling torque.
    pub fn active(&self) -> bool {
        self.friction > 0.0 || self.rolling > 0.0
    }
}

/// Hertz normal force with a Mindlin tangential spring, sharing their square roots (the
/// pair kernel's common case). Returns (F_n, k_t, η_t): exactly what
/// `NormalLaw::Hertz { gamma }.force(δ, v_n, E*, R*, m*).0`,
/// [`mindlin_stiffness`]`(G*, R*, δ)` and `damping·√(m*·k_t)` give, up to rounding.
///
/// `mindlin_c` = √(6·G*/E*): with K = (4/3)·E*·√R*, m*·k_t = m*·K·(6·G*/E*)·√δ, so
/// √(m*·k_t) = √(m*·K)·mindlin_c·δ^(1/4) needs no square root of its own.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn hertz_mindlin(
    delta: f64,
    vn: f64,
    e_eff: f64,
    g_eff: f64,
    r_eff: f64,
    m_eff: f64,
    gamma: f64,
    damping: f64,
    mindlin_c: f64,
) -> (f64, f64, f64) {
    let pc = HertzPair::new(e_eff, r_eff, m_eff);
    hertz_mindlin_pair(delta, vn, &pc, e_eff, g_eff, gamma, damping, mindlin_c)
}

/// The constants of one Hertz contact that depend only on the two bodies: computed once
/// per listed pair, not per step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HertzPair {
    /// Effective radius R*, m.
    pub r_eff: f64,
    /// Effective mass m*, kg.
    pub m_eff: f64,
    /// √R*, √m.
    pub sqrt_r: f64,
    /// √(m*·K) with K = (4/3)·E*·√R*, kg/(s·m^(1/4)).
    pub smk: f64,
}

impl HertzPair {
    /// Constants for effective modulus `e_eff` (Pa), radius `r_eff` (m), mass `m_eff` (kg).
    #[inline]
    pub fn new(e_eff: f64, r_eff: f64, m_eff: f64) -> Self {
        let sqrt_r = r_eff.sqrt();
        let k = 4.0 / 3.0 * e_eff * sqrt_r;
        HertzPair {
            r_eff,
            m_eff,
            sqrt_r,
            smk: (m_eff * k).sqrt(),
        }
    }
}

/// [`hertz_mindlin`] from a pair's precomputed constants.
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn hertz_mindlin_pair(
    delta: f64,
    vn: f64,
    pc: &HertzPair,
    e_eff: f64,
    g_eff: f64,
    gamma: f64,
    damping: f64,
    mindlin_c: f64,
) -> (f64, f64, f64) {
    let sr = pc.sqrt_r;
    let k = 4.0 / 3.0 * e_eff * sr;
    let smk = pc.smk;
    let sd = delta.sqrt(); // the uncapped overlap: Mindlin
    let q = sd.sqrt();
    // The normal force uses the overlap capped at OVERLAP_CAP·R* (hard cases only).
    let cap = super::normal::OVERLAP_CAP * pc.r_eff;
    let (dc, sdc, qc) = if delta > cap {
        let s = cap.sqrt();
        (cap, s, s.sqrt())
    } else {
        (delta, sd, q)
    };
    let fn_ = k * dc * sdc - gamma * smk * qc * vn;
    let kt = 8.0 * g_eff * sr * sd;
    let eta = damping * smk * mindlin_c * q;
    (fn_, kt, eta)
}

/// Rotate the history `xi` onto the tangent plane of unit normal `n`, keeping its length.
#[inline]
pub fn rotate_history(xi: DVec3, n: DVec3) -> DVec3 {
    let l2 = xi.length_squared();
    if l2 == 0.0 {
        return xi;
    }
    let p = xi - xi.dot(n) * n;
    let pl2 = p.length_squared();
    if pl2 == 0.0 {
        return DVec3::ZERO;
    }
    p * (l2 / pl2).sqrt()
}

/// Result of one tangential update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TangentialUpdate {
    /// Tangential force on the body whose relative velocity is `vt`, N.
    pub force: DVec3,
    /// New history displacement, m.
    pub history: DVec3,
    /// True when the contact slid (Coulomb limit reached).
    pub sliding: bool,
}

/// One step of the tangential spring–dashpot with Coulomb limit.
///
/// `xi` is the history from the last step (any orientation), `n` the current unit normal,
/// `vt` the tangential relative velocity of the contact point (this body relative to the
/// other, m/s, in the tangent plane), `kt` the tangential stiffness (N/m), `eta` the
/// dashpot coefficient (kg/s), `limit` = μ_s·|F_n| (N), `dt` the step (s).
#[inline]
pub fn tangential_force(
    xi: DVec3,
    n: DVec3,
    vt: DVec3,
    kt: f64,
    eta: f64,
    limit: f64,
    dt: f64,
) -> TangentialUpdate {
    let xi = rotate_history(xi, n) + vt * dt;
    let trial = -kt * xi - eta * vt;
    // Compared squared: a sticking contact (the usual case) needs no square root.
    let mag2 = trial.length_squared();
    if mag2 > limit * limit {
        let mag = mag2.sqrt();
        let force = if mag > 0.0 {
            trial * (limit / mag)
        } else {
            DVec3::ZERO
        };
        let history = if kt > 0.0 {
            -(force + eta * vt) / kt
        } else {
            DVec3::ZERO
        };
        TangentialUpdate {
            force,
            history,
            sliding: true,
        }
    } else {
        TangentialUpdate {
            force: trial,
            history: xi,
            sliding: false,
        }
    }
}

/// Constant directional rolling-resistance torque on the body spinning at `omega_rel`
/// relative to the other: −μ_r·|F_n|·R*·ω̂_rel (zero when μ_r = 0 or ω_rel = 0), N·m.
#[inline]
pub fn rolling_torque(mu_r: f64, fn_abs: f64, r_eff: f64, omega_rel: DVec3) -> DVec3 {
    if mu_r <= 0.0 {
        return DVec3::ZERO;
    }
    let w = omega_rel.length();
    if w <= 0.0 || !w.is_finite() {
        return DVec3::ZERO;
    }
    -(mu_r * fn_abs * r_eff / w) * omega_rel
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn history_rotation_keeps_length_and_is_tangent() {
        let xi = DVec3::new(1.0, 0.0, 0.2);
        let n = DVec3::new(0.1, 0.0, 1.0).normalize();
        let r = rotate_history(xi, n);
        assert!((r.length() - xi.length()).abs() < 1e-14);
        assert!(r.dot(n).abs() < 1e-14);
        assert_eq!(rotate_history(DVec3::ZERO, n), DVec3::ZERO);
    }

    #[test]
    fn elastic_spring_below_limit() {
        let n = DVec3::Z;
        let u = tangential_force(
            DVec3::ZERO,
            n,
            DVec3::new(1.0, 0.0, 0.0),
            100.0,
            0.0,
            1e9,
            0.01,
        );
        assert!(!u.sliding);
        assert!((u.history.x - 0.01).abs() < 1e-15);
        assert!((u.force.x + 1.0).abs() < 1e-12);
    }

    #[test]
    fn coulomb_limit_and_history_rescale() {
        let n = DVec3::Z;
        let vt = DVec3::new(2.0, 1.0, 0.0);
        let (kt, eta, limit) = (1e4, 3.0, 5.0);
        let u = tangential_force(DVec3::new(0.1, 0.0, 0.0), n, vt, kt, eta, limit, 1e-3);
        assert!(u.sliding);
        assert!((u.force.length() - limit).abs() < 1e-12);
        // The history reproduces the limited force.
        let back = -kt * u.history - eta * vt;
        assert!((back - u.force).length() < 1e-9);
    }

    #[test]
    fn mindlin_and_moduli() {
        let g = effective_shear_modulus(1e9, 0.3, 1e9, 0.3);
        let g1 = shear_modulus(1e9, 0.3);
        assert!((g - g1 / (2.0 * 1.7)).abs() < 1e-3);
        assert!((mindlin_stiffness(g, 1e-3, 1e-6) - 8.0 * g * 1e-9_f64.sqrt()).abs() < 1e-6);
        // Ratio k_t/k_n for Hertz: 8G*√(Rδ) / (2E*√(Rδ)) = 4G*/E* = 2(1−ν)/(2−ν).
        let e = crate::physics::contact::normal::effective_modulus(1e9, 0.3, 1e9, 0.3);
        let kn = 1.5 * crate::physics::contact::normal::hertz_stiffness(e, 1e-3) * 1e-3;
        let kt = mindlin_stiffness(g, 1e-3, 1e-6);
        assert!((kt / kn - 2.0 * 0.7 / 1.7).abs() < 1e-12);
    }

    #[test]
    fn damping_is_consistent_with_normal() {
        let law = NormalLaw::hertz(0.5);
        let NormalLaw::Hertz { gamma } = law else {
            unreachable!()
        };
        let c = damping_factor(law);
        // η_n from the normal law at δ equals c·√(m·k_n).
        let (m, e, r, d) = (1e-3, 1e8, 1e-3, 1e-6);
        let (f0, kn) = law.force(d, 0.0, e, r, m);
        let (f1, _) = law.force(d, 1.0, e, r, m);
        let eta_n = f0 - f1;
        assert!((eta_n - c * (m * kn).sqrt()).abs() < 1e-9 * eta_n.abs());
        assert!(gamma > 0.0);
        assert_eq!(damping_factor(NormalLaw::linear(10.0, 1.0)), 0.0);
    }

    #[test]
    fn rolling_torque_opposes_spin() {
        let t = rolling_torque(0.1, 2.0, 0.5, DVec3::new(0.0, 3.0, 0.0));
        assert!((t - DVec3::new(0.0, -0.1, 0.0)).length() < 1e-15);
        assert_eq!(rolling_torque(0.0, 2.0, 0.5, DVec3::Y), DVec3::ZERO);
        assert_eq!(rolling_torque(0.1, 2.0, 0.5, DVec3::ZERO), DVec3::ZERO);
    }

    #[test]
    fn hertz_mindlin_matches_the_separate_laws() {
        use crate::physics::contact::NormalLaw;
        let (e, g): (f64, f64) = (
            1.0e8 / (2.0 * (1.0 - 0.09)),
            1.0e8 / (2.0 * 2.6) / (2.0 * 1.7),
        );
        let c = (6.0 * g / e).sqrt();
        let gamma = 0.3;
        let law = NormalLaw::Hertz { gamma };
        for (delta, vn, r, m) in [
            (1e-6, 0.3, 5e-4, 1e-6),
            (3e-9, -2.0, 1e-4, 2e-9),
            (2e-3, 0.0, 1e-3, 5e-6), // overlap above the cap R*
            (7e-5, 11.0, 2.5e-4, 3e-8),
        ] {
            let (f, kt, eta) = hertz_mindlin(delta, vn, e, g, r, m, gamma, 0.7, c);
            let (f0, _) = law.force(delta, vn, e, r, m);
            let kt0 = mindlin_stiffness(g, r, delta);
            let eta0 = 0.7 * (m * kt0).sqrt();
            for (a, b) in [(f, f0), (kt, kt0), (eta, eta0)] {
                assert!((a - b).abs() <= 1e-13 * b.abs().max(1e-300), "{a} vs {b}");
            }
        }
    }
}
