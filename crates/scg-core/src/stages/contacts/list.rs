//! Neighbour-list upkeep (StepSet::NeighbourSearch): the particle table's rows index the
//! contact arrays; the Verlet list ([`crate::physics::neighbour`]) is rebuilt when some
//! particle moved more than half the skin or the set of particles changed, and every
//! touching pair keeps its tangential history across rebuilds, keyed by its particles'
//! ids.

use bevy_ecs::prelude::*;
use bytemuck::TransparentWrapper;
use glam::DVec3;

use super::ContactState;
use super::slots::layout_slots;
use crate::components::*;
use crate::physics::contact::normal::effective;
use crate::physics::contact::pair::PairState;
use crate::physics::contact::tangential::HertzPair;
use crate::physics::integrate::{angular_kick_factor, linear_kick_factor};
use crate::stages::table::columns;
use crate::state::{SimClock, StepDisplacement};

/// Check that the particles are still those of the arrays, row for row, and keep the
/// neighbour list up to date.
///
/// Rows are in table order, which depends only on the history of spawns and despawns,
/// never on the thread count. While the set of particles is unchanged nothing is copied:
/// the displacement check and the list build read the position column in place. When the
/// set changes (a particle fed or drained), ids, groups, radii, masses and kick factors
/// are gathered again, the list is rebuilt and each touching pair's history is carried
/// over by (id_i, id_j).
pub fn maintain_neighbour_list(
    mut state: ResMut<ContactState>,
    clock: Res<SimClock>,
    disp: Res<StepDisplacement>,
    q: Query<(&ParticleId, &GroupId, &Position, &Diameter, &Mass)>,
) {
    let st = &mut *state;
    // How far the last integration step moved any particle (None before the first).
    let drift = disp.take();
    let (ids, groups, xs, ds, ms) = columns(&q).unwrap_or_default();
    let pos = Position::peel_slice(xs);
    let same_set = ParticleId::peel_slice(ids) == st.ids;
    if same_set {
        if !st.list.needs_rebuild(pos, drift) {
            return;
        }
        st.list.build(pos, &st.radius);
        carry_history(st, pos, None);
        st.slots = layout_slots(&st.list.pairs, st.ids.len());
        return;
    }
    let old_ids = std::mem::replace(&mut st.ids, ids.iter().map(|id| id.0).collect());
    st.group = groups.iter().map(|g| g.0).collect();
    st.radius = ds.iter().map(|d| 0.5 * d.0).collect();
    st.mass = ms.iter().map(|m| m.0).collect();
    let dt = clock.dt;
    st.kick_v = st.mass.iter().map(|&m| linear_kick_factor(m, dt)).collect();
    st.kick_w = (st.mass.iter().zip(&st.radius))
        .map(|(&m, &r)| angular_kick_factor(m, 2.0 * r, dt))
        .collect();
    st.list.build(pos, &st.radius);
    carry_history(st, pos, Some(&old_ids));
    st.slots = layout_slots(&st.list.pairs, st.ids.len());
}

/// New pair states for the rebuilt list, each touching pair keeping its history
/// (`ids_before`: the ids the old pair indices refer to, when the set changed).
///
/// Only the pairs in contact carry anything, and they are few: each is looked up in the
/// new (sorted) list by binary search, after mapping its particles' ids to their new
/// indices when the set changed; a pair one of whose particles left is dropped.
fn carry_history(st: &mut ContactState, pos: &[DVec3], ids_before: Option<&[u32]>) {
    let old = std::mem::take(&mut st.pairs);
    let (radius, mass, par) = (&st.radius, &st.mass, &st.params);
    let mut pairs: Vec<PairState> = st
        .list
        .pairs
        .iter()
        .map(|&[i, j]| {
            let (a, b) = (i as usize, j as usize);
            PairState {
                i,
                j,
                shift: par
                    .periodic
                    .map_or(DVec3::ZERO, |pb| pb.image_shift(pos[b] - pos[a])),
                hertz: HertzPair::new(
                    par.e_eff,
                    effective(radius[a], radius[b]),
                    effective(mass[a], mass[b]),
                ),
                ..Default::default()
            }
        })
        .collect();
    let touching: Vec<&PairState> = old.iter().filter(|p| p.touching).collect();
    if !touching.is_empty() {
        // Old index → new index through the ids (identity while the set is unchanged).
        let remap: Option<std::collections::HashMap<u32, u32>> = ids_before.map(|before| {
            let wanted: std::collections::HashMap<u32, u32> = touching
                .iter()
                .flat_map(|p| [p.i, p.j])
                .map(|k| (before[k as usize], k))
                .collect();
            let mut out = std::collections::HashMap::with_capacity(wanted.len());
            for (new_k, id) in st.ids.iter().enumerate() {
                if let Some(&old_k) = wanted.get(id) {
                    out.insert(old_k, new_k as u32);
                }
            }
            out
        });
        for p in touching {
            let (a, b) = match &remap {
                None => (p.i, p.j),
                Some(m) => match (m.get(&p.i), m.get(&p.j)) {
                    (Some(&a), Some(&b)) => (a, b),
                    _ => continue, // a particle left
                },
            };
            // The history is stored as seen from the pair's first particle: flip it when
            // the pair's orientation changed.
            let (key, h) = if a < b {
                ([a, b], p.history)
            } else {
                ([b, a], -p.history)
            };
            if let Ok(k) = st.list.pairs.binary_search(&key) {
                pairs[k].history = h;
                pairs[k].touching = true;
            }
        }
    }
    st.pairs = pairs;
}
