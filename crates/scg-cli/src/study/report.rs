//! A study's tables: `summary.json`, `report.txt` and the CSVs.

use std::fmt::Write as _;
use std::path::Path;

use crate::analysis::interval::wilson95;
use crate::analysis::{
    self, cut_size, cut_size95, steady_cut_size, undecided, w1_intervals, w1_to,
};

use super::VariantRun;

fn json_num(x: f64) -> serde_json::Value {
    if x.is_finite() {
        serde_json::json!(x)
    } else {
        serde_json::Value::Null
    }
}

/// Per variant, per class: W1's bootstrap interval and the sampling-noise W1 against the
/// first variant ([`w1_intervals`]: resampling, computed once for all tables).
type Intervals = Vec<Vec<((f64, f64), f64)>>;

fn intervals(runs: &[VariantRun]) -> Intervals {
    runs.iter()
        .map(|v| w1_intervals(&runs[0].result, &v.result))
        .collect()
}

/// `summary.json` of a study.
pub fn summary(runs: &[VariantRun]) -> serde_json::Value {
    summary_with(runs, &intervals(runs))
}

fn summary_with(runs: &[VariantRun], intervals: &Intervals) -> serde_json::Value {
    let mut variants = serde_json::Map::new();
    let reference = &runs[0].result;
    for (v, iv) in runs.iter().zip(intervals) {
        let w1 = w1_to(reference, &v.result);
        let mut classes = serde_json::Map::new();
        for ((c, w), ((lo, hi), noise)) in v.result.classes.iter().zip(&w1).zip(iv) {
            let (dlo, dhi) = wilson95(c.drained, c.cohort);
            classes.insert(
                format!("{}", (c.diameter * 1e6 * 1000.0).round() / 1000.0),
                serde_json::json!({
                    "w1": json_num(*w),
                    "w1_95": [json_num(*lo), json_num(*hi)],
                    "w1_noise95": json_num(*noise),
                    "w1_agrees": *w <= *noise,
                    "drained": json_num(c.drained_fraction),
                    "drained_95": [json_num(dlo), json_num(dhi)],
                    "fate_fine": c.fates.fine,
                    "fate_coarse": c.fates.coarse,
                    "fate_undecided": c.fates.undecided,
                    "steady_fine_fraction": json_num(c.fates.fine_fraction()),
                    "mean_r_m": json_num(c.mean_r),
                }),
            );
        }
        let um = |d: Option<f64>| d.map_or(serde_json::Value::Null, |d| json_num(d * 1e6));
        let decided: u64 = v
            .result
            .classes
            .iter()
            .map(|c| c.fates.fine + c.fates.coarse)
            .sum();
        variants.insert(
            v.name.clone(),
            serde_json::json!({
                "time_s": v.time_s,
                "total_s": v.total_s,
                "d50_drained_um": um(cut_size(&v.result)),
                "d50_drained_95_um": cut_size95(&v.result)
                    .map_or(serde_json::Value::Null, |(lo, hi)| serde_json::json!([
                        json_num(lo * 1e6),
                        json_num(hi * 1e6)
                    ])),
                "d50_steady_um": um(steady_cut_size(&v.result)),
                "fates_decided": decided,
                "fates_undecided": undecided(&v.result),
                "classes": classes,
            }),
        );
    }
    serde_json::json!({
        "definitions": {
        "d50_drained_um": "finite time: the partition of drained fractions of the particles fed by cohort_until, gone by the last frame",
        "w1_95": "95 % bootstrap interval of w1, resampling particles (not frames) of both runs",
        "w1_noise95": "the w1 two runs of these particle counts reach from sampling noise alone in 5 % of cases (permutation test over particles); w1_agrees = w1 ≤ w1_noise95",
        "drained_95": "Wilson 95 % interval of the drained fraction",
        "d50_drained_95_um": "95 % bootstrap interval of d50_drained (null bound: open, the data cannot place the cut on that side)",
        "d50_steady_um": "steady state: the partition of each particle's decided fate (fine at the nozzle radius or drained, coarse in the wall zone), undecided particles left out"
        },
        "cohort_until_s": runs[0].result.params.cohort_until,
        "last_frame_s": runs[0].result.last_time,
        "variants": variants
    })
}

