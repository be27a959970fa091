//! Particle–particle contacts: neighbour-list maintenance and contact forces.
//!
//! * [`maintain_neighbour_list`] (StepSet::NeighbourSearch) gathers the particles, sorted by
//!   id, into contiguous arrays and rebuilds the Verlet list ([`crate::neighbour`]) when
//!   some particle moved more than half the skin; the tangential history of every listed
//!   pair is carried over by (id_i, id_j).
//! * [`particle_contact_forces`] (StepSet::Forces) computes each pair's force once and
//!   adds it to its two particles at once (+F on i, −F exactly on j). The pair list is cut
//!   into a few fixed *slots* (by pair count, never by thread count); each slot sums its
//!   pairs in pair order into its own per-particle arrays, and the slots run in parallel.
//!   [`apply_contact_kicks`] adds the slots' sums per particle in slot order. The result is
//!   bit-identical whatever the thread count.
//!
//! Physics: the normal law of [`crate::contact::normal`], the tangential Mindlin spring and
//! rolling resistance of [`crate::contact::tangential`], torque r_i·n × F_t (paper eq. 3).

use bevy_ecs::prelude::*;
use bytemuck::TransparentWrapper;
use glam::DVec3;

use crate::components::*;
use crate::contact::normal::effective;
use crate::contact::tangential::{
    HertzPair, TangentialStiffness, hertz_mindlin_pair, rolling_torque, tangential_force,
};
use crate::contact::{Material, NormalLaw, TangentialLaw};
use crate::effects::motion::{Motion, StepDisplacement};
use crate::effects::recording::Tally;
use crate::integrate::{angular_kick_factor, linear_kick_factor};
use crate::neighbour::{NeighbourList, PeriodicBox};
use crate::step::{StepBuilder, StepSet};

/// Particle–particle contact settings (part of [`crate::SimConfig`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactConfig {
    /// Normal law.
    pub law: NormalLaw,
    /// Particle material (E, ν, e, μ_s).
    pub material: Material,
    /// Verlet skin, m.
    pub skin: f64,
    /// Orthogonal periodic box lengths, m (`None` = open).
    pub periodic: Option<DVec3>,
    /// Rolling friction coefficient μ_r (0 = off).
    pub rolling_friction: f64,
    /// Tangential stiffness rule.
    pub tangential_stiffness: TangentialStiffness,
}

impl ContactConfig {
    /// The tangential law these settings give.
    pub fn tangential(&self) -> TangentialLaw {
        TangentialLaw {
            stiffness: self.tangential_stiffness,
            ..TangentialLaw::new(self.law, self.material.friction, self.rolling_friction)
        }
    }
}

/// Contact parameters derived once (resource).
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct ContactParams {
    /// Normal law.
    pub law: NormalLaw,
    /// Tangential law.
    pub tangential: TangentialLaw,
    /// Effective modulus E*, Pa.
    pub e_eff: f64,
    /// Effective shear modulus G*, Pa.
    pub g_eff: f64,
    /// Periodic box.
    pub periodic: Option<PeriodicBox>,
    /// √(6·G*/E*), for [`hertz_mindlin`].
    pub mindlin_c: f64,
}

/// One candidate pair with its contact history and the constants of its contact law.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairState {
    /// Particle indices (into the gathered arrays), i < j.
    pub i: u32,
    /// Second index.
    pub j: u32,
    /// In contact after this step's force evaluation.
    pub touching: bool,
    /// Whole periodic box lengths taken off x_j − x_i for the minimum image (zero in an
    /// open domain), m. Fixed between list builds: positions are not wrapped and move less
    /// than half the skin.
    pub shift: DVec3,
    /// Tangential history displacement, m (zero while not touching).
    pub history: DVec3,
    /// R*, m*, √R* and √(m*·K) of the pair.
    pub hertz: HertzPair,
}

/// A pair in contact this step and what it does to its two particles.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairContact {
    /// First particle index.
    pub i: u32,
    /// Second particle index.
    pub j: u32,
    /// Contact started this step.
    pub started: bool,
    /// Force on i, N (the force on j is exactly −force).
    pub force: DVec3,
    /// Torque on i, N·m.
    pub torque_i: DVec3,
    /// Torque on j, N·m.
    pub torque_j: DVec3,
}

