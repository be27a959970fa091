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
use crate::physics::contact::pair::{PairArrays, PairState};
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
///
/// Ghost rows ([`super::ghosts`]) follow the table's rows: the list is rebuilt when a
/// driver gives a ghost set ([`ContactState::set_ghosts`]), not when it forwards their
/// states ([`ContactState::put_ghost_states`]), and it holds no ghost–ghost pair.
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
    let table_ids = ParticleId::peel_slice(ids);
    // Ghost rows (a decomposed run) follow the table's rows. Between two ghost sets the
    // driver forwards their states and guarantees that none moved more than skin/2 since
    // the set was given (their owners check them); only the table's rows are checked
    // here, and the list is rebuilt whenever a new set is given.
    let rows = table_ids.len() + st.ghosts.len();
    let same_set = !st.rebuild_due
        && st.local == table_ids.len()
        && st.ids[..st.local] == *table_ids
        && st.ids[st.local..] == st.ghosts.ids[..];
    st.rebuild_due = false;
    let joined = |st: &ContactState| -> Vec<DVec3> { [pos, &st.ghosts.pos].concat() };
    if same_set && st.arrived.is_empty() {
        if !st.list.needs_rebuild_of(pos, rows, drift) {
            return;
        }
        let touching = touching_pairs(st);
        let all_pos = joined(st);
        st.list.build(&all_pos, &st.radius);
        drop_ghost_pairs(st);
        carry_history(st, &all_pos, touching, None);
        st.slots = layout_slots(&st.list.pairs, st.ids.len(), st.local);
        return;
    }
    let touching = touching_pairs(st);
    let old_ids = gather(st, ids, groups, ds, ms, clock.dt);
    let all_pos = joined(st);
    st.list.build(&all_pos, &st.radius);
    drop_ghost_pairs(st);
    carry_history(st, &all_pos, touching, Some(&old_ids));
    st.slots = layout_slots(&st.list.pairs, st.ids.len(), st.local);
}

/// Drop the ghost–ghost pairs from a list just built (with i < j they are the last
/// ones: i is a ghost row).
fn drop_ghost_pairs(st: &mut ContactState) {
    let local = st.local as u32;
    let keep = st.list.pairs.partition_point(|p| p[0] < local);
    st.list.pairs.truncate(keep);
}

/// Gather ids, groups, radii, masses and kick factors of the rows (the table's, then the
/// ghosts'); returns the old ids.
fn gather(
    st: &mut ContactState,
    ids: &[ParticleId],
    groups: &[GroupId],
    ds: &[Diameter],
    ms: &[Mass],
    dt: f64,
) -> Vec<u32> {
    let old_ids = std::mem::replace(&mut st.ids, ids.iter().map(|id| id.0).collect());
    st.local = ids.len();
    st.group = groups.iter().map(|g| g.0).collect();
    st.radius = ds.iter().map(|d| 0.5 * d.0).collect();
    st.mass = ms.iter().map(|m| m.0).collect();
    st.kick_v = st.mass.iter().map(|&m| linear_kick_factor(m, dt)).collect();
    st.kick_w = (st.mass.iter().zip(&st.radius))
        .map(|(&m, &r)| angular_kick_factor(m, 2.0 * r, dt))
        .collect();
    let g = &st.ghosts;
    st.ids.extend_from_slice(&g.ids);
    st.group.extend_from_slice(&g.group);
    st.radius.extend_from_slice(&g.radius);
    st.mass.extend_from_slice(&g.mass);
    old_ids
}

/// The pair state of list pair (i, j) before any contact (constants of the pair law).
fn fresh_pair(st: &ContactState, i: u32, j: u32) -> PairState {
    let (a, b) = (i as usize, j as usize);
    let par = &st.params;
    PairState {
        hertz: HertzPair::new(
            par.e_eff,
            effective(st.radius[a], st.radius[b]),
            effective(st.mass[a], st.mass[b]),
        ),
        ..Default::default()
    }
}

/// The arrays of the list's pairs before any contact: no history, the pair law's
/// constants, and the minimum-image shifts of positions `pos` in a periodic box (none in
/// an open domain).
fn fresh_pairs(st: &ContactState, pos: &[DVec3]) -> PairArrays {
    let ij = &st.list.pairs;
    PairArrays {
        touching: vec![false; ij.len()],
        shift: match st.params.periodic {
            Some(pb) => (ij.iter())
                .map(|&[i, j]| pb.image_shift(pos[j as usize] - pos[i as usize]))
                .collect(),
            None => Vec::new(),
        },
        state: ij.iter().map(|&[i, j]| fresh_pair(st, i, j)).collect(),
    }
}

impl ContactState {
    /// The arrays that carry over between steps (checkpoints).
    pub fn record(&self) -> crate::checkpoint::records::ContactRecord {
        let (reference, drift_bound) = self.list.carried();
        crate::checkpoint::records::ContactRecord {
            ids: self.ids.clone(),
            list_pairs: self.list.pairs.clone(),
            reference: reference.to_vec(),
            builds: self.list.builds,
            checks: self.list.checks,
            drift_bound,
            pairs: (self.list.pairs.iter().enumerate())
                .map(|(k, &[i, j])| crate::checkpoint::records::PairRecord {
                    i,
                    j,
                    touching: self.pairs.touching[k],
                    shift: self.pairs.shift(k),
                    history: self.pairs.state[k].history,
                })
                .collect(),
            sparse: self.sparse,
            active: self.active,
        }
    }

