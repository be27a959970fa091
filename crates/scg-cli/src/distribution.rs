//! The fates of a size distribution by mass: each fate's share of the original powder's
//! mass, Σ over the report bins of the bin's prescribed mass share times the share of the
//! bin's particles that met that fate — the quadrature ∫ η(d)·q₃(d) dd with η constant in
//! each bin (a grade curve's total efficiency when the fate is "collected").
//!
//! Interval: each bin's share has Wilson's 95 % interval; the bins are independent, so
//! the sum's half-width is 1.96·√(Σ w²·σ²) with σ the Wilson half-width / 1.96. A bin
//! that received no particle is unknown: it adds 0 to the lower bound and its whole mass
//! share to the upper one, and the estimate is over the other bins.

use std::collections::BTreeMap;

use scg_scene::Scene;

use crate::analysis::interval::wilson95;
use crate::fates::GroupFates;

/// One fate's share of a distribution's mass.
#[derive(Clone, Debug, PartialEq)]
pub struct MassShare {
    /// The fate, as the fates table names it.
    pub what: String,
    /// Estimate (0..1) and its 95 % interval.
    pub share: f64,
    /// Lower bound of the 95 % interval.
    pub lo: f64,
    /// Upper bound of the 95 % interval.
    pub hi: f64,
}

/// A distribution's fates by mass.
#[derive(Clone, Debug, PartialEq)]
pub struct DistributionFates {
    /// The `[[groups]]` entry's name.
    pub name: String,
    /// What the distribution is (shape, basis, range, bins).
    pub describe: String,
    /// Mass share of the bins no particle was fed to.
    pub empty_share: f64,
    /// Per fate.
    pub shares: Vec<MassShare>,
}

/// Σ w·k/n over bins (w the mass share, k of n particles) with its 95 % interval, and
/// the mass share of the bins with n = 0.
pub fn combine(bins: &[(f64, u64, u64)]) -> (MassShare, f64) {
    let (mut sum, mut weight, mut var, mut empty) = (0.0, 0.0, 0.0, 0.0);
    for &(w, k, n) in bins {
        if n == 0 {
            empty += w;
            continue;
        }
        let (lo, hi) = wilson95(k, n);
        let sigma = (hi - lo) / (2.0 * 1.96);
        sum += w * k as f64 / n as f64;
        weight += w;
        var += w * w * sigma * sigma;
    }
    let half = 1.96 * var.sqrt();
    let share = if weight > 0.0 { sum / weight } else { f64::NAN };
    let m = MassShare {
        what: String::new(),
        share,
        lo: (sum - half).max(0.0),
        hi: (sum + half + empty).min(1.0),
    };
    (m, empty)
}

