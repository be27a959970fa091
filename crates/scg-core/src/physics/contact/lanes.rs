//! The Hertz–Mindlin pair kernel four pairs at a time (AVX2, x86-64).
//!
//! [`hertz_mindlin_x4`] does, lane by lane, exactly the floating-point operations of
//! [`super::pair::pair_kernel`] for a pair already known to touch, in the same order and
//! without fused multiply–adds. Every operation used (+, −, ×, ÷, √) is correctly rounded
//! in IEEE 754, so each lane gives the bits the scalar kernel gives; the branches of the
//! scalar kernel (the overlap cap, an empty or normal history, sliding) become per-lane
//! selections between both outcomes. The test below checks the bits against the scalar
//! kernel on random pairs that stick, slide, overlap past the cap and carry degenerate
//! histories.

use super::NormalLaw;
use super::pair::PairParams;
use super::tangential::TangentialStiffness;

#[cfg(target_arch = "x86_64")]
pub use x86::{LaneOut, hertz_mindlin_x4};

/// The pair law the lanes compute, Hertz normal force with Mindlin tangential stiffness,
/// and its normal damping coefficient γ (the other constants are the [`PairParams`]').
#[derive(Clone, Copy, Debug)]
pub struct HertzMindlin {
    /// Normal damping coefficient γ.
    pub gamma: f64,
}

