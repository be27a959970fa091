//! The ranks' regions: one axis-aligned box per rank, the leaves of a tree of cuts.
//!
//! Two shapes come from one construction ([`Regions::balanced`]): the particles are
//! split at a quantile of their coordinates along an axis, the ranks in two halves with
//! shares proportional to their counts, and each half is split again until one rank is
//! left. Cutting along one fixed axis every time gives *slabs* ([`Shape::Slabs`]); along
//! the longest extent of each part's particles, *recursive coordinate bisection*
//! ([`Shape::Bisection`], Berger & Bokhari 1987; LAMMPS's `balance rcb`). Slabs suit
//! elongated domains (a pipe, a channel: few cut faces, two neighbours); bisection
//! compact ones on more ranks, where slabs grow thinner than the ghost halo and every
//! particle becomes somebody's ghost. [`Shape::Auto`] builds both and keeps the one with
//! fewer ghost copies ([`Regions::ghost_copies`]: a particle near a box's corner is a
//! ghost on each box round it).
//!
//! Along a periodic axis (a contact scene's periodic box) coordinates are wrapped into
//! [0, P) first; the boxes tile [0, P) there and meet across the box's sides.

use glam::DVec3;

/// How [`Regions::balanced`] cuts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Every cut along this axis (0 = x, 1 = y, 2 = z).
    Slabs(usize),
    /// Each cut along the longest extent of the particles it splits.
    Bisection,
    /// Slabs along the longest extent or bisection, whichever gives fewer ghost copies
    /// ([`Regions::ghost_copies`]; slabs on a tie, and always on 2 ranks, where the two
    /// are the same cut).
    Auto,
}

/// How [`Regions::grow`] places a cut: (the particles of the node, sorted along the axis
/// on return; its first, middle and end rank) → (axis, coordinate).
type ChooseCut<'a> = dyn FnMut(&mut [DVec3], usize, usize, usize) -> (usize, f64) + 'a;

/// A node of the tree: ranks `first..end` are split at `mid`, the ranks below `mid`
/// owning the coordinates `c < at` along `axis`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cut {
    first: usize,
    mid: usize,
    end: usize,
    axis: usize,
    at: f64,
}

/// One box per rank, from a tree of cuts: rank r owns the positions in its box
/// `[lo, hi)` (open to infinity at the domain's open sides; [0, P) along a periodic
/// axis, positions wrapped). A position on a cut belongs to the box above it.
#[derive(Clone, Debug, PartialEq)]
pub struct Regions {
    /// The cuts in depth-first order (the root first, then its lower subtree).
    cuts: Vec<Cut>,
    /// Per rank its box: (lo, hi), m.
    boxes: Vec<(DVec3, DVec3)>,
    /// Per axis the periodic box's length, m (`None`: open).
    period: [Option<f64>; 3],
    /// Whether every cut is along one axis (slabs), and which.
    slab_axis: Option<usize>,
}

impl Regions {
    /// One region holding everything (`ranks` = 1), or `ranks` slabs along `axis` cut
    /// at 0 until [`Regions::balanced`] places them.
    pub fn new(axis: usize, ranks: usize) -> Self {
        Regions::slabs(axis, vec![0.0; ranks.max(1) - 1], [None; 3])
    }

    /// Slabs along `axis` cut at the ascending coordinates `cuts` (one fewer than the
    /// ranks): rank r owns `cuts[r-1] <= c < cuts[r]`.
    pub fn slabs(axis: usize, cuts: Vec<f64>, period: [Option<f64>; 3]) -> Self {
        let axis = axis.min(2);
        let ranks = cuts.len() + 1;
        let mut r = Regions::empty(ranks, period);
        r.slab_axis = Some(axis);
        r.grow(&mut [], (0, ranks), r.domain(), &mut |_, _, mid, _| {
            (axis, cuts[mid - 1])
        });
        r
    }

