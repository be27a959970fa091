//! One formula for one particle or four: the analytic flows are written once, generic
//! over [`Lane3`], and instantiated for a `DVec3` (the scalar step) and for four vectors
//! in AVX2 lanes (`crate::simd::V4`, the four-lane kernels). Every operation is the
//! correctly rounded IEEE 754 one in the same order, so the lanes give the scalar bits.

use std::ops::{Add, Mul, Sub};

use glam::DVec3;

/// A real number: one `f64`, or four lanes.
pub trait Real: Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> {
    /// A mask: one `bool`, or four lanes.
    type Mask: Copy;
    /// `x` (in every lane).
    fn splat(x: f64) -> Self;
    /// `self > o` (false when either is NaN).
    fn gt(self, o: Self) -> Self::Mask;
}

/// A 3-vector: one `DVec3`, or four in lanes.
pub trait Lane3: Copy + Add<Output = Self> + Sub<Output = Self> {
    /// Its components' type.
    type R: Real;
    /// `v` (in every lane).
    fn splat(v: DVec3) -> Self;
    /// From components.
    fn from_xyz(x: Self::R, y: Self::R, z: Self::R) -> Self;
    /// Its components.
    fn xyz(self) -> [Self::R; 3];
    /// As glam's `DVec3::dot`.
    fn dot(self, o: Self) -> Self::R;
    /// As glam's `DVec3::cross`.
    fn cross(self, o: Self) -> Self;
    /// `self·s` per component.
    fn scale(self, s: Self::R) -> Self;
    /// `m ? a : self` (per lane).
    fn or_where(self, m: <Self::R as Real>::Mask, a: Self) -> Self;
}

impl Real for f64 {
    type Mask = bool;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
    }
}

impl Lane3 for DVec3 {
    type R = f64;
    #[inline(always)]
    fn splat(v: DVec3) -> Self {
        v
    }
    #[inline(always)]
    fn from_xyz(x: f64, y: f64, z: f64) -> Self {
        DVec3::new(x, y, z)
    }
    #[inline(always)]
    fn xyz(self) -> [f64; 3] {
        self.to_array()
    }
    #[inline(always)]
    fn dot(self, o: Self) -> f64 {
        DVec3::dot(self, o)
    }
    #[inline(always)]
    fn cross(self, o: Self) -> Self {
        DVec3::cross(self, o)
    }
    #[inline(always)]
    fn scale(self, s: f64) -> Self {
        self * s
    }
    #[inline(always)]
    fn or_where(self, m: bool, a: Self) -> Self {
        if m { a } else { self }
    }
}

#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::*;
    use crate::simd::{F4, M4, V4};

    impl Real for F4 {
        type Mask = M4;
        #[inline(always)]
        fn splat(x: f64) -> Self {
            F4::splat(x)
        }
        #[inline(always)]
        fn gt(self, o: Self) -> M4 {
            F4::gt(self, o)
        }
    }

    impl Lane3 for V4 {
        type R = F4;
        #[inline(always)]
        fn splat(v: DVec3) -> Self {
            V4::splat(v)
        }
        #[inline(always)]
        fn from_xyz(x: F4, y: F4, z: F4) -> Self {
            V4 { x, y, z }
        }
        #[inline(always)]
        fn xyz(self) -> [F4; 3] {
            [self.x, self.y, self.z]
        }
        #[inline(always)]
        fn dot(self, o: Self) -> F4 {
            V4::dot(self, o)
        }
        #[inline(always)]
        fn cross(self, o: Self) -> Self {
            V4::cross(self, o)
        }
        #[inline(always)]
        fn scale(self, s: F4) -> Self {
            V4::scale(self, s)
        }
        #[inline(always)]
        fn or_where(self, m: M4, a: Self) -> Self {
            V4::or_where(self, m, a)
        }
    }
}
