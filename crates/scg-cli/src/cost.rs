//! `scg cost`: what accuracy costs in time.
//!
//! A sweep over the knobs that trade accuracy for speed — coarse-grain ratio α, the
//! coarse-graining law, a time-step multiplier, the drag integrator and (with wall or
//! particle contacts) a Young's-modulus reduction factor — on one scene. Every point is
//! run to the end and timed; its error is measured against a reference run.
//!
//! # The original particle and the points
//!
//! * **Single-particle mode** (the scene's original group holds exactly one particle, as in
//!   `cases/uniform.toml` and `cases/vortex.toml`): the *original* is the scene's first
//!   group with α = 1 (the first group when none has α = 1). Every point runs a scene that
//!   holds only that particle, with the point's α and law, at the original's start
//!   position. The other groups of the file (which only show the paper's CG variants side
//!   by side) are dropped.
//! * **Population mode** (any other scene): every group is given the point's α and law and
//!   its random particle count is divided by α³ (a CG particle stands for α³ originals).
//!   No error is computed there yet (see [`population_error_note`]).
//!
//! The points are not the full factorial product: for every (law, α) pair the *base point*
//! uses the first value of each of `--dt-mult`, `--integrators` and `--stiffness`, and each
//! further value of one knob is run with the other knobs at their base value (one knob at
//! a time). α = 1 is the same for every law and runs once, under the law name `original`.
//!
//! # Error
//!
//! The reference is α = 1 with the smallest dt multiplier, the exponential integrator and
//! the largest stiffness factor. The trajectory error of a point is the RMS over common
//! sample times t_k of `|(x(t_k) − x(0)) − (x_ref(t_k) − x_ref(0))| / L`, each particle
//! measured from its own start, with `L` the reference particle's largest displacement
//! from its start. (The maximum over t_k saturates once a particle sits on a wall, which
//! hides how much earlier it got there; the RMS does not.) Errors below [`ERROR_FLOOR`] are clamped to it in the
//! plot (log axes cannot show 0); the CSV keeps the measured value.
//!
//! # Timing
//!
//! Points run one after another on the simulator's thread pool (never in parallel), so
//! that each wall time is not distorted by another run. A single-particle run measures the
//! cost per particle-step; the speed-up column estimates what the same change saves on a
//! system of N originals: `(wall_ref / wall) · n_ref / n` with n = α³ originals represented
//! per CG particle (laws `scg`, `none`, `parcel`; 1 for `mass`, whose particles keep the
//! original's mass and so stand for one original each).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use clap::Args;
use glam::DVec3;
use indicatif::{ProgressBar, ProgressStyle};

use scg_core::physics::contact::NormalLaw;
use scg_core::physics::integrate::Integrator;
use scg_core::physics::scaling::CoarseGrainLaw;
use scg_core::step::StepSet;
use scg_scene::{Placement, Scene};

use crate::EXIT_BAD_INPUT;
use crate::classify;
use crate::study::AnalysisSink;

/// Smallest error shown on the log–log plot.
pub const ERROR_FLOOR: f64 = 1e-16;

