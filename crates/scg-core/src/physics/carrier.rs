//! The carrier-velocity seam: "the fluid velocity this particle sees at x", and the one
//! per-particle step every integration scheme takes through it.
//!
//! A [`Carrier`] gives the fluid velocity at a point: the analytic flows
//! ([`FlowField`], ignoring the cell) and the flows on CFD meshes
//! ([`crate::physics::mesh_flow::MeshFlow`], walking from the particle's cell) implement it.
//! A modifier adds to it: [`WithOffset`] adds a particle's own offset (its
//! [`crate::components::CarrierOffset`], written by a carrier-modifier stage such as
//! turbulent dispersion) to every evaluation of that particle's step — as OpenFOAM's
//! `DispersionModel` adds its fluctuation where the carrier velocity is formed.
//!
//! [`advance`] is the per-particle step of every scheme (exponential midpoint with Stokes
//! factors or a Reynolds-dependent response time, sub-stepped semi-implicit Euler,
//! ballistic) for any carrier, so the analytic and the mesh flows share one integration
//! path; the mesh stage lands the result on the mesh afterwards (patches, walls). The
//! Stokes and ballistic fast paths of [`crate::stages::motion`] are specialisations of
//! the exponential arm with the same operations (their bit tests keep them so).

use glam::{DMat3, DVec3};

use super::drag::{DragLaw, particle_reynolds};
pub use super::drag_factors::DragFactors;
use super::flow::{FlowField, Fluid};
use super::forces::StepForces;
use super::integrate::{
    Integrator, explicit_euler, explicit_substeps, exponential_drift, linear_kick,
};
use crate::components::{FluidCoupling, StokesFactors};

/// Where a carrier last found a particle: its mesh cell and, as a hint that changes no
/// result, the tetrahedron record of the cell's decomposition that held it
/// ([`scg_mesh::NO_TET`]: unknown). Analytic flows carry it through unchanged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Place {
    /// The mesh cell (or a departure marker, see `mesh_flow::hint`).
    pub cell: u32,
    /// The tetrahedron hint.
    pub tet: u32,
}

impl Place {
    /// Cell `cell`, no tetrahedron hint.
    #[inline]
    pub const fn cell(cell: u32) -> Self {
        Place {
            cell,
            tet: scg_mesh::NO_TET,
        }
    }
}

/// The fluid velocity a particle sees.
pub trait Carrier: Sync {
    /// The fluid velocity at `x` (m/s) for a particle last found at `place`, and where `x`
    /// is (analytic flows return `place` unchanged; a mesh flow returns the cell and
    /// tetrahedron its walk ended in).
    fn at(&self, place: Place, x: DVec3) -> (DVec3, Place);

    /// The velocity gradient at `x` in `cell` (the cell [`Carrier::at`] returned), column
    /// k = ∂u/∂x_k, 1/s: read only by the opt-in forces ([`crate::physics::forces`]).
    fn gradient(&self, cell: u32, x: DVec3) -> DMat3;
}

impl Carrier for FlowField {
    #[inline(always)]
    fn at(&self, place: Place, x: DVec3) -> (DVec3, Place) {
        (self.velocity(x), place)
    }

    fn gradient(&self, _cell: u32, x: DVec3) -> DMat3 {
        FlowField::gradient(self, x)
    }
}

impl<C: Carrier + ?Sized> Carrier for &C {
    #[inline(always)]
    fn at(&self, place: Place, x: DVec3) -> (DVec3, Place) {
        (**self).at(place, x)
    }

    fn gradient(&self, cell: u32, x: DVec3) -> DMat3 {
        (**self).gradient(cell, x)
    }
}

/// A carrier plus one particle's offset `du` (m/s), added to every evaluation: the slot
/// where a modifier (turbulent dispersion) enters.
#[derive(Clone, Copy, Debug)]
pub struct WithOffset<C> {
    /// The mean carrier.
    pub inner: C,
    /// Added velocity, m/s.
    pub du: DVec3,
}

impl<C: Carrier> Carrier for WithOffset<C> {
    #[inline(always)]
    fn at(&self, place: Place, x: DVec3) -> (DVec3, Place) {
        let (u, p) = self.inner.at(place, x);
        (u + self.du, p)
    }

    /// The mean carrier's (the offset is uniform over the step).
    fn gradient(&self, cell: u32, x: DVec3) -> DMat3 {
        self.inner.gradient(cell, x)
    }
}

/// Response time under `law` for the slip speed `slip` (m/s), s: the particle's Stokes τ
/// divided by the law's correction at the particle Reynolds number of its
/// `reynolds_diameter` (its drag diameter, or an SCG particle's original diameter).
#[inline]
pub fn effective_tau(law: DragLaw, fc: &FluidCoupling, fluid: &Fluid, slip: f64) -> f64 {
    let re = particle_reynolds(fc.reynolds_diameter, slip, fluid.density, fluid.viscosity);
    fc.tau / law.correction(re)
}

