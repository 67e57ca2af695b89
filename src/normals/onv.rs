//! Octahedron normal vectors (Meyer et al. 2010, §5): project onto the octahedron `|x|+|y|+|z| = 1`
//! with the 1-norm, unfold the lower half onto the corners of the square `[-1,1]^2` (Fig. 2), and
//! store `[u, v]` as two SNORM fields.
//!
//! Two ways to pick the stored lattice point:
//! - **domain** rounding: round `u` and `v` independently (error bound eq. 10, `≈ 3ε/√2`);
//! - **range** rounding: of the four corners of the parameter cell holding `[u, v]`, keep the one
//!   whose decoded normal is closest to the input on the sphere (bound eq. 11, `≈ √2·ε`). The
//!   comparison never uses the largest dot product: at 24 bits and above the four candidates'
//!   cosines are equal in f32 (and at 64 bits even in f64), so the choice becomes arbitrary. It
//!   compares `sin²` of the angles, `|n×p|²/|p|²`, in f64 and cross-multiplied (no division, no
//!   normalization of the candidates): the cross product of two nearly parallel vectors keeps
//!   its relative accuracy where `1 - cos` cancels.
//!
//! Fold: for `z < 0` we unfold with `x = σ(u)(1-|v|)`, `y = σ(v)(1-|u|)` (Engelhardt &
//! Dachsbacher 2008; Cigolle et al. 2014), which is continuous across the fold `|u|+|v| = 1`
//! and across the square's border. Eq. 9 as printed in our copy of the paper swaps the signs
//! (`[σ(v)-v, σ(u)-u]`), which agrees in the first quadrant only and would tear the other three
//! fold edges apart; both unfold the same octahedron, ours keeps rounding across the fold local.

use super::fixed::{field, floor_small, from_field, round_ties_even, snorm_max, snorm_value, to_field};
use super::vec::{cross, dot, normalize, sign_not_zero, Dir};

/// Field widths of an ONV code: `u` in the low `u_bits`, `v` in the next `v_bits`
/// (`u_bits = ⌈b/2⌉`, `v_bits = ⌊b/2⌋`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OnvLayout {
    /// Width of the `u` field (low bits).
    pub u_bits: u32,
    /// Width of the `v` field (above `u`).
    pub v_bits: u32,
}

impl OnvLayout {
    /// The split of a `bits`-bit budget.
    pub fn new(bits: u32) -> Self {
        OnvLayout { u_bits: bits.div_ceil(2), v_bits: bits / 2 }
    }
}

/// The point `[u, v]` of the unfolded octahedron for a nonzero direction (need not be unit).
#[inline]
pub fn oct_from_dir(n: Dir) -> [f64; 2] {
    let inv_l1 = 1.0 / (n[0].abs() + n[1].abs() + n[2].abs());
    let (u, v) = (n[0] * inv_l1, n[1] * inv_l1);
    // Both branches are computed and one selected: the hemisphere of random normals is a coin
    // flip, which a branch would mispredict half the time.
    let (fu, fv) = ((1.0 - v.abs()) * sign_not_zero(u), (1.0 - u.abs()) * sign_not_zero(v));
    let lower = n[2] < 0.0;
    [if lower { fu } else { u }, if lower { fv } else { v }]
}

/// The point on the octahedron for `[u, v]` in `[-1,1]^2` (eq. 9 with the continuous fold).
#[inline]
pub fn octahedron_from_oct(p: [f64; 2]) -> Dir {
    let (u, v) = (p[0], p[1]);
    let z = 1.0 - u.abs() - v.abs();
    if z < 0.0 {
        [(1.0 - v.abs()) * sign_not_zero(u), (1.0 - u.abs()) * sign_not_zero(v), z]
    } else {
        [u, v, z]
    }
}

/// The unit normal for `[u, v]` (eq. 9, then 2-norm normalization).
#[inline]
pub fn dir_from_oct(p: [f64; 2]) -> Dir {
    normalize(octahedron_from_oct(p))
}

#[inline]
fn pack(su: i64, sv: i64, layout: OnvLayout) -> u64 {
    to_field(su, layout.u_bits) | (to_field(sv, layout.v_bits) << layout.u_bits)
}

/// The lattice integers `(s_u, s_v)` stored in a code.
#[inline]
pub fn unpack(code: u64, layout: OnvLayout) -> (i64, i64) {
    (
        from_field(field(code, 0, layout.u_bits), layout.u_bits),
        from_field(field(code, layout.u_bits, layout.v_bits), layout.v_bits),
    )
}

/// Per-layout constants of the encoders: `q` of each field and its reciprocal.
#[derive(Clone, Copy, Debug)]
struct Consts {
    qu: f64,
    qv: f64,
    ru: f64,
    rv: f64,
}

impl Consts {
    #[inline]
    fn new(layout: OnvLayout) -> Self {
        let (qu, qv) = (snorm_max(layout.u_bits) as f64, snorm_max(layout.v_bits) as f64);
        Consts { qu, qv, ru: 1.0 / qu, rv: 1.0 / qv }
    }
}

