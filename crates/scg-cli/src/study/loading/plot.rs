//! `loading.svg`: error against wall time, one panel per loading.

use std::path::Path;

use super::report::{Record, loadings as loadings_of};

/// Smallest W1/R drawn (log axis).
const FLOOR: f64 = 1e-4;

/// `loading.svg`: one panel per loading, log–log W1/R of the class farthest beyond its
/// noise against the wall time, with that class's 95 % bootstrap interval as a bar; one
/// curve per family (SCG, sampling) through α = 2 and 4; the originals' wall time as a
/// dashed line; hollow markers agree with the originals within the intervals.
pub fn plot(rows: &[Record], path: &Path) -> Result<(), String> {
    use plotters::prelude::*;
    let loadings = loadings_of(rows);
    if loadings.is_empty() {
        return Ok(());
    }
    let root = SVGBackend::new(path, (420 * loadings.len() as u32, 460)).into_drawing_area();
    let e = |x: plotters::drawing::DrawingAreaErrorKind<std::io::Error>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let panels = root.split_evenly((1, loadings.len()));
    // shared axes
    let walls: Vec<f64> = rows.iter().map(|r| r.wall_s.max(1e-3)).collect();
    let (tmin, tmax) = walls
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), t| (a.min(*t), b.max(*t)));
    let bar = |r: &Record| -> Option<(f64, f64, f64)> {
        let w = r.w1?;
        let (lo, hi) = r.w1_95.unwrap_or((None, None));
        Some((w, lo.unwrap_or(w), hi.unwrap_or(w)))
    };
    let emax = rows
        .iter()
        .filter(|r| r.law != "original")
        .filter_map(|r| bar(r).map(|b| b.2))
        .fold(FLOOR * 10.0, f64::max);
    let families: [(&str, &str, RGBColor); 2] = [
        ("SCG (hollow: agrees)", "scg", RGBColor(31, 119, 180)),
        ("sampling (hollow: agrees)", "sample", RGBColor(214, 39, 40)),
    ];
    for (panel, l) in panels.iter().zip(&loadings) {
        let mut chart = ChartBuilder::on(panel)
            .caption(format!("×{l} the paper's feed"), ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (tmin / 1.5..tmax * 1.5).log_scale(),
                (FLOOR..emax * 2.0).log_scale(),
            )
            .map_err(|x| x.to_string())?;
        chart
            .configure_mesh()
            .x_desc("wall time [s]")
            .y_desc("W1/R (worst class)")
            .x_label_formatter(&|v| format!("{v:.2}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|x| x.to_string())?;
        let here: Vec<&Record> = rows.iter().filter(|r| r.loading == *l).collect();
        if let Some(o) = here.iter().find(|r| r.law == "original") {
            let t = o.wall_s.max(1e-3);
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(t, FLOOR), (t, emax * 2.0)],
                    6,
                    4,
                    BLACK.stroke_width(1),
                ))
                .map_err(|x| x.to_string())?
                .label("originals (the reference)")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        }
        for (name, law, color) in families {
            // (α, wall time, W1, its interval's low and high ends, agrees)
            let mut pts: Vec<(f64, f64, f64, f64, f64, bool)> = here
                .iter()
                .filter(|r| r.law == law)
                .filter_map(|r| {
                    let (w, lo, hi) = bar(r)?;
                    Some((
                        r.alpha,
                        r.wall_s.max(1e-3),
                        w.max(FLOOR),
                        lo.max(FLOOR),
                        hi.max(FLOOR),
                        r.agrees == Some(true),
                    ))
                })
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            chart
                .draw_series(LineSeries::new(
                    pts.iter().map(|p| (p.1, p.2)),
                    color.stroke_width(2),
                ))
                .map_err(|x| x.to_string())?
                .label(name)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            for p in &pts {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(p.1, p.3), (p.1, p.4)],
                        color.stroke_width(1),
                    )))
                    .map_err(|x| x.to_string())?;
                let style = if p.5 {
                    color.stroke_width(2)
                } else {
                    color.filled()
                };
                chart
                    .draw_series(std::iter::once(Circle::new((p.1, p.2), 5, style)))
                    .map_err(|x| x.to_string())?;
                chart
                    .draw_series(std::iter::once(Text::new(
                        format!("α{}", p.0),
                        (p.1, p.2),
                        ("sans-serif", 11).into_font(),
                    )))
                    .map_err(|x| x.to_string())?;
            }
        }
        crate::chart::legend(&mut chart)?;
    }
    root.present().map_err(e)?;
    Ok(())
}
