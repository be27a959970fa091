//! The per-particle moves of the integration stage with wall forces or a body
//! acceleration — Stokes drag in a flow, or no fluid — four particles at a time.
//!
//! [`move_piece`] moves one piece of the particle table: the wall kick ([`linear_kick`]),
//! then a [`Drift`] — the flow at the predicted mid-step point and the exact exponential
//! drift ([`StokesDrift`], [`exponential_drift`]), or the ballistic drift under the body
//! acceleration ([`BallisticDrift`]) — then the finiteness test and the largest
//! displacement, as the scalar per-particle step does. On x86-64 CPUs with AVX2 it runs
//! four particles at a time with the same operations in the same order, unfused, so every
//! lane gives the scalar step's bits (tested below); the flows here ([`Lanes`]) have a
//! four-lane velocity written the same way. The paper's classifier (walls, and a nozzle
//! that makes its flow piecewise) and the dense contact bed (walls, gravity, no fluid)
//! spend their integration in this step. [`scalar_rows`] is the one per-particle loop of
//! every move (the Reynolds-dependent and explicit schemes of [`super::motion`] too): it
//! writes the new states and reports the largest displacement and finiteness.

use glam::DVec3;

use crate::components::*;
use crate::physics::flow::{Affine, FlowField, Vortex};
use crate::physics::integrate::{exponential_drift, linear_kick};
use crate::physics::lane::{Lane3, Real};
#[cfg(target_arch = "x86_64")]
use crate::simd::{F4, V4};

/// A flow field with a scalar and a four-lane velocity that give the same bits (one
/// formula, [`Lane3`], instantiated twice).
pub(super) trait Lanes: Copy + Send + Sync {
    /// Fluid velocity at `x`, m/s.
    fn velocity(&self, x: DVec3) -> DVec3;

    /// [`Lanes::velocity`] at four points, lane by lane the same operations.
    #[cfg(target_arch = "x86_64")]
    fn velocity4(&self, x: V4) -> V4;
}

/// A flow in the x–y plane that does not depend on z (e.g. a vortex about z), in affine
/// form: u = (m00·x + m01·y + b0, m10·x + m11·y + b1, 0).
#[derive(Clone, Copy, Debug)]
pub(super) struct PlanarZ {
    /// m00, m01, m10, m11, 1/s.
    pub m: [f64; 4],
    /// b0, b1, m/s.
    pub b: [f64; 2],
}

impl PlanarZ {
    /// The velocity of one point or four lanes (one formula).
    #[inline(always)]
    fn velocity_of<V: Lane3>(&self, x: V) -> V {
        let [m00, m01, m10, m11] = self.m.map(V::R::splat);
        let [b0, b1] = self.b.map(V::R::splat);
        let [px, py, _] = x.xyz();
        V::from_xyz(
            m00 * px + m01 * py + b0,
            m10 * px + m11 * py + b1,
            V::R::splat(0.0),
        )
    }
}

/// A flow whose one formula (`velocity_of`, generic over [`Lane3`]) gives [`Lanes`].
macro_rules! lanes_from_formula {
    ($t:ty, |$s:ident, $x:ident| $body:expr) => {
        impl Lanes for $t {
            #[inline(always)]
            fn velocity(&self, $x: DVec3) -> DVec3 {
                let $s = self;
                $body
            }

            #[cfg(target_arch = "x86_64")]
            #[inline(always)]
            fn velocity4(&self, $x: V4) -> V4 {
                let $s = self;
                $body
            }
        }
    };
}

lanes_from_formula!(PlanarZ, |s, x| s.velocity_of(x));
lanes_from_formula!(Affine, |s, x| s.velocity_of(x));
lanes_from_formula!(FlowField, |s, x| s.velocity_of(x));
lanes_from_formula!(ClassifierFlow, |s, x| s.vortex.classifier_of(
    s.nozzle_radius,
    s.axial_speed,
    x
));

/// The paper's classifier flow ([`crate::physics::flow::FlowField::Classifier`]): the
/// vortex, plus the axial speed inside the nozzle radius.
#[derive(Clone, Copy, Debug)]
pub(super) struct ClassifierFlow {
    /// The rotating part.
    pub vortex: Vortex,
    /// Radius of the outlet nozzle, m.
    pub nozzle_radius: f64,
    /// Axial velocity inside the nozzle radius, m/s.
    pub axial_speed: f64,
}

