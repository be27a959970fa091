//! `cost.svg`: the sweep's error against the measured wall time.

use std::path::Path;

use super::ERROR_FLOOR;
use super::run::{Outcome, Sweep, pareto};

/// `cost.svg`: log–log error against the measured wall time (single-particle scenes: of
/// the population standing for the same originals), one curve per law through its base
/// points in α order (from the α = 1 reference), every point labelled with α and dt, the
/// Pareto front marked.
pub fn plot(s: &Sweep, path: &Path) -> Result<(), String> {
    use plotters::prelude::*;
    let pts: Vec<(&Outcome, f64, f64)> = s
        .outcomes
        .iter()
        .filter(|o| o.error.is_finite() && o.failure.is_none())
        .map(|o| (o, o.wall_s.max(1e-6), o.error.max(ERROR_FLOOR)))
        .collect();
    if pts.is_empty() {
        return Ok(());
    }
    // SVG only: no font rasterizer or system font library is needed (PNG: `rsvg-convert`).
    draw(
        s,
        &pts,
        SVGBackend::new(path, (900, 620)).into_drawing_area(),
    )
}

fn draw<DB: plotters::prelude::DrawingBackend>(
    s: &Sweep,
    pts: &[(&Outcome, f64, f64)],
    root: plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    use plotters::prelude::*;
    let (tmin, tmax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.1), b.max(p.1))
    });
    let (emin, emax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.2), b.max(p.2))
    });
    let e = |x: plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    root.fill(&WHITE).map_err(e)?;
    let caption = match s.represented {
        Some(n) => format!(
            "scg cost: {}, {n} originals represented (errors clamped at {ERROR_FLOOR:e})",
            s.scene
        ),
        None => format!("scg cost: {} (errors clamped at {ERROR_FLOOR:e})", s.scene),
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (tmin / 1.5..tmax * 1.5).log_scale(),
            (emin / 10.0..(emax * 10.0).max(emin * 100.0)).log_scale(),
        )
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(if s.represented.is_some() {
            "measured wall time of the represented population [s]"
        } else {
            "measured wall time [s]"
        })
        .y_desc("error")
        .x_label_formatter(&|v| format!("{v:.3}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(e)?;
    let laws = ["original", "scg", "none", "mass", "parcel", "sample"];
    let r = &s.reference;
    let is_base = |o: &Outcome| {
        o.point.dt_mult == r.dt_mult
            && o.point.integrator == r.integrator
            && o.point.stiffness == r.stiffness
    };
    // The α = 1 reference, where every law's curve starts.
    let start = pts
        .iter()
        .find(|p| p.0.point.law.is_none() && is_base(p.0))
        .map(|p| (p.1, p.2));
    for (k, law) in laws.iter().enumerate() {
        let series: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.0.point.law_name() == *law)
            .map(|p| (p.1, p.2))
            .collect();
        if series.is_empty() {
            continue;
        }
        let c = Palette99::pick(k).to_rgba();
        if k > 0 {
            let mut base: Vec<(f64, f64, f64)> = pts
                .iter()
                .filter(|p| p.0.point.law_name() == *law && is_base(p.0))
                .map(|p| (p.0.point.alpha, p.1, p.2))
                .collect();
            base.sort_by(|a, b| a.0.total_cmp(&b.0));
            let curve: Vec<(f64, f64)> = start
                .into_iter()
                .chain(base.iter().map(|b| (b.1, b.2)))
                .collect();
            chart
                .draw_series(LineSeries::new(curve, c.stroke_width(2)))
                .map_err(e)?;
        }
        chart
            .draw_series(
                series
                    .iter()
                    .map(|&(x, y)| Circle::new((x, y), 5, c.filled())),
            )
            .map_err(e)?
            .label(*law)
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, c.filled()));
    }
    // Labels: α and dt of every point (and the integrator or stiffness where not the
    // reference's).
    chart
        .draw_series(pts.iter().map(|p| {
            let o = p.0;
            let mut t = format!("α{} dt{:.0e}", o.point.alpha, o.dt);
            if o.point.integrator != r.integrator {
                t.push_str(&format!(" {}", o.point.integrator.name()));
            }
            if o.point.stiffness != r.stiffness {
                t.push_str(&format!(" E×{}", o.point.stiffness));
            }
            Text::new(t, (p.1, p.2), ("sans-serif", 10).into_font())
        }))
        .map_err(e)?;
    let front: Vec<(f64, f64)> = pareto(&s.outcomes)
        .into_iter()
        .map(|i| {
            let o = &s.outcomes[i];
            (o.wall_s.max(1e-6), o.error.max(ERROR_FLOOR))
        })
        .collect();
    chart
        .draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(1)))
        .map_err(e)?
        .label("Pareto front")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    chart
        .draw_series(
            front
                .iter()
                .map(|&(x, y)| Circle::new((x, y), 9, BLACK.stroke_width(2))),
        )
        .map_err(e)?;
    crate::chart::legend(&mut chart)?;
    root.present().map_err(e)?;
    Ok(())
}
