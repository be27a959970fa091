//! `scg check` on `[dispersion]`: where the turbulence came from, its ranges, the eddy
//! lifetime against the time step.

use scg_core::physics::dispersion::{Model, Turbulence, lagrangian_time};

use super::{Finding, Level};
use crate::Scene;

/// Notes on the turbulence, and a warning when dt is not below the eddy (or Lagrangian)
/// time in more than a tenth of the domain (there the eddy model switches the fluctuation
/// off, as OpenFOAM's does; the Langevin model stays stable but under-resolves it).
pub(super) fn findings(scene: &Scene) -> Vec<Finding> {
    let Some(d) = &scene.dispersion else {
        return Vec::new();
    };
    let (k, eps): (Vec<f64>, Vec<f64>) = match &d.turbulence {
        Turbulence::Uniform { k, epsilon } => (vec![*k], vec![*epsilon]),
        Turbulence::Profile(p) => (p.k.clone(), p.epsilon.clone()),
        Turbulence::Cells(c) => (c.k.clone(), c.epsilon.clone()),
    };
    let (what, time): (&str, Vec<f64>) = match d.model {
        Model::StochasticRas => (
            "eddy lifetime k/ε",
            k.iter().zip(&eps).map(|(k, e)| k / e).collect(),
        ),
        Model::Langevin { c0, .. } => (
            "Lagrangian time T_L = 4k/(3·C₀·ε)",
            k.iter()
                .zip(&eps)
                .map(|(k, e)| lagrangian_time(*k, *e, c0))
                .collect(),
        ),
    };
    let range = |v: &[f64]| {
        let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
        s.sort_by(f64::total_cmp);
        match s.len() {
            0 => (f64::NAN, f64::NAN, f64::NAN),
            n => (s[0], s[n / 2], s[n - 1]),
        }
    };
    let (k0, km, k1) = range(&k);
    let (e0, em, e1) = range(&eps);
    let (t0, tm, t1) = range(&time);
    let dt = scene.dt;
    let short = time.iter().filter(|t| t.is_nan() || **t <= dt).count();
    let share = short as f64 / time.len().max(1) as f64;
    let mut out = vec![Finding {
        level: Level::Note,
        message: format!(
            "dispersion `{}`: {}; k {k0:.3e}..{k1:.3e} (median {km:.3e}) m²/s², ε \
             {e0:.3e}..{e1:.3e} (median {em:.3e}) m²/s³; {what} {t0:.3e}..{t1:.3e} s (median \
             {tm:.3e}), i.e. {:.1}..{:.0} steps of dt = {dt:e} s{}",
            d.model.name(),
            scene.dispersion_source,
            t0 / dt,
            t1 / dt,
            match d.turbulence {
                Turbulence::Cells(_) => " (over the mesh's cells)",
                _ => "",
            }
        ),
    }];
    if share > 0.1 {
        out.push(Finding {
            level: Level::Warning,
            message: format!(
                "dispersion: dt = {dt:e} s is not below the {what} in {:.0} % of the domain; \
                 {}",
                100.0 * share,
                match d.model {
                    Model::StochasticRas =>
                        "there the eddy model gives no fluctuation at all (as OpenFOAM's); \
                         lower dt",
                    Model::Langevin { .. } => "there the random walk is not resolved; lower dt",
                }
            ),
        });
    }
    out
}
