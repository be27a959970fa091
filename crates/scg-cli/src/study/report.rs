//! A study's tables: `summary.json`, `report.txt` and the CSVs.

use std::fmt::Write as _;
use std::path::Path;

use crate::analysis::{self, cut_size, w1_to};

use super::VariantRun;

fn json_num(x: f64) -> serde_json::Value {
    if x.is_finite() {
        serde_json::json!(x)
    } else {
        serde_json::Value::Null
    }
}

/// `summary.json` of a study.
pub fn summary(runs: &[VariantRun]) -> serde_json::Value {
    let mut variants = serde_json::Map::new();
    let reference = &runs[0].result;
    for v in runs {
        let w1 = w1_to(reference, &v.result);
        let mut classes = serde_json::Map::new();
        for (c, w) in v.result.classes.iter().zip(&w1) {
            classes.insert(
                format!("{}", (c.diameter * 1e6 * 1000.0).round() / 1000.0),
                serde_json::json!({
                    "w1": json_num(*w),
                    "drained": json_num(c.drained_fraction),
                    "mean_r_m": json_num(c.mean_r),
                }),
            );
        }
        let d50 = cut_size(&v.result).map(|d| d * 1e6);
        variants.insert(
            v.name.clone(),
            serde_json::json!({
                "time_s": v.time_s,
                "d50_um": d50.map_or(serde_json::Value::Null, json_num),
                "classes": classes,
            }),
        );
    }
    serde_json::json!({ "variants": variants })
}

/// Text report: per class mean radius, drained fraction, W1; times; d50.
pub fn report(runs: &[VariantRun]) -> String {
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
        "{:<10} {:>8} {:>10} {:>9} {:>9} {:>10} {:>8}",
        "variant", "class", "mean_r[m]", "r/R", "drained", "W1/R", "samples"
    );
    for v in runs {
        let w1 = w1_to(reference, &v.result);
        for (c, w) in v.result.classes.iter().zip(&w1) {
            let _ = writeln!(
                s,
                "{:<10} {:>6.0}µm {:>10.4e} {:>9.4} {:>9.4} {:>10.4} {:>8}",
                v.name,
                c.diameter * 1e6,
                c.mean_r,
                c.mean_r / reference.params.radius,
                c.drained_fraction,
                w,
                c.radii.len()
            );
        }
    }
    let _ = writeln!(
        s,
        "\n{:<10} {:>14} {:>12} {:>10} {:>10} {:>10}",
        "variant", "time 0.1 s [s]", "total [s]", "resident", "lost", "d50 [µm]"
    );
    let t0 = runs[0].time_s;
    for v in runs {
        let d50 = cut_size(&v.result);
        let _ = writeln!(
            s,
            "{:<10} {:>14.3} {:>12.3} {:>10} {:>10} {:>10}   (time ratio to original {:.3})",
            v.name,
            v.time_s,
            v.total_s,
            v.resident,
            v.lost.iter().sum::<usize>(),
            d50.map_or("—".to_string(), |d| format!("{:.1}", d * 1e6)),
            v.time_s / t0
        );
    }
    s
}

/// Write every table of a study into `out`.
pub fn write_tables(runs: &[VariantRun], out: &Path) -> Result<(), String> {
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
        let _ = write!(part, ",{}", v.name);
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
            let _ = write!(part, ",{:e}", v.result.classes[ci].drained_fraction);
        }
        part.push('\n');
    }
    part.push_str("d50_um");
    for v in runs {
        let d = cut_size(&v.result);
        let _ = write!(
            part,
            ",{}",
            d.map_or("".into(), |d| format!("{:e}", d * 1e6))
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
        serde_json::to_string_pretty(&summary(runs)).map_err(|e| e.to_string())? + "\n",
    )?;
    w("report.txt", report(runs))
}
