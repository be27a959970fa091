//! Where the elbow wears: the wall faces' wear summed into zones along the pipe (as
//! `cases/elbow/bend.py` does for the side by side with OpenFOAM), each zone's share of
//! the total with a 95 % interval over the particles, and the deepest face.
//!
//! Zones: 50 mm of the inlet leg (x < 0) or of the outlet leg (y > R), counted from the
//! bend, or 30° of the bend (θ = atan2(x, R − y): 0 where it starts, 90° where it ends) on
//! its outer half (the extrados: farther than R from the bend's axis) or its inner half.

use std::collections::BTreeMap;

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Bend radius to the pipe axis, m (`cases/elbow/blockmesh.py`).
pub const BEND_RADIUS: f64 = 0.075;
/// Length of each straight leg, m.
pub const LEG: f64 = 0.3;
/// The legs' zones, m along the pipe.
pub const LEG_BIN: f64 = 0.05;
/// The bend's zones, degrees.
pub const BEND_BIN: f64 = 30.0;

/// The zones in order along the pipe: the inlet leg from its far end, the extrados, the
/// intrados, the outlet leg from the bend.
pub fn zone_names() -> Vec<String> {
    let legs = (LEG / LEG_BIN).round() as usize;
    let bins = (90.0 / BEND_BIN).round() as usize;
    let leg = |k: usize| {
        format!(
            "{:.0}-{:.0} mm",
            k as f64 * LEG_BIN * 1e3,
            (k + 1) as f64 * LEG_BIN * 1e3
        )
    };
    let bend = |side: &str, k: usize| {
        format!(
            "bend {side} {:.0}-{:.0}°",
            k as f64 * BEND_BIN,
            (k + 1) as f64 * BEND_BIN
        )
    };
    (0..legs)
        .rev()
        .map(|k| format!("inlet leg {}", leg(k)))
        .chain((0..bins).map(|k| bend("outer", k)))
        .chain((0..bins).map(|k| bend("inner", k)))
        .chain((0..legs).map(|k| format!("outlet leg {}", leg(k))))
        .collect()
}

/// The zone (index into [`zone_names`]) of a wall point and its bend angle (degrees; `None`
/// on a leg).
pub fn zone_of(c: DVec3) -> (usize, Option<f64>) {
    let legs = (LEG / LEG_BIN).round() as usize;
    let bins = (90.0 / BEND_BIN).round() as usize;
    let along = |s: f64| ((s / LEG_BIN * (1.0 + 1e-12)) as usize).min(legs - 1);
    if c.x < 0.0 {
        return (legs - 1 - along(-c.x), None);
    }
    if c.y > BEND_RADIUS {
        return (legs + 2 * bins + along(c.y - BEND_RADIUS), None);
    }
    let (dx, dy) = (c.x, BEND_RADIUS - c.y);
    let theta = dx.atan2(dy).to_degrees();
    let k = ((theta / BEND_BIN) as usize).min(bins - 1);
    let outer = dx.hypot(dy) > BEND_RADIUS;
    (legs + if outer { k } else { bins + k }, Some(theta))
}

/// A zone's share of the total wear with its 95 % interval.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ZoneShare {
    /// Zone name ([`zone_names`]).
    pub zone: String,
    /// Share of the total volume removed.
    pub share: f64,
    /// 95 % interval (particles resampled: the ratio's normal interval).
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
}

/// The wear of one run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Wear {
    /// Total volume removed, m³, with its 95 % interval.
    pub total: (f64, f64, f64),
    /// Particles that entered (those that wore nothing count as zeros).
    pub entered: u64,
    /// Impacts logged.
    pub impacts: u64,
    /// Per zone, in [`zone_names`] order.
    pub zones: Vec<ZoneShare>,
    /// Zone with the largest share.
    pub top: String,
    /// The face with the largest depth rate: centre (m), bend angle (degrees, NaN on a
    /// leg), depth rate (m/s over the run), zone.
    pub deepest: ([f64; 3], f64, f64, String),
}

