//! The elbow study's tables: penetration per class, the wear in total and by zone, where
//! its maximum sits, the cost, each variant's verdict against the originals, and the
//! tracer check; as text, Markdown (docs/ quotes it), CSV and `summary.json`.

use std::fmt::Write;

use serde::{Deserialize, Serialize};

use super::ElbowRun;
use super::wear::ZoneShare;
use crate::analysis::interval::share95 as share;
use crate::study::cyclone::{ClassGrade, TracerCheck};

/// `summary.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    /// Feed scale on the scene's 2000 originals per class.
    pub feed_scale: f64,
    /// Simulated time, s.
    pub duration_s: f64,
    /// The variants, the originals first.
    pub variants: Vec<ElbowRun>,
    /// The tracer check.
    pub tracers: Option<TracerCheck>,
    /// One line per variant against the originals.
    pub verdicts: Vec<String>,
}

/// The summary of a finished study.
pub fn summary(
    runs: &[ElbowRun],
    tracers: Option<&TracerCheck>,
    feed: f64,
    duration: f64,
) -> Summary {
    Summary {
        feed_scale: feed,
        duration_s: duration,
        variants: runs.to_vec(),
        tracers: tracers.cloned(),
        verdicts: runs
            .iter()
            .skip(1)
            .map(|v| verdict(&runs[0], v).1)
            .collect(),
    }
}

fn overlap(a: (f64, f64), b: (f64, f64)) -> bool {
    a.0 <= b.1 && b.0 <= a.1
}

/// The count of one fate in a class.
type Count = fn(&ClassGrade) -> u64;

/// What a class did: (name, its count).
const FATES: [(&str, Count); 3] = [
    ("reached the outlet (penetration)", |c| c.escaped),
    ("still in the pipe at the end", |c| c.held),
    ("back out of the inlet", |c| c.lost),
];

/// Whether `v` keeps the originals' answers within the intervals, and one line saying so:
/// every class's fates, the total wear, the share of every zone with at least 1 % of
/// either run's wear, and the top zone among the originals' candidates for the maximum.
pub fn verdict(o: &ElbowRun, v: &ElbowRun) -> (bool, String) {
    let mut off = Vec::new();
    for (co, cv) in o.run.classes.iter().zip(&v.run.classes) {
        for (what, k) in FATES {
            let (a, b) = (share(k(co), co.fed), share(k(cv), cv.fed));
            if !overlap((a.1, a.2), (b.1, b.2)) {
                off.push(format!("{} {what} {:.3} vs {:.3}", co.group, b.0, a.0));
            }
        }
    }
    let (to, tv) = (o.wear.total, v.wear.total);
    if !overlap((to.1, to.2), (tv.1, tv.2)) {
        off.push(format!("total wear {:.3}× the originals'", tv.0 / to.0));
    }
    // the zones that carry at least 1 % of either run's wear
    for (zo, zv) in o.wear.zones.iter().zip(&v.wear.zones) {
        let worth = zo.share.max(zv.share) >= 0.01;
        if worth && !overlap((zo.lo, zo.hi), (zv.lo, zv.hi)) {
            off.push(format!(
                "{} share {:.3} vs {:.3}",
                zo.zone, zv.share, zo.share
            ));
        }
    }
    if !o.wear.top_candidates().contains(&v.wear.top.as_str()) {
        off.push(format!(
            "most wear in {} (originals: {})",
            v.wear.top, o.wear.top
        ));
    }
    let ok = off.is_empty();
    let line = if ok {
        format!(
            "{}: agrees with the originals within the 95 % intervals (fates of every class, total wear, every zone's share, where the maximum sits)",
            v.run.name
        )
    } else {
        format!(
            "{}: differs beyond the intervals: {}",
            v.run.name,
            off.join("; ")
        )
    };
    (ok, line)
}

