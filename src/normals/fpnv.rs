//! Floating-point normal vectors (Meyer et al. 2010, §3): three floats with `m`-bit mantissas,
//! rounded to nearest. Their worst angular error is eq. 3, reached by *direction* vectors whose
//! cell sits at the lower-left corner of a diagonal block (`c = (1/2+ε/2)(1,1,1)`, `ε = 2^(-m-1)`).
//! Unit-length vectors cannot sit there (a unit vector has no three components near 1/2), so
//! they stay below eq. 3: `--table` reports both (`table.rs`).

use super::metrics::angle_between;
use glam::DVec3;

/// A float format by mantissa width. The exponent range is taken as unbounded (the paper's
/// model); for binary16 and wider formats subnormal steps are far below the mantissa step at 1/2,
/// so the worst case is unaffected.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FloatFormat {
    /// Name, e.g. `binary32`.
    pub name: &'static str,
    /// Total width of one component in bits.
    pub width: u32,
    /// Explicit mantissa bits `m`.
    pub mantissa_bits: u32,
}

/// IEEE 754 binary32.
pub const BINARY32: FloatFormat = FloatFormat { name: "binary32", width: 32, mantissa_bits: 23 };

/// The IEEE-style format of one component when `bits` are split into three equal floats, if
/// there is a standard one: 8 → E4M3 (OCP FP8), 16 → binary16 (the paper's 48-bit column),
/// 32 → binary32, 64 → binary64.
pub fn format_for_budget(bits: u32) -> Option<FloatFormat> {
    if bits % 3 != 0 {
        return None;
    }
    match bits / 3 {
        8 => Some(FloatFormat { name: "fp8-e4m3", width: 8, mantissa_bits: 3 }),
        16 => Some(FloatFormat { name: "binary16", width: 16, mantissa_bits: 10 }),
        32 => Some(BINARY32),
        64 => Some(FloatFormat { name: "binary64", width: 64, mantissa_bits: 52 }),
        _ => None,
    }
}

/// Rounds `x` to the nearest float with an `m`-bit mantissa (ties to even), unbounded exponent.
/// Exact for `m <= 52` because every intermediate is a power-of-two scaling.
#[inline]
pub fn round_to_mantissa(x: f64, m: u32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    // x = f·2^e with f in [1, 2): the grid step at x is 2^(e-m).
    let e = x.abs().log2().floor() as i32;
    let mut e = e;
    // log2 can be off by one near powers of two; correct it exactly.
    if (x.abs() / 2f64.powi(e)) >= 2.0 {
        e += 1;
    } else if (x.abs() / 2f64.powi(e)) < 1.0 {
        e -= 1;
    }
    let scale = 2f64.powi(m as i32 - e);
    (x * scale).round_ties_even() / scale
}

/// Rounds each component of a direction.
#[inline]
pub fn round_dir(n: DVec3, m: u32) -> DVec3 {
    DVec3::new(round_to_mantissa(n.x, m), round_to_mantissa(n.y, m), round_to_mantissa(n.z, m))
}

/// The angular error of storing direction `n` with `m`-bit mantissas (for `m = 23` the cast to
/// `f32` itself is used).
#[inline]
pub fn error(n: DVec3, m: u32) -> f64 {
    let q = if m == 23 { n.map(|c| c as f32 as f64) } else { round_dir(n, m) };
    angle_between(n, q)
}

/// Adversarial direction vectors at the worst case of §3: near the centre
/// `c = (1/2+ε/2)(1,1,1)` of the lower-left cell of the diagonal block, nudged towards each of
/// the vertices `(1/2+ε, 1/2, 1/2)` (and permutations) so rounding picks that vertex; also the
/// same cells scaled by powers of two and mirrored (the error is invariant under both).
pub fn adversarial_directions(m: u32) -> Vec<DVec3> {
    let eps = (-(m as f64) - 1.0).exp2();
    let mut out = Vec::new();
    for scale in [1.0, 0.25, 8.0] {
        for axis in 0..3 {
            for sign in [1.0, -1.0] {
                let c = DVec3::splat(0.5 + 0.5 * eps);
                let mut v = DVec3::splat(0.5);
                v[axis] = 0.5 + eps;
                // 1e-6 of a cell towards v (representable in f64 for m <= 30): rounding goes to
                // v and the error is eq. 3's to within ~1e-6 relative.
                let t = if m <= 30 { 1e-6 } else { 1e-3 };
                out.push(sign * scale * (c + t * (v - c)));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mantissa_rounding_matches_hardware_casts() {
        let mut s = crate::rng::SplitMix64::new(11);
        for _ in 0..100_000 {
            let x = (s.next_f64() - 0.5) * 4.0;
            assert_eq!(round_to_mantissa(x, 23), x as f32 as f64, "{x}");
            assert_eq!(round_to_mantissa(x, 52), x);
        }
        assert_eq!(round_to_mantissa(1.0 + 3.0 * (-11f64).exp2(), 10), 1.0 + 4.0 * (-11f64).exp2());
        // tie to even
    }

    #[test]
    fn adversarial_vectors_reach_eq_3() {
        for m in [3, 10, 23] {
            let bound = crate::normals::bounds::fpnv(m);
            let worst = adversarial_directions(m).into_iter().map(|d| error(d, m)).fold(0.0, f64::max);
            assert!(worst <= bound * (1.0 + 1e-9), "m {m}: {worst} > {bound}");
            assert!(worst >= bound * 0.99999, "m {m}: {worst} far below {bound}");
        }
    }
}