/// Pairs per accumulation slot (the slot count is fixed by the pair count).
const PAIRS_PER_SLOT: usize = 4096;
/// Most slots: four tasks per core on two cores. Each slot's arrays also cover the far
/// neighbours (j) of its pairs, so more slots mean more entries to clear and sum each step
/// (16 slots ran the 32 000-particle dense bed about 4 % slower).
const MAX_SLOTS: usize = 8;

/// One slot of the force accumulation: a fixed range of the pair list whose forces are
/// summed, in pair order, into per-particle arrays covering particles `base..base+len`.
/// Invariant between steps: the arrays are zero except where the last step wrote
/// (`touched`, or anywhere when `dirty`).
#[derive(Debug, Default)]
struct Slot {
    /// Pair indices of this slot.
    pairs: std::ops::Range<usize>,
    /// First particle index covered.
    base: usize,
    /// Summed force (N) and torque (N·m) per covered particle.
    sums: Vec<[DVec3; 2]>,
    /// Covered particles written this step (sparse steps), global indices.
    touched: Vec<u32>,
    /// `touched` membership, local indices.
    marked: Vec<bool>,
    /// Written anywhere (a dense step): clear everything before the next step.
    dirty: bool,
    /// Contacts started this step, per group.
    collisions: Vec<u64>,
    /// Pairs in contact this step.
    active: usize,
}

impl Slot {
    /// True when particle `k` is covered.
    #[inline]
    fn covers(&self, k: usize) -> bool {
        k >= self.base && k - self.base < self.sums.len()
    }

    /// Zero what the last step wrote.
    fn clear(&mut self, groups: usize) {
        if self.dirty {
            self.sums.fill([DVec3::ZERO; 2]);
            self.dirty = false;
        } else {
            for &k in &self.touched {
                let l = k as usize - self.base;
                self.sums[l] = [DVec3::ZERO; 2];
                self.marked[l] = false;
            }
        }
        self.touched.clear();
        self.collisions.clear();
        self.collisions.resize(groups, 0);
        self.active = 0;
    }

    /// Compute the slot's pairs and sum them; `sparse` records the particles written.
    ///
    /// On x86-64 CPUs with AVX2 the same code is compiled a second time for them and
    /// picked at run time (no fused multiply–add: Rust never contracts a·b + c, so both
    /// versions give the same bits).
    fn run(&mut self, pairs: &mut [PairState], k: &Kernel, groups: usize, sparse: bool) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU supports AVX2, checked just above.
            unsafe { self.run_avx2(pairs, k, groups, sparse) };
            return;
        }
        self.run_portable(pairs, k, groups, sparse);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn run_avx2(&mut self, pairs: &mut [PairState], k: &Kernel, groups: usize, sparse: bool) {
        self.run_portable(pairs, k, groups, sparse);
    }

    #[inline(always)]
    fn run_portable(&mut self, pairs: &mut [PairState], k: &Kernel, groups: usize, sparse: bool) {
        self.clear(groups);
        let base = self.base;
        let group = k.group;
        for p in pairs {
            let Some(c) = pair_kernel(p, &k.bodies, &k.par, k.dt) else {
                continue;
            };
            let (i, j) = (c.i as usize, c.j as usize);
            let (li, lj) = (i - base, j - base);
            let si = &mut self.sums[li];
            si[0] += c.force;
            si[1] += c.torque_i;
            let sj = &mut self.sums[lj];
            sj[0] -= c.force;
            sj[1] += c.torque_j;
            self.active += 1;
            if sparse {
                for (l, k) in [(li, i), (lj, j)] {
                    if !self.marked[l] {
                        self.marked[l] = true;
                        self.touched.push(k as u32);
                    }
                }
            }
            if c.started {
                for g in [group[i], group[j]] {
                    if let Some(n) = self.collisions.get_mut(g as usize) {
                        *n += 1;
                    }
                }
            }
        }
        self.dirty = !sparse;
    }
}

