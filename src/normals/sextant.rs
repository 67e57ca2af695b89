//! What sextant parallel projection and the cube map share: the face of the dominant axis.
//!
//! Face index `f = 2·axis + (1 if the component is negative)`, axis 0 = x, 1 = y, 2 = z, stored in
//! 3 whole bits (the paper's accounting, §4: "three extra bits", two states unused). The other two
//! components follow in cyclic order: for x they are `(y, z)`, for y `(z, x)`, for z `(x, y)`.
//! Codes 6 and 7 are never written; they decode like faces 4 and 5 (axis clamped to z).
//! Ties between equal largest magnitudes go to the lower axis (x before y before z).

use super::vec::Dir;

/// The dominant axis of `n` and whether that component is negative.
#[inline]
pub fn face_of(n: Dir) -> (usize, bool) {
    let (ax, ay, az) = (n[0].abs(), n[1].abs(), n[2].abs());
    let axis = if ax >= ay && ax >= az {
        0
    } else if ay >= az {
        1
    } else {
        2
    };
    (axis, n[axis] < 0.0)
}

/// The face index stored in the low 3 bits.
#[inline]
pub fn face_index(axis: usize, negative: bool) -> u64 {
    (2 * axis + usize::from(negative)) as u64
}

/// Axis and sign of a stored face index (6 and 7 decode like 4 and 5).
#[inline]
pub fn face_from_index(index: u64) -> (usize, bool) {
    (((index >> 1) as usize).min(2), index & 1 == 1)
}

/// The two minor axes of `axis`, in cyclic order.
#[inline]
pub fn minor_axes(axis: usize) -> (usize, usize) {
    ((axis + 1) % 3, (axis + 2) % 3)
}

/// Field widths after the 3 face bits: `a` gets `⌈(b-3)/2⌉`, `b` gets `⌊(b-3)/2⌋`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaceLayout {
    /// Width of the first minor component's field (after the 3 face bits).
    pub a_bits: u32,
    /// Width of the second minor component's field.
    pub b_bits: u32,
}

impl FaceLayout {
    /// The split of a `bits`-bit budget.
    pub fn new(bits: u32) -> Self {
        FaceLayout { a_bits: (bits - 3).div_ceil(2), b_bits: (bits - 3) / 2 }
    }
}
