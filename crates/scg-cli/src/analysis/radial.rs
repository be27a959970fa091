//! Radial-distance distributions per size class over a time window, a top-view snapshot
//! and drained fractions, accumulated frame by frame.
//!
//! Everything is computed from recorded [`Frame`]s, fed one at a time to [`Analysis`], so a
//! live run (frames through [`SharedAnalysis`]) and `scg replay --analyze` (frames read
//! back from the MCAP) give the same numbers to the last digit.

use std::sync::{Arc, Mutex};

use glam::DVec3;

use scg_core::Simulation;
use scg_core::frame::{Frame, FrameSink, RunMeta};
use scg_core::physics::flow::FlowField;
use scg_scene::Scene;

use super::axis::FlowAxis;
use super::fate::{FateBounds, FateCounts, Fates, WALL_ZONE};
use super::stats::{histogram, mean, percentile};

/// Time windows of the analysis.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Params {
    /// Radial distributions are cumulated over frames with from ≤ t ≤ to, s.
    pub from: f64,
    /// End of that window, s.
    pub to: f64,
    /// Time of the top-view snapshot (the nearest frame), s.
    pub snapshot: f64,
    /// The drained fraction of a class is taken over the particles first seen at or before
    /// this time (the cohort), counting those absent from the last frame as drained, s.
    pub cohort_until: f64,
    /// Radius that normalises W1 and spans the histograms (the vessel radius), m.
    pub radius: f64,
    /// Histogram bins over [0, radius].
    pub bins: usize,
    /// Where each particle's fate is decided (the steady-state partition, `fate.rs`).
    pub fates: FateBounds,
}

impl Params {
    /// The study's choice for a window [from, to]: snapshot at its middle, cohort fed up to
    /// half of `to`, 30 bins.
    pub fn for_window(from: f64, to: f64, radius: f64) -> Self {
        Params {
            from,
            to,
            snapshot: 0.5 * (from + to),
            cohort_until: 0.5 * to,
            radius,
            bins: 30,
            fates: FateBounds {
                fine_radius: 0.0,
                coarse_radius: radius - WALL_ZONE,
            },
        }
    }

    /// [`Params::for_window`] with the vessel radius of `scene`, fates decided fine at its
    /// outlet's nozzle radius.
    pub fn for_scene(scene: &Scene, from: f64, to: f64) -> Self {
        let mut p = Params::for_window(from, to, vessel_radius(scene));
        p.fates.fine_radius = scene.outlet.map_or(0.0, |o| o.geometry.nozzle_radius);
        p
    }
}

/// Tolerance on frame times (frames sit at step·dt, never exactly at decimal times).
const T_EPS: f64 = 1e-9;

/// One particle of the snapshot: position across the axis and group.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SnapPoint {
    /// Coordinates in the plane normal to the axis, m.
    pub xy: [f64; 2],
    /// Group index.
    pub group: u32,
    /// Simulated diameter, m.
    pub diameter: f64,
}

/// Accumulates the analysis frame by frame.
#[derive(Clone, Debug)]
pub struct Analysis {
    params: Params,
    axis: FlowAxis,
    basis: (DVec3, DVec3),
    groups: Vec<String>,
    diameters: Vec<f64>,
    samples: Vec<Vec<f64>>,
    /// The id of each sample of `samples`.
    sample_ids: Vec<Vec<u32>>,
    frames_in_window: usize,
    /// Group + 1 of each id first seen by `cohort_until` (0 = not in the cohort).
    cohort: Vec<u32>,
    last_ids: Vec<u32>,
    last_time: f64,
    snapshot: Option<(f64, Vec<SnapPoint>)>,
    fates: Fates,
}

/// Per-class result.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClassResult {
    /// Group name.
    pub name: String,
    /// Original diameter, m.
    pub diameter: f64,
    /// Radial distances over the window, sorted, m.
    pub radii: Vec<f64>,
    /// Mean radial distance, m (NaN without samples).
    pub mean_r: f64,
    /// Particles of the cohort.
    pub cohort: u64,
    /// Of those, gone by the last frame (drained or lost).
    pub drained: u64,
    /// drained / cohort (NaN for an empty cohort).
    pub drained_fraction: f64,
    /// Histogram over [0, radius]: fraction of the samples per bin.
    pub histogram: Vec<f64>,
    /// The same radii per particle (in id order, each particle's in time order): what
    /// intervals resample ([`super::interval`]); carried with the result between MPI
    /// ranks.
    pub clusters: Vec<super::interval::Cluster>,
    /// Fates of every particle of the class seen (fine, coarse, undecided by the last
    /// frame): the steady-state partition.
    pub fates: FateCounts,
}