/// Cut `pairs` (sorted by i, with i < j) into slots: as many as the pair count gives (at
/// most [`MAX_SLOTS`]), halved while their arrays together would cover more than
/// max(4·n, 2²⁰) particles (particles stored far from their neighbours in index order).
fn layout_slots(pairs: &[[u32; 2]], n: usize) -> Vec<Slot> {
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
                    .map(|p| p[1] as usize)
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
fn slot_sum(slots: &[Slot], k: usize) -> (DVec3, DVec3) {
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

/// The particles gathered in id order, the neighbour list and the pair states (resource).
#[derive(Resource, Debug, Default)]
pub struct ContactState {
    /// Ids, in the order of the arrays (the particles' table order).
    pub ids: Vec<u32>,
    /// Groups.
    pub group: Vec<u32>,
    /// Positions, m.
    pub pos: Vec<DVec3>,
    /// Velocities, m/s.
    pub vel: Vec<DVec3>,
    /// Angular velocities, rad/s.
    pub omega: Vec<DVec3>,
    /// Radii, m.
    pub radius: Vec<f64>,
    /// Masses, kg.
    pub mass: Vec<f64>,
    /// dt/m per particle ([`linear_kick_factor`]), s/kg.
    kick_v: Vec<f64>,
    /// dt/I per particle ([`angular_kick_factor`]), s/(kg·m²).
    kick_w: Vec<f64>,
    /// Verlet list.
    pub list: NeighbourList,
    /// Pair states aligned with `list.pairs`.
    pub pairs: Vec<PairState>,
    /// Force accumulation slots over the pair list (laid out at each rebuild).
    slots: Vec<Slot>,
    /// Whether this step's slots record the particles they touch (few contacts) or
    /// every particle is summed (dense packings).
    sparse: bool,
    /// Particles with a contact this step (scratch of the sparse kick).
    touched: Vec<u32>,
    /// `touched` membership (scratch).
    marked: Vec<bool>,
    /// Particle–particle contacts in touch after the last step.
    pub active: usize,
}

impl ContactState {
    /// The summed contact force (N) and torque (N·m) on the particle at index `k` of the
    /// gathered arrays (`ids[k]`) from this step's force stage.
    pub fn contact_force(&self, k: usize) -> (DVec3, DVec3) {
        slot_sum(&self.slots, k)
    }

    /// One line on the neighbour list for run reports: builds (and their time), exact
    /// displacement checks, candidate pairs and pairs in contact.
    pub fn summary(&self) -> String {
        format!(
            "{} builds ({:.3} s), {} exact displacement checks, {} candidate pairs in {} force slots, {} in contact",
            self.list.builds,
            self.list.build_time.as_secs_f64(),
            self.list.checks,
            self.list.pairs.len(),
            self.slots.len(),
            self.active
        )
    }

    /// Number of force accumulation slots (fixed by the pair list, not the threads).
    pub fn slot_count(&self) -> usize {
        self.slots.len()
    }
}

/// Insert the contact resources and add the systems (called only when the scene declares
/// contacts).
pub fn plugin(world: &mut World, b: &mut StepBuilder, cfg: &ContactConfig) {
    let periodic = cfg.periodic.map(PeriodicBox::new);
    world.insert_resource(ContactParams {
        law: cfg.law,
        tangential: cfg.tangential(),
        e_eff: cfg.material.effective_modulus(),
        g_eff: cfg.material.effective_shear_modulus(),
        periodic,
        mindlin_c: (6.0 * cfg.material.effective_shear_modulus()
            / cfg.material.effective_modulus())
        .sqrt(),
    });
    world.insert_resource(StepDisplacement::default());
    world.insert_resource(ContactState {
        list: NeighbourList::new(cfg.skin, periodic),
        ..Default::default()
    });
    b.add(
        StepSet::NeighbourSearch,
        "contacts",
        "maintain_neighbour_list",
        maintain_neighbour_list,
    );
    b.add(
        StepSet::Forces,
        "contacts",
        "particle_contact_forces",
        particle_contact_forces,
    );
    b.add(
        StepSet::Integration,
        "contacts",
        "apply_contact_kicks",
        apply_contact_kicks,
    );
}

type GatherQuery<'w, 's> = Query<
    'w,
    's,
    (
        &'static ParticleId,
        &'static GroupId,
        &'static Position,
        &'static Velocity,
        Option<&'static AngularVelocity>,
        &'static Diameter,
        &'static Mass,
    ),
>;

/// Check that the particles are still those of the arrays, in the same table order, and
/// keep the neighbour list up to date.
///
/// Particles are indexed in the query's iteration order (table order), which depends only
/// on the history of spawns and despawns, never on the thread count. While the set of
/// particles is unchanged nothing is copied: the displacement check reads the position
/// column in place (when all particles share one table, the usual case). When the set
/// changes, ids, groups, radii and masses are gathered again, the list is rebuilt and each
/// pair's history is carried over by (id_i, id_j).
pub fn maintain_neighbour_list(
    mut state: ResMut<ContactState>,
    params: Res<ContactParams>,
    motion: Res<Motion>,
    disp: Res<StepDisplacement>,
    q: GatherQuery,
) {
    let st = &mut *state;
    // How far the last integration step moved any particle (None before the first).
    let drift = disp.take();
    let n = q.iter().len();
    let mut same_set = n == st.ids.len();
    // The position column when every particle is in one table, else `None`.
    let mut column: Option<&[DVec3]> = None;
    if same_set {
        let mut k = 0;
        match q.contiguous_iter() {
            Ok(chunks) => {
                let mut count = 0;
                for (ids, _, xs, ..) in chunks {
                    let n = ids.len();
                    if !ids.iter().zip(&st.ids[k..k + n]).all(|(a, b)| a.0 == *b) {
                        same_set = false;
                        break;
                    }
                    if count == 0 {
                        column = Some(Position::peel_slice(xs));
                    }
                    count += 1;
                    k += n;
                }
                if count != 1 {
                    column = None;
                }
            }
            Err(_) => {
                for (id, ..) in q.iter() {
                    if st.ids[k] != id.0 {
                        same_set = false;
                        break;
                    }
                    k += 1;
                }
            }
        }
    }
    if same_set {
        let need = match column {
            Some(c) => st.list.needs_rebuild(c, drift),
            None => {
                st.pos.clear();
                st.pos.extend(q.iter().map(|(_, _, x, ..)| x.0));
                st.list.needs_rebuild(&st.pos, drift)
            }
        };
        if !need {
            return;
        }
        if let Some(c) = column {
            st.pos.clear();
            st.pos.extend_from_slice(c);
        }
        st.list.build(&st.pos, &st.radius);
        carry_history(st, &params, None);
        st.slots = layout_slots(&st.list.pairs, st.ids.len());
        return;
    }
    let old_ids = std::mem::take(&mut st.ids);
    st.group.clear();
    st.pos.clear();
    st.radius.clear();
    st.mass.clear();
    for (id, g, x, _, _, d, m) in q.iter() {
        st.ids.push(id.0);
        st.group.push(g.0);
        st.pos.push(x.0);
        st.radius.push(0.5 * d.0);
        st.mass.push(m.0);
    }
    let dt = motion.dt;
    st.kick_v = st.mass.iter().map(|&m| linear_kick_factor(m, dt)).collect();
    st.kick_w = (st.mass.iter().zip(&st.radius))
        .map(|(&m, &r)| angular_kick_factor(m, 2.0 * r, dt))
        .collect();
    st.list.build(&st.pos, &st.radius);
    carry_history(st, &params, Some(&old_ids));
    st.slots = layout_slots(&st.list.pairs, st.ids.len());
}

/// New pair states for the rebuilt list, each touching pair keeping its history
/// (`ids_before`: the ids the old pair indices refer to, when the set changed).
///
/// Only the pairs in contact carry anything, and they are few: each is looked up in the
/// new (sorted) list by binary search, after mapping its particles' ids to their new
/// indices when the set changed.
fn carry_history(st: &mut ContactState, par: &ContactParams, ids_before: Option<&[u32]>) {
    let old = std::mem::take(&mut st.pairs);
    let (pos, radius, mass) = (&st.pos, &st.radius, &st.mass);
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
        // Old index → new index (identity while the set is unchanged).
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

/// Everything the pair kernel reads.
struct Kernel<'a> {
    bodies: Bodies<'a>,
    par: ContactParams,
    /// Time step, s.
    dt: f64,
    /// Group of each particle (collision counts).
    group: &'a [u32],
}

/// Per-particle inputs of the pair kernel.
struct Bodies<'a> {
    pos: &'a [DVec3],
    vel: &'a [DVec3],
    omega: &'a [DVec3],
    radius: &'a [f64],
}

/// The force, torques and new history of one pair (pure); `None` when it does not touch.
#[inline(always)]
fn pair_kernel(p: &mut PairState, b: &Bodies, par: &ContactParams, dt: f64) -> Option<PairContact> {
    let (i, j) = (p.i as usize, p.j as usize);
    let d = b.pos[j] - b.pos[i] - p.shift;
    let (ri, rj) = (b.radius[i], b.radius[j]);
    let dist2 = d.length_squared();
    let reach = ri + rj;
    let was = p.touching;
    if dist2 >= reach * reach || dist2 == 0.0 {
        if was {
            p.touching = false;
            p.history = DVec3::ZERO;
        }
        return None;
    }
    let dist = dist2.sqrt();
    let n = d * (1.0 / dist); // from i to j
    let delta = reach - dist;
    let pc = &p.hertz;
    // Velocity of i's contact point relative to j's.
    let v_rel = b.vel[i] - b.vel[j] + (ri * b.omega[i] + rj * b.omega[j]).cross(n);
    let vn_approach = v_rel.dot(n);
    let tl = &par.tangential;
    let (fn_, kt, eta) = match (par.law, tl.stiffness) {
        // The common case in one pass (shared square roots, per-pair constants).
        (NormalLaw::Hertz { gamma }, TangentialStiffness::Mindlin) => hertz_mindlin_pair(
            delta,
            -vn_approach,
            pc,
            par.e_eff,
            par.g_eff,
            gamma,
            tl.damping,
            par.mindlin_c,
        ),
        _ => {
            let (fn_, kn) = par
                .law
                .force(delta, -vn_approach, par.e_eff, pc.r_eff, pc.m_eff);
            let kt = tl.stiffness(par.g_eff, pc.r_eff, delta, kn);
            (fn_, kt, tl.damping * (pc.m_eff * kt).sqrt())
        }
    };
    let mut c = PairContact {
        i: p.i,
        j: p.j,
        started: !was,
        force: -fn_ * n,
        ..Default::default()
    };
    if tl.friction > 0.0 {
        let vt = v_rel - vn_approach * n;
        let u = tangential_force(p.history, n, vt, kt, eta, tl.friction * fn_.abs(), dt);
        p.history = u.history;
        c.force += u.force;
        // Torque about each centre from the force at its contact point (r·n × F_t).
        let nf = n.cross(u.force);
        c.torque_i = ri * nf;
        c.torque_j = rj * nf;
    }
    if tl.rolling > 0.0 {
        let t = rolling_torque(tl.rolling, fn_.abs(), pc.r_eff, b.omega[i] - b.omega[j]);
        c.torque_i += t;
        c.torque_j -= t;
    }
    p.touching = true;
    Some(c)
}

/// The position, velocity and angular velocity columns when every particle is in one
/// table holding exactly the `n` gathered particles.
fn state_columns<'a>(q: &'a StateQuery, n: usize) -> Option<Columns<'a>> {
    let mut it = q.contiguous_iter().ok()?;
    let (xs, vs, ws) = it.next()?;
    if it.next().is_some() || xs.len() != n {
        return None;
    }
    Some((
        Position::peel_slice(xs),
        Velocity::peel_slice(vs),
        ws.map(AngularVelocity::peel_slice),
    ))
}

