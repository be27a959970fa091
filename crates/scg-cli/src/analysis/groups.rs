//! Per-group statistics of any recording (`scg replay --analyze`): the radial distance from
//! the flow axis over a time window, with the counts the recording's stats hold.

use scg_core::frame::Frame;
use scg_core::stats::Stat;
use scg_record::Recording;

use super::axis::FlowAxis;
use super::stats::{histogram_counts, mean, percentile};

/// Histogram bins of the CSV, over [0, largest distance].
const BINS: usize = 20;

/// Statistics per group over the frames in [from, to]: text report and CSV.
pub fn group_stats(rec: &Recording, from: f64, to: f64) -> Result<(String, String), String> {
    let scene = super::recording_scene(rec)?;
    let axis = FlowAxis::of(&scene.flow);
    let frames: Vec<&Frame> = rec
        .frames
        .iter()
        .filter(|f| f.time >= from && f.time <= to)
        .collect();
    if frames.is_empty() {
        return Err(format!("no frame between {from} s and {to} s"));
    }
    let ng = rec.meta.groups.len();
    let mut r: Vec<Vec<f64>> = vec![Vec::new(); ng];
    // the id of each sample, for the intervals (resampled by particle)
    let mut ids: Vec<Vec<u32>> = vec![Vec::new(); ng];
    for f in &frames {
        for (i, g) in f.group.iter().enumerate() {
            if let Some(v) = r.get_mut(*g as usize) {
                v.push(axis.distance(f.position[i]));
                ids[*g as usize].push(f.id[i]);
            }
        }
    }
    let last = frames[frames.len() - 1];
    let stat = |s: Stat| s.find(&last.stats).unwrap_or(0.0);
    let rmax = r.iter().flatten().copied().fold(0.0, f64::max).max(1e-300);
    let mut text = format!(
        "window {:.6}–{:.6} s, {} frames; radial distance from the flow axis, m\n{:<16} {:>8} {:>8} {:>12} {:>12} {:>12} {:>12}\n",
        frames[0].time,
        last.time,
        frames.len(),
        "group",
        "count",
        "drained",
        "mean",
        "p10",
        "p50",
        "p90"
    );
    let mut csv = String::from(
        "group,count,drained,samples,mean_r_m,p10_m,p50_m,p90_m,particles,mean_r_lo_m,\
         mean_r_hi_m,p10_lo_m,p10_hi_m,p50_lo_m,p50_hi_m,p90_lo_m,p90_hi_m",
    );
    for b in 0..BINS {
        csv.push_str(&format!(",bin{b}"));
    }
    csv.push('\n');
    for (gi, g) in rec.meta.groups.iter().enumerate() {
        let clusters = super::radial::clusters(&ids[gi], &r[gi]);
        let v = &mut r[gi];
        v.sort_by(f64::total_cmp);
        let m = mean(v);
        let (p10, p50, p90) = (percentile(v, 0.1), percentile(v, 0.5), percentile(v, 0.9));
        let (count, drained) = (stat(Stat::Count(&g.name)), stat(Stat::Drained(&g.name)));
        text.push_str(&format!(
            "{:<16} {:>8} {:>8} {:>12.5e} {:>12.5e} {:>12.5e} {:>12.5e}\n",
            g.name, count, drained, m, p10, p50, p90
        ));
        csv.push_str(&format!(
            "{},{},{},{},{:e},{:e},{:e},{:e}",
            g.name,
            count,
            drained,
            v.len(),
            m,
            p10,
            p50,
            p90
        ));
        let ((mlo, mhi), qi) = super::interval::mean_and_quantiles95(
            &clusters,
            &[0.1, 0.5, 0.9],
            super::interval::RESAMPLES,
            0x5c6_0a11,
        );
        csv.push_str(&format!(",{},{mlo:e},{mhi:e}", clusters.len()));
        for (lo, hi) in qi {
            csv.push_str(&format!(",{lo:e},{hi:e}"));
        }
        for h in histogram_counts(v, rmax, BINS) {
            csv.push_str(&format!(",{h}"));
        }
        csv.push('\n');
    }
    text.push_str(&format!(
        "histogram: {BINS} bins over 0–{rmax:e} m (in the CSV)\n"
    ));
    Ok((text, csv))
}