    /// Restore the arrays saved by [`ContactState::record`] for the particle table
    /// `ids`… (the rows of the restored particles, in order); the per-row constants are
    /// gathered again from the table, the pair constants derived again.
    #[allow(clippy::too_many_arguments)]
    pub fn restore(
        &mut self,
        r: &crate::checkpoint::records::ContactRecord,
        ids: &[ParticleId],
        groups: &[GroupId],
        ds: &[Diameter],
        ms: &[Mass],
        dt: f64,
    ) -> Result<(), String> {
        let n = r.ids.len();
        if r.pairs.len() != r.list_pairs.len()
            || r.pairs
                .iter()
                .zip(&r.list_pairs)
                .any(|(p, l)| [p.i, p.j] != *l)
            || r.list_pairs
                .iter()
                .any(|l| l[0] >= l[1] || l[1] as usize >= n)
            || (!r.reference.is_empty() && r.reference.len() != n)
        {
            return Err("the contact list is inconsistent".into());
        }
        self.list.restore(
            r.list_pairs.clone(),
            r.reference.clone(),
            r.builds,
            r.checks,
            r.drift_bound,
        );
        self.sparse = r.sparse;
        self.active = r.active;
        self.local = n;
        self.ghosts = Default::default();
        self.arrived.clear();
        let current = ParticleId::peel_slice(ids) == r.ids.as_slice();
        if current {
            gather(self, ids, groups, ds, ms, dt);
        } else {
            // Taken after a feeder or the outlet changed the particle set: the arrays
            // still describe the rows before the change, and the next neighbour stage
            // gathers them again and carries the touching pairs' histories over by id.
            // Only the ids and the pairs' contact state are read on that path.
            self.ids.clone_from(&r.ids);
            (self.group, self.radius, self.mass) = (Vec::new(), Vec::new(), Vec::new());
            (self.kick_v, self.kick_w) = (Vec::new(), Vec::new());
        }
        // The saved contact state; the pair constants derived again when the rows are
        // current (else the next neighbour stage rebuilds the list anyway).
        self.pairs = PairArrays {
            touching: r.pairs.iter().map(|p| p.touching).collect(),
            shift: match self.params.periodic {
                Some(_) => r.pairs.iter().map(|p| p.shift).collect(),
                None => Vec::new(),
            },
            state: (r.pairs.iter())
                .map(|p| PairState {
                    history: p.history,
                    hertz: if current {
                        fresh_pair(self, p.i, p.j).hertz
                    } else {
                        Default::default()
                    },
                })
                .collect(),
        };
        self.slots = if current {
            layout_slots(&self.list.pairs, n, n)
        } else {
            Vec::new()
        };
        self.marked = vec![false; if current { n } else { 0 }];
        Ok(())
    }
}

/// (i, j, history) of the pairs in contact, before the list is rebuilt.
fn touching_pairs(st: &ContactState) -> Vec<(u32, u32, DVec3)> {
    (st.pairs.in_contact(&st.list.pairs))
        .map(|([i, j], p)| (i, j, p.history))
        .collect()
}

/// New pair states for the rebuilt list, each touching pair keeping its history
/// (`ids_before`: the ids the old pair indices refer to, when the set changed).
///
/// Only the pairs in contact carry anything, and they are few: each is looked up in the
/// new (sorted) list by binary search, after mapping its particles' ids to their new
/// indices when the set changed; a pair one of whose particles left is dropped.
fn carry_history(
    st: &mut ContactState,
    pos: &[DVec3],
    touching: Vec<(u32, u32, DVec3)>,
    ids_before: Option<&[u32]>,
) {
    let mut pairs = fresh_pairs(st, pos);
    if !touching.is_empty() {
        // Old index → new index through the ids (identity while the set is unchanged).
        let remap: Option<std::collections::HashMap<u32, u32>> = ids_before.map(|before| {
            let wanted: std::collections::HashMap<u32, u32> = touching
                .iter()
                .flat_map(|&(i, j, _)| [i, j])
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
        for (i, j, history) in touching {
            let (a, b) = match &remap {
                None => (i, j),
                Some(m) => match (m.get(&i), m.get(&j)) {
                    (Some(&a), Some(&b)) => (a, b),
                    _ => continue, // a particle left
                },
            };
            // The history is stored as seen from the pair's first particle: flip it when
            // the pair's orientation changed.
            let (key, h) = if a < b {
                ([a, b], history)
            } else {
                ([b, a], -history)
            };
            if let Ok(k) = st.list.pairs.binary_search(&key) {
                pairs.state[k].history = h;
                pairs.touching[k] = true;
            }
        }
    }
    // Histories brought by particles that moved here (a decomposed run), for the pairs
    // this process did not carry already.
    if !st.arrived.is_empty() {
        let arrived = std::mem::take(&mut st.arrived);
        let wanted: std::collections::HashSet<u32> =
            arrived.iter().flat_map(|h| [h.a, h.b]).collect();
        let index: std::collections::HashMap<u32, u32> = (st.ids.iter().enumerate())
            .filter(|(_, id)| wanted.contains(id))
            .map(|(k, &id)| (id, k as u32))
            .collect();
        for h in arrived {
            let (Some(&a), Some(&b)) = (index.get(&h.a), index.get(&h.b)) else {
                continue;
            };
            let (key, v) = if a < b {
                ([a, b], h.history)
            } else {
                ([b, a], -h.history)
            };
            if let Ok(k) = st.list.pairs.binary_search(&key)
                && !pairs.touching[k]
            {
                pairs.state[k].history = v;
                pairs.touching[k] = true;
            }
        }
    }
    st.pairs = pairs;
}