/// Positions, velocities and (when present) angular velocities, in table order.
type Columns<'a> = (&'a [DVec3], &'a [DVec3], Option<&'a [DVec3]>);

type StateQuery<'w, 's> = Query<
    'w,
    's,
    (
        &'static Position,
        &'static Velocity,
        Option<&'static AngularVelocity>,
    ),
>;

/// Compute every pair's force (parallel), then sum them per particle (fixed order) for
/// the particles in contact. The sums are applied by [`apply_contact_kicks`].
pub fn particle_contact_forces(
    mut state: ResMut<ContactState>,
    params: Res<ContactParams>,
    motion: Res<Motion>,
    mut tally: ResMut<Tally>,
    q: StateQuery,
) {
    let st = &mut *state;
    let par = *params;
    let dt = motion.dt;
    let n = st.ids.len();
    // Read the columns in place when possible; otherwise copy them in table order (the
    // same order the neighbour stage checked).
    let cols = state_columns(&q, n);
    if cols.is_none() {
        st.pos.clear();
        st.vel.clear();
        for (x, v, _) in q.iter() {
            st.pos.push(x.0);
            st.vel.push(v.0);
        }
    }
    let omega_col = cols.and_then(|(_, _, w)| w);
    if omega_col.is_none() {
        st.omega.clear();
        st.omega
            .extend(q.iter().map(|(_, _, w)| w.map_or(DVec3::ZERO, |w| w.0)));
    }
    let (pos, vel): (&[DVec3], &[DVec3]) = match cols {
        Some((x, v, _)) => (x, v),
        None => (&st.pos, &st.vel),
    };
    let bodies = Bodies {
        pos,
        vel,
        omega: omega_col.unwrap_or(&st.omega),
        radius: &st.radius,
    };
    // Few contacts last step: record the particles written, so the kick and the next
    // clear visit only those. Many: sum and clear every particle (no bookkeeping).
    st.sparse = st.active * 8 <= n;
    if st.marked.len() != n {
        st.marked.clear();
        st.marked.resize(n, false);
    }
    let sparse = st.sparse;
    let groups = tally.collisions.len();
    let group = &st.group;
    let mut work: Vec<(&mut Slot, &mut [PairState])> = Vec::with_capacity(st.slots.len());
    let mut rest: &mut [PairState] = &mut st.pairs;
    let mut at = 0;
    for slot in st.slots.iter_mut() {
        let (mine, tail) = std::mem::take(&mut rest).split_at_mut(slot.pairs.end - at);
        at = slot.pairs.end;
        rest = tail;
        work.push((slot, mine));
    }
    let kernel = Kernel {
        bodies,
        par,
        dt,
        group,
    };
    crate::team::for_each_item(&mut work, |_, (slot, pairs)| {
        slot.run(pairs, &kernel, groups, sparse);
    });
    let mut active = 0;
    for slot in &st.slots {
        active += slot.active;
        for (t, c) in tally.collisions.iter_mut().zip(&slot.collisions) {
            *t += c;
        }
    }
    st.active = active;
}

