//! Fluid drag laws (pure functions).
//!
//! The drag force on a sphere of diameter d with slip u_r = u − v is (paper eq. 4)
//! F_D = C_d·A·ρ_f·|u_r|·u_r/2 with A = π·d²/4. Writing C_d = (24/Re)·f(Re) gives
//! F_D = 3π·μ·d·f(Re)·u_r, so a particle relaxes to the fluid velocity with the response
//! time τ = m / (3π·μ·d·f(Re)).

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A drag law.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum DragLaw {
    /// Stokes: C_d = 24/Re (paper eq. 5), valid for Re < 0.1. Linear in the slip.
    #[default]
    Stokes,
    /// Schiller & Naumann (1933): C_d = 24/Re·(1 + 0.15·Re^0.687) for Re < 1000, the
    /// Newton regime's C_d = 0.44 beyond (as OpenFOAM's `SchillerNaumann` drag).
    SchillerNaumann,
    /// Putnam (1961), OpenFOAM's `sphereDrag`: C_d = 24/Re·(1 + Re^(2/3)/6) for
    /// Re < 1000, 0.424 beyond (the law OpenFOAM's particle tracker runs by default, for
    /// like-for-like comparisons).
    Putnam,
}

impl DragLaw {
    /// Scene-file name.
    pub fn name(self) -> &'static str {
        match self {
            DragLaw::Stokes => "stokes",
            DragLaw::SchillerNaumann => "schiller_naumann",
            DragLaw::Putnam => "putnam",
        }
    }

    /// The correction f(Re) = C_d·Re/24 of this law.
    #[inline]
    pub fn correction(self, re: f64) -> f64 {
        match self {
            DragLaw::Stokes => 1.0,
            DragLaw::SchillerNaumann => schiller_naumann_correction(re),
            DragLaw::Putnam => putnam_correction(re),
        }
    }

    /// Drag coefficient C_d at particle Reynolds number `re` (> 0).
    pub fn coefficient(self, re: f64) -> f64 {
        match self {
            DragLaw::Stokes => stokes_cd(re),
            DragLaw::SchillerNaumann => schiller_naumann_cd(re),
            DragLaw::Putnam => 24.0 / re * putnam_correction(re),
        }
    }
}

/// Mean free path of air at 20 °C and 101.325 kPa, m (the value that gives Davies'
/// C_c = 1.166 at 1 µm; the scene states its own).
pub const AIR_MEAN_FREE_PATH: f64 = 6.6e-8;

/// Cunningham's slip correction with Davies' (1945) constants:
/// C_c = 1 + Kn·(1.257 + 0.4·exp(−1.1/Kn)), Kn = 2λ/d, for a sphere of diameter `d` in a
/// gas of mean free path `lambda` (both m). Stokes drag is divided by it.
#[inline]
pub fn cunningham_davies(d: f64, lambda: f64) -> f64 {
    let kn = 2.0 * lambda / d;
    1.0 + kn * (1.257 + 0.4 * (-1.1 / kn).exp())
}

/// Stokes drag coefficient C_d = 24/Re (paper eq. 5).
pub fn stokes_cd(re: f64) -> f64 {
    24.0 / re
}

/// Schiller–Naumann drag coefficient C_d = 24/Re·(1 + 0.15·Re^0.687) below Re = 1000,
/// 0.44 from there.
pub fn schiller_naumann_cd(re: f64) -> f64 {
    24.0 / re * schiller_naumann_correction(re)
}

/// Schiller–Naumann correction to Stokes drag, f = 1 + 0.15·Re^0.687 for Re < 1000,
/// f = 0.44·Re/24 (C_d = 0.44, the Newton regime) from there, as OpenFOAM's
/// `SchillerNaumann` drag writes it (the two meet within 0.5 % at Re = 1000). The power
/// by [`crate::physics::elementary::powf`] (within 2·10^-15 of libm's, and evaluated in
/// lanes for a block of particles); below Re = 10^-300 the correction is 1.
#[inline(always)]
pub fn schiller_naumann_correction(re: f64) -> f64 {
    if re < 1000.0 {
        let p = crate::physics::elementary::powf(re.max(1e-300), 0.687);
        1.0 + 0.15 * p
    } else {
        0.44 * re / 24.0
    }
}

/// Putnam's correction to Stokes drag as OpenFOAM's `sphereDrag` writes it:
/// f = 1 + Re^(2/3)/6 for Re < 1000, else 0.424·Re/24 (C_d = 0.424).
/// The power by [`crate::physics::elementary::powf`] (within 2·10^-15 of libm's `pow`,
/// and evaluated in lanes for a block of particles); below Re = 10^-300 the correction
/// is 1.
#[inline(always)]
pub fn putnam_correction(re: f64) -> f64 {
    if re < 1000.0 {
        1.0 + crate::physics::elementary::powf(re.max(1e-300), 2.0 / 3.0) / 6.0
    } else {
        0.424 * re / 24.0
    }
}

/// Particle Reynolds number Re = ρ_f·d·|u_r|/μ (paper eq. 5).
#[inline]
pub fn particle_reynolds(
    diameter: f64,
    slip_speed: f64,
    fluid_density: f64,
    viscosity: f64,
) -> f64 {
    fluid_density * diameter * slip_speed / viscosity
}