fn fmt3((x, lo, hi): (f64, f64, f64)) -> String {
    format!("{x:.3} [{lo:.3}, {hi:.3}]")
}

/// The zones worth a row: those with at least 1 % of some variant's wear.
fn zones_shown(runs: &[ElbowRun]) -> Vec<usize> {
    let n = runs.first().map_or(0, |r| r.wear.zones.len());
    (0..n)
        .filter(|&k| runs.iter().any(|r| r.wear.zones[k].share >= 0.01))
        .collect()
}

fn zone_cell(z: &ZoneShare) -> String {
    if z.share.is_finite() {
        fmt3((z.share, z.lo, z.hi))
    } else {
        "–".into()
    }
}

/// The report as text.
pub fn report(runs: &[ElbowRun], tracers: Option<&TracerCheck>) -> String {
    let mut s = String::new();
    let Some(o) = runs.first() else {
        return s;
    };
    let per_class = o.run.classes.first().map_or(0, |c| c.fed);
    let _ = writeln!(
        s,
        "scg study elbow: 90° elbow (D 50 mm, R/D 1.5), sand in air at 20 m/s, {:.3} s \
         (cases/elbow.toml); {per_class} originals per class, every variant the same mass \
         (1/α³ as many particles)\n",
        o.run.duration
    );
    let _ = writeln!(
        s,
        "{:<10}{:>4} {:<8}{:>10}{:>10}{:>14}{:>10}",
        "variant", "α", "law", "particles", "wall [s]", "p-steps/s", "speed-up"
    );
    for r in runs {
        let fed: u64 = r.run.classes.iter().map(|c| c.fed).sum();
        let _ = writeln!(
            s,
            "{:<10}{:>4} {:<8}{:>10}{:>10.2}{:>14.3e}{:>10.1}",
            r.run.name,
            r.run.alpha,
            r.run.law,
            fed,
            r.run.total_s,
            r.run.particle_steps as f64 / r.run.total_s,
            o.run.total_s / r.run.total_s
        );
    }
    for (what, k) in FATES {
        let _ = writeln!(s, "\n{what}, share of the fed [95 % Wilson]:");
        let _ = write!(s, "{:<8}", "class");
        for r in runs {
            let _ = write!(s, "{:>24}", r.run.name);
        }
        s.push('\n');
        for (i, c) in o.run.classes.iter().enumerate() {
            let _ = write!(s, "{:<8}", c.group);
            for r in runs {
                let c = &r.run.classes[i];
                let _ = write!(s, "{:>24}", fmt3(share(k(c), c.fed)));
            }
            s.push('\n');
        }
    }
    let _ = writeln!(
        s,
        "\nwear (Finnie), volume removed over the run, m³ [95 %, particles resampled]:"
    );
    for r in runs {
        let (t, lo, hi) = r.wear.total;
        let _ = writeln!(
            s,
            "  {:<10}{t:.4e} [{lo:.4e}, {hi:.4e}]  {:.3}× the originals'; {} impacts",
            r.run.name,
            t / o.wear.total.0,
            r.wear.impacts
        );
    }
    let _ = writeln!(
        s,
        "\nwear by zone along the pipe, share of the run's total [95 %]:"
    );
    let _ = write!(s, "{:<24}", "zone");
    for r in runs {
        let _ = write!(s, "{:>24}", r.run.name);
    }
    s.push('\n');
    for k in zones_shown(runs) {
        let _ = write!(s, "{:<24}", o.wear.zones[k].zone);
        for r in runs {
            let _ = write!(s, "{:>24}", zone_cell(&r.wear.zones[k]));
        }
        s.push('\n');
    }
    let _ = writeln!(s, "\nwhere the maximum sits:");
    for r in runs {
        let d = &r.wear.deepest;
        let _ = writeln!(
            s,
            "  {:<10}most wear in {} (zones within its interval: {}); deepest face at \
             [{:.1}, {:.1}, {:.1}] mm{}, {:.3e} m/s",
            r.run.name,
            r.wear.top,
            r.wear.top_candidates().join(", "),
            d.0[0] * 1e3,
            d.0[1] * 1e3,
            d.0[2] * 1e3,
            if d.1.is_finite() {
                format!(" (θ = {:.1}°)", d.1)
            } else {
                String::new()
            },
            d.2
        );
    }
    let _ = writeln!(s, "\nagainst the originals:");
    for v in runs.iter().skip(1) {
        let _ = writeln!(s, "  {}", verdict(o, v).1);
    }
    if let Some(t) = tracers {
        s.push('\n');
        s += &t.text();
    }
    s
}

