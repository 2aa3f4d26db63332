//! A small deterministic generator for unit tests (xorshift64): the same numbers on every
//! machine, no dependency.

/// Numbers uniform in [-0.5, 0.5) from `seed` (not 0), the same sequence for the same seed.
pub fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut x = seed;
    move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}
