//! Force slots: the pair list is cut into a few fixed *slots* (by pair count, never by
//! thread count); each slot computes its pairs' forces and sums them, in pair order, into
//! its own per-particle arrays, and the slots run in parallel on the team. The kick stage
//! ([`super::kicks`]) adds the slots' sums per particle in slot order, so the result is
//! bit-identical whatever the thread count.

use bevy_ecs::prelude::*;
use bytemuck::TransparentWrapper;
use glam::DVec3;

use super::ContactState;
use crate::components::*;
use crate::physics::contact::lanes::HertzMindlin;
use crate::physics::contact::pair::{Bodies, PairContact, PairParams, PairsMut, Rows};
use crate::physics::contact::tangential::HertzPair;
use crate::stages::table::columns;
use crate::state::{ContactResolution, SimClock, Tally};

/// Everything the pair kernel reads.
pub(super) struct Kernel<'a> {
    /// Per-particle inputs.
    pub bodies: Bodies<'a>,
    /// The pair law.
    pub par: PairParams,
    /// The pair law's constants for the four-lane kernel (`None`: not its law).
    pub lanes: Option<HertzMindlin>,
    /// Time step, s.
    pub dt: f64,
    /// Group of each particle (collision counts).
    pub group: &'a [u32],
    /// Rows of the particle table (the rows after are ghosts: their collisions are
    /// counted by the process that owns them).
    pub local: usize,
}

/// Pairs per accumulation slot (the slot count is fixed by the pair count).
const PAIRS_PER_SLOT: usize = 4096;
/// Most slots: four tasks per core on two cores. Each slot's arrays also cover the far
/// neighbours (j) of its pairs, so more slots mean more entries to clear and sum each step
/// (16 slots ran the 32 000-particle dense bed about 4 % slower).
const MAX_SLOTS: usize = 8;
/// Candidate pairs listed per block by the four-lane path.
const LIST_BLOCK: usize = 64;

/// One slot of the force accumulation: a fixed range of the pair list whose forces are
/// summed, in pair order, into per-particle arrays covering particles `base..base+len`.
/// Ghost rows (a decomposed run: rows from `local` on) are never covered: their owner
/// computes the pair too and kicks them, so only the local side of a local–ghost pair is
/// summed (else every slot holding one would stretch to the ghost rows at the end of the
/// table, and every particle be covered by every slot).
/// Invariant between steps: the arrays are zero except where the last step wrote
/// (`touched`, or anywhere when `dirty`) and the kicks did not zero what they read
/// (the rows below `consumed`).
#[derive(Debug, Default)]
pub(super) struct Slot {
    /// Pair indices of this slot.
    pub(super) pairs: std::ops::Range<usize>,
    /// First particle index covered.
    pub(super) base: usize,
    /// The first ghost row: the pairs' j from here on are not summed.
    local: usize,
    /// Summed force (N) and torque (N·m) per covered particle.
    pub(super) sums: Vec<[DVec3; 2]>,
    /// Covered particles written this step (sparse steps), global indices.
    pub(super) touched: Vec<u32>,
    /// `touched` membership, local indices.
    marked: Vec<bool>,
    /// Written anywhere (a dense step): clear everything before the next step, but for
    /// the rows the kicks zeroed (`consumed`).
    pub(super) dirty: bool,
    /// The rows below this one were zeroed by the kicks that read them (0: none).
    pub(super) consumed: usize,
    /// Contacts started this step, per group.
    pub(super) collisions: Vec<u64>,
    /// Pairs in contact this step.
    pub(super) active: usize,
    /// Shortest duration of the contacts started this step, s (at their approach speed).
    shortest: f64,
    /// Scratch of the four-lane path: this step's touching pairs, in pair order.
    hits: Vec<u32>,
}

impl Slot {
    /// True when particle `k` is covered.
    #[inline]
    pub(super) fn covers(&self, k: usize) -> bool {
        k >= self.base && k - self.base < self.sums.len()
    }

    /// Zero what the last step wrote.
    pub(super) fn clear(&mut self, groups: usize) {
        if self.dirty {
            let from = self.consumed.saturating_sub(self.base).min(self.sums.len());
            self.sums[from..].fill([DVec3::ZERO; 2]);
            self.dirty = false;
        } else {
            for &k in &self.touched {
                let l = k as usize - self.base;
                self.sums[l] = [DVec3::ZERO; 2];
                self.marked[l] = false;
            }
        }
        self.consumed = 0;
        self.touched.clear();
        self.collisions.clear();
        self.collisions.resize(groups, 0);
        self.active = 0;
        self.shortest = f64::INFINITY;
    }