    /// Regions of `ranks` holding equal shares (±1) of the particles at `xs` (any order;
    /// non-finite positions ignored), cut as `shape` says; `halo` (m) is the reach
    /// [`Shape::Auto`] compares the shapes by. Each cut lies halfway between the last
    /// particle of one share and the first of the next. The result depends only on the
    /// multiset of positions, so every rank computes the same regions from the same data.
    pub fn balanced(
        shape: Shape,
        ranks: usize,
        xs: &[DVec3],
        period: [Option<f64>; 3],
        halo: f64,
    ) -> Self {
        let ranks = ranks.max(1);
        let wrapped: Vec<DVec3> = {
            let open = Regions::empty(1, period);
            xs.iter()
                .map(|&x| open.wrap(x))
                .filter(|x| x.is_finite())
                .collect()
        };
        let build = |shape: Shape| -> Regions {
            let mut r = Regions::empty(ranks, period);
            if let Shape::Slabs(a) = shape {
                r.slab_axis = Some(a.min(2));
            }
            let mut pts = wrapped.clone();
            r.grow(
                &mut pts,
                (0, ranks),
                r.domain(),
                &mut |p, first, mid, end| Regions::quantile_cut(shape, p, (first, mid, end)),
            );
            r
        };
        match shape {
            Shape::Auto => {
                let slabs = build(Shape::Slabs(crate::decomp::longest_axis(
                    wrapped.iter().copied(),
                )));
                if ranks <= 2 {
                    return slabs;
                }
                let rcb = build(Shape::Bisection);
                if rcb.ghost_copies(&wrapped, halo) < slabs.ghost_copies(&wrapped, halo) {
                    rcb
                } else {
                    slabs
                }
            }
            s => build(s),
        }
    }

    fn empty(ranks: usize, period: [Option<f64>; 3]) -> Self {
        Regions {
            cuts: Vec::new(),
            boxes: vec![(DVec3::ZERO, DVec3::ZERO); ranks.max(1)],
            period,
            slab_axis: None,
        }
    }

    /// The whole domain: [0, P) along periodic axes, all of space along open ones.
    fn domain(&self) -> (DVec3, DVec3) {
        let lo = self.period.map(|p| p.map_or(f64::NEG_INFINITY, |_| 0.0));
        let hi = self.period.map(|p| p.unwrap_or(f64::INFINITY));
        (DVec3::from_array(lo), DVec3::from_array(hi))
    }

    /// Build the tree below ranks `first..end` within `bounds` over the particles `pts`
    /// (wrapped, finite; none for given cuts): `choose(pts, first, mid, end)` gives each
    /// cut's axis and coordinate, with `pts` sorted along that axis, and the particles
    /// below the cut go to the lower ranks.
    fn grow(
        &mut self,
        pts: &mut [DVec3],
        (first, end): (usize, usize),
        bounds: (DVec3, DVec3),
        choose: &mut ChooseCut<'_>,
    ) {
        if end - first <= 1 {
            self.boxes[first] = bounds;
            return;
        }
        let mid = first + (end - first) / 2;
        let (axis, at) = choose(pts, first, mid, end);
        let at = at.clamp(bounds.0[axis], bounds.1[axis]);
        self.cuts.push(Cut {
            first,
            mid,
            end,
            axis,
            at,
        });
        let k = pts.partition_point(|p| p[axis] < at);
        let (lo_pts, hi_pts) = pts.split_at_mut(k);
        let (mut below, mut above) = (bounds, bounds);
        below.1[axis] = at;
        above.0[axis] = at;
        self.grow(lo_pts, (first, mid), below, choose);
        self.grow(hi_pts, (mid, end), above, choose);
    }

