//! The one contact model of particle pairs and walls: the contact geometry is formed
//! once — unit normal, overlap, effective radius and mass, and the relative velocity of
//! the contact points *including the other body's own velocity there* (a moving wall's) —
//! then normal → damping → tangential → rolling as composable pure parts, as LAMMPS's
//! `pair granular` composes its sub-models.
//!
//! A pair's geometry is formed by [`super::pair::pair_kernel`] (its Hertz–Mindlin fast
//! path uses the pair's precomputed [`HertzPair`] constants; the four-lane kernel
//! [`super::lanes`] is that path four pairs at a time, bit-tested against it); a wall's by
//! [`wall_geometry`]. Both then take [`ContactModel::response`].

use glam::DVec3;

use super::tangential::{
    HertzPair, TangentialStiffness, TangentialUpdate, hertz_mindlin_pair, rolling_torque,
    tangential_force,
};
use super::{NormalLaw, TangentialLaw};

/// The constants of one contact law: normal and tangential laws and effective moduli.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactModel {
    /// Normal law (with its damping).
    pub law: NormalLaw,
    /// Tangential law (stiffness rule, damping, Coulomb and rolling friction).
    pub tangential: TangentialLaw,
    /// Effective modulus E*, Pa.
    pub e_eff: f64,
    /// Effective shear modulus G*, Pa.
    pub g_eff: f64,
}

/// The geometry of one contact, formed once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Geometry {
    /// Unit normal. Its sign is the caller's (pairs: from i to j; walls: from the wall
    /// toward the centre); the tangential part is the same either way.
    pub normal: DVec3,
    /// Overlap δ, m.
    pub overlap: f64,
    /// Normal separation speed of the contact points, m/s (negative when closing): the
    /// normal laws' `vn`.
    pub separation: f64,
    /// Tangential relative velocity of this body's contact point against the other's,
    /// m/s (in the tangent plane).
    pub slip: DVec3,
    /// Effective radius R*, m.
    pub r_eff: f64,
    /// Effective mass m*, kg.
    pub m_eff: f64,
}

/// What the model gives for one contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Response {
    /// Normal force, N (signed: repulsive positive).
    pub normal: f64,
    /// The tangential update (`None` without sliding friction): force on this body and
    /// the new history.
    pub tangential: Option<TangentialUpdate>,
}

impl ContactModel {
    /// Normal force and the tangential spring's stiffness and dashpot for `g`: the normal
    /// law with its damping, then the tangential stiffness rule. With `hertz` (a pair's
    /// precomputed constants) the Hertz–Mindlin case takes its one-pass form
    /// ([`hertz_mindlin_pair`]); otherwise each law in turn.
    #[inline(always)]
    pub fn normal_and_springs(&self, g: &Geometry, hertz: Option<(&HertzPair, f64)>) -> [f64; 3] {
        let tl = &self.tangential;
        match (self.law, tl.stiffness, hertz) {
            (NormalLaw::Hertz { gamma }, TangentialStiffness::Mindlin, Some((pc, c))) => {
                let (fn_, kt, eta) = hertz_mindlin_pair(
                    g.overlap,
                    g.separation,
                    pc,
                    self.e_eff,
                    self.g_eff,
                    gamma,
                    tl.damping,
                    c,
                );
                [fn_, kt, eta]
            }
            _ => {
                let (fn_, kn) =
                    self.law
                        .force(g.overlap, g.separation, self.e_eff, g.r_eff, g.m_eff);
                let kt = tl.stiffness(self.g_eff, g.r_eff, g.overlap, kn);
                [fn_, kt, tl.damping * (g.m_eff * kt).sqrt()]
            }
        }
    }

    /// The tangential spring–dashpot with its Coulomb limit for the normal force `fn_`
    /// and springs `kt`, `eta` ([`ContactModel::normal_and_springs`]), from the history
    /// `prev` (m); `None` without sliding friction.
    #[inline(always)]
    pub fn tangential(
        &self,
        g: &Geometry,
        [fn_, kt, eta]: [f64; 3],
        prev: DVec3,
        dt: f64,
    ) -> Option<TangentialUpdate> {
        let tl = &self.tangential;
        (tl.friction > 0.0)
            .then(|| tangential_force(prev, g.normal, g.slip, kt, eta, tl.friction * fn_.abs(), dt))
    }

