//! Statistics of samples: mean, percentiles, histograms and the 1-Wasserstein distance.

/// Mean of `v` (NaN when empty).
pub fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// The `q`-quantile (0 ≤ q ≤ 1) of `sorted` samples: the nearest rank, no interpolation.
/// NaN when empty.
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// Samples per bin of [0, range]: below 0 (and NaN) counts in the first bin, beyond `range`
/// in the last. No bins give an empty histogram.
pub fn histogram_counts(samples: &[f64], range: f64, bins: usize) -> Vec<u64> {
    let mut h = vec![0u64; bins];
    if bins == 0 {
        return h;
    }
    for x in samples {
        let b = ((x / range * bins as f64).floor().max(0.0) as usize).min(bins - 1);
        h[b] += 1;
    }
    h
}

/// Fraction of the samples per bin of [0, range] (binned as [`histogram_counts`]); empty
/// samples give zeros.
pub fn histogram(samples: &[f64], range: f64, bins: usize) -> Vec<f64> {
    if samples.is_empty() {
        return vec![0.0; bins];
    }
    let n = samples.len() as f64;
    histogram_counts(samples, range, bins)
        .into_iter()
        .map(|c| c as f64 / n)
        .collect()
}

/// 1-Wasserstein distance between the empirical distributions of two sorted samples:
/// ∫ |F_a(x) − F_b(x)| dx. NaN when either is empty.
pub fn wasserstein1(a: &[f64], b: &[f64]) -> f64 {
    if a.is_empty() || b.is_empty() {
        return f64::NAN;
    }
    let (na, nb) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j) = (0usize, 0usize);
    let mut x = a[0].min(b[0]);
    let mut w = 0.0;
    while i < a.len() || j < b.len() {
        let next = match (a.get(i), b.get(j)) {
            (Some(&p), Some(&q)) => p.min(q),
            (Some(&p), None) => p,
            (None, Some(&q)) => q,
            (None, None) => break,
        };
        w += (i as f64 / na - j as f64 / nb).abs() * (next - x);
        x = next;
        while i < a.len() && a[i] <= x {
            i += 1;
        }
        while j < b.len() && b[j] <= x {
            j += 1;
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn w1_of_shifted_samples_is_the_shift() {
        let a = [0.0, 1.0, 2.0, 3.0];
        let b: Vec<f64> = a.iter().map(|x| x + 0.25).collect();
        assert!((wasserstein1(&a, &b) - 0.25).abs() < 1e-15);
        assert_eq!(wasserstein1(&a, &a), 0.0);
        // Point masses: |x − y|.
        assert!((wasserstein1(&[1.0], &[4.0]) - 3.0).abs() < 1e-15);
        // Different sample sizes: {0, 1} vs {0, 0, 1, 1} are the same distribution.
        assert!(wasserstein1(&[0.0, 1.0], &[0.0, 0.0, 1.0, 1.0]).abs() < 1e-15);
        // {0} vs {0, 1}: half the mass moves by 1.
        assert!((wasserstein1(&[0.0], &[0.0, 1.0]) - 0.5).abs() < 1e-15);
        assert!(wasserstein1(&[], &[1.0]).is_nan());
    }

    #[test]
    fn w1_is_symmetric() {
        let a = [0.1, 0.4, 0.4, 0.9];
        let b = [0.0, 0.2, 0.7];
        assert!((wasserstein1(&a, &b) - wasserstein1(&b, &a)).abs() < 1e-15);
    }

    #[test]
    fn histogram_sums_to_one() {
        let h = histogram(&[0.0, 0.1, 0.5, 0.99, 2.0], 1.0, 10);
        assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert_eq!(h[9], 0.4);
        assert_eq!(histogram(&[], 1.0, 3), vec![0.0; 3]);
        assert!(histogram(&[0.5], 1.0, 0).is_empty());
    }

    #[test]
    fn counts_clamp_to_the_end_bins() {
        assert_eq!(
            histogram_counts(&[-1.0, f64::NAN, 0.0, 0.49, 0.5, 1.0, 7.0], 1.0, 2),
            vec![4, 3]
        );
    }

    #[test]
    fn nearest_rank_percentiles_and_mean() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(percentile(&v, 0.1), 1.0);
        assert_eq!(percentile(&v, 0.5), 3.0);
        assert_eq!(percentile(&v, 0.9), 5.0);
        assert!(percentile(&[], 0.5).is_nan());
        assert_eq!(mean(&v), 3.0);
        assert!(mean(&[]).is_nan());
    }
}
