//! The design of a sweep: which points run, the reference, and the scene of each point.

use scg_core::physics::contact::NormalLaw;
use scg_core::physics::integrate::Integrator;
use scg_core::physics::scaling::CoarseGrainLaw;
use scg_scene::{Placement, Scene};

use super::{CostArgs, population};

/// What a sweep runs: its points, the reference point and, for single-particle scenes,
/// the number of originals every point represents.
#[derive(Clone, Debug, PartialEq)]
pub struct Design {
    /// The points, in run order.
    pub points: Vec<Point>,
    /// The reference point.
    pub reference: Point,
    /// Originals represented by every point (`--represented`; used by single-particle
    /// scenes only).
    pub represented: usize,
}

/// One point of the sweep.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Point {
    /// Law (`None` = the original, α = 1).
    pub law: Option<CoarseGrainLaw>,
    /// α.
    pub alpha: f64,
    /// dt multiplier.
    pub dt_mult: u32,
    /// Integrator.
    pub integrator: Integrator,
    /// Young's-modulus factor.
    pub stiffness: f64,
}

impl Point {
    /// Law name for reports (`original` at α = 1).
    pub fn law_name(&self) -> &'static str {
        self.law.map_or("original", |l| l.name())
    }
}

/// A law or integrator name of an argument list, through the type's serde names (the
/// names scene files use).
fn parse_name<T: serde::de::DeserializeOwned>(s: &str, what: &str) -> Result<T, String> {
    use serde::de::IntoDeserializer;
    T::deserialize(s.trim().into_deserializer())
        .map_err(|e: serde::de::value::Error| format!("unknown {what}: {e}"))
}

/// The points of the sweep, one knob at a time around each (law, α) base point.
pub fn points(
    alphas: &[f64],
    laws: &[CoarseGrainLaw],
    dt_mult: &[u32],
    integrators: &[Integrator],
    stiffness: &[f64],
) -> Vec<Point> {
    let mut out: Vec<Point> = Vec::new();
    let (m0, i0, s0) = (dt_mult[0], integrators[0], stiffness[0]);
    let mut pairs: Vec<(Option<CoarseGrainLaw>, f64)> = Vec::new();
    for &a in alphas {
        if a == 1.0 {
            if !pairs.iter().any(|p| p.0.is_none()) {
                pairs.push((None, 1.0));
            }
        } else {
            for &l in laws {
                pairs.push((Some(l), a));
            }
        }
    }
    for (law, alpha) in pairs {
        let base = Point {
            law,
            alpha,
            dt_mult: m0,
            integrator: i0,
            stiffness: s0,
        };
        let mut push = |p: Point| {
            if !out.contains(&p) {
                out.push(p);
            }
        };
        push(base);
        for &m in &dt_mult[1..] {
            push(Point { dt_mult: m, ..base });
        }
        for &i in &integrators[1..] {
            push(Point {
                integrator: i,
                ..base
            });
        }
        for &s in &stiffness[1..] {
            push(Point {
                stiffness: s,
                ..base
            });
        }
    }
    out
}

pub use super::population::original_group;

/// True when the sweep runs in single-particle mode.
pub fn single_particle(scene: &Scene) -> bool {
    scene.groups[original_group(scene)].count() == 1
}

/// The scene of one point (see the module documentation for the rule). In a
/// single-particle scene, `represented = Some(n)` gives the population standing for `n`
/// originals (`cost::population`) and `None` the original particle alone.
pub fn point_scene(base: &Scene, p: &Point, represented: Option<usize>) -> Scene {
    let mut s = base.clone();
    let law = p.law.unwrap_or(CoarseGrainLaw::Scg);
    if single_particle(base) {
        let mut g = base.groups[original_group(base)].clone();
        g.alpha = p.alpha;
        g.law = law;
        if let Some(n) = represented {
            g.placement =
                population::placement(base, population::simulated_count(p.law, p.alpha, n));
        }
        s.groups = vec![g];
    } else {
        for g in &mut s.groups {
            g.alpha = p.alpha;
            g.law = law;
            if let Placement::Random { count, .. } = &mut g.placement {
                *count = ((*count as f64) / p.alpha.powi(3)).round().max(1.0) as usize;
            }
        }
    }
    s.dt = base.dt * p.dt_mult as f64;
    s.integrator = p.integrator;
    let scale_law = |l: &mut NormalLaw| {
        if let NormalLaw::Linear { stiffness, .. } = l {
            *stiffness *= p.stiffness;
        }
    };
    if let Some(m) = &mut s.material {
        m.youngs_modulus *= p.stiffness;
    }
    if let Some(l) = &mut s.normal_law {
        scale_law(l);
    }
    if let Some(c) = &mut s.contacts {
        c.material.youngs_modulus *= p.stiffness;
        scale_law(&mut c.law);
    }
    s
}