/// Apply the contact forces and torques of this step as kicks (first system of the
/// integration stage): v += F·dt/m, ω += T·dt/I with I = 0.4·m·r², F and T the slots'
/// sums. After a step with few contacts only the particles touched are visited; after a
/// dense one every particle, in parallel chunks. Equivalent to adding them to the force
/// the integrator kicks with, since every force of the step was computed from the state
/// before any kick.
pub fn apply_contact_kicks(
    mut state: ResMut<ContactState>,
    mut q: Query<(&ParticleId, &mut Velocity, Option<&mut AngularVelocity>)>,
) {
    let st = &mut *state;
    if st.active == 0 {
        return;
    }
    let n = st.ids.len();
    // The particles to visit on a sparse step, in slot order, each once.
    let mut touched = std::mem::take(&mut st.touched);
    touched.clear();
    if st.sparse {
        for s in &st.slots {
            for &k in &s.touched {
                if !st.marked[k as usize] {
                    st.marked[k as usize] = true;
                    touched.push(k);
                }
            }
        }
        for &k in &touched {
            st.marked[k as usize] = false;
        }
    }
    let slots = &st.slots;
    let (kick_v, kick_w) = (&st.kick_v, &st.kick_w);
    let kick = |k: usize, v: &mut DVec3, w: Option<&mut DVec3>| {
        let (f, t) = slot_sum(slots, k);
        *v += f * kick_v[k];
        if let Some(w) = w {
            *w += t * kick_w[k];
        }
    };
    // One table holding exactly the gathered particles (checked by the neighbour stage
    // this step; nothing spawns or despawns in between): index the columns directly.
    if let Ok(mut it) = q.contiguous_iter_mut()
        && let Some((ids, mut vs, ws)) = it.next()
        && it.next().is_none()
        && ids.len() == n
        && ids.first().map(|i| i.0) == st.ids.first().copied()
        && ids.last().map(|i| i.0) == st.ids.last().copied()
    {
        let vs = Velocity::peel_slice_mut(vs.bypass_change_detection());
        let mut ws = ws;
        let mut ws = ws
            .as_mut()
            .map(|w| AngularVelocity::peel_slice_mut(w.bypass_change_detection()));
        if st.sparse {
            for &k in &touched {
                let k = k as usize;
                kick(k, &mut vs[k], ws.as_deref_mut().map(|w| &mut w[k]));
            }
        } else {
            kick_all(vs, ws, slots, kick_v, kick_w);
        }
    } else if st.sparse {
        let slot: std::collections::HashMap<u32, usize> = touched
            .iter()
            .map(|&k| (st.ids[k as usize], k as usize))
            .collect();
        for (id, mut v, w) in q.iter_mut() {
            if let Some(&k) = slot.get(&id.0) {
                let mut w = w;
                kick(k, &mut v.0, w.as_deref_mut().map(|w| &mut w.0));
            }
        }
    } else {
        let index: std::collections::HashMap<u32, usize> =
            st.ids.iter().enumerate().map(|(k, id)| (*id, k)).collect();
        for (id, mut v, w) in q.iter_mut() {
            if let Some(&k) = index.get(&id.0) {
                let mut w = w;
                kick(k, &mut v.0, w.as_deref_mut().map(|w| &mut w.0));
            }
        }
    }
    st.touched = touched;
}

