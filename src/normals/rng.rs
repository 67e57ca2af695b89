//! A small deterministic generator (SplitMix64, Steele et al. 2014) for random directions: the
//! table's samples are a pure function of `(seed, chunk index)`, so results do not depend on
//! the thread count.

use super::vec::Dir;

/// Next 64 random bits.
#[inline]
pub fn next_u64(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform in `[0, 1)` with 53 random bits.
#[inline]
pub fn next_f64(state: &mut u64) -> f64 {
    (next_u64(state) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniformly distributed unit direction (Archimedes: `z` uniform in `[-1, 1]`).
#[inline]
pub fn uniform_direction(state: &mut u64) -> Dir {
    let z = 2.0 * next_f64(state) - 1.0;
    let phi = std::f64::consts::TAU * next_f64(state);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = phi.sin_cos();
    [r * c, r * s, z]
}

/// The generator state for chunk `chunk` of a run seeded with `seed`.
pub fn chunk_state(seed: u64, chunk: u64) -> u64 {
    let mut s = seed ^ 0x6A09_E667_F3BC_C909;
    let a = next_u64(&mut s);
    a ^ chunk.wrapping_mul(0xD1B5_4A32_D192_ED03)
}
