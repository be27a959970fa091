//! Parallel iteration that pays for threads only when there is enough work.
//!
//! The hot loops (table columns cut into pieces, contact slots, kicks, list builds) run
//! on the fork–join [`crate::team`]: the calling thread plus one worker per further core,
//! each taking mostly the same share of the work at every step, so that its data stays in
//! its core's caches. On two cores, work split among bevy's task pool (two threads plus
//! the calling thread) and handed out in arbitrary order ran the dense contact bed 1.3×
//! faster than one thread; on the team it runs 1.7–1.8× faster.
//!
//! Between jobs the workers spin for a short *block time* (as OpenMP runtimes do, e.g.
//! `KMP_BLOCKTIME`) instead of going to sleep at once: a step has several short jobs, and a
//! core that sleeps between them is halted, lent by the host to someone else and handed
//! back late (steal time). `SCG_BLOCKTIME_US` sets the block time in µs (default 1000;
//! 0 = sleep at once). The per-entity fallback ([`for_each_mut`], for components outside
//! table storage) still uses bevy's parallel iteration through [`section`], which keeps
//! the pool's threads warm the same way.

use bevy_ecs::query::{
    ArchetypeFilter, ArchetypeQueryData, ContiguousQueryData, IterQueryData, QueryData, QueryItem,
};
use bevy_ecs::system::Query;

static SECTION: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
static BLOCK_TIME_US: std::sync::OnceLock<u64> = std::sync::OnceLock::new();

pub(crate) fn block_time() -> std::time::Duration {
    let us = *BLOCK_TIME_US.get_or_init(|| {
        std::env::var("SCG_BLOCKTIME_US")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(1000)
    });
    std::time::Duration::from_micros(us)
}

/// Release the cores kept warm after the last section (a new section or team job is
/// starting).
pub(crate) fn end_block_time() {
    SECTION.fetch_add(1, std::sync::atomic::Ordering::AcqRel);
}

/// Run one parallel section `f`, then keep the cores warm for the next one (see the
/// module documentation). Results never depend on it: the spinning tasks touch no data.
pub fn section<R>(f: impl FnOnce() -> R) -> R {
    use std::sync::atomic::Ordering;
    let me = SECTION.fetch_add(1, Ordering::AcqRel) + 1;
    let out = f();
    let wait = block_time();
    let pool = bevy_tasks::ComputeTaskPool::get_or_init(bevy_tasks::TaskPool::default);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let spinners = pool.thread_num().min(cores);
    if !wait.is_zero() && spinners > 1 {
        for _ in 0..spinners {
            pool.spawn(async move {
                let start = std::time::Instant::now();
                while SECTION.load(Ordering::Acquire) == me && start.elapsed() < wait {
                    for _ in 0..64 {
                        std::hint::spin_loop();
                    }
                    // Let a thread with work (the caller's serial part) have the core.
                    std::thread::yield_now();
                }
            })
            .detach();
        }
    }
    out
}

/// Default of [`parallel_min`]. A team job starts in under a microsecond, but on a small
/// scene the second core gains nothing: its share is a few µs of work and the particle
/// data moves between the two cores' caches. On the dilute contact benchmark on two
/// threads (`scg bench dilute`, best of 3), 10^4 particles ran at 7.4 ns per
/// particle-step with a threshold of 16 384 and at 5.2 ns with this one; 10^3 particles
/// ran at 8.6–8.8 ns with any threshold down to 256.
pub const PARALLEL_THRESHOLD: usize = 4096;

static PARALLEL_MIN: std::sync::OnceLock<usize> = std::sync::OnceLock::new();

/// Below this many entities a per-entity system iterates on one thread. Default
/// [`PARALLEL_THRESHOLD`]; `SCG_PARALLEL_MIN` sets it (tests set it low so that small
/// scenes go through every parallel path). Results never depend on it.
pub fn parallel_min() -> usize {
    *PARALLEL_MIN.get_or_init(|| {
        std::env::var("SCG_PARALLEL_MIN")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(PARALLEL_THRESHOLD)
    })
}

/// `q.par_iter_mut().for_each(f)` for large queries, a plain loop for small ones.
/// Each entity is visited once either way; `f` must not depend on the visiting order.
#[inline]
pub fn for_each_mut<'a, 's, D, F>(
    q: &'a mut Query<'_, 's, D, F>,
    f: impl Fn(QueryItem<'a, 's, D>) + Send + Sync + Clone,
) where
    D: QueryData + IterQueryData,
    D::ReadOnly: ArchetypeQueryData,
    F: ArchetypeFilter,
{
    if q.iter().len() < parallel_min() {
        q.iter_mut().for_each(f);
    } else {
        section(|| q.par_iter_mut().for_each(f));
    }
}

/// Column slices that can be cut at a row: a slice, an optional slice, or a tuple of
/// those (all of one table, so of one length).
pub trait Split: Sized + Send {
    /// Rows (the shortest member; `usize::MAX` when there is no column).
    fn rows(&self) -> usize;
    /// Rows `..k` and `k..`.
    fn split_at(self, k: usize) -> (Self, Self);
}

impl<T: Send> Split for &mut [T] {
    fn rows(&self) -> usize {
        self.len()
    }
    fn split_at(self, k: usize) -> (Self, Self) {
        self.split_at_mut(k)
    }
}

