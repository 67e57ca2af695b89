//! Closed intervals [lo, hi] of reals with outward rounding.
//!
//! Every result is rounded outwards so the exact mathematical result, and the value the point
//! (`f64`) evaluation of the same expression computes, both lie inside. Basic operations are
//! correctly rounded in IEEE 754, so one ulp (`next_down`/`next_up`) suffices; the elementary
//! functions of the platform libm (glibc: < 1 ulp for exp/log/sin/cos) are widened by
//! [`LIBM_ULPS`] ulps. Infinite endpoints mean "unbounded"; `0 × ∞` is taken as 0 (set semantics).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Ulps by which results of libm functions (exp, ln, sin, cos, powf) are widened.
pub const LIBM_ULPS: u32 = 2;

/// A bound ≥ `x` one ulp above it (infinities and NaN are kept). Results never fall in the
/// subnormal range: near 0 the bound is 0 or the smallest normal number instead (a computed
/// result in [−MIN_POSITIVE, 0) comes from an exact value < 0, one in [0, MIN_POSITIVE) from
/// one < MIN_POSITIVE). Subnormal operands make the arithmetic that follows many times slower,
/// and `up(0)` is frequent (rounding errors of exact operations).
#[inline]
pub fn up(x: f64) -> f64 {
    if (-f64::MIN_POSITIVE..f64::MIN_POSITIVE).contains(&x) {
        if x < 0.0 {
            0.0
        } else {
            f64::MIN_POSITIVE
        }
    } else if x.is_finite() {
        x.next_up()
    } else {
        x
    }
}

/// A bound ≤ `x` one ulp below it; the mirror image of [`up`].
#[inline]
pub fn down(x: f64) -> f64 {
    -up(-x)
}

/// `n` ulps towards −∞.
pub fn down_by(mut x: f64, n: u32) -> f64 {
    for _ in 0..n {
        x = down(x);
    }
    x
}

/// `n` ulps towards +∞.
pub fn up_by(mut x: f64, n: u32) -> f64 {
    for _ in 0..n {
        x = up(x);
    }
    x
}

/// Product with `0 × ±∞ = 0` (a zero factor from a degenerate interval annihilates an unbounded one).
#[inline]
fn mul0(a: f64, b: f64) -> f64 {
    if a == 0.0 || b == 0.0 {
        0.0
    } else {
        a * b
    }
}

/// A closed interval; `lo <= hi` always (NaN never enters: operations map it to [`Interval::ENTIRE`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
}

// Named methods (not operator traits): every call site reads as the arithmetic it performs,
// and the same names serve the `Real` trait.
#[allow(clippy::should_implement_trait)]
impl Interval {
    /// The whole real line: the conservative answer when nothing better is known.
    pub const ENTIRE: Interval = Interval { lo: f64::NEG_INFINITY, hi: f64::INFINITY };

    /// `[lo, hi]`; a NaN endpoint or `lo > hi` gives [`Interval::ENTIRE`] (never a panic).
    pub fn new(lo: f64, hi: f64) -> Interval {
        if lo.is_nan() || hi.is_nan() || lo > hi {
            Interval::ENTIRE
        } else {
            Interval { lo, hi }
        }
    }

    /// The degenerate interval `[x, x]`.
    pub fn point(x: f64) -> Interval {
        Interval::new(x, x)
    }

    /// Smallest interval holding both.
    pub fn hull(self, o: Interval) -> Interval {
        Interval { lo: self.lo.min(o.lo), hi: self.hi.max(o.hi) }
    }

    /// Intersection; both must hold the same value, so an empty result (impossible for correct
    /// bounds) falls back to the hull rather than inventing a value.
    pub fn intersect(self, o: Interval) -> Interval {
        let (lo, hi) = (self.lo.max(o.lo), self.hi.min(o.hi));
        if lo <= hi {
            Interval { lo, hi }
        } else {
            self.hull(o)
        }
    }

    /// `hi − lo` rounded up.
    pub fn width(self) -> f64 {
        up(self.hi - self.lo)
    }

    /// Midpoint (not rounded outward: a representative, not a bound).
    pub fn mid(self) -> f64 {
        if self.lo.is_finite() && self.hi.is_finite() {
            0.5 * self.lo + 0.5 * self.hi
        } else if self.lo.is_finite() {
            self.lo
        } else if self.hi.is_finite() {
            self.hi
        } else {
            0.0
        }
    }

    /// Both endpoints finite.
    pub fn is_finite(self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }

