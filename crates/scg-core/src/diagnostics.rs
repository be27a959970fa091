//! Whole-system diagnostics for tests and reports (not part of the step).

use bevy_ecs::prelude::*;
use glam::DVec3;

use crate::components::*;

/// Total kinetic energy (translational + rotational, I = m·d²/10), J, and momentum,
/// kg·m/s, of the particles, summed in a fixed order.
pub fn kinetic_energy_and_momentum(world: &mut World) -> (f64, DVec3) {
    let mut q = world.query::<(&Velocity, Option<&AngularVelocity>, &Mass, &Diameter)>();
    let mut rows: Vec<_> = q
        .iter(world)
        .map(|(v, w, m, d)| (v.0, w.map_or(DVec3::ZERO, |w| w.0), m.0, d.0))
        .collect();
    // Fixed summation order.
    rows.sort_by(|a, b| a.0.x.total_cmp(&b.0.x).then(a.0.y.total_cmp(&b.0.y)));
    let mut e = 0.0;
    let mut p = DVec3::ZERO;
    for (v, w, m, d) in rows {
        e += 0.5 * m * v.length_squared() + 0.5 * (0.1 * m * d * d) * w.length_squared();
        p += m * v;
    }
    (e, p)
}
