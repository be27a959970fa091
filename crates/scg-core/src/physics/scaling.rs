//! Coarse-graining laws: how an original particle (d, ρ) becomes a coarse-grained one.
//!
//! Every law but `sample` enlarges the diameter by α. They differ in the density and in
//! how the fluid force is evaluated:
//!
//! | law      | d_CG | ρ_CG        | fluid force               | source |
//! |----------|------|-------------|---------------------------|--------|
//! | `scg`    | α·d  | ρ/α²        | for d_CG                  | Kushimoto et al. 2021, eq. 7 (ρ·d² constant) |
//! | `none`   | α·d  | ρ           | for d_CG                  | the paper's "without SCG" |
//! | `mass`   | α·d  | ρ/α³        | for d_CG                  | the paper's Appendix A (mass equals the original's) |
//! | `parcel` | α·d  | ρ           | for d, multiplied by α³   | parcel approach of LIGGGHTS/CFDEM, MFiX, OpenFOAM MPPIC |
//! | `sample` | d    | ρ           | for d                     | plain sampling: the original particle, α³ fewer of them |
//!
//! Under every law a simulated particle stands for α³ originals: feeders given a volume or
//! mass rate and `scg cost`'s populations simulate α³ fewer particles. `sample` is the
//! control every coarse-graining law must beat: α³ fewer particles, each an original, so
//! no model error at all — only the statistical noise of the smaller population and, where
//! particles touch, α³ fewer collision partners.
//!
//! Under Stokes drag (F = 3πμ·d·u_r) the acceleration of a particle is 18μ·u_r/(ρ·d²):
//! `scg` and `parcel` keep it equal to the original's, `none` divides it by α², `mass`
//! multiplies it by α.

use serde::{Deserialize, Serialize};

/// A coarse-graining law (see the module docs for the table).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum CoarseGrainLaw {
    /// Simpler coarse-grain model: ρ_CG·d_CG² = ρ·d² (paper eq. 7).
    #[default]
    Scg,
    /// Enlarged, density unchanged.
    None,
    /// Enlarged, mass equal to the original's (ρ_CG = ρ/α³).
    Mass,
    /// Enlarged, density unchanged, fluid force of α³ original particles.
    Parcel,
    /// Not enlarged: the original particle, standing for α³ originals (sampling).
    Sample,
}

impl CoarseGrainLaw {
    /// All laws, in the order reports list them.
    pub const ALL: [CoarseGrainLaw; 5] = [
        CoarseGrainLaw::Scg,
        CoarseGrainLaw::None,
        CoarseGrainLaw::Mass,
        CoarseGrainLaw::Parcel,
        CoarseGrainLaw::Sample,
    ];

    /// Lower-case name as used in scene files.
    pub fn name(self) -> &'static str {
        match self {
            CoarseGrainLaw::Scg => "scg",
            CoarseGrainLaw::None => "none",
            CoarseGrainLaw::Mass => "mass",
            CoarseGrainLaw::Parcel => "parcel",
            CoarseGrainLaw::Sample => "sample",
        }
    }

    /// Whether the law enlarges the particle (every law but `sample`).
    pub fn enlarges(self) -> bool {
        self != CoarseGrainLaw::Sample
    }
}

/// The result of coarse graining one particle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scaled {
    /// Simulated diameter, m.
    pub diameter: f64,
    /// Simulated density, kg/m³.
    pub density: f64,
    /// Diameter the fluid force is evaluated for, m.
    pub drag_diameter: f64,
    /// Multiplier on the fluid force, dimensionless.
    pub force_scale: f64,
}

impl Scaled {
    /// Mass of the simulated particle, kg.
    pub fn mass(&self) -> f64 {
        sphere_mass(self.diameter, self.density)
    }
}

/// Mass of a sphere, kg, from its diameter (m) and density (kg/m³).
pub fn sphere_mass(diameter: f64, density: f64) -> f64 {
    density * std::f64::consts::PI * diameter * diameter * diameter / 6.0
}

