//! Spherical coordinates (Meyer et al. 2010, §4, eq. 5): `θ ∈ [0, π]` from +Z and `φ ∈ [0, 2π)`
//! from +X towards +Y (the prtkit frame).
//!
//! Split (the paper does not spell its own out): `θ` gets the low `⌊b/2⌋` bits as a SNORM field
//! `t` with `θ = (t+1)·π/2` (poles and equator exact), `φ` the high `⌈b/2⌉` bits as an unsigned
//! fraction of a full turn, `φ = 2π·j/2^bφ` (periodic, so all codes are used and ±X, ±Y exact).
//! Both steps are then `≈ π·2^(1-b/2)`: θ covers half the angle of φ with one bit less of
//! lattice. Encoding uses `atan2` for both angles (accurate at the poles, where `acos(z)` is not).

use super::fixed::{field, from_field, mask, snorm_max, snorm_round, snorm_value, to_field};
use super::vec::{sincos_half_pi, Dir};
use std::f64::consts::{FRAC_PI_2, TAU};

/// Field widths of an SC code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ScLayout {
    /// Width of the SNORM `θ` field (low bits).
    pub theta_bits: u32,
    /// Width of the unsigned `φ` field (high bits).
    pub phi_bits: u32,
}

impl ScLayout {
    /// The split of a `bits`-bit budget.
    pub fn new(bits: u32) -> Self {
        ScLayout { theta_bits: bits / 2, phi_bits: bits.div_ceil(2) }
    }
    /// Step of `θ` in radians.
    pub fn theta_step(&self) -> f64 {
        FRAC_PI_2 / snorm_max(self.theta_bits) as f64
    }
    /// Step of `φ` in radians.
    pub fn phi_step(&self) -> f64 {
        TAU / (1u64 << self.phi_bits) as f64
    }
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
pub fn encode(n: Dir, layout: ScLayout) -> u64 {
    let (t, turns) = params_from_dir(n);
    let st = snorm_round(t, layout.theta_bits);
    let j = ((turns * (1u64 << layout.phi_bits) as f64).round() as u64) & mask(layout.phi_bits);
    to_field(st, layout.theta_bits) | (j << layout.theta_bits)
}

/// Decodes any code to a unit direction.
#[inline]
pub fn decode(code: u64, layout: ScLayout) -> Dir {
    let st = from_field(field(code, 0, layout.theta_bits), layout.theta_bits);
    let j = field(code, layout.theta_bits, layout.phi_bits);
    dir_from_params(snorm_value(st, layout.theta_bits), j as f64 / (1u64 << layout.phi_bits) as f64)
}
