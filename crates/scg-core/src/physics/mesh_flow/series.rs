//! An unsteady field on a fixed mesh: a series of snapshots (an OpenFOAM case's time
//! directories), linear in time between the two around t.
//!
//! [`SeriesClock`] maps simulation time onto the snapshots (pure); [`Blend`] is the carrier
//! of one step, two snapshots' [`MeshFlow`]s and the weight of the later one. The stage
//! that keeps two snapshots in memory and reads the next one ahead is
//! [`crate::stages::flow_series`].

use std::fmt;
use std::sync::Arc;

use glam::{DMat3, DVec3};

use super::MeshFlow;
use crate::physics::carrier::{Carrier, Place};
use crate::physics::dispersion::{CellTurbulence, Local};

/// The snapshot times of a series and how simulation time runs through them.
///
/// Simulation time 0 is the first snapshot. Between snapshots k and k+1 the field is
/// `(1 − w)·U_k + w·U_{k+1}`, w = (t − t_k)/(t_{k+1} − t_k). Without `cycle` the field
/// holds the last snapshot after the window's end (validation refuses a run that goes
/// past it). With `cycle` the window repeats with period `span + seam`: after the last
/// snapshot the field runs linearly back to the first over `seam`, the mean spacing
/// span/(n − 1), so it is continuous in time; the change across the seam is what
/// `scg check` states.
#[derive(Clone, Debug, PartialEq)]
pub struct SeriesClock {
    /// Snapshot times from the first, s: 0 = t_0 < t_1 < … .
    times: Vec<f64>,
    cycle: bool,
}

/// Two snapshots and the weight of the second, `(1 − w)·U_a + w·U_b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// The earlier snapshot.
    pub a: usize,
    /// The later snapshot (with `cycle`, the first after the last).
    pub b: usize,
    /// Weight of `b`, in [0, 1].
    pub w: f64,
}

impl SeriesClock {
    /// The clock of snapshots at `times` (s, any origin: the first becomes t = 0). At least
    /// two, finite and strictly increasing.
    pub fn new(times: &[f64], cycle: bool) -> Result<Self, String> {
        if times.len() < 2 {
            return Err(format!(
                "{} snapshot(s): a series needs at least two",
                times.len()
            ));
        }
        if let Some(t) = times.iter().find(|t| !t.is_finite()) {
            return Err(format!("snapshot time {t} is not finite"));
        }
        if let Some(w) = times.windows(2).find(|w| w[1] <= w[0]) {
            return Err(format!(
                "snapshot times must increase ({} then {})",
                w[0], w[1]
            ));
        }
        Ok(SeriesClock {
            times: times.iter().map(|t| t - times[0]).collect(),
            cycle,
        })
    }

    /// Number of snapshots.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Always false (a series has at least two snapshots).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Whether the window repeats.
    pub fn cycles(&self) -> bool {
        self.cycle
    }

    /// Snapshot times from the first, s.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// Time from the first snapshot to the last, s.
    pub fn span(&self) -> f64 {
        self.times[self.times.len() - 1]
    }

    /// The blend from the last snapshot back to the first when cycling: the mean
    /// spacing, s.
    pub fn seam(&self) -> f64 {
        self.span() / (self.times.len() - 1) as f64
    }

    /// The period of a cycling series (span + seam), s; `None` without `cycle`.
    pub fn period(&self) -> Option<f64> {
        self.cycle.then(|| self.span() + self.seam())
    }

    /// The smallest and largest spacing between snapshots, s.
    pub fn spacing(&self) -> (f64, f64) {
        self.times
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold((f64::INFINITY, 0.0_f64), |(a, b), d| (a.min(d), b.max(d)))
    }