/// Every size distribution of `scene` by mass, from the per-group `fates`.
pub fn by_mass(scene: &Scene, fates: &[GroupFates]) -> Vec<DistributionFates> {
    let mut out: Vec<DistributionFates> = Vec::new();
    let mut parents: Vec<&str> = Vec::new();
    for g in &scene.groups {
        if let Some(s) = &g.size
            && !parents.contains(&s.parent.as_str())
        {
            parents.push(&s.parent);
        }
    }
    for parent in parents {
        // (mass share, fates) of each bin
        let bins: Vec<(f64, &GroupFates, &scg_scene::SizeBin)> = scene
            .groups
            .iter()
            .zip(fates)
            .filter_map(|(g, f)| {
                let s = g.size.as_ref().filter(|s| s.parent == parent)?;
                Some((s.mass_share(), f, s))
            })
            .collect();
        let mut counts: BTreeMap<String, Vec<u64>> = BTreeMap::new();
        let mut order: Vec<String> = Vec::new();
        for (b, (_, f, _)) in bins.iter().enumerate() {
            for (what, k) in crate::fates::lines(f) {
                if !counts.contains_key(&what) {
                    order.push(what.clone());
                }
                counts.entry(what).or_insert_with(|| vec![0; bins.len()])[b] = k;
            }
        }
        let mut shares = Vec::new();
        let mut empty_share = 0.0;
        for what in order {
            let ks = &counts[&what];
            let input: Vec<(f64, u64, u64)> = bins
                .iter()
                .zip(ks)
                .map(|((w, f, _), k)| (*w, *k, f.entered()))
                .collect();
            let (mut m, empty) = combine(&input);
            m.what = what;
            empty_share = empty;
            shares.push(m);
        }
        let s = bins[0].2;
        let d = &s.distribution;
        let shape = match d.shape() {
            scg_core::physics::size_distribution::Shape::RosinRammler { d63, spread } => {
                format!("Rosin–Rammler d63 {:.3} µm, n {spread}", d63 * 1e6)
            }
            scg_core::physics::size_distribution::Shape::LogNormal { median, sigma_g } => {
                format!("log-normal median {:.3} µm, σ_g {sigma_g}", median * 1e6)
            }
            scg_core::physics::size_distribution::Shape::Table { d, .. } => {
                format!("table of {} points", d.len())
            }
        };
        out.push(DistributionFates {
            name: parent.to_string(),
            describe: format!(
                "{shape} by {}, {:.3}–{:.3} µm in {} bins",
                d.basis().name(),
                d.min() * 1e6,
                d.max() * 1e6,
                bins.len()
            ),
            empty_share,
            shares,
        });
    }
    out
}

/// The console lines.
pub fn render(ds: &[DistributionFates]) -> String {
    let mut s = String::new();
    for d in ds {
        s += &format!(
            "{} ({}), by mass of the original powder (Σ bin mass share × fate share, 95 %):\n",
            d.name, d.describe
        );
        for m in &d.shares {
            s += &format!(
                "    {:<34} {:>6.2} %  [{:.2}, {:.2}]\n",
                m.what,
                100.0 * m.share,
                100.0 * m.lo,
                100.0 * m.hi
            );
        }
        if d.empty_share > 0.0 {
            s += &format!(
                "    bins fed no particle hold {:.3} % of the mass (unknown: in the upper bounds)\n",
                100.0 * d.empty_share
            );
        }
    }
    s
}

/// The JSON for `summary.json`.
pub fn json(ds: &[DistributionFates]) -> serde_json::Value {
    serde_json::Value::Array(
        ds.iter()
            .map(|d| {
                serde_json::json!({
                    "name": d.name,
                    "describe": d.describe,
                    "empty_mass_share": d.empty_share,
                    "by_mass": d.shares.iter().map(|m| serde_json::json!({
                        "fate": m.what, "share": m.share, "share_95": [m.lo, m.hi],
                    })).collect::<Vec<_>>(),
                })
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn combine_weights_bins_and_bounds_empty_ones() {
        // two bins, mass shares 0.25 and 0.75: 10 of 100 and 90 of 100
        let (m, empty) = combine(&[(0.25, 10, 100), (0.75, 90, 100)]);
        assert_eq!(empty, 0.0);
        assert!((m.share - (0.25 * 0.1 + 0.75 * 0.9)).abs() < 1e-15);
        assert!(m.lo < m.share && m.share < m.hi);
        // the half-width: 1.96·√(Σ w²σ²) from the Wilson intervals
        let s = |k, n| {
            let (a, b) = wilson95(k, n);
            (b - a) / 3.92
        };
        let half = 1.96 * (0.0625 * s(10, 100).powi(2) + 0.5625 * s(90, 100).powi(2)).sqrt();
        assert!((m.hi - m.share - half).abs() < 1e-12);
        // an empty bin: the estimate over the others, the upper bound takes its share
        let (e, empty) = combine(&[(0.2, 0, 0), (0.8, 40, 100)]);
        assert_eq!(empty, 0.2);
        assert!((e.share - 0.4).abs() < 1e-15);
        assert!(e.hi > 0.8 * 0.4 + 0.2 - 1e-12);
    }
}
