//! The particle table: every particle lives in one bevy storage table, and the systems
//! read and write its columns in place.
//!
//! The invariant holds by construction: particles are spawned already coarse-grained, with
//! every component the scene's layout needs, in one bundle ([`crate::spawn`]), and nothing
//! adds or removes a particle component afterwards. [`columns`] and [`columns_mut`] are
//! the one way the systems reach the columns; they check the invariant and stop the run
//! with a message naming it if something (a test, a library user) broke it. Table rows
//! are in spawn order, with a despawned particle's row taken by the last one; that order
//! depends only on the history of spawns and despawns, never on the thread count.

use bevy_ecs::change_detection::ContiguousMut;
use bevy_ecs::query::{ArchetypeFilter, ContiguousQueryData};
use bevy_ecs::system::Query;

const BROKEN: &str = "particles span more than one storage table: a component was added \
to or removed from some particles after spawning (scg keeps every particle in one table)";

/// The columns of the particle table read-only (`None` when there is no particle).
///
/// # Panics
/// When particles are in more than one table or a component is not in table storage.
pub fn columns<'a, 's, D, F>(
    q: &'a Query<'_, 's, D, F>,
) -> Option<<D::ReadOnly as ContiguousQueryData>::Contiguous<'a, 's>>
where
    D: bevy_ecs::query::QueryData,
    D::ReadOnly: ContiguousQueryData,
    F: ArchetypeFilter,
{
    let mut tables = q.contiguous_iter().expect(BROKEN);
    let first = tables.next();
    assert!(tables.next().is_none(), "{BROKEN}");
    first
}

/// The columns of the particle table (`None` when there is no particle).
///
/// # Panics
/// When particles are in more than one table or a component is not in table storage.
pub fn columns_mut<'a, 's, D, F>(q: &'a mut Query<'_, 's, D, F>) -> Option<D::Contiguous<'a, 's>>
where
    D: ContiguousQueryData,
    F: ArchetypeFilter,
{
    let mut tables = q.contiguous_iter_mut().expect(BROKEN);
    let first = tables.next();
    assert!(tables.next().is_none(), "{BROKEN}");
    first
}

/// The column of a mutable component as a plain slice, skipping the change ticks (nothing
/// filters on changes of particle components).
pub fn bypass<T>(c: ContiguousMut<'_, T>) -> &mut [T] {
    ContiguousMut::bypass_change_detection_split(c).0
}
