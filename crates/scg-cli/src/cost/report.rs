//! The sweep's tables: `cost.csv` and `cost.md`.

use std::fmt::Write as _;

use scg_core::step::StepSet;

use super::ERROR_FLOOR;
use super::run::{Outcome, Sweep, est_speedup_alpha3, pareto, speedup};

/// An error for the Markdown table and the progress bar (`n/a` for NaN).
pub(super) fn fmt_err(e: f64) -> String {
    if e.is_nan() {
        "n/a".into()
    } else {
        format!("{e:.3e}")
    }
}

/// "SCG against plain sampling": per α, every law's base point beside the `sample` point
/// of the same α (the same simulated count of originals), error and wall time; empty
/// when the sweep has no `sample` point.
fn against_sampling(s: &Sweep) -> String {
    use scg_core::physics::scaling::CoarseGrainLaw;
    let r = &s.reference;
    let base = |o: &&Outcome| {
        o.point.dt_mult == r.dt_mult
            && o.point.integrator == r.integrator
            && o.point.stiffness == r.stiffness
            && o.failure.is_none()
    };
    let samples: Vec<&Outcome> = s
        .outcomes
        .iter()
        .filter(base)
        .filter(|o| o.point.law == Some(CoarseGrainLaw::Sample))
        .collect();
    if samples.is_empty() {
        return String::new();
    }
    let mut m = String::from(
        "\n## Against plain sampling (base points)\n\n`sample` simulates the same number \
         of particles as a coarse-grained point of its α, each an original: no model error, \
         only the smaller population. A law pays only where its error is below sampling's at \
         the same wall time.\n\n| α | law | error | wall [s] | sample error | sample wall [s] | \
         better than sampling |\n|---|---|---|---|---|---|---|\n",
    );
    for smp in samples {
        for o in s.outcomes.iter().filter(base).filter(|o| {
            o.point.alpha == smp.point.alpha
                && o.point.law.is_some()
                && o.point.law != Some(CoarseGrainLaw::Sample)
        }) {
            let better = if o.error < smp.error && o.wall_s <= 1.1 * smp.wall_s {
                "yes"
            } else {
                "no"
            };
            let _ = writeln!(
                m,
                "| {} | {} | {} | {:.3} | {} | {:.3} | {better} |",
                o.point.alpha,
                o.point.law_name(),
                fmt_err(o.error),
                o.wall_s,
                fmt_err(smp.error),
                smp.wall_s
            );
        }
    }
    m
}

/// A mean particle count for the CSV: whole numbers as such, else two decimals.
fn fmt_particles(n: f64) -> String {
    if n.fract() == 0.0 {
        format!("{n}")
    } else {
        format!("{n:.2}")
    }
}

/// The α³ estimate for the CSV (empty where there is none).
fn fmt_est(x: f64) -> String {
    if x.is_nan() {
        String::new()
    } else {
        format!("{x:.4}")
    }
}

/// `cost.csv`.
pub fn csv(s: &Sweep) -> String {
    let mut out = String::from(
        "law,alpha,dt,integrator,stiffness,represented,particles,wall_s,particle_steps,\
         particle_steps_per_s,error,speedup,est_speedup_alpha3,wall_alone_s,pareto",
    );
    for set in StepSet::ORDER {
        let _ = write!(out, ",t_{}_s", set.name());
    }
    out.push_str(
        ",d50_m,d50_error,w1_per_class,d50_lo_m,d50_hi_m,d50_agrees,w1_lo_per_class,\
         w1_hi_per_class,w1_noise95_per_class,w1_agrees,failure\n",
    );
    let front = pareto(&s.outcomes);
    for (i, o) in s.outcomes.iter().enumerate() {
        let _ = write!(
            out,
            "{},{},{:e},{},{},{},{},{:.6},{},{:.6e},{:e},{:.4},{},{},{}",
            o.point.law_name(),
            o.point.alpha,
            o.dt,
            o.point.integrator.name(),
            o.point.stiffness,
            s.represented.map_or(String::new(), |n| n.to_string()),
            fmt_particles(o.particles()),
            o.wall_s,
            o.particle_steps,
            o.particle_steps_per_s(),
            o.error,
            speedup(s, o),
            fmt_est(est_speedup_alpha3(s, o)),
            o.alone_wall_s.map_or(String::new(), |t| format!("{t:.6}")),
            front.contains(&i)
        );
        for t in o.sets {
            let _ = write!(out, ",{t:.6}");
        }
        match &o.classes {
            Some(c) => {
                let list = |v: &mut dyn Iterator<Item = f64>| -> String {
                    v.map(|x| format!("{x:e}")).collect::<Vec<_>>().join(";")
                };
                let _ = write!(
                    out,
                    ",{},{:e},{},{},{},{},{},{},{},{}",
                    c.d50.map_or(String::new(), |d| format!("{d:e}")),
                    c.d50_error,
                    list(&mut c.w1.iter().copied()),
                    c.d50_95.map_or(String::new(), |d| format!("{:e}", d.0)),
                    c.d50_95.map_or(String::new(), |d| format!("{:e}", d.1)),
                    c.d50_agrees.map_or(String::new(), |a| a.to_string()),
                    list(&mut c.w1_95.iter().map(|x| x.0)),
                    list(&mut c.w1_95.iter().map(|x| x.1)),
                    list(&mut c.w1_noise95.iter().copied()),
                    c.w1_agrees()
                );
            }
            None => out.push_str(",,,,,,,,,,"),
        }
        let _ = writeln!(
            out,
            ",{}",
            o.failure.as_deref().unwrap_or("").replace([',', '\n'], ";")
        );
    }
    out
}

