//! The one seeded generator of the crate: SplitMix64 (Steele, Lea & Flood 2014, "Fast
//! Splittable Pseudorandom Number Generators"). Every random choice — the shader sampler's
//! points, the normal table's directions, the noise permutation, test inputs — draws from a
//! generator seeded by a pure function of the work item (a quadtree node, a chunk index), never
//! by the thread that runs it, so results do not depend on the thread count.

use glam::DVec3;

/// SplitMix64: a 64-bit counter advanced by the golden-ratio increment, hashed by a
/// variant of MurmurHash3's finalizer.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator whose state is `seed`.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// A generator for a combination of keys (e.g. seed, depth, x, y): each key is mixed into
    /// the state by one step of the generator.
    pub fn keyed(keys: &[u64]) -> Self {
        let mut h = SplitMix64(0x9E37_79B9_7F4A_7C15);
        for &k in keys {
            h.0 ^= k;
            h.next_u64();
        }
        h
    }

    /// The generator of chunk `chunk` of a run seeded with `seed` (the normal table's parallel
    /// chunks): the seed is hashed once, then the chunk index is spread by an odd multiplier.
    pub fn for_chunk(seed: u64, chunk: u64) -> Self {
        let mut s = SplitMix64(seed ^ 0x6A09_E667_F3BC_C909);
        SplitMix64(s.next_u64() ^ chunk.wrapping_mul(0xD1B5_4A32_D192_ED03))
    }

    /// Next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 53 random bits.
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in [lo, hi] (inclusive; modulo bias below 2⁻⁵⁰ for ranges under 2¹⁴).
    pub fn range_i64(&mut self, lo: i64, hi: i64) -> i64 {
        lo + (self.next_u64() % (hi - lo + 1) as u64) as i64
    }

    /// A uniformly distributed unit direction (Archimedes: z uniform in [−1, 1], φ uniform).
    #[inline]
    pub fn direction(&mut self) -> DVec3 {
        let z = 2.0 * self.next_f64() - 1.0;
        let phi = std::f64::consts::TAU * self.next_f64();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let (s, c) = phi.sin_cos();
        DVec3::new(r * c, r * s, z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reproduces_the_reference_splitmix64_sequence() {
        // The first outputs of SplitMix64 seeded with 1234567, as printed by the reference
        // implementation (Vigna's splitmix64.c, also used to seed xoshiro).
        let mut r = SplitMix64::new(1234567);
        let want = [6457827717110365317u64, 3203168211198807973, 9817491932198370423, 4593380528125082431];
        for w in want {
            assert_eq!(r.next_u64(), w);
        }
    }

    #[test]
    fn directions_are_unit_and_unbiased() {
        let mut r = SplitMix64::for_chunk(7, 3);
        let n = 100_000;
        let mut mean = DVec3::ZERO;
        for _ in 0..n {
            let d = r.direction();
            assert!((d.length() - 1.0).abs() < 1e-15);
            mean += d;
        }
        // The mean of n uniform directions has a standard deviation of 1/√(3n) per axis.
        assert!((mean / n as f64).abs().max_element() < 5.0 / (3.0 * n as f64).sqrt(), "{mean}");
    }
}