/// The kicks of [`apply_contact_kicks`] for every particle, in parallel chunks (each
/// particle's update is independent). A chunk sums the slots covering it, in slot order,
/// into a buffer (contiguous runs), then kicks.
fn kick_all(
    v: &mut [DVec3],
    w: Option<&mut [DVec3]>,
    slots: &[Slot],
    kick_v: &[f64],
    kick_w: &[f64],
) {
    const C: usize = 4096;
    // Sums are built in blocks small enough to stay in the L1 cache.
    const B: usize = 256;
    let block = |base: usize, vc: &mut [DVec3], wc: Option<&mut [DVec3]>| {
        let len = vc.len();
        let mut f = [DVec3::ZERO; B];
        let mut t = [DVec3::ZERO; B];
        let (f, t) = (&mut f[..len], &mut t[..len]);
        for s in slots {
            let lo = base.max(s.base);
            let hi = (base + len).min(s.base + s.sums.len());
            if lo >= hi {
                continue;
            }
            let ss = &s.sums[lo - s.base..hi - s.base];
            for ((a, c), [b, d]) in f[lo - base..hi - base]
                .iter_mut()
                .zip(t[lo - base..hi - base].iter_mut())
                .zip(ss)
            {
                *a += *b;
                *c += *d;
            }
        }
        let kv = &kick_v[base..base + len];
        for ((v, f), k) in vc.iter_mut().zip(&*f).zip(kv) {
            *v += *f * *k;
        }
        if let Some(wc) = wc {
            let kw = &kick_w[base..base + len];
            for ((w, t), k) in wc.iter_mut().zip(&*t).zip(kw) {
                *w += *t * *k;
            }
        }
    };
    let chunk = |base: usize, vc: &mut [DVec3], wc: Option<&mut [DVec3]>| {
        let mut w_blocks = wc.map(|w| w.chunks_mut(B));
        for (b, vb) in vc.chunks_mut(B).enumerate() {
            block(base + b * B, vb, w_blocks.as_mut().and_then(|it| it.next()));
        }
    };
    if v.len() < 2 * C {
        chunk(0, v, w);
        return;
    }
    // (velocities, angular velocities) of each chunk; chunk k starts at particle k·C.
    let mut w_chunks = w.map(|w| w.chunks_mut(C));
    let mut work: Vec<(&mut [DVec3], Option<&mut [DVec3]>)> = v
        .chunks_mut(C)
        .map(|vc| (vc, w_chunks.as_mut().and_then(|it| it.next())))
        .collect();
    crate::team::for_each_item(&mut work, |k, (vc, wc)| chunk(k * C, vc, wc.as_deref_mut()));
}

