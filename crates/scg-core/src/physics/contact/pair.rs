//! One particle pair: its state between steps and the kernel that turns the pair's
//! geometry into force and torques (pure). The contact geometry is computed once, then
//! the normal law ([`super::normal`]), the tangential spring with its Coulomb limit and
//! the rolling resistance ([`super::tangential`]), as LAMMPS's granular sub-models.
//!
//! The torque on each particle is r·n × F_t about its centre (paper eq. 3).

use glam::DVec3;

use super::tangential::{
    HertzPair, TangentialStiffness, hertz_mindlin_pair, rolling_torque, tangential_force,
};
use super::{NormalLaw, TangentialLaw};
use crate::physics::periodic::PeriodicBox;

/// The constants of the pair law, derived once from the scene's contact settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairParams {
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
    /// √(6·G*/E*), for [`super::tangential::hertz_mindlin_pair`].
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
    /// Normal approach speed of the contact points, m/s (positive when closing).
    pub approach: f64,
    /// Force on i, N (the force on j is exactly −force).
    pub force: DVec3,
    /// Torque on i, N·m.
    pub torque_i: DVec3,
    /// Torque on j, N·m.
    pub torque_j: DVec3,
}

/// Per-particle inputs of the pair kernel.
pub struct Bodies<'a> {
    /// Centres, m.
    pub pos: &'a [DVec3],
    /// Velocities, m/s.
    pub vel: &'a [DVec3],
    /// Angular velocities, rad/s.
    pub omega: &'a [DVec3],
    /// Radii, m.
    pub radius: &'a [f64],
}

/// The force, torques and new history of one pair (pure); `None` when it does not touch.
#[inline(always)]
pub fn pair_kernel(
    p: &mut PairState,
    b: &Bodies,
    par: &PairParams,
    dt: f64,
) -> Option<PairContact> {
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
        approach: vn_approach,
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
