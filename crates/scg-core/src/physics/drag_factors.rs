//! The factors of a Reynolds-dependent exponential step — the drag law's response time τ
//! from the particle Reynolds number at the start of the step and the integrator's
//! [`exponential_factors`] of it — for one particle ([`DragFactors::new`]) or for a block
//! of [`BLOCK`] particles at once ([`DragBlock`]), four lanes at a time where the CPU has
//! AVX2: the laws' powers and e^x − 1 are [`crate::physics::elementary`]'s plain
//! arithmetic, so the lanes give the one-particle bits.

use crate::physics::drag::{DragLaw, putnam_correction, schiller_naumann_correction};
use crate::physics::integrate::exponential_factors;

/// The factors of a Reynolds-dependent exponential step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DragFactors {
    /// Response time, s.
    pub tau: f64,
    /// 1 − e^(−dt/τ).
    pub gain: f64,
    /// τ·(1 − e^(−dt/τ)), s.
    pub relax: f64,
}

impl DragFactors {
    /// τ = `tau_stokes` (s) / the drag law's `correction`, and the [`exponential_factors`]
    /// of τ and `dt` (s).
    #[inline(always)]
    pub fn new(tau_stokes: f64, correction: f64, dt: f64) -> Self {
        let tau = tau_stokes / correction;
        let (gain, relax) = exponential_factors(tau, dt);
        DragFactors { tau, gain, relax }
    }
}

/// Particles per [`DragBlock`].
pub const BLOCK: usize = 64;

/// The drag factors of up to [`BLOCK`] particles, computed together so that the drag
/// law's power and e^x − 1 run in lanes; a particle whose start Reynolds number is not
/// known has none (its step computes its factors itself, with [`DragFactors::new`]).
pub struct DragBlock {
    known: [bool; BLOCK],
    tau_stokes: [f64; BLOCK],
    re: [f64; BLOCK],
    tau: [f64; BLOCK],
    gain: [f64; BLOCK],
    relax: [f64; BLOCK],
}

impl Default for DragBlock {
    fn default() -> Self {
        DragBlock {
            known: [false; BLOCK],
            tau_stokes: [0.0; BLOCK],
            re: [0.0; BLOCK],
            tau: [0.0; BLOCK],
            gain: [0.0; BLOCK],
            relax: [0.0; BLOCK],
        }
    }
}

impl DragBlock {
    /// The factors of `n` (≤ [`BLOCK`]) particles under `law` and step `dt` (s); `row(j)`
    /// gives particle j's Stokes τ (s) and its start Reynolds number when known.
    #[inline(always)]
    pub fn fill(
        &mut self,
        law: DragLaw,
        dt: f64,
        n: usize,
        mut row: impl FnMut(usize) -> (f64, Option<f64>),
    ) {
        let n = n.min(BLOCK);
        for j in 0..n {
            let (tau_stokes, re) = row(j);
            self.known[j] = re.is_some();
            self.re[j] = re.unwrap_or(1.0);
            self.tau_stokes[j] = tau_stokes;
        }
        #[cfg(target_arch = "x86_64")]
        if crate::exec::lanes() {
            // SAFETY: the CPU supports AVX2 (`exec::lanes` checked it).
            return unsafe { self.compute_avx2(law, dt, n) };
        }
        self.compute(law, dt, n);
    }

    /// Particle j's factors, when its start Reynolds number was known.
    #[inline(always)]
    pub fn factors(&self, j: usize) -> Option<DragFactors> {
        self.known[j].then(|| DragFactors {
            tau: self.tau[j],
            gain: self.gain[j],
            relax: self.relax[j],
        })
    }

    /// [`DragBlock::compute`] compiled for AVX2: the same loops, vectorised by the compiler.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn compute_avx2(&mut self, law: DragLaw, dt: f64, n: usize) {
        self.compute(law, dt, n);
    }

    /// The factors of the first `n` rows, one law at a time so that each loop is
    /// straight-line (no call: the compiler vectorises only such loops).
    #[inline(always)]
    fn compute(&mut self, law: DragLaw, dt: f64, n: usize) {
        match law {
            DragLaw::Stokes => self.each::<0>(dt, n),
            DragLaw::SchillerNaumann => self.each::<1>(dt, n),
            DragLaw::Putnam => self.each::<2>(dt, n),
        }
    }

    /// Law 0: Stokes, 1: Schiller–Naumann, 2: Putnam.
    #[inline(always)]
    fn each<const LAW: u8>(&mut self, dt: f64, n: usize) {
        let (ts, re) = (&self.tau_stokes[..n], &self.re[..n]);
        let (tau, gain, relax) = (
            &mut self.tau[..n],
            &mut self.gain[..n],
            &mut self.relax[..n],
        );
        for i in 0..n {
            let correction = match LAW {
                0 => 1.0,
                1 => schiller_naumann_correction(re[i]),
                _ => putnam_correction(re[i]),
            };
            let f = DragFactors::new(ts[i], correction, dt);
            tau[i] = f.tau;
            gain[i] = f.gain;
            relax[i] = f.relax;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn a_block_in_lanes_gives_the_one_particle_bits() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(4);
        let n = 203;
        let ts: Vec<f64> = (0..n)
            .map(|_| 10f64.powf(rng.random_range(-7.0..-1.0)))
            .collect();
        let mut re: Vec<Option<f64>> = (0..n)
            .map(|_| Some(10f64.powf(rng.random_range(-8.0..4.0))))
            .collect();
        re[5] = Some(0.0);
        re[6] = Some(f64::NAN);
        re[7] = Some(f64::INFINITY);
        re[8] = Some(1000.0);
        re[9] = None;
        for law in [DragLaw::SchillerNaumann, DragLaw::Putnam, DragLaw::Stokes] {
            let mut block = DragBlock::default();
            for base in (0..n).step_by(BLOCK) {
                let m = (n - base).min(BLOCK);
                block.fill(law, 1e-5, m, |j| (ts[base + j], re[base + j]));
                for j in 0..m {
                    let i = base + j;
                    let got = block.factors(j);
                    let want = re[i].map(|r| DragFactors::new(ts[i], law.correction(r), 1e-5));
                    assert_eq!(got.is_some(), want.is_some(), "{law:?} {i}");
                    if let (Some(g), Some(w)) = (got, want) {
                        assert_eq!(g.tau.to_bits(), w.tau.to_bits(), "{law:?} {i}");
                        assert_eq!(g.gain.to_bits(), w.gain.to_bits(), "{law:?} {i}");
                        assert_eq!(g.relax.to_bits(), w.relax.to_bits(), "{law:?} {i}");
                    }
                }
            }
        }
    }
}
