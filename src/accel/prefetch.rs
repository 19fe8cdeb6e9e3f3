//! The one cache-prefetch hint, for inner nodes (`tree.rs`) and leaf blocks
//! (`leaf.rs`) alike.

/// Starts loading every cache line of `items[0..n]` (a hint; a no-op on other
/// architectures). A plain counted loop: `step_by` costs a division per call.
///
/// # Safety
/// `p..p + n` must lie inside one allocation (a prefetch never faults, but the
/// pointer arithmetic must stay in bounds).
#[inline(always)]
pub(super) unsafe fn prefetch_lines<T>(p: *const T, n: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let (p, bytes) = (p as *const i8, n * std::mem::size_of::<T>());
        let mut line = 0;
        while line < bytes {
            _mm_prefetch::<_MM_HINT_T0>(p.add(line));
            line += 64;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (p, n);
}
