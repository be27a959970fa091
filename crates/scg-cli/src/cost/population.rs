//! The represented population of a single-particle scene: how many particles a point
//! simulates and where they start.
//!
//! A point stands for `N_orig` original particles. At α = 1 it simulates all of them; a
//! coarse-grained point simulates `N_orig / α³` (rounded, at least 1), each standing for α³
//! originals — for every law: `scg`, `none` and `mass` replace α³ originals by one enlarged
//! particle (they differ in its density), `parcel` by one enlarged particle that carries
//! the fluid force of α³ originals (see `scg_core::physics::scaling`).
//!
//! Particle 0 starts where the scene's original particle starts, with its velocity, so the
//! error can be measured on it exactly as on the lone particle. The others are spread over
//! the region the scene's particles live in, on a low-discrepancy (R2) sequence, so that
//! every point's first `n` starts are the same whatever `n`:
//!
//! * **axial flows** (vortex): at the original's distance from the axis, spread in angle
//!   over the full turn and in height over the range of the scene's listed starts; the
//!   original's velocity is rotated with the angle (the flow is axisymmetric and does not
//!   depend on the height, so every particle follows the original's path, rotated and
//!   shifted);
//! * **other flows** (uniform): over the bounding box of the scene's listed starts (a
//!   segment for `cases/uniform.toml`), all with the original's velocity;
//! * an original placed at random (`count = 1` in a region) becomes `count = n` in the
//!   same region (the seeded stream gives the same first particle for every `n`).

use std::f64::consts::TAU;

use glam::DVec3;

use scg_scene::{Placement, Scene};

use scg_core::physics::scaling::CoarseGrainLaw;

/// Originals represented by default.
pub const REPRESENTED_DEFAULT: usize = 10_000;

/// Originals represented under `--quick`: the α = 1 and α = 2 points are still dominated
/// by particle work (≈ 20 ns per particle-step against ≈ 1 µs of overhead per step), and
/// every point runs on the calling thread (below the parallel threshold of 4096).
pub const REPRESENTED_QUICK: usize = 2_000;

/// Simulated particles of a point coarse-grained by `law` (`None`: scg) with ratio `alpha`
/// standing for `n_orig` originals: `n_orig / α³`, rounded, at least 1, for the laws that
/// replace α³ originals by one particle (`scg`, `none`, `parcel`); `n_orig` for `mass`,
/// whose particles keep one original's mass and so stand for one original each.
pub fn simulated_count(law: Option<CoarseGrainLaw>, alpha: f64, n_orig: usize) -> usize {
    if law == Some(CoarseGrainLaw::Mass) {
        return n_orig;
    }
    ((n_orig as f64) / alpha.powi(3)).round().max(1.0) as usize
}

/// Index of the scene's original group: the first with α = 1, else the first.
pub fn original_group(scene: &Scene) -> usize {
    scene
        .groups
        .iter()
        .position(|g| g.alpha == 1.0)
        .unwrap_or(0)
}

fn frac(x: f64) -> f64 {
    x - x.floor()
}

/// The listed (explicit) starts of every group of `scene`.
fn listed_starts(scene: &Scene) -> Vec<DVec3> {
    scene
        .groups
        .iter()
        .flat_map(|g| match &g.placement {
            Placement::Explicit { positions, .. } => positions.clone(),
            Placement::Random { .. } => Vec::new(),
        })
        .collect()
}