/// Text report: per class mean radius, drained fraction, fates, W1; times; both d50s.
pub fn report(runs: &[VariantRun]) -> String {
    report_with(runs, &intervals(runs))
}

fn report_with(runs: &[VariantRun], intervals: &Intervals) -> String {
    let mut s = String::new();
    let reference = &runs[0].result;
    let _ = writeln!(
        s,
        "radial distributions over {}–{} s; drained fraction of the particles fed by {} s, gone by {} s",
        reference.params.from,
        reference.params.to,
        reference.params.cohort_until,
        reference.last_time
    );
    let _ = writeln!(
        s,
        "fates (steady state): fine once at r ≤ {:.4} m or drained, coarse once at r ≥ {:.4} m, \
         else undecided by {} s",
        reference.params.fates.fine_radius,
        reference.params.fates.coarse_radius,
        reference.last_time
    );
    let _ = writeln!(
        s,
        "{:<10} {:>8} {:>10} {:>9} {:>9} {:>15} {:>10} {:>10} {:>8} {:>7} {:>7} {:>7} {:>7}",
        "variant",
        "class",
        "mean_r[m]",
        "r/R",
        "drained",
        "drained 95 %",
        "W1/R",
        "noise95",
        "samples",
        "fine",
        "coarse",
        "undec",
        "f_fine"
    );
    for (v, iv) in runs.iter().zip(intervals) {
        let w1 = w1_to(reference, &v.result);
        for ((c, w), (_, noise)) in v.result.classes.iter().zip(&w1).zip(iv) {
            let (dlo, dhi) = wilson95(c.drained, c.cohort);
            let _ = writeln!(
                s,
                "{:<10} {:>6.0}µm {:>10.4e} {:>9.4} {:>9.4} {:>15} {:>10.4} {:>10.4} {:>8} {:>7} {:>7} {:>7} {:>7.4}",
                v.name,
                c.diameter * 1e6,
                c.mean_r,
                c.mean_r / reference.params.radius,
                c.drained_fraction,
                format!("[{dlo:.3}, {dhi:.3}]"),
                w,
                noise,
                c.radii.len(),
                c.fates.fine,
                c.fates.coarse,
                c.fates.undecided,
                c.fates.fine_fraction()
            );
        }
    }
    let _ = writeln!(
        s,
        "\n{:<10} {:>14} {:>12} {:>10} {:>10} {:>14} {:>14} {:>10}",
        "variant",
        "time 0.1 s [s]",
        "total [s]",
        "resident",
        "lost",
        "d50 drained",
        "d50 steady",
        "undecided"
    );
    let t0 = runs[0].time_s;
    let um = |d: Option<f64>| d.map_or("—".to_string(), |d| format!("{:.1} µm", d * 1e6));
    let bound = |x: f64| {
        if x.is_finite() {
            format!("{:.1}", x * 1e6)
        } else {
            "…".into()
        }
    };
    let mut cuts = String::new();
    for v in runs {
        if let (Some(d), Some((lo, hi))) = (cut_size(&v.result), cut_size95(&v.result)) {
            let _ = write!(
                cuts,
                "  {} {:.1} [{}, {}] µm",
                v.name,
                d * 1e6,
                bound(lo),
                bound(hi)
            );
        }
        let _ = writeln!(
            s,
            "{:<10} {:>14.3} {:>12.3} {:>10} {:>10} {:>14} {:>14} {:>10}   (time ratio to original {:.3})",
            v.name,
            v.time_s,
            v.total_s,
            v.resident,
            v.lost.iter().sum::<usize>(),
            um(cut_size(&v.result)),
            um(steady_cut_size(&v.result)),
            undecided(&v.result),
            v.time_s / t0
        );
    }
    let _ = writeln!(
        s,
        "d50 drained: finite-time cut of the drained fractions (cohort fed by {} s, gone by {} s); \
         d50 steady: cut of the decided fates (undecided particles left out)",
        reference.params.cohort_until, reference.last_time
    );
    if !cuts.is_empty() {
        let _ = writeln!(
            s,
            "d50 drained with its 95 % bootstrap interval (… = open):{cuts}"
        );
    }
    let _ = writeln!(
        s,
        "W1/R agrees with the original's distribution when ≤ noise95, the W1 that two runs of \
         these particle counts reach from sampling alone in 5 % of cases (permutation test over \
         particles); drained 95 %: Wilson's interval."
    );
    s
}

