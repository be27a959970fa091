//! The reordering of the particle table by mesh cell ([`sort_by_cell`]).

use bevy_ecs::prelude::*;

use super::{MeshFlowState, keeps_start};
use crate::components::{CellHint, FlowAtCentre, ParticleId};
use crate::stages::carrier::CarrierModifier;
use crate::stages::table::reorder_particles;
use crate::state::{Motion, SimClock};
use crate::step::{StepBuilder, StepSet, StepSystem};

/// Default steps between two reorderings of the particle table by mesh cell
/// ([`sort_by_cell`]; scene key `flow.sort_every`).
pub const SORT_EVERY: u64 = 100;

/// Add the reordering of the particle table by mesh cell (inlet/outlet stage, after the
/// feeders). Only for scenes without particle contacts: there every particle's step
/// reads only its own state, so the table order changes no result.
pub(crate) fn add_sort(b: &mut StepBuilder) {
    b.add(
        StepSet::InletOutlet,
        "mesh_flow",
        StepSystem::SortByCell,
        sort_by_cell,
    );
}

/// Reorder the particle table by mesh cell, then id, after the first step (when every
/// particle has been located) and every `sort_every` steps ([`MeshFlowSpec`](super::MeshFlowSpec), default
/// [`SORT_EVERY`]), as LAMMPS's `atom_modify
/// sort` does by bins. The cell records of consecutive particles are then neighbours in
/// memory, and a step reads the mesh almost in order instead of at random: on a
/// 10^6-cell mesh this more than doubles the speed of the integration, which is bound
/// by memory latency. Every component column of the particle table is permuted alike
/// (the rows keep their entities; nothing holds a particle's entity across steps), so
/// each particle's state is unchanged but for its row; and since no stage of a scene
/// without contacts depends on the row order, the results are bit-identical to an
/// unsorted run's (tested).
///
/// # Panics
/// When the particles carry a component the layout does not know
/// ([`reorder_particles`]): it stops before moving anything.
pub fn sort_by_cell(world: &mut World) {
    let step = world.resource::<SimClock>().step;
    let every = world.resource::<MeshFlowState>().spec.sort_every;
    if every == 0 || (step != 1 && !step.is_multiple_of(every)) {
        return;
    }
    let mut q = world.query::<(&ParticleId, Option<&CellHint>)>();
    let keys: Vec<(u32, u32)> = q
        .iter(world)
        .map(|(id, h)| (h.map_or(u32::MAX, |h| h.0), id.0))
        .collect();
    if keys.is_sorted() {
        return;
    }
    let mut perm: Vec<u32> = (0..keys.len() as u32).collect();
    perm.sort_unstable_by_key(|&i| keys[i as usize]);
    // The start's fluid velocity only where it is kept.
    let keep_start = keeps_start(
        world.resource::<Motion>(),
        world.get_resource::<CarrierModifier>(),
    );
    let flow_at_centre = std::any::TypeId::of::<FlowAtCentre>();
    reorder_particles(world, &perm, |t| keep_start || t != flow_at_centre);
}
