//! Particle–particle contacts: neighbour-list maintenance and contact forces.
//!
//! * [`maintain_neighbour_list`] (StepSet::NeighbourSearch) gathers the particles, sorted by
//!   id, into contiguous arrays and rebuilds the Verlet list ([`crate::neighbour`]) when
//!   some particle moved more than half the skin; the tangential history of every listed
//!   pair is carried over by (id_i, id_j).
//! * [`particle_contact_forces`] (StepSet::Forces) computes each pair's force once, in
//!   parallel chunks, into a per-pair buffer, then adds it to the two particles in pair
//!   order on one thread: +F on i, −F (exactly) on j. Each pair's arithmetic does not depend
//!   on the chunking, so the result is bit-identical whatever the thread count.
//!
//! Physics: the normal law of [`crate::contact::normal`], the tangential Mindlin spring and
//! rolling resistance of [`crate::contact::tangential`], torque r_i·n × F_t (paper eq. 3).

use bevy_ecs::prelude::*;
use bevy_tasks::{ComputeTaskPool, ParallelSliceMut};
use glam::DVec3;

use crate::components::*;
use crate::contact::normal::effective;
use crate::contact::tangential::{TangentialStiffness, rolling_torque, tangential_force};
use crate::contact::{Material, NormalLaw, TangentialLaw};
use crate::effects::motion::Motion;
use crate::effects::recording::Tally;
use crate::neighbour::{NeighbourList, PeriodicBox, separation};
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
}

/// One candidate pair with its contact history and this step's result.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairState {
    /// Particle indices (into the id-sorted arrays), i < j.
    pub i: u32,
    /// Second index.
    pub j: u32,
    /// Tangential history displacement, m.
    pub history: DVec3,
    /// In contact after this step's force evaluation.
    pub touching: bool,
    /// Contact started this step.
    pub started: bool,
    /// Force on i, N (the force on j is exactly −force).
    pub force: DVec3,
    /// Torque on i, N·m.
    pub torque_i: DVec3,
    /// Torque on j, N·m.
    pub torque_j: DVec3,
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
    /// Verlet list.
    pub list: NeighbourList,
    /// Pair states aligned with `list.pairs`.
    pub pairs: Vec<PairState>,
    /// Accumulated force per particle (scratch), N.
    force: Vec<DVec3>,
    /// Accumulated torque per particle (scratch), N·m.
    torque: Vec<DVec3>,
    /// Particles with a contact this step (scratch).
    touched: Vec<u32>,
    /// `touched` membership (scratch).
    marked: Vec<bool>,
    /// Particle–particle contacts in touch after the last step.
    pub active: usize,
}

