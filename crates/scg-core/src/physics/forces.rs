//! Forces on a particle besides drag, gravity and contacts, each opt-in per scene
//! (`[forces]`, docs/scenes.md) and each evaluated **for the original particle**: under
//! SCG a coarse particle stands for originals whose acceleration it must have, so a force
//! that does not scale like the drag (the slip correction with d, lift with α, the
//! pressure-gradient and added-mass terms with α²) is computed for the original and
//! applied as its acceleration. The diameter and density used are the particle's
//! [`FluidCoupling::reynolds_diameter`] and [`FluidCoupling::force_density`]: the
//! original's for SCG (under `forces_at = "original"`), parcels and samples, the simulated
//! sphere's for the laws that do not claim the original's acceleration.
//!
//! * Cunningham slip ([`super::drag::cunningham_davies`]): the drag of a particle
//!   comparable with the gas's mean free path falls by C_c; its response time grows by
//!   C_c (at spawn: [`crate::spawn::coarse_grained`]).
//! * Added mass (C_A, 0.5 for a sphere): C_A·m_f·(Du/Dt − dv/dt) moves the particle's
//!   inertia to m + C_A·m_f, so τ and every other acceleration divide by
//!   k = 1 + C_A·ρ_f/ρ_p ([`ExtraForces::inertia`], at spawn) and the fluid's
//!   acceleration adds C_A·(ρ_f/ρ_p)·Du/Dt/k (each step).
//! * Pressure gradient (the undisturbed flow's stress): m_f·Du/Dt, as OpenFOAM's
//!   `pressureGradient` (buoyancy stays with `[gravity] buoyancy`).
//! * Saffman–Mei shear lift ([`saffman_mei`]), Mei's (1992) correction as in OpenFOAM's
//!   `SaffmanMeiLiftForce`.
//! * Rubinow–Keller rotational lift ([`rubinow_keller`]) on a particle's spin relative to
//!   the fluid's rotation, the spin relaxing toward half the vorticity under the Stokes
//!   torque −π·μ·d³·(ω_p − ω/2) with τ_r = ρ_p·d²/(60·μ) ([`rotational_lift_step`]; its
//!   own stage, `stages::rotational_lift`, before the integration, applied as a kick).
//!
//! Du/Dt is the steady carrier's (u·∇)u = J·u with J = ∇u the carrier's velocity
//! gradient at the mid-step point ([`crate::physics::carrier::Carrier::gradient`]); the
//! forces enter the exponential step as a constant acceleration over it.

use glam::{DMat3, DVec3};

use super::drag::particle_reynolds;
use super::flow::Fluid;
use crate::components::FluidCoupling;

/// The opt-in forces a scene declares (none by default).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExtraForces {
    /// Cunningham slip correction (Davies' constants): the gas's mean free path, m.
    pub cunningham: Option<f64>,
    /// Added (virtual) mass coefficient C_A (0.5 for a sphere), or none.
    pub added_mass: Option<f64>,
    /// The pressure-gradient force m_f·Du/Dt.
    pub pressure_gradient: bool,
    /// Saffman–Mei shear lift.
    pub saffman_mei: bool,
    /// Rubinow–Keller rotational lift, with the particles' spin driven by the fluid.
    pub rubinow_keller: bool,
    /// A rotating frame the flow and the walls are given in (OpenFOAM's SRF), if any: the
    /// particles are tracked in it with the centrifugal and Coriolis accelerations.
    pub frame: Option<RotatingFrame>,
}

/// A frame rotating at a constant angular velocity about a centre (OpenFOAM's
/// `SRFProperties`: origin, axis, rpm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotatingFrame {
    /// Angular velocity Ω (axis times rate, right-handed), rad/s.
    pub omega: DVec3,
    /// A point on the axis, m.
    pub centre: DVec3,
}

impl RotatingFrame {
    /// The fictitious acceleration (m/s²) on a particle at `x` (m) moving at `v` (m/s)
    /// relative to the frame: −2·Ω × v (Coriolis) − Ω × (Ω × (x − c)) (centrifugal).
    #[inline]
    pub fn acceleration(&self, x: DVec3, v: DVec3) -> DVec3 {
        let w = self.omega;
        -2.0 * w.cross(v) - w.cross(w.cross(x - self.centre))
    }
}

