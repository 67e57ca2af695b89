//! Parallel projection with a sign bit (Meyer et al. 2010, §4, eq. 6): store `x` and `y`,
//! rebuild `|z| = sqrt(1 - x² - y²)`, and keep the sign of `z` in one bit. Unstable near the
//! equator (`‖∇z‖ → ∞`), which is why its error is `O(√ε)`.
//!
//! Layout: bit 0 is the sign of `z` (1 = negative; `-0.0` counts as positive), then `x` as a
//! SNORM field of `⌈(b-1)/2⌉` bits, then `y` of `⌊(b-1)/2⌋` bits. Lattice points outside the unit
//! disk decode to `z = 0` and are renormalized, so every code decodes to a unit vector.

use super::fixed::{field, from_field, snorm_round, snorm_value, to_field};
use super::vec::{normalize, Dir};

/// Field widths of a PP code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PpLayout {
    /// Width of the `x` field (after the sign bit).
    pub x_bits: u32,
    /// Width of the `y` field (after `x`).
    pub y_bits: u32,
}

impl PpLayout {
    /// The split of a `bits`-bit budget.
    pub fn new(bits: u32) -> Self {
        PpLayout { x_bits: (bits - 1).div_ceil(2), y_bits: (bits - 1) / 2 }
    }
}

/// Rounds `x` and `y` of the unit direction in the domain.
#[inline]
pub fn encode(n: Dir, layout: PpLayout) -> u64 {
    let negative = u64::from(n[2] < 0.0);
    let sx = snorm_round(n[0], layout.x_bits);
    let sy = snorm_round(n[1], layout.y_bits);
    negative | (to_field(sx, layout.x_bits) << 1) | (to_field(sy, layout.y_bits) << (1 + layout.x_bits))
}

/// Decodes any code to a unit direction.
#[inline]
pub fn decode(code: u64, layout: PpLayout) -> Dir {
    let x = snorm_value(from_field(field(code, 1, layout.x_bits), layout.x_bits), layout.x_bits);
    let y = snorm_value(from_field(field(code, 1 + layout.x_bits, layout.y_bits), layout.y_bits), layout.y_bits);
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    let z = if code & 1 == 1 { -z } else { z };
    if x == 0.0 && y == 0.0 {
        // Exactly a pole (z = ±1 exactly, no rounding through sqrt).
        return [0.0, 0.0, if code & 1 == 1 { -1.0 } else { 1.0 }];
    }
    normalize([x, y, z])
}