/// The whole result.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Result {
    /// The parameters.
    pub params: Params,
    /// Frames in the window.
    pub frames: usize,
    /// Time of the last frame seen, s.
    pub last_time: f64,
    /// Per class (group order).
    pub classes: Vec<ClassResult>,
    /// The snapshot (time, particles), if a frame was seen.
    pub snapshot: Option<(f64, Vec<SnapPoint>)>,
}

impl Analysis {
    /// An empty analysis for a run described by `meta` with flow `flow`.
    pub fn new(meta: &RunMeta, flow: &FlowField, params: Params) -> Self {
        let axis = FlowAxis::of(flow);
        let ng = meta.groups.len();
        Analysis {
            params,
            axis,
            basis: axis.basis(),
            groups: meta.groups.iter().map(|g| g.name.clone()).collect(),
            diameters: meta.groups.iter().map(|g| g.original_diameter).collect(),
            samples: vec![Vec::new(); ng],
            sample_ids: vec![Vec::new(); ng],
            frames_in_window: 0,
            cohort: Vec::new(),
            last_ids: Vec::new(),
            last_time: f64::NEG_INFINITY,
            snapshot: None,
            fates: Fates::new(params.fates),
        }
    }

    /// Take one frame (frames must come in time order).
    pub fn observe(&mut self, f: &Frame) {
        let p = self.params;
        self.fates.observe(f, &self.axis);
        if f.time >= p.from - T_EPS && f.time <= p.to + T_EPS {
            self.frames_in_window += 1;
            for (i, g) in f.group.iter().enumerate() {
                let r = self.axis.distance(f.position[i]);
                if let Some(v) = self.samples.get_mut(*g as usize) {
                    v.push(r);
                    self.sample_ids[*g as usize].push(f.id[i]);
                }
            }
        }
        if f.time <= p.cohort_until + T_EPS {
            for (id, g) in f.id.iter().zip(&f.group) {
                let i = *id as usize;
                if self.cohort.len() <= i {
                    self.cohort.resize(i + 1, 0);
                }
                if self.cohort[i] == 0 {
                    self.cohort[i] = g + 1;
                }
            }
        }
        let better = match &self.snapshot {
            None => true,
            Some((t, _)) => (f.time - p.snapshot).abs() < (t - p.snapshot).abs(),
        };
        if better {
            let pts = (0..f.len())
                .map(|i| {
                    let r = self.axis.radial(f.position[i]);
                    SnapPoint {
                        xy: [r.dot(self.basis.0), r.dot(self.basis.1)],
                        group: f.group[i],
                        diameter: f.diameter[i],
                    }
                })
                .collect();
            self.snapshot = Some((f.time, pts));
        }
        self.last_ids.clear();
        self.last_ids.extend_from_slice(&f.id);
        self.last_time = f.time;
    }

    /// The result so far.
    pub fn result(&self) -> Result {
        let ng = self.groups.len();
        let mut cohort = vec![0u64; ng];
        let mut remaining = vec![0u64; ng];
        for g in &self.cohort {
            if *g > 0 && ((*g - 1) as usize) < ng {
                cohort[(*g - 1) as usize] += 1;
            }
        }
        for id in &self.last_ids {
            if let Some(g) = self.cohort.get(*id as usize)
                && *g > 0
                && ((*g - 1) as usize) < ng
            {
                remaining[(*g - 1) as usize] += 1;
            }
        }
        let fates = self.fates.counts(ng);
        let classes = (0..ng)
            .map(|gi| {
                let mut radii = self.samples[gi].clone();
                radii.sort_by(f64::total_cmp);
                let clusters = clusters(&self.sample_ids[gi], &self.samples[gi]);
                let mean_r = mean(&radii);
                let drained = cohort[gi] - remaining[gi];
                ClassResult {
                    name: self.groups[gi].clone(),
                    diameter: self.diameters[gi],
                    histogram: histogram(&radii, self.params.radius, self.params.bins),
                    radii,
                    clusters,
                    mean_r,
                    cohort: cohort[gi],
                    drained,
                    drained_fraction: if cohort[gi] == 0 {
                        f64::NAN
                    } else {
                        drained as f64 / cohort[gi] as f64
                    },
                    fates: fates[gi],
                }
            })
            .collect();
        Result {
            params: self.params,
            frames: self.frames_in_window,
            last_time: self.last_time,
            classes,
            snapshot: self.snapshot.clone(),
        }
    }
}

