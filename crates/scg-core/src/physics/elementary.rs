//! The logarithm, the exponential and `e^x − 1` in plain IEEE 754 arithmetic (+, −, ×, ÷
//! and bit operations on the representation, nothing fused, no table, no branch but
//! selections), so that a loop of them compiles to four AVX2 lanes and gives the bits of
//! the scalar call on every machine: the drag law's Reynolds power and the exponential
//! integrator's factors of a block of particles are computed so
//! ([`crate::physics::drag_factors`]), four at a time where the CPU has AVX2, where libm's
//! `pow` and `expm1` cost a call each.
//!
//! * [`ln`]: fdlibm's `__ieee754_log` (Sun Microsystems, 1993; as musl writes it):
//!   x = 2^k·(1 + f) with √2/2 ≤ 1 + f < √2, s = f/(2 + f), ln(1 + f) = f − f²/2 +
//!   s·(f²/2 + R(s²)) with fdlibm's degree-14 minimax R. Below 1 ulp.
//! * [`exp_m1`], [`exp`]: Cody–Waite reduction x = k·ln 2 + r, |r| ≤ ln 2/2 (ln 2 in two
//!   parts, fdlibm's), e^r − 1 by its Taylor series to r¹³/13! (truncation below 10^-17
//!   relative), then e^x − 1 = 2^k·(e^r − 1) + (2^k − 1), e^x = 2^k·(1 + (e^r − 1)).
//!   Within 2 ulp of libm (the tests), and exact in the limits the integrator reaches:
//!   e^x − 1 = x for |x| < 2^-54, −1 below −40.
//! * [`powf`] = e^(y·ln x): relative error below 2·10^-15 where |y·ln x| < 8 (the
//!   Reynolds powers of the drag laws below Re = 1000), against libm's correctly rounded
//!   `pow`.

/// ln 2's leading 32 bits (the last 21 of the significand zero: k·LN2_HI is exact for
/// |k| < 2^21), fdlibm's. (fdlibm's decimals, which round to its bit patterns.)
#[allow(clippy::excessive_precision)]
const LN2_HI: f64 = 6.931_471_803_691_238_164_90e-1;
/// ln 2 − LN2_HI, fdlibm's.
#[allow(clippy::excessive_precision)]
const LN2_LO: f64 = 1.908_214_929_270_587_700_02e-10;
/// 1/ln 2.
const INV_LN2: f64 = std::f64::consts::LOG2_E;
/// 1.5·2^52: adding it rounds a number below 2^51 in size to an integer, whose value is
/// then in the low bits of the sum's representation.
const SHIFT: f64 = 6_755_399_441_055_744.0;

/// fdlibm's minimax coefficients of R(z) ≈ (ln(1 + f) − f + f²/2)/s − f²/2.
#[allow(clippy::excessive_precision)]
const LG: [f64; 7] = [
    6.666_666_666_666_735_130e-1,
    3.999_999_999_940_941_908e-1,
    2.857_142_874_366_239_149e-1,
    2.222_219_843_214_978_396e-1,
    1.818_357_216_161_805_012e-1,
    1.531_383_769_920_937_332e-1,
    1.479_819_860_511_658_591e-1,
];

/// 1/n!, correctly rounded (n! is exact in f64 up to 18!).
const fn inv_factorial(n: u32) -> f64 {
    let mut f = 1.0;
    let mut i = 2;
    while i <= n {
        f *= i as f64;
        i += 1;
    }
    1.0 / f
}

/// Natural logarithm of a positive normal finite x (fdlibm's algorithm, see the module
/// documentation). Zero, subnormals, infinities and NaN are the caller's to exclude: the
/// result is unspecified there.
#[inline(always)]
pub fn ln(x: f64) -> f64 {
    // x = 2^k·m with m in [√2/2, √2): adding 1 − 0x3fe6a09e (√2/2's high word) to the
    // high word carries into the exponent exactly when m ≥ √2/2
    let mut u = x.to_bits();
    u = u.wrapping_add((0x3ff0_0000_u64 - 0x3fe6_a09e) << 32);
    let biased = u >> 52;
    u = (u & 0x000f_ffff_ffff_ffff) + (0x3fe6_a09e_u64 << 32);
    // k as an f64 without an integer conversion (AVX2 has none for 64-bit integers)
    let k = f64::from_bits(0x4330_0000_0000_0000 | biased) - (4_503_599_627_370_496.0 + 1023.0);
    let f = f64::from_bits(u) - 1.0;
    let hfsq = 0.5 * f * f;
    let s = f / (2.0 + f);
    let z = s * s;
    let w = z * z;
    let t1 = w * (LG[1] + w * (LG[3] + w * LG[5]));
    let t2 = z * (LG[0] + w * (LG[2] + w * (LG[4] + w * LG[6])));
    let r = t2 + t1;
    s * (hfsq + r) + k * LN2_LO - hfsq + f + k * LN2_HI
}

