//! Four f64 lanes on x86-64 AVX2, for kernels that must give the scalar code's bits:
//! every operation here (+, −, ×, ÷, √, comparisons, selections, sign) is the correctly
//! rounded IEEE 754 operation the scalar code performs, and nothing is fused.
//!
//! Values of these types exist only inside functions compiled with
//! `#[target_feature(enable = "avx2")]` and entered after the CPU was checked for it
//! (`is_x86_feature_detected!("avx2")`): that is what makes the `unsafe` intrinsic calls
//! of their methods sound.
#![cfg(target_arch = "x86_64")]

use core::arch::x86_64::*;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Four f64 lanes (see the module's note on safety).
#[derive(Clone, Copy)]
pub struct F4(pub __m256d);

macro_rules! op {
    ($tr:ident, $f:ident, $intr:ident) => {
        impl $tr for F4 {
            type Output = F4;
            #[inline(always)]
            fn $f(self, o: F4) -> F4 {
                // SAFETY: see the module's note.
                F4(unsafe { $intr(self.0, o.0) })
            }
        }
    };
}
op!(Add, add, _mm256_add_pd);
op!(Sub, sub, _mm256_sub_pd);
op!(Mul, mul, _mm256_mul_pd);
op!(Div, div, _mm256_div_pd);

impl Neg for F4 {
    type Output = F4;
    #[inline(always)]
    fn neg(self) -> F4 {
        // SAFETY: see the module's note. Flipping the sign bit is what scalar negation does.
        F4(unsafe { _mm256_xor_pd(self.0, _mm256_set1_pd(-0.0)) })
    }
}

/// A lane mask (all ones where true).
#[derive(Clone, Copy)]
pub struct M4(pub __m256d);

impl F4 {
    #[inline(always)]
    pub fn splat(x: f64) -> F4 {
        // SAFETY: see the module's note.
        F4(unsafe { _mm256_set1_pd(x) })
    }
    #[inline(always)]
    pub fn zero() -> F4 {
        // SAFETY: see the module's note.
        F4(unsafe { _mm256_setzero_pd() })
    }
    /// As `f64::abs`: the sign bit cleared.
    #[inline(always)]
    pub fn abs(self) -> F4 {
        // SAFETY: see the module's note.
        F4(unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0) })
    }
    #[inline(always)]
    pub fn sqrt(self) -> F4 {
        // SAFETY: see the module's note.
        F4(unsafe { _mm256_sqrt_pd(self.0) })
    }
    #[inline(always)]
    pub fn gt(self, o: F4) -> M4 {
        // SAFETY: see the module's note. Ordered, quiet: false when either is NaN, as `>`.
        M4(unsafe { _mm256_cmp_pd::<_CMP_GT_OQ>(self.0, o.0) })
    }
    #[inline(always)]
    pub fn eq(self, o: F4) -> M4 {
        // SAFETY: see the module's note. Ordered, quiet: false when either is NaN, as `==`.
        M4(unsafe { _mm256_cmp_pd::<_CMP_EQ_OQ>(self.0, o.0) })
    }
    /// `m ? a : self` per lane.
    #[inline(always)]
    pub fn or_where(self, m: M4, a: F4) -> F4 {
        // SAFETY: see the module's note.
        F4(unsafe { _mm256_blendv_pd(self.0, a.0, m.0) })
    }
    #[inline(always)]
    pub fn from_array(a: [f64; 4]) -> F4 {
        // SAFETY: see the module's note; `a` holds four f64.
        F4(unsafe { _mm256_loadu_pd(a.as_ptr()) })
    }

    /// `!(self >= o)` per lane (true when either is NaN).
    #[inline(always)]
    pub fn not_ge(self, o: F4) -> M4 {
        // SAFETY: see the module's note. Unordered, quiet.
        M4(unsafe { _mm256_cmp_pd::<_CMP_NGE_UQ>(self.0, o.0) })
    }

    /// `self != o` per lane (true when either is NaN).
    #[inline(always)]
    pub fn ne(self, o: F4) -> M4 {
        // SAFETY: see the module's note. Unordered, quiet.
        M4(unsafe { _mm256_cmp_pd::<_CMP_NEQ_UQ>(self.0, o.0) })
    }

    /// Lane-wise maximum as `if b > a { a = b }` keeps it: a NaN in `b` is ignored.
    #[inline(always)]
    pub fn max_keep(self, b: F4) -> F4 {
        // SAFETY: see the module's note. `max_pd(b, a)` returns its second operand, a,
        // when either is NaN, and b when b > a.
        F4(unsafe { _mm256_max_pd(b.0, self.0) })
    }

    /// The four lanes.
    #[inline(always)]
    pub fn to_array(self) -> [f64; 4] {
        let mut out = [0.0; 4];
        // SAFETY: see the module's note; `out` holds four f64.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), self.0) };
        out
    }
}