    /// Compute the slot's pairs and sum them; `sparse` records the particles written.
    ///
    /// On x86-64 CPUs with AVX2, and for the Hertz–Mindlin law, the touching pairs are
    /// computed four at a time ([`crate::physics::contact::lanes`]), which gives the
    /// scalar kernel's bits; other CPUs and laws run the scalar kernel.
    pub(super) fn run(&mut self, pairs: &mut PairsMut, k: &Kernel, groups: usize, sparse: bool) {
        #[cfg(target_arch = "x86_64")]
        if let Some(law) = k.lanes
            && crate::exec::lanes()
        {
            // SAFETY: the CPU supports AVX2 (`exec::lanes` checked it).
            unsafe { self.run_avx2(pairs, k, law, groups, sparse) };
            return;
        }
        self.run_portable(pairs, k, groups, sparse);
    }

    /// The four-lane path: first the touching pairs are listed (the pairs that stopped
    /// touching lose their history), then they are computed four at a time and summed
    /// in pair order, as the scalar path sums them.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn run_avx2(
        &mut self,
        pairs: &mut PairsMut,
        k: &Kernel,
        law: HertzMindlin,
        groups: usize,
        sparse: bool,
    ) {
        use crate::physics::contact::lanes::hertz_mindlin_x4;
        self.clear(groups);
        // The kernel reads the pair arrays unchecked at the listed pairs (below `n`).
        let n = pairs.len();
        assert!(
            pairs.touching.len() == n
                && pairs.state.len() == n
                && (pairs.shift.is_empty() || pairs.shift.len() == n),
            "pair arrays of unequal lengths"
        );
        let b = &k.bodies;
        let mut hits = std::mem::take(&mut self.hits);
        hits.resize(LIST_BLOCK + 4, 0);
        let rolling = k.par.tangential.rolling;
        // Without rolling resistance or bookkeeping (a dense step), lanes whose contact
        // went on add their rows to the sums whole.
        let whole = !sparse && rolling <= 0.0;
        // Listed and computed a block at a time, so that the particles the listing read
        // are still in the first-level cache when their pairs are computed; the touching
        // pairs carried over to the next block (fewer than four) keep the pair order.
        let (mut pending, mut start) = (0, 0);
        while start < n {
            let end = (start + LIST_BLOCK).min(n);
            pending = list_touching(pairs, start..end, b, &mut hits, pending);
            let full = if end == n { pending } else { pending / 4 * 4 };
            for chunk in hits[..full].chunks(4) {
                let live = chunk.len();
                let idx: [u32; 4] = std::array::from_fn(|l| chunk[l.min(live - 1)]);
                // SAFETY (`was`, `ij` below): the listed pairs are below `n`, the length of
                // every pair array (asserted above).
                let was = idx.map(|a| unsafe { *pairs.touching.get_unchecked(a as usize) });
                // SAFETY: AVX2 is enabled here; the listed pairs are below `n`, the length of
                // every pair array (asserted above), and their particle indices were checked
                // against the kernel's arrays as they were listed.
                let out = unsafe { hertz_mindlin_x4(pairs, idx, live, b, &k.par, law, k.dt) };
                for l in 0..live {
                    let at = idx[l] as usize;
                    let [i, j] = unsafe { *pairs.ij.get_unchecked(at) };
                    if whole && was[l] {
                        self.add_whole(i as usize, j as usize, &out, l);
                        self.active += 1;
                        continue;
                    }
                    let hertz = pairs.state[at].hertz;
                    let mut c = PairContact {
                        i,
                        j,
                        started: !was[l],
                        approach: out.approach(l),
                        force: out.force(l),
                        torque_i: out.torque_i(l),
                        torque_j: out.torque_j(l),
                    };
                    c.add_rolling(rolling, out.normal_force(l), hertz.r_eff, b);
                    self.credit(&c, &hertz, k, sparse);
                }
            }
            hits.copy_within(full..pending, 0);
            pending -= full;
            start = end;
        }
        self.hits = hits;
        self.dirty = !sparse;
    }

    /// [`Slot::credit`] for lane `l` of `out`, the pair (i, j) whose contact went on,
    /// without rolling resistance or bookkeeping: its rows added to the sums whole, the
    /// same additions component by component (the caller counts it in `active`).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    fn add_whole(
        &mut self,
        i: usize,
        j: usize,
        out: &crate::physics::contact::lanes::LaneOut,
        l: usize,
    ) {
        use core::arch::x86_64::*;
        for (k, row) in [(i, out.on_i(l)), (j, out.on_j(l))] {
            if k >= self.local {
                continue;
            }
            let s: &mut [DVec3; 2] = &mut self.sums[k - self.base];
            let s = s as *mut [DVec3; 2] as *mut f64;
            // SAFETY: `s` addresses six f64 (two `repr(C)` DVec3) and `row` six f64.
            unsafe {
                let a = _mm256_add_pd(_mm256_loadu_pd(s), _mm256_loadu_pd(row.as_ptr()));
                let b = _mm_add_pd(_mm_loadu_pd(s.add(4)), _mm_loadu_pd(row.as_ptr().add(4)));
                _mm256_storeu_pd(s, a);
                _mm_storeu_pd(s.add(4), b);
            }
        }
    }

    /// The scalar path, pair by pair.
    fn run_portable(&mut self, pairs: &mut PairsMut, k: &Kernel, groups: usize, sparse: bool) {
        self.clear(groups);
        for at in 0..pairs.len() {
            let Some(c) = pairs.kernel(at, &k.bodies, &k.par, k.dt) else {
                continue;
            };
            let hertz = pairs.state[at].hertz;
            self.credit(&c, &hertz, k, sparse);
        }
        self.dirty = !sparse;
    }

    /// Add one touching pair's force and torques to its particles' sums and count it.
    #[inline(always)]
    fn credit(&mut self, c: &PairContact, hertz: &HertzPair, k: &Kernel, sparse: bool) {
        let (i, j) = (c.i as usize, c.j as usize);
        let li = i - self.base;
        let si = &mut self.sums[li];
        si[0] += c.force;
        si[1] += c.torque_i;
        if j < self.local {
            let sj = &mut self.sums[j - self.base];
            sj[0] -= c.force;
            sj[1] += c.torque_j;
        }
        self.active += 1;
        if sparse {
            for r in [i, j] {
                let l = r - self.base;
                if r < self.local && !self.marked[l] {
                    self.marked[l] = true;
                    self.touched.push(r as u32);
                }
            }
        }
        if c.started {
            let tc = k
                .par
                .law
                .contact_time(hertz.m_eff, hertz.r_eff, k.par.e_eff, c.approach);
            self.shortest = self.shortest.min(tc);
            for r in [i, j] {
                if r < k.local
                    && let Some(n) = self.collisions.get_mut(k.group[r] as usize)
                {
                    *n += 1;
                }
            }
        }
    }
}

