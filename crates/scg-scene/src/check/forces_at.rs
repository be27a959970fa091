//! `scg check`'s notes on `[coarse_grain] forces_at`: per SCG group beyond Stokes drag,
//! which evaluation is in force and what the other would change.

use scg_core::physics::drag::{DragLaw, particle_reynolds};
use scg_core::physics::scaling::CoarseGrainLaw;

use super::{Finding, GroupReport, Level};
use crate::Scene;

/// Notes on `[coarse_grain] forces_at` for the SCG groups with α > 1 under a Reynolds-
/// dependent drag law: which is in force and, at the group's estimated slip, how much the
/// other would change the drag correction.
pub(super) fn findings(scene: &Scene, reports: &[GroupReport]) -> Vec<Finding> {
    let (Some(law), Some(f)) = (scene.drag, scene.fluid) else {
        return Vec::new();
    };
    if law == DragLaw::Stokes {
        return Vec::new();
    }
    let (now, other) = if scene.scg_at_original {
        ("original", "coarse")
    } else {
        ("coarse", "original")
    };
    scene
        .groups
        .iter()
        .zip(reports)
        .filter(|(g, r)| g.law == CoarseGrainLaw::Scg && g.alpha != 1.0 && r.slip > 0.0)
        .map(|(g, r)| {
            let re = |d: f64| particle_reynolds(d, r.slip, f.density, f.viscosity);
            let (orig, cg) = (
                law.correction(re(g.diameter)),
                law.correction(re(g.alpha * g.diameter)),
            );
            let (a, b) = if scene.scg_at_original { (orig, cg) } else { (cg, orig) };
            let buoy = if scene.gravity.is_some() && scene.buoyancy {
                format!(
                    ", buoyancy ρ_f/ρ_p {:.3e} (original) against {:.3e} (simulated)",
                    f.density / g.density,
                    f.density / r.density
                )
            } else {
                String::new()
            };
            Finding {
                level: Level::Note,
                message: format!(
                    "group `{}` (SCG α = {}): forces_at = \"{now}\": the drag correction at the {} particle's Re ({:.3}); forces_at = \"{other}\" would take it at {:.3} and change the drag by {:+.1} % at the slip {:.3e} m/s{buoy}",
                    g.name,
                    g.alpha,
                    if scene.scg_at_original { "original" } else { "simulated" },
                    a,
                    b,
                    100.0 * (b / a - 1.0),
                    r.slip
                ),
            }
        })
        .collect()
}
