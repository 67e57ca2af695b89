//! Mixed-radix codes: the whole bit budget for schemes whose alphabet is not a power of two.
//!
//! A cube map has 6 faces, which need `log2 6 ≈ 2.585` bits, not 3 (Meyer et al. 2010, §4, spend
//! three whole bits, "two states remain unused", but their Table 1 uses the fractional budget).
//! So SPP, CM, PP and SC store one number
//!
//! ```text
//! code = (face · N_a + a) · N_b + b,      F · N_a · N_b ≤ 2^bits,
//! ```
//!
//! with `face < F` (6 faces, 2 hemispheres for PP, 1 for SC) and two coordinate digits
//! `a < N_a`, `b < N_b` whose radices are chosen freely — not as powers of two — to minimize the
//! scheme's closed-form maximum error ([`best_split`], objectives in `bounds.rs`). Decoding is
//! `b = code mod N_b`, `a = ⌊code / N_b⌋ mod N_a`, `face = min(⌊code / (N_a N_b)⌋, F - 1)`; the
//! `2^bits - F·N_a·N_b` codes above the last valid one are never written and decode like the last
//! face, so every code decodes.
//!
//! ONV is not mixed-radix: its alphabet is `2^⌈b/2⌉ × 2^⌊b/2⌋` and its SNORM bit fields are what
//! GPUs unpack natively (`onv.rs`).

use serde::{Deserialize, Serialize};

/// How a digit's integer `d < radix` is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DigitKind {
    /// A `log2(radix)`-bit two's-complement SNORM field (ONV): value `max(s / q, -1)`,
    /// `q = radix/2 - 1` (`fixed.rs`).
    Snorm,
    /// A symmetric lattice over `[-1, 1]` with an odd number `N = 2h + 1` of points: value
    /// `(d - h) / h`, so `-1`, `0` and `+1` are exact.
    Symmetric,
    /// A fraction of a full turn: value `d / N` (periodic).
    Turns,
    /// One of `radix` alternatives (cube face `2·axis + negative`, hemisphere).
    Index,
}

impl DigitKind {
    /// The name used in JSON and in shader comments.
    pub fn name(self) -> &'static str {
        match self {
            DigitKind::Snorm => "snorm",
            DigitKind::Symmetric => "symmetric",
            DigitKind::Turns => "turns",
            DigitKind::Index => "index",
        }
    }
}

/// One digit of a code.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Digit {
    /// Name (`u`, `v`, `theta`, `phi`, `x`, `y`, `a`, `b`, `face`, `z_negative`).
    pub name: String,
    /// Number of values `N`; the code is `Σ d_i · Π_{j<i} N_j` over the digits, lowest first.
    pub radix: u64,
    /// How the integer is read.
    pub kind: DigitKind,
}

/// A mixed-radix layout: `F` faces, then coordinate digits of radices `N_a` and `N_b`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridLayout {
    /// Number of faces `F` (the most significant digit).
    pub faces: u64,
    /// Radix `N_a` of the middle digit.
    pub a: u64,
    /// Radix `N_b` of the least significant digit.
    pub b: u64,
}

impl GridLayout {
    /// `(face · N_a + a) · N_b + b` (the caller keeps each digit below its radix).
    #[inline]
    pub fn pack(&self, face: u64, a: u64, b: u64) -> u64 {
        (face * self.a + a) * self.b + b
    }

    /// `(face, a, b)` of any code; codes past the last valid one give `face = F - 1`.
    #[inline]
    pub fn unpack(&self, code: u64) -> (u64, u64, u64) {
        let (rest, b) = (code / self.b, code % self.b);
        ((rest / self.a).min(self.faces - 1), rest % self.a, b)
    }
}

/// Which radices a coordinate digit may have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RadixRule {
    /// Odd, at least 3: a [`DigitKind::Symmetric`] lattice with `0` and `±1` exact.
    Odd,
    /// A multiple of 4, at least 4: quarter turns exact (SC's `φ`: ±X, ±Y exact).
    QuarterTurns,
}

impl RadixRule {
    /// The largest allowed radix `<= n`, if any.
    fn at_most(self, n: u128) -> Option<u64> {
        let n = n.min(u64::MAX as u128) as u64;
        let r = match self {
            RadixRule::Odd => n - (1 - n % 2),
            RadixRule::QuarterTurns => n - n % 4,
        };
        (r >= self.min()).then_some(r)
    }

    fn min(self) -> u64 {
        match self {
            RadixRule::Odd => 3,
            RadixRule::QuarterTurns => 4,
        }
    }

    fn step(self) -> u64 {
        match self {
            RadixRule::Odd => 2,
            RadixRule::QuarterTurns => 4,
        }
    }
}