    /// The snapshots around simulation time `t` (s) and the weight of the later one.
    pub fn at(&self, t: f64) -> Interval {
        let n = self.times.len();
        let tau = match self.period() {
            Some(p) => {
                let tau = t - (t / p).floor() * p;
                // rounding in the division may leave tau just outside [0, p)
                if tau < 0.0 {
                    tau + p
                } else if tau >= p {
                    tau - p
                } else {
                    tau
                }
            }
            None => t.clamp(0.0, self.span()),
        };
        if tau >= self.span() {
            return match self.cycle {
                true => Interval {
                    a: n - 1,
                    b: 0,
                    w: ((tau - self.span()) / self.seam()).min(1.0),
                },
                false => Interval {
                    a: n - 2,
                    b: n - 1,
                    w: 1.0,
                },
            };
        }
        // the last snapshot at or before tau
        let a = self.times.partition_point(|&s| s <= tau).max(1) - 1;
        let (ta, tb) = (self.times[a], self.times[a + 1]);
        Interval {
            a,
            b: a + 1,
            w: (tau - ta) / (tb - ta),
        }
    }

    /// The snapshot to read after the pair `iv` (the one the clock reaches next), if any.
    pub fn after(&self, iv: Interval) -> Option<usize> {
        let n = self.times.len();
        match (self.cycle, iv.b + 1 < n) {
            (_, true) => Some(iv.b + 1),
            (true, false) => Some((iv.b + 1) % n),
            (false, false) => None,
        }
    }
}

/// One snapshot of a series: its flow and, with turbulent dispersion, its k and ε per
/// cell.
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// The flow on the series' mesh.
    pub flow: Arc<MeshFlow>,
    /// k, ε (and ∇σ) per cell, when the scene disperses by the CFD's fields.
    pub turbulence: Option<Arc<CellTurbulence>>,
}

/// Reads snapshot k of a series (an error names the file and what is wrong with it).
pub type SnapshotLoader = dyn Fn(usize) -> Result<Snapshot, String> + Send + Sync;

/// A series as a scene gives it: the clock, the reader of its snapshots and the second
/// snapshot, read when the scene was (the first is the scene's flow).
#[derive(Clone)]
pub struct FlowSeriesSpec {
    /// The clock.
    pub clock: SeriesClock,
    /// Reads snapshot k.
    pub load: Arc<SnapshotLoader>,
    /// Snapshot 1.
    pub second: Snapshot,
    /// The first snapshot's turbulence (its flow is the scene's).
    pub first_turbulence: Option<Arc<CellTurbulence>>,
}

impl fmt::Debug for FlowSeriesSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FlowSeriesSpec")
            .field("clock", &self.clock)
            .finish_non_exhaustive()
    }
}

/// The carrier of one step of an unsteady series: the flows of two snapshots on the same
/// mesh, `(1 − w)·U_a + w·U_b`. The particle is located in `a` (the same cells and
/// tetrahedra as in `b`: one mesh), and `b` is read at that place.
#[derive(Clone, Copy, Debug)]
pub struct Blend<'a> {
    /// The earlier snapshot.
    pub a: &'a MeshFlow,
    /// The later snapshot.
    pub b: &'a MeshFlow,
    /// Weight of `b`.
    pub w: f64,
}

impl Carrier for Blend<'_> {
    #[inline(always)]
    fn at(&self, place: Place, x: DVec3) -> (DVec3, Place) {
        let (ua, p) = self.a.velocity_at(place, x);
        let (ub, _) = self.b.velocity_at(p, x);
        (blend(ua, ub, self.w), p)
    }

    fn gradient(&self, cell: u32, _x: DVec3) -> DMat3 {
        let (ga, gb) = (self.a.cell_gradient(cell), self.b.cell_gradient(cell));
        ga + (gb - ga) * self.w
    }
}

/// The turbulence of two snapshots blended like their velocities: k, ε and ∇σ each
/// `(1 − w)·a + w·b`.
#[inline]
pub fn blend_turbulence(a: Local, b: Local, w: f64) -> Local {
    let s = |x: f64, y: f64| if w >= 1.0 { y } else { x + (y - x) * w };
    Local {
        k: s(a.k, b.k),
        epsilon: s(a.epsilon, b.epsilon),
        grad_sigma: blend(a.grad_sigma, b.grad_sigma, w),
    }
}

