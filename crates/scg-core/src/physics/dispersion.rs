//! Turbulent dispersion: the fluctuation a RANS field's turbulence adds to the mean carrier
//! velocity a particle sees (pure; the stage is [`crate::stages::carrier`]).
//!
//! A RANS field gives the mean velocity and the turbulence model's k (m²/s²) and ε (m²/s³)
//! or ω (1/s; ε = C_μ·k·ω, C_μ = 0.09). Two models, selectable as OpenFOAM selects its
//! `dispersionModel`:
//!
//! * [`stochastic_ras`] — OpenFOAM's `StochasticDispersionRAS` (Gosman & Ioannides eddy
//!   interaction), step for step: an eddy lives min(k/ε, C_ps·k^1.5/(ε·|v − u − u'|)) with
//!   C_ps = 0.16432; when its age passes the lifetime a new fluctuation is drawn,
//!   |u'| = σ·|N(0,1)| with σ = √(2k/3), in a direction uniform on the sphere — so
//!   ⟨|u'|²⟩ = 2k/3 and ⟨u'_x²⟩ = 2k/9, a third of the turbulence's own 2k/3 per component
//!   (OpenFOAM's convention, kept so that results compare one to one); where dt is not
//!   below the lifetime the particle sees no fluctuation (age set to "great", as OpenFOAM).
//!   A new particle starts with no fluctuation and age 0 (OpenFOAM's parcel constructor),
//!   so its first eddy is drawn one lifetime after it enters. For what it is for and
//!   where it fails (it does not keep tracers well mixed where k varies), see
//!   docs/dispersion.md.
//! * [`langevin`] — a continuous random walk for the fluid velocity seen: the normalised
//!   Langevin equation (Wilson, Legg & Thomson 1983; MacInnes & Bracco 1992) for
//!   w = u'/σ, dw = −w·dt/T_L + ∇σ·dt + √(2/T_L)·dW, with σ = √(2k/3) per component and
//!   T_L = 2σ²/(C₀·ε) (Thomson 1987; C₀ = 2.1 by default). The ∇σ drift is the correction
//!   that keeps tracers well mixed in inhomogeneous isotropic Gaussian turbulence (it is
//!   Thomson's well-mixed model for that case); mean-shear terms are not modelled. Each
//!   step is the exact Ornstein–Uhlenbeck update, stable for any dt.
//!
//! Under coarse graining nothing here is scaled: the eddy model reads the particle's slip,
//! which SCG keeps equal to the original's, and the Langevin model is the fluid's own;
//! a coarse particle is one random sample of the original's trajectory law.

use glam::DVec3;

use super::random::Draws;

/// C_μ of the k–ε/k–ω models: ε = C_μ·k·ω.
pub const C_MU: f64 = 0.09;

/// OpenFOAM's `cps` of the eddy-crossing time in the dispersion models.
pub const C_PS: f64 = 0.16432;

/// OpenFOAM's `small` (added to the slip speed).
const SMALL: f64 = 1e-15;
/// OpenFOAM's `rootVSmall` (added to ε).
const ROOT_VSMALL: f64 = 1e-150;
/// OpenFOAM's `great`: the age of an eddy switched off.
pub const GREAT: f64 = 1e15;

/// The turbulence at a point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Local {
    /// Turbulent kinetic energy k, m²/s².
    pub k: f64,
    /// Dissipation rate ε, m²/s³.
    pub epsilon: f64,
    /// Gradient of σ = √(2k/3), 1/s (the Langevin model's drift).
    pub grad_sigma: DVec3,
}

/// A dispersion model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Model {
    /// OpenFOAM's `StochasticDispersionRAS`.
    StochasticRas,
    /// The normalised Langevin equation with C₀ (dimensionless).
    Langevin {
        /// Kolmogorov's Lagrangian constant C₀.
        c0: f64,
        /// Csanady's β of the crossing-trajectories correction ([`csanady_factors`]);
        /// `None`: every particle sees the tracers' Lagrangian time.
        csanady: Option<f64>,
    },
}

impl Model {
    /// Scene and plan name.
    pub fn name(&self) -> &'static str {
        match self {
            Model::StochasticRas => "stochastic_ras",
            Model::Langevin { .. } => "langevin",
        }
    }

    /// True when a step reads the mean carrier velocity at the particle: the eddy model's
    /// slip (its eddy-crossing time), Csanady's slip against the fluid seen.
    pub fn reads_mean(&self) -> bool {
        match self {
            Model::StochasticRas => true,
            Model::Langevin { csanady, .. } => csanady.is_some(),
        }
    }
}

/// A particle's dispersion state.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct State {
    /// The fluctuation added to the carrier, m/s (OpenFOAM's `UTurb`).
    pub u: DVec3,
    /// `stochastic_ras`: age of the current eddy, s (OpenFOAM's `tTurb`).
    pub age: f64,
    /// `langevin`: σ the fluctuation was set with, m/s (0: none yet), so that u/σ is the
    /// normalised velocity.
    pub sigma: f64,
}

