//! Classifier analysis (paper Section 5, Figs 8–10): radial-distance distributions per
//! size class over a time window, a top-view snapshot, drained fractions, the partition
//! (Tromp) curve with its cut size d50, and the 1-Wasserstein distance between
//! distributions.
//!
//! Everything is computed from recorded [`Frame`]s, fed one at a time to [`Analysis`], so a
//! live run (frames from a recorder) and `scg replay --analyze` (frames read back from the
//! MCAP) give the same numbers to the last digit.

use glam::DVec3;

use scg_core::frame::{Frame, RunMeta};
use scg_core::physics::flow::FlowField;

/// Time windows of the analysis.
#[derive(Clone, Copy, Debug, PartialEq)]
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
        }
    }
}

/// Tolerance on frame times (frames sit at step·dt, never exactly at decimal times).
const T_EPS: f64 = 1e-9;

/// One particle of the snapshot: position across the axis and group.
#[derive(Clone, Copy, Debug, PartialEq)]
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
    center: DVec3,
    axis: DVec3,
    basis: (DVec3, DVec3),
    groups: Vec<String>,
    diameters: Vec<f64>,
    samples: Vec<Vec<f64>>,
    frames_in_window: usize,
    /// Group + 1 of each id first seen by `cohort_until` (0 = not in the cohort).
    cohort: Vec<u32>,
    last_ids: Vec<u32>,
    last_time: f64,
    snapshot: Option<(f64, Vec<SnapPoint>)>,
}

/// Per-class result.
#[derive(Clone, Debug, PartialEq)]
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
}