/// The radices `(N_a, N_b)` with `faces · N_a · N_b ≤ 2^bits` that minimize `objective`.
///
/// `objective(N_a, N_b)` must be a strictly increasing function of the scheme's closed-form
/// `Δmax`, evaluated with `+ − × ÷ √` only (correctly rounded everywhere, so the split — part of
/// the code format — is the same on every platform), defined for real radices and decreasing in
/// each. `balance` is the real `N_a` where the two digits' errors are equal.
///
/// The search walks `N_a` down and up from `balance`. For a given `N_a` no allowed `N_b` beats the
/// real `N_b = M / N_a` (`M = ⌊2^bits / F⌋`), so `objective(N_a, M / N_a)` is a lower bound for
/// that `N_a`; along the hyperbola it grows away from the balance point, and the walk in each
/// direction stops once it reaches the best value found. Ties keep the first candidate (the
/// walk's order is fixed), so the result is deterministic.
pub fn best_split(
    bits: u32,
    faces: u64,
    rule_a: RadixRule,
    rule_b: RadixRule,
    balance: f64,
    objective: impl Fn(f64, f64) -> f64,
) -> (u64, u64) {
    let m = (1u128 << bits) / faces as u128;
    let lower_bound = |na: u64| objective(na as f64, m as f64 / na as f64);
    let mut best: Option<(f64, u64, u64)> = None;
    let mut consider = |na: u64| -> bool {
        if let Some((value, ..)) = best {
            if lower_bound(na) >= value {
                return false;
            }
        }
        if let Some(nb) = rule_b.at_most(m / na as u128) {
            let value = objective(na as f64, nb as f64);
            if best.is_none_or(|(v, ..)| value < v) {
                best = Some((value, na, nb));
            }
        }
        true
    };
    let start = rule_a.at_most(balance.max(0.0) as u128).unwrap_or(rule_a.min());
    let mut na = start;
    while na >= rule_a.min() && consider(na) {
        na -= rule_a.step();
    }
    let mut na = start + rule_a.step();
    while (na as u128) * (rule_b.min() as u128) <= m && consider(na) {
        na += rule_a.step();
    }
    let (_, na, nb) = best.expect("every budget of at least 8 bits fits 6 x 3 x 3 codes");
    (na, nb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pack_unpack_round_trip_and_invalid_codes_clamp_the_face() {
        let l = GridLayout { faces: 6, a: 7, b: 5 };
        for face in 0..6 {
            for a in 0..7 {
                for b in 0..5 {
                    assert_eq!(l.unpack(l.pack(face, a, b)), (face, a, b));
                }
            }
        }
        assert_eq!(l.faces * l.a * l.b, 210);
        // 210..=255 are never written: face 5.
        assert_eq!(l.unpack(210).0, 5);
        assert_eq!(l.unpack(255), (5, (255 / 5) % 7, 0));
    }

    #[test]
    fn search_finds_the_brute_force_optimum() {
        // Brute force over every pair at small budgets, for a symmetric objective and a lopsided
        // one: the walk must find the same minimum.
        let symmetric = |a: f64, b: f64| (1.0 / (a - 1.0)).powi(2) + (1.0 / (b - 1.0)).powi(2);
        let lopsided = |a: f64, b: f64| (2.0 / a).powi(2) + (1.0 / (b - 1.0)).powi(2);
        for bits in 8..=20 {
            for (faces, rule_a, rule_b) in
                [(6, RadixRule::Odd, RadixRule::Odd), (1, RadixRule::QuarterTurns, RadixRule::Odd)]
            {
                let objective =
                    |a: f64, b: f64| if rule_a == RadixRule::Odd { symmetric(a, b) } else { lopsided(a, b) };
                let m = (1u64 << bits) / faces;
                let mut brute = (f64::INFINITY, 0, 0);
                let mut na = rule_a.min();
                while na * rule_b.min() <= m {
                    if let Some(nb) = rule_b.at_most((m / na) as u128) {
                        let v = objective(na as f64, nb as f64);
                        if v < brute.0 {
                            brute = (v, na, nb);
                        }
                    }
                    na += rule_a.step();
                }
                let balance = if faces == 6 { (m as f64).sqrt() } else { (2.0 * m as f64).sqrt() };
                let (na, nb) = best_split(bits, faces, rule_a, rule_b, balance, objective);
                assert_eq!(objective(na as f64, nb as f64), brute.0, "{bits} bits, {faces} faces");
                assert!(faces as u128 * na as u128 * nb as u128 <= 1u128 << bits);
            }
        }
    }
}
