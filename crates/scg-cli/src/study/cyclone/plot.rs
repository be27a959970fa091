//! The cyclone study's plots (SVG): partition curves of the variants (and OpenFOAM) with
//! the theory's cut sizes, residence-time distributions, and a top and side view of each
//! variant at the snapshot time with the mesh's feature edges for context.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;
use plotters::prelude::*;
use scg_core::frame::PatchSurface;

use super::grade::{ExternalGrade, cut_size};
use super::run::CycloneRun;
use super::theory::Cyclone;
use crate::chart::legend;
use crate::study::plot::{VARIANT_COLORS, perr, svg_root};

type PlotResult = Result<(), String>;

/// Minor grid lines.
const LIGHT: RGBColor = RGBColor(235, 235, 235);

fn color(i: usize) -> RGBColor {
    VARIANT_COLORS[i % VARIANT_COLORS.len()]
}

/// Grade efficiency against the original diameter (log axis) for every variant and
/// OpenFOAM, with the simulated d50s and the Lapple and Barth–Muschelknautz cut sizes.
pub fn plot_partition(
    runs: &[CycloneRun],
    openfoam: Option<&ExternalGrade>,
    theory: &Cyclone,
    path: &Path,
) -> PlotResult {
    let o = &runs[0];
    let d: Vec<f64> = o.classes.iter().map(|c| c.diameter * 1e6).collect();
    let (lo, hi) = (d[0] * 0.8, d[d.len() - 1] * 1.25);
    let rho = o.classes[0].density;
    let root = svg_root(path, (760, 520))?;
    let title = if o.classes.iter().any(|c| c.collected.is_some()) {
        "cyclone grade efficiency (collected/fed)"
    } else {
        "cyclone grade efficiency (1 − escaped/fed)"
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d((lo..hi).log_scale(), 0.0..1.0)
        .map_err(perr)?;
    chart
        .configure_mesh()
        .light_line_style(LIGHT)
        .x_desc("original diameter [µm]")
        .y_desc("grade efficiency")
        .draw()
        .map_err(perr)?;
    let mut curves: Vec<(String, Vec<(f64, f64)>)> = runs
        .iter()
        .map(|v| {
            (
                v.name.clone(),
                v.classes
                    .iter()
                    .map(|c| (c.diameter * 1e6, c.efficiency))
                    .collect(),
            )
        })
        .collect();
    if let Some(g) = openfoam {
        curves.push((
            g.code.clone(),
            g.classes
                .iter()
                .map(|c| (c.diameter * 1e6, c.efficiency))
                .collect(),
        ));
    }
    for (i, (name, pts)) in curves.iter().enumerate() {
        let pts: Vec<(f64, f64)> = pts.iter().copied().filter(|p| p.1.is_finite()).collect();
        let col = color(i);
        let width = if i == 0 { 3 } else { 2 };
        chart
            .draw_series(LineSeries::new(pts.clone(), col.stroke_width(width)))
            .map_err(perr)?
            .label(name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2)));
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 3, col.filled())))
            .map_err(perr)?;
    }
    let grey = RGBColor(150, 150, 150);
    chart
        .draw_series(LineSeries::new(
            vec![(lo, 0.5), (hi, 0.5)],
            grey.stroke_width(1),
        ))
        .map_err(perr)?;
    let mut lines = vec![
        ("Lapple".to_string(), theory.lapple_d50(rho) * 1e6, 0),
        (
            "Barth–Muschelknautz".to_string(),
            theory.barth_muschelknautz_d50(rho) * 1e6,
            1,
        ),
    ];
    if let Some((vt, _)) = theory.field_swirl {
        lines.push((
            format!("B–M, the field's swirl {vt:.1} m/s,"),
            theory.bm_d50_with_swirl(rho, vt) * 1e6,
            2,
        ));
    }
    for (label, x, style) in lines {
        let col = match style {
            0 => RGBColor(120, 120, 120),
            1 => RGBColor(180, 130, 60),
            _ => RGBColor(120, 60, 160),
        };
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x, 0.0), (x, 1.0)],
                6,
                4,
                col.stroke_width(2),
            ))
            .map_err(perr)?
            .label(format!("{label} d50 {x:.1} µm"))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2)));
    }
    if let Some(d50) = cut_size(&o.classes) {
        let x = d50 * 1e6;
        chart
            .draw_series(std::iter::once(TriangleMarker::new(
                (x, 0.5),
                7,
                BLACK.filled(),
            )))
            .map_err(perr)?
            .label(format!("original d50 {x:.1} µm"))
            .legend(|(x, y)| TriangleMarker::new((x + 10, y), 5, BLACK.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.8))
        .draw()
        .map_err(perr)?;
    root.present().map_err(perr)
}

