//! Ghost particles: read-only copies of particles another process owns (a decomposed run,
//! `scg-mpi`), that this process's particles may touch.
//!
//! The contact arrays of [`ContactState`] hold the particle table's rows (`local` of
//! them) followed by the ghost rows the driver gave with [`ContactState::set_ghosts`] (a
//! new set: the list is rebuilt) and whose states it updates before each step with
//! [`ContactState::put_ghost_states`] (the list is kept: the driver gives a new set
//! before any particle, here or there, moved half the skin, which [`RebuildCheck::due`]
//! tells it for this process's particles). The neighbour list is built over both,
//! without ghost–ghost pairs;
//! the force stage computes the local–local and local–ghost pairs; the kicks apply to the
//! local rows only, so a ghost is never integrated, recorded, counted, drained or fed
//! (it is not in the particle table at all). A local–ghost pair's tangential history
//! lives in the pair list like any other and is carried over rebuilds by the two ids, so
//! it survives a change of the ghost set as long as the pair stays listed. When a
//! particle moves to another process, its touching pairs' histories go with it
//! ([`ContactState::histories_of`] → [`ContactState::receive_histories`]) and are taken
//! up by the next rebuild there.
//!
//! Without ghosts (a single process) nothing here runs and no bit of a run changes.

use bevy_ecs::prelude::*;
use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::ContactState;
use crate::components::*;
use crate::state::StepDisplacement;

/// Rows of particles as the pair kernel reads them: the ghost rows a driver hands to
/// [`ContactState::set_ghosts`] (also the rows a driver picks them from, see
/// [`table_rows`]).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Ghosts {
    /// Particle ids.
    pub ids: Vec<u32>,
    /// Groups.
    pub group: Vec<u32>,
    /// Radii, m.
    pub radius: Vec<f64>,
    /// Masses, kg.
    pub mass: Vec<f64>,
    /// Centres, m.
    pub pos: Vec<DVec3>,
    /// Velocities, m/s.
    pub vel: Vec<DVec3>,
    /// Angular velocities, rad/s.
    pub omega: Vec<DVec3>,
}

impl Ghosts {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.ids.len()
    }

    /// True when there is no row.
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }

    /// Append row `k` of `other`.
    pub fn push_row(&mut self, other: &Ghosts, k: usize) {
        self.ids.push(other.ids[k]);
        self.group.push(other.group[k]);
        self.radius.push(other.radius[k]);
        self.mass.push(other.mass[k]);
        self.pos.push(other.pos[k]);
        self.vel.push(other.vel[k]);
        self.omega.push(other.omega[k]);
    }

    /// Append every row of `other`.
    pub fn extend(&mut self, other: &Ghosts) {
        for k in 0..other.len() {
            self.push_row(other, k);
        }
    }

    /// The rows sorted by id (a canonical order, whatever order they arrived in).
    pub fn sorted_by_id(&self) -> Ghosts {
        let mut order: Vec<usize> = (0..self.len()).collect();
        order.sort_unstable_by_key(|&k| self.ids[k]);
        let mut out = Ghosts::default();
        for k in order {
            out.push_row(self, k);
        }
        out
    }

    /// True when every array has one entry per id.
    fn consistent(&self) -> bool {
        let n = self.ids.len();
        [
            self.group.len(),
            self.radius.len(),
            self.mass.len(),
            self.pos.len(),
            self.vel.len(),
            self.omega.len(),
        ]
        .iter()
        .all(|&l| l == n)
    }
}

/// The particle table's rows as ghost rows (what a driver picks the ghosts it sends
/// from), in table order. Empty when the scene has no contacts (no angular velocity).
pub fn table_rows(world: &mut World) -> Ghosts {
    table_rows_where(world, |_, _| true)
}

/// The rows of the particle table whose position and radius (m) `keep` accepts, as ghost
/// rows in table order: a driver's candidates without copying the whole table.
pub fn table_rows_where(world: &mut World, mut keep: impl FnMut(DVec3, f64) -> bool) -> Ghosts {
    let mut q = world.query::<(
        &ParticleId,
        &GroupId,
        &Diameter,
        &Mass,
        &Position,
        &Velocity,
        &AngularVelocity,
    )>();
    let mut g = Ghosts::default();
    for (id, group, d, m, x, v, w) in q.iter(world) {
        if !keep(x.0, 0.5 * d.0) {
            continue;
        }
        g.ids.push(id.0);
        g.group.push(group.0);
        g.radius.push(0.5 * d.0);
        g.mass.push(m.0);
        g.pos.push(x.0);
        g.vel.push(v.0);
        g.omega.push(w.0);
    }
    g
}