/// rms fluctuation per component of isotropic turbulence, σ = √(2k/3), m/s.
#[inline]
pub fn sigma_of(k: f64) -> f64 {
    (2.0 * k / 3.0).max(0.0).sqrt()
}

/// The eddy model's lifetime for the slip speed `slip` (m/s), s:
/// min(k/ε, C_ps·k^1.5/(ε·(slip + small))), ε + rootVSmall as OpenFOAM (k^1.5 as k·√k:
/// one correctly rounded root instead of a `pow`, within an ulp of it).
#[inline]
pub fn eddy_lifetime(k: f64, epsilon: f64, slip: f64) -> f64 {
    let eps = epsilon + ROOT_VSMALL;
    (k / eps).min(C_PS * (k * k.sqrt()) / eps / (slip + SMALL))
}

/// The Langevin model's Lagrangian time T_L = 2σ²/(C₀·ε) = 4k/(3·C₀·ε), s.
#[inline]
pub fn lagrangian_time(k: f64, epsilon: f64, c0: f64) -> f64 {
    4.0 * k / (3.0 * c0 * epsilon)
}

/// ε from ω (the k–ω models): ε = C_μ·k·ω, m²/s³.
#[inline]
pub fn epsilon_from_omega(k: f64, omega: f64) -> f64 {
    C_MU * k * omega
}

/// A unit vector uniform on the sphere (OpenFOAM's: θ uniform in [0, 2π), cos φ uniform in
/// [−1, 1]).
#[inline]
fn direction(d: &mut Draws) -> DVec3 {
    let theta = d.uniform() * std::f64::consts::TAU;
    let u = 2.0 * d.uniform() - 1.0;
    let a = (1.0 - u * u).max(0.0).sqrt();
    DVec3::new(a * theta.cos(), a * theta.sin(), u)
}

/// One step of OpenFOAM's `StochasticDispersionRAS::update` for a particle of velocity
/// `v` in the mean carrier velocity `u` (m/s): updates the fluctuation and the eddy age
/// in `s`. `mask` zeroes the directions a 2-D case does not solve (OpenFOAM's
/// `constrainDirection`; ones in 3-D).
#[inline]
pub fn stochastic_ras(
    dt: f64,
    t: &Local,
    v: DVec3,
    u: DVec3,
    mask: DVec3,
    s: &mut State,
    d: &mut Draws,
) {
    let slip = (v - u - s.u).length();
    let life = eddy_lifetime(t.k, t.epsilon, slip);
    if dt < life {
        s.age += dt;
        if s.age > life {
            s.age = 0.0;
            let dir = direction(d);
            let (n, _) = d.normal_pair();
            s.u = sigma_of(t.k) * n.abs() * dir * mask;
        }
    } else {
        s.age = GREAT;
        s.u = DVec3::ZERO;
    }
}

/// Csanady's (1963) crossing-trajectories correction of the Lagrangian time a particle
/// with slip `slip` = v − u − u′ (m/s, against the fluid it sees) sees in turbulence of rms
/// `sigma` (m/s): along the slip T_L/√(1 + β²ξ²), across it T_L/√(1 + 4β²ξ²), ξ = |slip|/σ.
/// A heavy particle falling or flung through the eddies leaves each one before it decays:
/// the fluid velocity it sees decorrelates faster than a tracer's. Returns the two factors
/// (along, across), 1 for a tracer.
#[inline]
pub fn csanady_factors(beta: f64, slip: DVec3, sigma: f64) -> (f64, f64) {
    let b2x2 = beta * beta * slip.length_squared() / (sigma * sigma);
    (1.0 / (1.0 + b2x2).sqrt(), 1.0 / (1.0 + 4.0 * b2x2).sqrt())
}

/// The crossing-trajectories correction a [`langevin`] step applies: Csanady's β and the
/// particle's slip against the fluid it sees (the mean carrier and its fluctuation before
/// the step), m/s: zero for a tracer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// β, the ratio of the Lagrangian to the Eulerian integral time (dimensionless).
    pub beta: f64,
    /// v − u − u′, m/s.
    pub slip: DVec3,
}

/// One step of the normalised Langevin model: the exact Ornstein–Uhlenbeck update of
/// w = u'/σ over dt, with the drift ∇σ, then u' = σ·w. A particle without a fluctuation
/// yet (σ = 0 in `s`) starts from the stationary distribution, w ~ N(0, 1) per component.
/// Where k or ε is not positive the fluctuation is zero. With `crossing` the component of
/// w along the slip relaxes over Csanady's longitudinal time and the rest over the
/// lateral one ([`csanady_factors`]); the stationary variance stays σ² per component.
#[inline]
pub fn langevin(
    dt: f64,
    t: &Local,
    c0: f64,
    crossing: Option<Crossing>,
    mask: DVec3,
    s: &mut State,
    d: &mut Draws,
) {
    let sigma = sigma_of(t.k);
    if sigma <= 0.0 || t.epsilon <= 0.0 || !t.epsilon.is_finite() {
        s.u = DVec3::ZERO;
        s.sigma = 0.0;
        return;
    }
    let tl = lagrangian_time(t.k, t.epsilon, c0);
    let w0 = if s.sigma > 0.0 {
        s.u / s.sigma
    } else {
        DVec3::from_array(d.normal3())
    };
    let xi = DVec3::from_array(d.normal3());
    let relax = |tl: f64, w0: DVec3, drift: DVec3, xi: DVec3| {
        let a = (-dt / tl).exp();
        a * w0 + ((1.0 - a) * tl) * drift + (1.0 - a * a).sqrt() * xi
    };
    let w = match crossing {
        Some(c) if c.slip.length_squared() > 0.0 => {
            let (along, across) = csanady_factors(c.beta, c.slip, sigma);
            let e = c.slip.normalize();
            let par = |v: DVec3| v.dot(e) * e;
            let (w0p, gp, xip) = (par(w0), par(t.grad_sigma), par(xi));
            relax(tl * along, w0p, gp, xip)
                + relax(tl * across, w0 - w0p, t.grad_sigma - gp, xi - xip)
        }
        _ => relax(tl, w0, t.grad_sigma, xi),
    };
    s.u = sigma * w * mask;
    s.sigma = sigma;
}