impl M4 {
    /// Both.
    #[inline(always)]
    pub fn and(self, o: M4) -> M4 {
        // SAFETY: see the module's note.
        M4(unsafe { _mm256_and_pd(self.0, o.0) })
    }

    /// Bit l set when lane l is true.
    #[inline(always)]
    pub fn bits(self) -> u32 {
        // SAFETY: see the module's note.
        unsafe { _mm256_movemask_pd(self.0) as u32 }
    }

    /// Any lane true.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.bits() != 0
    }
}

/// Three components of four vectors.
#[derive(Clone, Copy)]
pub struct V4 {
    pub x: F4,
    pub y: F4,
    pub z: F4,
}

impl V4 {
    #[inline(always)]
    pub fn zero() -> V4 {
        V4 {
            x: F4::zero(),
            y: F4::zero(),
            z: F4::zero(),
        }
    }
    /// The same 3-vector in every lane.
    #[inline(always)]
    pub fn splat(v: glam::DVec3) -> V4 {
        V4 {
            x: F4::splat(v.x),
            y: F4::splat(v.y),
            z: F4::splat(v.z),
        }
    }
    /// As glam's `DVec3::dot`: (x·x′ + y·y′) + z·z′.
    #[inline(always)]
    pub fn dot(self, o: V4) -> F4 {
        (self.x * o.x) + (self.y * o.y) + (self.z * o.z)
    }
    /// As glam's `DVec3::cross`.
    #[inline(always)]
    pub fn cross(self, o: V4) -> V4 {
        V4 {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }
    /// s·v per component (glam's `f64 * DVec3` and `DVec3 * f64` alike).
    #[inline(always)]
    pub fn scale(self, s: F4) -> V4 {
        V4 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    #[inline(always)]
    pub fn or_where(self, m: M4, a: V4) -> V4 {
        V4 {
            x: self.x.or_where(m, a.x),
            y: self.y.or_where(m, a.y),
            z: self.z.or_where(m, a.z),
        }
    }
    /// Four 3-vectors starting at `p[0..4]` (each three consecutive f64), transposed.
    ///
    /// # Safety
    /// Each pointer must be valid for reading three f64.
    #[inline(always)]
    pub unsafe fn gather(p: [*const f64; 4]) -> V4 {
        // SAFETY: the caller's contract; the fourth lane of each load is masked off
        // (never read, so never beyond the vector).
        let r = p.map(|p| unsafe { F4(_mm256_maskload_pd(p, _mm256_set_epi64x(0, -1, -1, -1))) });
        let [x, y, z, _] = rows(r[0], r[1], r[2], r[3]);
        V4 {
            x: F4(x),
            y: F4(y),
            z: F4(z),
        }
    }

    /// Four consecutive 3-vectors `p[0..12]` (x0 y0 z0 x1 …), transposed.
    ///
    /// # Safety
    /// `p` must be valid for reading 12 f64.
    #[inline(always)]
    pub unsafe fn load_aos(p: *const f64) -> V4 {
        // SAFETY: the caller's contract.
        unsafe {
            let r0 = _mm256_loadu_pd(p); // x0 y0 | z0 x1
            let r1 = _mm256_loadu_pd(p.add(4)); // y1 z1 | x2 y2
            let r2 = _mm256_loadu_pd(p.add(8)); // z2 x3 | y3 z3
            let a = _mm256_blend_pd::<0b1100>(r0, r1); // x0 y0 | x2 y2
            let b = _mm256_permute2f128_pd::<0x21>(r0, r2); // z0 x1 | z2 x3
            let c = _mm256_blend_pd::<0b1100>(r1, r2); // y1 z1 | y3 z3
            V4 {
                x: F4(_mm256_shuffle_pd::<0b1010>(a, b)),
                y: F4(_mm256_shuffle_pd::<0b0101>(a, c)),
                z: F4(_mm256_shuffle_pd::<0b1010>(b, c)),
            }
        }
    }

    /// Store as four consecutive 3-vectors `p[0..12]`: the inverse of [`V4::load_aos`].
    ///
    /// # Safety
    /// `p` must be valid for writing 12 f64.
    #[inline(always)]
    pub unsafe fn store_aos(self, p: *mut f64) {
        // SAFETY: the caller's contract.
        unsafe {
            let (x, y, z) = (self.x.0, self.y.0, self.z.0);
            let a = _mm256_shuffle_pd::<0b0000>(x, y); // x0 y0 | x2 y2
            let b = _mm256_shuffle_pd::<0b1010>(z, x); // z0 x1 | z2 x3
            let c = _mm256_shuffle_pd::<0b1111>(y, z); // y1 z1 | y3 z3
            _mm256_storeu_pd(p, _mm256_permute2f128_pd::<0x20>(a, b));
            _mm256_storeu_pd(p.add(4), _mm256_blend_pd::<0b0011>(a, c));
            _mm256_storeu_pd(p.add(8), _mm256_permute2f128_pd::<0x31>(b, c));
        }
    }
}

/// The 4×4 transpose: lane l of the result holds the l-th lanes of a, b, c, d.
#[inline(always)]
pub fn rows(a: F4, b: F4, c: F4, d: F4) -> [__m256d; 4] {
    // SAFETY: see the module's note.
    unsafe {
        let t0 = _mm256_unpacklo_pd(a.0, b.0); // a0 b0 a2 b2
        let t1 = _mm256_unpackhi_pd(a.0, b.0); // a1 b1 a3 b3
        let t2 = _mm256_unpacklo_pd(c.0, d.0); // c0 d0 c2 d2
        let t3 = _mm256_unpackhi_pd(c.0, d.0); // c1 d1 c3 d3
        [
            _mm256_permute2f128_pd::<0x20>(t0, t2),
            _mm256_permute2f128_pd::<0x20>(t1, t3),
            _mm256_permute2f128_pd::<0x31>(t0, t2),
            _mm256_permute2f128_pd::<0x31>(t1, t3),
        ]
    }
}

impl Add for V4 {
    type Output = V4;
    #[inline(always)]
    fn add(self, o: V4) -> V4 {
        V4 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl Sub for V4 {
    type Output = V4;
    #[inline(always)]
    fn sub(self, o: V4) -> V4 {
        V4 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl Div<F4> for V4 {
    type Output = V4;
    #[inline(always)]
    fn div(self, s: F4) -> V4 {
        V4 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
}

impl Neg for V4 {
    type Output = V4;
    #[inline(always)]
    fn neg(self) -> V4 {
        V4 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `load_aos` and `store_aos` are inverse transposes of four packed 3-vectors.
    #[test]
    fn aos_round_trip_transposes() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let src: Vec<f64> = (0..12).map(f64::from).collect();
        let mut dst = [0.0; 12];
        // SAFETY: AVX2 checked above; both hold 12 f64.
        let v = unsafe { V4::load_aos(src.as_ptr()) };
        assert_eq!(v.x.to_array(), [0.0, 3.0, 6.0, 9.0]);
        assert_eq!(v.y.to_array(), [1.0, 4.0, 7.0, 10.0]);
        assert_eq!(v.z.to_array(), [2.0, 5.0, 8.0, 11.0]);
        unsafe { v.store_aos(dst.as_mut_ptr()) };
        assert_eq!(dst.to_vec(), src);
    }
}
