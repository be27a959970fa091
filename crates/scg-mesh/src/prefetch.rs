//! Cache prefetch hints for the memory-bound walks over large meshes (no-ops off x86-64):
//! the one helper the locator, the cell table and scg-core's mesh flow use.

/// Ask the processor to load element `i` of `v` into the cache (nothing when `i` is out
/// of range).
#[inline(always)]
pub fn element<T>(v: &[T], i: usize) {
    if let Some(x) = v.get(i) {
        lines(x, 1);
    }
}

/// Ask the processor to load `n` cache lines (64 bytes, at most 12) from `x` on.
#[inline(always)]
pub fn lines<T>(x: &T, n: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        let p = (x as *const T).cast::<i8>();
        for k in 0..n.min(12) {
            // SAFETY: a prefetch is a hint that never faults, whatever the address.
            unsafe {
                core::arch::x86_64::_mm_prefetch::<{ core::arch::x86_64::_MM_HINT_T0 }>(
                    p.wrapping_add(64 * k),
                )
            };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (x, n);
}
