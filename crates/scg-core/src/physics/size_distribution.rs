//! Particle size distributions: Rosin–Rammler, log-normal and tabulated, given on a
//! number or a mass basis and truncated to [min, max]; sampled per particle (a feeder's
//! stream is a number stream), with the number and mass shares of any size range and the
//! total efficiency ∫η(d)·q₃(d) dd of a grade curve η.
//!
//! Every shape is integrated once onto a grid of [`GRID`] log-spaced intervals (plus the
//! table's points and any report-bin edges, so that those are exact nodes), with an
//! 8-point Gauss–Legendre rule per interval, both the number share Q₀ and the mass share
//! Q₃ below each node. A distribution on one basis is the other's weighted by d^∓3:
//! q₀(d) ∝ q₃(d)/d³. Sampling inverts Q₀ (the interval by bisection, linear inside it;
//! its error, below 1e-6 in Q₀, is far under a Kolmogorov–Smirnov test's resolution at
//! 10^5 samples, 4·10^-3).

use std::cmp::Ordering;

use rand::Rng;

/// A weight of the density (1, d³ or d⁻³).
type Weight = fn(f64) -> f64;

/// The basis a distribution is given on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Basis {
    /// Shares of the particle count (Q₀).
    Number,
    /// Shares of the mass (volume; Q₃).
    Mass,
}

impl Basis {
    /// The scene file's name.
    pub fn name(self) -> &'static str {
        match self {
            Basis::Number => "number",
            Basis::Mass => "mass",
        }
    }
}

/// The shape of a distribution, as given on its basis.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Rosin–Rammler (Weibull): Q(d) = 1 − exp(−(d/d63)^n); `d63` in m, `spread` = n.
    RosinRammler {
        /// Size below which 63.2 % lie, m.
        d63: f64,
        /// Spread (uniformity) exponent n, dimensionless.
        spread: f64,
    },
    /// Log-normal: ln d normal with mean ln(median) and standard deviation ln σ_g.
    LogNormal {
        /// Median, m.
        median: f64,
        /// Geometric standard deviation σ_g (> 1), dimensionless.
        sigma_g: f64,
    },
    /// A cumulative table: share `q[i]` below `d[i]` (m), linear in d between points (a
    /// constant density per interval); `q` rises from 0 to 1.
    Table {
        /// Sizes, m, increasing.
        d: Vec<f64>,
        /// Cumulative shares, 0 at the first size, 1 at the last, non-decreasing.
        q: Vec<f64>,
    },
}

/// Log-spaced intervals of the integration grid between min and max.
pub const GRID: usize = 4096;

/// 8-point Gauss–Legendre nodes on [−1, 1] (positive half) and weights.
const GL_X: [f64; 4] = [
    0.183_434_642_495_649_8,
    0.525_532_409_916_329,
    0.796_666_477_413_626_7,
    0.960_289_856_497_536_3,
];
const GL_W: [f64; 4] = [
    0.362_683_783_378_362,
    0.313_706_645_877_887_3,
    0.222_381_034_453_374_5,
    0.101_228_536_290_376_3,
];

/// ∫ₐᵇ f by the 8-point Gauss–Legendre rule.
fn gauss8(a: f64, b: f64, f: &impl Fn(f64) -> f64) -> f64 {
    let (m, h) = (0.5 * (a + b), 0.5 * (b - a));
    let mut s = 0.0;
    for k in 0..4 {
        s += GL_W[k] * (f(m - h * GL_X[k]) + f(m + h * GL_X[k]));
    }
    s * h
}

/// A truncated size distribution, integrated onto its grid.
#[derive(Clone, Debug, PartialEq)]
pub struct SizeDistribution {
    shape: Shape,
    basis: Basis,
    /// Grid nodes, m: the first is min, the last max.
    nodes: Vec<f64>,
    /// Number share below each node (0 at min, 1 at max).
    q0: Vec<f64>,
    /// Mass share below each node.
    q3: Vec<f64>,
    /// Number-mean d³ over [min, max], m³.
    mean_d3: f64,
    /// The unnormalised mass integral over [min, max] (the rule's ∫ q₃ before Q₃ is
    /// normalised), the denominator of [`SizeDistribution::total_efficiency`].
    mass_norm: f64,
}

