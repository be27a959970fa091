//! Parallel iteration that pays for threads only when there is enough work.
//!
//! Every parallel section runs through [`section`]: after it, one worker per core beyond
//! the calling thread spins for a short *block time* (as OpenMP runtimes do, e.g.
//! `KMP_BLOCKTIME`) instead of going to sleep at once, until the next section starts.
//! A step has several short sections; a core that sleeps between them is halted, and on a
//! shared virtual machine the host then lends it to someone else and hands it back late
//! (steal time), which stalls the next section. `SCG_BLOCKTIME_US` sets the block time in
//! µs (default 1000; 0 = sleep at once).

use bevy_ecs::query::{
    ArchetypeFilter, ArchetypeQueryData, ContiguousQueryData, IterQueryData, QueryData, QueryItem,
};
use bevy_ecs::system::Query;

static SECTION: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
static BLOCK_TIME_US: std::sync::OnceLock<u64> = std::sync::OnceLock::new();

fn block_time() -> std::time::Duration {
    let us = *BLOCK_TIME_US.get_or_init(|| {
        std::env::var("SCG_BLOCKTIME_US")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(1000)
    });
    std::time::Duration::from_micros(us)
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

/// Default of [`parallel_min`]. A parallel section costs some 10 µs on this 2-core VM
/// (waking and joining the workers); the per-particle passes (drag, integration, walls)
/// take a few ns per particle, so below about 2·10^4 particles one thread is faster: the
/// dilute contact benchmark at 10^4 particles ran at 12–14 ns per particle-step on two
/// threads with a threshold of 2048 and at 7–10 ns with this one.
pub const PARALLEL_THRESHOLD: usize = 16384;

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

/// `f` on each contiguous table chunk of `q` (one tight loop per chunk), on every core in
/// several batches per thread (they balance the load when a core is briefly busy) when
/// the query is large. Returns false, having run nothing, when some component is not in
/// table storage: the caller then iterates per entity.
pub fn for_each_chunk_mut<'a, 's, D, F>(
    q: &'a mut Query<'_, 's, D, F>,
    f: impl Fn(D::Contiguous<'a, 's>) + Send + Sync + Clone,
) -> bool
where
    D: ContiguousQueryData,
    D::ReadOnly: ArchetypeQueryData,
    F: ArchetypeFilter,
{
    if q.iter().len() < parallel_min() {
        q.contiguous_iter_mut().map(|it| it.for_each(f)).is_ok()
    } else {
        section(|| {
            q.contiguous_par_iter_mut()
                .map(|it| {
                    it.batching_strategy(
                        bevy_ecs::batching::BatchingStrategy::new().batches_per_thread(4),
                    )
                    .for_each(f)
                })
                .is_ok()
        })
    }
}

/// Elements per task of the slice helpers below.
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
    let pool = bevy_tasks::ComputeTaskPool::get_or_init(bevy_tasks::TaskPool::default);
    section(|| {
        bevy_tasks::ParallelSlice::par_chunk_map(&&a[..n], pool, SLICE_CHUNK, |i, chunk| {
            max(chunk, &b[i * SLICE_CHUNK..])
        })
    })
    .into_iter()
    .fold(0.0_f64, f64::max)
}

/// `f(chunk_k, &mut out[k])` for the chunks of `chunk` elements of `items`, with one
/// output slot per chunk (`out.len()` = number of chunks), on all cores when there are
/// several chunks. Consecutive chunks are grouped into a few tasks per thread, so the
/// task count stays small whatever the length; each chunk's result does not depend on the
/// grouping.
pub fn par_chunks_with<A: Send, B: Send>(
    items: &mut [A],
    chunk: usize,
    out: &mut [B],
    f: impl Fn(&mut [A], &mut B) + Send + Sync,
) {
    let chunk = chunk.max(1);
    assert_eq!(out.len(), items.len().div_ceil(chunk));
    let pool = bevy_tasks::ComputeTaskPool::get_or_init(bevy_tasks::TaskPool::default);
    let tasks = (pool.thread_num() * 4).max(1);
    if out.len() < 2 || pool.thread_num() < 2 {
        for (c, o) in items.chunks_mut(chunk).zip(out.iter_mut()) {
            f(c, o);
        }
        return;
    }
    let per_task = out.len().div_ceil(tasks);
    let f = &f;
    section(|| {
        pool.scope(|s| {
            for (cs, os) in items
                .chunks_mut(chunk * per_task)
                .zip(out.chunks_mut(per_task))
            {
                s.spawn(async move {
                    for (c, o) in cs.chunks_mut(chunk).zip(os.iter_mut()) {
                        f(c, o);
                    }
                });
            }
        })
    });
}