impl HertzMindlin {
    /// The lanes' law for the pair law `par`, or `None` when it is another law (those
    /// run the scalar kernel).
    pub fn of(par: &PairParams) -> Option<Self> {
        match (par.law, par.tangential.stiffness) {
            (NormalLaw::Hertz { gamma }, TangentialStiffness::Mindlin) => {
                Some(HertzMindlin { gamma })
            }
            _ => None,
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    use core::arch::x86_64::*;

    use crate::simd::{F4, V4, rows};

    use super::HertzMindlin;
    use crate::physics::contact::normal::OVERLAP_CAP;
    use crate::physics::contact::pair::{Bodies, PairParams, PairsMut, Rows};

    /// What four pairs do to their particles, a row per pair (lane), laid out as the
    /// force slots' per-particle sums `[force, torque]` so a row adds to them whole.
    #[derive(Clone, Copy, Debug, Default)]
    #[repr(C, align(32))]
    pub struct LaneOut {
        /// Per lane: force on i (N), torque on i (N·m), force on j (N, exactly the
        /// opposite of i's), torque on j (N·m), approach speed (m/s), normal force (N),
        /// two unused.
        rows: [[f64; 16]; 4],
    }

    impl LaneOut {
        /// The 3-vector at `rows[l][at..at + 3]`.
        #[inline(always)]
        fn vector(&self, l: usize, at: usize) -> glam::DVec3 {
            let r = &self.rows[l];
            glam::DVec3::new(r[at], r[at + 1], r[at + 2])
        }
        /// Force on i of lane `l`, N (the force on j is exactly its opposite).
        #[inline(always)]
        pub fn force(&self, l: usize) -> glam::DVec3 {
            self.vector(l, 0)
        }
        /// Torque on i of lane `l`, N·m.
        #[inline(always)]
        pub fn torque_i(&self, l: usize) -> glam::DVec3 {
            self.vector(l, 3)
        }
        /// Torque on j of lane `l`, N·m.
        #[inline(always)]
        pub fn torque_j(&self, l: usize) -> glam::DVec3 {
            self.vector(l, 9)
        }
        /// Normal approach speed of lane `l`, m/s (positive when closing).
        #[inline(always)]
        pub fn approach(&self, l: usize) -> f64 {
            self.rows[l][12]
        }
        /// Normal force magnitude of lane `l`, N (positive = repulsive).
        #[inline(always)]
        pub fn normal_force(&self, l: usize) -> f64 {
            self.rows[l][13]
        }
        /// Lane `l`'s force and torque on i, `[f, t]` as six f64 (the layout of a
        /// slot's per-particle sum).
        #[inline(always)]
        pub fn on_i(&self, l: usize) -> &[f64; 6] {
            self.rows[l][..6].try_into().expect("six")
        }
        /// Lane `l`'s force and torque on j, `[f, t]` as six f64. Adding it equals
        /// subtracting the force on i: x − y and x + (−y) round alike in IEEE 754.
        #[inline(always)]
        pub fn on_j(&self, l: usize) -> &[f64; 6] {
            self.rows[l][6..12].try_into().expect("six")
        }
    }

    /// Forces, torques and new histories of four touching pairs, lane l the pair
    /// `idx[l]` of `pairs` (their `touching` flags and histories are updated for lanes
    /// `l < live`; lanes from `live` on repeat a live pair and are ignored). Rolling
    /// resistance is not included.
    ///
    /// # Safety
    /// The CPU must support AVX2; every `idx[l]` must index each of `pairs`' arrays
    /// (`ij`, `touching`, `state`, and `shift` unless it is empty), and every `i`, `j`
    /// of those pairs must index `b`'s arrays.
    #[target_feature(enable = "avx2")]
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub unsafe fn hertz_mindlin_x4(
        pairs: &mut PairsMut,
        idx: [u32; 4],
        live: usize,
        b: &Bodies,
        par: &PairParams,
        law: HertzMindlin,
        dt: f64,
    ) -> LaneOut {
        let at = idx.map(|k| k as usize);
        // SAFETY (here and below, for `at`): every idx[l] indexes `pairs` (the contract),
        // whose arrays are as long as its pair list (or `shift` empty).
        let ps = at.map(|k| unsafe { pairs.state.get_unchecked(k) });
        let ij = at.map(|k| unsafe { *pairs.ij.get_unchecked(k) });
        let (i, j) = (ij.map(|p| p[0] as usize), ij.map(|p| p[1] as usize));
        // SAFETY (`v3`, `radius`): every i and j indexes `b`'s arrays (the contract).
        let v3 = |a: Rows, r: [usize; 4]| r.map(|k| unsafe { a.ptr(k) });
        let radius = |k: usize| unsafe { *b.radius.get_unchecked(k) };
        // SAFETY: every pointer addresses a DVec3 (three consecutive f64, `repr(C)`).
        let (pi, pj, shift, vi, vj, wi, wj, hist) = unsafe {
            (
                V4::gather(v3(b.pos, i)),
                V4::gather(v3(b.pos, j)),
                if pairs.shift.is_empty() {
                    V4::zero()
                } else {
                    V4::gather(at.map(|k| pairs.shift.as_ptr().add(k) as *const f64))
                },
                V4::gather(v3(b.vel, i)),
                V4::gather(v3(b.vel, j)),
                V4::gather(v3(b.omega, i)),
                V4::gather(v3(b.omega, j)),
                V4::gather(ps.map(|p| &p.history as *const _ as *const f64)),
            )
        };
        let ri = F4::from_array(i.map(radius));
        let rj = F4::from_array(j.map(radius));
        let r_eff = F4::from_array(ps.map(|p| p.hertz.r_eff));
        let sr = F4::from_array(ps.map(|p| p.hertz.sqrt_r));
        let smk = F4::from_array(ps.map(|p| p.hertz.smk));

        // Geometry.
        let d = (pj - pi) - shift;
        let dist2 = d.dot(d);
        let reach = ri + rj;
        let dist = dist2.sqrt();
        let n = d.scale(F4::splat(1.0) / dist);
        let delta = reach - dist;
        let v_rel = (vi - vj) + (wi.scale(ri) + wj.scale(rj)).cross(n);
        let vn_approach = v_rel.dot(n);

        // Normal force, tangential stiffness and damping (`hertz_mindlin_pair`).
        let k = F4::splat(4.0 / 3.0 * par.e_eff) * sr;
        let sd = delta.sqrt();
        let q = sd.sqrt();
        let cap = F4::splat(OVERLAP_CAP) * r_eff;
        let over = delta.gt(cap);
        let (mut dc, mut sdc, mut qc) = (delta, sd, q);
        if over.any() {
            let s = cap.sqrt();
            dc = dc.or_where(over, cap);
            sdc = sdc.or_where(over, s);
            qc = qc.or_where(over, s.sqrt());
        }
        let vn = -vn_approach;
        let fn_ = k * dc * sdc - F4::splat(law.gamma) * smk * qc * vn;
        let kt = F4::splat(8.0 * par.g_eff) * sr * sd;
        let eta = F4::splat(par.tangential.damping) * smk * F4::splat(par.mindlin_c) * q;
        let mut force = n.scale(-fn_);
        let (mut torque_i, mut torque_j) = (V4::zero(), V4::zero());
        let mut history = hist;

        let friction = par.tangential.friction;
        if friction > 0.0 {
            let vt = v_rel - n.scale(vn_approach);
            let limit = F4::splat(friction) * fn_.abs();
            // `rotate_history`.
            let l2 = hist.dot(hist);
            let p = hist - n.scale(hist.dot(n));
            let pl2 = p.dot(p);
            let rotated = p
                .scale((l2 / pl2).sqrt())
                .or_where(pl2.eq(F4::zero()), V4::zero())
                .or_where(l2.eq(F4::zero()), hist);
            // `tangential_force`.
            let xi = rotated + vt.scale(F4::splat(dt));
            let trial = xi.scale(-kt) - vt.scale(eta);
            let mag2 = trial.dot(trial);
            let slide = mag2.gt(limit * limit);
            let (mut ft, mut h) = (trial, xi);
            if slide.any() {
                let mag = mag2.sqrt();
                let fs = V4::zero().or_where(mag.gt(F4::zero()), trial.scale(limit / mag));
                let hs = V4::zero().or_where(kt.gt(F4::zero()), -(fs + vt.scale(eta)) / kt);
                ft = ft.or_where(slide, fs);
                h = h.or_where(slide, hs);
            }
            history = h;
            force = force + ft;
            let nf = n.cross(ft);
            torque_i = nf.scale(ri);
            torque_j = nf.scale(rj);
        }

        let h = rows(history.x, history.y, history.z, F4::zero());
        for (l, &k) in at.iter().enumerate().take(live) {
            if friction > 0.0 {
                let to = unsafe { &mut pairs.state.get_unchecked_mut(k).history }
                    as *mut glam::DVec3 as *mut f64;
                // SAFETY: `to` addresses a DVec3, three f64: x and y, then z.
                unsafe {
                    _mm_storeu_pd(to, _mm256_castpd256_pd128(h[l]));
                    _mm_store_sd(to.add(2), _mm256_extractf128_pd::<1>(h[l]));
                }
            }
            unsafe { *pairs.touching.get_unchecked_mut(k) = true };
        }
        let mut out = LaneOut::default();
        let fj = -force;
        let parts = [
            rows(force.x, force.y, force.z, torque_i.x),
            rows(torque_i.y, torque_i.z, fj.x, fj.y),
            rows(fj.z, torque_j.x, torque_j.y, torque_j.z),
            rows(vn_approach, fn_, F4::zero(), F4::zero()),
        ];
        for (l, row) in out.rows.iter_mut().enumerate() {
            for (p, part) in parts.iter().enumerate() {
                // SAFETY: `row` holds 16 f64, so 4p..4p+4 is inside it.
                unsafe { _mm256_storeu_pd(row.as_mut_ptr().add(4 * p), part[l]) };
            }
        }
        out
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use glam::DVec3;
    use rand::{Rng, SeedableRng};

    use super::*;
    use crate::physics::contact::NormalLaw;
    use crate::physics::contact::pair::{Bodies, PairArrays, PairParams, PairState};
    use crate::physics::contact::tangential::{HertzPair, TangentialLaw};

    /// Every lane of the AVX2 kernel gives the scalar kernel's bits: force, torques,
    /// history, approach speed. Pairs that stick and slide, overlaps past the cap, empty
    /// histories, histories along the normal and ones that underflow are all drawn.
    #[test]
    fn four_lanes_give_the_scalar_kernels_bits() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            eprintln!("no AVX2 here: nothing to compare");
            return;
        }
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        for friction in [0.0, 0.5] {
            let law = NormalLaw::Hertz { gamma: 1.2 };
            let (e_eff, g_eff) = (3.5e7, 1.4e7);
            let tangential = TangentialLaw::new(law, friction, 0.0);
            let par = PairParams {
                law,
                tangential,
                e_eff,
                g_eff,
                periodic: None,
                mindlin_c: (6.0 * g_eff / e_eff).sqrt(),
            };
            let lanes_law = HertzMindlin::of(&par).unwrap();
            let n = 64;
            let radius: Vec<f64> = (0..n).map(|_| rng.random_range(0.5e-3..2e-3)).collect();
            let pos: Vec<DVec3> = (0..n)
                .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) * 3e-3)
                .collect();
            let vel: Vec<DVec3> = (0..n)
                .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5)
                .collect();
            let omega: Vec<DVec3> = (0..n)
                .map(|_| (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 100.0)
                .collect();
            let b = Bodies {
                pos: (&pos).into(),
                vel: (&vel).into(),
                omega: (&omega).into(),
                radius: &radius,
            };
            let mut ij = Vec::new();
            let mut arrays = PairArrays::default();
            for i in 0..n as u32 {
                for j in i + 1..n as u32 {
                    let (a, c) = (radius[i as usize], radius[j as usize]);
                    let r_eff = a * c / (a + c);
                    let history = match rng.random_range(0..6) {
                        0 => DVec3::ZERO,
                        1 => DVec3::splat(1e-200),
                        2 => (pos[j as usize] - pos[i as usize]) * 0.01,
                        3 => DVec3::new(rng.random(), rng.random(), rng.random()) * 1e-2,
                        _ => (DVec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 1e-6,
                    };
                    ij.push([i, j]);
                    arrays.shift.push(if rng.random_bool(0.2) {
                        DVec3::new(1e-3, 0.0, -2e-3)
                    } else {
                        DVec3::ZERO
                    });
                    arrays.touching.push(rng.random_bool(0.5));
                    arrays.state.push(PairState {
                        history,
                        hertz: HertzPair::new(e_eff, r_eff, rng.random_range(1e-6..1e-5)),
                    });
                }
            }
            let before = arrays.clone();
            let mut scalar = arrays.clone();
            let all = 0..ij.len();
            let touching: Vec<u32> = (0..ij.len() as u32)
                .filter(|&k| {
                    let mut copy = before.clone();
                    copy.view(&ij, all.clone())
                        .kernel(k as usize, &b, &par, 1e-5)
                        .is_some()
                })
                .collect();
            assert!(touching.len() > 100, "{} touching pairs", touching.len());
            let (mut slid, mut capped) = (0, 0);
            for chunk in touching.chunks(4) {
                let live = chunk.len();
                let idx: [u32; 4] = std::array::from_fn(|l| chunk[l.min(live - 1)]);
                let mut lanes = arrays.view(&ij, all.clone());
                // SAFETY: AVX2 checked above; the indices are in range.
                let out =
                    unsafe { hertz_mindlin_x4(&mut lanes, idx, live, &b, &par, lanes_law, 1e-5) };
                for (l, &k) in chunk.iter().enumerate() {
                    let k = k as usize;
                    let c = scalar
                        .view(&ij, all.clone())
                        .kernel(k, &b, &par, 1e-5)
                        .unwrap();
                    let bits = |v: DVec3| v.to_array().map(f64::to_bits);
                    assert_eq!(bits(out.force(l)), bits(c.force), "pair {k}");
                    assert_eq!(bits(out.torque_i(l)), bits(c.torque_i), "pair {k}");
                    assert_eq!(bits(out.torque_j(l)), bits(c.torque_j), "pair {k}");
                    assert_eq!(out.approach(l).to_bits(), c.approach.to_bits());
                    let (h, s) = (arrays.state[k].history, scalar.state[k].history);
                    assert_eq!(bits(h), bits(s), "pair {k}");
                    assert!(arrays.touching[k] && scalar.touching[k]);
                    let [i, j] = ij[k];
                    let d = pos[j as usize] - pos[i as usize] - before.shift[k];
                    let delta = radius[i as usize] + radius[j as usize] - d.length();
                    capped += usize::from(delta > before.state[k].hertz.r_eff);
                    // Sliding: the tangential force is at the Coulomb limit μ·|F_n|.
                    let n = d.normalize();
                    let ft = c.torque_i.length() / radius[i as usize];
                    let limit = friction * (c.force.dot(n)).abs();
                    slid += usize::from(friction > 0.0 && (ft - limit).abs() < 1e-6 * limit);
                }
            }
            assert!(capped > 0, "no pair overlapped past the cap");
            assert!(friction == 0.0 || slid > 0);
        }
    }
}
