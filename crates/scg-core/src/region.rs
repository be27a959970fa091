//! Regions for random placement (initial particles and feeders).

use glam::DVec3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A region for random placement.
#[derive(Clone, Debug, PartialEq)]
pub enum Region {
    /// Axis-aligned box, m.
    Box {
        /// Lower corner.
        min: DVec3,
        /// Upper corner.
        max: DVec3,
    },
    /// Annular cylinder (radius_min..radius_max, height range along the axis), m.
    Cylinder {
        /// Point on the axis.
        center: DVec3,
        /// Unit axis.
        axis: DVec3,
        /// Inner radius.
        radius_min: f64,
        /// Outer radius.
        radius_max: f64,
        /// Height range along the axis from `center`.
        height: (f64, f64),
    },
}

impl Region {
    /// A point uniformly at random in the region (uniform in area for the annulus).
    ///
    /// Written as interpolations so that any finite region (even one spanning ±1e308)
    /// gives a finite point without overflow, and without the range checks that make
    /// `random_range` panic.
    pub fn sample(&self, rng: &mut ChaCha8Rng) -> DVec3 {
        let mut lerp = |lo: f64, hi: f64| {
            let u: f64 = rng.random();
            lo * (1.0 - u) + hi * u
        };
        match *self {
            Region::Box { min, max } => DVec3::new(
                lerp(min.x, max.x),
                lerp(min.y, max.y),
                lerp(min.z, max.z),
            ),
            Region::Cylinder {
                center,
                axis,
                radius_min,
                radius_max,
                height,
            } => {
                let (a, b) = axis.any_orthonormal_pair();
                // Uniform in area: r² uniform between the radii, scaled by radius_max so
                // that the squares cannot overflow.
                let q = if radius_max > 0.0 {
                    radius_min / radius_max
                } else {
                    0.0
                };
                let r = radius_max * lerp(q * q, 1.0).sqrt();
                let phi = lerp(0.0, std::f64::consts::TAU);
                let h = lerp(height.0, height.1);
                center + axis * h + r * (a * phi.cos() + b * phi.sin())
            }
        }
    }
}
