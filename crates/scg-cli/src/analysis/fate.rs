//! Each particle's fate in a classifier, decided from recorded frames instead of waiting
//! for it to drain: the steady-state cut size.
//!
//! In the classifier flow (forced vortex plus an inflow k·ω·r toward the axis) the radius of
//! a particle grows or decays exponentially, at a rate whose sign is that of τ·ω − k; near
//! the cut the rate is small (≈ 52·Δd/d per second), so the fraction drained after a finite
//! time says more about the time than about the cut. A particle's fate is decided once its
//! radius has diverged far enough to leave no doubt where the steady state sends it:
//!
//! * **fine** once it is seen at or inside the outlet nozzle radius (where the axial flow
//!   takes it up to the drain), or when it vanishes from the frames (the outlet removed it)
//!   before anything else decided it;
//! * **coarse** once it is seen in the wall zone, at or beyond `coarse_radius` (the vessel
//!   radius less [`WALL_ZONE`]);
//! * **undecided** otherwise, until the end of the recording. Undecided particles are
//!   counted and left out of the steady-state partition.
//!
//! The first decision sticks (a coarse particle bouncing off the wall, or a fine one
//! already in the nozzle, stays what it is). The decision uses positions only, so the
//! same frames give the same fates live and replayed.

use scg_core::frame::Frame;

use super::axis::FlowAxis;

/// Width of the wall zone, m: a particle whose distance from the axis reaches the vessel
/// radius less this is coarse. 1 mm in the 30 mm vessel of `cases/classifier*.toml` puts
/// the boundary at 29 mm, outside the feed annulus (12–28 mm), so no particle is decided
/// where it enters, and a particle beyond it has diverged by e^{ln(29/28)} or more from its
/// outermost possible feed radius while the inflow at k·ω·r = 76 m/s pulls it in.
pub const WALL_ZONE: f64 = 1.0e-3;

/// Where fates are decided.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FateBounds {
    /// Seen at or inside this distance from the axis: fine (the nozzle radius), m; 0
    /// without an outlet (then only vanishing decides fine).
    pub fine_radius: f64,
    /// Seen at or beyond this distance from the axis: coarse (the wall zone), m.
    pub coarse_radius: f64,
}

/// A particle's fate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fate {
    /// Not decided yet.
    Undecided,
    /// Goes with the fines (drained, or reached the nozzle radius).
    Fine,
    /// Goes with the coarse product (reached the wall zone).
    Coarse,
}

/// Fate counts of one class.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct FateCounts {
    /// Particles decided fine.
    pub fine: u64,
    /// Particles decided coarse.
    pub coarse: u64,
    /// Particles seen but not decided by the last frame.
    pub undecided: u64,
}

impl FateCounts {
    /// fine / (fine + coarse): the steady-state partition of the class over its decided
    /// particles (NaN when none is decided).
    pub fn fine_fraction(&self) -> f64 {
        let n = self.fine + self.coarse;
        if n == 0 {
            f64::NAN
        } else {
            self.fine as f64 / n as f64
        }
    }
}

/// Per-particle fates, fed frame by frame (frames in time order).
#[derive(Clone, Debug, PartialEq)]
pub struct Fates {
    bounds: FateBounds,
    /// Per id: group + 1 (0 = never seen).
    group: Vec<u32>,
    /// Per id: the fate.
    fate: Vec<Fate>,
    /// Per id: the index of the last frame it was seen in.
    last_frame: Vec<u64>,
    /// Ids of the previous frame.
    prev_ids: Vec<u32>,
    frames: u64,
}

impl Fates {
    /// No particle seen yet.
    pub fn new(bounds: FateBounds) -> Self {
        Fates {
            bounds,
            group: Vec::new(),
            fate: Vec::new(),
            last_frame: Vec::new(),
            prev_ids: Vec::new(),
            frames: 0,
        }
    }

    /// The bounds.
    pub fn bounds(&self) -> FateBounds {
        self.bounds
    }

