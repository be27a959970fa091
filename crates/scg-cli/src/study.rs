//! `scg study classifier|classifier-psd`: the paper's Section 5 end to end. Runs the three
//! variants (original, CG α = 2 with SCG, CG α = 2 without SCG), then writes the radial
//! distributions (Fig. 10), top-view snapshots (Fig. 9), drained fractions and the
//! partition curve with d50, the computing time for 0.1 s (Fig. 8), the normalised W1
//! distances to the original, and `summary.json`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use clap::Args;

use scg_core::frame::{Frame, FrameSink};
use scg_core::stages::outlet::OutletLog;

use crate::EXIT_BAD_INPUT;
use crate::classify::{self, Analysis, Params};

/// The classifier scene (embedded so the study runs from any directory).
pub const CLASSIFIER: &str = include_str!("../../../cases/classifier.toml");
/// The classifier with a continuous size distribution.
pub const CLASSIFIER_PSD: &str = include_str!("../../../cases/classifier-psd.toml");

/// Arguments of `scg study`.
#[derive(Args, Debug)]
pub struct StudyArgs {
    /// `classifier` (paper Table 3) or `classifier-psd` (size distribution, partition curve).
    pub study: String,
    /// Fewer particles (feed rates scaled down): a few minutes in all.
    #[arg(long)]
    pub quick: bool,
    /// Output folder (default `recordings/study-<study>[-quick]`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Do not write an MCAP recording per variant.
    #[arg(long)]
    pub no_record: bool,
    /// Extra scene overrides applied to every variant (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

/// One study: its scene and windows.
#[derive(Clone, Debug)]
pub struct StudySpec {
    /// Name.
    pub name: &'static str,
    /// Scene text.
    pub scene: &'static str,
    /// Analysis window (distributions), s; the computing time is measured over its last
    /// 0.1 s, the drained fraction over the particles fed up to half of `to`.
    pub window: (f64, f64),
    /// Feed-rate scale of `--quick`.
    pub quick_scale: f64,
}

/// The studies.
pub fn spec(name: &str) -> Option<StudySpec> {
    match name {
        "classifier" => Some(StudySpec {
            name: "classifier",
            scene: CLASSIFIER,
            window: (0.2, 0.3),
            quick_scale: 1.0 / 12.0,
        }),
        "classifier-psd" => Some(StudySpec {
            name: "classifier-psd",
            scene: CLASSIFIER_PSD,
            window: (0.5, 0.6),
            quick_scale: 1.0 / 4.0,
        }),
        _ => None,
    }
}

/// The variants: name and the overrides that select them.
pub const VARIANTS: [(&str, [&str; 2]); 3] = [
    ("original", ["coarse_grain.alpha=1", "coarse_grain.law=scg"]),
    ("scg", ["coarse_grain.alpha=2", "coarse_grain.law=scg"]),
    ("none", ["coarse_grain.alpha=2", "coarse_grain.law=none"]),
];

/// Frames go straight into the analysis (also used by `scg cost`).
pub(crate) struct AnalysisSink(pub(crate) Arc<Mutex<Analysis>>);

impl FrameSink for AnalysisSink {
    fn write_frame(&mut self, frame: &Frame) -> Result<(), String> {
        self.0.lock().map_err(|e| e.to_string())?.observe(frame);
        Ok(())
    }
    fn finish(&mut self) -> Result<(), String> {
        Ok(())
    }
}

/// One variant's run.
#[derive(Clone, Debug)]
pub struct VariantRun {
    /// Variant name.
    pub name: String,
    /// The analysis.
    pub result: classify::Result,
    /// Wall time of the last 0.1 s of the window, s.
    pub time_s: f64,
    /// Wall time of the whole run, s.
    pub total_s: f64,
    /// Particles drained, per class (outlet log).
    pub drained: Vec<usize>,
    /// Particles lost (left the domain elsewhere), per class.
    pub lost: Vec<usize>,
    /// Particles resident at the end.
    pub resident: usize,
    /// Simulated particles fed.
    pub fed: Vec<u64>,
}

/// Run one variant of `text` with `overrides`; record to `mcap` when given.
pub fn run_variant(
    name: &str,
    text: &str,
    overrides: &[String],
    window: (f64, f64),
    mcap: Option<&Path>,
) -> Result<VariantRun, String> {
    let scene =
        scg_scene::parse(text, &format!("<{name}>"), name, overrides).map_err(|e| e.to_string())?;
    let params = Params::for_window(window.0, window.1, classify::vessel_radius(&scene));
    let mut sim = scene.build(true);
    let meta = scene.run_meta(scg_scene::check::check(&scene).messages());
    let analysis = Arc::new(Mutex::new(Analysis::new(&meta, &scene.flow, params)));
    sim.add_recorder(Box::new(AnalysisSink(analysis.clone())));
    if let Some(p) = mcap {
        let sink = scg_record::McapSink::create(p, &meta).map_err(|e| e.to_string())?;
        sim.add_recorder(Box::new(sink));
    }
    let steps = scene.steps();
    let timed_from = (((window.1 - 0.1).max(0.0)) / scene.dt).round() as u64;
    let timed_from = timed_from.min(steps);
    let t0 = Instant::now();
    sim.record_now().map_err(|e| e.to_string())?;
    sim.run(timed_from, |_| true).map_err(|e| e.to_string())?;
    let t1 = Instant::now();
    sim.run(steps - timed_from, |_| true)
        .map_err(|e| e.to_string())?;
    let time_s = t1.elapsed().as_secs_f64();
    let total_s = t0.elapsed().as_secs_f64();
    sim.finish_recorders().map_err(|e| e.to_string())?;
    let log = sim.world.resource::<OutletLog>().clone();
    let fed = sim.world.resource::<scg_core::state::Tally>().fed.clone();
    let resident = sim.particles().len();
    let result = analysis.lock().map_err(|e| e.to_string())?.result();
    Ok(VariantRun {
        name: name.to_string(),
        result,
        time_s,
        total_s,
        drained: log.drained.iter().map(Vec::len).collect(),
        lost: log.lost.iter().map(Vec::len).collect(),
        resident,
        fed,
    })
}

/// Normalised W1 of each class of `v` to the same class of `reference`.
pub fn w1_to(reference: &classify::Result, v: &classify::Result) -> Vec<f64> {
    let r = reference.params.radius;
    reference
        .classes
        .iter()
        .zip(&v.classes)
        .map(|(a, b)| classify::wasserstein1(&a.radii, &b.radii) / r)
        .collect()
}

/// The partition curve (original diameter, drained fraction) of a run.
pub fn partition(r: &classify::Result) -> Vec<(f64, f64)> {
    r.classes
        .iter()
        .map(|c| (c.diameter, c.drained_fraction))
        .collect()
}

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
        let d50 = classify::d50(&partition(&v.result)).map(|d| d * 1e6);
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
        let d50 = classify::d50(&partition(&v.result));
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

type PlotResult = Result<(), String>;

fn perr<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

const VARIANT_COLORS: [plotters::style::RGBColor; 3] = [
    plotters::style::RGBColor(0, 0, 0),
    plotters::style::RGBColor(31, 119, 180),
    plotters::style::RGBColor(214, 39, 40),
];

/// Fig. 10: per class, the radial distribution of each variant (fraction per bin vs r/R).
pub fn plot_radial(runs: &[VariantRun], path: &Path) -> PlotResult {
    use plotters::prelude::*;
    let n = runs[0].result.classes.len();
    let cols = n.min(4);
    let rows = n.div_ceil(cols);
    let root =
        SVGBackend::new(path, (300 * cols as u32, 260 * rows as u32 + 30)).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    let (title, body) = root.split_vertically(30);
    title
        .titled(
            &format!(
                "radial distance distributions, {}–{} s (black original, blue SCG, red no SCG)",
                runs[0].result.params.from, runs[0].result.params.to
            ),
            ("sans-serif", 16),
        )
        .map_err(perr)?;
    let areas = body.split_evenly((rows, cols));
    let bins = runs[0].result.params.bins;
    for (ci, area) in areas.iter().enumerate().take(n) {
        let ymax = runs
            .iter()
            .flat_map(|v| v.result.classes[ci].histogram.iter().copied())
            .fold(0.0f64, f64::max)
            .max(1e-3)
            * 1.1;
        let mut chart = ChartBuilder::on(area)
            .caption(
                format!("{:.0} µm", runs[0].result.classes[ci].diameter * 1e6),
                ("sans-serif", 14),
            )
            .margin(6)
            .x_label_area_size(30)
            .y_label_area_size(40)
            .build_cartesian_2d(0.0..1.0, 0.0..ymax)
            .map_err(perr)?;
        chart
            .configure_mesh()
            .x_desc("r / R")
            .y_desc("fraction")
            .draw()
            .map_err(perr)?;
        for (vi, v) in runs.iter().enumerate() {
            let h = &v.result.classes[ci].histogram;
            let mut pts = Vec::with_capacity(2 * bins);
            for (b, y) in h.iter().enumerate() {
                pts.push((b as f64 / bins as f64, *y));
                pts.push(((b + 1) as f64 / bins as f64, *y));
            }
            chart
                .draw_series(LineSeries::new(pts, VARIANT_COLORS[vi % 3].stroke_width(2)))
                .map_err(perr)?;
        }
    }
    root.present().map_err(perr)?;
    Ok(())
}

/// Fig. 9: top view of one run at the snapshot time, coloured by class.
pub fn plot_snapshot(v: &VariantRun, nozzle: f64, path: &Path) -> PlotResult {
    use plotters::prelude::*;
    let Some((t, pts)) = &v.result.snapshot else {
        return Ok(());
    };
    let r = v.result.params.radius;
    let root = SVGBackend::new(path, (640, 680)).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{}: top view at t = {t:.4} s ({} particles)",
                v.name,
                pts.len()
            ),
            ("sans-serif", 16),
        )
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(50)
        .build_cartesian_2d(-r * 1.05..r * 1.05, -r * 1.05..r * 1.05)
        .map_err(perr)?;
    chart.configure_mesh().disable_mesh().draw().map_err(perr)?;
    for (rad, c) in [(r, BLACK), (nozzle, RGBColor(120, 120, 120))] {
        let circle: Vec<(f64, f64)> = (0..=180)
            .map(|k| {
                let a = k as f64 / 180.0 * std::f64::consts::TAU;
                (rad * a.cos(), rad * a.sin())
            })
            .collect();
        chart
            .draw_series(LineSeries::new(circle, c.stroke_width(1)))
            .map_err(perr)?;
    }
    let ng = v.result.classes.len();
    for g in 0..ng {
        let c = Palette99::pick(g).to_rgba();
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| p.group as usize == g)
                    .map(|p| Circle::new((p.xy[0], p.xy[1]), 1, c.filled())),
            )
            .map_err(perr)?
            .label(format!("{:.0} µm", v.result.classes[g].diameter * 1e6))
            .legend(move |(x, y)| Circle::new((x + 8, y), 4, c.filled()));
    }
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(perr)?;
    root.present().map_err(perr)?;
    Ok(())
}

