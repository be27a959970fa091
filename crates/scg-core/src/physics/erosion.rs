//! Wall erosion by particle impacts: the volume a wall loses per impact, as selectable
//! models (pure functions).
//!
//! An impact is the particle's velocity relative to the wall `v` (m/s) meeting a wall
//! of unit normal `n` (into the fluid), by a particle standing for `mass` kg of original
//! powder. Under SCG and parcels a simulated particle stands for α³ originals, each
//! hitting at the same speed and angle: the wear counts α³·m_original, not the simulated
//! particle's own mass (α·m under SCG: α² too little).
//!
//! * [`ErosionModel::Finnie`]: Finnie's (1960) micro-cutting model for ductile walls, as
//!   OpenFOAM's `ParticleErosion` writes it: Q = m·|v|²/(p·ψ·K)·f(θ),
//!   f = sin 2θ − (6/K)·sin²θ for tan θ < K/6, else K·cos²θ/6, θ the impact angle from
//!   the wall's plane, p the wall's flow stress (Pa).
//! * [`ErosionModel::Dnv`]: DNV RP-O501's model for ductile steel: eroded mass per mass
//!   of particles K·|v|^n·F(θ), F a polynomial in θ (rad) that peaks at 1 near 36°;
//!   Q = m·K·|v|^n·F(θ)/ρ_wall.

use glam::DVec3;

/// An erosion model and its constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ErosionModel {
    /// Finnie (OpenFOAM's `ParticleErosion`).
    Finnie {
        /// The wall's plastic flow stress p, Pa.
        flow_stress: f64,
        /// Ratio of the contact depth to the cutting depth ψ (OpenFOAM's default 2).
        psi: f64,
        /// Ratio of normal to horizontal force K (OpenFOAM's default 2).
        k: f64,
    },
    /// DNV RP-O501 (ductile steel by default: K = 2e-9, n = 2.6).
    Dnv {
        /// Material constant K, (m/s)^-n.
        k: f64,
        /// Velocity exponent n.
        n: f64,
        /// Density of the wall, kg/m³.
        wall_density: f64,
    },
}

/// DNV RP-O501's angle function coefficients A₁…A₈ (ductile steel), F(θ) = Σ Aᵢ·θⁱ.
pub const DNV_A: [f64; 8] = [
    9.370, -42.295, 110.864, -175.804, 170.137, -98.398, 31.211, -4.170,
];

/// Impact angle θ (rad, 0 grazing to π/2 head-on) of a velocity `v` toward a wall of unit
/// normal `n` (into the fluid); 0 for a particle moving away or along it.
#[inline]
pub fn impact_angle(v: DVec3, n: DVec3) -> f64 {
    let s = v.length();
    let toward = -v.dot(n);
    if s == 0.0 || toward <= 0.0 {
        return 0.0;
    }
    (toward / s).clamp(0.0, 1.0).asin()
}

/// Finnie's angle function f(θ) with constant K.
#[inline]
pub fn finnie_angle(theta: f64, k: f64) -> f64 {
    if theta.tan() < k / 6.0 {
        (2.0 * theta).sin() - 6.0 / k * theta.sin().powi(2)
    } else {
        k * theta.cos().powi(2) / 6.0
    }
}

/// DNV RP-O501's angle function F(θ) (θ in rad).
#[inline]
pub fn dnv_angle(theta: f64) -> f64 {
    DNV_A.iter().rev().fold(0.0, |acc, a| (acc + a) * theta)
}

impl ErosionModel {
    /// The scene file's name.
    pub fn name(&self) -> &'static str {
        match self {
            ErosionModel::Finnie { .. } => "finnie",
            ErosionModel::Dnv { .. } => "dnv",
        }
    }

    /// Wall volume removed by one impact (m³) of `mass` kg of particles at velocity `v`
    /// (m/s, relative to the wall) on a wall of unit normal `n`.
    pub fn volume(&self, mass: f64, v: DVec3, n: DVec3) -> f64 {
        let theta = impact_angle(v, n);
        if theta <= 0.0 {
            return 0.0;
        }
        match *self {
            ErosionModel::Finnie {
                flow_stress,
                psi,
                k,
            } => mass * v.length_squared() / (flow_stress * psi * k) * finnie_angle(theta, k),
            ErosionModel::Dnv { k, n, wall_density } => {
                mass * k * v.length().powf(n) * dnv_angle(theta) / wall_density
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finnie_as_openfoam_writes_it() {
        let m = ErosionModel::Finnie {
            flow_stress: 1e9,
            psi: 2.0,
            k: 2.0,
        };
        let n = DVec3::Z;
        for deg in [5.0_f64, 10.0, 18.0, 18.5, 30.0, 60.0, 90.0] {
            let t = deg.to_radians();
            let v = 20.0 * DVec3::new(t.cos(), 0.0, -t.sin());
            let q = m.volume(3e-9, v, n);
            let coeff = 3e-9 * 400.0 / (1e9 * 2.0 * 2.0);
            let want = if t.tan() < 2.0 / 6.0 {
                coeff * ((2.0 * t).sin() - 3.0 * t.sin() * t.sin())
            } else {
                coeff * (2.0 * t.cos() * t.cos() / 6.0)
            };
            assert!((q - want).abs() <= 1e-12 * want, "{deg}°: {q} vs {want}");
            assert!((impact_angle(v, n) - t).abs() < 1e-12);
        }
        // continuous where the two branches meet (tan θ = 1/3), zero head-on only for K
        // → ∞; nothing for a particle leaving the wall
        let t = (1.0_f64 / 3.0).atan();
        assert!((finnie_angle(t - 1e-12, 2.0) - finnie_angle(t + 1e-12, 2.0)).abs() < 1e-9);
        assert_eq!(m.volume(1.0, DVec3::new(1.0, 0.0, 1.0), n), 0.0);
    }

    #[test]
    fn dnv_angle_function_peaks_at_one_near_36_degrees() {
        let (mut best, mut at) = (0.0, 0.0);
        for i in 0..=9000 {
            let t = (i as f64 / 100.0).to_radians();
            let f = dnv_angle(t);
            assert!(f >= -1e-12, "{i}: {f}");
            if f > best {
                (best, at) = (f, i as f64 / 100.0);
            }
        }
        assert!(
            (best - 1.0).abs() < 0.01 && (30.0..40.0).contains(&at),
            "{best} at {at}°"
        );
        let m = ErosionModel::Dnv {
            k: 2e-9,
            n: 2.6,
            wall_density: 7800.0,
        };
        let t = 0.5_f64;
        let v = 15.0 * DVec3::new(t.cos(), -t.sin(), 0.0);
        let want = 2.0 * 2e-9 * 15.0_f64.powf(2.6) * dnv_angle(t) / 7800.0;
        assert!((m.volume(2.0, v, DVec3::Y) - want).abs() <= 1e-12 * want);
    }
}