    /// Take one frame; `axis` measures the distances.
    pub fn observe(&mut self, f: &Frame, axis: &FlowAxis) {
        self.frames += 1;
        let now = self.frames;
        for (i, (id, g)) in f.id.iter().zip(&f.group).enumerate() {
            let k = *id as usize;
            if self.group.len() <= k {
                self.group.resize(k + 1, 0);
                self.fate.resize(k + 1, Fate::Undecided);
                self.last_frame.resize(k + 1, 0);
            }
            self.group[k] = g + 1;
            self.last_frame[k] = now;
            if self.fate[k] == Fate::Undecided {
                let r = axis.distance(f.position[i]);
                if r <= self.bounds.fine_radius {
                    self.fate[k] = Fate::Fine;
                } else if r >= self.bounds.coarse_radius {
                    self.fate[k] = Fate::Coarse;
                }
            }
        }
        // Seen in the previous frame, gone now: the outlet took it.
        for id in &self.prev_ids {
            let k = *id as usize;
            if self.last_frame[k] != now && self.fate[k] == Fate::Undecided {
                self.fate[k] = Fate::Fine;
            }
        }
        self.prev_ids.clear();
        self.prev_ids.extend_from_slice(&f.id);
    }

    /// The fate of particle `id` (undecided if never seen).
    pub fn fate(&self, id: u32) -> Fate {
        self.fate
            .get(id as usize)
            .copied()
            .unwrap_or(Fate::Undecided)
    }

    /// Counts per group (`groups` of them) over every particle seen.
    pub fn counts(&self, groups: usize) -> Vec<FateCounts> {
        let mut c = vec![FateCounts::default(); groups];
        for (g, fate) in self.group.iter().zip(&self.fate) {
            if *g == 0 || (*g - 1) as usize >= groups {
                continue;
            }
            let e = &mut c[(*g - 1) as usize];
            match fate {
                Fate::Fine => e.fine += 1,
                Fate::Coarse => e.coarse += 1,
                Fate::Undecided => e.undecided += 1,
            }
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn frame(step: u64, parts: &[(u32, u32, f64)]) -> Frame {
        // (id, group, distance from the z axis); every particle on the x axis at z = 1 cm.
        Frame {
            step,
            time: step as f64 * 1e-3,
            id: parts.iter().map(|p| p.0).collect(),
            group: parts.iter().map(|p| p.1).collect(),
            position: parts.iter().map(|p| [p.2, 0.0, 0.01]).collect(),
            velocity: vec![[0.0; 3]; parts.len()],
            diameter: vec![1e-4; parts.len()],
            density: vec![100.0; parts.len()],
            fluctuation: Vec::new(),
            stats: Vec::new(),
        }
    }

    #[test]
    fn fates_from_hand_made_frames() {
        let axis = FlowAxis {
            center: DVec3::ZERO,
            axis: DVec3::Z,
        };
        let mut f = Fates::new(FateBounds {
            fine_radius: 6e-3,
            coarse_radius: 29e-3,
        });
        // id 0 (group 0) drifts in to the nozzle radius, then drains;
        // id 1 (group 1) drifts out to the wall zone, then bounces back inside it;
        // id 2 (group 1) vanishes while undecided (drained between frames);
        // id 3 (group 0) stays in between: undecided;
        // id 4 (group 1) enters in the second frame and never moves: undecided.
        f.observe(
            &frame(
                0,
                &[(0, 0, 10e-3), (1, 1, 28e-3), (2, 1, 7e-3), (3, 0, 20e-3)],
            ),
            &axis,
        );
        assert_eq!(f.fate(0), Fate::Undecided);
        f.observe(
            &frame(
                1,
                &[(0, 0, 6e-3), (1, 1, 29e-3), (3, 0, 20e-3), (4, 1, 15e-3)],
            ),
            &axis,
        );
        assert_eq!(f.fate(0), Fate::Fine);
        assert_eq!(f.fate(1), Fate::Coarse);
        assert_eq!(f.fate(2), Fate::Fine);
        f.observe(
            &frame(2, &[(1, 1, 25e-3), (3, 0, 28.9e-3), (4, 1, 15e-3)]),
            &axis,
        );
        // id 0 vanished after being decided (stays fine); id 1 stays coarse.
        assert_eq!(f.fate(0), Fate::Fine);
        assert_eq!(f.fate(1), Fate::Coarse);
        assert_eq!(f.fate(3), Fate::Undecided);
        assert_eq!(f.fate(4), Fate::Undecided);
        assert_eq!(f.fate(99), Fate::Undecided);
        let c = f.counts(2);
        assert_eq!(
            c[0],
            FateCounts {
                fine: 1,
                coarse: 0,
                undecided: 1
            }
        );
        assert_eq!(
            c[1],
            FateCounts {
                fine: 1,
                coarse: 1,
                undecided: 1
            }
        );
        assert_eq!(c[1].fine_fraction(), 0.5);
        assert!(FateCounts::default().fine_fraction().is_nan());
    }
}
