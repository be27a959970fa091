//! Intervals on population statistics: Wilson's score interval on a share, bootstrap
//! intervals on W1 and on a cut size, and the permutation test that says whether two runs'
//! distributions differ beyond their sampling noise.
//!
//! Radial distances are recorded frame after frame, so one particle gives many correlated
//! samples: every resampling here draws **particles** (clusters of samples), never single
//! samples, or the intervals would be as narrow as if every frame were a new particle.
//! Every function is deterministic: its random draws come from a ChaCha8 stream seeded by
//! the caller.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::classes::d50;
use super::stats::percentile;
#[cfg(test)]
use super::stats::wasserstein1;

/// Resamples behind every bootstrap or permutation interval of the reports.
pub const RESAMPLES: usize = 400;

/// Wilson's score interval (95 %, z = 1.96) of a binomial share k/n: (low, high), NaN
/// for n = 0. Unlike ±2σ it stays inside [0, 1] and is not empty at k = 0 or n.
pub fn wilson95(k: u64, n: u64) -> (f64, f64) {
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let (z, n) = (1.96_f64, n as f64);
    let p = k as f64 / n;
    let d = 1.0 + z * z / n;
    let c = (p + z * z / (2.0 * n)) / d;
    let h = z * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt() / d;
    ((c - h).max(0.0), (c + h).min(1.0))
}

/// The share k/n with its Wilson 95 % interval: (k/n, lo, hi).
pub fn share95(k: u64, n: u64) -> (f64, f64, f64) {
    let (lo, hi) = wilson95(k, n);
    (k as f64 / n.max(1) as f64, lo, hi)
}

/// The samples of one particle (a cluster): its radial distances over the window.
pub type Cluster = Vec<f64>;

/// Two populations' samples pooled and sorted once, each sample with its cluster's index
/// in the pool (`a`'s clusters first): a resample or a split is then a weight per cluster
/// and W1 one walk over the pool, with no copy and no sort.
struct Pool {
    /// (sample, cluster index), sorted by sample.
    samples: Vec<(f64, u32)>,
    /// Samples per cluster.
    sizes: Vec<u32>,
    /// Clusters of `a` (the first ones).
    na: usize,
}

impl Pool {
    fn new(a: &[Cluster], b: &[Cluster]) -> Self {
        let mut samples = Vec::new();
        for (i, c) in a.iter().chain(b).enumerate() {
            samples.extend(c.iter().map(|x| (*x, i as u32)));
        }
        samples.sort_by(|p, q| p.0.total_cmp(&q.0));
        Pool {
            samples,
            sizes: a.iter().chain(b).map(|c| c.len() as u32).collect(),
            na: a.len(),
        }
    }

    /// W1 between the distribution weighted by `wa` and the one weighted by `wb` (a weight
    /// per cluster of the pool: how many times it is drawn into each side).
    fn w1(&self, wa: &[u32], wb: &[u32]) -> f64 {
        let total = |w: &[u32]| -> f64 {
            w.iter()
                .zip(&self.sizes)
                .map(|(w, n)| f64::from(*w) * f64::from(*n))
                .sum()
        };
        let (ta, tb) = (total(wa), total(wb));
        if ta == 0.0 || tb == 0.0 {
            return f64::NAN;
        }
        let (mut fa, mut fb, mut w) = (0.0_f64, 0.0_f64, 0.0);
        let mut x0 = self.samples.first().map_or(0.0, |p| p.0);
        for &(x, c) in &self.samples {
            w += (fa - fb).abs() * (x - x0);
            x0 = x;
            fa += f64::from(wa[c as usize]) / ta;
            fb += f64::from(wb[c as usize]) / tb;
        }
        w
    }
}

/// The 2.5 % and 97.5 % quantiles of `v` (sorted here), NaN when empty.
fn central95(v: &mut [f64]) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (percentile(v, 0.025), percentile(v, 0.975))
}

