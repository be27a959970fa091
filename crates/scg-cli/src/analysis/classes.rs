//! What the classes of a [`Result`] say together: the partition (Tromp) curve of drained
//! fractions after a finite time and its cut size d50, the steady-state partition of
//! decided fates and its cut size, and the W1 distances to a reference run.

use super::interval::{ClassCount, RESAMPLES, d50_interval, w1_interval, w1_noise95};
use super::radial::Result;
use super::stats::wasserstein1;

/// The partition curve (original diameter, drained fraction) of a run, in class order.
pub fn partition(r: &Result) -> Vec<(f64, f64)> {
    r.classes
        .iter()
        .map(|c| (c.diameter, c.drained_fraction))
        .collect()
}

/// Cut size from a partition curve: `points` are (diameter, fraction drained to the fines)
/// in increasing diameter; d50 is where the curve first falls through 0.5, interpolated
/// linearly in diameter. `None` when it never crosses 0.5.
pub fn d50(points: &[(f64, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.1.is_finite()).collect();
    for w in pts.windows(2) {
        let ((d0, f0), (d1, f1)) = (w[0], w[1]);
        if f0 >= 0.5 && f1 < 0.5 {
            return Some(d0 + (f0 - 0.5) / (f0 - f1) * (d1 - d0));
        }
    }
    None
}

/// The [`partition`] curve as counts (drained of the cohort), for its intervals.
pub fn partition_counts(r: &Result) -> Vec<ClassCount> {
    r.classes
        .iter()
        .map(|c| ClassCount {
            diameter: c.diameter,
            k: c.drained,
            n: c.cohort,
        })
        .collect()
}

/// Bootstrap 95 % interval of [`cut_size`] ([`d50_interval`], [`RESAMPLES`] redraws, a
/// fixed seed): `None` when the curve does not cross 0.5, a NaN bound where it is open.
pub fn cut_size95(r: &Result) -> Option<(f64, f64)> {
    d50_interval(&partition_counts(r), RESAMPLES, 0x5c6_d50)
}

/// Per class of `v`: the 95 % bootstrap interval of its W1 to the same class of
/// `reference` and the W1 the two would show from sampling noise alone (the permutation
/// test's 95 % quantile), both / the reference's radius ([`super::interval`]).
pub fn w1_intervals(reference: &Result, v: &Result) -> Vec<((f64, f64), f64)> {
    let r = reference.params.radius;
    reference
        .classes
        .iter()
        .zip(&v.classes)
        .enumerate()
        .map(|(i, (a, b))| {
            let seed = 0x5c6_0001 + i as u64;
            let (lo, hi) = w1_interval(&a.clusters, &b.clusters, RESAMPLES, seed);
            let noise = w1_noise95(&a.clusters, &b.clusters, RESAMPLES, seed);
            ((lo / r, hi / r), noise / r)
        })
        .collect()
}

/// The cut size d50 of a run's [`partition`] curve, m.
pub fn cut_size(r: &Result) -> Option<f64> {
    d50(&partition(r))
}

/// The steady-state partition curve (original diameter, fine fraction of the decided
/// particles, see `fate.rs`) of a run, in class order.
pub fn steady_partition(r: &Result) -> Vec<(f64, f64)> {
    r.classes
        .iter()
        .map(|c| (c.diameter, c.fates.fine_fraction()))
        .collect()
}

/// The steady-state cut size: d50 of the [`steady_partition`] curve, m.
pub fn steady_cut_size(r: &Result) -> Option<f64> {
    d50(&steady_partition(r))
}

/// Particles of a run whose fate was still undecided at its last frame, over all classes.
pub fn undecided(r: &Result) -> u64 {
    r.classes.iter().map(|c| c.fates.undecided).sum()
}

/// Normalised W1 (/ the reference's radius) of each class of `v` to the same class of
/// `reference`.
pub fn w1_to(reference: &Result, v: &Result) -> Vec<f64> {
    let r = reference.params.radius;
    reference
        .classes
        .iter()
        .zip(&v.classes)
        .map(|(a, b)| wasserstein1(&a.radii, &b.radii) / r)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn d50_interpolates_the_crossing() {
        let pts = [(100e-6, 0.9), (160e-6, 0.7), (220e-6, 0.1), (280e-6, 0.0)];
        let d = d50(&pts).unwrap();
        // 0.7 → 0.1 over 60 µm: 0.5 is 1/3 of the way.
        assert!((d - 180e-6).abs() < 1e-12, "{d}");
        assert_eq!(d50(&[(1.0, 0.2), (2.0, 0.1)]), None);
        assert_eq!(d50(&[(1.0, 0.9), (2.0, 0.6)]), None);
        assert_eq!(d50(&[(1.0, 0.5), (2.0, 0.0)]), Some(1.0));
        // NaN classes (empty cohorts) are skipped.
        assert_eq!(d50(&[(1.0, 1.0), (2.0, f64::NAN), (3.0, 0.0)]), Some(2.0));
    }
}