/// Write every table of a study into `out`; returns the text report (report.txt).
pub fn write_tables(runs: &[VariantRun], out: &Path) -> Result<String, String> {
    let intervals = intervals(runs);
    let w = |name: &str, text: String| {
        std::fs::write(out.join(name), text)
            .map_err(|e| format!("{}: {e}", out.join(name).display()))
    };
    let mut long = String::from("variant,class_um,bin_lo_r_over_R,bin_hi_r_over_R,fraction\n");
    for v in runs {
        w(
            &format!("radial-{}.csv", v.name),
            analysis::radial_csv(&v.result),
        )?;
        let bins = v.result.params.bins;
        for c in &v.result.classes {
            for (b, f) in c.histogram.iter().enumerate() {
                let _ = writeln!(
                    long,
                    "{},{},{:e},{:e},{:e}",
                    v.name,
                    (c.diameter * 1e6).round(),
                    b as f64 / bins as f64,
                    (b + 1) as f64 / bins as f64,
                    f
                );
            }
        }
    }
    w("radial.csv", long)?;
    let reference = &runs[0].result;
    let mut w1 = String::from("variant,class_um,w1_over_R,mean_r_m,drained_fraction\n");
    let mut part = String::from("class_um");
    for v in runs {
        let _ = write!(
            part,
            ",{0}_drained,{0}_steady,{0}_fine,{0}_coarse,{0}_undecided",
            v.name
        );
        for (c, d) in v.result.classes.iter().zip(w1_to(reference, &v.result)) {
            let _ = writeln!(
                w1,
                "{},{},{:e},{:e},{:e}",
                v.name,
                (c.diameter * 1e6).round(),
                d,
                c.mean_r,
                c.drained_fraction
            );
        }
    }
    part.push('\n');
    for (ci, c) in reference.classes.iter().enumerate() {
        let _ = write!(part, "{}", (c.diameter * 1e6).round());
        for v in runs {
            let c = &v.result.classes[ci];
            let _ = write!(
                part,
                ",{:e},{:e},{},{},{}",
                c.drained_fraction,
                c.fates.fine_fraction(),
                c.fates.fine,
                c.fates.coarse,
                c.fates.undecided
            );
        }
        part.push('\n');
    }
    let um = |d: Option<f64>| d.map_or(String::new(), |d| format!("{:e}", d * 1e6));
    part.push_str("d50_um");
    for v in runs {
        let _ = write!(
            part,
            ",{},{},,,{}",
            um(cut_size(&v.result)),
            um(steady_cut_size(&v.result)),
            undecided(&v.result)
        );
    }
    part.push('\n');
    w("w1.csv", w1)?;
    w("partition.csv", part)?;
    let mut time = String::from("variant,time_0.1s_s,total_s,resident,ratio_to_original\n");
    for v in runs {
        let _ = writeln!(
            time,
            "{},{:e},{:e},{},{:e}",
            v.name,
            v.time_s,
            v.total_s,
            v.resident,
            v.time_s / runs[0].time_s
        );
    }
    w("time.csv", time)?;
    w(
        "summary.json",
        serde_json::to_string_pretty(&summary_with(runs, &intervals)).map_err(|e| e.to_string())?
            + "\n",
    )?;
    let text = report_with(runs, &intervals);
    w("report.txt", text.clone())?;
    Ok(text)
}