/// Partition curves (drained fraction vs original diameter) of the variants.
pub fn plot_partition(runs: &[VariantRun], path: &Path) -> PlotResult {
    use plotters::prelude::*;
    let d: Vec<f64> = runs[0]
        .result
        .classes
        .iter()
        .map(|c| c.diameter * 1e6)
        .collect();
    let (lo, hi) = (d[0] * 0.9, d[d.len() - 1] * 1.05);
    let root = SVGBackend::new(path, (720, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "partition curve: drained fraction (fines) per class",
            ("sans-serif", 16),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(lo..hi, 0.0..1.0)
        .map_err(perr)?;
    chart
        .configure_mesh()
        .x_desc("original diameter [µm]")
        .y_desc("drained fraction")
        .draw()
        .map_err(perr)?;
    for (vi, v) in runs.iter().enumerate() {
        let pts: Vec<(f64, f64)> = v
            .result
            .classes
            .iter()
            .filter(|c| c.drained_fraction.is_finite())
            .map(|c| (c.diameter * 1e6, c.drained_fraction))
            .collect();
        let col = VARIANT_COLORS[vi % 3];
        chart
            .draw_series(LineSeries::new(pts.clone(), col.stroke_width(2)))
            .map_err(perr)?
            .label(v.name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col));
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 4, col.filled())))
            .map_err(perr)?;
    }
    chart
        .draw_series(LineSeries::new(
            vec![(lo, 0.5), (hi, 0.5)],
            RGBColor(150, 150, 150).stroke_width(1),
        ))
        .map_err(perr)?;
    chart
        .configure_series_labels()
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(perr)?;
    root.present().map_err(perr)?;
    Ok(())
}

