//! Carrier modifiers: the stage that writes each particle's [`CarrierOffset`], the
//! velocity every integration scheme adds to the fluid velocity the particle sees
//! ([`crate::physics::carrier`]). Added only when the scene declares a modifier; its
//! system runs at the start of the integration stage, before the particles move.
//!
//! Today's modifier is a constant offset (a uniform wind on top of the flow, and the
//! seam's own test); turbulent dispersion adds its per-particle fluctuation here.

use bevy_ecs::prelude::*;
use glam::DVec3;

use super::table::{bypass, columns_mut};
use crate::components::CarrierOffset;
use crate::exec::par::for_each_piece;
use crate::step::{StepBuilder, StepSet, StepSystem};

/// A carrier modifier (resource).
#[derive(Resource, Clone, Copy, Debug, PartialEq)]
pub enum CarrierModifier {
    /// The same velocity added everywhere, m/s.
    ConstantOffset(DVec3),
}

impl CarrierModifier {
    /// Scene and plan name.
    pub fn name(&self) -> &'static str {
        match self {
            CarrierModifier::ConstantOffset(_) => "carrier:constant_offset",
        }
    }
}

/// Add the modifier's system (the integration stage's first) and its resource.
pub fn plugin(world: &mut World, b: &mut StepBuilder, m: CarrierModifier) {
    world.insert_resource(m);
    b.add(
        StepSet::Integration,
        m.name(),
        StepSystem::ModifyCarrier,
        modify_carrier,
    );
}

/// Write every particle's offset for this step.
pub fn modify_carrier(m: Res<CarrierModifier>, mut q: Query<&mut CarrierOffset>) {
    let Some(offs) = columns_mut(&mut q) else {
        return;
    };
    match *m {
        CarrierModifier::ConstantOffset(du) => for_each_piece(bypass(offs), |offs| {
            for o in offs {
                o.0 = du;
            }
        }),
    }
}
