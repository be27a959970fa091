//! The state guard: stops a run the moment a position or velocity turns non-finite,
//! naming the step, the particle and the field.

use bevy_ecs::prelude::*;

use crate::components::*;
use crate::state::{Health, NonFinite, SimClock};
use crate::step::{StepBuilder, StepSet, StepSystem};

/// Add the guard (always present).
pub fn plugin(b: &mut StepBuilder) {
    b.add(
        StepSet::InletOutlet,
        "guard",
        StepSystem::CheckFiniteState,
        check_finite_state,
    );
}

/// Find the first non-finite particle when a kernel raised the flag.
pub fn check_finite_state(
    clock: Res<SimClock>,
    mut health: ResMut<Health>,
    q: Query<(&ParticleId, &Position, &Velocity)>,
) {
    if !health.take_suspect() || health.failure.is_some() {
        return;
    }
    let mut worst: Option<NonFinite> = None;
    for (id, x, v) in &q {
        let bad = if !x.0.is_finite() {
            Some(("position", x.0))
        } else if !v.0.is_finite() {
            Some(("velocity", v.0))
        } else {
            None
        };
        if let Some((field, val)) = bad
            && worst.as_ref().is_none_or(|w| id.0 < w.particle)
        {
            worst = Some(NonFinite {
                step: clock.step,
                particle: id.0,
                field,
                value: val.to_array(),
            });
        }
    }
    health.failure = worst;
}