/// ONV_domain for one direction: the lattice integers (as f64) nearest to `[u, v]`.
#[inline(always)]
fn domain_lane(n: Dir, k: Consts) -> (f64, f64) {
    let p = oct_from_dir(n);
    (round_ties_even(p[0] * k.qu).clamp(-k.qu, k.qu), round_ties_even(p[1] * k.qv).clamp(-k.qv, k.qv))
}

/// `sin²` numerator and denominator of the angle between `n` and the octahedron point `(u, v)`:
/// `|n×p|²` and `|p|²` (eq. 9 unfolded branch-free: `x = u - σ(u)·max(-z, 0)`).
#[inline(always)]
fn sine2(n: Dir, u: f64, v: f64) -> (f64, f64) {
    let z = 1.0 - u.abs() - v.abs();
    let t = (-z).max(0.0);
    let x = u - if u >= 0.0 { t } else { -t };
    let y = v - if v >= 0.0 { t } else { -t };
    let c = cross(n, [x, y, z]);
    (dot(c, c), x * x + y * y + z * z)
}

/// ONV_range for one direction: the lattice integers (as f64) of the best of the four corners of
/// the parameter cell. Candidates are visited in the order (0,0), (1,0), (0,1), (1,1) and the
/// first strictly smaller one wins, so ties resolve the same way everywhere.
#[inline(always)]
fn range_lane(n: Dir, k: Consts) -> (f64, f64) {
    let p = oct_from_dir(n);
    let u0 = floor_small(p[0] * k.qu).clamp(-k.qu, k.qu - 1.0);
    let v0 = floor_small(p[1] * k.qv).clamp(-k.qv, k.qv - 1.0);
    // Candidate coordinates by a reciprocal multiply (the decoder divides; the two differ by at
    // most an ulp, which can only matter between exactly tied candidates).
    let (ua, ub) = (u0 * k.ru, (u0 + 1.0) * k.ru);
    let (va, vb) = (v0 * k.rv, (v0 + 1.0) * k.rv);
    let mut best = sine2(n, ua, va);
    let (mut du, mut dv) = (0.0, 0.0);
    for (cu, cv, u, v) in [(1.0, 0.0, ub, va), (0.0, 1.0, ua, vb), (1.0, 1.0, ub, vb)] {
        let cand = sine2(n, u, v);
        // sin²(cand) < sin²(best) without dividing: cand.0/cand.1 < best.0/best.1.
        let better = cand.0 * best.1 < best.0 * cand.1;
        best = if better { cand } else { best };
        du = if better { cu } else { du };
        dv = if better { cv } else { dv };
    }
    (u0 + du, v0 + dv)
}

/// ONV_domain: rounds `u` and `v` to the nearest lattice values.
#[inline]
pub fn encode_domain(n: Dir, layout: OnvLayout) -> u64 {
    let (su, sv) = domain_lane(n, Consts::new(layout));
    pack(su as i64, sv as i64, layout)
}

/// ONV_range (§5): of the four corners of the parameter cell holding the input, the one whose
/// decoded normal is nearest on the sphere. `n` need not be unit length (the `sin²` comparison
/// scales out).
#[inline]
pub fn encode_range(n: Dir, layout: OnvLayout) -> u64 {
    let (su, sv) = range_lane(n, Consts::new(layout));
    pack(su as i64, sv as i64, layout)
}

/// Batch encoder for f32 normals: blocks of 64 in structure-of-arrays form so the arithmetic
/// vectorizes; the same lane functions as [`encode_domain`] / [`encode_range`], so the codes are
/// identical.
pub fn encode_block_f32(normals: &[[f32; 3]], codes: &mut [u64], layout: OnvLayout, range: bool) {
    let k = Consts::new(layout);
    for (n, c) in normals.chunks(64).zip(codes.chunks_mut(64)) {
        let mut su = [0f64; 64];
        let mut sv = [0f64; 64];
        if range {
            for (i, d) in n.iter().enumerate() {
                (su[i], sv[i]) = range_lane(d.map(f64::from), k);
            }
        } else {
            for (i, d) in n.iter().enumerate() {
                (su[i], sv[i]) = domain_lane(d.map(f64::from), k);
            }
        }
        for (i, c) in c.iter_mut().enumerate() {
            *c = pack(su[i] as i64, sv[i] as i64, layout);
        }
    }
}

/// The f32 decoder of the batch path for codes of at most 32 bits (fields of at most 16 bits,
/// exact in f32), written branch-free like the shader decoders: `x = u - σ(u)·max(-z, 0)` is
/// eq. 9's fold `σ(u)(1-|v|)` rewritten. It differs from [`decode`] rounded to f32 by a few
/// f32 ulps (< 3e-7 rad, tested), far below the 32-bit code's own error (≥ 4e-5 rad).
#[inline]
pub fn decode_f32(code: u64, layout: OnvLayout) -> [f32; 3] {
    let (ku, kv) = (layout.u_bits, layout.v_bits);
    let c = code as u32;
    let su = ((c << (32 - ku)) as i32) >> (32 - ku);
    let sv = (((c >> ku) << (32 - kv)) as i32) >> (32 - kv);
    let u = (su as f32 / ((1u32 << (ku - 1)) - 1) as f32).max(-1.0);
    let v = (sv as f32 / ((1u32 << (kv - 1)) - 1) as f32).max(-1.0);
    let z = 1.0 - u.abs() - v.abs();
    let t = (-z).max(0.0);
    let x = u - if u >= 0.0 { t } else { -t };
    let y = v - if v >= 0.0 { t } else { -t };
    let inv = 1.0 / (x * x + y * y + z * z).sqrt();
    [x * inv, y * inv, z * inv]
}