    /// `lo <= x <= hi`.
    pub fn contains(self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    /// `lo == hi`.
    pub fn is_point(self) -> bool {
        self.lo == self.hi
    }

    /// Sum.
    pub fn add(self, o: Interval) -> Interval {
        Interval::new(down(self.lo + o.lo), up(self.hi + o.hi))
    }

    /// Difference.
    pub fn sub(self, o: Interval) -> Interval {
        Interval::new(down(self.lo - o.hi), up(self.hi - o.lo))
    }

    /// Negation (exact).
    pub fn neg(self) -> Interval {
        Interval { lo: -self.hi, hi: -self.lo }
    }

    /// Product: the extremes are among the four endpoint products.
    pub fn mul(self, o: Interval) -> Interval {
        let p = [mul0(self.lo, o.lo), mul0(self.lo, o.hi), mul0(self.hi, o.lo), mul0(self.hi, o.hi)];
        let lo = p.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Interval::new(down(lo), up(hi))
    }

    /// Square (non-negative, tighter than `x * x` when x straddles 0).
    pub fn sqr(self) -> Interval {
        let (a, b) = (self.lo.abs(), self.hi.abs());
        let hi = up(mul0(a.max(b), a.max(b)));
        let lo = if self.lo <= 0.0 && self.hi >= 0.0 { 0.0 } else { down(mul0(a.min(b), a.min(b))).max(0.0) };
        Interval::new(lo, hi)
    }

    /// Quotient with the language's rule `x / 0 = 0`: a divisor range that contains 0 (other than
    /// exactly `[0, 0]`) gives [`Interval::ENTIRE`] unless the dividend is exactly 0
    /// (`docs/shading-language.md`, "Division by zero").
    pub fn div(self, o: Interval) -> Interval {
        if o.lo == 0.0 && o.hi == 0.0 || self.lo == 0.0 && self.hi == 0.0 {
            return Interval::point(0.0);
        }
        if o.lo <= 0.0 && o.hi >= 0.0 {
            return Interval::ENTIRE;
        }
        let q = [self.lo / o.lo, self.lo / o.hi, self.hi / o.lo, self.hi / o.hi];
        if q.iter().any(|v| v.is_nan()) {
            return Interval::ENTIRE;
        }
        let lo = q.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = q.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Interval::new(down(lo), up(hi))
    }

    /// `sqrt(max(x, 0))` (the language clamps the argument; sqrt is correctly rounded).
    pub fn sqrt(self) -> Interval {
        let lo = down(self.lo.max(0.0).sqrt()).max(0.0);
        let hi = up(self.hi.max(0.0).sqrt());
        Interval::new(lo, hi)
    }

    /// `exp(x)` (monotone).
    pub fn exp(self) -> Interval {
        Interval::new(down_by(self.lo.exp(), LIBM_ULPS).max(0.0), up_by(self.hi.exp(), LIBM_ULPS))
    }

    /// `ln(max(x, f64::MIN_POSITIVE))` (monotone; the language clamps the argument so `log` is finite).
    pub fn ln(self) -> Interval {
        let f = |x: f64| x.max(f64::MIN_POSITIVE).ln();
        Interval::new(down_by(f(self.lo), LIBM_ULPS), up_by(f(self.hi), LIBM_ULPS))
    }

    /// `sin(x)`: endpoint values plus ±1 wherever a maximum (π/2 + 2kπ) or minimum (−π/2 + 2kπ)
    /// lies in the range. The test for an extremum is widened so a rounding error can only add
    /// one (which is conservative), never miss one.
    pub fn sin(self) -> Interval {
        periodic_extremes(self, f64::sin, FRAC_PI_2, -FRAC_PI_2)
    }

    /// `cos(x)`: maxima at 2kπ, minima at π + 2kπ.
    pub fn cos(self) -> Interval {
        periodic_extremes(self, f64::cos, 0.0, PI)
    }

    /// `|x|`.
    pub fn abs(self) -> Interval {
        if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            self.neg()
        } else {
            Interval { lo: 0.0, hi: (-self.lo).max(self.hi) }
        }
    }

    /// `min(x, y)` (monotone in both).
    pub fn min(self, o: Interval) -> Interval {
        Interval { lo: self.lo.min(o.lo), hi: self.hi.min(o.hi) }
    }

    /// `max(x, y)`.
    pub fn max(self, o: Interval) -> Interval {
        Interval { lo: self.lo.max(o.lo), hi: self.hi.max(o.hi) }
    }

    /// `floor(x)` (monotone, exact).
    pub fn floor(self) -> Interval {
        Interval { lo: self.lo.floor(), hi: self.hi.floor() }
    }

    /// A value known only to lie in `[lo, hi]` of `x`, scaled: `k * x` for a constant `k`.
    pub fn scale(self, k: f64) -> Interval {
        self.mul(Interval::point(k))
    }
}

/// Range of a 2π-periodic function over `x` given where its maxima and minima sit.
fn periodic_extremes(x: Interval, f: fn(f64) -> f64, max_at: f64, min_at: f64) -> Interval {
    if !x.is_finite() || x.hi - x.lo >= TAU {
        return Interval { lo: -1.0, hi: 1.0 };
    }
    let (a, b) = (f(x.lo), f(x.hi));
    let mut lo = down_by(a.min(b), LIBM_ULPS).max(-1.0);
    let mut hi = up_by(a.max(b), LIBM_ULPS).min(1.0);
    // Slack covering the rounding of k·2π + offset and of the division below.
    let slack = 1e-9 * (1.0 + x.lo.abs().max(x.hi.abs()));
    let hits = |at: f64| {
        // Smallest k with at + 2kπ >= lo − slack; is that point <= hi + slack?
        let k = ((x.lo - slack - at) / TAU).ceil();
        at + k * TAU <= x.hi + slack
    };
    if hits(max_at) {
        hi = 1.0;
    }
    if hits(min_at) {
        lo = -1.0;
    }
    Interval { lo, hi }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sin_over_a_maximum_reaches_one() {
        let r = Interval::new(1.0, 2.0).sin();
        assert_eq!(r.hi, 1.0);
        assert!(r.lo <= 1.0f64.sin() && r.lo > 0.84);
    }

    #[test]
    fn division_by_range_with_zero_is_entire() {
        assert_eq!(Interval::new(1.0, 2.0).div(Interval::new(-1.0, 1.0)), Interval::ENTIRE);
        assert_eq!(Interval::new(1.0, 2.0).div(Interval::point(0.0)), Interval::point(0.0));
        let q = Interval::new(1.0, 2.0).div(Interval::new(4.0, 8.0));
        assert!(q.lo <= 0.125 && q.hi >= 0.5 && q.hi < 0.5000001);
    }

    #[test]
    fn zero_times_entire_is_zero() {
        let z = Interval::point(0.0).mul(Interval::ENTIRE);
        assert!(z.contains(0.0) && z.width() < 1e-300);
    }
}
