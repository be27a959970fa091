//! Analysis shared by `scg study`, `scg cost` and `scg replay` (paper Section 5, Figs
//! 8–10): radial-distance distributions per size class over a time window, a top-view
//! snapshot, drained fractions, the partition (Tromp) curve with its cut size d50, and the
//! 1-Wasserstein distance between distributions; per-group statistics of any recording.
//!
//! * `stats.rs`: mean, percentiles, histograms, W1;
//! * `axis.rs`: the flow axis radial distances are measured from;
//! * `radial.rs`: the per-class analysis fed frame by frame ([`Analysis`]), its CSV;
//! * `fate.rs`: each particle's fate (fine at the nozzle, coarse at the wall, undecided);
//! * `classes.rs`: partition curves (finite-time drained, steady-state fates), their d50,
//!   W1 of every class to a reference;
//! * `interval.rs`: Wilson, bootstrap (by particle) and permutation intervals;
//! * `groups.rs`: per-group statistics of a recording (`scg replay --analyze`).

mod axis;
mod classes;
mod fate;
mod groups;
pub mod interval;
mod radial;
mod stats;

pub use axis::FlowAxis;
pub use classes::{
    cut_size, cut_size95, d50, partition, partition_counts, steady_cut_size, steady_partition,
    undecided, w1_intervals, w1_to,
};
pub use fate::{Fate, FateBounds, FateCounts, Fates, WALL_ZONE};
pub use groups::group_stats;
pub use radial::{
    Analysis, ClassResult, Params, Result, SharedAnalysis, SnapPoint, analyze_recording,
    radial_csv, vessel_radius,
};
pub use stats::{histogram, histogram_counts, mean, percentile, wasserstein1};

use scg_record::Recording;
use scg_scene::Scene;

/// The scene embedded in a recording.
///
/// With `dt = "auto"` the step is chosen by a rule that may change between versions: the
/// scene then takes the recording's own dt, so it re-runs as recorded.
pub fn recording_scene(rec: &Recording) -> std::result::Result<Scene, String> {
    // Relative paths resolve from the folder the scene came from (stored since it was;
    // older recordings: the working folder).
    let base = std::path::Path::new(&rec.meta.scene_dir);
    let mut scene = scg_scene::parse_in(
        &rec.meta.scene_toml,
        "<recording>",
        base,
        &rec.meta.case,
        &[],
    )
    .map_err(|e| format!("the recording's scene: {e}"))?;
    if rec.meta.dt > 0.0 {
        scene.dt = rec.meta.dt;
    }
    Ok(scene)
}
