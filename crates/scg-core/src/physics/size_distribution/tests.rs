//! Sampling against the closed-form distributions (Kolmogorov–Smirnov at 10^5 samples,
//! number and mass basis), moments and total efficiencies against their closed forms.

use super::*;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const UM: f64 = 1e-6;
const SAMPLES: usize = 100_000;

/// erfc(x) (Numerical Recipes' erfcc, fractional error below 1.2e-7).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

fn phi(z: f64) -> f64 {
    0.5 * erfc(-z / std::f64::consts::SQRT_2)
}

/// The truncated CDF `f` normalised to [min, max].
fn truncated(f: impl Fn(f64) -> f64, min: f64, max: f64) -> impl Fn(f64) -> f64 {
    let (a, b) = (f(min), f(max));
    move |d| (f(d) - a) / (b - a)
}

/// Kolmogorov–Smirnov distance of weighted samples from `cdf`, and the effective count.
fn ks(samples: &[f64], weight: impl Fn(f64) -> f64, cdf: &dyn Fn(f64) -> f64) -> (f64, f64) {
    let mut s: Vec<f64> = samples.to_vec();
    s.sort_by(f64::total_cmp);
    let w: Vec<f64> = s.iter().map(|&d| weight(d)).collect();
    let total: f64 = w.iter().sum();
    let n_eff = total * total / w.iter().map(|x| x * x).sum::<f64>();
    let (mut below, mut dmax) = (0.0, 0.0f64);
    for (d, wi) in s.iter().zip(&w) {
        let f = cdf(*d);
        dmax = dmax.max((f - below / total).abs());
        below += wi;
        dmax = dmax.max((f - below / total).abs());
    }
    (dmax, n_eff)
}

/// Samples pass at the 1 % level: D < 1.63/√n.
fn assert_ks(
    name: &str,
    dist: &SizeDistribution,
    number: impl Fn(f64) -> f64,
    mass: impl Fn(f64) -> f64,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let s: Vec<f64> = (0..SAMPLES).map(|_| dist.sample(&mut rng)).collect();
    assert!(s.iter().all(|d| *d >= dist.min() && *d <= dist.max()));
    let (d0, n0) = ks(&s, |_| 1.0, &number);
    let (d3, n3) = ks(&s, |d| d * d * d, &mass);
    eprintln!("{name}: D number {d0:.2e} (n {n0:.0}), D mass {d3:.2e} (n_eff {n3:.0})");
    assert!(d0 < 1.63 / n0.sqrt(), "{name}: number basis D = {d0}");
    assert!(
        d3 < 1.63 / n3.sqrt(),
        "{name}: mass basis D = {d3} at n_eff {n3}"
    );
    // and the tests would see a wrong distribution: the same samples against a 3 % wider
    // one fail
    let (wrong, _) = ks(&s, |_| 1.0, &|d| number(d / 1.03));
    assert!(
        wrong > 1.63 / n0.sqrt(),
        "{name}: KS does not resolve 3 % ({wrong})"
    );
}

/// The CDF of the density `g(d)·d` in ln d over [min, max] (the trapezoid rule on 2·10^5
/// intervals, linear between them), normalised.
fn quadrature_cdf(min: f64, max: f64, g: impl Fn(f64) -> f64) -> impl Fn(f64) -> f64 {
    let k = 200_000;
    let h = (max / min).ln() / k as f64;
    let f = |i: usize| g(min * (h * i as f64).exp());
    let mut cum = vec![0.0; k + 1];
    for i in 1..=k {
        cum[i] = cum[i - 1] + 0.5 * h * (f(i - 1) + f(i));
    }
    let total = cum[k];
    move |d: f64| {
        let x = ((d / min).ln() / h).clamp(0.0, k as f64);
        let i = (x as usize).min(k - 1);
        (cum[i] + (cum[i + 1] - cum[i]) * (x - i as f64)) / total
    }
}

fn rr(d: f64, d63: f64, n: f64) -> f64 {
    1.0 - (-(d / d63).powf(n)).exp()
}

#[test]
fn rosin_rammler_number_basis_sampled_and_mass_share_follows() {
    let (d63, n, min, max) = (10.0 * UM, 1.5, 0.5 * UM, 60.0 * UM);
    let dist = SizeDistribution::new(
        Shape::RosinRammler { d63, spread: n },
        Basis::Number,
        min,
        max,
        &[],
    )
    .unwrap();
    let number = truncated(|d| rr(d, d63, n), min, max);
    // the mass CDF of a number-basis RR by a fine independent quadrature in ln d
    let mass = quadrature_cdf(min, max, |d| {
        let x = (d / d63).powf(n);
        n * x * (-x).exp() * d * d * d // q0(d)·d³·d (dd = d·d ln d)
    });
    assert_ks("RR number", &dist, number, mass);
}