impl ClassifierFlow {
    /// The classifier of `field`, `None` for any other flow.
    pub fn of(field: &FlowField) -> Option<Self> {
        match *field {
            FlowField::Classifier {
                vortex,
                nozzle_radius,
                axial_speed,
            } => Some(ClassifierFlow {
                vortex,
                nozzle_radius,
                axial_speed,
            }),
            _ => None,
        }
    }
}

/// What moves a particle once its wall kick is applied: the exponential drift in a flow
/// (Stokes drag) or the ballistic drift, over the time step `dt` (s). `one` is the scalar
/// step of row `i`; `four` the same for rows `k..k + 4`, lane by lane the same operations
/// (`None`: these four take the scalar step).
pub(super) trait Drift: Copy {
    /// Position and velocity after the step of row `i`, from its position `x`, kicked
    /// velocity `vk` and body acceleration `a`.
    fn one(&self, i: usize, x: DVec3, vk: DVec3, a: DVec3, dt: f64) -> (DVec3, DVec3);

    /// [`Drift::one`] for rows `k..k + 4`.
    #[cfg(target_arch = "x86_64")]
    fn four(&self, k: usize, x: V4, vk: V4, a: V4, dt: f64) -> Option<(V4, V4)>;
}

/// Stokes drag, exponential scheme: the flow at the predicted mid-step point, then the
/// exact drift ([`exponential_drift`]) with the precomputed factors.
#[derive(Clone, Copy)]
pub(super) struct StokesDrift<'a, L> {
    /// The flow.
    pub flow: L,
    /// Drag factors per row (for the scene's dt).
    pub factors: &'a [StokesFactors],
    /// Couplings per row (τ).
    pub couplings: &'a [FluidCoupling],
}

impl<L: Lanes> Drift for StokesDrift<'_, L> {
    #[inline(always)]
    fn one(&self, i: usize, x: DVec3, vk: DVec3, a: DVec3, dt: f64) -> (DVec3, DVec3) {
        let (sf, fc) = (&self.factors[i], &self.couplings[i]);
        let u = self.flow.velocity(x + vk * (0.5 * dt));
        exponential_drift(x, vk, u, a, fc.tau, sf.gain, sf.relax, dt)
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn four(&self, k: usize, x0: V4, vk: V4, a: V4, dt: f64) -> Option<(V4, V4)> {
        let tau = F4::from_array(std::array::from_fn(|l| self.couplings[k + l].tau));
        if F4::splat(f64::INFINITY).gt(tau.abs()).bits() != 0b1111 {
            // A particle without drag (or a non-finite τ): its own branch, one by one.
            return None;
        }
        let row = |f: fn(&StokesFactors) -> f64| {
            F4::from_array(std::array::from_fn(|l| f(&self.factors[k + l])))
        };
        let (gain, relax) = (row(|s| s.gain), row(|s| s.relax));
        // `exponential_drift` with finite τ.
        let u = self.flow.velocity4(x0 + vk.scale(F4::splat(0.5 * dt)));
        let w = u + a.scale(tau);
        let dv = vk - w;
        let x1 = x0 + w.scale(F4::splat(dt)) + dv.scale(relax);
        Some((x1, vk - dv.scale(gain)))
    }
}

/// No fluid: the exact drift under the body acceleration, x + v·dt + a·dt²/2.
#[derive(Clone, Copy)]
pub(super) struct BallisticDrift;

impl Drift for BallisticDrift {
    #[inline(always)]
    fn one(&self, _: usize, x: DVec3, vk: DVec3, a: DVec3, dt: f64) -> (DVec3, DVec3) {
        (x + vk * dt + 0.5 * a * dt * dt, vk + a * dt)
    }

    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn four(&self, _: usize, x: V4, vk: V4, a: V4, dt: f64) -> Option<(V4, V4)> {
        let dt = F4::splat(dt);
        let x1 = x + vk.scale(dt) + a.scale(F4::splat(0.5)).scale(dt).scale(dt);
        Some((x1, vk + a.scale(dt)))
    }
}

/// A piece of the particle table as a move reads it: positions, velocities, masses, wall
/// forces (with walls) and body accelerations (with gravity).
pub(super) struct MovePiece<'a> {
    /// Positions, m.
    pub x: &'a mut [Position],
    /// Velocities, m/s.
    pub v: &'a mut [Velocity],
    /// Masses, kg.
    pub m: &'a [Mass],
    /// Wall forces of the step, N.
    pub f: Option<&'a [Force]>,
    /// Body accelerations, m/s².
    pub a: Option<&'a [BodyAcceleration]>,
}