/// The tables in Markdown, as docs/ quotes them.
pub fn markdown(runs: &[ElbowRun], tracers: Option<&TracerCheck>) -> String {
    let mut s = String::new();
    let Some(o) = runs.first() else {
        return s;
    };
    let _ = write!(s, "| | ");
    let _ = writeln!(
        s,
        "{} |",
        runs.iter()
            .map(|r| r.run.name.as_str())
            .collect::<Vec<_>>()
            .join(" | ")
    );
    let _ = writeln!(s, "|---|{}", "---|".repeat(runs.len()));
    let row = |s: &mut String, label: &str, cells: Vec<String>| {
        let _ = writeln!(s, "| {label} | {} |", cells.join(" | "));
    };
    row(
        &mut s,
        "particles fed",
        runs.iter()
            .map(|r| r.run.classes.iter().map(|c| c.fed).sum::<u64>().to_string())
            .collect(),
    );
    row(
        &mut s,
        "wall time, s",
        runs.iter()
            .map(|r| format!("{:.2}", r.run.total_s))
            .collect(),
    );
    for (i, c) in o.run.classes.iter().enumerate() {
        row(
            &mut s,
            &format!("{} penetration", c.group),
            runs.iter()
                .map(|r| {
                    let c = &r.run.classes[i];
                    fmt3(share(c.escaped, c.fed))
                })
                .collect(),
        );
    }
    row(
        &mut s,
        "wear, 10⁻¹³ m³",
        runs.iter()
            .map(|r| {
                let (t, lo, hi) = r.wear.total;
                format!("{:.2} [{:.2}, {:.2}]", t * 1e13, lo * 1e13, hi * 1e13)
            })
            .collect(),
    );
    for k in zones_shown(runs) {
        row(
            &mut s,
            &o.wear.zones[k].zone,
            runs.iter().map(|r| zone_cell(&r.wear.zones[k])).collect(),
        );
    }
    row(
        &mut s,
        "most wear",
        runs.iter().map(|r| r.wear.top.clone()).collect(),
    );
    row(
        &mut s,
        "deepest face, θ",
        runs.iter()
            .map(|r| {
                if r.wear.deepest.1.is_finite() {
                    format!("{:.1}°", r.wear.deepest.1)
                } else {
                    r.wear.deepest.3.clone()
                }
            })
            .collect(),
    );
    row(
        &mut s,
        "within the intervals",
        runs.iter()
            .enumerate()
            .map(|(i, r)| {
                if i == 0 {
                    "(reference)".into()
                } else if verdict(o, r).0 {
                    "✓".into()
                } else {
                    "✗".into()
                }
            })
            .collect(),
    );
    if let Some(t) = tracers {
        s.push('\n');
        s += &t.text();
    }
    s
}

/// `variant,zone,share,lo,hi` for every zone of every variant.
pub fn csv(runs: &[ElbowRun]) -> String {
    let mut s = String::from("variant,alpha,law,zone,share,lo,hi\n");
    for r in runs {
        for z in &r.wear.zones {
            let _ = writeln!(
                s,
                "{},{},{},{},{:e},{:e},{:e}",
                r.run.name, r.run.alpha, r.run.law, z.zone, z.share, z.lo, z.hi
            );
        }
    }
    s
}
