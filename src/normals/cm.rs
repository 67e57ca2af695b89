//! Cube map (Meyer et al. 2010, §4, eq. 8): project onto the cube `[-1,1]^3` by dividing by the
//! largest magnitude, drop that coordinate (its axis and sign are the face digit) and store the
//! other two, each in `[-1, 1]`, as odd symmetric lattices (mixed-radix layout in `sextant.rs`)
//! whose radices minimize eq. 8 for the split (`bounds::cm_split`).

use super::bounds::objective;
use super::fixed::{symmetric_round, symmetric_value};
use super::radix::GridLayout;
use super::sextant::{face_from_index, face_index, face_of, minor_axes};
use glam::DVec3;

/// The split of a `bits`-bit budget.
pub fn layout(bits: u32) -> GridLayout {
    super::sextant::layout(bits, objective::cm_pp)
}

/// Rounds the two cube-face coordinates in the domain.
#[inline]
pub fn encode(n: DVec3, l: GridLayout) -> u64 {
    let (axis, negative) = face_of(n);
    let (i, j) = minor_axes(axis);
    let inv = 1.0 / n[axis].abs();
    let a = symmetric_round((n[i] * inv).clamp(-1.0, 1.0), l.a);
    let b = symmetric_round((n[j] * inv).clamp(-1.0, 1.0), l.b);
    l.pack(face_index(axis, negative), a, b)
}

/// Decodes any code to a unit direction.
#[inline]
pub fn decode(code: u64, l: GridLayout) -> DVec3 {
    let (face, a, b) = l.unpack(code);
    let (axis, negative) = face_from_index(face);
    let (i, j) = minor_axes(axis);
    let mut n = DVec3::ZERO;
    n[axis] = if negative { -1.0 } else { 1.0 };
    n[i] = symmetric_value(a, l.a);
    n[j] = symmetric_value(b, l.b);
    n.normalize()
}