#[test]
fn rosin_rammler_mass_basis_sampled() {
    // the usual powder description: RR by mass, d63 = 20 µm, n = 2, truncated 1..100 µm
    let (d63, n, min, max) = (20.0 * UM, 2.0, 1.0 * UM, 100.0 * UM);
    let dist = SizeDistribution::new(
        Shape::RosinRammler { d63, spread: n },
        Basis::Mass,
        min,
        max,
        &[],
    )
    .unwrap();
    let mass = truncated(|d| rr(d, d63, n), min, max);
    // number CDF ∝ ∫ q3/d³: by quadrature in ln d
    let number = quadrature_cdf(min, max, |d| {
        let x = (d / d63).powf(n);
        n * x * (-x).exp() / (d * d * d)
    });
    assert_ks("RR mass", &dist, number, mass);
    // at a node (d63 made one), the grid's mass CDF is the truncated closed form to 1e-12
    let at = SizeDistribution::new(
        Shape::RosinRammler { d63, spread: n },
        Basis::Mass,
        min,
        max,
        &[d63],
    )
    .unwrap();
    let err = (at.cdf(d63, Basis::Mass) - truncated(|d| rr(d, d63, n), min, max)(d63)).abs();
    assert!(err < 1e-12, "{err:e}");
}

#[test]
fn log_normal_both_bases_and_hatch_choate() {
    // by mass: median 8 µm, σ_g = 1.8; by number the median is exp(ln 8 µm − 3 ln²1.8)
    let (m3, sg) = (8.0 * UM, 1.8);
    let s = f64::ln(sg);
    let m0 = (m3.ln() - 3.0 * s * s).exp();
    let (min, max) = (0.3 * UM, 60.0 * UM);
    let ln_cdf = |m: f64| move |d: f64| phi((d / m).ln() / s);
    let by_mass = SizeDistribution::new(
        Shape::LogNormal {
            median: m3,
            sigma_g: sg,
        },
        Basis::Mass,
        min,
        max,
        &[],
    )
    .unwrap();
    assert_ks(
        "LN mass",
        &by_mass,
        truncated(ln_cdf(m0), min, max),
        truncated(ln_cdf(m3), min, max),
    );
    let by_number = SizeDistribution::new(
        Shape::LogNormal {
            median: m0,
            sigma_g: sg,
        },
        Basis::Number,
        min,
        max,
        &[],
    )
    .unwrap();
    assert_ks(
        "LN number",
        &by_number,
        truncated(ln_cdf(m0), min, max),
        truncated(ln_cdf(m3), min, max),
    );
    // untruncated (±9 σ): the number median and the mean d³ of Hatch–Choate to 1e-7
    let wide = SizeDistribution::new(
        Shape::LogNormal {
            median: m3,
            sigma_g: sg,
        },
        Basis::Mass,
        m0 * (-9.0 * s).exp(),
        m3 * (9.0 * s).exp(),
        &[m0],
    )
    .unwrap();
    let half = wide.cdf(m0, Basis::Number);
    assert!((half - 0.5).abs() < 1e-7, "{half}");
    let d3 = m0.powi(3) * (4.5 * s * s).exp();
    assert!(
        (wide.mean_d3() / d3 - 1.0).abs() < 1e-7,
        "{}",
        wide.mean_d3() / d3
    );
}

#[test]
fn table_on_mass_basis_sampled() {
    let d: Vec<f64> = [1.0, 2.0, 5.0, 10.0, 20.0, 40.0]
        .iter()
        .map(|x| x * UM)
        .collect();
    let q = vec![0.0, 0.05, 0.2, 0.5, 0.85, 1.0];
    let dist = SizeDistribution::new(
        Shape::Table {
            d: d.clone(),
            q: q.clone(),
        },
        Basis::Mass,
        d[0],
        d[5],
        &[],
    )
    .unwrap();
    let mass = move |x: f64| {
        let i = d.partition_point(|v| *v <= x).clamp(1, d.len() - 1);
        (q[i - 1] + (q[i] - q[i - 1]) * (x - d[i - 1]) / (d[i] - d[i - 1])).clamp(0.0, 1.0)
    };
    // by number: q0 ∝ (ΔQ/Δd)/d³ per piece, ∫ d⁻³ = (a⁻² − x⁻²)/2, in closed form
    let (dd, qq) = match dist.shape() {
        Shape::Table { d, q } => (d.clone(), q.clone()),
        _ => unreachable!(),
    };
    let piece = |i: usize, x: f64| {
        let c = (qq[i] - qq[i - 1]) / (dd[i] - dd[i - 1]);
        c * 0.5 * (dd[i - 1].powi(-2) - x.powi(-2))
    };
    let total: f64 = (1..dd.len()).map(|i| piece(i, dd[i])).sum();
    let lo = dd.clone();
    let n_points = dd.len();
    let number = move |x: f64| {
        let mut s = 0.0;
        for i in 1..n_points {
            s += piece(i, x.clamp(lo[i - 1], lo[i]));
        }
        s / total
    };
    assert_ks("table mass", &dist, number, mass);
}