/// The rows of the particle table whose position and radius (m) `keep` accepts: their
/// row indices in the table and their ghost rows, in table order (what a driver sends as
/// ghosts and then forwards by row until the next ghost set).
pub fn table_rows_indexed_where(
    world: &mut World,
    mut keep: impl FnMut(DVec3, f64) -> bool,
) -> (Vec<u32>, Ghosts) {
    let mut k = 0u32;
    let mut rows = Vec::new();
    let g = table_rows_where(world, |x, r| {
        let kept = keep(x, r);
        if kept {
            rows.push(k);
        }
        k += 1;
        kept
    });
    (rows, g)
}

/// Bytes of one forwarded state ([`TableStates`], [`ContactState::put_ghost_states`]).
pub const STATE_BYTES: usize = 72;

/// The reader of the states a driver forwards each step to the ghosts of its particles
/// elsewhere ([`ContactState::put_ghost_states`] reads them). It keeps its query from one
/// step to the next: building a query every step cost more than reading the few ghost
/// rows of a dilute run.
pub struct TableStates(
    bevy_ecs::query::QueryState<(
        &'static Position,
        &'static Velocity,
        &'static AngularVelocity,
    )>,
);

impl TableStates {
    /// A reader of `world`'s particle table (use it with that world only).
    pub fn new(world: &mut World) -> Self {
        TableStates(world.query())
    }

    /// The position (m), velocity (m/s) and angular velocity (rad/s) of table rows
    /// `rows`, as nine f64 per row (x, v, ω) in native byte order, appended to `out`.
    ///
    /// # Panics
    /// When a row is past the table.
    pub fn append(&mut self, world: &World, rows: &[u32], out: &mut Vec<u8>) {
        let q = self.0.query(world);
        let Some((xs, vs, ws)) = crate::stages::table::columns(&q) else {
            assert!(rows.is_empty(), "ghost rows of an empty table");
            return;
        };
        out.reserve(STATE_BYTES * rows.len());
        for &k in rows {
            let k = k as usize;
            let (x, v, w) = (xs[k].0, vs[k].0, ws[k].0);
            let s: [f64; 9] = [x.x, x.y, x.z, v.x, v.y, v.z, w.x, w.y, w.z];
            out.extend_from_slice(bytemuck::bytes_of(&s));
        }
    }
}

/// Why a process of a decomposed run needs a new ghost set before its next step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Due {
    /// It does not.
    No,
    /// A particle here moved more than half the skin since the list was built.
    Moved,
    /// The particle table is not the rows the list was built over (a particle fed,
    /// drained or moved here): its rows cannot be forwarded either.
    Table,
}

/// Whether this process's part of a decomposed run needs a new ghost set before its next
/// step (asked between steps, [`RebuildCheck::due`]). It keeps its query from one step to
/// the next, as [`TableStates`] does.
pub struct RebuildCheck(bevy_ecs::query::QueryState<&'static Position>);

impl RebuildCheck {
    /// A check of `world`'s particle table (use it with that world only).
    pub fn new(world: &mut World) -> Self {
        RebuildCheck(world.query())
    }

    /// Whether a new ghost set is due before the next step. The driver gives every
    /// process a new set when any of them says so; ghosts are checked by their owners,
    /// never here. A feed and a drain in the same step leave the count alone: the driver
    /// counts its feeds.
    ///
    /// This is the next neighbour stage's displacement check, done now: it takes the
    /// last step's displacement into the list's bound (the stage then finds nothing more
    /// to add), so the exact check, when the bound passes half the skin, runs once a
    /// step.
    pub fn due(&mut self, world: &mut World) -> Due {
        rebuild_due(&mut self.0, world)
    }
}

fn rebuild_due(qs: &mut bevy_ecs::query::QueryState<&'static Position>, world: &mut World) -> Due {
    let drift = world.resource::<StepDisplacement>().take();
    let due = world.resource_scope(|world, mut st: Mut<ContactState>| {
        let q = qs.query(world);
        let pos: &[Position] = crate::stages::table::columns(&q).unwrap_or_default();
        let pos = <Position as bytemuck::TransparentWrapper<DVec3>>::peel_slice(pos);
        if pos.len() != st.local || !st.arrived.is_empty() {
            return Due::Table;
        }
        let rows = st.ids.len();
        if st.list.needs_rebuild_of(pos, rows, drift) {
            Due::Moved
        } else {
            Due::No
        }
    });
    // Nothing moves before the neighbour stage: it adds no displacement to the bound.
    let disp = world.resource::<StepDisplacement>();
    disp.record(0.0);
    disp.mark_reported();
    due
}

/// The tangential history of one touching pair, keyed by its particles' ids, as seen
/// from particle `a` (what migrates with a particle).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairHistory {
    /// Id of the particle the history is seen from.
    pub a: u32,
    /// Id of the other particle.
    pub b: u32,
    /// Tangential displacement, m, as seen from `a`.
    pub history: DVec3,
}

