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
    /// Whether x is in the region (its boundary included), m.
    pub fn contains(&self, x: DVec3) -> bool {
        match *self {
            Region::Box { min, max } => x.cmpge(min).all() && x.cmple(max).all(),
            Region::Cylinder {
                center,
                axis,
                radius_min,
                radius_max,
                height,
            } => {
                let d = x - center;
                let h = d.dot(axis);
                let r2 = (d - h * axis).length_squared();
                h >= height.0
                    && h <= height.1
                    && r2 >= radius_min * radius_min
                    && r2 <= radius_max * radius_max
            }
        }
    }

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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn sampled_points_are_contained_and_outside_points_are_not() {
        let regions = [
            Region::Box {
                min: DVec3::new(-1.0, 0.0, 2.0),
                max: DVec3::new(1.0, 0.5, 3.0),
            },
            Region::Cylinder {
                center: DVec3::new(0.0, 0.0, -1.0),
                axis: DVec3::Z,
                radius_min: 0.1,
                radius_max: 0.25,
                height: (0.0, 0.2),
            },
        ];
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for r in &regions {
            for _ in 0..1000 {
                let x = r.sample(&mut rng);
                // sampled on the boundary to rounding: shrink toward the inside by 1e-12
                assert!(
                    r.contains(x) || r.contains(x * (1.0 - 1e-12)),
                    "{x} in {r:?}"
                );
            }
        }
        assert!(!regions[0].contains(DVec3::new(0.0, 0.6, 2.5)));
        assert!(!regions[1].contains(DVec3::new(0.05, 0.0, -0.9))); // inside radius_min
        assert!(!regions[1].contains(DVec3::new(0.2, 0.0, -0.7))); // above the height
        assert!(regions[1].contains(DVec3::new(0.0, 0.2, -0.9)));
    }
}