/// Total kinetic energy (translational + rotational, I = m·d²/10) and momentum of the
/// particles, for tests and diagnostics.
pub fn kinetic_energy_and_momentum(world: &mut World) -> (f64, DVec3) {
    let mut q = world.query::<(&Velocity, Option<&AngularVelocity>, &Mass, &Diameter)>();
    let mut rows: Vec<_> = q
        .iter(world)
        .map(|(v, w, m, d)| (v.0, w.map_or(DVec3::ZERO, |w| w.0), m.0, d.0))
        .collect();
    // Fixed summation order.
    rows.sort_by(|a, b| a.0.x.total_cmp(&b.0.x).then(a.0.y.total_cmp(&b.0.y)));
    let mut e = 0.0;
    let mut p = DVec3::ZERO;
    for (v, w, m, d) in rows {
        e += 0.5 * m * v.length_squared() + 0.5 * (0.1 * m * d * d) * w.length_squared();
        p += m * v;
    }
    (e, p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::Material;
    use rand::{Rng, SeedableRng};

    /// The run-time-selected AVX2 build of the slot loop gives the same bits as the
    /// portable one.
    #[test]
    fn avx2_and_portable_slot_loops_agree_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let n = 400;
        let d = 1e-3;
        let pos: Vec<DVec3> = (0..n)
            .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) * 6.0 * d)
            .collect();
        let vel: Vec<DVec3> = (0..n)
            .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5)
            .collect();
        let omega: Vec<DVec3> = (0..n)
            .map(|_| (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 100.0)
            .collect();
        let radius: Vec<f64> = (0..n)
            .map(|_| 0.5 * d * rng.random_range(0.7..1.0))
            .collect();
        let mass: Vec<f64> = radius
            .iter()
            .map(|r| 2500.0 * 4.18879 * r * r * r)
            .collect();
        let material = Material {
            youngs_modulus: 1e8,
            poisson_ratio: 0.3,
            restitution: 0.6,
            friction: 0.4,
        };
        let law = NormalLaw::hertz(0.6);
        let par = ContactParams {
            law,
            tangential: TangentialLaw::new(law, 0.4, 0.05),
            e_eff: material.effective_modulus(),
            g_eff: material.effective_shear_modulus(),
            periodic: None,
            mindlin_c: (6.0 * material.effective_shear_modulus() / material.effective_modulus())
                .sqrt(),
        };
        let mut pairs = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                if (pos[j] - pos[i]).length() < 1.1 * (radius[i] + radius[j]) {
                    pairs.push(PairState {
                        i: i as u32,
                        j: j as u32,
                        touching: rng.random(),
                        history: (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5)
                            * 1e-6,
                        hertz: HertzPair::new(
                            par.e_eff,
                            effective(radius[i], radius[j]),
                            effective(mass[i], mass[j]),
                        ),
                        ..Default::default()
                    });
                }
            }
        }
        let list: Vec<[u32; 2]> = pairs.iter().map(|p| [p.i, p.j]).collect();
        let group = vec![0; n];
        let kernel = Kernel {
            bodies: Bodies {
                pos: &pos,
                vel: &vel,
                omega: &omega,
                radius: &radius,
            },
            par,
            dt: 1e-6,
            group: &group,
        };
        let run = |avx: bool| {
            let mut slots = layout_slots(&list, n);
            let mut ps = pairs.clone();
            let slot = &mut slots[0];
            let range = slot.pairs.clone();
            if avx {
                #[cfg(target_arch = "x86_64")]
                if std::arch::is_x86_feature_detected!("avx2") {
                    unsafe { slot.run_avx2(&mut ps[range], &kernel, 1, true) };
                    return Some((slot.sums.clone(), ps));
                }
                return None;
            }
            slot.run_portable(&mut ps[range], &kernel, 1, true);
            Some((slot.sums.clone(), ps))
        };
        let portable = run(false).unwrap();
        assert!(portable.0.iter().any(|f| f[0] != DVec3::ZERO));
        assert!(pairs.len() > 300, "{} pairs", pairs.len());
        if let Some(avx) = run(true) {
            let bits = |v: &[[DVec3; 2]]| -> Vec<u64> {
                v.iter()
                    .flatten()
                    .flat_map(|x| x.to_array().map(f64::to_bits))
                    .collect()
            };
            assert_eq!(bits(&portable.0), bits(&avx.0));
            assert_eq!(portable.1, avx.1);
        }
    }
}
