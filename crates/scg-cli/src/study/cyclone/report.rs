//! The cyclone study's tables: `report.txt`, `summary.json`, `grade.csv`, and the issue's
//! criteria checked on the numbers.

use std::fmt::Write as _;
use std::path::Path;

use super::grade::{ClassGrade, ExternalGrade, cut_size, cut_size95, residence_w1, wilson95};
use super::run::{CycloneRun, LATE, MOVING};
use super::theory::Cyclone;
use super::tracers::TracerCheck;

fn num(x: f64) -> serde_json::Value {
    if x.is_finite() {
        serde_json::json!(x)
    } else {
        serde_json::Value::Null
    }
}

fn opt_num(x: Option<f64>) -> serde_json::Value {
    x.map_or(serde_json::Value::Null, num)
}

/// Two binomial standard errors of an efficiency from `n` particles, percentage points.
fn two_sigma_pp(c: &ClassGrade) -> f64 {
    let p = c.efficiency;
    200.0 * (p * (1.0 - p) / c.fed as f64).sqrt()
}

/// One criterion of issue 16: what, the measured value, the limit (None: stated only).
#[derive(Clone, Debug, PartialEq)]
pub struct Criteria {
    /// What is measured.
    pub what: String,
    /// The value.
    pub value: f64,
    /// Passes when `value ≤ limit`; `None` when only stated.
    pub limit: Option<f64>,
}

impl Criteria {
    /// Whether it holds (`None` when only stated or not measurable).
    pub fn pass(&self) -> Option<bool> {
        self.limit
            .filter(|_| self.value.is_finite())
            .map(|l| self.value <= l)
    }
}

/// The largest |Δ efficiency| of `v` to the reference over the classes, percentage points.
pub fn max_delta_pp(reference: &CycloneRun, v: &CycloneRun) -> f64 {
    reference
        .classes
        .iter()
        .zip(&v.classes)
        .map(|(a, b)| 100.0 * (b.efficiency - a.efficiency).abs())
        .filter(|d| d.is_finite())
        .fold(f64::NAN, f64::max)
}

/// Classes of `v` whose η differs from the reference's beyond the intervals: |Δη| above
/// the two Wilson 95 % half-widths added in quadrature (an approximate 95 % test of the
/// difference of two binomial shares).
pub fn classes_beyond(reference: &CycloneRun, v: &CycloneRun) -> usize {
    let half = |c: &ClassGrade| {
        let (lo, hi) = c.efficiency95();
        0.5 * (hi - lo)
    };
    reference
        .classes
        .iter()
        .zip(&v.classes)
        .filter(|(a, b)| (b.efficiency - a.efficiency).abs() > half(a).hypot(half(b)))
        .count()
}

/// The largest residence-time W1 / mean of `v` to the reference over the classes where both
/// have escaped particles.
pub fn max_w1(reference: &CycloneRun, v: &CycloneRun) -> f64 {
    reference
        .classes
        .iter()
        .zip(&v.classes)
        .map(|(a, b)| residence_w1(a, b))
        .filter(|d| d.is_finite())
        .fold(f64::NAN, f64::max)
}

/// Whether `v` fed the same mass as `reference`: Σ fed·α³ within 5 % (the feed of a
/// coarse-grained variant is rounded down to whole particles).
pub fn same_mass(reference: &CycloneRun, v: &CycloneRun) -> bool {
    let m = |r: &CycloneRun| r.classes.iter().map(|c| c.fed as f64).sum::<f64>() * r.alpha.powi(3);
    (m(v) - m(reference)).abs() <= 0.05 * m(reference)
}

/// The criteria of issue 16 on `runs` (original first; variants found by name).
pub fn criteria(runs: &[CycloneRun]) -> Vec<Criteria> {
    let o = &runs[0];
    let find = |n: &str| runs.iter().find(|v| v.name == n);
    let mut c = Vec::new();
    for (name, limit) in [
        ("scg2", Some(3.0)),
        ("scg4", Some(5.0)),
        ("none2", None),
        ("parcel2", None),
        ("sample2", None),
        ("sample4", None),
    ] {
        if let Some(v) = find(name) {
            c.push(Criteria {
                what: format!("{name}: max |Δ grade efficiency| to the original, pp"),
                value: max_delta_pp(o, v),
                limit,
            });
        }
    }
    for name in ["scg2", "scg4", "none2", "parcel2", "sample2", "sample4"] {
        if let Some(v) = find(name) {
            c.push(Criteria {
                what: format!("{name}: max W1(residence times) / original mean"),
                value: max_w1(o, v),
                limit: name.starts_with("scg").then_some(0.05),
            });
        }
    }
    if let Some(v) = find("scg2") {
        // Only a run feeding the same mass as the original is a cost comparison (not one
        // with `--cg-feed`).
        let same = same_mass(o, v);
        let note = if same {
            ""
        } else {
            " (not the same mass fed: no criterion)"
        };
        c.push(Criteria {
            what: format!("scg2: whole-run wall time / the original's{note}"),
            value: v.total_s / o.total_s,
            limit: same.then_some(1.0 / 6.0),
        });
        if let (Some(a), Some(b)) = (v.cpu_s, o.cpu_s) {
            c.push(Criteria {
                what: format!("scg2: whole-run CPU time / the original's{note}"),
                value: a / b,
                limit: same.then_some(1.0 / 6.0),
            });
        }
    }
    c
}