/// The head of the point columns of a Markdown table, and its rule.
const MD_POINT_HEAD: &str = "| law | α | dt [s] | integrator | stiffness |";
const MD_POINT_RULE: &str = "|---|---|---|---|---|";

/// The point columns of a Markdown row (under [`MD_POINT_HEAD`]).
fn md_point(o: &Outcome) -> String {
    format!(
        "| {} | {} | {:.3e} | {} | {} |",
        o.point.law_name(),
        o.point.alpha,
        o.dt,
        o.point.integrator.name(),
        o.point.stiffness
    )
}

/// The α³ estimate for the Markdown tables (`—` where there is none).
fn fmt_est_md(x: f64) -> String {
    if x.is_nan() {
        "—".into()
    } else {
        format!("{x:.1}×")
    }
}

/// `cost.md`.
pub fn markdown(s: &Sweep) -> String {
    let mut m = String::new();
    let _ = writeln!(m, "# Cost of accuracy: `{}`\n", s.scene);
    let r = &s.reference;
    let _ = writeln!(
        m,
        "Simulated duration {} s per point. Reference: α = 1, dt × {}, {} integrator, stiffness × {}. \
         Points ran **sequentially** (one at a time, after an untimed warm-up{}) so that wall times are not distorted by each other; \
         other load on the machine still adds noise of some 10 %. Threads: {}{} (a pass over {} or more \
         particles runs on all of them, a smaller one on one thread; `--threads N` or \
         `SCG_THREADS`).\n",
        s.duration,
        r.dt_mult,
        r.integrator.name(),
        r.stiffness,
        if s.processes > 1 {
            format!(", on each of {} MPI ranks sharing the points", s.processes)
        } else {
            String::new()
        },
        s.threads.0,
        if s.processes > 1 { " per rank" } else { "" },
        s.threads.1
    );
    if let (true, Some(n)) = (s.single, s.represented) {
        let _ = writeln!(
            m,
            "Every point stands for the same **{n} original particles**: α = 1 simulates all of \
             them, a coarse-grained point N/α³ (rounded, at least 1) of its law, particle 0 at the \
             original's start and the others spread over the region the scene's particles live \
             in (vortex: the original's radius, spread in angle and height). **wall** is the \
             measured whole run of that population; **speed-up** = reference wall / wall, both \
             for the same {n} originals.\n"
        );
        let _ = writeln!(
            m,
            "Error: on particle 0 against particle 0 of the reference population, the RMS over \
             sample times of |Δx − Δx_ref| / L, each particle measured from its own start, \
             L = {:.4e} m (largest displacement of the reference particle). The particles do not \
             touch each other and the flow is the same along each particle's path up to a shift \
             or rotation, so every particle of a population has this error. Errors of exactly 0 \
             are drawn at {ERROR_FLOOR:e} on the plot (log axes).\n",
            s.length
        );
        let _ = writeln!(
            m,
            "est. α³ (`est_speedup_alpha3`): the old estimate, **not a measurement of the \
             population** — the original particle alone timed at the point and at the \
             reference (wall alone), times the originals one particle stands for (α³ for scg, \
             none, parcel; 1 for mass). A lone particle's run is dominated by the per-step \
             overhead, so it shows roughly α³ × the dt multiplier, not what the scene costs.\n"
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
        "{MD_POINT_HEAD} particles | wall [s] | particle-steps | p-steps/s | error | speed-up | est. α³ | Pareto |"
    );
    for set in StepSet::ORDER {
        let _ = write!(m, " {} [s] |", set.name());
    }
    let _ = write!(m, "\n{MD_POINT_RULE}---|---|---|---|---|---|---|---|");
    for _ in StepSet::ORDER {
        m.push_str("---|");
    }
    m.push('\n');
    let front = pareto(&s.outcomes);
    for (i, o) in s.outcomes.iter().enumerate() {
        let _ = write!(
            m,
            "{} {} | {:.3} | {} | {:.3e} | {} | {:.2} | {} | {} |",
            md_point(o),
            o.particles().round(),
            o.wall_s,
            o.particle_steps,
            o.particle_steps_per_s(),
            match &o.failure {
                Some(f) => format!("failed: {f}"),
                None => fmt_err(o.error),
            },
            speedup(s, o),
            fmt_est_md(est_speedup_alpha3(s, o)),
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
        let _ = writeln!(
            m,
            "| law | α | particles | wall [s] | speed-up (measured) | est. α³ | error |\n\
             |---|---|---|---|---|---|---|"
        );
        for o in &s.outcomes {
            let p = &o.point;
            if p.dt_mult == s.reference.dt_mult
                && p.integrator == s.reference.integrator
                && p.stiffness == s.reference.stiffness
            {
                let _ = writeln!(
                    m,
                    "| {} | {} | {} | {:.3} | {:.2}× | {} | {} |",
                    p.law_name(),
                    p.alpha,
                    o.particles().round(),
                    o.wall_s,
                    speedup(s, o),
                    fmt_est_md(est_speedup_alpha3(s, o)),
                    fmt_err(o.error)
                );
            }
        }
    }
    m.push_str(&against_sampling(s));
    if let Some(first) = s.outcomes.iter().find_map(|o| o.classes.as_ref()) {
        let _ = writeln!(
            m,
            "\n## Classifier: per-class W1 (/ vessel radius) and d50\n\n\
             Each W1 cell reads `W1 ≤ noise` (agrees) or `W1 > noise` (differs): noise is the W1 \
             that two runs of these particle counts reach from sampling alone in 5 % of cases \
             (a permutation test over particles, {} splits). d50 with its 95 % bootstrap \
             interval ({} redraws of each class's drained count; `…` = open: the data cannot \
             place the cut on that side); its error is ✓ when |Δd50| is within the two \
             intervals' half-widths added in quadrature. CSV: the W1 intervals too.\n",
            crate::analysis::interval::RESAMPLES,
            crate::analysis::interval::RESAMPLES
        );
        m.push_str(MD_POINT_HEAD);
        for n in &first.names {
            let _ = write!(m, " W1 {n} |");
        }
        let _ = writeln!(m, " d50 [µm] | d50 error |");
        m.push_str(MD_POINT_RULE);
        for _ in &first.names {
            m.push_str("---|");
        }
        m.push_str("---|---|\n");
        for o in &s.outcomes {
            let Some(c) = &o.classes else { continue };
            m.push_str(&md_point(o));
            for (w, n) in c.w1.iter().zip(&c.w1_noise95) {
                let rel = if w <= n { "≤" } else { ">" };
                let _ = write!(m, " {w:.4} {rel} {n:.4} |");
            }
            let bound = |x: f64| {
                if x.is_finite() {
                    format!("{:.1}", x * 1e6)
                } else {
                    "…".into()
                }
            };
            let _ = writeln!(
                m,
                " {} | {} |",
                match (c.d50, c.d50_95) {
                    (Some(d), Some((lo, hi))) =>
                        format!("{:.1} [{}, {}]", d * 1e6, bound(lo), bound(hi)),
                    _ => "—".into(),
                },
                match c.d50_agrees {
                    Some(true) => format!("{} ✓", fmt_err(c.d50_error)),
                    Some(false) => format!("{} ✗", fmt_err(c.d50_error)),
                    None => fmt_err(c.d50_error),
                }
            );
        }
    }
    let _ = writeln!(
        m,
        "\nPlot: `cost.svg` (log–log error vs measured wall time, one curve per law through its \
         base points, points labelled with α and dt, ★ = Pareto front)."
    );
    m
}
