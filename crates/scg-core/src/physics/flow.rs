//! Prescribed fluid: its properties and its velocity field (one-way coupling).

use bevy_ecs::prelude::Resource;
use glam::{DMat3, DVec3};

use super::lane::{Lane3, Real};

/// Fluid properties (resource).
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct Fluid {
    /// Density ρ_f, kg/m³.
    pub density: f64,
    /// Dynamic viscosity μ, Pa·s.
    pub viscosity: f64,
}

/// A rotating flow about an axis: a forced vortex u_θ = ω·r plus a flow toward the axis
/// u_r = −k·ω·r (paper Section 4; k is `inflow_ratio`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vortex {
    /// A point on the axis, m.
    pub center: DVec3,
    /// Unit vector along the axis; the rotation is right-handed about it.
    pub axis: DVec3,
    /// Angular speed ω, rad/s.
    pub omega: f64,
    /// Inflow speed toward the axis as a fraction of the local tangential speed, dimensionless.
    pub inflow_ratio: f64,
}

impl Vortex {
    /// Component of `x − center` perpendicular to the axis (the radial vector), m.
    #[inline(always)]
    pub fn radial(&self, x: DVec3) -> DVec3 {
        self.radial_of(x)
    }

    /// Fluid velocity at `x`, m/s. Linear in the radial vector, so r = 0 gives exactly zero.
    #[inline]
    pub fn velocity(&self, x: DVec3) -> DVec3 {
        self.velocity_of(x)
    }

    /// The velocity gradient J (column k = ∂u/∂x_k), 1/s: u = J·(x − c), constant.
    pub fn gradient(&self) -> DMat3 {
        // u = ω·(a × r − k·r), r = P·(x − c), P = I − a·aᵀ; a × (P y) = a × y.
        let a = self.axis;
        let cross = DMat3::from_cols(a.cross(DVec3::X), a.cross(DVec3::Y), a.cross(DVec3::Z));
        let proj = DMat3::IDENTITY - DMat3::from_cols(a * a.x, a * a.y, a * a.z);
        self.omega * (cross - self.inflow_ratio * proj)
    }

    /// [`Vortex::radial`] of one point or four lanes ([`Lane3`]): rel − (rel·a)·a.
    #[inline(always)]
    pub fn radial_of<V: Lane3>(&self, x: V) -> V {
        let rel = x - V::splat(self.center);
        let axis = V::splat(self.axis);
        rel - axis.scale(rel.dot(axis))
    }

    /// [`Vortex::velocity`] of one point or four lanes: ω·(a × r − k·r).
    #[inline(always)]
    pub fn velocity_of<V: Lane3>(&self, x: V) -> V {
        let r = self.radial_of(x);
        let axis = V::splat(self.axis);
        (axis.cross(r) - r.scale(V::R::splat(self.inflow_ratio))).scale(V::R::splat(self.omega))
    }

    /// The paper's classifier (Section 5) of one point or four lanes: this vortex, plus
    /// `axial_speed` (m/s, along the axis) where the distance from the axis is below
    /// `nozzle_radius` (m).
    #[inline(always)]
    pub fn classifier_of<V: Lane3>(&self, nozzle_radius: f64, axial_speed: f64, x: V) -> V {
        let r = self.radial_of(x);
        let axis = V::splat(self.axis);
        let u = (axis.cross(r) - r.scale(V::R::splat(self.inflow_ratio)))
            .scale(V::R::splat(self.omega));
        let inside = V::R::splat(nozzle_radius * nozzle_radius).gt(r.dot(r));
        u.or_where(inside, u + V::splat(axial_speed * self.axis))
    }
}

/// The flow field (resource).
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub enum FlowField {
    /// Fluid at rest.
    Still,
    /// The same velocity everywhere, m/s.
    Uniform(DVec3),
    /// Forced vortex with inflow toward the axis.
    Vortex(Vortex),
    /// The classifier of the paper's Section 5: a vortex, plus a constant axial velocity
    /// wherever the distance from the axis is below the outlet nozzle radius.
    Classifier {
        /// The rotating part.
        vortex: Vortex,
        /// Radius of the outlet nozzle, m.
        nozzle_radius: f64,
        /// Axial velocity inside the nozzle radius, m/s, signed along `vortex.axis`.
        axial_speed: f64,
    },
}

impl FlowField {
    /// The rotating part of a vortex or classifier flow, if the flow has one.
    pub fn vortex(&self) -> Option<&Vortex> {
        match self {
            FlowField::Vortex(v) | FlowField::Classifier { vortex: v, .. } => Some(v),
            FlowField::Still | FlowField::Uniform(_) => None,
        }
    }

    /// Fluid velocity at `x`, m/s. Finite for every finite `x`, including on an axis.
    #[inline(always)]
    pub fn velocity(&self, x: DVec3) -> DVec3 {
        self.velocity_of(x)
    }

    /// [`FlowField::velocity`] of one point or four lanes ([`Lane3`]): the one formula
    /// of every analytic flow, for the scalar step and the four-lane kernels alike.
    #[inline(always)]
    pub fn velocity_of<V: Lane3>(&self, x: V) -> V {
        match self {
            FlowField::Still => V::splat(DVec3::ZERO),
            FlowField::Uniform(u) => V::splat(*u),
            FlowField::Vortex(v) => v.velocity_of(x),
            FlowField::Classifier {
                vortex,
                nozzle_radius,
                axial_speed,
            } => vortex.classifier_of(*nozzle_radius, *axial_speed, x),
        }
    }