/// For each 4-bit lane mask, its set lanes in ascending order (then zeros).
#[cfg(target_arch = "x86_64")]
const COMPACT: [[u32; 4]; 16] = {
    let mut t = [[0u32; 4]; 16];
    let mut mask = 0;
    while mask < 16 {
        let (mut l, mut k) = (0, 0);
        while l < 4 {
            if mask >> l & 1 != 0 {
                t[mask][k] = l as u32;
                k += 1;
            }
            l += 1;
        }
        mask += 1;
    }
    t
};

/// Set lanes of each 4-bit lane mask.
#[cfg(target_arch = "x86_64")]
const COUNT: [u8; 16] = [0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4];

/// The first pass of the four-lane path: list the pairs `range` of `pairs` that touch
/// in `hits` from `hits[m]` on (in pair order; returns the new count) and clear the pairs
/// that stopped touching, four pairs at a time with the scalar kernel's test,
/// [`crate::physics::contact::pair::within_reach`]. `hits` must have room for
/// `m + range.len()`.
///
/// Every pair listed has both particle indices inside `b`'s arrays (checked here, four
/// pairs at a time; a pair outside them panics), which is what the four-lane kernel
/// needs of the pairs it is given.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn list_touching(
    pairs: &mut PairsMut,
    range: std::ops::Range<usize>,
    b: &Bodies,
    hits: &mut [u32],
    mut m: usize,
) -> usize {
    use crate::physics::contact::pair::{PairState, within_reach};
    use crate::simd::{F4, V4};
    use core::arch::x86_64::*;
    let n = range.end;
    let n4 = range.start + range.len() / 4 * 4;
    let periodic = !pairs.shift.is_empty();
    // The pairs' states, for prefetching only (a hint that never faults).
    let state: *const PairState = pairs.state.as_ptr();
    // A pair that stopped touching loses its history.
    let separated = |pairs: &mut PairsMut, at: usize, touch: bool| {
        if pairs.touching[at] && !touch {
            pairs.touching[at] = false;
            pairs.state[at].history = DVec3::ZERO;
        }
    };
    // Rows every array of `b` has: particle indices below it are read unchecked.
    let rows = (b
        .pos
        .len()
        .min(b.vel.len())
        .min(b.omega.len())
        .min(b.radius.len()))
    .min(u32::MAX as usize) as u32;
    let sign = _mm256_set1_epi32(i32::MIN);
    let limit = _mm256_set1_epi32((rows ^ 0x8000_0000) as i32);
    for base in (range.start..n4).step_by(4) {
        let ij: &[[u32; 2]; 4] = pairs.ij[base..base + 4].try_into().expect("four");
        // The eight indices below `rows` (unsigned, compared as signed with the sign bit
        // flipped), or a panic.
        // SAFETY: `ij` is four [u32; 2], 32 bytes.
        let inside = unsafe {
            let raw = _mm256_loadu_si256(ij.as_ptr() as *const __m256i);
            _mm256_movemask_epi8(_mm256_cmpgt_epi32(limit, _mm256_xor_si256(raw, sign)))
        };
        assert!(inside == -1, "a pair indexes past the particle arrays");
        let (i, j) = (ij.map(|p| p[0] as usize), ij.map(|p| p[1] as usize));
        // SAFETY (here and below): every index of `i` and `j` is below `rows`, checked
        // just above.
        let row = |k: usize| unsafe { b.pos.ptr(k) };
        let radius = |k: usize| unsafe { *b.radius.get_unchecked(k) };
        // SAFETY: each pointer addresses a DVec3 (three f64); four shifts are 12 f64.
        let mut d = unsafe { V4::gather(j.map(row)) - V4::gather(i.map(row)) };
        if periodic {
            let s = pairs.shift[base..base + 4].as_ptr() as *const f64;
            d = d - unsafe { V4::load_aos(s) };
        }
        let dist2 = d.dot(d);
        let reach = F4::from_array(i.map(radius)) + F4::from_array(j.map(radius));
        // `within_reach` on four lanes: !(|d|² ≥ reach²) and |d|² ≠ 0, NaN counting in.
        let touch = (dist2.not_ge(reach * reach).and(dist2.ne(F4::zero()))).bits() as usize;
        // The touching lanes' pair indices, in order, at hits[m..]: four written, the
        // touching ones counted.
        let at = hits[m..m + 4].as_mut_ptr();
        // SAFETY: `at` addresses four u32 (the slice just taken).
        unsafe {
            let lanes = _mm_loadu_si128(COMPACT[touch].as_ptr() as *const __m128i);
            let ids = _mm_add_epi32(lanes, _mm_set1_epi32(base as i32));
            _mm_storeu_si128(at as *mut __m128i, ids);
        }
        m += COUNT[touch] as usize;
        // The kernel reads the touching ones' states within the block: load the four
        // states' lines now (each state's first byte and the last one's last byte reach
        // every line they span).
        for l in 0..4 {
            _mm_prefetch::<_MM_HINT_T0>(state.wrapping_add(base + l) as *const i8);
        }
        let last = state.wrapping_add(base + 4) as *const i8;
        _mm_prefetch::<_MM_HINT_T0>(last.wrapping_sub(1));
        // The pairs that stopped touching (rare: a test of all four first).
        let was: [bool; 4] = pairs.touching[base..base + 4].try_into().expect("four");
        let was = was
            .iter()
            .enumerate()
            .fold(0, |a, (l, &w)| a | usize::from(w) << l);
        let gone = was & !touch;
        if gone != 0 {
            for l in 0..4 {
                separated(pairs, base + l, gone & (1 << l) == 0);
            }
        }
    }
    for at in n4..n {
        let [i, j] = pairs.ij[at];
        assert!(i.max(j) < rows, "a pair indexes past the particle arrays");
        let (i, j) = (i as usize, j as usize);
        let mut d = b.pos[j] - b.pos[i];
        if periodic {
            d -= pairs.shift[at];
        }
        let dist2 = d.length_squared();
        let reach = b.radius[i] + b.radius[j];
        let touch = within_reach(dist2, reach);
        hits[m] = at as u32;
        m += usize::from(touch);
        separated(pairs, at, touch);
    }
    m
}

