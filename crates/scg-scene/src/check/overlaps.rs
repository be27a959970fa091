//! `scg check`: listed particles that overlap at the start.

use super::*;

/// Listed (explicit) positions checked for initial overlaps; larger scenes skip the check.
const OVERLAP_CHECK_LIMIT: usize = 4096;

/// Pairs of listed particles (spawn indices) that overlap at the start, with the overlap as
/// a fraction of the smaller simulated diameter (at most 20 pairs reported).
pub fn initial_overlaps(scene: &Scene) -> Vec<(usize, usize, f64)> {
    let mut ps: Vec<(usize, DVec3, f64)> = Vec::new();
    let mut index = 0;
    for g in &scene.groups {
        let d = coarse_grain(g.law, g.alpha, g.diameter, g.density).diameter;
        match &g.placement {
            Placement::Explicit { positions, .. } => {
                for p in positions {
                    ps.push((index, *p, d));
                    index += 1;
                }
            }
            Placement::Random { count, .. } => index += count,
        }
    }
    let mut out = Vec::new();
    if ps.len() > OVERLAP_CHECK_LIMIT {
        return out;
    }
    for (i, a) in ps.iter().enumerate() {
        for b in &ps[i + 1..] {
            let delta = 0.5 * (a.2 + b.2) - (a.1 - b.1).length();
            if delta > 0.0 && out.len() < 20 {
                out.push((a.0, b.0, delta / a.2.min(b.2)));
            }
        }
    }
    out
}