/// What every particle's step reads besides the particle: the step, the drag law (`None`:
/// no fluid drag), the integrator and the fluid.
#[derive(Clone, Copy, Debug)]
pub struct Scheme {
    /// Time step, s.
    pub dt: f64,
    /// Drag law.
    pub law: Option<DragLaw>,
    /// Integrator.
    pub integrator: Integrator,
    /// Fluid (for the Reynolds number; a placeholder without one).
    pub fluid: Fluid,
    /// The opt-in forces evaluated each step (pressure gradient, added mass, lift), if
    /// any: a constant acceleration over the step, from the mid-step point.
    pub forces: Option<StepForces>,
}

impl Scheme {
    /// The fluid a scheme uses when the scene has none (only a drag-free step runs then).
    pub const NO_FLUID: Fluid = Fluid {
        density: 0.0,
        viscosity: 1.0,
    };

    /// The drag law when the step is the Reynolds-dependent exponential one (τ from the
    /// slip at the start: [`start_reynolds`], [`DragFactors`]).
    pub fn reynolds_law(&self) -> Option<DragLaw> {
        match (self.law, self.integrator) {
            (None | Some(DragLaw::Stokes), _) | (_, Integrator::Explicit) => None,
            (Some(law), _) => Some(law),
        }
    }

    /// True when the step reads the fluid velocity at its start (the explicit scheme, the
    /// Reynolds-dependent laws), so a caller that knows it may pass it to [`advance`].
    pub fn reads_start(&self) -> bool {
        match (self.law, self.integrator) {
            (Some(_), Integrator::Explicit) => true,
            (None | Some(DragLaw::Stokes), _) => false,
            (Some(_), _) => true,
        }
    }
}

/// The particle Reynolds number [`advance`]'s Reynolds-dependent exponential step takes its
/// τ from (the slip at the start, after the wall force's kick), given the carrier velocity
/// `u0` at `b.x`; `None` when the step is not such a step (the explicit scheme, Stokes
/// drag, no drag).
#[inline(always)]
pub fn start_reynolds(s: &Scheme, b: &Body, u0: DVec3) -> Option<f64> {
    s.reynolds_law()?;
    Some(slip_reynolds(s, b.fc, u0, kicked(s, b)))
}

/// The velocity after the wall force's kick (m/s): the exponential schemes' start.
#[inline(always)]
fn kicked(s: &Scheme, b: &Body) -> DVec3 {
    match b.force {
        Some(f) => linear_kick(b.v, f, b.m, s.dt),
        None => b.v,
    }
}

/// The particle Reynolds number of the slip `u0 − vk` (velocities in m/s).
#[inline(always)]
fn slip_reynolds(s: &Scheme, fc: &FluidCoupling, u0: DVec3, vk: DVec3) -> f64 {
    particle_reynolds(
        fc.reynolds_diameter,
        (u0 - vk).length(),
        s.fluid.density,
        s.fluid.viscosity,
    )
}

/// One particle as a step reads it: position (m), velocity (m/s), mass (kg), the wall
/// force of the step (N, with walls), the body acceleration (m/s²), its fluid coupling and
/// Stokes factors.
#[derive(Clone, Copy, Debug)]
pub struct Body<'a> {
    /// Position, m.
    pub x: DVec3,
    /// Velocity, m/s.
    pub v: DVec3,
    /// Mass, kg.
    pub m: f64,
    /// Wall force of the step, N.
    pub force: Option<DVec3>,
    /// Body acceleration, m/s².
    pub a: DVec3,
    /// Fluid coupling (τ, drag diameter).
    pub fc: &'a FluidCoupling,
    /// Exponential factors of τ for the scheme's dt.
    pub sf: &'a StokesFactors,
}