/// Fig. 8: computing time for 0.1 s per variant.
pub fn plot_time(runs: &[VariantRun], path: &Path) -> PlotResult {
    use plotters::prelude::*;
    let tmax = runs.iter().map(|v| v.time_s).fold(0.0, f64::max).max(1e-6) * 1.15;
    let root = SVGBackend::new(path, (520, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    let mut chart = ChartBuilder::on(&root)
        .caption("computing time for 0.1 s", ("sans-serif", 16))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(0.0..runs.len() as f64, 0.0..tmax)
        .map_err(perr)?;
    let names: Vec<String> = runs.iter().map(|v| v.name.clone()).collect();
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(runs.len() * 2 + 1)
        .x_label_formatter(&|x| {
            let i = (x - 0.5).round();
            if (x - 0.5 - i).abs() < 1e-6 && i >= 0.0 && (i as usize) < names.len() {
                names[i as usize].clone()
            } else {
                String::new()
            }
        })
        .y_desc("wall time [s]")
        .draw()
        .map_err(perr)?;
    chart
        .draw_series(runs.iter().enumerate().map(|(i, v)| {
            Rectangle::new(
                [(i as f64 + 0.2, 0.0), (i as f64 + 0.8, v.time_s)],
                VARIANT_COLORS[i % 3].filled(),
            )
        }))
        .map_err(perr)?;
    root.present().map_err(perr)?;
    Ok(())
}

/// Write every table and plot of a study into `out`.
pub fn write_outputs(runs: &[VariantRun], nozzle: f64, out: &Path) -> Result<(), String> {
    let w = |name: &str, text: String| {
        std::fs::write(out.join(name), text)
            .map_err(|e| format!("{}: {e}", out.join(name).display()))
    };
    let mut long = String::from("variant,class_um,bin_lo_r_over_R,bin_hi_r_over_R,fraction\n");
    for v in runs {
        w(
            &format!("radial-{}.csv", v.name),
            classify::radial_csv(&v.result),
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
        let d = classify::d50(&partition(&v.result));
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
        serde_json::to_string_pretty(&summary(runs)).map_err(perr)? + "\n",
    )?;
    w("report.txt", report(runs))?;
    plot_radial(runs, &out.join("radial.svg"))?;
    plot_partition(runs, &out.join("partition.svg"))?;
    plot_time(runs, &out.join("time.svg"))?;
    for v in runs {
        plot_snapshot(v, nozzle, &out.join(format!("snapshot-{}.svg", v.name)))?;
    }
    Ok(())
}

/// Run `scg study`; returns the exit status.
pub fn study(a: StudyArgs) -> i32 {
    let Some(spec) = spec(&a.study) else {
        eprintln!(
            "error: unknown study `{}` (classifier, classifier-psd)",
            a.study
        );
        return EXIT_BAD_INPUT;
    };
    let out = a.out.clone().unwrap_or_else(|| {
        PathBuf::from(format!(
            "recordings/study-{}{}",
            spec.name,
            if a.quick { "-quick" } else { "" }
        ))
    });
    if let Err(e) = std::fs::create_dir_all(&out) {
        eprintln!("error: cannot create {}: {e}", out.display());
        return EXIT_BAD_INPUT;
    }
    let mut runs = Vec::new();
    let mut nozzle = 0.0;
    for (name, sets) in VARIANTS {
        let mut overrides: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        overrides.push(format!("name=\"{}-{name}\"", spec.name));
        if a.quick {
            overrides.push(format!("feed_scale={}", spec.quick_scale));
        }
        overrides.extend(a.set.iter().cloned());
        let mcap = (!a.no_record).then(|| out.join(format!("{}-{name}.mcap", spec.name)));
        eprintln!("study {}: running variant `{name}`…", spec.name);
        match run_variant(name, spec.scene, &overrides, spec.window, mcap.as_deref()) {
            Ok(v) => {
                eprintln!(
                    "  done in {:.1} s ({} resident, 0.1 s took {:.2} s)",
                    v.total_s, v.resident, v.time_s
                );
                runs.push(v);
            }
            Err(e) => {
                eprintln!("error: variant `{name}`: {e}");
                return 1;
            }
        }
        if let Ok(s) = scg_scene::parse(spec.scene, "<study>", spec.name, &[]) {
            nozzle = s.outlet.map_or(0.0, |o| o.geometry.nozzle_radius);
        }
    }
    print!("{}", report(&runs));
    if let Err(e) = write_outputs(&runs, nozzle, &out) {
        eprintln!("error: {e}");
        return 1;
    }
    eprintln!(
        "wrote tables, plots and summary.json under {}",
        out.display()
    );
    0
}