/// Arguments of `scg cost`.
#[derive(Args, Debug, Clone)]
pub struct CostArgs {
    /// Scene file.
    pub case: PathBuf,
    /// Output folder for cost.md, cost.csv and cost.svg.
    #[arg(long, default_value = "cost")]
    pub out: PathBuf,
    /// Reduced sweep for CI: a tenth of the duration (at most 0.3 s of simulated time),
    /// laws scg,none,mass, dt multipliers 1,2, the first integrator and stiffness only.
    #[arg(long)]
    pub quick: bool,
    /// Coarse-grain ratios α.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8")]
    pub alphas: Vec<f64>,
    /// Coarse-graining laws.
    #[arg(long, value_delimiter = ',', default_value = "scg,none,mass,parcel")]
    pub laws: Vec<String>,
    /// Time-step multipliers (positive integers) applied to the scene's dt.
    #[arg(long = "dt-mult", value_delimiter = ',', default_value = "1,2,4")]
    pub dt_mult: Vec<u32>,
    /// Drag integrators.
    #[arg(long, value_delimiter = ',', default_value = "exponential,explicit")]
    pub integrators: Vec<String>,
    /// Young's-modulus factors (only with walls or contacts).
    #[arg(long, value_delimiter = ',', default_value = "1,0.1")]
    pub stiffness: Vec<f64>,
    /// Override a scene key before the sweep (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// One point of the sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
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

/// The measured result of one point.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The point.
    pub point: Point,
    /// Time step, s.
    pub dt: f64,
    /// Wall time of the run, s.
    pub wall_s: f64,
    /// Particle-steps.
    pub particle_steps: u64,
    /// Error against the reference (NaN when not computed).
    pub error: f64,
    /// Wall time per step set, s (indexed like [`StepSet::ORDER`]).
    pub sets: [f64; 6],
    /// Why the run stopped early, if it did.
    pub failure: Option<String>,
    /// Classifier scenes: per-class errors.
    pub classes: Option<ClassErrors>,
}

/// Classifier errors of one point against the reference.
#[derive(Clone, Debug, Default)]
pub struct ClassErrors {
    /// Class names.
    pub names: Vec<String>,
    /// W1 of each class's radial distribution to the reference's, / vessel radius.
    pub w1: Vec<f64>,
    /// Cut size d50, m (None when the partition curve never crosses 0.5).
    pub d50: Option<f64>,
    /// |d50 − d50_ref| / d50_ref (NaN when either is missing).
    pub d50_error: f64,
}

/// A finished sweep.
#[derive(Clone, Debug)]
pub struct Sweep {
    /// Scene name.
    pub scene: String,
    /// Simulated duration of every point, s.
    pub duration: f64,
    /// Single-particle mode (trajectory error) or population mode.
    pub single: bool,
    /// The plan of the reference run, rendered.
    pub plan: String,
    /// Systems per set in the reference run.
    pub plan_sets: PlanSets,
    /// Reference point.
    pub reference: Point,
    /// Reference length L, m.
    pub length: f64,
    /// Results, in run order (the reference first).
    pub outcomes: Vec<Outcome>,
    /// Notes for the report.
    pub notes: Vec<String>,
}