    /// The field as u(x) = M·x + b when it is affine (still, uniform, vortex), for fast
    /// kernels; `None` for the classifier (its nozzle makes it piecewise).
    pub fn affine(&self) -> Option<Affine> {
        match *self {
            FlowField::Still => Some(Affine {
                m: DMat3::ZERO,
                b: DVec3::ZERO,
            }),
            FlowField::Uniform(u) => Some(Affine {
                m: DMat3::ZERO,
                b: u,
            }),
            FlowField::Vortex(v) => {
                let m = v.gradient();
                Some(Affine {
                    m,
                    b: -(m * v.center),
                })
            }
            FlowField::Classifier { .. } => None,
        }
    }

    /// The velocity gradient at `x` (column k = ∂u/∂x_k), 1/s: zero for still and
    /// uniform flows, the vortex's everywhere else (the classifier's axial speed inside
    /// its nozzle is constant: its jump at the nozzle radius is not a gradient).
    pub fn gradient(&self, _x: DVec3) -> DMat3 {
        match self {
            FlowField::Still | FlowField::Uniform(_) => DMat3::ZERO,
            FlowField::Vortex(v) | FlowField::Classifier { vortex: v, .. } => v.gradient(),
        }
    }

    /// Characteristic rate of change of the flow along a path, 1/s (ω for rotating flows,
    /// 0 for uniform ones). Used by the `auto` time step.
    pub fn rate(&self) -> f64 {
        match self {
            FlowField::Still | FlowField::Uniform(_) => 0.0,
            FlowField::Vortex(v) | FlowField::Classifier { vortex: v, .. } => {
                v.omega.abs() * (1.0 + v.inflow_ratio.abs())
            }
        }
    }
}

/// An affine velocity field u(x) = M·x + b.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    /// Velocity gradient M, 1/s.
    pub m: DMat3,
    /// Velocity at the origin, m/s.
    pub b: DVec3,
}

impl Affine {
    /// True when the field has no z component and does not depend on z.
    pub fn is_planar_z(&self) -> bool {
        self.b.z == 0.0
            && self.m.z_axis == DVec3::ZERO
            && self.m.x_axis.z == 0.0
            && self.m.y_axis.z == 0.0
    }

    /// Fluid velocity at `x`, m/s.
    #[inline(always)]
    pub fn velocity(&self, x: DVec3) -> DVec3 {
        self.velocity_of(x)
    }

    /// [`Affine::velocity`] of one point or four lanes: as glam's `DMat3 * DVec3`,
    /// ((X·x + Y·y) + Z·z), then + b.
    #[inline(always)]
    pub fn velocity_of<V: Lane3>(&self, x: V) -> V {
        let [px, py, pz] = x.xyz();
        V::splat(self.m.x_axis).scale(px)
            + V::splat(self.m.y_axis).scale(py)
            + V::splat(self.m.z_axis).scale(pz)
            + V::splat(self.b)
    }
}

/// Convert revolutions per minute to rad/s.
pub fn rpm_to_rad_per_s(rpm: f64) -> f64 {
    rpm * 2.0 * std::f64::consts::PI / 60.0
}

/// Convert rad/s to revolutions per minute.
pub fn rad_per_s_to_rpm(omega: f64) -> f64 {
    omega * 60.0 / (2.0 * std::f64::consts::PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vortex() -> Vortex {
        Vortex {
            center: DVec3::ZERO,
            axis: DVec3::Z,
            omega: rpm_to_rad_per_s(300.0),
            inflow_ratio: 0.1,
        }
    }

    #[test]
    fn vortex_speeds() {
        let v = vortex();
        let x = DVec3::new(2e-4, 0.0, 7.0);
        let u = v.velocity(x);
        // tangential +y at ω·r, radial −x at 0.1·ω·r, no axial part.
        assert!((u.y - v.omega * 2e-4).abs() < 1e-18);
        assert!((u.x + 0.1 * v.omega * 2e-4).abs() < 1e-18);
        assert_eq!(u.z, 0.0);
    }

    #[test]
    fn affine_form_matches_the_field() {
        let v = Vortex {
            center: DVec3::new(1e-3, -2e-3, 0.5),
            axis: DVec3::new(0.3, -0.2, 0.9).normalize(),
            omega: 523.6,
            inflow_ratio: 5.0,
        };
        for f in [
            FlowField::Vortex(v),
            FlowField::Uniform(DVec3::new(1.0, 2.0, 3.0)),
            FlowField::Still,
        ] {
            let aff = f.affine().unwrap();
            for x in [
                DVec3::new(3e-3, 1e-3, 0.2),
                DVec3::ZERO,
                v.center,
                DVec3::new(-0.1, 0.2, 7.0),
            ] {
                let (a, b) = (aff.velocity(x), f.velocity(x));
                assert!(
                    (a - b).length() <= 1e-12 * (1.0 + b.length()),
                    "{f:?} at {x}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn axis_is_finite_and_still() {
        let v = vortex();
        assert_eq!(v.velocity(DVec3::new(0.0, 0.0, 3.0)), DVec3::ZERO);
        let c = FlowField::Classifier {
            vortex: v,
            nozzle_radius: 1e-3,
            axial_speed: 1.0,
        };
        assert_eq!(c.velocity(DVec3::new(0.0, 0.0, -1.0)), DVec3::Z);
        assert_eq!(c.velocity(DVec3::new(2e-3, 0.0, 0.0)).z, 0.0);
    }
}