#[test]
fn total_efficiency_against_its_closed_form() {
    // RR by mass and η(d) = 1 − exp(−(d/dc)^n): with x = (d/d63)^n and r = d63/dc the
    // truncated integral is [(e^−xa − e^−xb) − (e^−xa(1+rⁿ) − e^−xb(1+rⁿ))/(1 + rⁿ)] over
    // (e^−xa − e^−xb).
    let (d63, n, min, max, dc) = (20.0 * UM, 2.0, 1.0 * UM, 100.0 * UM, 12.0 * UM);
    let dist = SizeDistribution::new(
        Shape::RosinRammler { d63, spread: n },
        Basis::Mass,
        min,
        max,
        &[],
    )
    .unwrap();
    let got = dist.total_efficiency(|d| 1.0 - (-(d / dc).powf(n)).exp());
    let (xa, xb, k) = (
        (min / d63).powf(n),
        (max / d63).powf(n),
        1.0 + (d63 / dc).powf(n),
    );
    let want = ((-xa).exp() - (-xb).exp() - ((-xa * k).exp() - (-xb * k).exp()) / k)
        / ((-xa).exp() - (-xb).exp());
    assert!((got - want).abs() < 1e-6, "{got} vs {want}");
    eprintln!(
        "total efficiency {got} vs {want}: {:.1e}",
        (got - want).abs()
    );
    // a sharp cut at d: the mass share above it
    let edge = 15.0 * UM;
    let with_edge = SizeDistribution::new(
        Shape::RosinRammler { d63, spread: n },
        Basis::Mass,
        min,
        max,
        &[edge],
    )
    .unwrap();
    let cut = with_edge.total_efficiency(|d| if d > edge { 1.0 } else { 0.0 });
    assert!((cut - (1.0 - with_edge.cdf(edge, Basis::Mass))).abs() < 1e-12);
}

#[test]
fn shares_and_bin_means() {
    let dist = SizeDistribution::new(
        Shape::RosinRammler {
            d63: 20.0 * UM,
            spread: 2.0,
        },
        Basis::Mass,
        UM,
        100.0 * UM,
        &log_edges(UM, 100.0 * UM, 5),
    )
    .unwrap();
    let e = log_edges(UM, 100.0 * UM, 5);
    let (mut n, mut m, mut mean) = (0.0, 0.0, 0.0);
    for w in e.windows(2) {
        let d3 = dist.mean_d3_in(w[0], w[1]);
        assert!(d3 >= w[0].powi(3) && d3 <= w[1].powi(3));
        n += dist.share(w[0], w[1], Basis::Number);
        m += dist.share(w[0], w[1], Basis::Mass);
        mean += dist.share(w[0], w[1], Basis::Number) * d3;
    }
    assert!((n - 1.0).abs() < 1e-12 && (m - 1.0).abs() < 1e-12);
    assert!((mean / dist.mean_d3() - 1.0).abs() < 1e-12);
}

#[test]
fn bad_parameters_are_refused() {
    let rr = Shape::RosinRammler {
        d63: 1e-5,
        spread: 2.0,
    };
    assert!(SizeDistribution::new(rr.clone(), Basis::Mass, 0.0, 1e-4, &[]).is_err());
    assert!(SizeDistribution::new(rr.clone(), Basis::Mass, 2e-4, 1e-4, &[]).is_err());
    assert!(SizeDistribution::new(rr.clone(), Basis::Mass, 1e-6, 1e-4, &[2e-4]).is_err());
    let ln = Shape::LogNormal {
        median: 1e-5,
        sigma_g: 1.0,
    };
    assert!(SizeDistribution::new(ln, Basis::Number, 1e-6, 1e-4, &[]).is_err());
    let t = |d: Vec<f64>, q: Vec<f64>| Shape::Table { d, q };
    for bad in [
        t(vec![1e-6], vec![0.0]),
        t(vec![1e-6, 1e-6], vec![0.0, 1.0]),
        t(vec![1e-6, 2e-6], vec![0.0, 0.9]),
        t(vec![1e-6, 2e-6, 3e-6], vec![0.0, 0.6, 0.5]),
    ] {
        assert!(SizeDistribution::new(bad, Basis::Mass, 1e-6, 2e-6, &[]).is_err());
    }
    // far in the tail: nothing between min and max
    let far = Shape::LogNormal {
        median: 1e-6,
        sigma_g: 1.1,
    };
    assert!(SizeDistribution::new(far, Basis::Number, 1.0, 2.0, &[]).is_err());
}
