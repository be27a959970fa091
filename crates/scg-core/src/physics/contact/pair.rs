//! One particle pair: its state between steps and the kernel that turns the pair's
//! geometry into force and torques (pure). The contact geometry is computed once, then
//! the normal law ([`super::normal`]), the tangential spring with its Coulomb limit and
//! the rolling resistance ([`super::tangential`]), as LAMMPS's granular sub-models.
//!
//! The torque on each particle is r·n × F_t about its centre (paper eq. 3).

use glam::DVec3;

use super::model::{ContactModel, Geometry};
use super::tangential::{HertzPair, rolling_torque};
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

impl PairParams {
    /// The contact model of these constants.
    #[inline(always)]
    pub fn model(&self) -> ContactModel {
        ContactModel {
            law: self.law,
            tangential: self.tangential,
            e_eff: self.e_eff,
            g_eff: self.g_eff,
        }
    }
}

/// What a candidate pair carries besides its two indices, its minimum-image shift and
/// whether it touches (those are read every step for every pair and live in arrays of
/// their own, [`PairArrays`]): read and written only while the pair touches.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairState {
    /// Tangential history displacement, m (zero while not touching).
    pub history: DVec3,
    /// R*, m*, √R* and √(m*·K) of the pair.
    pub hertz: HertzPair,
}

/// The candidate pairs' states, structure of arrays, aligned with the neighbour list's
/// pairs (indices i < j into the gathered arrays). The overlap test of every pair reads
/// the list's pairs, `shift` and `touching` (9–33 bytes a pair); the rest only for the
/// pairs that touch.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PairArrays {
    /// In contact after the last force evaluation.
    pub touching: Vec<bool>,
    /// Whole periodic box lengths taken off x_j − x_i for the minimum image, m (empty in
    /// an open domain). Fixed between list builds: positions are not wrapped and move less
    /// than half the skin.
    pub shift: Vec<DVec3>,
    /// History and law constants.
    pub state: Vec<PairState>,
}

impl PairArrays {
    /// The shift of pair `k` (zero in an open domain).
    #[inline(always)]
    pub fn shift(&self, k: usize) -> DVec3 {
        shift_of(&self.shift, k)
    }

    /// The pairs in contact, `([i, j], state)`, in list order; `ij` are the list's pairs.
    pub fn in_contact<'a>(
        &'a self,
        ij: &'a [[u32; 2]],
    ) -> impl Iterator<Item = ([u32; 2], &'a PairState)> + 'a {
        (ij.iter().zip(&self.touching).zip(&self.state))
            .filter(|((_, t), _)| **t)
            .map(|((&p, _), s)| (p, s))
    }

    /// The pairs `range` as a mutable view; `ij` are the list's pairs (all of them).
    pub fn view<'a>(
        &'a mut self,
        ij: &'a [[u32; 2]],
        range: std::ops::Range<usize>,
    ) -> PairsMut<'a> {
        PairsMut {
            ij: &ij[range.clone()],
            touching: &mut self.touching[range.clone()],
            shift: if self.shift.is_empty() {
                &[]
            } else {
                &self.shift[range.clone()]
            },
            state: &mut self.state[range],
        }
    }
}

/// A run of [`PairArrays`] (one force slot's), mutable where the force stage writes.
#[derive(Debug)]
pub struct PairsMut<'a> {
    /// Particle indices [i, j], i < j.
    pub ij: &'a [[u32; 2]],
    /// In contact after the last force evaluation.
    pub touching: &'a mut [bool],
    /// Minimum-image shifts, m (empty in an open domain).
    pub shift: &'a [DVec3],
    /// History and law constants.
    pub state: &'a mut [PairState],
}

/// Shift `k` of `shift`, zero when there are none (an open domain).
#[inline(always)]
fn shift_of(shift: &[DVec3], k: usize) -> DVec3 {
    if shift.is_empty() {
        DVec3::ZERO
    } else {
        shift[k]
    }
}

impl PairsMut<'_> {
    /// The shift of pair `k` (zero in an open domain).
    #[inline(always)]
    pub fn shift(&self, k: usize) -> DVec3 {
        shift_of(self.shift, k)
    }

    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.ij.len()
    }

    /// True when there is no pair.
    pub fn is_empty(&self) -> bool {
        self.ij.is_empty()
    }

    /// The scalar kernel on pair `k`.
    #[inline(always)]
    pub fn kernel(
        &mut self,
        k: usize,
        b: &Bodies,
        par: &PairParams,
        dt: f64,
    ) -> Option<PairContact> {
        let shift = self.shift(k);
        pair_kernel(
            self.ij[k],
            shift,
            &mut self.touching[k],
            &mut self.state[k],
            b,
            par,
            dt,
        )
    }

    /// Split at pair `k`.
    pub fn split_at(self, k: usize) -> (Self, Self) {
        let (i0, i1) = self.ij.split_at(k);
        let (t0, t1) = self.touching.split_at_mut(k);
        let (h0, h1) = if self.shift.is_empty() {
            (self.shift, self.shift)
        } else {
            self.shift.split_at(k)
        };
        let (s0, s1) = self.state.split_at_mut(k);
        (
            PairsMut {
                ij: i0,
                touching: t0,
                shift: h0,
                state: s0,
            },
            PairsMut {
                ij: i1,
                touching: t1,
                shift: h1,
                state: s1,
            },
        )
    }
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

