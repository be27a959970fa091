//! The decomposition itself, without MPI: slabs along one axis, who owns a position, the
//! cuts that balance the particle counts, and the merging of what the ranks hold into what
//! one rank would have had (frames, tallies).
//!
//! A drag-only step moves each particle from its own state alone, so which rank moves it
//! does not change a bit of the result: the frames gathered from the ranks and sorted by
//! id are those of one rank.

use glam::DVec3;

/// Slabs along axis `axis` (0 = x, 1 = y, 2 = z): rank r owns the positions whose
/// coordinate c satisfies `cuts[r-1] <= c < cuts[r]` (the first and last slabs are open).
/// Along a periodic axis (`period` P: particle contacts in a periodic box [0, P), whose
/// positions are not wrapped) c is the coordinate wrapped into [0, P), the first slab
/// starts at 0, the last ends at P, and the two are neighbours across the box's side.
#[derive(Clone, Debug, PartialEq)]
pub struct Slabs {
    /// The axis cut.
    pub axis: usize,
    /// Ascending cut coordinates, m; one fewer than the ranks.
    pub cuts: Vec<f64>,
    /// Length of the periodic box along `axis`, m (`None`: open).
    pub period: Option<f64>,
}

impl Slabs {
    /// One slab holding everything (`ranks` = 1), or `ranks` slabs cut at 0 along `axis`
    /// until [`Slabs::balanced`] places them.
    pub fn new(axis: usize, ranks: usize) -> Self {
        Slabs {
            axis: axis.min(2),
            cuts: vec![0.0; ranks.max(1) - 1],
            period: None,
        }
    }

    /// The coordinate of x that decides its slab: along the axis, wrapped into [0, P)
    /// when the axis is periodic.
    #[inline]
    pub fn coord(&self, x: DVec3) -> f64 {
        self.wrap(x[self.axis])
    }

    /// `c` wrapped into [0, P) along a periodic axis, else `c`.
    #[inline]
    pub fn wrap(&self, c: f64) -> f64 {
        match self.period {
            Some(p) if c.is_finite() => {
                let w = c - p * (c / p).floor();
                if w >= p { 0.0 } else { w }
            }
            _ => c,
        }
    }

    /// Slab q's extent along the axis, m: [lo, hi) (infinite at the open ends).
    pub fn bounds(&self, q: usize) -> (f64, f64) {
        let n = self.ranks();
        let (first, last) = match self.period {
            Some(p) => (0.0, p),
            None => (f64::NEG_INFINITY, f64::INFINITY),
        };
        let lo = if q == 0 { first } else { self.cuts[q - 1] };
        let hi = if q + 1 >= n { last } else { self.cuts[q] };
        (lo, hi)
    }

    /// Number of slabs (ranks).
    pub fn ranks(&self) -> usize {
        self.cuts.len() + 1
    }

    /// The rank owning position `x` (a non-finite coordinate goes to rank 0, whose guard
    /// reports it).
    pub fn owner(&self, x: DVec3) -> usize {
        let c = self.coord(x);
        if !c.is_finite() {
            return 0;
        }
        self.cuts.partition_point(|&cut| cut <= c)
    }

    /// Slabs along `axis` holding equal shares (±1) of the particles at the coordinates
    /// `coords` (any order): each cut lies halfway between the last coordinate of one
    /// share and the first of the next. The result depends only on the multiset of
    /// coordinates, so every rank computes the same cuts from the same data. Along a
    /// periodic axis (`period`) the coordinates are wrapped into [0, P) first.
    pub fn balanced(axis: usize, ranks: usize, coords: &[f64], period: Option<f64>) -> Self {
        let open = Slabs {
            period,
            ..Slabs::new(axis, 1)
        };
        let mut c: Vec<f64> = coords
            .iter()
            .map(|&c| open.wrap(c))
            .filter(|c| c.is_finite())
            .collect();
        c.sort_unstable_by(f64::total_cmp);
        let n = c.len();
        let ranks = ranks.max(1);
        let cuts = (1..ranks)
            .map(|k| {
                let i = k * n / ranks;
                match (i.checked_sub(1).and_then(|j| c.get(j)), c.get(i)) {
                    (Some(a), Some(b)) => 0.5 * (a + b),
                    (None, Some(b)) => *b,
                    (Some(a), None) => *a,
                    (None, None) => 0.0,
                }
            })
            .collect();
        Slabs {
            axis: axis.min(2),
            cuts,
            period,
        }
    }
}