/// Cumulative distributions of the residence times of the escaped, one panel per class
/// with escapes in the original, one line per variant.
pub fn plot_residence(runs: &[CycloneRun], path: &Path) -> PlotResult {
    let o = &runs[0];
    let shown: Vec<usize> = (0..o.classes.len())
        .filter(|&i| !o.classes[i].residence_times.is_empty())
        .collect();
    if shown.is_empty() {
        return Ok(());
    }
    let cols = shown.len().min(3);
    let rows = shown.len().div_ceil(cols);
    let root = svg_root(path, (330 * cols as u32, 250 * rows as u32 + 30))?;
    let (title, body) = root.split_vertically(30);
    title
        .titled(
            "residence time of the escaped (feed to outlet), cumulative",
            ("sans-serif", 16),
        )
        .map_err(perr)?;
    let tmax = runs
        .iter()
        .flat_map(|v| v.classes.iter())
        .filter_map(|c| c.residence_times.last().copied())
        .fold(0.0f64, f64::max)
        .max(1e-3)
        * 1.05;
    let areas = body.split_evenly((rows, cols));
    for (k, &i) in shown.iter().enumerate() {
        let mut chart = ChartBuilder::on(&areas[k])
            .caption(
                format!(
                    "{:.0} µm (original: {} escaped)",
                    o.classes[i].diameter * 1e6,
                    o.classes[i].escaped
                ),
                ("sans-serif", 13),
            )
            .margin(6)
            .x_label_area_size(28)
            .y_label_area_size(36)
            .build_cartesian_2d(0.0..tmax, 0.0..1.0)
            .map_err(perr)?;
        chart
            .configure_mesh()
            .light_line_style(LIGHT)
            .x_desc("t [s]")
            .draw()
            .map_err(perr)?;
        for (vi, v) in runs.iter().enumerate() {
            let t = &v.classes[i].residence_times;
            if t.is_empty() {
                continue;
            }
            let n = t.len() as f64;
            let mut pts = vec![(0.0, 0.0)];
            for (j, x) in t.iter().enumerate() {
                pts.push((*x, j as f64 / n));
                pts.push((*x, (j + 1) as f64 / n));
            }
            pts.push((tmax, 1.0));
            let col = color(vi);
            chart
                .draw_series(LineSeries::new(pts, col.stroke_width(2)))
                .map_err(perr)?
                .label(v.name.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], col));
        }
        if k == 0 {
            legend(&mut chart)?;
        }
    }
    root.present().map_err(perr)
}

/// Edges between faces whose normals differ by more than this are drawn, degrees (the
/// barrel–cone junction of the cyclone is a 19° fold; facets of its snapped barrel differ
/// by a few degrees).
pub const FEATURE_ANGLE: f64 = 12.0;

/// The feature edges of the patches: edges of one triangle only (patch borders) or between
/// triangles whose normals differ by more than `angle_deg`.
pub fn feature_edges(patches: &[PatchSurface], angle_deg: f64) -> Vec<[DVec3; 2]> {
    let cos = angle_deg.to_radians().cos();
    let mut edges = Vec::new();
    for p in patches {
        let v: Vec<DVec3> = p.vertices.iter().map(|x| DVec3::from_array(*x)).collect();
        let mut map: HashMap<(u32, u32), Vec<DVec3>> = HashMap::new();
        for t in &p.triangles {
            let n = (v[t[1] as usize] - v[t[0] as usize])
                .cross(v[t[2] as usize] - v[t[0] as usize])
                .normalize_or_zero();
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                map.entry((a.min(b), a.max(b))).or_default().push(n);
            }
        }
        let mut keys: Vec<_> = map.into_iter().collect();
        keys.sort_by_key(|e| e.0);
        for ((a, b), ns) in keys {
            let feature = ns.len() != 2 || ns[0].dot(ns[1]) < cos;
            if feature {
                edges.push([v[a as usize], v[b as usize]]);
            }
        }
    }
    edges
}

