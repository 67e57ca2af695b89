//! Cube map (Meyer et al. 2010, §4, eq. 8): project onto the cube `[-1,1]^3` by dividing by the
//! largest magnitude, drop that coordinate (its axis and sign take the 3 face bits) and store the
//! other two, each in `[-1, 1]`, as SNORM fields (layout in `sextant.rs`); spacing `ε = 1/q`,
//! the paper's `2·2^(-(b-3)/2)`.

use super::fixed::{field, from_field, snorm_round, snorm_value, to_field};
use super::sextant::{face_from_index, face_index, face_of, minor_axes, FaceLayout};
use super::vec::{normalize, Dir};

/// Rounds the two cube-face coordinates in the domain.
#[inline]
pub fn encode(n: Dir, layout: FaceLayout) -> u64 {
    let (axis, negative) = face_of(n);
    let (i, j) = minor_axes(axis);
    let inv = 1.0 / n[axis].abs();
    let sa = snorm_round((n[i] * inv).clamp(-1.0, 1.0), layout.a_bits);
    let sb = snorm_round((n[j] * inv).clamp(-1.0, 1.0), layout.b_bits);
    face_index(axis, negative)
        | (to_field(sa, layout.a_bits) << 3)
        | (to_field(sb, layout.b_bits) << (3 + layout.a_bits))
}

/// Decodes any code to a unit direction.
#[inline]
pub fn decode(code: u64, layout: FaceLayout) -> Dir {
    let (axis, negative) = face_from_index(code & 7);
    let (i, j) = minor_axes(axis);
    let mut n = [0.0; 3];
    n[axis] = if negative { -1.0 } else { 1.0 };
    n[i] = snorm_value(from_field(field(code, 3, layout.a_bits), layout.a_bits), layout.a_bits);
    n[j] = snorm_value(from_field(field(code, 3 + layout.a_bits, layout.b_bits), layout.b_bits), layout.b_bits);
    normalize(n)
}