/// Cut `pairs` (sorted by i, with i < j, i below `local`) into slots: as many as the
/// pair count gives (at most [`MAX_SLOTS`]), halved while their arrays together would
/// cover more than max(4·n, 2²⁰) particles (particles stored far from their neighbours in
/// index order). A slot covers its pairs' rows below `local` (the table's; the ghost rows
/// after them are not summed, [`Slot`]).
pub(super) fn layout_slots(pairs: &[[u32; 2]], n: usize, local: usize) -> Vec<Slot> {
    if pairs.is_empty() {
        return Vec::new();
    }
    let budget = (4 * n).max(1 << 20);
    let mut count = pairs.len().div_ceil(PAIRS_PER_SLOT).clamp(1, MAX_SLOTS);
    loop {
        let per = pairs.len().div_ceil(count);
        let spans: Vec<(std::ops::Range<usize>, usize, usize)> = (0..pairs.len())
            .step_by(per)
            .map(|p0| {
                let p1 = (p0 + per).min(pairs.len());
                let base = pairs[p0][0] as usize;
                let top = pairs[p0..p1]
                    .iter()
                    .map(|&[i, j]| if (j as usize) < local { j } else { i } as usize)
                    .max()
                    .unwrap_or(base);
                (p0..p1, base, top - base + 1)
            })
            .collect();
        let covered: usize = spans.iter().map(|s| s.2).sum();
        if count == 1 || covered <= budget {
            return spans
                .into_iter()
                .map(|(range, base, len)| Slot {
                    pairs: range,
                    base,
                    local,
                    sums: vec![[DVec3::ZERO; 2]; len],
                    marked: vec![false; len],
                    ..Default::default()
                })
                .collect();
        }
        count /= 2;
    }
}