/// k and ε varying along one axis, piecewise linear between tabulated points, clamped
/// beyond the ends or repeated with the table's span as period.
#[derive(Clone, Debug, PartialEq)]
pub struct Profile {
    /// Axis index (0 x, 1 y, 2 z).
    pub axis: usize,
    /// Coordinates along the axis, m, strictly increasing.
    pub at: Vec<f64>,
    /// k at each coordinate, m²/s² (≥ 0).
    pub k: Vec<f64>,
    /// ε at each coordinate, m²/s³ (> 0).
    pub epsilon: Vec<f64>,
    /// Repeat the table with period `at[last] − at[0]` (its end values must then agree).
    pub periodic: bool,
}

impl Profile {
    /// The turbulence at `x`.
    pub fn at(&self, x: DVec3) -> Local {
        let n = self.at.len();
        let (a0, a1) = (self.at[0], self.at[n - 1]);
        let mut s = x[self.axis];
        if self.periodic {
            s = a0 + (s - a0).rem_euclid(a1 - a0);
        }
        if s <= a0 || s >= a1 {
            let i = if s <= a0 { 0 } else { n - 1 };
            return Local {
                k: self.k[i],
                epsilon: self.epsilon[i],
                grad_sigma: DVec3::ZERO,
            };
        }
        let i = self.at.partition_point(|&a| a <= s).clamp(1, n - 1) - 1;
        let h = self.at[i + 1] - self.at[i];
        let f = (s - self.at[i]) / h;
        let k = self.k[i] + f * (self.k[i + 1] - self.k[i]);
        let epsilon = self.epsilon[i] + f * (self.epsilon[i + 1] - self.epsilon[i]);
        let dk = (self.k[i + 1] - self.k[i]) / h;
        let sigma = sigma_of(k);
        let mut grad_sigma = DVec3::ZERO;
        if sigma > 0.0 {
            // σ = √(2k/3): dσ/dk = 1/(3σ).
            grad_sigma[self.axis] = dk / (3.0 * sigma);
        }
        Local {
            k,
            epsilon,
            grad_sigma,
        }
    }
}

/// k, ε and ∇σ per mesh cell (the cell values of the CFD's fields, as OpenFOAM's
/// dispersion models read them).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CellTurbulence {
    /// k per cell, m²/s².
    pub k: Vec<f64>,
    /// ε per cell, m²/s³.
    pub epsilon: Vec<f64>,
    /// ∇σ per cell, 1/s (Gauss gradient of σ = √(2k/3); zero where not computed).
    pub grad_sigma: Vec<DVec3>,
}

/// Where the turbulence comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Turbulence {
    /// The same k (m²/s²) and ε (m²/s³) everywhere.
    Uniform {
        /// k, m²/s².
        k: f64,
        /// ε, m²/s³.
        epsilon: f64,
    },
    /// Varying along one axis.
    Profile(Profile),
    /// Per mesh cell (mesh flows), read by the particle's cell.
    Cells(std::sync::Arc<CellTurbulence>),
}

impl Turbulence {
    /// The turbulence at `x` in mesh cell `cell` (a cell index past the mesh, a particle
    /// not located, sees none).
    #[inline]
    pub fn at(&self, cell: u32, x: DVec3) -> Local {
        match self {
            Turbulence::Uniform { k, epsilon } => Local {
                k: *k,
                epsilon: *epsilon,
                grad_sigma: DVec3::ZERO,
            },
            Turbulence::Profile(p) => p.at(x),
            Turbulence::Cells(c) => c.local(cell),
        }
    }
}

impl CellTurbulence {
    /// The turbulence of mesh cell `cell` (none past the mesh: a particle not located).
    #[inline]
    pub fn local(&self, cell: u32) -> Local {
        let i = cell as usize;
        match (self.k.get(i), self.epsilon.get(i)) {
            (Some(&k), Some(&epsilon)) => Local {
                k,
                epsilon,
                grad_sigma: self.grad_sigma.get(i).copied().unwrap_or(DVec3::ZERO),
            },
            _ => Local::default(),
        }
    }
}

#[cfg(test)]
mod tests;
