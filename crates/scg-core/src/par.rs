//! Parallel iteration that pays for threads only when there is enough work.

use bevy_ecs::query::{ArchetypeFilter, ArchetypeQueryData, IterQueryData, QueryData, QueryItem};
use bevy_ecs::system::Query;

/// Below this many entities a system iterates on one thread: starting tasks costs more
/// than the work (a few µs per system per step, which dominates single-particle scenes).
pub const PARALLEL_THRESHOLD: usize = 2048;

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
    if q.iter().len() < PARALLEL_THRESHOLD {
        q.iter_mut().for_each(f);
    } else {
        q.par_iter_mut().for_each(f);
    }
}