/// The weights turning a density on `basis` into the number and the mass densities (up
/// to one common constant): q₀ ∝ q·w₀, q₃ ∝ q·w₃.
fn weights(basis: Basis) -> (Weight, Weight) {
    match basis {
        Basis::Number => (|_| 1.0, |x| x * x * x),
        Basis::Mass => (|x| 1.0 / (x * x * x), |_| 1.0),
    }
}

impl SizeDistribution {
    /// `shape` on `basis`, truncated to [`min`, `max`] (m), with `edges` (m) made exact
    /// nodes of the grid. Errors name what is wrong, for the scene's message.
    pub fn new(
        shape: Shape,
        basis: Basis,
        min: f64,
        max: f64,
        edges: &[f64],
    ) -> Result<Self, String> {
        if !(min.is_finite() && max.is_finite() && min > 0.0 && max > min) {
            return Err(format!("needs 0 < min < max, got min {min:e}, max {max:e}"));
        }
        let mut nodes = log_edges(min, max, GRID);
        match &shape {
            Shape::RosinRammler { d63, spread } => {
                if !(*d63 > 0.0 && d63.is_finite() && *spread > 0.0 && spread.is_finite()) {
                    return Err("Rosin–Rammler needs d63 > 0 and spread > 0".into());
                }
            }
            Shape::LogNormal { median, sigma_g } => {
                if !(*median > 0.0 && median.is_finite() && *sigma_g > 1.0 && sigma_g.is_finite()) {
                    return Err("log-normal needs median > 0 and sigma_g > 1".into());
                }
            }
            Shape::Table { d, q } => {
                if d.len() < 2 || d.len() != q.len() {
                    return Err("a table needs at least two [size, share] points".into());
                }
                if d.windows(2)
                    .any(|w| w[1].partial_cmp(&w[0]) != Some(Ordering::Greater))
                    || d[0] <= 0.0
                {
                    return Err("the table's sizes must be positive and increasing".into());
                }
                if q.windows(2).any(|w| w[1] < w[0]) || q[0] != 0.0 || q[q.len() - 1] != 1.0 {
                    return Err(
                        "the table's shares must rise from 0 (first point) to 1 (last)".into(),
                    );
                }
                if min < d[0] || max > d[d.len() - 1] {
                    return Err(format!(
                        "min and max must lie within the table ({:e} .. {:e} m)",
                        d[0],
                        d[d.len() - 1]
                    ));
                }
                nodes.extend(d.iter().copied().filter(|x| *x > min && *x < max));
            }
        }
        for e in edges {
            if !(*e >= min && *e <= max) {
                return Err(format!("a bin edge {e:e} m lies outside [min, max]"));
            }
        }
        nodes.extend(edges.iter().copied().filter(|x| *x > min && *x < max));
        nodes.sort_by(f64::total_cmp);
        nodes.dedup();
        let native = |x: f64| density(&shape, x);
        let (w0, w3) = weights(basis);
        let mut q0 = vec![0.0; nodes.len()];
        let mut q3 = vec![0.0; nodes.len()];
        for i in 1..nodes.len() {
            let (a, b) = (nodes[i - 1], nodes[i]);
            q0[i] = q0[i - 1] + gauss8(a, b, &|x| native(x) * w0(x));
            q3[i] = q3[i - 1] + gauss8(a, b, &|x| native(x) * w3(x));
        }
        let (n_all, m_all) = (q0[nodes.len() - 1], q3[nodes.len() - 1]);
        if !(n_all > 0.0 && m_all > 0.0 && n_all.is_finite() && m_all.is_finite()) {
            return Err(format!(
                "holds no particles between min {min:e} and max {max:e} m"
            ));
        }
        q0.iter_mut().for_each(|v| *v /= n_all);
        q3.iter_mut().for_each(|v| *v /= m_all);
        Ok(SizeDistribution {
            shape,
            basis,
            nodes,
            q0,
            q3,
            mean_d3: m_all / n_all,
            mass_norm: m_all,
        })
    }

    /// The shape as given.
    pub fn shape(&self) -> &Shape {
        &self.shape
    }

    /// The basis it was given on.
    pub fn basis(&self) -> Basis {
        self.basis
    }