fn class_json(
    c: &ClassGrade,
    reference: &ClassGrade,
    extra: serde_json::Value,
) -> serde_json::Value {
    let mut j = serde_json::to_value(c).unwrap_or_default();
    if let (Some(m), serde_json::Value::Object(e)) = (j.as_object_mut(), extra) {
        m.insert("held_share".into(), num(c.held_share()));
        m.insert("escaped_share".into(), num(c.escaped_share()));
        m.insert("lost_share".into(), num(c.lost_share()));
        m.insert("mean_residence_time".into(), num(c.mean_residence()));
        m.insert(
            "delta_efficiency_pp".into(),
            num(100.0 * (c.efficiency - reference.efficiency)),
        );
        m.insert("two_sigma_pp".into(), num(two_sigma_pp(c)));
        let (lo, hi) = c.efficiency95();
        m.insert(
            "efficiency_95".into(),
            serde_json::json!([num(lo), num(hi)]),
        );
        let (lo, hi) = wilson95(c.escaped, c.fed);
        m.insert(
            "escaped_share_95".into(),
            serde_json::json!([num(lo), num(hi)]),
        );
        m.insert("w1_over_mean".into(), num(residence_w1(reference, c)));
        m.extend(e);
    }
    j
}

/// `summary.json`: per variant the classes (the field names of `grade.json`) with their
/// differences to the original, d50, times; the theory's cut sizes; OpenFOAM's curve.
pub fn summary(
    runs: &[CycloneRun],
    theory: &Cyclone,
    openfoam: Option<&ExternalGrade>,
    tracers: Option<&TracerCheck>,
) -> serde_json::Value {
    let o = &runs[0];
    let rho = o.classes.first().map_or(2000.0, |c| c.density);
    let mut variants = serde_json::Map::new();
    for v in runs {
        let classes: Vec<serde_json::Value> = v
            .classes
            .iter()
            .enumerate()
            .map(|(i, c)| {
                class_json(
                    c,
                    &o.classes[i],
                    serde_json::json!({
                        "held_moving": v.held_moving[i],
                        "escaped_in_last_s": v.escaped_late[i],
                    }),
                )
            })
            .collect();
        variants.insert(
            v.name.clone(),
            serde_json::json!({
                "alpha": v.alpha,
                "law": v.law,
                "total_s": v.total_s,
                "time_ratio_to_original": v.total_s / o.total_s,
                "cpu_s": opt_num(v.cpu_s),
                "cpu_ratio_to_original": opt_num(v.cpu_s.zip(o.cpu_s).map(|(a, b)| a / b)),
                "particle_steps": v.particle_steps,
                "particle_steps_per_s": v.particle_steps as f64 / v.total_s,
                "duration_s": v.duration,
                "d50": opt_num(cut_size(&v.classes)),
                "d50_95": cut_size95(&v.classes)
                    .map_or(serde_json::Value::Null, |(lo, hi)| serde_json::json!([num(lo), num(hi)])),
                "unmatched_departures": v.unmatched,
                "classes": classes,
            }),
        );
    }
    let of = openfoam.map(|g| {
        let classes: Vec<serde_json::Value> = g
            .classes
            .iter()
            .map(|c| {
                let scg = o
                    .classes
                    .iter()
                    .find(|s| (s.diameter - c.diameter).abs() <= 1e-3 * s.diameter);
                scg.map_or_else(
                    || serde_json::to_value(c).unwrap_or_default(),
                    |s| class_json(c, s, serde_json::json!({})),
                )
            })
            .collect();
        serde_json::json!({
            "code": g.code,
            "d50": opt_num(g.d50.or_else(|| cut_size(&g.classes))),
            "particle_steps_per_s": opt_num(g.particle_steps_per_s),
            "classes": classes,
        })
    });
    serde_json::json!({
        "code": "scg",
        "case": "cyclone",
        "definitions": {
            "efficiency": "collected/fed where the scene has a collecting zone (collected: entered it, the dust outlet at the bottom of the cone), else 1 - escaped/fed (escaped: left through the outlet patch, the vortex finder; held: inside at the end, undecided; lost: out through the inlet)",
            "residence_times": "feed-to-escape time of each escaped particle, s (held and lost particles have none)",
            "w1_over_mean": "1-Wasserstein distance between the class's residence times and the original's, over the original's mean",
            "delta_efficiency_pp": "efficiency minus the original's (OpenFOAM: minus scg original's), percentage points",
            "two_sigma_pp": "two binomial standard errors of the efficiency from the fed count, percentage points",
            "efficiency_95": "Wilson's 95 % score interval of the efficiency",
            "escaped_share_95": "Wilson's 95 % score interval of escaped/fed",
            "held_moving": format!("held particles faster than {MOVING} m/s at the end"),
            "escaped_in_last_s": format!("escapes during the last {LATE} s of the run"),
            "d50": "diameter where the efficiency first rises through 0.5, linear between classes, m"
        },
        "theory": {
            "density": rho,
            "lapple_d50": theory.lapple_d50(rho),
            "barth_muschelknautz_d50": theory.barth_muschelknautz_d50(rho),
            "barth_muschelknautz_v_theta": theory.bm_tangential_velocity(),
            "field_v_theta": opt_num(theory.field_swirl.map(|f| f.0)),
            "field_v_r": opt_num(theory.field_swirl.map(|f| f.1)),
            "barth_muschelknautz_d50_field_swirl": opt_num(theory.field_swirl.map(|f| theory.bm_d50_with_swirl(rho, f.0))),
        },
        "variants": variants,
        "openfoam": of,
        "tracers": tracers.map(|t| serde_json::to_value(t).unwrap_or_default()),
        "criteria": criteria(runs).iter().map(|c| serde_json::json!({
            "what": c.what, "value": num(c.value), "limit": opt_num(c.limit), "pass": c.pass(),
        })).collect::<Vec<_>>(),
    })
}

