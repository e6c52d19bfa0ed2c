//! Which copy of the retina's numeric stages runs: the one compiled for AVX2 where the CPU
//! has it, else the baseline x86-64 one. The copies give the same bits (Rust neither
//! reassociates nor fuses floating-point operations, so a wider register runs each element's
//! operations in the same order); the unit tests run both and compare.

/// Whether the AVX2 copies may run here.
#[inline]
pub(crate) fn avx2() -> bool {
    #[cfg(test)]
    if BASELINE_ONLY.with(std::cell::Cell::get) {
        return false;
    }
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
thread_local! {
    static BASELINE_ONLY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f` on this thread with the baseline copies only.
#[cfg(test)]
pub(crate) fn baseline_only<R>(f: impl FnOnce() -> R) -> R {
    BASELINE_ONLY.with(|b| b.set(true));
    let result = f();
    BASELINE_ONLY.with(|b| b.set(false));
    result
}
