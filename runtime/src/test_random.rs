//! Seeded uniform numbers for the unit tests: a linear congruential stream, so a test's
//! random scenes are the same on every run.

/// Uniform numbers in [0, 1) from `seed`.
pub fn unit_stream(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}
