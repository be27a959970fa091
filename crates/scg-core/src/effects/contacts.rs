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
    /// Entities in id order.
    pub order: Vec<Entity>,
    /// Ids in order.
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
        Entity,
        &'static ParticleId,
        &'static GroupId,
        &'static Position,
        &'static Velocity,
        Option<&'static AngularVelocity>,
        &'static Diameter,
        &'static Mass,
    ),
>;

/// Gather the particles in id order and rebuild the neighbour list when needed.
pub fn maintain_neighbour_list(mut state: ResMut<ContactState>, q: GatherQuery) {
    let st = &mut *state;
    let mut rows: Vec<_> = q.iter().collect();
    rows.sort_unstable_by_key(|r| r.1.0);
    let same_set =
        rows.len() == st.ids.len() && rows.iter().zip(&st.ids).all(|(r, id)| r.1.0 == *id);
    let old_ids = std::mem::take(&mut st.ids);
    st.order.clear();
    st.group.clear();
    st.pos.clear();
    st.vel.clear();
    st.omega.clear();
    st.radius.clear();
    st.mass.clear();
    for (e, id, g, x, v, w, d, m) in rows {
        st.order.push(e);
        st.ids.push(id.0);
        st.group.push(g.0);
        st.pos.push(x.0);
        st.vel.push(v.0);
        st.omega.push(w.map_or(DVec3::ZERO, |w| w.0));
        st.radius.push(0.5 * d.0);
        st.mass.push(m.0);
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
    // Carry the history of the old pairs over to the new list, matched by (id_i, id_j);
    // both lists are sorted by id pairs since indices follow ids.
    let old = std::mem::take(&mut st.pairs);
    let key_old = |p: &PairState| (old_ids[p.i as usize], old_ids[p.j as usize]);
    let mut k = 0;
    let mut pairs = Vec::with_capacity(st.list.pairs.len());
    for &[i, j] in &st.list.pairs {
        let key = (st.ids[i as usize], st.ids[j as usize]);
        while k < old.len() && key_old(&old[k]) < key {
            k += 1;
        }
        let mut p = PairState {
            i,
            j,
            ..Default::default()
        };
        if k < old.len() && key_old(&old[k]) == key {
            p.history = old[k].history;
            p.touching = old[k].touching;
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
    mut q: Query<(&mut Force, Option<&mut Torque>)>,
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
    let n = st.pos.len();
    st.force.clear();
    st.force.resize(n, DVec3::ZERO);
    st.torque.clear();
    st.torque.resize(n, DVec3::ZERO);
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
        if p.started {
            for g in [st.group[i], st.group[j]] {
                if let Some(c) = tally.collisions.get_mut(g as usize) {
                    *c += 1;
                }
            }
        }
    }
    st.active = active;
    for (k, e) in st.order.iter().enumerate() {
        if let Ok((mut f, t)) = q.get_mut(*e) {
            f.0 += st.force[k];
            if let Some(mut t) = t {
                t.0 += st.torque[k];
            }
        }
    }
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
