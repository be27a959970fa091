//! Slip speeds `scg check` estimates: from the fluid velocity where particles start (the
//! analytic flow's or the mesh flow's) and the terminal slips under the scene's drag law.

use glam::DVec3;

use scg_core::physics::drag::{DragLaw, particle_reynolds};
use scg_core::physics::flow::Fluid;

use crate::Scene;

/// The fluid velocity at x, m/s: the analytic flow's, or the mesh flow's interpolated
/// value (zero outside the mesh).
pub(crate) fn fluid_velocity(scene: &Scene, x: DVec3) -> DVec3 {
    match &scene.mesh_flow {
        Some(m) => m
            .flow
            .find_cell(x)
            .map_or(DVec3::ZERO, |c| m.flow.velocity(c, x).0),
        None => scene.flow.velocity(x),
    }
}

/// The slip speed at which the drag of `law` balances an acceleration `a` (m/s²): τ·a
/// under Stokes drag, τ·a/f(Re) under a Reynolds-dependent law (solved by fixed-point
/// iteration, which converges as f grows with Re), m/s.
pub(crate) fn terminal_slip(law: DragLaw, tau: f64, a: f64, d: f64, fluid: Fluid) -> f64 {
    let stokes = tau * a;
    if !stokes.is_finite() || law == DragLaw::Stokes {
        return stokes;
    }
    let mut v = stokes;
    for _ in 0..100 {
        let next = stokes / law.correction(particle_reynolds(d, v, fluid.density, fluid.viscosity));
        if (next - v).abs() <= 1e-12 * v.abs() {
            return next;
        }
        v = 0.5 * (v + next);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The terminal slip balances drag and the acceleration: τ·a = v·f(Re(v)).
    #[test]
    fn terminal_slip_balances_the_drag_law() {
        let air = Fluid {
            density: 1.2,
            viscosity: 1.8e-5,
        };
        let (d, rho) = (100e-6, 2500.0);
        let tau = rho * d * d / (18.0 * air.viscosity);
        let g = 9.81;
        assert_eq!(terminal_slip(DragLaw::Stokes, tau, g, d, air), tau * g);
        let v = terminal_slip(DragLaw::SchillerNaumann, tau, g, d, air);
        let re = particle_reynolds(d, v, air.density, air.viscosity);
        let f = DragLaw::SchillerNaumann.correction(re);
        assert!((v * f - tau * g).abs() < 1e-9 * tau * g, "{v} {f}");
        // slower than the Stokes estimate (0.76 m/s), about 0.59 m/s
        assert!(v < 0.8 * tau * g && v > 0.5, "{v}");
    }
}