/// Inputs of one particle's move: position (m), velocity (m/s), mass (kg), wall force of
/// the step (N, when the scene has walls) and body acceleration (m/s²).
pub(super) struct Mover {
    pub x: DVec3,
    pub v: DVec3,
    pub m: f64,
    pub force: Option<DVec3>,
    pub a: DVec3,
}

impl Mover {
    /// Velocity after the wall kick: v + F/m·dt ([`linear_kick`]; unchanged without
    /// walls).
    #[inline(always)]
    pub fn kicked(&self, dt: f64) -> DVec3 {
        match self.force {
            Some(f) => linear_kick(self.v, f, self.m, dt),
            None => self.v,
        }
    }
}

/// Rows `range` of a piece, one particle at a time: `step` gives row `i`'s new position
/// and velocity from its [`Mover`]; they are written. Returns the largest squared
/// displacement and whether every result is finite.
#[inline(always)]
pub(super) fn scalar_rows(
    p: &mut MovePiece,
    range: std::ops::Range<usize>,
    step: impl Fn(usize, Mover) -> (DVec3, DVec3),
) -> (f64, bool) {
    let (mut d2max, mut finite) = (0.0_f64, true);
    for i in range {
        let x = p.x[i].0;
        let mover = Mover {
            x,
            v: p.v[i].0,
            m: p.m[i].0,
            force: p.f.map(|f| f[i].0),
            a: p.a.map_or(DVec3::ZERO, |g| g[i].0),
        };
        let (x1, v1) = step(i, mover);
        // One test catches any NaN or infinity among the six numbers.
        finite &= (x1 + v1).element_sum().is_finite();
        let d2 = (x1 - x).length_squared();
        if d2 > d2max {
            d2max = d2;
        }
        p.x[i].0 = x1;
        p.v[i].0 = v1;
    }
    (d2max, finite)
}

/// [`scalar_rows`] with the wall kick and `drift`.
#[inline(always)]
fn drift_rows<D: Drift>(
    p: &mut MovePiece,
    range: std::ops::Range<usize>,
    drift: &D,
    dt: f64,
) -> (f64, bool) {
    scalar_rows(p, range, |i, m| drift.one(i, m.x, m.kicked(dt), m.a, dt))
}

/// Move the particles of a piece (see the module documentation): the largest squared
/// displacement, m², and whether every new position and velocity is finite. Four at a
/// time where the CPU has AVX2, with the scalar path's bits.
pub(super) fn move_piece<D: Drift>(mut p: MovePiece, drift: D, dt: f64) -> (f64, bool) {
    let n = p.x.len();
    #[cfg(target_arch = "x86_64")]
    if crate::exec::lanes() {
        // SAFETY: the CPU supports AVX2 (`exec::lanes` checked it).
        return unsafe { move_piece_avx2(&mut p, drift, dt) };
    }
    drift_rows(&mut p, 0..n, &drift, dt)
}