/// The share Z/T of totals over `n` particles with per-particle parts `z_i` of `t_i`,
/// and its 95 % interval: R = z̄/t̄, var R ≈ s²(z − R·t) / (n·t̄²) (the ratio estimator's
/// linearisation; particles not listed are zeros in both). The standard error is at
/// least 1/m, m the particles with t > 0: no share is resolved finer than one particle's
/// worth (with none of m in a zone, its share may still be about 2/m: the rule of three),
/// where the linearisation, fed a few particles, would claim it is.
pub fn ratio95(parts: &[(f64, f64)], n: u64) -> (f64, f64, f64) {
    let z: f64 = parts.iter().map(|p| p.0).sum();
    let t: f64 = parts.iter().map(|p| p.1).sum();
    let n = (n as f64).max(parts.len() as f64);
    if t <= 0.0 || n < 2.0 {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let r = z / t;
    let ss: f64 = parts.iter().map(|p| (p.0 - r * p.1).powi(2)).sum();
    let m = parts.iter().filter(|p| p.1 > 0.0).count().max(1) as f64;
    let se = ((ss / (n - 1.0) / n).sqrt() / (t / n)).max(1.0 / m);
    (r, (r - 1.96 * se).max(0.0), (r + 1.96 * se).min(1.0))
}

/// The wear of a run from its impacts (particle id, face, volume), the faces' centres and
/// areas (`face` → (centre, area)), the total with its interval, the particles that
/// entered and the run's duration (s).
pub fn wear(
    impacts: &[(u32, u32, f64)],
    face: impl Fn(u32) -> (DVec3, f64),
    total: (f64, f64, f64),
    entered: u64,
    duration: f64,
) -> Wear {
    let names = zone_names();
    // per particle: (total, per zone)
    let mut by_particle: BTreeMap<u32, (f64, BTreeMap<usize, f64>)> = BTreeMap::new();
    let mut by_face: BTreeMap<u32, f64> = BTreeMap::new();
    for &(id, f, q) in impacts {
        let (zone, _) = zone_of(face(f).0);
        let e = by_particle.entry(id).or_default();
        e.0 += q;
        *e.1.entry(zone).or_default() += q;
        *by_face.entry(f).or_default() += q;
    }
    let zones: Vec<ZoneShare> = names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let parts: Vec<(f64, f64)> = by_particle
                .values()
                .map(|(t, z)| (z.get(&k).copied().unwrap_or(0.0), *t))
                .collect();
            let (share, lo, hi) = ratio95(&parts, entered);
            ZoneShare {
                zone: name.clone(),
                share,
                lo,
                hi,
            }
        })
        .collect();
    let top = zones
        .iter()
        .filter(|z| z.share.is_finite())
        .max_by(|a, b| a.share.total_cmp(&b.share))
        .map_or(String::new(), |z| z.zone.clone());
    let deepest = by_face
        .iter()
        .map(|(&f, &q)| {
            let (c, area) = face(f);
            (c, q / (area * duration.max(f64::MIN_POSITIVE)))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(
            ([f64::NAN; 3], f64::NAN, f64::NAN, String::new()),
            |(c, rate)| {
                let (k, theta) = zone_of(c);
                (
                    c.to_array(),
                    theta.unwrap_or(f64::NAN),
                    rate,
                    names[k].clone(),
                )
            },
        );
    Wear {
        total,
        entered,
        impacts: impacts.len() as u64,
        zones,
        top,
        deepest,
    }
}

impl Wear {
    /// The zones whose interval reaches the top zone's: where the maximum may sit.
    pub fn top_candidates(&self) -> Vec<&str> {
        let Some(t) = self.zones.iter().find(|z| z.zone == self.top) else {
            return Vec::new();
        };
        self.zones
            .iter()
            .filter(|z| z.hi >= t.lo)
            .map(|z| z.zone.as_str())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zones_follow_the_pipe() {
        let names = zone_names();
        assert_eq!(names.len(), 6 + 3 + 3 + 6);
        let at = |x: f64, y: f64| names[zone_of(DVec3::new(x, y, 0.0)).0].clone();
        assert_eq!(at(-0.29, -0.025), "inlet leg 250-300 mm");
        assert_eq!(at(-0.01, 0.025), "inlet leg 0-50 mm");
        assert_eq!(at(-0.3, 0.0), "inlet leg 250-300 mm");
        // the extrados at 45°: R + D/2 from the axis through (0, R)
        let (s, c) = 45f64.to_radians().sin_cos();
        let out = |r: f64| (r * s, BEND_RADIUS - r * c);
        let (x, y) = out(0.1);
        assert_eq!(at(x, y), "bend outer 30-60°");
        let (x, y) = out(0.05);
        assert_eq!(at(x, y), "bend inner 30-60°");
        assert!((zone_of(DVec3::new(x, y, 0.0)).1.unwrap() - 45.0).abs() < 1e-9);
        assert_eq!(at(0.1, 0.075), "bend outer 60-90°");
        assert_eq!(at(0.1, 0.076), "outlet leg 0-50 mm");
        assert_eq!(at(0.1, 0.375), "outlet leg 250-300 mm");
        assert_eq!(at(0.0001, -0.025), "bend outer 0-30°");
    }

    #[test]
    fn the_ratio_interval_covers_the_share_at_its_rate() {
        // Every particle wears 1 in total, a fraction p of them all in the zone: the share
        // is that fraction, with a binomial standard error √(p(1−p)/n).
        let n = 10_000u64;
        let parts: Vec<(f64, f64)> = (0..n).map(|i| ((i % 4 == 0) as u8 as f64, 1.0)).collect();
        let (r, lo, hi) = ratio95(&parts, n);
        assert!((r - 0.25).abs() < 1e-12);
        let se = (0.25f64 * 0.75 / n as f64).sqrt();
        assert!(
            ((hi - lo) / 2.0 - 1.96 * se).abs() < 1e-4 * se + 1e-6,
            "{lo} {hi}"
        );
        // particles that wore nothing do not change a ratio but count in n
        let (r2, lo2, hi2) = ratio95(&parts, 2 * n);
        assert!((r2 - r).abs() < 1e-12 && hi2 - lo2 < hi - lo);
        assert!(ratio95(&[], 10).0.is_nan());
        // a few particles: the share is not resolved finer than one particle's worth
        let few = [(0.0, 1.0), (0.0, 2.0), (0.0, 1.0)];
        let (r, lo, hi) = ratio95(&few, 3);
        assert_eq!((r, lo), (0.0, 0.0));
        assert!((hi - 1.96 / 3.0).abs() < 1e-12, "{hi}");
    }

    #[test]
    fn wear_sums_zones_and_finds_the_deepest_face() {
        // two faces: one on the extrados at 45° (area 1e-4), one on the outlet leg (2e-4)
        let (s, c) = 45f64.to_radians().sin_cos();
        let bend = DVec3::new(0.1 * s, BEND_RADIUS - 0.1 * c, 0.0);
        let leg = DVec3::new(0.1, 0.2, 0.0);
        let face = |f: u32| if f == 0 { (bend, 1e-4) } else { (leg, 2e-4) };
        let impacts = [(1, 0, 3.0), (2, 1, 1.0), (2, 0, 1.0), (3, 1, 5.0)];
        let w = wear(&impacts, face, (10.0, 9.0, 11.0), 4, 2.0);
        let share = |z: &str| w.zones.iter().find(|s| s.zone == z).unwrap().share;
        assert!((share("bend outer 30-60°") - 0.4).abs() < 1e-12);
        assert!((share("outlet leg 100-150 mm") - 0.6).abs() < 1e-12);
        assert_eq!(w.top, "outlet leg 100-150 mm");
        // depth rates: bend 4/(1e-4·2) = 2e4, leg 6/(2e-4·2) = 1.5e4
        assert_eq!(w.deepest.3, "bend outer 30-60°");
        assert!((w.deepest.1 - 45.0).abs() < 1e-9 && (w.deepest.2 - 2e4).abs() < 1e-9);
        assert_eq!(w.impacts, 4);
        assert!(w.top_candidates().contains(&"bend outer 30-60°"));
    }
}
