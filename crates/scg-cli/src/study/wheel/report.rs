//! The wheel study's tables: per class the fines, rejected and orbiting shares with their
//! intervals, the cut size with its interval, the equilibrium cut beside it, the cost,
//! each variant's verdict against the originals, and the tracer check; as text, Markdown
//! (docs/ quotes it) and `summary.json`.

use std::fmt::Write;

use serde::{Deserialize, Serialize};

use super::{Theory, WheelRun};
use crate::analysis::interval::share95 as share;
use crate::study::cyclone::grade::{cut_size, cut_size95};
use crate::study::cyclone::{ClassGrade, TracerCheck};

/// `summary.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    /// Feed scale on the scene's 500 originals per class.
    pub feed_scale: f64,
    /// Simulated time, s.
    pub duration_s: f64,
    /// The equilibrium cut from the field.
    pub theory: Theory,
    /// The variants, the originals first.
    pub variants: Vec<WheelRun>,
    /// The tracer check.
    pub tracers: Option<TracerCheck>,
    /// One line per variant against the originals.
    pub verdicts: Vec<String>,
}

/// The summary of a finished study.
pub fn summary(
    runs: &[WheelRun],
    theory: &Theory,
    tracers: Option<&TracerCheck>,
    feed: f64,
    duration: f64,
) -> Summary {
    Summary {
        feed_scale: feed,
        duration_s: duration,
        theory: theory.clone(),
        variants: runs.to_vec(),
        tracers: tracers.cloned(),
        verdicts: runs
            .iter()
            .skip(1)
            .map(|v| verdict(&runs[0], v).1)
            .collect(),
    }
}

/// The fines share of a class (escaped through the fines outlet) with its interval.
pub fn fines(c: &ClassGrade) -> (f64, f64, f64) {
    share(c.escaped, c.fed)
}

/// The cut size of a run (where the fines share falls through 50 %), m, and its 95 %
/// interval.
pub fn cut(run: &WheelRun) -> (Option<f64>, Option<(f64, f64)>) {
    (cut_size(&run.run.classes), cut_size95(&run.run.classes))
}

/// Whether a variant's fines shares agree with the originals' (intervals overlap in every
/// class), and one line saying so.
pub fn verdict(o: &WheelRun, v: &WheelRun) -> (bool, String) {
    let beyond: Vec<String> = o
        .run
        .classes
        .iter()
        .zip(&v.run.classes)
        .filter(|(a, b)| {
            let (_, alo, ahi) = fines(a);
            let (_, blo, bhi) = fines(b);
            !(alo <= bhi && blo <= ahi)
        })
        .map(|(a, _)| format!("{:.1} µm", a.diameter * 1e6))
        .collect();
    let ok = beyond.is_empty();
    let speed = o.run.total_s / v.run.total_s.max(1e-9);
    let line = if ok {
        format!(
            "{}: fines shares within the originals' intervals in every class; {speed:.1}× faster",
            v.run.name
        )
    } else {
        format!(
            "{}: fines shares outside the originals' intervals in {} ({}); {speed:.1}× faster",
            v.run.name,
            beyond.len(),
            beyond.join(", ")
        )
    };
    (ok, line)
}

fn pc((x, lo, hi): (f64, f64, f64)) -> String {
    format!("{:.1} [{:.1}, {:.1}]", 100.0 * x, 100.0 * lo, 100.0 * hi)
}

fn um(x: Option<f64>) -> String {
    x.map_or("—".into(), |d| format!("{:.2}", d * 1e6))
}

fn cut_text(run: &WheelRun) -> String {
    let (d, i) = cut(run);
    match (d, i) {
        (Some(d), Some((lo, hi))) => format!(
            "{:.2} µm [{}, {}]",
            d * 1e6,
            um(lo.is_finite().then_some(lo)),
            um(hi.is_finite().then_some(hi))
        ),
        (Some(d), None) => format!("{:.2} µm", d * 1e6),
        _ => "— (the fines share never falls through 50 %)".into(),
    }
}

/// The tracers' mean residence against V/Q with the CFD's own inflow (the tracer check's
/// V/Q takes the interpolated field's, which the cell values do not conserve).
pub fn tracer_cfd_text(t: &TracerCheck, theory: &Theory) -> String {
    let (q_cfd, q_interp) = theory.inflow;
    let v_over_q = t.v_over_q * q_interp / q_cfd;
    format!(
        "with the CFD's own inflow ({q_cfd:.4e} m³/s): V/Q = {v_over_q:.4} s, the tracers' mean \
         residence {:.3}·V/Q ± {:.3}\n",
        t.mean_residence / v_over_q,
        t.mean_residence_95 / v_over_q
    )
}

/// The theory paragraph.
pub fn theory_text(t: &Theory) -> String {
    let critical = t.critical().map_or(String::new(), |(r, d)| {
        let at = |rr: f64| {
            t.profile
                .iter()
                .min_by(|a, b| (a.0 - rr).abs().total_cmp(&(b.0 - rr).abs()))
                .map_or(f64::NAN, |p| p.3 * 1e6)
        };
        format!(
            "  the same balance on every circle from the fines outlet to the inlet: smallest \
             {:.2} µm at r = {:.1} mm (20.5 mm: {:.2}, 35.5 mm: {:.2}, 50.5 mm: {:.2}, 75.5 mm: \
             {:.2}, 99.5 mm: {:.2} µm)\n",
            d * 1e6,
            r * 1e3,
            at(0.0205),
            at(0.0355),
            at(0.0505),
            at(0.0755),
            at(0.0995)
        )
    });
    let head = format!(
        "Equilibrium cut at the wheel radius R = {:.0} mm (field averaged on r = {:.1} mm): \
         d50 = √(18·μ·v_r·R/(ρ_p·u_θ²))\n  with the field's own v_r = {:.3} m/s and u_θ = {:.2} m/s: \
         {:.2} µm\n  nominal, v_r = Q/(2π·r·H) = {:.3} m/s and u_θ = Ω·r = {:.2} m/s: {:.2} µm \
         (Q = {:.4e} m³/s by the CFD's inlet face values; the interpolated field carries \
         {:.4e})\n",
        t.radius * 1e3,
        t.sampled_at * 1e3,
        t.v_r,
        t.u_theta,
        t.d50_field * 1e6,
        t.v_r_nominal,
        t.omega * t.sampled_at,
        t.d50_nominal * 1e6,
        t.inflow.0,
        t.inflow.1
    );
    head + &critical
}