fn parse_integrator(s: &str) -> Result<Integrator, String> {
    match s.trim() {
        "exponential" => Ok(Integrator::Exponential),
        "explicit" => Ok(Integrator::Explicit),
        o => Err(format!("unknown integrator `{o}` (exponential, explicit)")),
    }
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

/// Index of the scene's original group: the first with α = 1, else the first.
pub fn original_group(scene: &Scene) -> usize {
    scene
        .groups
        .iter()
        .position(|g| g.alpha == 1.0)
        .unwrap_or(0)
}

/// True when the sweep runs in single-particle mode.
pub fn single_particle(scene: &Scene) -> bool {
    scene.groups[original_group(scene)].count() == 1
}

/// The scene of one point (see the module documentation for the rule).
pub fn point_scene(base: &Scene, p: &Point) -> Scene {
    let mut s = base.clone();
    let law = p.law.unwrap_or(CoarseGrainLaw::Scg);
    if single_particle(base) {
        let mut g = base.groups[original_group(base)].clone();
        g.alpha = p.alpha;
        g.law = law;
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

/// Run one point: wall time, particle-steps, per-set times and the sampled displacement of
/// particle 0 from its start every `sample_base_steps · base_dt` seconds.
fn run_point(
    base: &Scene,
    p: &Point,
    steps_base: u64,
    sample_base_steps: u64,
) -> (Outcome, Vec<DVec3>, String, PlanSets) {
    let scene = point_scene(base, p);
    let mut sim = scene.build(false);
    let plan = sim.plan().render();
    let plan_sets = plan_sets(&sim);
    let m = p.dt_mult as u64;
    let chunk = (sample_base_steps / m).max(1);
    let total = steps_base / m;
    let x0 = sim.particles().first().map_or(DVec3::ZERO, |q| q.position);
    let mut samples = vec![DVec3::ZERO];
    let mut done = 0;
    let mut wall = 0.0;
    let mut failure = None;
    while done + chunk <= total {
        let t0 = Instant::now();
        let r = sim.run(chunk, |_| true);
        wall += t0.elapsed().as_secs_f64();
        if let Err(e) = r {
            failure = Some(e.to_string());
            break;
        }
        done += chunk;
        let x = sim.particles().first().map_or(DVec3::NAN, |q| q.position);
        samples.push(x - x0);
    }
    if failure.is_none() && done < total {
        let t0 = Instant::now();
        if let Err(e) = sim.run(total - done, |_| true) {
            failure = Some(e.to_string());
        }
        wall += t0.elapsed().as_secs_f64();
    }
    let mut sets = [0.0; 6];
    for (i, (_, d)) in sim.timers().by_set().into_iter().enumerate() {
        sets[i] = d.as_secs_f64();
    }
    (
        Outcome {
            point: *p,
            dt: scene.dt,
            wall_s: wall,
            particle_steps: sim.particle_steps(),
            error: f64::NAN,
            sets,
            failure,
            classes: None,
        },
        samples,
        plan,
        plan_sets,
    )
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
fn classifier_overrides(base: &Scene, p: &Point) -> Vec<String> {
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

/// Run one classifier point with the analysis attached (its frames cost a little time,
/// the same for every point).
fn run_classifier_point(
    base: &Scene,
    p: &Point,
) -> (Outcome, Option<classify::Result>, String, PlanSets) {
    let fail = |e: String| Outcome {
        point: *p,
        dt: base.dt * p.dt_mult as f64,
        wall_s: 0.0,
        particle_steps: 0,
        error: f64::NAN,
        sets: [0.0; 6],
        failure: Some(e),
        classes: None,
    };
    let scene = match scg_scene::parse(
        &base.source,
        &base.file,
        &base.name,
        &classifier_overrides(base, p),
    ) {
        Ok(s) => s,
        Err(e) => return (fail(e.to_string()), None, String::new(), Vec::new()),
    };
    let window = (0.5 * scene.duration, scene.duration);
    let params = classify::Params::for_window(window.0, window.1, classify::vessel_radius(&scene));
    let mut sim = scene.build(true);
    let plan = sim.plan().render();
    let plan_sets = plan_sets(&sim);
    let meta = scene.run_meta(Vec::new());
    let analysis = Arc::new(Mutex::new(classify::Analysis::new(
        &meta,
        &scene.flow,
        params,
    )));
    sim.add_recorder(Box::new(AnalysisSink(analysis.clone())));
    let t0 = Instant::now();
    let r = sim
        .record_now()
        .and_then(|_| sim.run(scene.steps(), |_| true));
    let wall = t0.elapsed().as_secs_f64();
    let _ = sim.finish_recorders();
    let mut sets = [0.0; 6];
    for (i, (_, d)) in sim.timers().by_set().into_iter().enumerate() {
        sets[i] = d.as_secs_f64();
    }
    let result = analysis.lock().ok().map(|a| a.result());
    (
        Outcome {
            point: *p,
            dt: scene.dt,
            wall_s: wall,
            particle_steps: sim.particle_steps(),
            error: f64::NAN,
            sets,
            failure: r.err().map(|e| e.to_string()),
            classes: None,
        },
        result,
        plan,
        plan_sets,
    )
}

/// Per-class errors of `v` against `reference`.
fn class_errors(reference: &classify::Result, v: &classify::Result) -> ClassErrors {
    let d_ref = classify::d50(&crate::study::partition(reference));
    let d50 = classify::d50(&crate::study::partition(v));
    ClassErrors {
        names: v.classes.iter().map(|c| c.name.clone()).collect(),
        w1: crate::study::w1_to(reference, v),
        d50,
        d50_error: match (d50, d_ref) {
            (Some(a), Some(b)) => ((a - b) / b).abs(),
            _ => f64::NAN,
        },
    }
}

type PlanSets = Vec<(StepSet, Vec<&'static str>)>;

fn plan_sets(sim: &scg_core::Simulation) -> PlanSets {
    StepSet::ORDER
        .iter()
        .map(|s| (*s, sim.plan().in_set(*s).map(|x| x.system.name()).collect()))
        .collect()
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// The note written when population-mode errors are not computed.
pub fn population_error_note() -> &'static str {
    "population scene without a classifier flow: no error metric is computed (the \
     classifier's per-class W1 and d50 errors apply only to classifier scenes); times and \
     particle-steps are measured"
}

/// Run the whole sweep. `progress` is called after each point.
pub fn sweep(
    base: &Scene,
    pts: &[Point],
    reference: Point,
    mut progress: impl FnMut(&Outcome),
) -> Sweep {
    if is_classifier(base) {
        return sweep_classifier(base, pts, reference, progress);
    }
    let single = single_particle(base);
    let steps_base = base.steps();
    // Sample interval: the scene's record interval, rounded up to a multiple of every dt
    // multiplier, so that all points sample at the same times.
    let lcm = pts
        .iter()
        .chain(std::iter::once(&reference))
        .map(|p| p.dt_mult as u64)
        .fold(1u64, |a, b| a / gcd(a, b) * b);
    let sample = base.record_every.max(1).div_ceil(lcm) * lcm;
    // Warm-up (thread pool, caches, clock ramp): a tenth of the reference, untimed, so
    // that the reference time every speed-up divides is not the slowest by accident.
    let _ = run_point(base, &reference, steps_base / 10, sample);
    let (ref_out, ref_traj, plan, plan_sets) = run_point(base, &reference, steps_base, sample);
    progress(&ref_out);
    let length = ref_traj.iter().map(|d| d.length()).fold(0.0, f64::max);
    let mut notes = Vec::new();
    if !single {
        notes.push(population_error_note().to_string());
    }
    let mut outcomes = vec![ref_out.clone()];
    outcomes[0].error = if single { 0.0 } else { f64::NAN };
    for p in pts {
        if *p == reference {
            continue;
        }
        let (mut o, traj, _, _) = run_point(base, p, steps_base, sample);
        if single {
            let n = traj.len().min(ref_traj.len());
            // RMS over the sample times (NaN propagates): unlike the maximum, it does not
            // saturate once both particles have reached the vessel wall.
            let sq = (0..n)
                .map(|k| (traj[k] - ref_traj[k]).length_squared())
                .sum::<f64>();
            let e = if n > 0 { (sq / n as f64).sqrt() } else { 0.0 };
            o.error = if length > 0.0 { e / length } else { e };
            if o.failure.is_some() {
                o.error = f64::NAN;
            }
        }
        progress(&o);
        outcomes.push(o);
    }
    Sweep {
        scene: base.name.clone(),
        duration: base.duration,
        single,
        plan,
        plan_sets,
        reference,
        length,
        outcomes,
        notes,
    }
}

/// The classifier sweep: error = largest per-class W1 (/ vessel radius) to the reference.
fn sweep_classifier(
    base: &Scene,
    pts: &[Point],
    reference: Point,
    mut progress: impl FnMut(&Outcome),
) -> Sweep {
    let (mut ref_out, ref_res, plan, plan_sets) = run_classifier_point(base, &reference);
    if let Some(r) = &ref_res {
        let ce = class_errors(r, r);
        ref_out.error = ce.w1.iter().copied().fold(0.0, f64::max);
        ref_out.classes = Some(ce);
    }
    progress(&ref_out);
    let mut outcomes = vec![ref_out];
    for p in pts {
        if *p == reference {
            continue;
        }
        let (mut o, res, _, _) = run_classifier_point(base, p);
        if let (Some(r), Some(v), None) = (&ref_res, &res, &o.failure) {
            let ce = class_errors(r, v);
            o.error = ce.w1.iter().copied().fold(
                0.0,
                |a: f64, b| if b.is_nan() { f64::NAN } else { a.max(b) },
            );
            o.classes = Some(ce);
        }
        progress(&o);
        outcomes.push(o);
    }
    Sweep {
        scene: base.name.clone(),
        duration: base.duration,
        single: false,
        plan,
        plan_sets,
        reference,
        length: classify::vessel_radius(base),
        outcomes,
        notes: vec![format!(
            "classifier: every group coarse-grained through `[coarse_grain]` (feeders keep \
             the solid volume rate); error = largest per-class 1-Wasserstein distance of the \
             radial distributions over t ∈ [{}, {}] s to the reference's, divided by the \
             vessel radius; d50 from the partition curve (drained fractions). The analysis \
             reads every recorded frame, included in the wall times.",
            0.5 * base.duration,
            base.duration
        )],
    }
}

/// Originals represented per simulated particle.
fn represented(p: &Point) -> f64 {
    match p.law {
        None | Some(CoarseGrainLaw::Mass) => 1.0,
        Some(_) => p.alpha.powi(3),
    }
}

/// Estimated speed-up for a system of N originals against the reference.
pub fn speedup(s: &Sweep, o: &Outcome) -> f64 {
    let r = &s.outcomes[0];
    let t = r.wall_s / o.wall_s.max(1e-12);
    if s.single {
        t * represented(&o.point) / represented(&r.point)
    } else {
        // The population runs hold the particles themselves.
        t
    }
}

/// Pareto front (indices into `outcomes`): no other point is both faster and more accurate.
pub fn pareto(outcomes: &[Outcome]) -> Vec<usize> {
    let ok: Vec<usize> = (0..outcomes.len())
        .filter(|&i| outcomes[i].error.is_finite() && outcomes[i].failure.is_none())
        .collect();
    let mut front: Vec<usize> = ok
        .iter()
        .copied()
        .filter(|&i| {
            let (t, e) = (outcomes[i].wall_s, outcomes[i].error.max(ERROR_FLOOR));
            !ok.iter().any(|&j| {
                let (tj, ej) = (outcomes[j].wall_s, outcomes[j].error.max(ERROR_FLOOR));
                j != i && tj <= t && ej <= e && (tj < t || ej < e)
            })
        })
        .collect();
    front.sort_by(|a, b| outcomes[*a].wall_s.total_cmp(&outcomes[*b].wall_s));
    front
}

fn fmt_err(e: f64) -> String {
    if e.is_nan() {
        "n/a".into()
    } else {
        format!("{e:.3e}")
    }
}

/// `cost.csv`.
pub fn csv(s: &Sweep) -> String {
    let mut out = String::from(
        "law,alpha,dt,integrator,stiffness,wall_s,particle_steps,particle_steps_per_s,error,speedup,pareto",
    );
    for set in StepSet::ORDER {
        let _ = write!(out, ",t_{}_s", set.name());
    }
    out.push_str(",d50_m,d50_error,w1_per_class,failure\n");
    let front = pareto(&s.outcomes);
    for (i, o) in s.outcomes.iter().enumerate() {
        let _ = write!(
            out,
            "{},{},{:e},{},{},{:.6},{},{:.6e},{:e},{:.4},{}",
            o.point.law_name(),
            o.point.alpha,
            o.dt,
            o.point.integrator.name(),
            o.point.stiffness,
            o.wall_s,
            o.particle_steps,
            o.particle_steps as f64 / o.wall_s.max(1e-12),
            o.error,
            speedup(s, o),
            front.contains(&i)
        );
        for t in o.sets {
            let _ = write!(out, ",{t:.6}");
        }
        match &o.classes {
            Some(c) => {
                let w: Vec<String> = c.w1.iter().map(|x| format!("{x:e}")).collect();
                let _ = write!(
                    out,
                    ",{},{:e},{}",
                    c.d50.map_or(String::new(), |d| format!("{d:e}")),
                    c.d50_error,
                    w.join(";")
                );
            }
            None => out.push_str(",,,"),
        }
        let _ = writeln!(
            out,
            ",{}",
            o.failure.as_deref().unwrap_or("").replace([',', '\n'], ";")
        );
    }
    out
}

/// `cost.md`.
pub fn markdown(s: &Sweep) -> String {
    let mut m = String::new();
    let _ = writeln!(m, "# Cost of accuracy: `{}`\n", s.scene);
    let r = &s.reference;
    let _ = writeln!(
        m,
        "Simulated duration {} s per point. Reference: α = 1, dt × {}, {} integrator, stiffness × {}. \
         Points ran **sequentially** (one at a time, after an untimed warm-up) so that wall times are not distorted by each other; \
         other load on the machine still adds noise of some 10 %.\n",
        s.duration,
        r.dt_mult,
        r.integrator.name(),
        r.stiffness
    );
    if s.single {
        let _ = writeln!(
            m,
            "Error: max over sample times of |Δx − Δx_ref| / L, each particle measured from its own start, \
             L = {:.4e} m (largest displacement of the reference particle); the error is the RMS over the sample times. Errors of exactly 0 are \
             drawn at {ERROR_FLOOR:e} on the plot (log axes).\n",
            s.length
        );
        let _ = writeln!(
            m,
            "Speed-up: (reference wall time / wall time) × (originals represented per particle: α³ for \
             scg, none, parcel; 1 for mass) — the estimate for a system of many originals, measured \
             here on one particle.\n"
        );
    }
    for n in &s.notes {
        let _ = writeln!(m, "Note: {n}\n");
    }
    let _ = writeln!(m, "## Systems that ran (reference run)\n");
    let _ = writeln!(m, "| set | systems |\n|---|---|");
    for (set, sys) in &s.plan_sets {
        let _ = writeln!(
            m,
            "| {} | {} |",
            set.name(),
            if sys.is_empty() {
                "(nothing — no cost)".to_string()
            } else {
                sys.join(", ")
            }
        );
    }
    let _ = writeln!(m, "\n## Points\n");
    let _ = write!(
        m,
        "| law | α | dt [s] | integrator | stiffness | wall [s] | particle-steps | p-steps/s | error | speed-up | Pareto |"
    );
    for set in StepSet::ORDER {
        let _ = write!(m, " {} [s] |", set.name());
    }
    let _ = write!(m, "\n|---|---|---|---|---|---|---|---|---|---|---|");
    for _ in StepSet::ORDER {
        m.push_str("---|");
    }
    m.push('\n');
    let front = pareto(&s.outcomes);
    for (i, o) in s.outcomes.iter().enumerate() {
        let _ = write!(
            m,
            "| {} | {} | {:.3e} | {} | {} | {:.3} | {} | {:.3e} | {} | {:.1} | {} |",
            o.point.law_name(),
            o.point.alpha,
            o.dt,
            o.point.integrator.name(),
            o.point.stiffness,
            o.wall_s,
            o.particle_steps,
            o.particle_steps as f64 / o.wall_s.max(1e-12),
            match &o.failure {
                Some(f) => format!("failed: {f}"),
                None => fmt_err(o.error),
            },
            speedup(s, o),
            if front.contains(&i) { "★" } else { "" }
        );
        for t in o.sets {
            let _ = write!(m, " {t:.3} |");
        }
        m.push('\n');
    }
    if s.single {
        let _ = writeln!(
            m,
            "\n## Speed-up of each α against its error (base points)\n"
        );
        let _ = writeln!(m, "| law | α | speed-up | error |\n|---|---|---|---|");
        for o in &s.outcomes {
            let p = &o.point;
            if p.dt_mult == s.reference.dt_mult
                && p.integrator == s.reference.integrator
                && p.stiffness == s.reference.stiffness
            {
                let _ = writeln!(
                    m,
                    "| {} | {} | {:.1}× | {} |",
                    p.law_name(),
                    p.alpha,
                    speedup(s, o),
                    fmt_err(o.error)
                );
            }
        }
    }
    if let Some(first) = s.outcomes.iter().find_map(|o| o.classes.as_ref()) {
        let _ = writeln!(
            m,
            "\n## Classifier: per-class W1 (/ vessel radius) and d50\n"
        );
        let _ = write!(m, "| law | α | dt [s] | integrator | stiffness |");
        for n in &first.names {
            let _ = write!(m, " W1 {n} |");
        }
        let _ = writeln!(m, " d50 [µm] | d50 error |");
        let _ = write!(m, "|---|---|---|---|---|");
        for _ in &first.names {
            m.push_str("---|");
        }
        m.push_str("---|---|\n");
        for o in &s.outcomes {
            let Some(c) = &o.classes else { continue };
            let _ = write!(
                m,
                "| {} | {} | {:.3e} | {} | {} |",
                o.point.law_name(),
                o.point.alpha,
                o.dt,
                o.point.integrator.name(),
                o.point.stiffness
            );
            for w in &c.w1 {
                let _ = write!(m, " {} |", fmt_err(*w));
            }
            let _ = writeln!(
                m,
                " {} | {} |",
                c.d50.map_or("—".into(), |d| format!("{:.1}", d * 1e6)),
                fmt_err(c.d50_error)
            );
        }
    }
    let _ = writeln!(
        m,
        "\nPlot: `cost.svg` (log–log error vs wall time, ★ = Pareto front)."
    );
    m
}

/// `cost.svg`: log–log error against wall time, one series per law, Pareto front marked.
pub fn plot(s: &Sweep, path: &Path) -> Result<(), String> {
    use plotters::prelude::*;
    let pts: Vec<(&Outcome, f64, f64)> = s
        .outcomes
        .iter()
        .filter(|o| o.error.is_finite() && o.failure.is_none())
        .map(|o| (o, o.wall_s.max(1e-6), o.error.max(ERROR_FLOOR)))
        .collect();
    if pts.is_empty() {
        return Ok(());
    }
    if path.extension().is_some_and(|x| x == "png") {
        draw(
            s,
            &pts,
            BitMapBackend::new(path, (900, 620)).into_drawing_area(),
        )
    } else {
        draw(
            s,
            &pts,
            SVGBackend::new(path, (900, 620)).into_drawing_area(),
        )
    }
}

fn draw<DB: plotters::prelude::DrawingBackend>(
    s: &Sweep,
    pts: &[(&Outcome, f64, f64)],
    root: plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    use plotters::prelude::*;
    let (tmin, tmax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.1), b.max(p.1))
    });
    let (emin, emax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.2), b.max(p.2))
    });
    let e = |x: plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("scg cost: {} (errors clamped at {ERROR_FLOOR:e})", s.scene),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (tmin / 1.5..tmax * 1.5).log_scale(),
            (emin / 10.0..(emax * 10.0).max(emin * 100.0)).log_scale(),
        )
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("wall time [s]")
        .y_desc("error")
        .x_label_formatter(&|v| format!("{v:.3}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(e)?;
    let laws = ["original", "scg", "none", "mass", "parcel"];
    for (k, law) in laws.iter().enumerate() {
        let series: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.0.point.law_name() == *law)
            .map(|p| (p.1, p.2))
            .collect();
        if series.is_empty() {
            continue;
        }
        let c = Palette99::pick(k).to_rgba();
        chart
            .draw_series(
                series
                    .iter()
                    .map(|&(x, y)| Circle::new((x, y), 5, c.filled())),
            )
            .map_err(e)?
            .label(*law)
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
    }
    let front: Vec<(f64, f64)> = pareto(&s.outcomes)
        .into_iter()
        .map(|i| {
            let o = &s.outcomes[i];
            (o.wall_s.max(1e-6), o.error.max(ERROR_FLOOR))
        })
        .collect();
    chart
        .draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(1)))
        .map_err(e)?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    chart
        .draw_series(
            front
                .iter()
                .map(|&(x, y)| Circle::new((x, y), 9, BLACK.stroke_width(2))),
        )
        .map_err(e)?;
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(e)?;
    root.present().map_err(e)?;
    Ok(())
}

