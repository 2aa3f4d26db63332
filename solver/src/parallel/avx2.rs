//! Whether the point passes take their AVX2 copies. Particle to grid, grid to particle and the
//! stress pass are each compiled twice, once for the baseline x86-64 and once with
//! `#[target_feature(enable = "avx2")]`, and each pass picks one at run time for every
//! thread's whole range (the scatters through [`call`], the stress pass through its own
//! target-feature function). AVX2 holds four f64 lanes in one register instead of two; without
//! FMA (not enabled, and Rust never contracts a product and a sum) each operation rounds as in
//! the baseline, so both copies give the same bits (docs/design.md §9,
//! docs/performance-avx2.md). `scripts/check-avx2-copies` checks in the release binary that
//! the copies are AVX2 code.

/// Whether this processor runs AVX2.
pub fn present() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Whether this processor runs AVX2 and this build does not already assume it (a build for
/// x86-64-v3 compiles every pass with it, and needs no second copy).
pub fn detected() -> bool {
    !cfg!(target_feature = "avx2") && present()
}

#[cfg(test)]
thread_local! {
    /// Tests: `true` keeps the passes this thread starts on their portable copies.
    static PORTABLE_ONLY: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether a pass started on this thread takes its AVX2 copy: where [`detected`] allows it
/// (and, in tests, this thread has not asked for the portable ones).
pub fn use_avx2() -> bool {
    #[cfg(test)]
    if PORTABLE_ONLY.with(|p| p.get()) {
        return false;
    }
    detected()
}

/// Tests: runs `f` with the passes it starts on this thread on their portable copies (`true`)
/// or as [`use_avx2`] chooses (`false`).
#[cfg(test)]
pub fn with_portable<T>(portable: bool, f: impl FnOnce() -> T) -> T {
    PORTABLE_ONLY.with(|p| p.set(portable));
    let out = f();
    PORTABLE_ONLY.with(|p| p.set(false));
    out
}

/// Calls `f` compiled with AVX2: a closure written for one call here is inlined into this
/// function and takes its target features (a closure alone takes those of the function it is
/// written in).
///
/// # Safety
/// The processor must have AVX2 ([`present`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub unsafe fn call<T>(f: impl FnOnce() -> T) -> T {
    f()
}

/// Elsewhere: calls `f` (AVX2 is never chosen there).
///
/// # Safety
/// None; unsafe only to match the x86-64 version.
#[cfg(not(target_arch = "x86_64"))]
pub unsafe fn call<T>(f: impl FnOnce() -> T) -> T {
    f()
}
