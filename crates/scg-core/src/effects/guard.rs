//! The state guard: stops a run the moment a position or velocity turns non-finite,
//! naming the step, the particle and the field.

use std::sync::atomic::{AtomicBool, Ordering};

use bevy_ecs::prelude::*;

use crate::components::*;
use crate::effects::motion::SimClock;
use crate::step::{StepBuilder, StepSet};

/// A non-finite value found by the guard.
#[derive(Clone, Debug, PartialEq)]
pub struct NonFinite {
    /// Step at which it appeared.
    pub step: u64,
    /// Particle id.
    pub particle: u32,
    /// Field name (`position`, `velocity`).
    pub field: &'static str,
    /// The value.
    pub value: [f64; 3],
}

impl std::fmt::Display for NonFinite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "non-finite {} {:?} of particle {} at step {}",
            self.field, self.value, self.particle, self.step
        )
    }
}

/// Health of the run (resource). Integration kernels raise `suspect` cheaply; the guard
/// then scans and records the first offending particle (lowest id) in `failure`.
#[derive(Resource, Default)]
pub struct Health {
    suspect: AtomicBool,
    /// The failure that stops the run, if any.
    pub failure: Option<NonFinite>,
}

impl Health {
    /// Called by kernels when they produce a non-finite value.
    #[inline]
    pub fn raise(&self) {
        self.suspect.store(true, Ordering::Relaxed);
    }
}

/// Add the guard (always present).
pub fn plugin(b: &mut StepBuilder) {
    b.add(
        StepSet::InletOutlet,
        "guard",
        "check_finite_state",
        check_finite_state,
    );
}

/// Find the first non-finite particle when a kernel raised the flag.
pub fn check_finite_state(
    clock: Res<SimClock>,
    mut health: ResMut<Health>,
    q: Query<(&ParticleId, &Position, &Velocity)>,
) {
    if !health.suspect.swap(false, Ordering::Relaxed) || health.failure.is_some() {
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
