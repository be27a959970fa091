//! Orthogonal periodic boxes: the minimum image of a separation (pure).

use glam::DVec3;

/// An orthogonal periodic box [0, L) in each direction (positions may lie anywhere;
/// they are wrapped for binning and distances use the minimum image).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeriodicBox {
    /// Box lengths, m.
    pub lengths: DVec3,
    /// 1/L per axis, 1/m (so the minimum image multiplies instead of dividing).
    inv: DVec3,
}

impl PeriodicBox {
    /// A box of `lengths` (m).
    pub fn new(lengths: DVec3) -> Self {
        PeriodicBox {
            lengths,
            inv: lengths.recip(),
        }
    }

    /// The minimum-image form of the separation `d`: `d − image_shift(d)`.
    #[inline]
    pub fn min_image(&self, d: DVec3) -> DVec3 {
        d - self.image_shift(d)
    }

    /// The whole-box offset the minimum image removes from the separation `d`, m.
    #[inline]
    pub fn image_shift(&self, d: DVec3) -> DVec3 {
        let q = d * self.inv;
        self.lengths * DVec3::new(round_nearest(q.x), round_nearest(q.y), round_nearest(q.z))
    }

    /// `x` wrapped into [0, L).
    #[inline]
    pub fn wrap(&self, x: DVec3) -> DVec3 {
        let w = x - self.lengths * (x / self.lengths).floor();
        // Rounding can give exactly L; fold it back to 0.
        DVec3::select(w.cmpge(self.lengths), DVec3::ZERO, w)
    }
}

/// `x` rounded to the nearest integer (ties to even) with two additions: `f64::round` is a
/// library call on baseline x86-64 (no SSE4.1), and the pair kernel rounds every periodic
/// separation.
#[inline(always)]
fn round_nearest(x: f64) -> f64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0; // 1.5·2^52
    if x.abs() < 4.0e15 {
        (x + MAGIC) - MAGIC
    } else {
        x.round()
    }
}

/// Separation x_j − x_i, minimum image when `periodic`.
#[inline]
pub fn separation(xi: DVec3, xj: DVec3, periodic: Option<&PeriodicBox>) -> DVec3 {
    let d = xj - xi;
    match periodic {
        Some(b) => b.min_image(d),
        None => d,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_nearest_matches_round_away_from_ties() {
        for x in [
            0.0,
            0.4,
            0.6,
            -0.4,
            -0.6,
            1.49,
            -2.51,
            123456.7,
            -9.0e14 - 0.3,
            1.0e17,
            -3.0e300,
        ] {
            assert_eq!(round_nearest(x), x.round(), "{x}");
        }
        assert_eq!(round_nearest(2.5), 2.0);
        assert_eq!(round_nearest(-0.5).abs(), 0.0);
    }

    #[test]
    fn minimum_image() {
        let b = PeriodicBox::new(DVec3::splat(1.0));
        let d = b.min_image(DVec3::new(0.9, -0.6, 0.2));
        assert!((d - DVec3::new(-0.1, 0.4, 0.2)).length() < 1e-15);
        let w = b.wrap(DVec3::new(-0.25, 1.5, 0.0));
        assert!((w - DVec3::new(0.75, 0.5, 0.0)).length() < 1e-15);
    }
}