    /// Rolling-resistance torque on the body spinning at `omega_rel` relative to the
    /// other, for the normal force `fn_` (zero without rolling friction), N·m.
    #[inline(always)]
    pub fn rolling(&self, fn_: f64, r_eff: f64, omega_rel: DVec3) -> DVec3 {
        let mu_r = self.tangential.rolling;
        if mu_r > 0.0 {
            rolling_torque(mu_r, fn_.abs(), r_eff, omega_rel)
        } else {
            DVec3::ZERO
        }
    }

    /// Normal force and tangential update of the contact `g` (normal → damping →
    /// tangential; rolling is [`ContactModel::rolling`], on the caller's relative spin).
    #[inline(always)]
    pub fn response(
        &self,
        g: &Geometry,
        hertz: Option<(&HertzPair, f64)>,
        prev: DVec3,
        dt: f64,
    ) -> Response {
        let springs = self.normal_and_springs(g, hertz);
        Response {
            normal: springs[0],
            tangential: self.tangential(g, springs, prev, dt),
        }
    }
}

/// The geometry of a sphere of radius `r` (m) and mass `m` (kg) touching a wall: `normal`
/// from the wall toward the centre, `overlap` (m), the sphere's velocity `v` (m/s) and
/// spin `w` (rad/s), and the wall's own velocity at the contact point `wall_velocity`
/// (m/s; zero for a wall at rest). The contact point is at −r·n from the centre; the
/// wall is a body of infinite radius and mass (R* = r, m* = m).
#[inline(always)]
pub fn wall_geometry(
    normal: DVec3,
    overlap: f64,
    r: f64,
    m: f64,
    v: DVec3,
    w: DVec3,
    wall_velocity: DVec3,
) -> Geometry {
    let n = normal;
    let vc = v + w.cross(-r * n) - wall_velocity;
    let vn = vc.dot(n);
    Geometry {
        normal: n,
        overlap,
        separation: vn,
        slip: vc - vn * n,
        r_eff: r,
        m_eff: m,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::contact::Material;

    fn model() -> ContactModel {
        let mat = Material {
            youngs_modulus: 1e7,
            poisson_ratio: 0.3,
            restitution: 0.8,
            friction: 0.4,
        };
        let law = NormalLaw::hertz(mat.restitution);
        ContactModel {
            law,
            tangential: TangentialLaw::new(law, mat.friction, 0.05),
            e_eff: mat.effective_modulus(),
            g_eff: mat.effective_shear_modulus(),
        }
    }

    /// A wall moving at V is a wall at rest seen by a sphere moving at v − V: the same
    /// geometry and response, to the bit (the wall's velocity only enters the contact
    /// point's relative velocity).
    #[test]
    fn a_moving_wall_is_a_resting_wall_in_its_frame() {
        let (n, delta, r, m) = (DVec3::new(0.0, 0.6, 0.8), 2e-6, 5e-4, 1e-6);
        let (v, w, vw) = (
            DVec3::new(0.3, -1.0, -2.0),
            DVec3::new(5.0, -3.0, 1.0),
            DVec3::new(0.25, 0.5, -0.125),
        );
        let moving = wall_geometry(n, delta, r, m, v, w, vw);
        let resting = wall_geometry(n, delta, r, m, v - vw, w, DVec3::ZERO);
        for (a, b) in [
            (moving.separation, resting.separation),
            (moving.slip.x, resting.slip.x),
            (moving.slip.y, resting.slip.y),
        ] {
            assert!((a - b).abs() <= 1e-15 * (1.0 + b.abs()), "{a} vs {b}");
        }
        let mdl = model();
        let (ra, rb) = (
            mdl.response(&moving, None, DVec3::ZERO, 1e-7),
            mdl.response(&resting, None, DVec3::ZERO, 1e-7),
        );
        assert!((ra.normal - rb.normal).abs() <= 1e-12 * rb.normal.abs());
        let (ta, tb) = (ra.tangential.unwrap(), rb.tangential.unwrap());
        assert!((ta.force - tb.force).length() <= 1e-12 * tb.force.length());
        // A wall at rest: the zero velocity changes nothing, to the bit.
        let still = wall_geometry(n, delta, r, m, v, w, DVec3::ZERO);
        let vc = v + w.cross(-r * n);
        assert_eq!(still.separation.to_bits(), vc.dot(n).to_bits());
    }
}