impl<T: Sync> Split for &[T] {
    fn rows(&self) -> usize {
        self.len()
    }
    fn split_at(self, k: usize) -> (Self, Self) {
        <[T]>::split_at(self, k)
    }
}

impl<S: Split> Split for Option<S> {
    fn rows(&self) -> usize {
        self.as_ref().map_or(usize::MAX, S::rows)
    }
    fn split_at(self, k: usize) -> (Self, Self) {
        match self {
            Some(s) => {
                let (a, b) = s.split_at(k);
                (Some(a), Some(b))
            }
            None => (None, None),
        }
    }
}

impl Split for () {
    fn rows(&self) -> usize {
        usize::MAX
    }
    fn split_at(self, _: usize) -> (Self, Self) {
        ((), ())
    }
}

macro_rules! split_tuple {
    ($($t:ident $v:ident $a:ident $b:ident),+) => {
        impl<$($t: Split),+> Split for ($($t,)+) {
            fn rows(&self) -> usize {
                let ($($v,)+) = self;
                usize::MAX$(.min($v.rows()))+
            }
            fn split_at(self, k: usize) -> (Self, Self) {
                let ($($v,)+) = self;
                $(let ($a, $b) = $v.split_at(k);)+
                (($($a,)+), ($($b,)+))
            }
        }
    };
}
split_tuple!(A a a0 a1, B b b0 b1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1, D d d0 d1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1, D d d0 d1, E e e0 e1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1, D d d0 d1, E e e0 e1, F f f0 f1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1, D d d0 d1, E e e0 e1, F f f0 f1, G g g0 g1);
split_tuple!(A a a0 a1, B b b0 b1, C c c0 c1, D d d0 d1, E e e0 e1, F f f0 f1, G g g0 g1, H h h0 h1);

/// The column of a mutable component as a plain slice, skipping the change ticks (for
/// columns nothing filters on).
pub fn bypass<T>(c: bevy_ecs::change_detection::ContiguousMut<'_, T>) -> &mut [T] {
    bevy_ecs::change_detection::ContiguousMut::bypass_change_detection_split(c).0
}

/// Rows per piece when a table's columns are cut for the team.
const PIECE_ROWS: usize = 4096;

/// `body` on the column slices of each table of `q` (one tight loop per piece): `parts`
/// turns a table's columns into slices (on the calling thread), which are cut into pieces
/// of [`PIECE_ROWS`] rows run on the [`crate::team`] when the query is large. The pieces
/// depend on the row count only, and `body` must treat rows independently. Returns false,
/// having run nothing, when some component is not in table storage: the caller then
/// iterates per entity.
pub fn for_each_split<'a, 's, D, F, P>(
    q: &'a mut Query<'_, 's, D, F>,
    parts: impl Fn(D::Contiguous<'a, 's>) -> P,
    body: impl Fn(P) + Sync,
) -> bool
where
    D: ContiguousQueryData,
    D::ReadOnly: ArchetypeQueryData,
    F: ArchetypeFilter,
    P: Split,
{
    let parallel = q.iter().len() >= parallel_min();
    let Ok(tables) = q.contiguous_iter_mut() else {
        return false;
    };
    // Small pieces when the threshold is set low (tests), so that small scenes are cut too.
    let piece = PIECE_ROWS.min(parallel_min().div_ceil(2).max(64));
    for table in tables {
        let mut rest = parts(table);
        let rows = rest.rows();
        if !parallel || rows == usize::MAX || rows < 2 * piece {
            body(rest);
            continue;
        }
        let mut pieces = Vec::with_capacity(rows.div_ceil(piece));
        let mut left = rows;
        while left > piece {
            let (a, b) = rest.split_at(piece);
            pieces.push(Some(a));
            rest = b;
            left -= piece;
        }
        pieces.push(Some(rest));
        crate::team::for_each_item(&mut pieces, |_, p| {
            if let Some(p) = p.take() {
                body(p)
            }
        });
    }
    true
}

/// Elements per task of [`par_max_zip`].
const SLICE_CHUNK: usize = 8192;

/// The largest `f(&a[k], &b[k])` over k (0 for empty slices), on all cores when the
/// slices are long. The maximum does not depend on the chunking.
pub fn par_max_zip<A: Sync, B: Sync>(
    a: &[A],
    b: &[B],
    f: impl Fn(&A, &B) -> f64 + Send + Sync,
) -> f64 {
    let n = a.len().min(b.len());
    let max = |x: &[A], y: &[B]| {
        x.iter()
            .zip(y)
            .map(|(x, y)| f(x, y))
            .fold(0.0_f64, f64::max)
    };
    if n < 2 * SLICE_CHUNK {
        return max(&a[..n], &b[..n]);
    }
    let mut out = vec![0.0_f64; n.div_ceil(SLICE_CHUNK)];
    crate::team::for_each_item(&mut out, |c, m| {
        let (lo, hi) = (c * SLICE_CHUNK, ((c + 1) * SLICE_CHUNK).min(n));
        *m = max(&a[lo..hi], &b[lo..hi]);
    });
    out.into_iter().fold(0.0_f64, f64::max)
}