/// The samples `r` grouped by their particle `ids` (ids in increasing order).
pub(super) fn clusters(ids: &[u32], r: &[f64]) -> Vec<super::interval::Cluster> {
    let mut order: Vec<usize> = (0..ids.len()).collect();
    order.sort_by_key(|&i| ids[i]); // stable: each particle's samples stay in time order
    let mut out: Vec<super::interval::Cluster> = Vec::new();
    let mut last = None;
    for i in order {
        if last != Some(ids[i]) {
            out.push(Vec::new());
            last = Some(ids[i]);
        }
        if let Some(c) = out.last_mut() {
            c.push(r[i]);
        }
    }
    out
}

/// The radial-distance table of one run as CSV: per class, the sample count, mean,
/// quantiles, cohort and drained counts, fates, the particles behind the samples and the
/// 95 % intervals of the mean and quantiles (bootstrap over particles) and of the drained
/// share (Wilson), then the histogram (shortest round-trip floats,
/// so equal results give equal text).
pub fn radial_csv(r: &Result) -> String {
    let bins = r.params.bins;
    let mut s = String::from(
        "class,diameter_m,samples,mean_r_m,p10_m,p50_m,p90_m,cohort,drained,drained_fraction,\
         fate_fine,fate_coarse,fate_undecided,fate_fine_fraction,particles,mean_r_lo_m,\
         mean_r_hi_m,p10_lo_m,p10_hi_m,p50_lo_m,p50_hi_m,p90_lo_m,p90_hi_m,drained_lo,\
         drained_hi",
    );
    for b in 0..bins {
        s.push_str(&format!(",bin{b}"));
    }
    s.push('\n');
    for c in &r.classes {
        let q = |p: f64| percentile(&c.radii, p);
        s.push_str(&format!(
            "{},{:e},{},{:e},{:e},{:e},{:e},{},{},{:e},{},{},{},{:e}",
            c.name,
            c.diameter,
            c.radii.len(),
            c.mean_r,
            q(0.1),
            q(0.5),
            q(0.9),
            c.cohort,
            c.drained,
            c.drained_fraction,
            c.fates.fine,
            c.fates.coarse,
            c.fates.undecided,
            c.fates.fine_fraction()
        ));
        // 95 % intervals: mean and quantiles resampling particles, Wilson on the share
        let ((mlo, mhi), qi) = super::interval::mean_and_quantiles95(
            &c.clusters,
            &[0.1, 0.5, 0.9],
            super::interval::RESAMPLES,
            0x5c6_0a11,
        );
        let (dlo, dhi) = super::interval::wilson95(c.drained, c.cohort);
        s.push_str(&format!(",{},{mlo:e},{mhi:e}", c.clusters.len()));
        for (lo, hi) in qi {
            s.push_str(&format!(",{lo:e},{hi:e}"));
        }
        s.push_str(&format!(",{dlo:e},{dhi:e}"));
        for h in &c.histogram {
            s.push_str(&format!(",{h:e}"));
        }
        s.push('\n');
    }
    s
}

/// Vessel radius of a scene: its inner cylinder wall, else the outlet's domain, else the
/// largest radial sample.
pub fn vessel_radius(scene: &Scene) -> f64 {
    for w in &scene.walls {
        if let scg_core::physics::wall_shape::WallShape::CylinderInside { radius, .. } = w.shape {
            return radius;
        }
    }
    scene.outlet.map_or(1.0, |o| o.geometry.domain_radius)
}

/// Analyse a whole recording.
pub fn analyze_recording(
    rec: &scg_record::Recording,
    from: f64,
    to: f64,
) -> std::result::Result<Result, String> {
    let scene = super::recording_scene(rec)?;
    let mut a = Analysis::new(&rec.meta, &scene.flow, Params::for_scene(&scene, from, to));
    for f in &rec.frames {
        a.observe(f);
    }
    Ok(a.result())
}

/// An [`Analysis`] fed live by a simulation: attached as a recorder, every recorded frame
/// goes straight in.
#[derive(Clone, Debug)]
pub struct SharedAnalysis(Arc<Mutex<Analysis>>);

impl SharedAnalysis {
    /// Attach `analysis` to `sim` (after the recorders already there).
    pub fn attach(sim: &mut Simulation, analysis: Analysis) -> Self {
        let shared = SharedAnalysis(Arc::new(Mutex::new(analysis)));
        sim.add_recorder(Box::new(shared.clone()));
        shared
    }

    /// The result so far.
    pub fn result(&self) -> std::result::Result<Result, String> {
        Ok(self.0.lock().map_err(|e| e.to_string())?.result())
    }
}

impl FrameSink for SharedAnalysis {
    fn write_frame(&mut self, frame: &Frame) -> std::result::Result<(), String> {
        self.0.lock().map_err(|e| e.to_string())?.observe(frame);
        Ok(())
    }
    fn finish(&mut self) -> std::result::Result<(), String> {
        Ok(())
    }
}