impl ExtraForces {
    /// The forces evaluated every step, if any (added mass enters the step through the
    /// fluid's acceleration only with the pressure gradient or on its own).
    pub fn step(&self, fluid: Fluid) -> Option<StepForces> {
        let any = self.added_mass.is_some() || self.pressure_gradient || self.saffman_mei;
        (any || self.frame.is_some()).then_some(StepForces {
            fluid,
            added_mass: self.added_mass.unwrap_or(0.0),
            pressure_gradient: self.pressure_gradient,
            saffman_mei: self.saffman_mei,
            frame: self.frame,
        })
    }

    /// The inertia factor k = 1 + C_A·ρ_f/ρ_p of a particle of density `density`
    /// (kg/m³) in `fluid` (1 without added mass).
    pub fn inertia(&self, fluid: Option<&Fluid>, density: f64) -> f64 {
        match (self.added_mass, fluid) {
            (Some(c), Some(f)) => 1.0 + c * f.density / density,
            _ => 1.0,
        }
    }

    /// The names of the forces evaluated each step, in a fixed order (for the plan).
    pub fn step_names(&self) -> Vec<&'static str> {
        [
            ("pressure_gradient", self.pressure_gradient),
            ("added_mass", self.added_mass.is_some()),
            ("saffman_mei", self.saffman_mei),
        ]
        .into_iter()
        .filter_map(|(name, on)| on.then_some(name))
        .collect()
    }
}

/// The forces a step evaluates at the mid-step point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepForces {
    /// The carrier fluid.
    pub fluid: Fluid,
    /// C_A (0: no added mass).
    pub added_mass: f64,
    /// The pressure-gradient force.
    pub pressure_gradient: bool,
    /// Saffman–Mei lift.
    pub saffman_mei: bool,
    /// The rotating frame's centrifugal and Coriolis accelerations, if any.
    pub frame: Option<RotatingFrame>,
}

impl StepForces {
    /// The acceleration (m/s²) these forces give a particle with coupling `fc` at `x` (m)
    /// moving at `v` (m/s) where the carrier's velocity is `u` (m/s) and its gradient `j`
    /// (J_ik = ∂u_i/∂x_k, 1/s): (C_P + C_A)·(ρ_f/ρ_p)·J·u + F_lift/m_p, divided by the
    /// inertia factor k, plus a rotating frame's fictitious acceleration (the scene allows
    /// a frame only without added mass, so k = 1 with it).
    #[inline]
    pub fn acceleration(
        &self,
        fc: &FluidCoupling,
        x: DVec3,
        u: DVec3,
        j: DMat3,
        v: DVec3,
    ) -> DVec3 {
        let fictitious = self.frame.map_or(DVec3::ZERO, |f| f.acceleration(x, v));
        let (d, rho_p) = (fc.reynolds_diameter, fc.force_density);
        let ratio = self.fluid.density / rho_p;
        let k = 1.0 + self.added_mass * ratio;
        let mut a = DVec3::ZERO;
        let cp = if self.pressure_gradient { 1.0 } else { 0.0 };
        if cp + self.added_mass != 0.0 {
            a += (cp + self.added_mass) * ratio * (j * u);
        }
        if self.saffman_mei {
            let f = saffman_mei(d, self.fluid, u - v, vorticity(j));
            a += f / (rho_p * std::f64::consts::PI / 6.0 * d * d * d);
        }
        a / k + fictitious
    }
}

/// The vorticity ∇×u (1/s) of the velocity gradient `j` (column k = ∂u/∂x_k).
#[inline]
pub fn vorticity(j: DMat3) -> DVec3 {
    DVec3::new(
        j.y_axis.z - j.z_axis.y,
        j.z_axis.x - j.x_axis.z,
        j.x_axis.y - j.y_axis.x,
    )
}

/// Saffman–Mei lift coefficient C_l (Mei 1992, as OpenFOAM's `SaffmanMeiLiftForce`):
/// with Re = ρ_f·|u − v|·d/μ, Re_ω = ρ_f·|ω|·d²/μ, β = Re_ω/(2·Re), α = 0.3314·√β,
/// f = (1 − α)·e^(−0.1·Re) + α, C_ld = 6.46·f (Re < 40) or 6.46·0.0524·√(β·Re), and
/// C_l = 3/(2π·√Re_ω)·C_ld.
#[inline]
pub fn saffman_mei_cl(re: f64, re_w: f64) -> f64 {
    if !(re > 0.0 && re_w > 0.0) {
        return 0.0;
    }
    let beta = 0.5 * re_w / re;
    let alpha = 0.3314 * beta.sqrt();
    let f = (1.0 - alpha) * (-0.1 * re).exp() + alpha;
    let cld = if re < 40.0 {
        6.46 * f
    } else {
        6.46 * 0.0524 * (beta * re).sqrt()
    };
    3.0 / (2.0 * std::f64::consts::PI * re_w.sqrt()) * cld
}