/// The text report.
pub fn report(runs: &[WheelRun], theory: &Theory, tracers: Option<&TracerCheck>) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Deflector-wheel classifier (cases/wheel.toml): per class the share that reached the \
         fines outlet, is still outside the wheel at the end (rejected) and between its \
         blades (%, Wilson 95 %)"
    );
    for r in runs {
        let fed: u64 = r.run.classes.iter().map(|c| c.fed).sum();
        let _ = writeln!(
            s,
            "\n{} (α = {}, law {}): {fed} simulated particles, {:.1} s wall, {} particle-steps",
            r.run.name, r.run.alpha, r.run.law, r.run.total_s, r.run.particle_steps
        );
        let _ = writeln!(
            s,
            "  {:>6}  {:>6}  {:>22}  {:>22}  {:>22}  {:>6}  {:>9}",
            "d µm", "fed", "fines", "rejected", "in the wheel", "lost", "held r mm"
        );
        for (k, c) in r.run.classes.iter().enumerate() {
            let out = r.outside.get(k).copied().unwrap_or(0);
            let _ = writeln!(
                s,
                "  {:>6.1}  {:>6}  {:>22}  {:>22}  {:>22}  {:>6}  {:>9.1}",
                c.diameter * 1e6,
                c.fed,
                pc(fines(c)),
                pc(share(out, c.fed)),
                pc(share(c.held.saturating_sub(out), c.fed)),
                c.lost,
                1e3 * r.held_radius.get(k).copied().flatten().unwrap_or(f64::NAN)
            );
        }
        let _ = writeln!(s, "  cut size (fines share 50 %): {}", cut_text(r));
    }
    if let Some(o) = runs.first() {
        let _ = writeln!(s, "\nAgainst the originals:");
        for v in runs.iter().skip(1) {
            let _ = writeln!(s, "  {}", verdict(o, v).1);
        }
    }
    let _ = writeln!(s, "\n{}", theory_text(theory));
    if let Some(t) = tracers {
        let _ = writeln!(s, "{}", t.text());
        let _ = write!(s, "{}", tracer_cfd_text(t, theory));
    }
    s
}

/// The Markdown tables: fines share per class and variant, then the cut size and the cost;
/// the theory and the tracer check below.
pub fn markdown(runs: &[WheelRun], theory: &Theory, tracers: Option<&TracerCheck>) -> String {
    let mut s = String::new();
    let _ = write!(s, "| fines share, % [95 %] |");
    for r in runs {
        let _ = write!(s, " {} |", r.run.name);
    }
    let _ = write!(s, "\n|---|");
    for _ in runs {
        let _ = write!(s, "---|");
    }
    s.push('\n');
    let n = runs.first().map_or(0, |r| r.run.classes.len());
    for k in 0..n {
        let _ = write!(s, "| {:.1} µm |", runs[0].run.classes[k].diameter * 1e6);
        for r in runs {
            let _ = write!(s, " {} |", pc(fines(&r.run.classes[k])));
        }
        s.push('\n');
    }
    let _ = write!(s, "| median r of the held, mm (4.5 µm; 5 µm) |");
    for r in runs {
        let at = |d: f64| {
            r.run
                .classes
                .iter()
                .position(|c| (c.diameter - d).abs() < 1e-9)
                .and_then(|k| r.held_radius.get(k).copied().flatten())
                .map_or("—".to_string(), |x| format!("{:.1}", x * 1e3))
        };
        let _ = write!(s, " {}; {} |", at(4.5e-6), at(5.0e-6));
    }
    let _ = write!(
        s,
        "\n| inside the wheel radius at the end, % (all classes) |"
    );
    for r in runs {
        let held: u64 = r.run.classes.iter().map(|c| c.held).sum();
        let out: u64 = r.outside.iter().sum();
        let fed: u64 = r.run.classes.iter().map(|c| c.fed).sum();
        let _ = write!(
            s,
            " {:.1} |",
            100.0 * held.saturating_sub(out) as f64 / fed.max(1) as f64
        );
    }
    let _ = write!(s, "\n| cut size, µm [95 %] |");
    for r in runs {
        let _ = write!(s, " {} |", cut_text(r).replace(" µm", ""));
    }
    let _ = write!(s, "\n| simulated particles |");
    for r in runs {
        let _ = write!(s, " {} |", r.run.classes.iter().map(|c| c.fed).sum::<u64>());
    }
    let _ = write!(s, "\n| wall time, s |");
    for r in runs {
        let _ = write!(s, " {:.1} |", r.run.total_s);
    }
    s.push_str("\n\n");
    for v in runs.iter().skip(1) {
        let _ = writeln!(s, "- {}", verdict(&runs[0], v).1);
    }
    let _ = writeln!(s, "\n{}", theory_text(theory).replace("\n  ", "\n- "));
    if let Some(t) = tracers {
        let _ = write!(s, "{}; {}", t.text().trim_end(), tracer_cfd_text(t, theory));
    }
    s
}
