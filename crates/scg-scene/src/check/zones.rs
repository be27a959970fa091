//! `scg check`'s notes on `[[zones]]`: what each zone does and where it is.

use super::{Finding, Level};
use crate::Scene;

/// A note per zone: whether it collects or counts, and its region.
pub(super) fn findings(scene: &Scene) -> Vec<Finding> {
    scene
        .zones
        .iter()
        .map(|z| Finding {
            level: Level::Note,
            message: format!(
                "zone `{}`: {} ({:?})",
                z.name,
                if !z.collects {
                    "counts the particles inside at the end".to_string()
                } else if z.collects_after > 0.0 {
                    format!(
                        "collects: a particle whose centre stays in it {} s ({} steps) is removed \
                         and counted as collected, at the time it entered",
                        z.collects_after,
                        (z.collects_after / scene.dt - 1e-9).ceil().max(0.0)
                    )
                } else {
                    "collects: a particle whose centre enters it is removed and counted as collected"
                        .to_string()
                },
                z.region
            ),
        })
        .collect()
}
