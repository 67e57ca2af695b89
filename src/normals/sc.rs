//! Spherical coordinates (Meyer et al. 2010, §4, eq. 5): `θ ∈ [0, π]` from +Z and `φ ∈ [0, 2π)`
//! from +X towards +Y (the prtkit frame).
//!
//! Mixed-radix code (`radix.rs`, one face): `code = j·N_θ + i` with `θ = π·i/(N_θ-1)` on an odd
//! lattice (poles and equator exact; stored as the symmetric digit of `t = 2θ/π - 1`) and
//! `φ = 2π·j/N_φ`, `N_φ` a multiple of 4 (periodic, ±X and ±Y exact). The radices minimize eq. 5
//! generalized to the two steps `π/(N_θ-1)` and `2π/N_φ`, which balances them: `N_φ ≈ 2·N_θ`
//! (the paper does not give its split). Encoding uses `atan2` for both angles (accurate at the
//! poles, where `acos(z)` is not).

use super::bounds::objective;
use super::fixed::{round_ties_even, symmetric_round, symmetric_value};
use super::radix::{best_split, GridLayout, RadixRule};
use super::vec::{sincos_half_pi, Dir};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// The split of a `bits`-bit budget: `N_a = N_φ`, `N_b = N_θ`.
pub fn layout(bits: u32) -> GridLayout {
    let balance = (2.0 * (bits as f64).exp2()).sqrt();
    let (n_phi, n_theta) = best_split(bits, 1, RadixRule::QuarterTurns, RadixRule::Odd, balance, objective::sc);
    GridLayout { faces: 1, a: n_phi, b: n_theta }
}

/// Step of `θ` in radians.
pub fn theta_step(l: GridLayout) -> f64 {
    PI / (l.b - 1) as f64
}

/// Step of `φ` in radians.
pub fn phi_step(l: GridLayout) -> f64 {
    TAU / l.a as f64
}

/// `(t, φ/(2π))` of a nonzero direction: `t = 2θ/π - 1 ∈ [-1, 1]`, `φ/(2π) ∈ [0, 1)`.
#[inline]
pub fn params_from_dir(n: Dir) -> (f64, f64) {
    let rho = n[0].hypot(n[1]);
    let theta = rho.atan2(n[2]);
    // At the poles φ is arbitrary; fix it to 0 so that (±0, ±0, ±1) all give one code.
    let mut phi = if rho == 0.0 { 0.0 } else { n[1].atan2(n[0]) };
    if phi < 0.0 {
        phi += TAU;
    }
    (theta / FRAC_PI_2 - 1.0, phi / TAU)
}

/// The unit direction at `(t, turns)`, exact on the axes: the angles are evaluated as quarter
/// turns with [`sincos_half_pi`].
#[inline]
pub fn dir_from_params(t: f64, turns: f64) -> Dir {
    // cos θ = -sin(tπ/2), sin θ = cos(tπ/2).
    let (s, c) = sincos_half_pi(t);
    let (cos_theta, sin_theta) = (-s, c);
    // φ in quarter turns: quadrant k and a remainder r ∈ [0, 1), rotated exactly by k·90°.
    let quarters = (turns - turns.floor()) * 4.0;
    let k = (quarters.floor() as i64).rem_euclid(4);
    let r = quarters - quarters.floor();
    let (sr, cr) = sincos_half_pi(r);
    let (cos_phi, sin_phi) = match k {
        0 => (cr, sr),
        1 => (-sr, cr),
        2 => (-cr, -sr),
        _ => (sr, -cr),
    };
    [sin_theta * cos_phi, sin_theta * sin_phi, cos_theta]
}

/// Rounds both angles in the parameter domain.
#[inline]
pub fn encode(n: Dir, l: GridLayout) -> u64 {
    let (t, turns) = params_from_dir(n);
    let i = symmetric_round(t, l.b);
    // turns < 1, so j <= N_φ; j = N_φ is φ = 2π, i.e. 0.
    let j = round_ties_even(turns * l.a as f64) as u64 % l.a;
    l.pack(0, j, i)
}

/// Decodes any code to a unit direction.
#[inline]
pub fn decode(code: u64, l: GridLayout) -> Dir {
    let (_, j, i) = l.unpack(code);
    dir_from_params(symmetric_value(i, l.b), j as f64 / l.a as f64)
}