/// True for classifier scenes (classifier flow): the error is per-class W1 and d50.
pub fn is_classifier(scene: &Scene) -> bool {
    matches!(
        scene.flow,
        scg_core::physics::flow::FlowField::Classifier { .. }
    )
}

/// The `--set` overrides of a classifier point: every group at once through
/// `[coarse_grain]` (feeders keep the solid volume rate, so α³ fewer particles are fed).
pub(super) fn classifier_overrides(base: &Scene, p: &Point) -> Vec<String> {
    let m = p.dt_mult as u64;
    let mut o = vec![
        format!("coarse_grain.alpha={}", p.alpha),
        format!(
            "coarse_grain.law=\"{}\"",
            p.law.unwrap_or(CoarseGrainLaw::Scg).name()
        ),
        format!("duration={:e}", base.duration),
        format!("dt={:e}", base.dt * m as f64),
        format!("record_every={}", (base.record_every / m).max(1)),
        format!("integrator=\"{}\"", p.integrator.name()),
    ];
    if let Some(mat) = base.material {
        o.push(format!(
            "material.youngs_modulus={:e}",
            mat.youngs_modulus * p.stiffness
        ));
    }
    o
}

/// The sweep `a` asks for on `base`: its points and the reference point (α = 1, the
/// smallest dt multiplier, the exponential integrator, the largest stiffness factor).
/// `--quick` shortens `base` to a tenth of its duration (at most 0.3 s), trims the lists
/// and represents fewer originals by default.
pub fn design(a: &CostArgs, base: &mut Scene) -> Result<Design, String> {
    let mut laws = a
        .laws
        .iter()
        .map(|l| parse_name(l, "law"))
        .collect::<Result<Vec<CoarseGrainLaw>, String>>()?;
    let mut integrators = a
        .integrators
        .iter()
        .map(|s| parse_name(s, "integrator"))
        .collect::<Result<Vec<Integrator>, String>>()?;
    let mut dt_mult = a.dt_mult.clone();
    let mut stiffness = a.stiffness.clone();
    let alphas = &a.alphas;
    if alphas.is_empty() || alphas.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return Err("--alphas must be finite numbers > 0".into());
    }
    if laws.is_empty() || integrators.is_empty() || dt_mult.is_empty() || stiffness.is_empty() {
        return Err("every sweep list needs at least one value".into());
    }
    if dt_mult.contains(&0) {
        return Err("--dt-mult values must be ≥ 1".into());
    }
    if stiffness.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return Err("--stiffness factors must be finite numbers > 0".into());
    }
    let represented = a.represented.unwrap_or(if a.quick {
        population::REPRESENTED_QUICK
    } else {
        population::REPRESENTED_DEFAULT
    });
    if represented == 0 {
        return Err("--represented must be ≥ 1".into());
    }
    let contacts = base.material.is_some()
        && (base.contact_walls().next().is_some() || base.contacts.is_some());
    if !contacts {
        stiffness = vec![1.0];
    }
    if a.quick {
        base.duration = (base.duration / 10.0).min(0.3).max(base.dt);
        laws.retain(|l| *l != CoarseGrainLaw::Parcel);
        dt_mult.truncate(2);
        integrators.truncate(1);
        stiffness.truncate(1);
    }
    let pts = points(alphas, &laws, &dt_mult, &integrators, &stiffness);
    let reference = Point {
        law: None,
        alpha: 1.0,
        dt_mult: *dt_mult.iter().min().unwrap_or(&1),
        integrator: Integrator::Exponential,
        stiffness: stiffness.iter().copied().fold(0.0, f64::max),
    };
    Ok(Design {
        points: pts,
        reference,
        represented,
    })
}
