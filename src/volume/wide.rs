//! Loops over voxels compiled twice, for the baseline processor and for AVX2, and run as AVX2
//! where the processor has it (checked at run time): the same operations, so the same results,
//! on vectors twice as wide.

/// Runs `work`, compiled for AVX2 as well as for the baseline processor and run so where the
/// processor has it. `work`'s loops are vectorized either way; AVX2 doubles their width and
/// adds what the baseline lacks (the minimum and maximum of 32-bit integers, for one).
#[inline]
pub(crate) fn wide<R>(work: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") {
        // SAFETY: this processor has AVX2.
        #[allow(unsafe_code)]
        unsafe {
            return with_avx2(work);
        }
    }
    work()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn with_avx2<R>(work: impl FnOnce() -> R) -> R {
    work()
}
