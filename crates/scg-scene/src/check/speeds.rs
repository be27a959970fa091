//! Speeds known before a run: the shortest particle–particle contact time at the largest
//! approach speed the scene's initial and feeding velocities give.

use glam::DVec3;
use scg_core::physics::contact::NormalLaw;
use scg_core::physics::contact::normal::{hertz_contact_time, linear_contact_time};
use scg_core::physics::scaling::coarse_grain;

use super::{group_report, group_velocities, known_speed};
use crate::Scene;

/// Shortest particle–particle contact time over all pairs of groups (the stiffest pair),
/// s, when the scene declares `[contacts]`: Hertz t_c with m*, R* of the pair at the
/// approach speed known before the run (the largest difference of the two groups' initial
/// and feeding velocities, or the faster group's `known_speed` when those agree), or
/// the linear law's t_c. The run measures the real approach speeds.
pub fn particle_contact_time(scene: &Scene) -> Option<f64> {
    let c = scene.contacts?;
    let e_eff = c.material.effective_modulus();
    // Mass, radius, known speed and the distinct initial and feeding velocities.
    type Known = (f64, f64, Option<f64>, Vec<DVec3>);
    let gs: Vec<Known> = scene
        .groups
        .iter()
        .map(|g| {
            let s = coarse_grain(g.law, g.alpha, g.min_diameter(), g.density);
            let r = group_report(scene, g);
            let vs: Vec<DVec3> = group_velocities(scene, g)
                .into_iter()
                .map(|p| p.1)
                .collect();
            let vs = distinct(&vs);
            (s.mass(), 0.5 * s.diameter, known_speed(scene, r.tau, g), vs)
        })
        .collect();
    let mut tc = f64::INFINITY;
    for (i, a) in gs.iter().enumerate() {
        for b in &gs[i..] {
            let m = scg_core::physics::contact::normal::effective(a.0, b.0);
            let r = scg_core::physics::contact::normal::effective(a.1, b.1);
            let mut v = largest_between_distinct(&a.3, &b.3);
            if v == 0.0 {
                v = a.2.unwrap_or(0.0).max(b.2.unwrap_or(0.0));
            }
            let t = match c.law {
                NormalLaw::Hertz { .. } if v > 0.0 => hertz_contact_time(m, r, e_eff, v),
                NormalLaw::Hertz { .. } => f64::INFINITY,
                NormalLaw::Linear { stiffness, zeta } => linear_contact_time(m, stiffness, zeta),
            };
            tc = tc.min(t);
        }
    }
    tc.is_finite().then_some(tc)
}

/// The largest |u − w| over u of `a` and w of `b` (0 when either is empty): exact over
/// the distinct vectors while there are at most [`EXACT_DIFFERENCES`] pairs of them, else
/// the bound of their bounding boxes, never smaller (so the contact time it gives is
/// never longer). A lattice of 10⁶ particles at rest is one vector, not 10¹² pairs.
pub fn largest_difference(a: &[DVec3], b: &[DVec3]) -> f64 {
    largest_between_distinct(&distinct(a), &distinct(b))
}

/// The distinct vectors of `vs` (bitwise), in a fixed order.
fn distinct(vs: &[DVec3]) -> Vec<DVec3> {
    let mut d: Vec<[u64; 3]> = vs.iter().map(|v| v.to_array().map(f64::to_bits)).collect();
    d.sort_unstable();
    d.dedup();
    d.into_iter()
        .map(|b| DVec3::from_array(b.map(f64::from_bits)))
        .collect()
}

/// [`largest_difference`] of two sets already distinct ([`distinct`]).
fn largest_between_distinct(a: &[DVec3], b: &[DVec3]) -> f64 {
    if a.is_empty() || b.is_empty() {
        return 0.0;
    }
    if a.len().saturating_mul(b.len()) <= EXACT_DIFFERENCES {
        let mut v: f64 = 0.0;
        for u in a {
            for w in b {
                v = v.max((*u - *w).length());
            }
        }
        return v;
    }
    let bounds = |vs: &[DVec3]| {
        vs.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), v| (lo.min(*v), hi.max(*v)),
        )
    };
    let ((alo, ahi), (blo, bhi)) = (bounds(a), bounds(b));
    (ahi - blo).abs().max((bhi - alo).abs()).length()
}

/// Pairs of distinct velocities [`largest_difference`] compares one by one at most.
pub const EXACT_DIFFERENCES: usize = 1 << 20;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn largest_difference_exact_for_few_and_bounded_for_many() {
        let a = [DVec3::ZERO, DVec3::X, DVec3::X];
        let b = [DVec3::new(0.0, -2.0, 0.0)];
        assert_eq!(largest_difference(&a, &b), 5f64.sqrt());
        assert_eq!(largest_difference(&a, &[]), 0.0);
        // A million particles at rest: one distinct vector, exact and instant.
        let rest = vec![DVec3::ZERO; 1_000_000];
        assert_eq!(largest_difference(&rest, &rest), 0.0);
        // Too many distinct ones for pairs: the bounding boxes' bound, never below the
        // exact value (computed here by brute force).
        let many: Vec<DVec3> = (0..1500)
            .map(|k| {
                let t = k as f64 * 0.37;
                DVec3::new(t.sin(), (1.3 * t).cos(), 0.1 * t.sin() * t.cos())
            })
            .collect();
        assert!(many.len() * many.len() > EXACT_DIFFERENCES);
        let mut exact: f64 = 0.0;
        for u in &many {
            for w in &many {
                exact = exact.max((*u - *w).length());
            }
        }
        let bound = largest_difference(&many, &many);
        assert!(bound >= exact && bound < 1.5 * exact, "{bound} {exact}");
    }
}
