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
                if z.collects {
                    "collects: a particle whose centre enters it is removed and counted as collected"
                } else {
                    "counts the particles inside at the end"
                },
                z.region
            ),
        })
        .collect()
}
