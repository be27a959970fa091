//! A study's plots: radial distributions (Fig. 10), top views (Fig. 9), partition curves
//! and computing times (Fig. 8), as SVG.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::{DrawingArea, IntoDrawingArea, SVGBackend, WHITE};

use super::VariantRun;
use crate::chart::legend;

type PlotResult = Result<(), String>;

pub(crate) fn perr<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// An SVG drawing area of `size` pixels at `path`, filled white.
pub(crate) fn svg_root(
    path: &Path,
    size: (u32, u32),
) -> Result<DrawingArea<SVGBackend<'_>, Shift>, String> {
    let root = SVGBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(perr)?;
    Ok(root)
}

/// Line colours of the variants, in order (black for the original).
pub(crate) const VARIANT_COLORS: [plotters::style::RGBColor; 8] = [
    plotters::style::RGBColor(0, 0, 0),
    plotters::style::RGBColor(31, 119, 180),
    plotters::style::RGBColor(214, 39, 40),
    plotters::style::RGBColor(44, 160, 44),
    plotters::style::RGBColor(148, 103, 189),
    plotters::style::RGBColor(255, 127, 14),
    plotters::style::RGBColor(140, 86, 75),
    plotters::style::RGBColor(23, 190, 207),
];

/// Fig. 10: per class, the radial distribution of each variant (fraction per bin vs r/R).
pub fn plot_radial(runs: &[VariantRun], path: &Path) -> PlotResult {
    use plotters::prelude::*;
    let n = runs[0].result.classes.len();
    let cols = n.min(4);
    let rows = n.div_ceil(cols);
    let root = svg_root(path, (300 * cols as u32, 260 * rows as u32 + 30))?;
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
                .draw_series(LineSeries::new(
                    pts,
                    VARIANT_COLORS[vi % VARIANT_COLORS.len()].stroke_width(2),
                ))
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
    let root = svg_root(path, (640, 680))?;
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
    legend(&mut chart)?;
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
    let root = svg_root(path, (720, 480))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "partition: drained by the end (solid), steady-state fates (dashed)",
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
        .y_desc("fraction to the fines")
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
        let col = VARIANT_COLORS[vi % VARIANT_COLORS.len()];
        chart
            .draw_series(LineSeries::new(pts.clone(), col.stroke_width(2)))
            .map_err(perr)?
            .label(v.name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col));
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 4, col.filled())))
            .map_err(perr)?;
        let steady: Vec<(f64, f64)> = v
            .result
            .classes
            .iter()
            .filter(|c| c.fates.fine_fraction().is_finite())
            .map(|c| (c.diameter * 1e6, c.fates.fine_fraction()))
            .collect();
        chart
            .draw_series(DashedLineSeries::new(
                steady.clone(),
                6,
                4,
                col.stroke_width(2),
            ))
            .map_err(perr)?;
        chart
            .draw_series(
                steady
                    .iter()
                    .map(|p| TriangleMarker::new(*p, 5, col.filled())),
            )
            .map_err(perr)?;
    }
    chart
        .draw_series(LineSeries::new(
            vec![(lo, 0.5), (hi, 0.5)],
            RGBColor(150, 150, 150).stroke_width(1),
        ))
        .map_err(perr)?;
    legend(&mut chart)?;
    root.present().map_err(perr)?;
    Ok(())
}

/// Fig. 8: computing time for 0.1 s per variant.
pub fn plot_time(runs: &[VariantRun], path: &Path) -> PlotResult {
    use plotters::prelude::*;
    let tmax = runs.iter().map(|v| v.time_s).fold(0.0, f64::max).max(1e-6) * 1.15;
    let root = svg_root(path, (520, 420))?;
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

/// Write every plot of a study into `out`.
pub fn write_plots(runs: &[VariantRun], nozzle: f64, out: &Path) -> PlotResult {
    plot_radial(runs, &out.join("radial.svg"))?;
    plot_partition(runs, &out.join("partition.svg"))?;
    plot_time(runs, &out.join("time.svg"))?;
    for v in runs {
        plot_snapshot(v, nozzle, &out.join(format!("snapshot-{}.svg", v.name)))?;
    }
    Ok(())
}