    /// The cut of `choose` in [`Regions::grow`] for a balanced split: along the slab axis
    /// or the particles' longest extent, halfway between the last particle of the lower
    /// ranks' share and the first of the upper's.
    fn quantile_cut(
        shape: Shape,
        pts: &mut [DVec3],
        (first, mid, end): (usize, usize, usize),
    ) -> (usize, f64) {
        let axis = match shape {
            Shape::Slabs(a) => a.min(2),
            _ => crate::decomp::longest_axis(pts.iter().copied()),
        };
        // A total order on positions (the axis first), so that the shares, and the
        // next cuts' axes, depend only on the multiset.
        let order = [axis, (axis + 1) % 3, (axis + 2) % 3];
        pts.sort_unstable_by(|a, b| {
            order
                .iter()
                .map(|&k| a[k].total_cmp(&b[k]))
                .find(|o| o.is_ne())
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        let i = pts.len() * (mid - first) / (end - first);
        let at = match (i.checked_sub(1).and_then(|j| pts.get(j)), pts.get(i)) {
            (Some(a), Some(b)) => 0.5 * (a[axis] + b[axis]),
            (None, Some(b)) => b[axis],
            (Some(a), None) => a[axis],
            (None, None) => 0.0,
        };
        (axis, at)
    }

    /// Number of regions (ranks).
    pub fn ranks(&self) -> usize {
        self.boxes.len()
    }

    /// Rank q's box (lo, hi), m.
    pub fn bounds(&self, q: usize) -> (DVec3, DVec3) {
        self.boxes[q]
    }

    /// The slab axis when every cut is along one axis.
    pub fn slab_axis(&self) -> Option<usize> {
        self.slab_axis
    }

    /// Per axis the periodic box's length the regions tile, m (`None`: open).
    pub fn period(&self) -> [Option<f64>; 3] {
        self.period
    }

    /// `x` wrapped into [0, P) along the periodic axes.
    #[inline]
    pub fn wrap(&self, x: DVec3) -> DVec3 {
        let mut w = x;
        for a in 0..3 {
            // Most positions lie in the box already (they are wrapped only here).
            if let Some(p) = self.period[a]
                && !(w[a] >= 0.0 && w[a] < p)
                && w[a].is_finite()
            {
                let c = w[a] - p * (w[a] / p).floor();
                w[a] = if c >= p { 0.0 } else { c };
            }
        }
        w
    }

    /// The rank owning position `x` (a non-finite position goes to rank 0, whose guard
    /// reports it).
    pub fn owner(&self, x: DVec3) -> usize {
        let x = self.wrap(x);
        if !x.is_finite() {
            return 0;
        }
        // Depth-first order: a node's lower subtree follows it, its upper one after.
        let mut k = 0;
        let (mut first, mut end) = (0, self.ranks());
        while end - first > 1 {
            let c = self.cuts[k];
            debug_assert!(c.first == first && c.end == end);
            if x[c.axis] < c.at {
                end = c.mid;
                k += 1;
            } else {
                // Skip the lower subtree: one cut per rank boundary in it.
                k += c.mid - c.first;
                first = c.mid;
            }
        }
        first
    }

    /// The squared distance from `x` to rank q's box, m², along each periodic axis to
    /// the nearest image.
    pub fn distance_squared(&self, x: DVec3, q: usize) -> f64 {
        self.distance_squared_wrapped(self.wrap(x), q)
    }

    /// [`Regions::distance_squared`] of a position already wrapped ([`Regions::wrap`]).
    #[inline]
    pub fn distance_squared_wrapped(&self, x: DVec3, q: usize) -> f64 {
        let (lo, hi) = self.boxes[q];
        let mut d2 = 0.0;
        for a in 0..3 {
            let (l, h, c) = (lo[a], hi[a], x[a]);
            if c >= l && c < h {
                // Within the box's extent along a (always along an axis it spans).
                continue;
            }
            let gap = |c: f64| (l - c).max(c - h).max(0.0);
            let d = match self.period[a] {
                Some(p) => gap(c).min(gap(c - p)).min(gap(c + p)),
                None => gap(c),
            };
            d2 += d * d;
        }
        d2
    }

    /// The squared gap between the boxes of ranks q and r, m² (0 when they touch),
    /// along each periodic axis the way round too.
    pub fn gap_squared(&self, q: usize, r: usize) -> f64 {
        let ((ql, qh), (rl, rh)) = (self.boxes[q], self.boxes[r]);
        (0..3)
            .map(|a| {
                let gap = |s: f64| (rl[a] + s - qh[a]).max(ql[a] - (rh[a] + s)).max(0.0);
                let d = match self.period[a] {
                    Some(p) => gap(0.0).min(gap(p)).min(gap(-p)),
                    None => gap(0.0),
                };
                d * d
            })
            .sum()
    }

    /// The ranks other than `me` whose region lies within `halo` of position `x` (the
    /// distance to the nearest image of the region's box), ascending: where a particle
    /// of `me` at `x` is a ghost. A non-finite position is nobody's ghost.
    pub fn within(&self, me: usize, x: DVec3, halo: f64) -> impl Iterator<Item = usize> + '_ {
        let (w, h2) = (self.wrap(x), halo * halo);
        let ranks = if w.is_finite() { self.ranks() } else { 0 };
        (0..ranks).filter(move |&q| q != me && self.distance_squared_wrapped(w, q) <= h2)
    }

    /// The ghost copies of `xs` with halo `halo`: per particle, the regions other than
    /// its own within `halo` of it (what the ranks forward each step, summed).
    pub fn ghost_copies(&self, xs: &[DVec3], halo: f64) -> usize {
        xs.iter()
            .map(|&x| self.within(self.owner(x), x, halo).count())
            .sum()
    }

    /// In words: "slabs along x", "4 boxes by recursive bisection (cuts along x, y)".
    pub fn describe(&self) -> String {
        if let Some(a) = self.slab_axis {
            return format!("in slabs along {}", ["x", "y", "z"][a]);
        }
        let mut axes: Vec<usize> = self.cuts.iter().map(|c| c.axis).collect();
        axes.sort_unstable();
        axes.dedup();
        let names: Vec<&str> = axes.iter().map(|&a| ["x", "y", "z"][a]).collect();
        format!(
            "in {} boxes by recursive bisection (cuts along {})",
            self.ranks(),
            names.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn on_z(z: f64) -> DVec3 {
        DVec3::new(100.0, -3.0, z)
    }

    #[test]
    fn slabs_own_by_their_cuts() {
        let s = Regions::slabs(1, vec![-1.0, 2.0], [None; 3]);
        let at = |y| s.owner(DVec3::new(100.0, y, -7.0));
        assert_eq!(at(-5.0), 0);
        assert_eq!(at(-1.0), 1, "a cut belongs to the slab above it");
        assert_eq!(at(1.999), 1);
        assert_eq!(at(2.0), 2);
        assert_eq!(at(1e9), 2);
        assert_eq!(at(f64::NAN), 0);
        assert_eq!(s.ranks(), 3);
        assert_eq!(s.slab_axis(), Some(1));
        assert_eq!(Regions::new(0, 1).owner(DVec3::splat(3.0)), 0);
        // Five slabs: the tree's depth-first walk finds every one.
        let five = Regions::slabs(0, vec![1.0, 2.0, 3.0, 4.0], [None; 3]);
        for (x, r) in [(0.5, 0), (1.5, 1), (2.5, 2), (3.5, 3), (4.5, 4), (4.0, 4)] {
            assert_eq!(five.owner(DVec3::new(x, 0.0, 0.0)), r, "{x}");
        }
    }

    #[test]
    fn periodic_slabs_own_wrapped_coordinates() {
        // A box [0, 3) along z cut at 1 and 2; positions are not wrapped.
        let xs: Vec<DVec3> = [0.5, 1.5, 2.5, 3.5, 4.5, 5.5].map(on_z).to_vec();
        let period = [None, None, Some(3.0)];
        let s = Regions::balanced(Shape::Slabs(2), 3, &xs, period, 0.1);
        let at = |z| s.owner(on_z(z));
        assert_eq!(at(0.2), 0);
        assert_eq!(at(3.2), 0, "one box up is the same place");
        assert_eq!(at(-0.2), 2, "just below 0 is the top of the box");
        assert_eq!(at(-1.5), 1);
        assert_eq!(at(2.999), 2);
        assert_eq!(at(f64::NAN), 0);
        assert_eq!((s.bounds(0).0.z, s.bounds(0).1.z), (0.0, 1.0));
        assert_eq!((s.bounds(2).0.z, s.bounds(2).1.z), (2.0, 3.0));
        assert_eq!(s.wrap(on_z(-1e-18)).z, 0.0, "rounding up to P folds to 0");
        let open = Regions::balanced(Shape::Slabs(2), 3, &xs[..3], [None; 3], 0.1);
        assert_eq!(open.bounds(0).0.z, f64::NEG_INFINITY);
        assert_eq!(open.owner(on_z(-0.2)), 0);
    }

    #[test]
    fn balanced_regions_share_the_particles_equally_whatever_the_order() {
        // 10 coordinates in scrambled order over 3 ranks: shares of 3, 3, 4.
        let coords = [9.0, 0.0, 5.0, 1.0, 8.0, 2.0, 7.0, 3.0, 6.0, 4.0];
        let xs: Vec<DVec3> = coords.map(on_z).to_vec();
        let s = Regions::balanced(Shape::Slabs(2), 3, &xs, [None; 3], 0.1);
        let mut counts = [0u64; 3];
        for x in &xs {
            counts[s.owner(*x)] += 1;
        }
        assert_eq!(counts, [3, 3, 4]);
        assert_eq!(s.owner(on_z(2.4)), 0);
        assert_eq!(s.owner(on_z(2.6)), 1, "cut halfway between 2 and 3");
        let mut rev = xs.clone();
        rev.reverse();
        assert_eq!(
            Regions::balanced(Shape::Slabs(2), 3, &rev, [None; 3], 0.1),
            s
        );
        // Fewer particles than ranks, or none: every position still has one owner.
        for n in [0, 1] {
            let few = Regions::balanced(Shape::Bisection, 4, &xs[..n], [None; 3], 0.1);
            assert_eq!(few.ranks(), 4);
            assert!(few.owner(on_z(3.0)) < 4);
        }
        // Bisection over a 16 × 8 × 2 lattice on 8 ranks: 16 particles each, any order.
        let mut lattice: Vec<DVec3> = (0..256)
            .map(|k| DVec3::new((k % 16) as f64, (k / 16 % 8) as f64, (k / 128) as f64))
            .collect();
        let rcb = Regions::balanced(Shape::Bisection, 8, &lattice, [None; 3], 0.5);
        lattice.reverse();
        lattice.swap(3, 100);
        assert_eq!(
            Regions::balanced(Shape::Bisection, 8, &lattice, [None; 3], 0.5),
            rcb
        );
        let mut counts = [0; 8];
        for x in &lattice {
            counts[rcb.owner(*x)] += 1;
        }
        assert_eq!(counts, [32; 8]);
        assert_eq!(rcb.slab_axis(), None);
        assert!(rcb.describe().contains("8 boxes"), "{}", rcb.describe());
    }

    /// Bisection cuts a compact cloud into boxes with fewer ghost copies than the slabs
    /// of the same cloud, and `Auto` keeps them; an elongated cloud stays in slabs; on 2
    /// ranks the two are the same.
    #[test]
    fn auto_keeps_the_shape_with_fewer_ghosts() {
        let cube: Vec<DVec3> = (0..4096)
            .map(|k| DVec3::new((k % 16) as f64, (k / 16 % 16) as f64, (k / 256) as f64))
            .collect();
        let h = 1.5;
        let slabs = Regions::balanced(Shape::Slabs(0), 8, &cube, [None; 3], h);
        let rcb = Regions::balanced(Shape::Bisection, 8, &cube, [None; 3], h);
        let (gs, gr) = (slabs.ghost_copies(&cube, h), rcb.ghost_copies(&cube, h));
        // Slabs 2 wide: every particle is within 1.5 of a neighbouring slab, most of
        // both (the end slabs have one neighbour).
        assert!(gs > 4096 + 2048, "{gs}");
        assert!(gr < gs * 3 / 4, "{gr} {gs}");
        assert_eq!(Regions::balanced(Shape::Auto, 8, &cube, [None; 3], h), rcb);
        let rod: Vec<DVec3> = (0..4096)
            .map(|k| DVec3::new((k % 512) as f64, (k / 512 % 2) as f64, (k / 1024) as f64))
            .collect();
        let auto = Regions::balanced(Shape::Auto, 8, &rod, [None; 3], h);
        assert_eq!(auto.slab_axis(), Some(0), "{}", auto.describe());
        assert_eq!(
            Regions::balanced(Shape::Auto, 2, &cube, [None; 3], h),
            Regions::balanced(Shape::Slabs(0), 2, &cube, [None; 3], h)
        );
    }

    #[test]
    fn distances_and_gaps_take_the_nearest_image() {
        // A periodic box 4 long in x, open in y and z: two slabs [0, 1) and [1, 4).
        let s = Regions::slabs(0, vec![1.0], [Some(4.0), None, None]);
        assert_eq!(s.distance_squared(DVec3::new(3.5, 0.0, 0.0), 0), 0.25);
        assert_eq!(s.distance_squared(DVec3::new(-0.5, 7.0, 0.0), 0), 0.25);
        assert_eq!(s.distance_squared(DVec3::new(2.0, 0.0, 0.0), 0), 1.0);
        assert_eq!(s.gap_squared(0, 1), 0.0);
        // Boxes by bisection in an open plane: diagonal neighbours have a corner gap.
        let xs: Vec<DVec3> = (0..16)
            .map(|k| DVec3::new((k % 4) as f64, (k / 4) as f64, 0.0))
            .collect();
        let r = Regions::balanced(Shape::Bisection, 4, &xs, [None; 3], 0.5);
        for q in 0..4 {
            for p in 0..4 {
                assert_eq!(r.gap_squared(q, p), r.gap_squared(p, q));
                assert_eq!(r.gap_squared(q, p), 0.0, "quadrants touch at the centre");
            }
        }
        assert_eq!(
            r.distance_squared(DVec3::new(0.0, 0.0, 0.0), r.owner(DVec3::splat(3.0))),
            2.0 * 1.5 * 1.5
        );
    }
}