/// Saffman–Mei shear lift on a sphere of diameter `d` (m) with slip `slip` = u − v (m/s)
/// in a flow of vorticity `omega` (1/s): F = V_p·ρ_f·C_l·(u − v) × ω, N. At small Re it
/// is Saffman's 1.615·d²·√(ρ_f·μ·|ω|)·|u − v| (f → 1).
#[inline]
pub fn saffman_mei(d: f64, fluid: Fluid, slip: DVec3, omega: DVec3) -> DVec3 {
    let re = particle_reynolds(d, slip.length(), fluid.density, fluid.viscosity);
    let re_w = fluid.density * omega.length() * d * d / fluid.viscosity;
    let vol = std::f64::consts::PI / 6.0 * d * d * d;
    vol * fluid.density * saffman_mei_cl(re, re_w) * slip.cross(omega)
}

/// Rubinow–Keller rotational lift on a sphere of diameter `d` (m) spinning at `spin`
/// (rad/s) in a flow of vorticity `omega` (1/s) with slip `slip` = u − v (m/s):
/// F = (π/8)·ρ_f·d³·Ω × (v − u), Ω = spin − ω/2 the spin relative to the fluid's
/// rotation, N (Rubinow & Keller 1961; Crowe et al., Multiphase Flows with Droplets and
/// Particles, eq. 4.119).
#[inline]
pub fn rubinow_keller(d: f64, fluid_density: f64, spin: DVec3, omega: DVec3, slip: DVec3) -> DVec3 {
    let rel = spin - 0.5 * omega;
    std::f64::consts::PI / 8.0 * fluid_density * d * d * d * rel.cross(-slip)
}

/// Rotational response time of a sphere of diameter `d` (m) and density `rho_p` (kg/m³)
/// in a fluid of viscosity `mu` (Pa·s): τ_r = ρ_p·d²/(60·μ), s (the Stokes torque
/// −π·μ·d³·(ω_p − Ω) on the moment of inertia m·d²/10). ρ_p·d² is SCG's invariant: a
/// coarse particle's spin relaxes as the original's does.
#[inline]
pub fn spin_relaxation_time(d: f64, rho_p: f64, mu: f64) -> f64 {
    rho_p * d * d / (60.0 * mu)
}

/// One step `dt` (s) of a spinning sphere, the original of coupling `fc` (its
/// `reynolds_diameter` and `force_density`), in a fluid whose velocity relative to the
/// particle is `slip` = u − v (m/s) and whose vorticity is `omega` (1/s): the spin relaxes
/// exactly toward ω/2 over the step (the torque-free state), and the Rubinow–Keller lift
/// on the step's mean relative spin gives the velocity change F·dt/(k·m_p), k = 1 +
/// C_A·ρ_f/ρ_p with `added_mass` C_A (0 without). Returns (Δv m/s, the new spin rad/s).
#[inline]
pub fn rotational_lift_step(
    spin: DVec3,
    omega: DVec3,
    slip: DVec3,
    fc: &FluidCoupling,
    fluid: Fluid,
    added_mass: f64,
    dt: f64,
) -> (DVec3, DVec3) {
    let (d, rho_p) = (fc.reynolds_diameter, fc.force_density);
    let k = 1.0 + added_mass * fluid.density / rho_p;
    let half = 0.5 * omega;
    let tau = spin_relaxation_time(d, rho_p, fluid.viscosity);
    let rel0 = spin - half;
    // the relative spin's mean over the step: rel0·τ_r/dt·(1 − e^(−dt/τ_r))
    let mean = if dt > 0.0 {
        rel0 * (-(-dt / tau).exp_m1() * tau / dt)
    } else {
        rel0
    };
    let m = rho_p * std::f64::consts::PI / 6.0 * d * d * d;
    let f = rubinow_keller(d, fluid.density, mean + half, omega, slip);
    (f * (dt / (k * m)), half + rel0 * (-dt / tau).exp())
}

#[cfg(test)]
mod tests;