/// One per-particle vector column as the pair kernel reads it: the particle table's rows
/// followed by the ghost rows of a decomposed run, read in place from the two slices
/// (row k < `local.len()` is `local[k]`, the rows after are `ghost`'s), so that a step
/// copies neither.
#[derive(Clone, Copy, Debug, Default)]
pub struct Rows<'a> {
    /// The particle table's rows.
    pub local: &'a [DVec3],
    /// The ghost rows after them.
    pub ghost: &'a [DVec3],
}

impl<'a> Rows<'a> {
    /// The table's rows followed by `ghost`.
    pub fn new(local: &'a [DVec3], ghost: &'a [DVec3]) -> Self {
        Rows { local, ghost }
    }

    /// Number of rows.
    #[inline(always)]
    pub fn len(&self) -> usize {
        self.local.len() + self.ghost.len()
    }

    /// True when there is no row.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Pointer to row `k` (three consecutive f64).
    ///
    /// # Safety
    /// `k` must be below [`Rows::len`].
    #[inline(always)]
    pub unsafe fn ptr(&self, k: usize) -> *const f64 {
        let n = self.local.len();
        // SAFETY: k < len (the contract), so it indexes one of the two slices.
        unsafe {
            if k < n {
                self.local.as_ptr().add(k) as *const f64
            } else {
                self.ghost.as_ptr().add(k - n) as *const f64
            }
        }
    }
}

impl<'a> From<&'a [DVec3]> for Rows<'a> {
    fn from(local: &'a [DVec3]) -> Self {
        Rows { local, ghost: &[] }
    }
}

impl<'a> From<&'a Vec<DVec3>> for Rows<'a> {
    fn from(local: &'a Vec<DVec3>) -> Self {
        Rows { local, ghost: &[] }
    }
}

impl std::ops::Index<usize> for Rows<'_> {
    type Output = DVec3;
    #[inline(always)]
    fn index(&self, k: usize) -> &DVec3 {
        let n = self.local.len();
        if k < n {
            &self.local[k]
        } else {
            &self.ghost[k - n]
        }
    }
}

/// Per-particle inputs of the pair kernel.
pub struct Bodies<'a> {
    /// Centres, m.
    pub pos: Rows<'a>,
    /// Velocities, m/s.
    pub vel: Rows<'a>,
    /// Angular velocities, rad/s.
    pub omega: Rows<'a>,
    /// Radii, m.
    pub radius: &'a [f64],
}

/// The contact test of a pair at squared distance `dist2` (m²) whose radii add up to
/// `reach` (m): closer than the radii, and not at one point (two particles at the same
/// centre have no normal). A NaN distance counts as touching, so that it reaches the
/// state guard.
#[inline(always)]
pub fn within_reach(dist2: f64, reach: f64) -> bool {
    !(dist2 >= reach * reach || dist2 == 0.0)
}

impl PairContact {
    /// Add the rolling resistance ([`rolling_torque`], coefficient `mu_r`, 0 = off) for
    /// the normal force `fn_` (N) and the pair's R* (m): its torque on i, and the
    /// opposite on j.
    #[inline(always)]
    pub fn add_rolling(&mut self, mu_r: f64, fn_: f64, r_eff: f64, b: &Bodies) {
        if mu_r > 0.0 {
            let (i, j) = (self.i as usize, self.j as usize);
            let t = rolling_torque(mu_r, fn_.abs(), r_eff, b.omega[i] - b.omega[j]);
            self.torque_i += t;
            self.torque_j -= t;
        }
    }
}

/// The force, torques and new history of the pair `ij` = [i, j] with minimum-image
/// `shift` (pure); `None` when it does not touch. `touching` is the pair's contact flag
/// (in and out), `p` its history and constants.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn pair_kernel(
    [pi, pj]: [u32; 2],
    shift: DVec3,
    touching: &mut bool,
    p: &mut PairState,
    b: &Bodies,
    par: &PairParams,
    dt: f64,
) -> Option<PairContact> {
    let (i, j) = (pi as usize, pj as usize);
    let d = b.pos[j] - b.pos[i] - shift;
    let (ri, rj) = (b.radius[i], b.radius[j]);
    let dist2 = d.length_squared();
    let reach = ri + rj;
    let was = *touching;
    if !within_reach(dist2, reach) {
        if was {
            *touching = false;
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
    let g = Geometry {
        normal: n,
        overlap: delta,
        separation: -vn_approach,
        slip: v_rel - vn_approach * n,
        r_eff: pc.r_eff,
        m_eff: pc.m_eff,
    };
    // The common case (Hertz–Mindlin) in one pass from the pair's constants.
    let r = par
        .model()
        .response(&g, Some((pc, par.mindlin_c)), p.history, dt);
    let fn_ = r.normal;
    let mut c = PairContact {
        i: pi,
        j: pj,
        started: !was,
        approach: vn_approach,
        force: -fn_ * n,
        ..Default::default()
    };
    if let Some(u) = r.tangential {
        p.history = u.history;
        c.force += u.force;
        // Torque about each centre from the force at its contact point (r·n × F_t).
        let nf = n.cross(u.force);
        c.torque_i = ri * nf;
        c.torque_j = rj * nf;
    }
    c.add_rolling(tl.rolling, fn_, pc.r_eff, b);
    *touching = true;
    Some(c)
}