/// The summed contact force and torque on particle `k`: the covering slots' sums added
/// in slot order (the same order on every path).
#[inline]
pub(super) fn slot_sum(slots: &[Slot], k: usize) -> (DVec3, DVec3) {
    let (mut f, mut t) = (DVec3::ZERO, DVec3::ZERO);
    for s in slots {
        if s.covers(k) {
            let [sf, st] = s.sums[k - s.base];
            f += sf;
            t += st;
        }
    }
    (f, t)
}

/// Compute every pair's force (parallel), then sum them per particle (fixed order) for
/// the particles in contact. The sums are applied by [`super::kicks::apply_contact_kicks`].
pub fn particle_contact_forces(
    mut state: ResMut<ContactState>,
    clock: Res<SimClock>,
    mut tally: ResMut<Tally>,
    resolution: Res<ContactResolution>,
    q: Query<(&Position, &Velocity, &AngularVelocity)>,
) {
    let st = &mut *state;
    let dt = clock.dt;
    let n = st.local;
    // The rows the neighbour stage checked this step (nothing spawns or despawns between
    // the two stages).
    let (xs, vs, ws) = columns(&q).unwrap_or_default();
    assert_eq!(
        xs.len(),
        n,
        "the particle table changed after the neighbour stage"
    );
    let (xs, vs, ws) = (
        Position::peel_slice(xs),
        Velocity::peel_slice(vs),
        AngularVelocity::peel_slice(ws),
    );
    // Ghost rows (a decomposed run) after the table's: the states of this step, read in
    // place after the table's.
    let g = &st.ghosts;
    assert_eq!(
        st.ids[n..],
        g.ids[..],
        "the ghosts changed after the neighbour stage"
    );
    let bodies = Bodies {
        pos: Rows::new(xs, &g.pos),
        vel: Rows::new(vs, &g.vel),
        omega: Rows::new(ws, &g.omega),
        radius: &st.radius,
    };
    // Few contacts last step: record the particles written, so the kick and the next
    // clear visit only those. Many: sum and clear every particle (no bookkeeping).
    st.sparse = st.active * 8 <= n;
    let rows = st.ids.len();
    if st.marked.len() != rows {
        st.marked.clear();
        st.marked.resize(rows, false);
    }
    let sparse = st.sparse;
    let groups = tally.collisions.len();
    let group = &st.group;
    let mut work: Vec<(&mut Slot, PairsMut)> = Vec::with_capacity(st.slots.len());
    let mut rest = st.pairs.view(&st.list.pairs, 0..st.list.pairs.len());
    let mut at = 0;
    for slot in st.slots.iter_mut() {
        let (mine, tail) = rest.split_at(slot.pairs.end - at);
        at = slot.pairs.end;
        rest = tail;
        work.push((slot, mine));
    }
    let kernel = Kernel {
        bodies,
        par: st.params,
        lanes: HertzMindlin::of(&st.params),
        dt,
        group,
        local: n,
    };
    crate::exec::team::for_each_item(&mut work, |_, (slot, pairs)| {
        slot.run(pairs, &kernel, groups, sparse);
    });
    let mut active = 0;
    for slot in &st.slots {
        active += slot.active;
        resolution.note_pair(slot.shortest);
        for (t, c) in tally.collisions.iter_mut().zip(&slot.collisions) {
            *t += c;
        }
    }
    st.active = active;
}

#[cfg(test)]
mod tests;