/// The Cody–Waite reduction of x (|x| ≤ 709): 2^k and r = x − k·ln 2, |r| ≤ ln 2/2 + ε.
#[inline(always)]
fn reduce(x: f64) -> (f64, f64) {
    let t = x * INV_LN2 + SHIFT;
    let k = t - SHIFT;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    // t's representation is SHIFT's plus k (its ulp is 1): 2^k from k's bits
    let ki = t.to_bits().wrapping_sub(SHIFT.to_bits());
    let scale = f64::from_bits(ki.wrapping_add(1023) << 52);
    (scale, r)
}

/// e^r − 1 for |r| ≤ ln 2/2 + ε: Taylor to r¹³/13!, r + r²·(1/2! + r/3! + …).
#[inline(always)]
fn exp_m1_reduced(r: f64) -> f64 {
    let mut q = inv_factorial(13);
    q = q * r + inv_factorial(12);
    q = q * r + inv_factorial(11);
    q = q * r + inv_factorial(10);
    q = q * r + inv_factorial(9);
    q = q * r + inv_factorial(8);
    q = q * r + inv_factorial(7);
    q = q * r + inv_factorial(6);
    q = q * r + inv_factorial(5);
    q = q * r + inv_factorial(4);
    q = q * r + inv_factorial(3);
    q = q * r + 0.5;
    r + r * r * q
}

/// e^x − 1 (see the module documentation): x ≤ 709 or +∞ (↦ +∞), −∞ ↦ −1, NaN ↦ NaN.
#[inline(always)]
pub fn exp_m1(x: f64) -> f64 {
    // below −40, e^x < 2^-57: −1 + e^x rounds to −1 (and 2^k stays normal)
    let xc = if x < -40.0 { -40.0 } else { x };
    let xc = if xc > 709.0 { 709.0 } else { xc };
    let (scale, r) = reduce(xc);
    let p = exp_m1_reduced(r);
    let y = scale * p + (scale - 1.0);
    if x > 709.0 { f64::INFINITY } else { y }
}

/// e^x for |x| ≤ 700 (see the module documentation; the caller keeps x there).
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    let (scale, r) = reduce(x);
    scale * (1.0 + exp_m1_reduced(r))
}

/// x^y = e^(y·ln x) for positive normal finite x and |y·ln x| ≤ 700 (the caller keeps
/// them there; see the module documentation for the accuracy).
#[inline(always)]
pub fn powf(x: f64, y: f64) -> f64 {
    exp(y * ln(x))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Distance in units in the last place.
    fn ulps(a: f64, b: f64) -> u64 {
        if a == b {
            return 0;
        }
        let (a, b) = (a.to_bits() as i64, b.to_bits() as i64);
        a.abs_diff(b)
    }

    #[test]
    fn ln_is_within_one_ulp_of_libm() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(1);
        let mut worst = 0;
        for _ in 0..200_000 {
            let x = 10f64.powf(rng.random_range(-300.0..300.0));
            worst = worst.max(ulps(ln(x), x.ln()));
        }
        for x in [
            1.0,
            2.0,
            0.5,
            1.0 + 1e-15,
            1.0 - 1e-16,
            f64::MIN_POSITIVE,
            f64::MAX,
        ] {
            worst = worst.max(ulps(ln(x), x.ln()));
        }
        assert_eq!(ln(1.0), 0.0);
        assert!(worst <= 1, "{worst} ulp");
    }

    #[test]
    fn exp_m1_is_within_two_ulp_of_libm_and_exact_in_its_limits() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(2);
        let mut worst = 0;
        for _ in 0..200_000 {
            // the integrator's −dt/τ: from −10^-20 to −10^3, and a few positive values
            let x = -(10f64.powf(rng.random_range(-20.0..3.0)));
            worst = worst.max(ulps(exp_m1(x), x.exp_m1()));
            let y = rng.random_range(-2.0..700.0);
            worst = worst.max(ulps(exp_m1(y), y.exp_m1()));
        }
        assert!(worst <= 2, "{worst} ulp");
        for x in [0.0, 1e-300, -1e-300, 5e-324, -1e-17] {
            assert_eq!(exp_m1(x).to_bits(), x.to_bits(), "{x}");
        }
        assert_eq!(exp_m1(-0.0), 0.0); // (+0: the sign of a zero is not kept)
        assert_eq!(exp_m1(-41.0), -1.0);
        assert_eq!(exp_m1(f64::NEG_INFINITY), -1.0);
        assert_eq!(exp_m1(f64::INFINITY), f64::INFINITY);
        assert_eq!(exp_m1(710.0), f64::INFINITY);
        assert!(exp_m1(f64::NAN).is_nan());
    }

    #[test]
    fn powers_of_the_drag_laws_are_within_2e_15_of_libm() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let mut worst = 0.0_f64;
        for _ in 0..200_000 {
            let re = 10f64.powf(rng.random_range(-6.0..3.0));
            for y in [0.687, 2.0 / 3.0] {
                let (a, b) = (powf(re, y), re.powf(y));
                worst = worst.max((a - b).abs() / b);
            }
        }
        assert!(worst < 2e-15, "{worst:e}");
        assert!(exp(0.0) == 1.0 && ulps(exp(1.0), std::f64::consts::E) <= 1);
    }
}