/// Decodes any code to a unit normal.
#[inline]
pub fn decode(code: u64, layout: OnvLayout) -> Dir {
    let (su, sv) = unpack(code, layout);
    dir_from_oct([snorm_value(su, layout.u_bits), snorm_value(sv, layout.v_bits)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fold_is_continuous() {
        // On the fold |u|+|v| = 1 both branches of eq. 9 give the same point (z = 0).
        for i in 0..=64 {
            let u = -1.0 + i as f64 / 32.0;
            for sv in [-1.0, 1.0] {
                let v = sv * (1.0 - u.abs());
                let upper = [u, v, 0.0];
                let lower = [(1.0 - v.abs()) * sign_not_zero(u), (1.0 - u.abs()) * sign_not_zero(v), 0.0];
                assert_eq!(upper, lower, "u {u} v {v}");
            }
        }
        // The square's border is identified with its mirror image: (1, v) ~ (1, -v).
        for i in 0..=16 {
            let v = i as f64 / 16.0;
            assert_eq!(octahedron_from_oct([1.0, v]), octahedron_from_oct([1.0, -v]));
            assert_eq!(octahedron_from_oct([v, -1.0]), octahedron_from_oct([-v, -1.0]));
        }
    }

    #[test]
    fn inverse_on_the_octahedron() {
        let mut state = 7u64;
        for _ in 0..10_000 {
            let n = crate::normals::rng::uniform_direction(&mut state);
            let p = oct_from_dir(n);
            let m = dir_from_oct(p);
            assert!(crate::normals::vec::distance_squared(n, m) < 1e-28, "{n:?}");
        }
    }

    #[test]
    fn f32_batch_decoder_matches_the_f64_decoder() {
        let mut state = 3u64;
        for bits in 8..=32 {
            let layout = OnvLayout::new(bits);
            for _ in 0..20_000 {
                let code = crate::normals::rng::next_u64(&mut state) & crate::normals::fixed::mask(bits);
                let a = decode(code, layout);
                let b = decode_f32(code, layout).map(f64::from);
                assert!(crate::normals::vec::angle_between(a, b) < 3e-7, "{bits} {code:#x}");
            }
        }
    }

    #[test]
    fn range_choice_by_sine_matches_choice_by_chord() {
        // Reference: the slow, obviously right rule (normalize, compare squared chords).
        let mut state = 13u64;
        for bits in [8, 16, 24, 32, 48, 64] {
            let layout = OnvLayout::new(bits);
            for _ in 0..20_000 {
                let n = crate::normals::rng::uniform_direction(&mut state);
                let p = oct_from_dir(n);
                let (u0, v0) = (
                    crate::normals::fixed::snorm_floor(p[0], layout.u_bits),
                    crate::normals::fixed::snorm_floor(p[1], layout.v_bits),
                );
                let best = [(u0, v0), (u0 + 1, v0), (u0, v0 + 1), (u0 + 1, v0 + 1)]
                    .into_iter()
                    .map(|(su, sv)| {
                        let q = dir_from_oct([snorm_value(su, layout.u_bits), snorm_value(sv, layout.v_bits)]);
                        crate::normals::vec::distance_squared(n, q)
                    })
                    .fold(f64::INFINITY, f64::min);
                let got = crate::normals::vec::distance_squared(n, decode(encode_range(n, layout), layout));
                assert!(got <= best * (1.0 + 1e-6) + 1e-30, "{bits}: {got:e} vs {best:e}");
            }
        }
    }

    #[test]
    fn lattice_corners_and_axes_are_exact() {
        for bits in [8, 16, 17, 32, 48, 64] {
            let layout = OnvLayout::new(bits);
            for axis in 0..3 {
                for sign in [1.0, -1.0] {
                    let mut n = [0.0; 3];
                    n[axis] = sign;
                    assert_eq!(decode(encode_domain(n, layout), layout), n, "bits {bits} axis {n:?}");
                    assert_eq!(decode(encode_range(n, layout), layout), n, "bits {bits} axis {n:?}");
                }
            }
            let q = snorm_max(layout.u_bits);
            // All four corners of the square are -Z.
            for (a, b) in [(q, q), (-q, q), (q, -q), (-q, -q)] {
                let c = to_field(a, layout.u_bits)
                    | (to_field(b * snorm_max(layout.v_bits) / q, layout.v_bits) << layout.u_bits);
                assert_eq!(decode(c, layout), [0.0, 0.0, -1.0]);
            }
        }
    }
}
