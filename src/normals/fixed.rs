//! Fixed-point fields: the SNORM convention every parameterization uses for its coordinates,
//! and bit-field helpers for packing several fields into one code word.
//!
//! A `k`-bit SNORM field holds a two's-complement integer `s` in `[-2^(k-1), 2^(k-1) - 1]` and
//! stands for `t = max(s / q, -1)` with `q = 2^(k-1) - 1` (the D3D/GL/Vulkan SNORM rule, so a
//! shader decodes 8- and 16-bit fields with `unpackSnorm*`). The lattice is symmetric and holds
//! `-1`, `0` and `+1` exactly, so axes and the octahedron's fold are lattice points; the one
//! extra code `-2^(k-1)` decodes like `-q` (decoding is total). Sample spacing: `ε = 1 / q`.

/// Largest SNORM magnitude `q = 2^(k-1) - 1` of a `k`-bit field (`2 <= k <= 32`).
#[inline]
pub fn snorm_max(bits: u32) -> i64 {
    (1i64 << (bits - 1)) - 1
}

/// Sample spacing `ε = 1/q` of a `k`-bit SNORM field over `[-1, 1]`.
#[inline]
pub fn snorm_spacing(bits: u32) -> f64 {
    1.0 / snorm_max(bits) as f64
}

/// Rounds `t` in `[-1, 1]` to the nearest SNORM integer (ties to even, which is symmetric:
/// `encode(-t) = -encode(t)`), clamped to `[-q, q]`.
#[inline]
pub fn snorm_round(t: f64, bits: u32) -> i64 {
    let q = snorm_max(bits) as f64;
    round_ties_even(t * q).clamp(-q, q) as i64
}

/// `1.5·2^52`: adding and subtracting it rounds any `|x| < 2^51` to an integer, ties to even
/// (the current rounding mode), in two plain additions that vectorize — unlike `f64::round`,
/// which baseline x86-64 (no SSE4.1 `roundsd`) turns into a libm call.
const ROUNDING_MAGIC: f64 = 6_755_399_441_055_744.0;

/// `x` rounded to the nearest integer, ties to even, for `|x| < 2^51` (all SNORM products here
/// are below `2^31`); NaN stays NaN.
#[inline]
pub fn round_ties_even(x: f64) -> f64 {
    (x + ROUNDING_MAGIC) - ROUNDING_MAGIC
}

/// The `bits`-wide two's-complement field (`bits <= 32`) of an integer-valued `s` with
/// `|s| < 2^31`, read from the mantissa of `s + 1.5·2^52`, whose low 32 bits are `s` in two's
/// complement: no float-to-integer conversion, which baseline x86-64 has no SIMD form of for
/// 64-bit integers, so batch loops stay vectorized.
#[inline(always)]
pub fn integer_to_field(s: f64, bits: u32) -> u64 {
    (s + ROUNDING_MAGIC).to_bits() & mask(bits)
}

/// `floor(x)` for `|x| < 2^51` without a libm call (see [`round_ties_even`]).
#[inline]
pub fn floor_small(x: f64) -> f64 {
    let r = round_ties_even(x);
    if r > x {
        r - 1.0
    } else {
        r
    }
}

/// The lower lattice index of the SNORM cell holding `t`: `s` with `s <= t*q < s + 1`, clamped so
/// that `s + 1 <= q` (the cell `[s, s+1]` always exists).
#[inline]
pub fn snorm_floor(t: f64, bits: u32) -> i64 {
    let q = snorm_max(bits) as f64;
    floor_small(t * q).clamp(-q, q - 1.0) as i64
}

/// The value of SNORM integer `s`: `max(s/q, -1)`. Division (not a reciprocal multiply) keeps
/// `±1` and `0` exact.
#[inline]
pub fn snorm_value(s: i64, bits: u32) -> f64 {
    (s as f64 / snorm_max(bits) as f64).max(-1.0)
}

/// The digit `d < N` of the symmetric lattice point nearest to `t` in `[-1, 1]` (odd `N = 2h+1`,
/// value `(d - h)/h`; `radix.rs`): ties to even like [`snorm_round`], so `t ↦ -t` mirrors the
/// digit about `h`.
#[inline]
pub fn symmetric_round(t: f64, radix: u64) -> u64 {
    let h = ((radix - 1) / 2) as f64;
    (round_ties_even(t * h).clamp(-h, h) + h) as u64
}

/// The value `(d - h)/h` of digit `d` of an odd symmetric lattice of `N = 2h+1` points. Division
/// (not a reciprocal multiply) keeps `±1` and `0` exact.
#[inline]
pub fn symmetric_value(d: u64, radix: u64) -> f64 {
    let h = (radix - 1) / 2;
    (d as i64 - h as i64) as f64 / h as f64
}

/// Stores a signed integer in a `bits`-wide two's-complement field.
#[inline]
pub fn to_field(s: i64, bits: u32) -> u64 {
    (s as u64) & mask(bits)
}

/// Reads a `bits`-wide two's-complement field (sign-extends).
#[inline]
pub fn from_field(field: u64, bits: u32) -> i64 {
    let shift = 64 - bits;
    ((field << shift) as i64) >> shift
}

/// The low `bits` bits set (`bits <= 64`).
#[inline]
pub fn mask(bits: u32) -> u64 {
    if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    }
}

/// Extracts the `bits`-wide field at bit offset `shift`.
#[inline]
pub fn field(code: u64, shift: u32, bits: u32) -> u64 {
    (code >> shift) & mask(bits)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snorm_is_symmetric_and_exact_at_endpoints() {
        for bits in 2..=32 {
            let q = snorm_max(bits);
            assert_eq!(snorm_value(q, bits), 1.0);
            assert_eq!(snorm_value(-q, bits), -1.0);
            assert_eq!(snorm_value(-q - 1, bits), -1.0, "extra code decodes like -q");
            assert_eq!(snorm_value(0, bits), 0.0);
            assert_eq!(snorm_round(1.0, bits), q);
            assert_eq!(snorm_round(-1.0, bits), -q);
            assert_eq!(snorm_round(-0.0, bits), 0);
            for s in [-q - 1, -q, -1, 0, 1, q] {
                assert_eq!(from_field(to_field(s, bits), bits), s, "bits {bits} s {s}");
            }
        }
        // 8-bit SNORM as the GPU reads it: 127 -> 1, -127 and -128 -> -1.
        assert_eq!(snorm_value(from_field(0x80, 8), 8), -1.0);
        assert_eq!(snorm_value(from_field(0x7f, 8), 8), 1.0);
    }

    #[test]
    fn integer_rounding_matches_std() {
        let mut s = crate::rng::SplitMix64::new(5);
        let specials =
            [0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 0.49999999999999994, -0.49999999999999994, 0.0, -0.0, 1e15 + 0.5];
        for x in specials.into_iter().chain((0..100_000).map(|_| (s.next_f64() - 0.5) * 1e9)) {
            assert_eq!(round_ties_even(x), x.round_ties_even(), "{x}");
            assert_eq!(floor_small(x), x.floor(), "{x}");
        }
    }

    #[test]
    fn floor_brackets_the_value() {
        for bits in [4, 9, 16, 32] {
            let q = snorm_max(bits) as f64;
            for i in 0..=1000 {
                let t = -1.0 + 2.0 * i as f64 / 1000.0;
                let s = snorm_floor(t, bits);
                assert!(snorm_value(s, bits) <= t + 1e-15 && t <= snorm_value(s + 1, bits) + 1e-15, "{t} {s} {q}");
            }
        }
    }
}
