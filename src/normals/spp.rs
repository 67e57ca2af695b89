//! Sextant parallel projection (Meyer et al. 2010, §4, eq. 7): store the two smaller components
//! and rebuild the largest, `|m| = sqrt(1 - a² - b²)`, whose axis and sign take 3 face bits.
//!
//! The minor components satisfy `|a|, |b| <= 1/√2` (equality at `a = m`, `b = 0`), so each is
//! stored as a SNORM field of `√2·a` (layout in `sextant.rs`); spacing `ε = √2/(2^k - 2)`, the
//! paper's `√2·2^(-(b-3)/2)`.

use super::fixed::{field, from_field, snorm_round, snorm_value, to_field};
use super::sextant::{face_from_index, face_index, face_of, minor_axes, FaceLayout};
use super::vec::{normalize, Dir};
use std::f64::consts::{FRAC_1_SQRT_2, SQRT_2};

/// Rounds the two minor components of the unit direction in the domain.
#[inline]
pub fn encode(n: Dir, layout: FaceLayout) -> u64 {
    let (axis, negative) = face_of(n);
    let (i, j) = minor_axes(axis);
    let sa = snorm_round((n[i] * SQRT_2).clamp(-1.0, 1.0), layout.a_bits);
    let sb = snorm_round((n[j] * SQRT_2).clamp(-1.0, 1.0), layout.b_bits);
    face_index(axis, negative)
        | (to_field(sa, layout.a_bits) << 3)
        | (to_field(sb, layout.b_bits) << (3 + layout.a_bits))
}

/// Decodes any code to a unit direction.
#[inline]
pub fn decode(code: u64, layout: FaceLayout) -> Dir {
    let (axis, negative) = face_from_index(code & 7);
    let (i, j) = minor_axes(axis);
    let a = FRAC_1_SQRT_2 * snorm_value(from_field(field(code, 3, layout.a_bits), layout.a_bits), layout.a_bits);
    let b = FRAC_1_SQRT_2
        * snorm_value(from_field(field(code, 3 + layout.a_bits, layout.b_bits), layout.b_bits), layout.b_bits);
    let mut n = [0.0; 3];
    if a == 0.0 && b == 0.0 {
        n[axis] = if negative { -1.0 } else { 1.0 };
        return n;
    }
    let m = (1.0 - a * a - b * b).max(0.0).sqrt();
    n[axis] = if negative { -m } else { m };
    n[i] = a;
    n[j] = b;
    normalize(n)
}