/// The placement of `n` particles standing for the scene's original particle (see the
/// module documentation).
pub fn placement(base: &Scene, n: usize) -> Placement {
    let g = &base.groups[original_group(base)];
    let (x0, v0) = match &g.placement {
        Placement::Random {
            region, velocity, ..
        } => {
            return Placement::Random {
                count: n,
                region: region.clone(),
                velocity: *velocity,
            };
        }
        Placement::Explicit {
            positions,
            velocities,
        } => (positions[0], velocities[0]),
    };
    let listed = listed_starts(base);
    let mut positions = Vec::with_capacity(n);
    let mut velocities = Vec::with_capacity(n);
    positions.push(x0);
    velocities.push(v0);
    // R2 sequence steps (powers of the inverse plastic number) and, for three dimensions,
    // of the inverse of the next generalised golden ratio.
    let g2 = 1.324_717_957_244_746_f64;
    let g3 = 1.220_744_084_605_759_5_f64;
    let k_at = |k: usize| k as f64;
    match base.flow.vortex() {
        Some(v) => {
            let height = |x: DVec3| (x - v.center).dot(v.axis);
            let (h_lo, h_hi) = listed
                .iter()
                .map(|x| height(*x))
                .fold((height(x0), height(x0)), |(a, b), h| (a.min(h), b.max(h)));
            let rad = v.radial(x0);
            let r = rad.length();
            let e1 = if r > 0.0 {
                rad / r
            } else {
                v.axis.any_orthonormal_vector()
            };
            let e2 = v.axis.cross(e1);
            let (va, v1, v2) = (v0.dot(v.axis), v0.dot(e1), v0.dot(e2));
            for k in 1..n {
                let (s, c) = (TAU * frac(k_at(k) / g2)).sin_cos();
                let h = h_lo + (h_hi - h_lo) * frac(k_at(k) / (g2 * g2));
                let (f1, f2) = (c * e1 + s * e2, c * e2 - s * e1);
                positions.push(v.center + h * v.axis + r * f1);
                velocities.push(va * v.axis + v1 * f1 + v2 * f2);
            }
        }
        None => {
            let (lo, hi) = listed
                .iter()
                .fold((x0, x0), |(a, b), x| (a.min(*x), b.max(*x)));
            for k in 1..n {
                let u = DVec3::new(
                    frac(k_at(k) / g3),
                    frac(k_at(k) / (g3 * g3)),
                    frac(k_at(k) / (g3 * g3 * g3)),
                );
                positions.push(lo + (hi - lo) * u);
                velocities.push(v0);
            }
        }
    }
    Placement::Explicit {
        positions,
        velocities,
    }
}

#[cfg(test)]
mod tests {
    use super::super::sweep::Point;
    use super::*;
    use scg_core::physics::integrate::Integrator;

    fn scene(name: &str) -> Scene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../cases")
            .join(format!("{name}.toml"));
        scg_scene::load(&path, &[]).unwrap()
    }

    fn point(alpha: f64) -> Point {
        Point {
            law: Some(CoarseGrainLaw::Scg),
            alpha,
            dt_mult: 1,
            integrator: Integrator::Exponential,
            stiffness: 1.0,
        }
    }

    #[test]
    fn counts_divide_by_alpha_cubed() {
        assert_eq!(simulated_count(Some(CoarseGrainLaw::Scg), 1.0, 2000), 2000);
        assert_eq!(simulated_count(Some(CoarseGrainLaw::Scg), 2.0, 2000), 250);
        assert_eq!(simulated_count(Some(CoarseGrainLaw::Scg), 4.0, 2000), 31);
        assert_eq!(simulated_count(Some(CoarseGrainLaw::Scg), 8.0, 2000), 4);
        assert_eq!(simulated_count(Some(CoarseGrainLaw::Scg), 8.0, 100), 1);
        let mass = Point {
            law: Some(scg_core::physics::scaling::CoarseGrainLaw::Mass),
            ..point(4.0)
        };
        assert_eq!(simulated_count(mass.law, mass.alpha, 2000), 2000);
    }

    /// Vortex: particle 0 is the original; all at its radius, spread in angle and height,
    /// and the first starts do not depend on the population size.
    #[test]
    fn vortex_population_keeps_the_radius_and_spreads() {
        let s = scene("vortex");
        let Placement::Explicit { positions, .. } = placement(&s, 500) else {
            panic!("explicit")
        };
        let Placement::Explicit { positions: few, .. } = placement(&s, 7) else {
            panic!("explicit")
        };
        assert_eq!(positions[0], DVec3::new(3.0e-4, 0.0, 0.0));
        assert_eq!(&positions[..7], &few[..]);
        let v = s.flow.vortex().unwrap();
        for x in &positions {
            assert!((v.radial(*x).length() - 3.0e-4).abs() < 1e-15);
            assert!(x.z >= 0.0 && x.z <= 9.0e-4, "{x}");
        }
        let (mut xs, mut ys) = (0.0, 0.0);
        for x in &positions {
            xs += x.x;
            ys += x.y;
        }
        // Spread over the full turn: the mean position is near the axis.
        assert!((xs / 500.0).abs() < 1e-5 && (ys / 500.0).abs() < 1e-5);
        let zmax = positions.iter().map(|x| x.z).fold(0.0, f64::max);
        assert!(zmax > 8.5e-4, "{zmax}");
    }

    #[test]
    fn uniform_population_lies_on_the_scene_segment() {
        let s = scene("uniform");
        let Placement::Explicit { positions, .. } = placement(&s, 100) else {
            panic!("explicit")
        };
        assert_eq!(positions[0], DVec3::ZERO);
        for x in &positions {
            assert!(
                x.x == 0.0 && x.z == 0.0 && (0.0..=0.18).contains(&x.y),
                "{x}"
            );
        }
    }
}