/// Percentile bootstrap 95 % interval of W1 between the distributions of two populations
/// of particles, `a` and `b` (each a list of clusters): both are resampled by particle,
/// `resamples` times. Its coverage is nominal where W1 stands clear of the sampling noise
/// (tests: 93–97 % at W1 ≥ 3× the noise); near zero, W1 cannot be told from noise, which
/// is what [`w1_noise95`] tests. (The reflected "basic" bootstrap covered worse there,
/// 68 % at W1 ≈ 2× the noise, because it corrects a bias the estimator mostly lacks.)
/// NaN when either population is empty.
pub fn w1_interval(a: &[Cluster], b: &[Cluster], resamples: usize, seed: u64) -> (f64, f64) {
    if a.is_empty() || b.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let pool = Pool::new(a, b);
    let n = pool.sizes.len();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut wa, mut wb) = (vec![0u32; n], vec![0u32; n]);
    let mut w: Vec<f64> = (0..resamples)
        .map(|_| {
            wa.fill(0);
            wb.fill(0);
            for _ in 0..pool.na {
                wa[rng.random_range(0..pool.na)] += 1;
            }
            for _ in pool.na..n {
                wb[rng.random_range(pool.na..n)] += 1;
            }
            pool.w1(&wa, &wb)
        })
        .collect();
    central95(&mut w)
}

/// The W1 two populations of `a`'s and `b`'s sizes show when they come from one and the
/// same distribution: the 95 % quantile of W1 over `resamples` random splits of the
/// pooled particles into groups of those sizes (a permutation test). A measured W1 above
/// it says the distributions differ (p < 0.05); at or below it, they agree within the
/// sampling noise. NaN when either is empty.
pub fn w1_noise95(a: &[Cluster], b: &[Cluster], resamples: usize, seed: u64) -> f64 {
    if a.is_empty() || b.is_empty() {
        return f64::NAN;
    }
    let pool = Pool::new(a, b);
    let n = pool.sizes.len();
    let mut order: Vec<usize> = (0..n).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut wa, mut wb) = (vec![0u32; n], vec![0u32; n]);
    let mut w: Vec<f64> = (0..resamples)
        .map(|_| {
            // Fisher–Yates over the first |a| places: a uniform split.
            for i in 0..pool.na {
                let j = rng.random_range(i..n);
                order.swap(i, j);
            }
            for (k, &c) in order.iter().enumerate() {
                let in_a = k < pool.na;
                wa[c] = u32::from(in_a);
                wb[c] = u32::from(!in_a);
            }
            pool.w1(&wa, &wb)
        })
        .collect();
    w.sort_by(f64::total_cmp);
    percentile(&w, 0.95)
}

/// Percentile bootstrap 95 % intervals of the mean and of the `qs`-quantiles (nearest
/// rank, as [`percentile`]) of the samples of `clusters`, resampling particles
/// `resamples` times: `(mean, [quantiles])`, each `(low, high)`; NaN when empty.
pub fn mean_and_quantiles95(
    clusters: &[Cluster],
    qs: &[f64],
    resamples: usize,
    seed: u64,
) -> ((f64, f64), Vec<(f64, f64)>) {
    let nan = (f64::NAN, f64::NAN);
    if clusters.is_empty() || clusters.iter().all(|c| c.is_empty()) {
        return (nan, vec![nan; qs.len()]);
    }
    let pool = Pool::new(clusters, &[]);
    let n = clusters.len();
    let sums: Vec<f64> = clusters.iter().map(|c| c.iter().sum()).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut w = vec![0u32; n];
    let mut means = Vec::with_capacity(resamples);
    let mut quant: Vec<Vec<f64>> = vec![Vec::with_capacity(resamples); qs.len()];
    let mut order: Vec<usize> = (0..qs.len()).collect();
    order.sort_by(|a, b| qs[*a].total_cmp(&qs[*b]));
    for _ in 0..resamples {
        w.fill(0);
        for _ in 0..n {
            w[rng.random_range(0..n)] += 1;
        }
        let total: f64 = w
            .iter()
            .zip(&pool.sizes)
            .map(|(w, s)| f64::from(*w) * f64::from(*s))
            .sum();
        let sum: f64 = w.iter().zip(&sums).map(|(w, s)| f64::from(*w) * s).sum();
        means.push(sum / total);
        // one walk for all quantiles, in increasing order
        let (mut cum, mut k) = (0.0, 0);
        for &(x, c) in &pool.samples {
            cum += f64::from(w[c as usize]);
            while k < order.len() && cum > ((total - 1.0) * qs[order[k]]).round() {
                quant[order[k]].push(x);
                k += 1;
            }
            if k == order.len() {
                break;
            }
        }
    }
    (
        central95(&mut means),
        quant.iter_mut().map(|v| central95(v)).collect(),
    )
}