    /// Smallest size, m.
    pub fn min(&self) -> f64 {
        self.nodes[0]
    }

    /// Largest size, m.
    pub fn max(&self) -> f64 {
        self.nodes[self.nodes.len() - 1]
    }

    /// Number-mean d³ over [min, max], m³ (a particle's mean volume is π/6 of it).
    pub fn mean_d3(&self) -> f64 {
        self.mean_d3
    }

    /// Share below `d` (m) on `basis`, 0 below min and 1 above max.
    pub fn cdf(&self, d: f64, basis: Basis) -> f64 {
        let q = match basis {
            Basis::Number => &self.q0,
            Basis::Mass => &self.q3,
        };
        if d <= self.min() {
            return 0.0;
        }
        if d >= self.max() {
            return 1.0;
        }
        let i = self.nodes.partition_point(|x| *x <= d);
        let (a, b) = (self.nodes[i - 1], self.nodes[i]);
        q[i - 1] + (q[i] - q[i - 1]) * (d - a) / (b - a)
    }

    /// Share of [`lo`, `hi`] (m) on `basis`.
    pub fn share(&self, lo: f64, hi: f64, basis: Basis) -> f64 {
        self.cdf(hi, basis) - self.cdf(lo, basis)
    }

    /// Number-mean d³ of the particles in [`lo`, `hi`] (m), m³.
    pub fn mean_d3_in(&self, lo: f64, hi: f64) -> f64 {
        let n = self.share(lo, hi, Basis::Number);
        if n <= 0.0 {
            // no particles there: the range's own middle
            return (0.5 * (lo + hi)).powi(3);
        }
        self.mean_d3 * self.share(lo, hi, Basis::Mass) / n
    }

    /// A size drawn by number (one particle of the stream), m.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let u: f64 = rng.random();
        let i = self
            .q0
            .partition_point(|q| *q <= u)
            .clamp(1, self.nodes.len() - 1);
        let (qa, qb) = (self.q0[i - 1], self.q0[i]);
        let (a, b) = (self.nodes[i - 1], self.nodes[i]);
        if qb <= qa {
            return a;
        }
        (a + (b - a) * (u - qa) / (qb - qa)).clamp(a, b)
    }

    /// Total efficiency of the grade curve `eta` (a share 0..1 at each size d in m):
    /// ∫ η(d)·q₃(d) dd over [min, max], by the grid's Gauss–Legendre rule.
    pub fn total_efficiency(&self, eta: impl Fn(f64) -> f64) -> f64 {
        let (_, w3) = weights(self.basis);
        let mut sum = 0.0;
        for i in 1..self.nodes.len() {
            let (a, b) = (self.nodes[i - 1], self.nodes[i]);
            sum += gauss8(a, b, &|x| eta(x) * density(&self.shape, x) * w3(x));
        }
        // over the same integral with η = 1 (summed alike at construction), so the rule's
        // own error cancels in the ratio
        sum / self.mass_norm
    }
}

/// The density of `shape` on its own basis at `d` (m), 1/m (not truncated).
fn density(shape: &Shape, d: f64) -> f64 {
    match shape {
        Shape::RosinRammler { d63, spread } => {
            let x = (d / d63).powf(*spread);
            spread / d * x * (-x).exp()
        }
        Shape::LogNormal { median, sigma_g } => {
            let s = sigma_g.ln();
            let z = (d / median).ln() / s;
            (-0.5 * z * z).exp() / (d * s * (2.0 * std::f64::consts::PI).sqrt())
        }
        Shape::Table { d: ds, q } => {
            // the piece holding d (the rule evaluates inside grid intervals, which never
            // straddle a table point)
            let i = ds.partition_point(|x| *x <= d);
            if i == 0 || i >= ds.len() {
                return 0.0;
            }
            (q[i] - q[i - 1]) / (ds[i] - ds[i - 1])
        }
    }
}

/// `count` log-spaced bins between `min` and `max` (m): `count + 1` edges.
pub fn log_edges(min: f64, max: f64, count: usize) -> Vec<f64> {
    let mut e: Vec<f64> = (0..=count)
        .map(|i| min * (max / min).powf(i as f64 / count as f64))
        .collect();
    e[0] = min;
    e[count] = max;
    e
}

#[cfg(test)]
mod tests;
