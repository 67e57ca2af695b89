//! Sextant parallel projection (Meyer et al. 2010, §4, eq. 7): store the two smaller components
//! and rebuild the largest, `|m| = sqrt(1 - a² - b²)`, whose axis and sign are the face digit.
//!
//! The minor components satisfy `|a|, |b| <= 1/√2` (equality at `a = m`, `b = 0`), so each is
//! stored as the odd symmetric lattice digit of `√2·a` (mixed-radix layout in `sextant.rs`), with
//! radices minimizing eq. 7 for the split (`bounds::spp_split`); spacing `ε = √2/(N-1)`.

use super::bounds::objective;
use super::fixed::{symmetric_round, symmetric_value};
use super::radix::GridLayout;
use super::sextant::{face_from_index, face_index, face_of, minor_axes};
use glam::DVec3;
use std::f64::consts::{FRAC_1_SQRT_2, SQRT_2};

/// The split of a `bits`-bit budget.
pub fn layout(bits: u32) -> GridLayout {
    super::sextant::layout(bits, objective::spp)
}

/// Rounds the two minor components of the unit direction in the domain.
#[inline]
pub fn encode(n: DVec3, l: GridLayout) -> u64 {
    let (axis, negative) = face_of(n);
    let (i, j) = minor_axes(axis);
    let a = symmetric_round((n[i] * SQRT_2).clamp(-1.0, 1.0), l.a);
    let b = symmetric_round((n[j] * SQRT_2).clamp(-1.0, 1.0), l.b);
    l.pack(face_index(axis, negative), a, b)
}

/// Decodes any code to a unit direction.
#[inline]
pub fn decode(code: u64, l: GridLayout) -> DVec3 {
    let (face, da, db) = l.unpack(code);
    let (axis, negative) = face_from_index(face);
    let (i, j) = minor_axes(axis);
    let a = FRAC_1_SQRT_2 * symmetric_value(da, l.a);
    let b = FRAC_1_SQRT_2 * symmetric_value(db, l.b);
    let mut n = DVec3::ZERO;
    if a == 0.0 && b == 0.0 {
        n[axis] = if negative { -1.0 } else { 1.0 };
        return n;
    }
    let m = (1.0 - a * a - b * b).max(0.0).sqrt();
    n[axis] = if negative { -m } else { m };
    n[i] = a;
    n[j] = b;
    n.normalize()
}