impl ContactState {
    /// Set the ghost rows of the coming step (ids must be distinct and differ from the
    /// table's). The neighbour stage rebuilds the list when the ghost ids differ from
    /// those it was built with; otherwise it uses the new states in place of the old.
    ///
    /// # Panics
    /// When the rows' arrays differ in length.
    pub fn set_ghosts(&mut self, ghosts: Ghosts) {
        assert!(ghosts.consistent(), "ghost rows of unequal lengths");
        self.ghosts = ghosts;
        self.rebuild_due = true;
    }

    /// Give ghost rows `at..` of the set last given ([`ContactState::set_ghosts`]) the
    /// states in `bytes` for the coming step, as [`TableStates::append`] writes them
    /// ([`STATE_BYTES`] a row: x in m, v in m/s, ω in rad/s); returns the row after the
    /// last one written. The list is not rebuilt: the driver guarantees that no ghost
    /// moved more than half the skin since the set was given.
    ///
    /// # Panics
    /// When `bytes` is not whole states or they run past the ghost rows.
    pub fn put_ghost_states(&mut self, at: usize, bytes: &[u8]) -> usize {
        assert!(
            bytes.len().is_multiple_of(STATE_BYTES),
            "forwarded states of {} bytes",
            bytes.len()
        );
        let g = &mut self.ghosts;
        let end = at + bytes.len() / STATE_BYTES;
        assert!(end <= g.len(), "forwarded states for another ghost set");
        for (k, s) in (at..end).zip(bytes.chunks_exact(STATE_BYTES)) {
            let s: [f64; 9] = bytemuck::pod_read_unaligned(s);
            g.pos[k] = DVec3::new(s[0], s[1], s[2]);
            g.vel[k] = DVec3::new(s[3], s[4], s[5]);
            g.omega[k] = DVec3::new(s[6], s[7], s[8]);
        }
        end
    }

    /// The ghost rows of the coming (or last) step.
    pub fn ghosts(&self) -> &Ghosts {
        &self.ghosts
    }

    /// Rows of the particle table the arrays describe (the rows after them are ghosts).
    pub fn local_rows(&self) -> usize {
        self.local
    }

    /// The touching pairs of the last force stage that involve a particle for which
    /// `leaving(id)` is true, seen from that particle (both ways when both leave), and
    /// the histories such a particle brought here that no rebuild took up yet.
    pub fn histories_of(&self, leaving: impl Fn(u32) -> bool) -> Vec<PairHistory> {
        let mut out = Vec::new();
        for ([i, j], p) in self.pairs.in_contact(&self.list.pairs) {
            let (Some(&a), Some(&b)) = (self.ids.get(i as usize), self.ids.get(j as usize)) else {
                continue;
            };
            if leaving(a) {
                out.push(PairHistory {
                    a,
                    b,
                    history: p.history,
                });
            }
            if leaving(b) {
                out.push(PairHistory {
                    a: b,
                    b: a,
                    history: -p.history,
                });
            }
        }
        // Histories that arrived with a particle moving on before a rebuild took them up.
        out.extend(self.arrived.iter().filter(|h| leaving(h.a)));
        out
    }

    /// Histories brought by particles that moved here: the next neighbour-list rebuild
    /// gives them to their pairs (a pair this process already carries keeps its own).
    pub fn receive_histories(&mut self, h: impl IntoIterator<Item = PairHistory>) {
        self.arrived.extend(h);
    }
}
