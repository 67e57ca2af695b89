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
use glam::DVec3;
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

/// `(sin(t·π/2), cos(t·π/2))` for `t` in `[-1, 1]`, exact at `t ∈ {-1, 0, 1}`: the argument is
/// reduced by the complement identity so the results hit `0` and `±1` exactly (`cos(π/2)` in
/// floating point is 6e-17, which would tilt the poles of spherical coordinates).
#[inline]
pub fn sincos_half_pi(t: f64) -> (f64, f64) {
    if t.abs() <= 0.5 {
        (t * FRAC_PI_2).sin_cos()
    } else {
        // sin(tπ/2) = σ(t)·cos((1-|t|)π/2), cos(tπ/2) = sin((1-|t|)π/2); 1-|t| is exact here.
        let (s, c) = ((1.0 - t.abs()) * FRAC_PI_2).sin_cos();
        (c.copysign(t), s)
    }
}

/// `(t, φ/(2π))` of a nonzero direction: `t = 2θ/π - 1 ∈ [-1, 1]`, `φ/(2π) ∈ [0, 1)`.
#[inline]
pub fn params_from_dir(n: DVec3) -> (f64, f64) {
    let rho = n.x.hypot(n.y);
    let theta = rho.atan2(n.z);
    // At the poles φ is arbitrary; fix it to 0 so that (±0, ±0, ±1) all give one code.
    let mut phi = if rho == 0.0 { 0.0 } else { n.y.atan2(n.x) };
    if phi < 0.0 {
        phi += TAU;
    }
    (theta / FRAC_PI_2 - 1.0, phi / TAU)
}

/// The unit direction at `(t, turns)`, exact on the axes: the angles are evaluated as quarter
/// turns with [`sincos_half_pi`].
#[inline]
pub fn dir_from_params(t: f64, turns: f64) -> DVec3 {
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
    DVec3::new(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta)
}

/// Rounds both angles in the parameter domain.
#[inline]
pub fn encode(n: DVec3, l: GridLayout) -> u64 {
    let (t, turns) = params_from_dir(n);
    let i = symmetric_round(t, l.b);
    // turns < 1, so j <= N_φ; j = N_φ is φ = 2π, i.e. 0.
    let j = round_ties_even(turns * l.a as f64) as u64 % l.a;
    l.pack(0, j, i)
}

/// Decodes any code to a unit direction.
#[inline]
pub fn decode(code: u64, l: GridLayout) -> DVec3 {
    let (_, j, i) = l.unpack(code);
    dir_from_params(symmetric_value(i, l.b), j as f64 / l.a as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sincos_exact_at_quarter_turns() {
        assert_eq!(sincos_half_pi(0.0), (0.0, 1.0));
        assert_eq!(sincos_half_pi(1.0), (1.0, 0.0));
        assert_eq!(sincos_half_pi(-1.0), (-1.0, 0.0));
        for i in 0..=200 {
            let t = -1.0 + i as f64 / 100.0;
            let (s, c) = sincos_half_pi(t);
            let (s0, c0) = (t * FRAC_PI_2).sin_cos();
            assert!((s - s0).abs() < 1e-15 && (c - c0).abs() < 1e-15, "{t}");
        }
    }
}
