//! `dt = "auto"`: the time step a scene gets when it does not give one.

use scg_core::physics::integrate::Integrator;

use super::{group_report, particle_contact_time};
use crate::Scene;

/// The `auto` time step: the smallest of
/// * 1/(100·ω(1 + k)) in a rotating flow (ω the angular speed, k the inflow ratio);
/// * t_c/50 with walls, t_c the Hertz contact time of the lightest particle of each group
///   against a wall at the reference speed (largest of the initial speeds, the flow speed
///   at the vessel radius, and 0.01 m/s);
/// * t_c/50 of the stiffest particle–particle pair with `[contacts]`
///   ([`particle_contact_time`]);
/// * τ/2 of the fastest-responding group with the explicit integrator;
/// * with a flow on a mesh: a quarter of the time the fastest air takes to cross a mean
///   cell ((V/N)^(1/3)/(4·u_max)), and the shortest drag time τ (the velocity a particle
///   sees changes along its path; walls that rebound, stick or escape add no contact time);
/// * duration/100.
pub fn auto_dt(scene: &Scene) -> f64 {
    let mut dt = scene.duration / 100.0;
    let rate = scene.flow.rate();
    if rate > 0.0 {
        dt = dt.min(1.0 / (100.0 * rate));
    }
    if let Some(m) = &scene.mesh_flow {
        let g = m.flow.geometry();
        let volume: f64 = g.cell_volumes.iter().sum();
        let cell = (volume / g.cell_volumes.len().max(1) as f64).cbrt();
        let umax = m.flow.field_speed().1;
        if umax > 0.0 && cell > 0.0 {
            dt = dt.min(cell / (4.0 * umax));
        }
        for g in &scene.groups {
            let tau = group_report(scene, g).tau;
            if tau.is_finite() && tau > 0.0 {
                dt = dt.min(tau);
            }
        }
    }
    for g in &scene.groups {
        let r = group_report(scene, g);
        if let Some(tc) = r.contact_time {
            dt = dt.min(tc / 50.0);
        }
        if scene.integrator == Integrator::Explicit && r.tau.is_finite() {
            dt = dt.min(0.5 * r.tau);
        }
    }
    if let Some(tc) = particle_contact_time(scene) {
        dt = dt.min(tc / 50.0);
    }
    dt
}