/// Top (x–y) and side (x–z) view of a variant's snapshot, particles coloured by class
/// (blue fine to red coarse), the mesh's feature edges in grey.
pub fn plot_snapshot(v: &CycloneRun, edges: &[[DVec3; 2]], path: &Path) -> PlotResult {
    let (t, pts) = &v.snapshot;
    let root = svg_root(path, (1100, 760))?;
    let (title, body) = root.split_vertically(30);
    title
        .titled(
            &format!(
                "{}: t = {t:.2} s, {} particles (colour: class, blue fine → red coarse)",
                v.name,
                pts.len()
            ),
            ("sans-serif", 16),
        )
        .map_err(perr)?;
    let (top, side) = body.split_horizontally(470);
    let ng = v.classes.len();
    let class_color = |g: u32| {
        let h = 0.66 * (1.0 - g as f64 / (ng.max(2) - 1) as f64);
        HSLColor(h, 0.85, 0.45)
    };
    // Equal scales: each view's ranges widened to the aspect of its plotting area
    // (the area less the margins, labels and caption).
    let views = [
        (&top, 0, 1, "top view (x, y)", (-0.55, 0.6), (-0.55, 0.55)),
        (&side, 0, 2, "side view (x, z)", (-0.55, 0.6), (-1.05, 1.15)),
    ];
    for (area, a, b, cap, xr, yr) in views {
        let (w, h) = area.dim_in_pixel();
        let (pw, ph) = (w as f64 - 56.0, h as f64 - 60.0);
        let (sx, sy) = (xr.1 - xr.0, yr.1 - yr.0);
        let scale = (sx / pw).max(sy / ph);
        let (cx, cy) = (0.5 * (xr.0 + xr.1), 0.5 * (yr.0 + yr.1));
        let xr = (cx - 0.5 * scale * pw, cx + 0.5 * scale * pw);
        let yr = (cy - 0.5 * scale * ph, cy + 0.5 * scale * ph);
        let mut chart = ChartBuilder::on(area)
            .caption(cap, ("sans-serif", 14))
            .margin(8)
            .x_label_area_size(28)
            .y_label_area_size(40)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(perr)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("m")
            .draw()
            .map_err(perr)?;
        let grey = RGBColor(170, 170, 170);
        chart
            .draw_series(edges.iter().map(|e| {
                PathElement::new(
                    vec![(e[0][a], e[0][b]), (e[1][a], e[1][b])],
                    grey.stroke_width(1),
                )
            }))
            .map_err(perr)?;
        for g in 0..ng as u32 {
            let c = class_color(g);
            chart
                .draw_series(
                    pts.iter()
                        .filter(|p| p.1 == g)
                        .map(|p| Circle::new((p.0[a], p.0[b]), 1, c.filled())),
                )
                .map_err(perr)?
                .label(format!("{:.0} µm", v.classes[g as usize].diameter * 1e6))
                .legend(move |(x, y)| Circle::new((x + 8, y), 4, c.filled()));
        }
        if b == 2 {
            legend(&mut chart)?;
        }
    }
    root.present().map_err(perr)
}

/// Write every plot into `out`.
pub fn write_plots(
    runs: &[CycloneRun],
    openfoam: Option<&ExternalGrade>,
    theory: &Cyclone,
    patches: &[PatchSurface],
    out: &Path,
) -> PlotResult {
    plot_partition(runs, openfoam, theory, &out.join("partition.svg"))?;
    plot_residence(runs, &out.join("residence.svg"))?;
    let edges = feature_edges(patches, FEATURE_ANGLE);
    for v in runs {
        plot_snapshot(v, &edges, &out.join(format!("snapshot-{}.svg", v.name)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feature_edges_of_a_folded_square() {
        // Two triangles in z = 0 (a flat square: its diagonal is no feature) and two
        // folded by 90° (their shared edge is).
        let flat = PatchSurface {
            name: "flat".into(),
            role: "wall".into(),
            vertices: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        assert_eq!(feature_edges(std::slice::from_ref(&flat), 30.0).len(), 4);
        let folded = PatchSurface {
            vertices: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [1.0, 1.0, 1.0],
            ],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
            ..flat
        };
        // 4 border edges + the fold.
        assert_eq!(feature_edges(&[folded], 30.0).len(), 5);
    }
}