/// Insert the contact resources and add the systems (called only when the scene declares
/// contacts).
pub fn plugin(world: &mut World, b: &mut StepBuilder, cfg: &ContactConfig) {
    let periodic = cfg.periodic.map(|l| PeriodicBox { lengths: l });
    world.insert_resource(ContactParams {
        law: cfg.law,
        tangential: cfg.tangential(),
        e_eff: cfg.material.effective_modulus(),
        g_eff: cfg.material.effective_shear_modulus(),
        periodic,
    });
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

/// Gather the particles' state into contiguous arrays and rebuild the neighbour list when
/// needed.
///
/// Particles are indexed in the query's iteration order (table order), which depends only
/// on the history of spawns and despawns, never on the thread count. While the set of
/// particles is unchanged only positions, velocities and spins are copied; when it changes
/// the list is rebuilt and each pair's history is carried over by (id_i, id_j).
pub fn maintain_neighbour_list(mut state: ResMut<ContactState>, q: GatherQuery) {
    let st = &mut *state;
    let n = q.iter().len();
    let mut same_set = n == st.ids.len();
    if same_set {
        let mut k = 0;
        match q.contiguous_iter() {
            Ok(chunks) => {
                for (ids, ..) in chunks {
                    let n = ids.len();
                    if !ids.iter().zip(&st.ids[k..k + n]).all(|(a, b)| a.0 == *b) {
                        same_set = false;
                        break;
                    }
                    k += n;
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
    let old_ids = if same_set {
        Vec::new()
    } else {
        std::mem::take(&mut st.ids)
    };
    if same_set {
        match q.contiguous_iter() {
            Ok(chunks) => {
                let mut k = 0;
                for (_, _, xs, vs, ws, _, _) in chunks {
                    let n = xs.len();
                    crate::par::par_map_into(&mut st.pos[k..k + n], xs, |x| x.0);
                    crate::par::par_map_into(&mut st.vel[k..k + n], vs, |v| v.0);
                    if let Some(ws) = ws {
                        crate::par::par_map_into(&mut st.omega[k..k + n], ws, |w| w.0);
                    }
                    k += n;
                }
            }
            Err(_) => {
                for (k, (_, _, x, v, w, _, _)) in q.iter().enumerate() {
                    st.pos[k] = x.0;
                    st.vel[k] = v.0;
                    st.omega[k] = w.map_or(DVec3::ZERO, |w| w.0);
                }
            }
        }
    } else {
        st.ids.clear();
        st.group.clear();
        st.pos.clear();
        st.vel.clear();
        st.omega.clear();
        st.radius.clear();
        st.mass.clear();
        for (id, g, x, v, w, d, m) in q.iter() {
            st.ids.push(id.0);
            st.group.push(g.0);
            st.pos.push(x.0);
            st.vel.push(v.0);
            st.omega.push(w.map_or(DVec3::ZERO, |w| w.0));
            st.radius.push(0.5 * d.0);
            st.mass.push(m.0);
        }
    }
    let rebuilt = if same_set {
        st.list.update(&st.pos, &st.radius)
    } else {
        st.list.build(&st.pos, &st.radius);
        true
    };
    if !rebuilt {
        return;
    }
    let old = std::mem::take(&mut st.pairs);
    let ids_before: &[u32] = if same_set { &st.ids } else { &old_ids };
    // Key (lower id, higher id) → (history, touching, id at the pair's first index).
    let carried: std::collections::HashMap<(u32, u32), (DVec3, bool, u32)> = old
        .iter()
        .filter(|p| p.touching)
        .map(|p| {
            let (a, b) = (ids_before[p.i as usize], ids_before[p.j as usize]);
            ((a.min(b), a.max(b)), (p.history, p.touching, a))
        })
        .collect();
    let mut pairs = Vec::with_capacity(st.list.pairs.len());
    for &[i, j] in &st.list.pairs {
        let (a, b) = (st.ids[i as usize], st.ids[j as usize]);
        let mut p = PairState {
            i,
            j,
            ..Default::default()
        };
        if let Some((h, t, first)) = carried.get(&(a.min(b), a.max(b))) {
            // The history is stored as seen from the pair's first particle: flip it when
            // the pair's orientation changed.
            p.history = if *first == a { *h } else { -*h };
            p.touching = *t;
        }
        pairs.push(p);
    }
    st.pairs = pairs;
}

/// Per-particle inputs of the pair kernel.
struct Bodies<'a> {
    pos: &'a [DVec3],
    vel: &'a [DVec3],
    omega: &'a [DVec3],
    radius: &'a [f64],
    mass: &'a [f64],
}

/// The force, torques and new history of one pair (pure).
#[inline]
fn pair_kernel(p: &mut PairState, b: &Bodies, par: &ContactParams, dt: f64) {
    let (i, j) = (p.i as usize, p.j as usize);
    let d = separation(b.pos[i], b.pos[j], par.periodic.as_ref());
    let (ri, rj) = (b.radius[i], b.radius[j]);
    let dist2 = d.length_squared();
    let reach = ri + rj;
    let was = p.touching;
    p.force = DVec3::ZERO;
    p.torque_i = DVec3::ZERO;
    p.torque_j = DVec3::ZERO;
    p.started = false;
    if dist2 >= reach * reach || dist2 == 0.0 {
        p.touching = false;
        p.history = DVec3::ZERO;
        return;
    }
    let dist = dist2.sqrt();
    let n = d / dist; // from i to j
    let delta = reach - dist;
    let r_eff = effective(ri, rj);
    let m_eff = effective(b.mass[i], b.mass[j]);
    // Velocity of i's contact point relative to j's.
    let v_rel = b.vel[i] - b.vel[j] + (ri * b.omega[i] + rj * b.omega[j]).cross(n);
    let vn_approach = v_rel.dot(n);
    let (fn_, kn) = par.law.force(delta, -vn_approach, par.e_eff, r_eff, m_eff);
    let mut f = -fn_ * n;
    let tl = &par.tangential;
    if tl.friction > 0.0 {
        let vt = v_rel - vn_approach * n;
        let kt = tl.stiffness(par.g_eff, r_eff, delta, kn);
        let eta = tl.damping * (m_eff * kt).sqrt();
        let u = tangential_force(p.history, n, vt, kt, eta, tl.friction * fn_.abs(), dt);
        p.history = u.history;
        f += u.force;
        // Torque about each centre from the force at its contact point.
        p.torque_i = (ri * n).cross(u.force);
        p.torque_j = (rj * n).cross(u.force);
    }
    if tl.rolling > 0.0 {
        let t = rolling_torque(tl.rolling, fn_.abs(), r_eff, b.omega[i] - b.omega[j]);
        p.torque_i += t;
        p.torque_j -= t;
    }
    p.force = f;
    p.touching = true;
    p.started = !was;
}

/// Pairs per parallel task.
const CHUNK: usize = 1024;

/// Compute every pair's force (parallel), then add them to the particles (fixed order).
pub fn particle_contact_forces(
    mut state: ResMut<ContactState>,
    params: Res<ContactParams>,
    motion: Res<Motion>,
    mut tally: ResMut<Tally>,
    mut q: Query<(&ParticleId, &mut Force, Option<&mut Torque>)>,
) {
    let st = &mut *state;
    let par = *params;
    let dt = motion.dt;
    let bodies = Bodies {
        pos: &st.pos,
        vel: &st.vel,
        omega: &st.omega,
        radius: &st.radius,
        mass: &st.mass,
    };
    if st.pairs.len() <= CHUNK {
        for p in st.pairs.iter_mut() {
            pair_kernel(p, &bodies, &par, dt);
        }
    } else {
        let pool = ComputeTaskPool::get_or_init(bevy_tasks::TaskPool::default);
        st.pairs.par_chunk_map_mut(pool, CHUNK, |_, chunk| {
            for p in chunk {
                pair_kernel(p, &bodies, &par, dt);
            }
        });
    }
    // Per-particle sums for the particles in contact only: `force`/`torque` stay zero
    // elsewhere, so a step with few contacts pays for those few, not for every particle.
    let n = st.pos.len();
    if st.force.len() != n {
        st.force.clear();
        st.force.resize(n, DVec3::ZERO);
        st.torque.clear();
        st.torque.resize(n, DVec3::ZERO);
        st.marked.clear();
        st.marked.resize(n, false);
    }
    st.touched.clear();
    let mut active = 0;
    for p in &st.pairs {
        if !p.touching {
            continue;
        }
        active += 1;
        let (i, j) = (p.i as usize, p.j as usize);
        st.force[i] += p.force;
        st.force[j] -= p.force;
        st.torque[i] += p.torque_i;
        st.torque[j] += p.torque_j;
        for k in [i, j] {
            if !st.marked[k] {
                st.marked[k] = true;
                st.touched.push(k as u32);
            }
        }
        if p.started {
            for g in [st.group[i], st.group[j]] {
                if let Some(c) = tally.collisions.get_mut(g as usize) {
                    *c += 1;
                }
            }
        }
    }
    st.active = active;
    if st.touched.is_empty() {
        return;
    }
    // The force stage iterates the particles in the same table order as the gather (ids
    // are checked); any mismatch falls back to a lookup by id.
    let mut chunks = Vec::new();
    let mut in_order = false;
    if let Ok(it) = q.contiguous_iter_mut() {
        let mut k = 0;
        in_order = true;
        for (ids, fs, ts) in it {
            let m = ids.len();
            if k + m > st.ids.len() || !ids.iter().zip(&st.ids[k..k + m]).all(|(a, b)| a.0 == *b) {
                in_order = false;
                break;
            }
            chunks.push((k, fs, ts));
            k += m;
        }
        in_order &= k == st.ids.len();
    }
    let st_touched = std::mem::take(&mut st.touched);
    if in_order {
        for &k in &st_touched {
            let k = k as usize;
            // Chunks are few (usually one table): find the one holding index k.
            let c = chunks.partition_point(|(start, _, _)| *start <= k) - 1;
            let (start, fs, ts) = &mut chunks[c];
            fs.bypass_change_detection()[k - *start].0 += st.force[k];
            if let Some(ts) = ts {
                ts.bypass_change_detection()[k - *start].0 += st.torque[k];
            }
        }
    } else {
        drop(chunks);
        let slot: std::collections::HashMap<u32, usize> = st_touched
            .iter()
            .map(|&k| (st.ids[k as usize], k as usize))
            .collect();
        for (id, mut f, t) in q.iter_mut() {
            if let Some(&k) = slot.get(&id.0) {
                f.0 += st.force[k];
                if let Some(mut t) = t {
                    t.0 += st.torque[k];
                }
            }
        }
    }
    for &k in &st_touched {
        let k = k as usize;
        st.force[k] = DVec3::ZERO;
        st.torque[k] = DVec3::ZERO;
        st.marked[k] = false;
    }
    st.touched = st_touched;
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