/// Who owns a particle: its slab, or (scenes without pair forces, where no particle needs
/// its neighbours) a hash of its id, which never changes, so nothing ever migrates and the
/// counts stay balanced.
#[derive(Clone, Debug, PartialEq)]
pub enum Owners {
    /// By position: slabs.
    Slabs(Slabs),
    /// By id over this many ranks.
    Ids(usize),
}

impl Owners {
    /// The rank owning particle `id` at `x`.
    pub fn owner(&self, id: u32, x: DVec3) -> usize {
        match self {
            Owners::Slabs(s) => s.owner(x),
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
    fn owner_follows_the_cuts() {
        let s = Slabs {
            axis: 1,
            cuts: vec![-1.0, 2.0],
            period: None,
        };
        let at = |y| s.owner(DVec3::new(100.0, y, -7.0));
        assert_eq!(at(-5.0), 0);
        assert_eq!(at(-1.0), 1, "a cut belongs to the slab above it");
        assert_eq!(at(1.999), 1);
        assert_eq!(at(2.0), 2);
        assert_eq!(at(1e9), 2);
        assert_eq!(at(f64::NAN), 0);
        assert_eq!(s.ranks(), 3);
        assert_eq!(Slabs::new(0, 1).owner(DVec3::splat(3.0)), 0);
    }

    #[test]
    fn periodic_slabs_own_wrapped_coordinates() {
        // A box [0, 3) along z cut at 1 and 2; positions are not wrapped.
        let s = Slabs::balanced(2, 3, &[0.5, 1.5, 2.5, 3.5, 4.5, 5.5], Some(3.0));
        assert_eq!(s.cuts, vec![1.0, 2.0]);
        let at = |z| s.owner(DVec3::new(0.0, 0.0, z));
        assert_eq!(at(0.2), 0);
        assert_eq!(at(3.2), 0, "one box up is the same place");
        assert_eq!(at(-0.2), 2, "just below 0 is the top of the box");
        assert_eq!(at(-1.5), 1);
        assert_eq!(at(2.999), 2);
        assert_eq!(at(f64::NAN), 0);
        assert_eq!(s.bounds(0), (0.0, 1.0));
        assert_eq!(s.bounds(2), (2.0, 3.0));
        assert_eq!(s.wrap(-1e-18), 0.0, "rounding up to P folds to 0");
        let open = Slabs::balanced(2, 3, &[0.5, 1.5, 2.5], None);
        assert_eq!(open.bounds(0), (f64::NEG_INFINITY, 1.0));
        assert_eq!(open.owner(DVec3::new(0.0, 0.0, -0.2)), 0);
    }

    #[test]
    fn balanced_cuts_share_the_particles_equally() {
        // 10 coordinates in scrambled order over 3 ranks: shares of 3, 3, 4.
        let coords = [9.0, 0.0, 5.0, 1.0, 8.0, 2.0, 7.0, 3.0, 6.0, 4.0];
        let s = Slabs::balanced(2, 3, &coords, None);
        assert_eq!(s.cuts, vec![2.5, 5.5]);
        let mut counts = [0u64; 3];
        for c in coords {
            counts[s.owner(DVec3::new(0.0, 0.0, c))] += 1;
        }
        assert_eq!(counts, [3, 3, 4]);
        assert!(!needs_rebalance(&counts, 1.2));
        // Order does not matter.
        let mut rev = coords;
        rev.reverse();
        assert_eq!(Slabs::balanced(2, 3, &rev, None), s);
        // Fewer particles than ranks, or none: still ascending cuts.
        let few = Slabs::balanced(0, 4, &[1.0], None);
        assert!(few.cuts.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(Slabs::balanced(0, 3, &[], None).cuts, vec![0.0, 0.0]);
    }

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
        let s = Owners::Slabs(Slabs::balanced(0, 2, &[0.0, 1.0], None));
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
