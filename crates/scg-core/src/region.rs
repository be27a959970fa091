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
    /// Any finite region gives a finite point: a range whose width overflows (a region
    /// spanning ±1e308) is sampled by interpolation instead of `random_range`, which
    /// panics on it. Ordinary regions draw exactly as before.
    pub fn sample(&self, rng: &mut ChaCha8Rng) -> DVec3 {
        let mut range = |lo: f64, hi: f64| {
            if (hi - lo).is_finite() {
                rng.random_range(lo..=hi)
            } else {
                let u: f64 = rng.random();
                lo * (1.0 - u) + hi * u
            }
        };
        match *self {
            Region::Box { min, max } => DVec3::new(
                range(min.x, max.x),
                range(min.y, max.y),
                range(min.z, max.z),
            ),
            Region::Cylinder {
                center,
                axis,
                radius_min,
                radius_max,
                height,
            } => {
                let (a, b) = axis.any_orthonormal_pair();
                // Uniform in area: r² uniform between the radii (scaled by radius_max
                // when the squares overflow).
                let r = if (radius_max * radius_max).is_finite() {
                    range(radius_min * radius_min, radius_max * radius_max).sqrt()
                } else {
                    let q = radius_min / radius_max;
                    radius_max * range(q * q, 1.0).sqrt()
                };
                let phi = range(0.0, std::f64::consts::TAU);
                let h = range(height.0, height.1);
                center + axis * h + r * (a * phi.cos() + b * phi.sin())
            }
        }
    }
}