/// `(1 − w)·a + w·b`, written so that w = 0 gives a and w = 1 gives b exactly.
#[inline(always)]
pub fn blend(a: DVec3, b: DVec3, w: f64) -> DVec3 {
    if w >= 1.0 { b } else { a + (b - a) * w }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clock_finds_the_snapshots_around_t() {
        let c = SeriesClock::new(&[2.0, 2.25, 2.75, 3.0], false).unwrap();
        assert_eq!(c.times(), &[0.0, 0.25, 0.75, 1.0]);
        assert_eq!(c.at(0.0), Interval { a: 0, b: 1, w: 0.0 });
        assert_eq!(c.at(0.125), Interval { a: 0, b: 1, w: 0.5 });
        assert_eq!(c.at(0.25), Interval { a: 1, b: 2, w: 0.0 });
        assert_eq!(c.at(0.5), Interval { a: 1, b: 2, w: 0.5 });
        assert_eq!(c.at(0.875), Interval { a: 2, b: 3, w: 0.5 });
        // past the end the last snapshot holds; before the start the first
        assert_eq!(c.at(1.0), Interval { a: 2, b: 3, w: 1.0 });
        assert_eq!(c.at(7.0), Interval { a: 2, b: 3, w: 1.0 });
        assert_eq!(c.at(-1.0), Interval { a: 0, b: 1, w: 0.0 });
        assert_eq!(c.spacing(), (0.25, 0.5));
        assert_eq!(c.period(), None);
        assert_eq!(c.after(c.at(0.5)), Some(3));
        assert_eq!(c.after(c.at(0.9)), None);
    }

    #[test]
    fn a_cycling_clock_runs_back_to_the_first_snapshot_over_the_seam() {
        let c = SeriesClock::new(&[0.0, 0.25, 0.5], true).unwrap();
        assert_eq!(c.seam(), 0.25);
        assert_eq!(c.period(), Some(0.75));
        assert_eq!(c.at(0.625), Interval { a: 2, b: 0, w: 0.5 });
        assert_eq!(c.after(c.at(0.625)), Some(1));
        assert_eq!(c.after(c.at(0.375)), Some(0));
        // one period later: the same interval and weight, bit for bit (dyadic times)
        for t in [0.0, 0.125, 0.3125, 0.5, 0.6875] {
            assert_eq!(c.at(t), c.at(t + 0.75), "t = {t}");
            assert_eq!(c.at(t), c.at(t + 3.0 * 0.75), "t = {t}");
        }
        assert_eq!(c.at(0.75), Interval { a: 0, b: 1, w: 0.0 });
    }

    #[test]
    fn a_bad_series_is_refused() {
        assert!(SeriesClock::new(&[1.0], false).unwrap_err().contains("two"));
        assert!(
            SeriesClock::new(&[0.0, 0.5, 0.5], false)
                .unwrap_err()
                .contains("increase")
        );
        assert!(SeriesClock::new(&[0.0, f64::NAN], true).is_err());
    }

    #[test]
    fn blend_is_exact_at_both_ends() {
        let (a, b) = (DVec3::new(0.1, 0.2, 0.3), DVec3::new(-0.7, 0.11, 3.0));
        assert_eq!(blend(a, b, 0.0), a);
        assert_eq!(blend(a, b, 1.0), b);
        assert!((blend(a, b, 0.5) - (a + b) * 0.5).length() < 1e-15);
        let (ta, tb) = (
            Local {
                k: 0.5,
                epsilon: 2.0,
                grad_sigma: a,
            },
            Local {
                k: 1.5,
                epsilon: 1.0,
                grad_sigma: b,
            },
        );
        assert_eq!(blend_turbulence(ta, tb, 0.0), ta);
        assert_eq!(blend_turbulence(ta, tb, 1.0), tb);
        let h = blend_turbulence(ta, tb, 0.25);
        assert_eq!((h.k, h.epsilon), (0.75, 1.75));
    }
}