/// The four-lane body of [`move_piece`]; groups of four the drift declines and the last
/// `n % 4` rows take the scalar path.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn move_piece_avx2<D: Drift>(p: &mut MovePiece, drift: D, dt: f64) -> (f64, bool) {
    let n = p.x.len().min(p.v.len()).min(p.m.len());
    let n4 = n / 4 * 4;
    let (dtv, inf) = (F4::splat(dt), F4::splat(f64::INFINITY));
    let mut d2max = F4::zero();
    let (mut top, mut finite) = (0.0_f64, true);
    for k in (0..n4).step_by(4) {
        let xp = p.x[k..k + 4].as_mut_ptr() as *mut f64;
        let vp = p.v[k..k + 4].as_mut_ptr() as *mut f64;
        // SAFETY: four consecutive `Position`s, `Velocity`s, `Force`s and
        // `BodyAcceleration`s (transparent DVec3s) are 12 f64 each.
        let (x0, v0) = unsafe { (V4::load_aos(xp), V4::load_aos(vp)) };
        let vk = match p.f {
            Some(f) => {
                // `linear_kick`: v + F·(dt/m).
                let force = unsafe { V4::load_aos(f[k..k + 4].as_ptr() as *const f64) };
                let m = F4::from_array(std::array::from_fn(|l| p.m[k + l].0));
                v0 + force.scale(dtv / m)
            }
            None => v0,
        };
        let a = match p.a {
            Some(g) => unsafe { V4::load_aos(g[k..k + 4].as_ptr() as *const f64) },
            None => V4::zero(),
        };
        let Some((x1, v1)) = drift.four(k, x0, vk, a, dt) else {
            let (d2, ok) = drift_rows(p, k..k + 4, &drift, dt);
            top = top.max(d2);
            finite &= ok;
            continue;
        };
        let s = x1 + v1;
        let sum = s.x + s.y + s.z;
        finite &= inf.gt(sum.abs()).bits() == 0b1111;
        let d = x1 - x0;
        d2max = d2max.max_keep(d.dot(d));
        // SAFETY: as for the loads.
        unsafe {
            x1.store_aos(xp);
            v1.store_aos(vp);
        }
    }
    let (d2, ok) = drift_rows(p, n4..n, &drift, dt);
    for v in d2max.to_array().into_iter().chain([d2]) {
        if v > top {
            top = v;
        }
    }
    (top, finite && ok)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DMat3;
    use rand::{Rng, SeedableRng};

    fn v3(rng: &mut rand::rngs::StdRng, s: f64) -> DVec3 {
        (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * s
    }

    /// The particle columns of `n` random particles; some without drag (τ = ∞) when
    /// `ballistic`, and one non-finite velocity when `bad`.
    #[allow(clippy::type_complexity)]
    fn columns(
        rng: &mut rand::rngs::StdRng,
        n: usize,
        ballistic: bool,
        bad: bool,
    ) -> (
        Vec<Position>,
        Vec<Velocity>,
        Vec<StokesFactors>,
        Vec<FluidCoupling>,
        Vec<Mass>,
        Vec<Force>,
        Vec<BodyAcceleration>,
    ) {
        let xs: Vec<Position> = (0..n).map(|_| Position(v3(rng, 0.06))).collect();
        let mut vs: Vec<Velocity> = (0..n).map(|_| Velocity(v3(rng, 20.0))).collect();
        if bad && n > 5 {
            vs[5].0.y = f64::NAN;
        }
        let fcs: Vec<FluidCoupling> = (0..n)
            .map(|i| FluidCoupling {
                drag_diameter: 1e-4,
                reynolds_diameter: 1e-4,
                force_density: 1000.0,
                force_scale: 1.0,
                tau: if ballistic && i % 7 == 3 {
                    f64::INFINITY
                } else {
                    rng.random_range(1e-6..1e-2)
                },
            })
            .collect();
        let dt = 2e-7;
        let sfs = fcs
            .iter()
            .map(|c| {
                let (gain, relax) = crate::physics::integrate::exponential_factors(c.tau, dt);
                StokesFactors { gain, relax }
            })
            .collect();
        let ms = (0..n)
            .map(|_| Mass(rng.random_range(1e-12..1e-9)))
            .collect();
        let fs = (0..n)
            .map(|i| {
                Force(if i % 3 == 0 {
                    DVec3::ZERO
                } else {
                    v3(rng, 1e-6)
                })
            })
            .collect();
        let gs = (0..n)
            .map(|_| BodyAcceleration(DVec3::new(0.0, 0.0, -9.81)))
            .collect();
        (xs, vs, sfs, fcs, ms, fs, gs)
    }

    fn bits(x: &[Position], v: &[Velocity]) -> Vec<[u64; 6]> {
        x.iter()
            .zip(v)
            .map(|(x, v)| {
                let (a, b) = (x.0.to_array(), v.0.to_array());
                [a[0], a[1], a[2], b[0], b[1], b[2]].map(f64::to_bits)
            })
            .collect()
    }

    /// Both paths on the same columns: the same bits of every position and velocity, the
    /// same largest displacement and finiteness; Stokes drag in `flow`, or no fluid.
    fn same_bits<L: Lanes>(seed: u64, flow: Option<L>) {
        let dt = 2e-7;
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        for (n, walls, gravity, ballistic, bad) in [
            (103, true, false, false, false),
            (64, true, true, true, false),
            (37, false, true, false, false),
            (41, true, false, true, true),
            (3, true, true, false, false),
        ] {
            let (xs, vs, sfs, fcs, ms, fs, gs) = columns(&mut rng, n, ballistic, bad);
            let run = |lanes: bool| {
                let (mut x, mut v) = (xs.clone(), vs.clone());
                let mut piece = MovePiece {
                    x: &mut x,
                    v: &mut v,
                    m: &ms,
                    f: walls.then_some(&fs[..]),
                    a: gravity.then_some(&gs[..]),
                };
                let (d2, ok) = match (flow, lanes) {
                    (Some(flow), lanes) => {
                        let d = StokesDrift {
                            flow,
                            factors: &sfs,
                            couplings: &fcs,
                        };
                        if lanes {
                            move_piece(piece, d, dt)
                        } else {
                            drift_rows(&mut piece, 0..n, &d, dt)
                        }
                    }
                    (None, true) => move_piece(piece, BallisticDrift, dt),
                    (None, false) => drift_rows(&mut piece, 0..n, &BallisticDrift, dt),
                };
                (bits(&x, &v), d2.to_bits(), ok)
            };
            let (scalar, lanes) = (run(false), run(true));
            assert_eq!(scalar.1, lanes.1, "largest displacement, n = {n}");
            assert_eq!(scalar.2, lanes.2, "finiteness, n = {n}");
            assert_eq!(scalar.2, !bad, "n = {n}");
            for (i, (a, b)) in scalar.0.iter().zip(&lanes.0).enumerate() {
                assert_eq!(a, b, "particle {i} of {n}");
            }
        }
    }

    /// The four-lane step gives the scalar step's bits in every flow with lanes and
    /// without a fluid, with and without wall forces and gravity, with particles without
    /// drag among them, a non-finite state and a tail after the last four (on CPUs
    /// without AVX2 both are the scalar path).
    #[test]
    fn four_lanes_give_the_scalar_steps_bits() {
        same_bits::<PlanarZ>(5, None);
        let vortex = Vortex {
            center: DVec3::new(1e-3, -2e-3, 0.01),
            axis: DVec3::new(0.1, -0.2, 0.9).normalize(),
            omega: 523.6,
            inflow_ratio: 5.0,
        };
        let classifier = ClassifierFlow {
            vortex,
            nozzle_radius: 0.012,
            axial_speed: 1.0,
        };
        same_bits(1, Some(classifier));
        let about_z = Vortex {
            axis: DVec3::Z,
            ..vortex
        };
        same_bits(
            2,
            Some(ClassifierFlow {
                vortex: about_z,
                nozzle_radius: 0.006,
                axial_speed: -2.0,
            }),
        );
        same_bits(
            3,
            Some(PlanarZ {
                m: [0.3, -1.7, 1.9, 0.2],
                b: [0.5, -0.25],
            }),
        );
        same_bits(
            4,
            Some(Affine {
                m: DMat3::from_cols_array(&[0.3, -1.7, 1.9, 0.2, 0.4, -0.6, 1.1, 0.9, -0.8]),
                b: DVec3::new(0.5, -0.25, 2.0),
            }),
        );
        same_bits(6, Some(FlowField::Vortex(vortex)));
    }

    /// The classifier's lanes: the velocity of each lane equals the scalar velocity, inside
    /// and outside the nozzle and on the axis.
    #[test]
    fn classifier_lanes_match_the_field() {
        let c = ClassifierFlow {
            vortex: Vortex {
                center: DVec3::ZERO,
                axis: DVec3::Z,
                omega: 523.6,
                inflow_ratio: 5.0,
            },
            nozzle_radius: 6e-3,
            axial_speed: 1.0,
        };
        let field = crate::physics::flow::FlowField::Classifier {
            vortex: c.vortex,
            nozzle_radius: c.nozzle_radius,
            axial_speed: c.axial_speed,
        };
        let pts = [
            DVec3::new(1e-3, 2e-3, 0.01),
            DVec3::new(0.02, -0.01, 0.03),
            DVec3::ZERO,
            DVec3::new(6e-3, 0.0, 0.0),
        ];
        for p in pts {
            assert_eq!(c.velocity(p), field.velocity(p));
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 checked just above (the lanes' operations need it).
            let got = unsafe { lanes4(&c, pts) };
            for (p, g) in pts.iter().zip(got) {
                assert_eq!(
                    g.to_array().map(f64::to_bits),
                    field.velocity(*p).to_array().map(f64::to_bits)
                );
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn lanes4<L: Lanes>(flow: &L, p: [DVec3; 4]) -> [DVec3; 4] {
        let flat: Vec<f64> = p.iter().flat_map(|v| v.to_array()).collect();
        // SAFETY: `flat` holds 12 f64.
        let x = unsafe { V4::load_aos(flat.as_ptr()) };
        let u = flow.velocity4(x);
        let mut out = [0.0; 12];
        // SAFETY: `out` holds 12 f64.
        unsafe { u.store_aos(out.as_mut_ptr()) };
        std::array::from_fn(|l| DVec3::from_slice(&out[3 * l..3 * l + 3]))
    }
}