/// Drag force, N, from paper eq. 4: F = C_d·A·ρ_f·|u_r|·u_r/2, for a slip vector `slip` (m/s).
pub fn drag_force(
    law: DragLaw,
    diameter: f64,
    slip: glam::DVec3,
    fluid_density: f64,
    viscosity: f64,
) -> glam::DVec3 {
    let s = slip.length();
    if s == 0.0 {
        return glam::DVec3::ZERO;
    }
    let re = particle_reynolds(diameter, s, fluid_density, viscosity);
    let area = PI * diameter * diameter / 4.0;
    law.coefficient(re) * area * fluid_density * s / 2.0 * slip
}

/// Stokes response time τ = m / (3π·μ·d_drag·scale), s, of a particle of mass `mass` (kg)
/// whose fluid force is evaluated for diameter `drag_diameter` (m) and multiplied by
/// `force_scale`. For an unscaled sphere this is τ = ρ·d²/(18·μ).
#[inline]
pub fn stokes_response_time(
    mass: f64,
    viscosity: f64,
    drag_diameter: f64,
    force_scale: f64,
) -> f64 {
    mass / (3.0 * PI * viscosity * drag_diameter * force_scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn eq4_with_stokes_is_3_pi_mu_d_u() {
        let (d, mu, rho_f) = (1e-5, 1.8e-5, 1.2);
        let slip = DVec3::new(0.3, -0.1, 0.05);
        let f = drag_force(DragLaw::Stokes, d, slip, rho_f, mu);
        let expect = 3.0 * PI * mu * d * slip;
        assert!((f - expect).length() / expect.length() < 1e-14);
    }

    #[test]
    fn response_time_matches_rho_d2_over_18_mu() {
        let (d, rho, mu) = (1e-5, 1000.0, 1.8e-5);
        let m = crate::physics::scaling::sphere_mass(d, rho);
        let tau = stokes_response_time(m, mu, d, 1.0);
        let expect = rho * d * d / (18.0 * mu);
        assert!(((tau - expect) / expect).abs() < 1e-14);
    }

    #[test]
    fn schiller_naumann_limits() {
        // f → 1 at small Re; C_d(Re = 1) = 24·1.15.
        assert!((schiller_naumann_correction(1e-12) - 1.0).abs() < 1e-8);
        assert!((schiller_naumann_cd(1.0) - 24.0 * 1.15).abs() < 1e-12);
        assert_eq!(DragLaw::Stokes.correction(50.0), 1.0);
    }

    #[test]
    fn cunningham_davies_values_and_limits() {
        // 1 µm in air: 1.166 (Davies; Hinds, Aerosol Technology, Table A.6 gives 1.168 at
        // λ = 66.5 nm)
        let c = cunningham_davies(1e-6, AIR_MEAN_FREE_PATH);
        assert!((c - 1.166).abs() < 5e-4, "{c}");
        // the formula itself, at Kn = 0.5: 1 + 0.5·(1.257 + 0.4·e^(−2.2))
        let want = 1.0 + 0.5 * (1.257 + 0.4 * f64::exp(-2.2));
        assert!(
            (cunningham_davies(4.0 * AIR_MEAN_FREE_PATH, AIR_MEAN_FREE_PATH) - want).abs() < 1e-15
        );
        // continuum: 1 + 2.514·λ/d; free molecular: C_c/Kn → 1.657
        let big = cunningham_davies(1e-3, 6.6e-8);
        assert!((big - (1.0 + 2.514 * 6.6e-8 / 1e-3)).abs() < 1e-12);
        let kn = 1e4;
        let tiny = cunningham_davies(2.0 * 6.6e-8 / kn, 6.6e-8);
        assert!((tiny / kn - 1.657).abs() < 1e-3);
    }

    #[test]
    fn schiller_naumann_caps_at_newtons_044() {
        // below 1000 the power law, from 1000 on C_d = 0.44 (Newton's regime)
        let re = 500.0;
        let libm = 1.0 + 0.15 * f64::powf(re, 0.687);
        assert!((schiller_naumann_correction(re) - libm).abs() < 2e-15 * libm);
        for re in [1000.0, 2000.0, 1e4, 2e5] {
            assert!(
                (DragLaw::SchillerNaumann.coefficient(re) - 0.44).abs() < 1e-15,
                "{re}"
            );
        }
        // the uncapped law falls on: C_d = 0.20 at 10^4, under half of Newton's
        assert!(24.0 / 1e4 * (1.0 + 0.15 * f64::powf(1e4, 0.687)) < 0.21);
        // the two branches meet within 0.5 % at 1000
        let (a, b) = (
            schiller_naumann_correction(1000.0 - 1e-9),
            schiller_naumann_correction(1000.0),
        );
        assert!((a - b).abs() < 5e-3 * b, "{a} {b}");
    }

    #[test]
    fn putnam_is_openfoams_sphere_drag() {
        // CdRe/24 = 1 + Re^(2/3)/6 below 1000, C_d = 0.424 above; continuous at 1000
        assert!((putnam_correction(8.0) - (1.0 + 4.0 / 6.0)).abs() < 1e-15);
        // the power is libm's pow(2/3) within 2e-15 relative over the law's range
        for k in 0..=600 {
            let re = 10f64.powf(-3.0 + k as f64 * 0.01);
            if re < 1000.0 {
                let want = 1.0 + re.powf(2.0 / 3.0) / 6.0;
                assert!((putnam_correction(re) - want).abs() <= 2e-15 * want, "{re}");
            }
        }
        assert!((DragLaw::Putnam.coefficient(2000.0) - 0.424).abs() < 1e-15);
        let (a, b) = (putnam_correction(1000.0 - 1e-9), putnam_correction(1000.0));
        assert!((a - b).abs() < 1e-9 * b);
        assert_eq!(DragLaw::Putnam.name(), "putnam");
    }
}
