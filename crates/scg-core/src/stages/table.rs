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

/// Reorder the particle table: row i takes the particle of row `perm[i]` (a permutation
/// of the rows). Every component column of the particle layout is permuted alike (the
/// rows keep their entities; nothing holds a particle's entity across steps), but for
/// the columns whose type `moved` refuses (a column nobody reads again before writing
/// it). Each particle's state is unchanged but for its row.
///
/// # Panics
/// When the particles carry a component the layout does not know (one added to the
/// particle layout without adding it to [`crate::spawn::visit_layout`]) or span several
/// storage tables: it stops before moving anything.
pub fn reorder_particles(
    world: &mut bevy_ecs::world::World,
    perm: &[u32],
    moved: impl Fn(std::any::TypeId) -> bool,
) {
    use crate::spawn::{LayoutComponent, LayoutVisitor, Role, visit_layout};
    // Every component of the particle layout, checked against the table's.
    struct Ids<'a>(
        &'a mut bevy_ecs::world::World,
        Vec<bevy_ecs::component::ComponentId>,
    );
    impl LayoutVisitor for Ids<'_> {
        fn visit<T: LayoutComponent>(&mut self, _: Role) {
            let id = self.0.register_component::<T>();
            self.1.push(id);
        }
    }
    let mut ids = Ids(world, Vec::new());
    visit_layout(&mut ids);
    let known = ids.1;
    let layouts = world
        .archetypes()
        .iter()
        .filter(|a| !a.is_empty() && a.contains(known[0]))
        .count();
    assert!(layouts <= 1, "{BROKEN} ({layouts} component layouts)");
    let unknown: Vec<String> = world
        .archetypes()
        .iter()
        .filter(|a| !a.is_empty() && a.contains(known[0]))
        .flat_map(|a| a.components().iter().copied())
        .filter(|c| !known.contains(c))
        .filter_map(|c| world.components().get_name(c).map(|n| n.to_string()))
        .collect();
    assert!(
        unknown.is_empty(),
        "reorder_particles does not know the particle components {unknown:?}"
    );
    struct Permute<'a, F> {
        world: &'a mut bevy_ecs::world::World,
        perm: &'a [u32],
        moved: F,
    }
    impl<F: Fn(std::any::TypeId) -> bool> LayoutVisitor for Permute<'_, F> {
        fn visit<T: LayoutComponent>(&mut self, _: Role) {
            if (self.moved)(std::any::TypeId::of::<T>()) {
                permute::<T>(self.world, self.perm);
            }
        }
    }
    visit_layout(&mut Permute { world, perm, moved });
}

/// Row i of the particles' `T` column takes the value of row `perm[i]` (no effect when
/// the particles have no `T`). Queries visit the one particle table in row order.
fn permute<T: bevy_ecs::component::Component<Mutability = bevy_ecs::component::Mutable> + Clone>(
    world: &mut bevy_ecs::world::World,
    perm: &[u32],
) {
    use bevy_ecs::change_detection::DetectChangesMut;
    use bevy_ecs::query::With;
    let mut q = world.query_filtered::<&mut T, With<crate::components::ParticleId>>();
    let old: Vec<T> = q.iter(world).cloned().collect();
    if old.len() != perm.len() {
        return;
    }
    for (i, mut x) in q.iter_mut(world).enumerate() {
        x.bypass_change_detection()
            .clone_from(&old[perm[i] as usize]);
    }
}
