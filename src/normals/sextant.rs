//! What sextant parallel projection and the cube map share: the face of the dominant axis and
//! their mixed-radix layout.
//!
//! Face index `f = 2·axis + (1 if the component is negative)`, axis 0 = x, 1 = y, 2 = z: the most
//! significant digit of `code = (f·N_a + a)·N_b + b` (`radix.rs`), so the six faces cost
//! `log2 6 ≈ 2.585` bits, not the paper's three whole bits. The other two components follow in
//! cyclic order: for x they are `(y, z)`, for y `(z, x)`, for z `(x, y)`. Ties between equal
//! largest magnitudes go to the lower axis (x before y before z).

use super::radix::{best_split, GridLayout, RadixRule};
use glam::DVec3;

/// The dominant axis of `n` and whether that component is negative.
#[inline]
pub fn face_of(n: DVec3) -> (usize, bool) {
    let (ax, ay, az) = (n.x.abs(), n.y.abs(), n.z.abs());
    let axis = if ax >= ay && ax >= az {
        0
    } else if ay >= az {
        1
    } else {
        2
    };
    (axis, n[axis] < 0.0)
}

/// The face digit of an axis and sign.
#[inline]
pub fn face_index(axis: usize, negative: bool) -> u64 {
    (2 * axis + usize::from(negative)) as u64
}

/// Axis and sign of a face digit (`< 6`).
#[inline]
pub fn face_from_index(index: u64) -> (usize, bool) {
    ((index >> 1) as usize, index & 1 == 1)
}

/// The two minor axes of `axis`, in cyclic order.
#[inline]
pub fn minor_axes(axis: usize) -> (usize, usize) {
    ((axis + 1) % 3, (axis + 2) % 3)
}

/// The six-face split of a `bits`-bit budget minimizing `objective` (`bounds::objective`):
/// `6·N_a·N_b ≤ 2^bits`, both odd, balanced near `N_a = N_b = sqrt(2^bits / 6)`.
pub fn layout(bits: u32, objective: impl Fn(f64, f64) -> f64) -> GridLayout {
    let balance = ((bits as f64).exp2() / 6.0).sqrt();
    let (a, b) = best_split(bits, 6, RadixRule::Odd, RadixRule::Odd, balance, objective);
    GridLayout { faces: 6, a, b }
}
