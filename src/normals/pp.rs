//! Parallel projection with a sign bit (Meyer et al. 2010, §4, eq. 6): store `x` and `y`,
//! rebuild `|z| = sqrt(1 - x² - y²)`, and keep the sign of `z`. Unstable near the equator
//! (`‖∇z‖ → ∞`), which is why its error is `O(√ε)`.
//!
//! Mixed-radix code (`radix.rs`): `code = (negative·N_x + x)·N_y + y` with 2 "faces" (the sign of
//! `z`, 1 = negative; `-0.0` counts as positive) and odd symmetric lattices for `x` and `y`, whose
//! radices minimize eq. 6 for the split (`bounds::pp_split`), `2·N_x·N_y ≤ 2^b`: the budget is
//! not cut into whole bits for each coordinate. Lattice points outside the unit disk decode to
//! `z = 0` and are renormalized, so every code decodes to a unit vector.

use super::bounds::objective;
use super::fixed::{symmetric_round, symmetric_value};
use super::radix::{best_split, GridLayout, RadixRule};
use glam::DVec3;

/// The split of a `bits`-bit budget: `N_a = N_x`, `N_b = N_y`.
pub fn layout(bits: u32) -> GridLayout {
    let balance = (0.5 * (bits as f64).exp2()).sqrt();
    let (nx, ny) = best_split(bits, 2, RadixRule::Odd, RadixRule::Odd, balance, objective::cm_pp);
    GridLayout { faces: 2, a: nx, b: ny }
}

/// Rounds `x` and `y` of the unit direction in the domain.
#[inline]
pub fn encode(n: DVec3, l: GridLayout) -> u64 {
    let negative = u64::from(n.z < 0.0);
    l.pack(negative, symmetric_round(n.x, l.a), symmetric_round(n.y, l.b))
}

/// Decodes any code to a unit direction.
#[inline]
pub fn decode(code: u64, l: GridLayout) -> DVec3 {
    let (negative, dx, dy) = l.unpack(code);
    let (x, y) = (symmetric_value(dx, l.a), symmetric_value(dy, l.b));
    if x == 0.0 && y == 0.0 {
        // Exactly a pole (z = ±1 exactly, no rounding through sqrt).
        return DVec3::new(0.0, 0.0, if negative == 1 { -1.0 } else { 1.0 });
    }
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    DVec3::new(x, y, if negative == 1 { -z } else { z }).normalize()
}