/// Apply `law` with ratio `alpha` to an original particle of diameter `d` (m) and density
/// `rho` (kg/m³).
pub fn coarse_grain(law: CoarseGrainLaw, alpha: f64, d: f64, rho: f64) -> Scaled {
    let diameter = alpha * d;
    match law {
        CoarseGrainLaw::Scg => Scaled {
            diameter,
            // ρ·d²/d_CG², written so that α = 1 returns ρ bit-for-bit.
            density: rho * (d * d) / (diameter * diameter),
            drag_diameter: diameter,
            force_scale: 1.0,
        },
        CoarseGrainLaw::None => Scaled {
            diameter,
            density: rho,
            drag_diameter: diameter,
            force_scale: 1.0,
        },
        CoarseGrainLaw::Mass => Scaled {
            diameter,
            density: rho / (alpha * alpha * alpha),
            drag_diameter: diameter,
            force_scale: 1.0,
        },
        CoarseGrainLaw::Parcel => Scaled {
            diameter,
            density: rho,
            drag_diameter: d,
            force_scale: alpha * alpha * alpha,
        },
        CoarseGrainLaw::Sample => Scaled {
            diameter: d,
            density: rho,
            drag_diameter: d,
            force_scale: 1.0,
        },
    }
}

/// Volume of original powder one simulated particle of `law` with ratio `alpha` stands
/// for (α³ originals of diameter `d`, m), m³: what a feeder's volume or mass rate is
/// divided by.
pub fn represented_volume(alpha: f64, d: f64) -> f64 {
    let d_cg = alpha * d;
    std::f64::consts::PI / 6.0 * d_cg.powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn scg_keeps_rho_d2() {
        for alpha in [1.0, 2.0, 3.0, 4.0, 8.0, 16.0, 1.7] {
            let s = coarse_grain(CoarseGrainLaw::Scg, alpha, 1e-5, 1000.0);
            assert!(rel(s.density * s.diameter * s.diameter, 1000.0 * 1e-10) < 1e-15);
            assert_eq!(s.diameter, alpha * 1e-5);
        }
    }

    #[test]
    fn table_1_densities() {
        // Paper Table 1: 1 mm at 1 g/cm³ → 2, 4, 8 mm at 0.25, 0.0625, 0.015625 g/cm³.
        for (alpha, rho) in [(2.0, 250.0), (4.0, 62.5), (8.0, 15.625)] {
            let s = coarse_grain(CoarseGrainLaw::Scg, alpha, 1e-3, 1000.0);
            assert!(rel(s.density, rho) < 1e-15, "{alpha}: {}", s.density);
        }
    }

    #[test]
    fn mass_law_keeps_mass_and_none_keeps_density() {
        let m0 = sphere_mass(1e-3, 1000.0);
        for alpha in [2.0, 4.0, 8.0] {
            let s = coarse_grain(CoarseGrainLaw::Mass, alpha, 1e-3, 1000.0);
            assert!(rel(s.mass(), m0) < 1e-14);
            let n = coarse_grain(CoarseGrainLaw::None, alpha, 1e-3, 1000.0);
            assert_eq!(n.density, 1000.0);
            assert!(rel(n.mass(), m0 * alpha.powi(3)) < 1e-14);
        }
    }

    #[test]
    fn parcel_law_drags_like_alpha_cubed_originals() {
        let s = coarse_grain(CoarseGrainLaw::Parcel, 4.0, 1e-4, 500.0);
        assert_eq!(s.density, 500.0);
        assert_eq!(s.drag_diameter, 1e-4);
        assert_eq!(s.force_scale, 64.0);
        assert_eq!(s.diameter, 4e-4);
    }

    #[test]
    fn sample_law_is_the_original() {
        let s = coarse_grain(CoarseGrainLaw::Sample, 4.0, 1e-4, 500.0);
        assert_eq!(
            (s.diameter, s.density, s.drag_diameter, s.force_scale),
            (1e-4, 500.0, 1e-4, 1.0)
        );
        // it stands for α³ originals, as an enlarged particle does
        let v = represented_volume(4.0, 1e-4);
        assert!(rel(v, 64.0 * std::f64::consts::PI / 6.0 * 1e-12) < 1e-14);
        assert!(!CoarseGrainLaw::Sample.enlarges() && CoarseGrainLaw::Scg.enlarges());
    }

    /// `name()` (reports) and the serde names (scene files, `--laws`) agree.
    #[test]
    fn names_round_trip() {
        use serde::de::IntoDeserializer;
        type E = serde::de::value::Error;
        let parse = |s: &str| CoarseGrainLaw::deserialize(s.into_deserializer());
        for l in CoarseGrainLaw::ALL {
            assert_eq!(parse(l.name()).map_err(|e: E| e.to_string()), Ok(l));
        }
        assert!(parse("SCG").is_err());
    }
}
