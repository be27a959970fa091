//! Rotational (Magnus) lift, `[forces] rubinow_keller = true`: every particle carries a
//! spin ([`AngularVelocity`]) that the fluid's torque relaxes toward half the local
//! vorticity, and the Rubinow–Keller lift on its spin relative to the fluid's rotation
//! ([`rotational_lift_step`]). Evaluated for the original particle (the coupling's
//! `reynolds_diameter` and `force_density`: under SCG the same Δv and spin as the
//! original's, bit for bit) at the start of the integration, after the carrier offsets
//! (the slip includes a dispersion's fluctuation), and applied as a velocity kick before
//! the particles move (first order in dt, as the forces of OpenFOAM's tracker enter its
//! step). Spin from wall or particle contacts (friction) adds in the same component.

use bevy_ecs::prelude::*;
use glam::DVec3;

use super::mesh_flow::MeshFlowState;
use super::table::{bypass, columns, columns_mut};
use crate::components::{
    AngularVelocity, CarrierOffset, CellHint, FluidCoupling, Position, Velocity,
};
use crate::exec::par::for_each_piece;
use crate::physics::carrier::{Carrier, Place};
use crate::physics::flow::{FlowField, Fluid};
use crate::physics::forces::{rotational_lift_step, vorticity};
use crate::state::SimClock;
use crate::step::{StepBuilder, StepSet, StepSystem};

/// The lift's settings (resource): C_A of an added mass (0 without), for the inertia
/// factor 1 + C_A·ρ_f/ρ_p.
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub struct RotationalLift {
    /// Added-mass coefficient (0: none).
    pub added_mass: f64,
}

/// Add the rotational-lift system (integration stage, after the carrier modifier).
pub fn plugin(world: &mut World, b: &mut StepBuilder, added_mass: f64) {
    world.insert_resource(RotationalLift { added_mass });
    b.add(
        StepSet::Integration,
        "forces:rubinow_keller",
        StepSystem::RotationalLift,
        rotational_lift,
    );
}

/// Relax every particle's spin over the step and kick its velocity by the rotational
/// lift (see the module documentation).
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
pub fn rotational_lift(
    lift: Res<RotationalLift>,
    clock: Res<SimClock>,
    fluid: Res<Fluid>,
    flow: Res<FlowField>,
    mesh: Option<Res<MeshFlowState>>,
    read: Query<(
        &Position,
        &FluidCoupling,
        Option<&CellHint>,
        Option<&CarrierOffset>,
    )>,
    mut write: Query<(&mut Velocity, &mut AngularVelocity)>,
) {
    let (Some((xs, fcs, cells, offs)), Some((vs, spins))) =
        (columns(&read), columns_mut(&mut write))
    else {
        return;
    };
    let (dt, fluid, ca) = (clock.dt, *fluid, lift.added_mass);
    let mesh = mesh.as_ref().map(|m| &*m.spec.flow);
    let at = |cell: u32, x: DVec3| match mesh {
        Some(mf) => (
            Carrier::at(mf, Place::cell(cell), x).0,
            Carrier::gradient(mf, cell, x),
        ),
        None => (flow.velocity(x), flow.gradient(x)),
    };
    let cols = (xs, fcs, cells, offs, bypass(vs), bypass(spins));
    for_each_piece(cols, |(xs, fcs, cells, offs, vs, spins)| {
        for i in 0..xs.len() {
            let x = xs[i].0;
            let (mut u, j) = at(cells.map_or(0, |c| c[i].0), x);
            if let Some(o) = offs {
                u += o[i].0;
            }
            let slip = u - vs[i].0;
            let (dv, spin) =
                rotational_lift_step(spins[i].0, vorticity(j), slip, &fcs[i], fluid, ca, dt);
            vs[i].0 += dv;
            spins[i].0 = spin;
        }
    });
}
