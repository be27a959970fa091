//! Running the sweep: each point timed on its own, the reference first, and the error of
//! every point against it (trajectory error, or per-class W1 and d50 on classifier scenes);
//! the measured speed-up, the α³ estimate and the Pareto front derived from the
//! measurements.

use std::time::Instant;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use scg_core::Simulation;
use scg_core::physics::scaling::CoarseGrainLaw;
use scg_core::step::StepSet;
use scg_scene::Scene;

use crate::analysis::{self, Analysis, Params, SharedAnalysis, cut_size, cut_size95, w1_to};
use crate::points::{Points, map};

use super::ERROR_FLOOR;
use super::sweep::{Point, classifier_overrides, is_classifier, point_scene, single_particle};

/// Wall time per step set, s, indexed like [`StepSet::ORDER`].
pub type SetTimes = [f64; StepSet::ORDER.len()];

/// The measured result of one point.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Outcome {
    /// The point.
    pub point: Point,
    /// Time step, s.
    pub dt: f64,
    /// Wall time of the run (the whole population), s.
    pub wall_s: f64,
    /// Steps run.
    pub steps: u64,
    /// Particle-steps.
    pub particle_steps: u64,
    /// Single-particle scenes: wall time of the original particle alone at this point, s
    /// (only for the α³ estimate).
    pub alone_wall_s: Option<f64>,
    /// Error against the reference (NaN when not computed; `null` in JSON).
    #[serde(with = "super::nan::num")]
    pub error: f64,
    /// Wall time per step set, s (indexed like [`StepSet::ORDER`]).
    pub sets: SetTimes,
    /// Why the run stopped early, if it did.
    pub failure: Option<String>,
    /// Classifier scenes: per-class errors.
    pub classes: Option<ClassErrors>,
    /// Particle–particle contacts started during the run.
    #[serde(default)]
    pub pair_contacts: u64,
    /// Particle–wall contacts started during the run.
    #[serde(default)]
    pub wall_contacts: u64,
}

impl Outcome {
    /// A point that measured nothing (yet): no wall time, no particle-steps, no error.
    fn unmeasured(point: Point, dt: f64, failure: Option<String>) -> Self {
        Outcome {
            point,
            dt,
            wall_s: 0.0,
            steps: 0,
            particle_steps: 0,
            alone_wall_s: None,
            error: f64::NAN,
            sets: [0.0; StepSet::ORDER.len()],
            failure,
            classes: None,
            pair_contacts: 0,
            wall_contacts: 0,
        }
    }

    /// What `sim` measured after running `point` for `wall_s` (the error comes later).
    fn measured(
        point: Point,
        sim: &Simulation,
        dt: f64,
        wall_s: f64,
        failure: Option<String>,
    ) -> Self {
        let contacts = sim.contact_resolution();
        Outcome {
            wall_s,
            steps: sim.step_count(),
            particle_steps: sim.particle_steps(),
            sets: set_times(sim),
            pair_contacts: contacts.pair.contacts,
            wall_contacts: contacts.wall.contacts,
            ..Outcome::unmeasured(point, dt, failure)
        }
    }

    /// Particle–particle contacts per simulated particle per second of simulated time (a
    /// contact counts for both its particles), 1/s; NaN before any step.
    pub fn contact_rate(&self) -> f64 {
        2.0 * self.pair_contacts as f64 / (self.particle_steps as f64 * self.dt)
    }

    /// Particle-steps per second of wall time.
    pub fn particle_steps_per_s(&self) -> f64 {
        self.particle_steps as f64 / self.wall_s.max(1e-12)
    }

    /// Simulated particles, the mean over the run (particle-steps / steps; the count at
    /// the start unless feeders or an outlet change it).
    pub fn particles(&self) -> f64 {
        self.particle_steps as f64 / self.steps.max(1) as f64
    }
}

/// Wall time per step set of a simulation's run so far.
fn set_times(sim: &Simulation) -> SetTimes {
    let mut sets = [0.0; StepSet::ORDER.len()];
    for (t, (_, d)) in sets.iter_mut().zip(sim.timers().by_set()) {
        *t = d.as_secs_f64();
    }
    sets
}

