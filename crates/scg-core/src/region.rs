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
    pub fn sample(&self, rng: &mut ChaCha8Rng) -> DVec3 {
        match *self {
            Region::Box { min, max } => DVec3::new(
                rng.random_range(min.x..=max.x),
                rng.random_range(min.y..=max.y),
                rng.random_range(min.z..=max.z),
            ),
            Region::Cylinder {
                center,
                axis,
                radius_min,
                radius_max,
                height,
            } => {
                let (a, b) = axis.any_orthonormal_pair();
                // Uniform in area: r² uniform between the radii.
                let r2 = rng.random_range(radius_min * radius_min..=radius_max * radius_max);
                let phi = rng.random_range(0.0..std::f64::consts::TAU);
                let h = rng.random_range(height.0..=height.1);
                center + axis * h + r2.sqrt() * (a * phi.cos() + b * phi.sin())
            }
        }
    }
}