/// Text report: the grade efficiency table, the shares held and lost, the residence
/// times, d50s, wall times and the criteria.
pub fn report(
    runs: &[CycloneRun],
    theory: &Cyclone,
    openfoam: Option<&ExternalGrade>,
    tracers: Option<&TracerCheck>,
) -> String {
    let mut s = String::new();
    let o = &runs[0];
    let collects = o.classes.iter().any(|c| c.collected.is_some());
    let _ = writeln!(
        s,
        "grade efficiency {}, % (simulated {:.1} s; fed per class: {})",
        if collects {
            "collected/fed"
        } else {
            "1 − escaped/fed"
        },
        o.duration,
        runs.iter()
            .map(|v| format!("{} {}", v.name, v.classes.first().map_or(0, |c| c.fed)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = write!(s, "{:>7}", "d[µm]");
    for v in runs {
        let _ = write!(s, " {:>9}", v.name);
    }
    if let Some(g) = openfoam {
        let _ = write!(s, " {:>9}", g.code);
    }
    let _ = writeln!(
        s,
        "   | original: {:>15} {:>15} {:>6} {:>6} {:>6} {:>5}",
        "η [95 %]", "escaped [95 %]", "held", "lost", "moving", "late"
    );
    for (i, c) in o.classes.iter().enumerate() {
        let _ = write!(s, "{:>7.1}", c.diameter * 1e6);
        for v in runs {
            let _ = write!(s, " {:>9.1}", 100.0 * v.classes[i].efficiency);
        }
        if let Some(g) = openfoam {
            let e = g.matching(c.diameter).map_or(f64::NAN, |m| m.efficiency);
            let _ = write!(s, " {:>9.1}", 100.0 * e);
        }
        let (lo, hi) = c.efficiency95();
        let (elo, ehi) = wilson95(c.escaped, c.fed);
        let _ = writeln!(
            s,
            "   |           {:>4.0} [{:>3.0},{:>3.0}]  {:>4.0} [{:>3.0},{:>3.0}] {:>5.1}% {:>5.1}% {:>6} {:>5}",
            100.0 * c.efficiency,
            100.0 * lo,
            100.0 * hi,
            100.0 * c.escaped_share(),
            100.0 * elo,
            100.0 * ehi,
            100.0 * c.held_share(),
            100.0 * c.lost_share(),
            o.held_moving[i],
            o.escaped_late[i]
        );
    }
    let _ = writeln!(
        s,
        "(η and escaped with Wilson's 95 % interval; held: still inside at the end, undecided; \
         lost: out through the inlet; all shares of the fed; moving: held particles faster than \
         {MOVING} m/s at the end; late: escapes in the last {LATE} s)"
    );
    let _ = writeln!(
        s,
        "\nΔ efficiency to the original, pp (± two binomial standard errors of the variant)"
    );
    let _ = write!(s, "{:>7}", "d[µm]");
    for v in &runs[1..] {
        let _ = write!(s, " {:>15}", v.name);
    }
    let _ = writeln!(s);
    for (i, c) in o.classes.iter().enumerate() {
        let _ = write!(s, "{:>7.1}", c.diameter * 1e6);
        for v in &runs[1..] {
            let b = &v.classes[i];
            let _ = write!(
                s,
                " {:>7.1} ±{:>6.1}",
                100.0 * (b.efficiency - c.efficiency),
                two_sigma_pp(b)
            );
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(
        s,
        "\nresidence time of the escaped, mean s (W1 / the original's mean)"
    );
    let _ = write!(s, "{:>7}", "d[µm]");
    for v in runs {
        let _ = write!(s, " {:>17}", v.name);
    }
    let _ = writeln!(s);
    for (i, c) in o.classes.iter().enumerate() {
        let _ = write!(s, "{:>7.1}", c.diameter * 1e6);
        for v in runs {
            let b = &v.classes[i];
            let _ = write!(
                s,
                " {:>7.3} ({:>6.3})",
                b.mean_residence(),
                residence_w1(c, b)
            );
        }
        let _ = writeln!(s);
    }
    let rho = o.classes.first().map_or(2000.0, |c| c.density);
    let um = |d: Option<f64>| d.map_or("—".to_string(), |d| format!("{:.2} µm", d * 1e6));
    let _ = writeln!(
        s,
        "\n{:<9} {:>10} {:>10} {:>8} {:>14} {:>12} {:>10}",
        "variant", "d50", "total [s]", "ratio", "particle-steps", "steps/s", "unmatched"
    );
    for v in runs {
        let _ = writeln!(
            s,
            "{:<9} {:>10} {:>10.1} {:>8.3} {:>14} {:>12.3e} {:>10}   (CPU {})",
            v.name,
            um(cut_size(&v.classes)),
            v.total_s,
            v.total_s / o.total_s,
            v.particle_steps,
            v.particle_steps as f64 / v.total_s,
            v.unmatched,
            v.cpu_s.map_or("—".to_string(), |c| format!(
                "{c:.1} s, ratio {:.3}",
                o.cpu_s.map_or(f64::NAN, |oc| c / oc)
            ))
        );
    }
    if let Some(g) = openfoam {
        let _ = writeln!(
            s,
            "{:<9} {:>10} {:>10} {:>8} {:>14} {:>12}",
            g.code,
            um(g.d50.or_else(|| cut_size(&g.classes))),
            "",
            "",
            "",
            g.particle_steps_per_s
                .map_or(String::new(), |x| format!("{x:.3e}"))
        );
    }
    let _ = writeln!(
        s,
        "cyclone theory at {rho} kg/m³: Lapple d50 = {:.2} µm, Barth–Muschelknautz x50 = {:.2} µm \
         (its swirl v_θCS = {:.1} m/s)",
        theory.lapple_d50(rho) * 1e6,
        theory.barth_muschelknautz_d50(rho) * 1e6,
        theory.bm_tangential_velocity()
    );
    if let Some((vt, vr)) = theory.field_swirl {
        let _ = writeln!(
            s,
            "the air field on the control surface (r = R_x below the vortex finder): v_θ = {vt:.1} m/s, \
             inward v_r = {vr:.2} m/s (the model's {:.2}); Barth–Muschelknautz with the field's swirl: \
             x50 = {:.2} µm",
            theory.bm_radial_velocity(),
            theory.bm_d50_with_swirl(rho, vt) * 1e6
        );
    }
    let _ = writeln!(s, "{}", theory.pressure_drops());
    if let Some(t) = tracers {
        s += &t.text();
    }
    let _ = writeln!(s, "\ncriteria (issue 16):");
    for c in criteria(runs) {
        let verdict = match c.pass() {
            Some(true) => "pass",
            Some(false) => "FAIL",
            None => "stated",
        };
        let _ = writeln!(
            s,
            "  {:<6} {} = {:.4}{}",
            verdict,
            c.what,
            c.value,
            c.limit
                .map_or(String::new(), |l| format!(" (limit {l:.4})"))
        );
    }
    s
}

/// Write `report.txt`, `summary.json` and `grade.csv` into `out`.
pub fn write_tables(
    runs: &[CycloneRun],
    theory: &Cyclone,
    openfoam: Option<&ExternalGrade>,
    tracers: Option<&TracerCheck>,
    out: &Path,
) -> Result<(), String> {
    let w = |name: &str, text: String| {
        std::fs::write(out.join(name), text)
            .map_err(|e| format!("{}: {e}", out.join(name).display()))
    };
    let mut csv = String::from(
        "code,variant,group,diameter_m,density,fed,escaped,held,lost,efficiency,mean_residence_s,w1_over_mean\n",
    );
    let o = &runs[0];
    let rows = runs
        .iter()
        .map(|v| ("scg", v.name.as_str(), &v.classes))
        .chain(openfoam.map(|g| (g.code.as_str(), "", &g.classes)));
    for (code, name, classes) in rows {
        for c in classes {
            let w1 = o
                .classes
                .iter()
                .find(|r| (r.diameter - c.diameter).abs() <= 1e-3 * r.diameter)
                .map_or(f64::NAN, |r| residence_w1(r, c));
            let _ = writeln!(
                csv,
                "{code},{name},{},{:e},{},{},{},{},{},{:e},{:e},{:e}",
                c.group,
                c.diameter,
                c.density,
                c.fed,
                c.escaped,
                c.held,
                c.lost,
                c.efficiency,
                c.mean_residence(),
                w1
            );
        }
    }
    w("grade.csv", csv)?;
    w(
        "summary.json",
        serde_json::to_string_pretty(&summary(runs, theory, openfoam, tracers))
            .map_err(|e| e.to_string())?
            + "\n",
    )?;
    w("report.txt", report(runs, theory, openfoam, tracers))
}

/// The study's tables in Markdown, as docs/cyclone.md quotes them (`scg study cyclone
/// --from DIR --markdown`): the original's grade curve with Wilson's 95 % interval, the
/// escaped and undecided shares; then per variant its largest |Δη| to the original, the
/// classes where Δη is beyond the intervals (`classes_beyond`), d50 and wall time
/// against the original's.
pub fn markdown(runs: &[CycloneRun]) -> String {
    let mut s = String::new();
    let o = &runs[0];
    let g = |x: f64| {
        let t = format!("{x:.1}");
        t.strip_suffix(".0").map_or(t.clone(), str::to_string)
    };
    let pc = |x: f64| g(100.0 * x);
    let eta = if o.classes.iter().any(|c| c.collected.is_some()) {
        "η = collected/fed"
    } else {
        "η = 1 − escaped/fed"
    };
    let _ = writeln!(
        s,
        "| d [µm] | {eta} [95 %] | escaped/fed | held (undecided) |\n|---|---|---|---|"
    );
    for c in &o.classes {
        let (lo, hi) = c.efficiency95();
        let _ = writeln!(
            s,
            "| {} | {} [{:.0}, {:.0}] | {} | {} % |",
            g(c.diameter * 1e6),
            pc(c.efficiency),
            100.0 * lo,
            100.0 * hi,
            pc(c.escaped_share()),
            pc(c.held_share())
        );
    }
    let _ = writeln!(
        s,
        "\n| variant | max \\|Δη\\| to the original, pp | classes beyond the 95 % intervals | d50 [µm] [95 %] | wall time / the original's |\n|---|---|---|---|---|"
    );
    for v in runs {
        let (d, k) = if v.name == o.name {
            ("—".to_string(), "—".to_string())
        } else {
            (
                format!("{:.2}", max_delta_pp(o, v)),
                format!("{} of {}", classes_beyond(o, v), v.classes.len()),
            )
        };
        let _ = writeln!(
            s,
            "| {} | {d} | {k} | {} | {:.3} |",
            v.name,
            match (cut_size(&v.classes), cut_size95(&v.classes)) {
                (Some(x), Some((lo, hi))) => {
                    let b = |y: f64| {
                        if y.is_finite() {
                            format!("{:.2}", y * 1e6)
                        } else {
                            "…".to_string()
                        }
                    };
                    format!("{:.2} [{}, {}]", x * 1e6, b(lo), b(hi))
                }
                _ => "—".to_string(),
            },
            v.total_s / o.total_s
        );
    }
    s
}