/// Classifier errors of one point against the reference.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct ClassErrors {
    /// Class names.
    pub names: Vec<String>,
    /// W1 of each class's radial distribution to the reference's, / vessel radius.
    #[serde(with = "super::nan::nums")]
    pub w1: Vec<f64>,
    /// Cut size d50, m (None when the partition curve never crosses 0.5).
    pub d50: Option<f64>,
    /// |d50 − d50_ref| / d50_ref (NaN when either is missing).
    #[serde(with = "super::nan::num")]
    pub d50_error: f64,
    /// 95 % bootstrap interval of each class's W1 (by particle), / vessel radius.
    #[serde(with = "super::nan::pairs")]
    pub w1_95: Vec<(f64, f64)>,
    /// W1 of each class that sampling noise alone reaches in 5 % of runs of these sizes
    /// (permutation test), / vessel radius: W1 at or below it agrees with the reference.
    #[serde(with = "super::nan::nums")]
    pub w1_noise95: Vec<f64>,
    /// 95 % bootstrap interval of d50, m (a NaN bound where it is open).
    #[serde(with = "super::nan::opt_pair")]
    pub d50_95: Option<(f64, f64)>,
    /// Whether d50 agrees with the reference's within the intervals: |Δ| ≤ the two
    /// half-widths added in quadrature (None when either is missing or open).
    pub d50_agrees: Option<bool>,
}