/// One step of `b` in `carrier` (see the module documentation): the new position and
/// velocity and the place the carrier last found (the mid-step point's for the
/// exponential schemes, the last sub-step's for the explicit one). `start`: the carrier
/// velocity at `b.x` when the caller knows it (it must be what `carrier.at(cell, b.x)`
/// gives). `drag`: the Reynolds-dependent exponential step's factors when the caller
/// computed them for a block of particles ([`start_reynolds`], then
/// [`crate::physics::drag_factors::DragBlock`]: the same operations, so the same bits).
#[inline(always)]
pub fn advance<C: Carrier>(
    s: &Scheme,
    carrier: &C,
    b: &Body,
    cell: Place,
    start: Option<DVec3>,
    drag: Option<DragFactors>,
) -> (DVec3, DVec3, Place) {
    let dt = s.dt;
    let (x0, v0, fc) = (b.x, b.v, b.fc);
    let u_start = |h: Place, x: DVec3| start.unwrap_or_else(|| carrier.at(h, x).0);
    match (s.law, s.integrator) {
        (Some(law), Integrator::Explicit) => {
            let mut acc = b.a;
            if let Some(f) = b.force {
                acc += f / b.m;
            }
            let (mut xi, mut vi, mut h) = (x0, v0, cell);
            let u0 = u_start(h, xi);
            let tau0 = effective_tau(law, fc, &s.fluid, (u0 - vi).length());
            let n = explicit_substeps(tau0, dt);
            let step = dt / n as f64;
            for _ in 0..n {
                let (u, hu) = carrier.at(h, xi);
                h = hu;
                let tau = effective_tau(law, fc, &s.fluid, (u - vi).length());
                let a = match &s.forces {
                    None => acc,
                    Some(f) => acc + f.acceleration(fc, xi, u, carrier.gradient(h.cell, xi), vi),
                };
                (xi, vi) = explicit_euler(xi, vi, u, a, tau, step);
            }
            (xi, vi, h)
        }
        _ => {
            let vk = kicked(s, b);
            let xm = x0 + vk * (0.5 * dt);
            let (u, hm) = carrier.at(cell, xm);
            // the opt-in forces at the mid-step point, with the velocity there: relaxed
            // halfway toward u under the body acceleration and, in a second pass, the
            // forces themselves (Coriolis and lift depend on it: with the relaxed
            // velocity alone the step would be first order in them)
            let a = match &s.forces {
                None => b.a,
                Some(f) => {
                    let relax = (-0.5 * dt / fc.tau).exp();
                    let gain = -fc.tau * (-0.5 * dt / fc.tau).exp_m1();
                    let j = carrier.gradient(hm.cell, xm);
                    let vm = u + (vk - u) * relax + b.a * gain;
                    let first = f.acceleration(fc, xm, u, j, vm);
                    b.a + f.acceleration(fc, xm, u, j, vm + first * gain)
                }
            };
            let (x1, v1) = match s.law {
                None => exponential_drift(x0, vk, u, a, f64::INFINITY, 0.0, dt, dt),
                Some(DragLaw::Stokes) => {
                    exponential_drift(x0, vk, u, a, fc.tau, b.sf.gain, b.sf.relax, dt)
                }
                Some(law) => {
                    let DragFactors { tau, gain, relax } = drag.unwrap_or_else(|| {
                        let re = slip_reynolds(s, fc, u_start(cell, x0), vk);
                        DragFactors::new(fc.tau, law.correction(re), dt)
                    });
                    exponential_drift(x0, vk, u, a, tau, gain, relax, dt)
                }
            };
            (x1, v1, hm)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body<'a>(fc: &'a FluidCoupling, sf: &'a StokesFactors) -> Body<'a> {
        Body {
            x: DVec3::new(0.1, -0.2, 0.3),
            v: DVec3::new(1.0, 2.0, -3.0),
            m: 1e-9,
            force: None,
            a: DVec3::new(0.0, 0.0, -9.81),
            fc,
            sf,
        }
    }

    /// In a uniform flow u with an offset δ, every scheme relaxes toward u + δ + a·τ as
    /// the exact solution of dv/dt = (u + δ − v)/τ + a says (Stokes drag: exactly the
    /// drift in the uniform flow u + δ).
    #[test]
    fn an_offset_is_a_uniform_flow_added() {
        let (u, du) = (DVec3::new(3.0, 0.0, 0.5), DVec3::new(-0.25, 1.5, 0.0));
        let tau = 2e-3;
        let dt = 5e-4;
        let fc = FluidCoupling {
            drag_diameter: 1e-5,
            reynolds_diameter: 1e-5,
            force_density: 1000.0,
            force_scale: 1.0,
            tau,
        };
        let (gain, relax) = crate::physics::integrate::exponential_factors(tau, dt);
        let sf = StokesFactors { gain, relax };
        let s = Scheme {
            dt,
            law: Some(DragLaw::Stokes),
            integrator: Integrator::Exponential,
            fluid: Fluid {
                density: 1.2,
                viscosity: 1.8e-5,
            },
            forces: None,
        };
        let b = body(&fc, &sf);
        let shifted = WithOffset {
            inner: FlowField::Uniform(u),
            du,
        };
        let (x1, v1, _) = advance(&s, &shifted, &b, Place::cell(0), None, None);
        let (x2, v2, _) = advance(
            &s,
            &FlowField::Uniform(u + du),
            &b,
            Place::cell(0),
            None,
            None,
        );
        assert_eq!((x1, v1), (x2, v2));
        // Many steps: the analytic relaxation of v toward w = u + δ + a·τ.
        let (mut x, mut v) = (b.x, b.v);
        let n = 40;
        for _ in 0..n {
            let bi = Body { x, v, ..b };
            (x, v, _) = advance(&s, &shifted, &bi, Place::cell(0), None, None);
        }
        let t = n as f64 * dt;
        let w = u + du + b.a * tau;
        let ve = w + (b.v - w) * (-t / tau).exp();
        let xe = b.x + w * t + (b.v - w) * tau * (1.0 - (-t / tau).exp());
        assert!((v - ve).length() <= 1e-12 * ve.length(), "{v} vs {ve}");
        assert!((x - xe).length() <= 1e-12 * xe.length(), "{x} vs {xe}");
    }
}
