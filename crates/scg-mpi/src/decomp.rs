//! The decomposition itself, without MPI: the ranks' regions (slabs along one axis or
//! boxes by recursive bisection, [`regions`]), who owns a position, the cuts that balance
//! the particle counts, and the merging of what the ranks hold into what one rank would
//! have had (frames, tallies).
//!
//! A drag-only step moves each particle from its own state alone, so which rank moves it
//! does not change a bit of the result: the frames gathered from the ranks and sorted by
//! id are those of one rank.

use glam::DVec3;

pub mod regions;
pub use regions::{Regions, Shape};

/// Who owns a particle: its region, or (scenes without pair forces, where no particle
/// needs its neighbours) a hash of its id, which never changes, so nothing ever migrates
/// and the counts stay balanced.
#[derive(Clone, Debug, PartialEq)]
pub enum Owners {
    /// By position: slabs or boxes.
    Regions(Regions),
    /// By id over this many ranks.
    Ids(usize),
}

impl Owners {
    /// The rank owning particle `id` at `x`.
    pub fn owner(&self, id: u32, x: DVec3) -> usize {
        match self {
            Owners::Regions(r) => r.owner(x),
            Owners::Ids(n) => (splitmix64(u64::from(id)) % (*n).max(1) as u64) as usize,
        }
    }
}

/// The axis along which the positions `xs` extend farthest (x when there are none).
pub fn longest_axis(xs: impl IntoIterator<Item = DVec3>) -> usize {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for x in xs.into_iter().filter(|x| x.is_finite()) {
        lo = lo.min(x);
        hi = hi.max(x);
    }
    let ext = hi - lo;
    if !ext.is_finite() {
        return 0;
    }
    let mut axis = 0;
    for a in 1..3 {
        if ext[a] > ext[axis] {
            axis = a;
        }
    }
    axis
}

/// Whether the particle counts per rank drifted enough to cut the slabs again: the
/// fullest rank holds more than `tolerance` times the mean and at least two particles
/// more than it.
pub fn needs_rebalance(counts: &[u64], tolerance: f64) -> bool {
    if counts.len() < 2 {
        return false;
    }
    let total: u64 = counts.iter().sum();
    let mean = total as f64 / counts.len() as f64;
    let max = counts.iter().copied().max().unwrap_or(0) as f64;
    max > tolerance * mean && max >= mean + 2.0
}

/// The per-group counts of all ranks merged: drained particles and collisions add up
/// (each rank counts its own); the fed counts are those of any one rank (every rank runs
/// every feeder, see [`crate`]).
pub fn merge_tally(tallies: &[scg_core::state::Tally]) -> Option<scg_core::state::Tally> {
    let first = tallies.first()?;
    let mut out = first.clone();
    for t in &tallies[1..] {
        for (a, b) in out.drained.iter_mut().zip(&t.drained) {
            *a += b;
        }
        for (a, b) in out.collisions.iter_mut().zip(&t.collisions) {
            *a += b;
        }
    }
    Some(out)
}

/// SplitMix64 of `x`: a well-mixed hash for order-independent digests of ids.
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn owners_by_id_are_balanced_and_fixed() {
        let o = Owners::Ids(3);
        let mut counts = [0u64; 3];
        for id in 0..3000 {
            let r = o.owner(id, DVec3::splat(id as f64));
            assert_eq!(r, o.owner(id, DVec3::ZERO), "the position does not matter");
            counts[r] += 1;
        }
        assert!(
            counts.iter().all(|&c| (900..1100).contains(&c)),
            "{counts:?}"
        );
        let xs = [DVec3::ZERO, DVec3::X];
        let s = Owners::Regions(Regions::balanced(Shape::Slabs(0), 2, &xs, [None; 3], 0.1));
        assert_eq!(s.owner(7, DVec3::new(0.0, 5.0, 5.0)), 0);
        assert_eq!(s.owner(7, DVec3::new(1.0, 5.0, 5.0)), 1);
    }

    #[test]
    fn rebalance_only_on_drift() {
        assert!(!needs_rebalance(&[100], 1.2));
        assert!(!needs_rebalance(&[100, 110, 95], 1.2));
        assert!(needs_rebalance(&[100, 200, 0], 1.2));
        // Two particles on one of two ranks: mean 1, max 2 < mean + 2.
        assert!(!needs_rebalance(&[2, 0], 1.2));
    }

    #[test]
    fn longest_axis_of_a_cloud() {
        let xs = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, -3.0, 0.5),
            DVec3::new(f64::NAN, 0.0, 0.0),
        ];
        assert_eq!(longest_axis(xs), 1);
        assert_eq!(longest_axis([]), 0);
    }

    #[test]
    fn tallies_merge_drained_and_collisions_but_not_fed() {
        use scg_core::state::Tally;
        let mut a = Tally::new(2);
        let mut b = Tally::new(2);
        a.drained = vec![1, 2];
        b.drained = vec![10, 20];
        a.collisions = vec![3, 0];
        b.collisions = vec![4, 1];
        a.fed = vec![7, 7];
        b.fed = vec![7, 7];
        let m = merge_tally(&[a, b]).unwrap();
        assert_eq!(m.drained, vec![11, 22]);
        assert_eq!(m.collisions, vec![7, 1]);
        assert_eq!(m.fed, vec![7, 7]);
        assert!(merge_tally(&[]).is_none());
    }
}