impl ClassErrors {
    /// Whether every class's W1 is within the sampling noise.
    pub fn w1_agrees(&self) -> bool {
        self.w1.iter().zip(&self.w1_noise95).all(|(w, n)| w <= n)
    }
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
    /// Single-particle mode: originals every point's population stands for.
    pub represented: Option<usize>,
    /// Threads of the simulator's team (of each process), and the particle count from
    /// which a pass runs on it (below it, on the calling thread alone).
    pub threads: (usize, usize),
    /// Processes the points were spread over (1: run one after another here).
    pub processes: usize,
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

/// Run one point (in a single-particle scene: the population standing for `represented`
/// originals, or the original alone for `None`): wall time, particle-steps, per-set times
/// and the sampled displacement of particle 0 from its start every
/// `sample_base_steps · base_dt` seconds.
fn run_point(
    base: &Scene,
    p: &Point,
    represented: Option<usize>,
    steps_base: u64,
    sample_base_steps: u64,
) -> (Outcome, Vec<DVec3>) {
    let scene = point_scene(base, p, represented);
    let mut sim = scene.build(false);
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
    (
        Outcome::measured(*p, &sim, scene.dt, wall, failure),
        samples,
    )
}

/// Run one classifier point with the analysis attached (its frames cost a little time,
/// the same for every point).
fn run_classifier_point(base: &Scene, p: &Point) -> (Outcome, Option<analysis::Result>) {
    let scene = match scg_scene::parse(
        &base.source,
        &base.file,
        &base.name,
        &classifier_overrides(base, p),
    ) {
        Ok(s) => s,
        Err(e) => {
            let dt = base.dt * p.dt_mult as f64;
            let fail = Outcome::unmeasured(*p, dt, Some(e.to_string()));
            return (fail, None);
        }
    };
    let params = Params::for_scene(&scene, 0.5 * scene.duration, scene.duration);
    let mut sim = scene.build(true);
    let meta = scene.run_meta(Vec::new());
    let analysis = SharedAnalysis::attach(&mut sim, Analysis::new(&meta, &scene.flow, params));
    let t0 = Instant::now();
    let r = sim
        .record_now()
        .and_then(|_| sim.run(scene.steps(), |_| true));
    let wall = t0.elapsed().as_secs_f64();
    let _ = sim.finish_recorders();
    let result = analysis.result().ok();
    let failure = r.err().map(|e| e.to_string());
    (Outcome::measured(*p, &sim, scene.dt, wall, failure), result)
}

/// The team size and the parallel threshold in force.
fn team() -> (usize, usize) {
    let e = scg_core::exec::settings();
    (e.team_size(), e.parallel_min)
}

/// Per-class errors of `v` against `reference`, whose cut size and its interval are
/// `ref_cut` (computed once per sweep).
fn class_errors(
    reference: &analysis::Result,
    ref_cut: (Option<f64>, Option<(f64, f64)>),
    v: &analysis::Result,
) -> ClassErrors {
    let (d_ref, ref95) = ref_cut;
    let d50 = cut_size(v);
    let d50_95 = cut_size95(v);
    let intervals = analysis::w1_intervals(reference, v);
    let half = |i: Option<(f64, f64)>| i.map(|(lo, hi)| 0.5 * (hi - lo)).filter(|h| h.is_finite());
    ClassErrors {
        names: v.classes.iter().map(|c| c.name.clone()).collect(),
        w1: w1_to(reference, v),
        d50,
        d50_error: match (d50, d_ref) {
            (Some(a), Some(b)) => ((a - b) / b).abs(),
            _ => f64::NAN,
        },
        w1_95: intervals.iter().map(|x| x.0).collect(),
        w1_noise95: intervals.iter().map(|x| x.1).collect(),
        d50_95,
        d50_agrees: match (d50, d_ref, half(d50_95), half(ref95)) {
            (Some(a), Some(b), Some(h), Some(k)) => Some((a - b).abs() <= h.hypot(k)),
            _ => None,
        },
    }
}

/// The systems of each step set, in [`StepSet::ORDER`].
pub type PlanSets = Vec<(StepSet, Vec<&'static str>)>;

fn plan_sets(sim: &Simulation) -> PlanSets {
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

/// The plan of the reference run, rendered, and its systems per set (from the scene
/// built, not run: the same plan as the run's).
fn reference_plan(
    base: &Scene,
    reference: &Point,
    population: Option<usize>,
) -> (String, PlanSets) {
    let scene = if is_classifier(base) {
        match scg_scene::parse(
            &base.source,
            &base.file,
            &base.name,
            &classifier_overrides(base, reference),
        ) {
            Ok(s) => s,
            Err(_) => return (String::new(), Vec::new()),
        }
    } else {
        point_scene(base, reference, population)
    };
    let sim = scene.build(is_classifier(base));
    (sim.plan().render(), plan_sets(&sim))
}

/// Estimated cost of a point (to balance the points over processes): simulated particles
/// over the dt multiplier (single-particle scenes: the population, plus the original
/// alone; population scenes: 1/α³ of the scene's).
fn point_cost(base: &Scene, p: &Point, represented: usize) -> f64 {
    let n = if single_particle(base) {
        super::population::simulated_count(p.law, p.alpha, represented) as f64 + 1.0
    } else {
        p.alpha.powi(-3)
    };
    n / p.dt_mult as f64
}

/// Run the whole sweep through `points` (the reference first, then every other point,
/// each timed on its own; spread over processes by another [`Points`] than
/// [`crate::points::Local`]). `progress` is called after each point this process ran
/// (its error is not known yet: NaN). `represented`: originals every point of a
/// single-particle scene stands for. The finished sweep on the process that writes the
/// outputs, `None` on the others.
pub fn sweep(
    base: &Scene,
    pts: &[Point],
    reference: Point,
    represented: usize,
    points: &dyn Points,
    mut progress: impl FnMut(&Outcome),
) -> Option<Sweep> {
    // The reference first, then the other points in order.
    let jobs: Vec<Point> = std::iter::once(reference)
        .chain(pts.iter().copied().filter(|p| *p != reference))
        .collect();
    let cost: Vec<f64> = jobs
        .iter()
        .map(|p| point_cost(base, p, represented))
        .collect();
    if is_classifier(base) {
        let runs = map(points, jobs.len(), &cost, |i| {
            let r = run_classifier_point(base, &jobs[i]);
            progress(&r.0);
            r
        })?;
        return Some(sweep_classifier(base, runs, reference, points.processes()));
    }
    let single = single_particle(base);
    let steps_base = base.steps();
    // Sample interval: the scene's record interval, rounded up to a multiple of every dt
    // multiplier, so that all points sample at the same times.
    let lcm = jobs
        .iter()
        .map(|p| p.dt_mult as u64)
        .fold(1u64, |a, b| a / gcd(a, b) * b);
    let sample = base.record_every.max(1).div_ceil(lcm) * lcm;
    let population = single.then_some(represented);
    // Warm-up (thread pool, caches, clock ramp) in every process: a tenth of the
    // reference, untimed, so that the reference time every speed-up divides is not the
    // slowest by accident.
    let _ = run_point(base, &reference, population, steps_base / 10, sample);
    let runs = map(points, jobs.len(), &cost, |i| {
        let p = &jobs[i];
        let (mut o, traj) = run_point(base, p, population, steps_base, sample);
        // The original alone at the point: the wall time of the α³ estimate.
        o.alone_wall_s = single.then(|| run_point(base, p, None, steps_base, sample).0.wall_s);
        progress(&o);
        (o, traj)
    })?;
    let (plan, plan_sets) = reference_plan(base, &reference, population);
    let ref_traj = &runs[0].1;
    let length = ref_traj.iter().map(|d| d.length()).fold(0.0, f64::max);
    let mut notes = Vec::new();
    if !single {
        notes.push(population_error_note().to_string());
    }
    let mut outcomes = Vec::with_capacity(runs.len());
    for (i, (mut o, traj)) in runs.iter().cloned().enumerate() {
        if i == 0 {
            o.error = if single { 0.0 } else { f64::NAN };
        } else if single {
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
        outcomes.push(o);
    }
    Some(Sweep {
        scene: base.name.clone(),
        duration: base.duration,
        single,
        represented: population,
        threads: team(),
        processes: points.processes(),
        plan,
        plan_sets,
        reference,
        length,
        outcomes,
        notes,
    })
}

/// The classifier sweep from its runs (the reference first): error = largest per-class
/// W1 (/ vessel radius) to the reference.
fn sweep_classifier(
    base: &Scene,
    runs: Vec<(Outcome, Option<analysis::Result>)>,
    reference: Point,
    processes: usize,
) -> Sweep {
    let (plan, plan_sets) = reference_plan(base, &reference, None);
    let ref_res = runs[0].1.clone();
    let ref_cut = ref_res
        .as_ref()
        .map_or((None, None), |r| (cut_size(r), cut_size95(r)));
    let mut outcomes = Vec::with_capacity(runs.len());
    for (i, (mut o, res)) in runs.into_iter().enumerate() {
        if i == 0 {
            if let Some(r) = &ref_res {
                let ce = class_errors(r, ref_cut, r);
                o.error = ce.w1.iter().copied().fold(0.0, f64::max);
                o.classes = Some(ce);
            }
        } else if let (Some(r), Some(v), None) = (&ref_res, &res, &o.failure) {
            let ce = class_errors(r, ref_cut, v);
            o.error = ce.w1.iter().copied().fold(
                0.0,
                |a: f64, b| if b.is_nan() { f64::NAN } else { a.max(b) },
            );
            o.classes = Some(ce);
        }
        outcomes.push(o);
    }
    Sweep {
        scene: base.name.clone(),
        duration: base.duration,
        single: false,
        represented: None,
        threads: team(),
        processes,
        plan,
        plan_sets,
        reference,
        length: analysis::vessel_radius(base),
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

/// Originals one particle alone stands for in the α³ estimate: α³ (`scg`, `none`,
/// `parcel`, `sample`), 1 for `mass` (its particle keeps one original's mass).
fn alone_represents(p: &Point) -> f64 {
    match p.law {
        None | Some(CoarseGrainLaw::Mass) => 1.0,
        Some(_) => p.alpha.powi(3),
    }
}

/// Measured speed-up against the reference: `wall_ref / wall`, both runs standing for the
/// same originals (single-particle scenes: the same `N_orig`; population scenes: the
/// scene's particles, α³ fewer per CG particle).
pub fn speedup(s: &Sweep, o: &Outcome) -> f64 {
    s.outcomes[0].wall_s / o.wall_s.max(1e-12)
}

/// The old estimate (single-particle scenes only, else NaN): the original alone timed at
/// the point and at the reference, times the originals one particle stands for,
/// `(wall_alone_ref / wall_alone) · n / n_ref`.
pub fn est_speedup_alpha3(s: &Sweep, o: &Outcome) -> f64 {
    let r = &s.outcomes[0];
    match (r.alone_wall_s, o.alone_wall_s) {
        (Some(tr), Some(t)) => {
            tr / t.max(1e-12) * alone_represents(&o.point) / alone_represents(&r.point)
        }
        _ => f64::NAN,
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