/// One class of a partition curve: diameter (m), particles that went to the fines (or were
/// collected, whichever the curve counts) and the class's particles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClassCount {
    /// Original diameter, m.
    pub diameter: f64,
    /// Particles counted by the curve.
    pub k: u64,
    /// Particles of the class.
    pub n: u64,
}

/// A binomial draw of `n` trials with probability `p` (a sum of Bernoulli draws: the
/// classes here hold at most some 10⁵ particles).
fn binomial(n: u64, p: f64, rng: &mut ChaCha8Rng) -> u64 {
    (0..n).filter(|_| rng.random::<f64>() < p).count() as u64
}

/// Bootstrap 95 % interval of the cut size d50 ([`d50`]: where the curve of k/n falls
/// through 0.5) of a partition curve: each class's count redrawn binomially from its
/// observed share (the same as resampling its particles), `resamples` times, percentile
/// interval. `None` when the observed curve does not cross 0.5; a bound is NaN when more
/// than 2.5 % of the redrawn curves do not cross it (the interval is open on that side:
/// the data cannot place the cut there).
pub fn d50_interval(classes: &[ClassCount], resamples: usize, seed: u64) -> Option<(f64, f64)> {
    let share = |c: &ClassCount, k: u64| {
        if c.n == 0 {
            f64::NAN
        } else {
            k as f64 / c.n as f64
        }
    };
    let curve = |ks: &[u64]| -> Vec<(f64, f64)> {
        classes
            .iter()
            .zip(ks)
            .map(|(c, k)| (c.diameter, share(c, *k)))
            .collect()
    };
    let observed: Vec<u64> = classes.iter().map(|c| c.k).collect();
    d50(&curve(&observed))?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut ks = vec![0u64; classes.len()];
    let (mut found, mut below, mut above) = (Vec::new(), 0usize, 0usize);
    for _ in 0..resamples {
        for (k, c) in ks.iter_mut().zip(classes) {
            *k = binomial(c.n, share(c, c.k), &mut rng);
        }
        let pts = curve(&ks);
        match d50(&pts) {
            Some(d) => found.push(d),
            // the curve stays above 0.5 (cut beyond the last class) or starts below it
            None if pts
                .iter()
                .rev()
                .find(|p| p.1.is_finite())
                .is_some_and(|p| p.1 >= 0.5) =>
            {
                above += 1
            }
            None => below += 1,
        }
    }
    found.sort_by(f64::total_cmp);
    // Curves that never cross place the cut outside the classes: below the first (they
    // start under 0.5) or beyond the last. Sort them to those ends and read the quantiles
    // over all resamples; a quantile that falls among them is an open bound (NaN).
    let q = |p: f64| -> f64 {
        let i = (p * (resamples - 1) as f64).round() as usize;
        match i.checked_sub(below) {
            Some(j) if j < found.len() => found[j],
            _ => f64::NAN,
        }
    };
    let (lo, hi) = (q(0.025), q(0.975));
    debug_assert!(above + below + found.len() == resamples);
    Some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(c: &[Cluster]) -> Vec<f64> {
        let mut v: Vec<f64> = c.iter().flatten().copied().collect();
        v.sort_by(f64::total_cmp);
        v
    }

    /// A standard normal draw (Box–Muller).
    fn normal(rng: &mut ChaCha8Rng) -> f64 {
        let (u, v): (f64, f64) = (rng.random(), rng.random());
        (-2.0 * (1.0 - u).ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    }

    /// A share of exactly 95 % within ±2 % over 1 000 repetitions (the test): the
    /// binomial standard error of such a share is 0.7 %, so ±2 % is about 3σ.
    fn near95(hits: usize, reps: usize, what: &str) {
        let c = hits as f64 / reps as f64;
        assert!((0.93..=0.97).contains(&c), "{what}: coverage {c}");
    }

    #[test]
    fn mean_and_median_intervals_cover() {
        // Particles of a normal population, four frames each that wander a little around
        // the particle's own value: the mean 0 and the median 0 covered at 95 % ± 2 %.
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let (mut hm, mut hq, reps) = (0, 0, 1000);
        for r in 0..reps {
            let pop: Vec<Cluster> = (0..500)
                .map(|_| {
                    let x = normal(&mut rng);
                    (0..4).map(|_| x + 0.1 * normal(&mut rng)).collect()
                })
                .collect();
            let ((mlo, mhi), q) = mean_and_quantiles95(&pop, &[0.5, 0.9], 200, r as u64);
            hm += usize::from(mlo <= 0.0 && 0.0 <= mhi);
            hq += usize::from(q[0].0 <= 0.0 && 0.0 <= q[0].1);
        }
        eprintln!("mean coverage {hm}/{reps}, median {hq}/{reps}");
        near95(hm, reps, "mean");
        near95(hq, reps, "median");
        // unit weights give the sample's own quantiles at the ends of the interval's reach
        let one: Vec<Cluster> = vec![vec![1.0, 2.0, 3.0, 4.0, 5.0]];
        let ((lo, hi), q) = mean_and_quantiles95(&one, &[0.0, 0.5, 1.0], 10, 1);
        assert_eq!((lo, hi), (3.0, 3.0));
        assert_eq!(q, vec![(1.0, 1.0), (3.0, 3.0), (5.0, 5.0)]);
    }

    #[test]
    fn pooled_w1_is_w1() {
        let a: Vec<Cluster> = vec![vec![0.3, 0.1], vec![0.9], vec![0.4, 0.4, 0.2]];
        let b: Vec<Cluster> = vec![vec![0.5], vec![0.05, 0.7]];
        let pool = Pool::new(&a, &b);
        let w = pool.w1(&[1, 1, 1, 0, 0], &[0, 0, 0, 1, 1]);
        assert!(
            (w - wasserstein1(&flat(&a), &flat(&b))).abs() < 1e-15,
            "{w}"
        );
        // a cluster drawn twice counts twice
        let twice = vec![a[0].clone(), a[0].clone(), a[2].clone()];
        let w = pool.w1(&[2, 0, 1, 0, 0], &[0, 0, 0, 1, 1]);
        assert!((w - wasserstein1(&flat(&twice), &flat(&b))).abs() < 1e-15);
    }

    #[test]
    fn wilson_covers_at_its_nominal_rate() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for (p, n) in [(0.3, 200), (0.1, 400), (0.5, 60)] {
            let mut hits = 0;
            for _ in 0..1000 {
                let (lo, hi) = wilson95(binomial(n, p, &mut rng), n);
                hits += usize::from(lo <= p && p <= hi);
            }
            near95(hits, 1000, &format!("wilson p={p} n={n}"));
            eprintln!("wilson p={p} n={n}: {hits}/1000");
        }
        let (lo, hi) = wilson95(0, 10);
        assert!(lo == 0.0 && hi > 0.2 && hi < 0.35, "{hi}");
        assert!(wilson95(1, 0).0.is_nan());
    }

    #[test]
    fn w1_interval_covers_a_known_shift() {
        // Two normal populations shifted by 0.5: W1 = 0.5 exactly. Particles carry three
        // samples each, strongly correlated (the particle's own offset plus a little
        // noise), as frames of one particle are.
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let shift = 0.5;
        let pop = |n: usize, m: f64, rng: &mut ChaCha8Rng| -> Vec<Cluster> {
            (0..n)
                .map(|_| {
                    let x = m + normal(rng);
                    vec![x; 3]
                })
                .collect()
        };
        let (mut hits, reps) = (0, 1000);
        let mut naive_hits = 0;
        for r in 0..reps {
            let a = pop(400, 0.0, &mut rng);
            let b = pop(300, shift, &mut rng);
            let (lo, hi) = w1_interval(&a, &b, 200, r as u64);
            hits += usize::from(lo <= shift && shift <= hi);
            if r >= 300 {
                continue;
            }
            // the same resampled sample by sample (every frame a new particle) is too narrow
            let sa: Vec<Cluster> = a.iter().flatten().map(|x| vec![*x]).collect();
            let sb: Vec<Cluster> = b.iter().flatten().map(|x| vec![*x]).collect();
            let (lo, hi) = w1_interval(&sa, &sb, 200, r as u64);
            naive_hits += usize::from(lo <= shift && shift <= hi);
        }
        near95(hits, reps, "w1 by particle");
        eprintln!("w1 coverage: by particle {hits}/{reps}, by sample {naive_hits}/300");
        assert!(naive_hits < 255, "by sample: {naive_hits} of 300");
    }

    #[test]
    fn w1_noise_rejects_at_five_percent() {
        // Two populations from one distribution: W1 above the permutation quantile in
        // 5 % of the repetitions; with a real shift, nearly always.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let pop = |n: usize, m: f64, rng: &mut ChaCha8Rng| -> Vec<Cluster> {
            (0..n).map(|_| vec![m + normal(rng); 2]).collect()
        };
        let (mut agree, mut agree_shifted, reps) = (0, 0, 1000);
        for r in 0..reps {
            let (a, b) = (pop(120, 0.0, &mut rng), pop(80, 0.0, &mut rng));
            let w = wasserstein1(&flat(&a), &flat(&b));
            agree += usize::from(w <= w1_noise95(&a, &b, 200, r as u64));
            let c = pop(80, 0.6, &mut rng);
            let w = wasserstein1(&flat(&a), &flat(&c));
            agree_shifted += usize::from(w <= w1_noise95(&a, &c, 200, r as u64));
        }
        near95(agree, reps, "permutation");
        eprintln!("permutation: agree {agree}/{reps}, shifted {agree_shifted}/{reps}");
        assert!(
            agree_shifted < 50,
            "shift 0.6σ agreed {agree_shifted} times"
        );
    }

    #[test]
    fn d50_interval_covers_the_cut() {
        // A piecewise-linear partition curve whose 0.5 crossing is known exactly.
        let ds = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let p = [0.95, 0.85, 0.62, 0.38, 0.15, 0.05];
        let truth = d50(&ds.iter().copied().zip(p).collect::<Vec<_>>()).unwrap();
        assert!((truth - 3.5).abs() < 1e-12);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let (mut hits, mut width, reps) = (0, 0.0, 1000);
        for r in 0..reps {
            let classes: Vec<ClassCount> = ds
                .iter()
                .zip(p)
                .map(|(d, p)| ClassCount {
                    diameter: *d,
                    k: binomial(300, p, &mut rng),
                    n: 300,
                })
                .collect();
            let (lo, hi) = d50_interval(&classes, 300, r as u64).expect("crosses");
            hits += usize::from(lo <= truth && truth <= hi);
            width += hi - lo;
        }
        near95(hits, reps, "d50");
        eprintln!("d50 coverage {hits}/{reps}");
        // ±σ_p/slope: σ = √(0.25/300) = 0.029 over a slope of 0.24 per unit → ±0.24 at 95 %
        let w = width / reps as f64;
        assert!(w > 0.3 && w < 0.7, "mean width {w}");
    }

    #[test]
    fn d50_interval_opens_where_the_data_cannot_place_the_cut() {
        // The curve barely crosses at its last class: many redraws never cross.
        let classes = [
            ClassCount {
                diameter: 1.0,
                k: 60,
                n: 100,
            },
            ClassCount {
                diameter: 2.0,
                k: 49,
                n: 100,
            },
        ];
        let (lo, hi) = d50_interval(&classes, 400, 1).unwrap();
        assert!(lo.is_finite() && hi.is_nan(), "{lo} {hi}");
        assert_eq!(
            d50_interval(&classes[..1], 100, 1),
            None,
            "one class never crosses"
        );
    }
}
