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
    out.push_str(",d50_m,d50_error,w1_per_class,failure\n");
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
    if let Some(first) = s.outcomes.iter().find_map(|o| o.classes.as_ref()) {
        let _ = writeln!(
            m,
            "\n## Classifier: per-class W1 (/ vessel radius) and d50\n"
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
        "\nPlot: `cost.svg` (log–log error vs measured wall time, one curve per law through its \
         base points, points labelled with α and dt, ★ = Pareto front)."
    );
    m
}
