//! Contact mechanics: pure kernels (normal, tangential, the one contact model of pairs
//! and walls, the pair kernel) and the contact material.
pub mod lanes;
pub mod model;
pub mod normal;
pub mod pair;
pub mod tangential;

pub use normal::NormalLaw;
pub use tangential::TangentialLaw;

use serde::{Deserialize, Serialize};

/// Contact material shared by particles and walls.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Young's modulus E, Pa.
    pub youngs_modulus: f64,
    /// Poisson's ratio ν, dimensionless.
    pub poisson_ratio: f64,
    /// Coefficient of restitution e, dimensionless (0 < e ≤ 1).
    pub restitution: f64,
    /// Sliding friction coefficient μ_s, dimensionless.
    pub friction: f64,
}

impl Material {
    /// Effective modulus E* of a contact between two bodies of this material, Pa.
    pub fn effective_modulus(&self) -> f64 {
        normal::effective_modulus(
            self.youngs_modulus,
            self.poisson_ratio,
            self.youngs_modulus,
            self.poisson_ratio,
        )
    }

    /// Effective shear modulus G* of a contact between two bodies of this material, Pa.
    pub fn effective_shear_modulus(&self) -> f64 {
        tangential::effective_shear_modulus(
            self.youngs_modulus,
            self.poisson_ratio,
            self.youngs_modulus,
            self.poisson_ratio,
        )
    }
}
