//! Coarse-graining stage: turns the spawned original-particle description into the
//! simulated particle (diameter, density, mass, fluid coupling, drag factors).

use bevy_ecs::prelude::*;

use crate::components::*;
use crate::drag::stokes_response_time;
use crate::effects::motion::{BodyAcceleration, Motion};
use crate::flow::Fluid;
use crate::integrate::exponential_factors;
use crate::scaling::coarse_grain;
use crate::step::{StepBuilder, StepSet};

/// Add the scaling stage (always present: every particle is scaled once, α = 1 included).
pub fn plugin(b: &mut StepBuilder) {
    b.add(
        StepSet::Scaling,
        "coarse_grain",
        "coarse_grain_new_particles",
        coarse_grain_new_particles,
    );
}

/// The per-particle quantities derived from a [`CoarseGrain`] record for time step `dt`.
pub fn derive(
    cg: &CoarseGrain,
    fluid: Option<&Fluid>,
    dt: f64,
) -> (Diameter, Density, Mass, FluidCoupling, StokesFactors) {
    let s = coarse_grain(cg.law, cg.alpha, cg.original_diameter, cg.original_density);
    let mass = s.mass();
    let tau = match fluid {
        Some(f) if f.viscosity > 0.0 => {
            stokes_response_time(mass, f.viscosity, s.drag_diameter, s.force_scale)
        }
        _ => f64::INFINITY,
    };
    let (gain, relax) = exponential_factors(tau, dt);
    (
        Diameter(s.diameter),
        Density(s.density),
        Mass(mass),
        FluidCoupling {
            drag_diameter: s.drag_diameter,
            force_scale: s.force_scale,
            tau,
        },
        StokesFactors { gain, relax },
    )
}

/// Scale every particle spawned since the last step (those still marked [`Unscaled`]).
/// The marker is an archetype filter, so a step without new particles costs nothing here.
#[allow(clippy::type_complexity)]
pub fn coarse_grain_new_particles(
    mut commands: Commands,
    motion: Res<Motion>,
    fluid: Option<Res<Fluid>>,
    mut q: Query<
        (
            Entity,
            &CoarseGrain,
            &mut Diameter,
            &mut Density,
            &mut Mass,
            &mut FluidCoupling,
            &mut StokesFactors,
            Option<&mut BodyAcceleration>,
        ),
        With<Unscaled>,
    >,
) {
    let fluid = fluid.as_deref();
    for (e, cg, mut d, mut rho, mut m, mut fc, mut sf, g) in &mut q {
        commands.entity(e).remove::<Unscaled>();
        let (d1, rho1, m1, fc1, sf1) = derive(cg, fluid, motion.dt);
        if let Some(mut g) = g {
            let reduce = match fluid {
                Some(f) if motion.buoyancy => 1.0 - f.density / rho1.0,
                _ => 1.0,
            };
            g.0 = motion.gravity * reduce;
        }
        *d = d1;
        *rho = rho1;
        *m = m1;
        *fc = fc1;
        *sf = sf1;
    }
}