/// Run `scg cost`; returns the exit status.
pub fn cost(a: CostArgs) -> i32 {
    let mut base = match scg_scene::load(&a.case, &a.set) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_BAD_INPUT;
        }
    };
    let bad = |m: String| {
        eprintln!("error: {m}");
        EXIT_BAD_INPUT
    };
    let laws: Result<Vec<CoarseGrainLaw>, String> = a
        .laws
        .iter()
        .map(|l| {
            CoarseGrainLaw::from_name(l.trim())
                .ok_or_else(|| format!("unknown law `{l}` (scg, none, mass, parcel)"))
        })
        .collect();
    let mut laws = match laws {
        Ok(l) => l,
        Err(m) => return bad(m),
    };
    let integrators: Result<Vec<Integrator>, String> =
        a.integrators.iter().map(|s| parse_integrator(s)).collect();
    let mut integrators = match integrators {
        Ok(i) => i,
        Err(m) => return bad(m),
    };
    let mut dt_mult = a.dt_mult.clone();
    let mut stiffness = a.stiffness.clone();
    let alphas = a.alphas.clone();
    if alphas.is_empty() || alphas.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return bad("--alphas must be finite numbers > 0".into());
    }
    if laws.is_empty() || integrators.is_empty() || dt_mult.is_empty() || stiffness.is_empty() {
        return bad("every sweep list needs at least one value".into());
    }
    if dt_mult.contains(&0) {
        return bad("--dt-mult values must be ≥ 1".into());
    }
    if stiffness.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
        return bad("--stiffness factors must be finite numbers > 0".into());
    }
    let contacts = base.material.is_some() && (!base.walls.is_empty() || base.contacts.is_some());
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
    let pts = points(&alphas, &laws, &dt_mult, &integrators, &stiffness);
    let reference = Point {
        law: None,
        alpha: 1.0,
        dt_mult: *dt_mult.iter().min().unwrap_or(&1),
        integrator: Integrator::Exponential,
        stiffness: stiffness.iter().copied().fold(0.0, f64::max),
    };
    if let Err(e) = crate::run::ensure_writable(&a.out) {
        return bad(e);
    }
    let n = 1 + pts.iter().filter(|p| **p != reference).count();
    eprintln!(
        "scg cost `{}`: {} points of {} s simulated each, run sequentially for honest timings{}",
        base.name,
        n,
        base.duration,
        if single_particle(&base) {
            " (single-particle mode: the original particle alone)"
        } else {
            " (population mode)"
        }
    );
    let bar = ProgressBar::new(n as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} points  {elapsed_precise} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let s = sweep(&base, &pts, reference, |o| {
        bar.set_message(format!(
            "{} α={} {:.1e}s {}",
            o.point.law_name(),
            o.point.alpha,
            o.dt,
            fmt_err(o.error)
        ));
        bar.inc(1);
    });
    bar.finish_and_clear();
    let md = markdown(&s);
    let files = [
        (a.out.join("cost.md"), md.clone()),
        (a.out.join("cost.csv"), csv(&s)),
    ];
    for (p, text) in &files {
        if let Err(e) = std::fs::write(p, text) {
            eprintln!("error: cannot write {}: {e}", p.display());
            return 1;
        }
    }
    let svg = a.out.join("cost.svg");
    if let Err(e) = plot(&s, &svg) {
        eprintln!("error: cannot draw {}: {e}", svg.display());
        return 1;
    }
    print!("{md}");
    for (p, _) in &files {
        eprintln!("wrote {}", p.display());
    }
    eprintln!("wrote {}", svg.display());
    0
}