/// The whole result.
#[derive(Clone, Debug, PartialEq)]
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
        let (center, axis) = match flow {
            FlowField::Vortex(v) | FlowField::Classifier { vortex: v, .. } => (v.center, v.axis),
            _ => (DVec3::ZERO, DVec3::Z),
        };
        let ng = meta.groups.len();
        Analysis {
            params,
            center,
            axis,
            basis: axis.any_orthonormal_pair(),
            groups: meta.groups.iter().map(|g| g.name.clone()).collect(),
            diameters: meta.groups.iter().map(|g| g.original_diameter).collect(),
            samples: vec![Vec::new(); ng],
            frames_in_window: 0,
            cohort: Vec::new(),
            last_ids: Vec::new(),
            last_time: f64::NEG_INFINITY,
            snapshot: None,
        }
    }

    fn radial(&self, p: [f64; 3]) -> DVec3 {
        let rel = DVec3::from_array(p) - self.center;
        rel - rel.dot(self.axis) * self.axis
    }

    /// Take one frame (frames must come in time order).
    pub fn observe(&mut self, f: &Frame) {
        let p = self.params;
        if f.time >= p.from - T_EPS && f.time <= p.to + T_EPS {
            self.frames_in_window += 1;
            for (i, g) in f.group.iter().enumerate() {
                let r = self.radial(f.position[i]).length();
                if let Some(v) = self.samples.get_mut(*g as usize) {
                    v.push(r);
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
                    let r = self.radial(f.position[i]);
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
        let classes = (0..ng)
            .map(|gi| {
                let mut radii = self.samples[gi].clone();
                radii.sort_by(f64::total_cmp);
                let mean_r = if radii.is_empty() {
                    f64::NAN
                } else {
                    radii.iter().sum::<f64>() / radii.len() as f64
                };
                let drained = cohort[gi] - remaining[gi];
                ClassResult {
                    name: self.groups[gi].clone(),
                    diameter: self.diameters[gi],
                    histogram: histogram(&radii, self.params.radius, self.params.bins),
                    radii,
                    mean_r,
                    cohort: cohort[gi],
                    drained,
                    drained_fraction: if cohort[gi] == 0 {
                        f64::NAN
                    } else {
                        drained as f64 / cohort[gi] as f64
                    },
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

/// Fraction of `sorted` samples per bin of [0, radius] (the last bin takes everything
/// beyond); empty samples give zeros.
pub fn histogram(sorted: &[f64], radius: f64, bins: usize) -> Vec<f64> {
    let mut h = vec![0.0; bins];
    if sorted.is_empty() || bins == 0 {
        return h;
    }
    for x in sorted {
        let b = ((x / radius * bins as f64).floor().max(0.0) as usize).min(bins - 1);
        h[b] += 1.0;
    }
    let n = sorted.len() as f64;
    h.iter_mut().for_each(|v| *v /= n);
    h
}

/// 1-Wasserstein distance between the empirical distributions of two sorted samples:
/// ∫ |F_a(x) − F_b(x)| dx. NaN when either is empty.
pub fn wasserstein1(a: &[f64], b: &[f64]) -> f64 {
    if a.is_empty() || b.is_empty() {
        return f64::NAN;
    }
    let (na, nb) = (a.len() as f64, b.len() as f64);
    let (mut i, mut j) = (0usize, 0usize);
    let mut x = a[0].min(b[0]);
    let mut w = 0.0;
    while i < a.len() || j < b.len() {
        let next = match (a.get(i), b.get(j)) {
            (Some(&p), Some(&q)) => p.min(q),
            (Some(&p), None) => p,
            (None, Some(&q)) => q,
            (None, None) => break,
        };
        w += (i as f64 / na - j as f64 / nb).abs() * (next - x);
        x = next;
        while i < a.len() && a[i] <= x {
            i += 1;
        }
        while j < b.len() && b[j] <= x {
            j += 1;
        }
    }
    w
}

/// Cut size from a partition curve: `points` are (diameter, fraction drained to the fines)
/// in increasing diameter; d50 is where the curve first falls through 0.5, interpolated
/// linearly in diameter. `None` when it never crosses 0.5.
pub fn d50(points: &[(f64, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.1.is_finite()).collect();
    for w in pts.windows(2) {
        let ((d0, f0), (d1, f1)) = (w[0], w[1]);
        if f0 >= 0.5 && f1 < 0.5 {
            return Some(d0 + (f0 - 0.5) / (f0 - f1) * (d1 - d0));
        }
    }
    None
}

/// The radial-distance table of one run as CSV: per class, the sample count, mean,
/// quantiles, cohort and drained counts, then the histogram (shortest round-trip floats,
/// so equal results give equal text).
pub fn radial_csv(r: &Result) -> String {
    let bins = r.params.bins;
    let mut s = String::from(
        "class,diameter_m,samples,mean_r_m,p10_m,p50_m,p90_m,cohort,drained,drained_fraction",
    );
    for b in 0..bins {
        s.push_str(&format!(",bin{b}"));
    }
    s.push('\n');
    for c in &r.classes {
        let q = |p: f64| {
            if c.radii.is_empty() {
                f64::NAN
            } else {
                c.radii[((c.radii.len() - 1) as f64 * p).round() as usize]
            }
        };
        s.push_str(&format!(
            "{},{:e},{},{:e},{:e},{:e},{:e},{},{},{:e}",
            c.name,
            c.diameter,
            c.radii.len(),
            c.mean_r,
            q(0.1),
            q(0.5),
            q(0.9),
            c.cohort,
            c.drained,
            c.drained_fraction
        ));
        for h in &c.histogram {
            s.push_str(&format!(",{h:e}"));
        }
        s.push('\n');
    }
    s
}

/// Vessel radius of a scene: its inner cylinder wall, else the outlet's domain, else the
/// largest radial sample.
pub fn vessel_radius(scene: &scg_scene::Scene) -> f64 {
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
    let scene = scg_scene::parse(&rec.meta.scene_toml, "<recording>", &rec.meta.case, &[])
        .map_err(|e| format!("the recording's scene: {e}"))?;
    let mut a = Analysis::new(
        &rec.meta,
        &scene.flow,
        Params::for_window(from, to, vessel_radius(&scene)),
    );
    for f in &rec.frames {
        a.observe(f);
    }
    Ok(a.result())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn w1_of_shifted_samples_is_the_shift() {
        let a = [0.0, 1.0, 2.0, 3.0];
        let b: Vec<f64> = a.iter().map(|x| x + 0.25).collect();
        assert!((wasserstein1(&a, &b) - 0.25).abs() < 1e-15);
        assert_eq!(wasserstein1(&a, &a), 0.0);
        // Point masses: |x − y|.
        assert!((wasserstein1(&[1.0], &[4.0]) - 3.0).abs() < 1e-15);
        // Different sample sizes: {0, 1} vs {0, 0, 1, 1} are the same distribution.
        assert!(wasserstein1(&[0.0, 1.0], &[0.0, 0.0, 1.0, 1.0]).abs() < 1e-15);
        // {0} vs {0, 1}: half the mass moves by 1.
        assert!((wasserstein1(&[0.0], &[0.0, 1.0]) - 0.5).abs() < 1e-15);
        assert!(wasserstein1(&[], &[1.0]).is_nan());
    }

    #[test]
    fn w1_is_symmetric() {
        let a = [0.1, 0.4, 0.4, 0.9];
        let b = [0.0, 0.2, 0.7];
        assert!((wasserstein1(&a, &b) - wasserstein1(&b, &a)).abs() < 1e-15);
    }

    #[test]
    fn d50_interpolates_the_crossing() {
        let pts = [(100e-6, 0.9), (160e-6, 0.7), (220e-6, 0.1), (280e-6, 0.0)];
        let d = d50(&pts).unwrap();
        // 0.7 → 0.1 over 60 µm: 0.5 is 1/3 of the way.
        assert!((d - 180e-6).abs() < 1e-12, "{d}");
        assert_eq!(d50(&[(1.0, 0.2), (2.0, 0.1)]), None);
        assert_eq!(d50(&[(1.0, 0.9), (2.0, 0.6)]), None);
        assert_eq!(d50(&[(1.0, 0.5), (2.0, 0.0)]), Some(1.0));
        // NaN classes (empty cohorts) are skipped.
        assert_eq!(d50(&[(1.0, 1.0), (2.0, f64::NAN), (3.0, 0.0)]), Some(2.0));
    }

    #[test]
    fn histogram_sums_to_one() {
        let h = histogram(&[0.0, 0.1, 0.5, 0.99, 2.0], 1.0, 10);
        assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert_eq!(h[9], 0.4);
    }
}
