//! The number trait the shading-language interpreter is generic over, and the semantics every
//! arithmetic shares (`docs/shading-language.md`): the `f64` implementation *defines* each
//! operation; [`Interval`] and [`Affine`] return guaranteed enclosures of it over their range.
//!
//! Total semantics (no NaN from the language's own operations):
//! - `x / 0 = 0` (as in OSL); a divisor *range* containing 0 gives an unbounded enclosure;
//! - `sqrt(x) = sqrt(max(x, 0))`, `log(x) = ln(max(x, f64::MIN_POSITIVE))`;
//! - `pow(x, n)` for an integer constant |n| ≤ 64 is sign(x)ⁿ·|x|ⁿ; any other exponent uses
//!   `max(x, 0)` as the base (`pow(0, y < 0) = +∞`).

use super::approx::{self, fade_point, fade_slack, powi_point, smooth01_point};
use super::form::Affine;
use super::interval::{down_by, up_by, Interval, LIBM_ULPS};

/// What is known about the sign of a value over its range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sign {
    /// Negative everywhere.
    Negative,
    /// Zero or positive everywhere.
    NonNegative,
    /// Both occur (only for ranges).
    Both,
}

/// Largest |n| for which `pow(x, n)` uses the signed integer power.
pub const MAX_INTEGER_POWER: f64 = 64.0;

/// A number type of the shading language: `f64` (point sampling), [`Interval`] or [`Affine`]
/// (area sampling with guaranteed bounds).
pub trait Real: Clone + PartialEq + std::fmt::Debug + Send + Sync + 'static {
    /// Name for reports: `point`, `interval`, `affine`.
    const NAME: &'static str;
    /// An exact constant.
    fn constant(x: f64) -> Self;
    /// A value known to lie in `iv` (for f64, the midpoint: only called on ranges).
    fn from_interval(iv: Interval) -> Self;
    /// An input that ranges over [lo, hi] (u, v of an area sample); for `f64` the midpoint.
    fn input(lo: f64, hi: f64) -> Self;
    /// Guaranteed bounds of the value.
    fn bounds(&self) -> Interval;
    /// The value if it is one exactly known number.
    fn as_constant(&self) -> Option<f64>;
    /// `self + o`.
    fn add(&self, o: &Self) -> Self;
    /// `self − o`.
    fn sub(&self, o: &Self) -> Self;
    /// `self · o`.
    fn mul(&self, o: &Self) -> Self;
    /// `self · self` (a value times itself: non-negative, tighter than a product of two
    /// independent values with the same range).
    fn sqr(&self) -> Self;
    /// `self / o` with `x / 0 = 0`.
    fn div(&self, o: &Self) -> Self;
    /// `−self`.
    fn neg(&self) -> Self;
    /// `sqrt(max(x, 0))`.
    fn sqrt(&self) -> Self;
    /// `exp(x)`.
    fn exp(&self) -> Self;
    /// `ln(max(x, f64::MIN_POSITIVE))`.
    fn ln(&self) -> Self;
    /// `sin(x)`.
    fn sin(&self) -> Self;
    /// `cos(x)`.
    fn cos(&self) -> Self;
    /// `|x|`.
    fn abs(&self) -> Self;
    /// `floor(x)`.
    fn floor(&self) -> Self;
    /// `min(x, o)`.
    fn min(&self, o: &Self) -> Self;
    /// `max(x, o)`.
    fn max(&self, o: &Self) -> Self;
    /// `pow(x, o)` (module docs).
    fn pow(&self, o: &Self) -> Self;
    /// 1 if x ≥ 0, else 0.
    fn step0(&self) -> Self;
    /// Hermite smoothstep of clamp(x, 0, 1).
    fn smooth01(&self) -> Self;
    /// Perlin's quintic fade 6t⁵ − 15t⁴ + 10t³ (a univariate primitive so that area
    /// arithmetics approximate it as a whole, not as a chain of products).
    fn fade(&self) -> Self;
    /// A value that may be `self` or `o` (both branches of a condition over a range).
    fn join(&self, o: &Self) -> Self;
    /// The central value and the guaranteed range of a value that depends to first order on
    /// the inputs (an affine form); `None` for points and intervals. Multivariate primitives
    /// (gradient noise) then use a first-order Taylor extension ([`Real::taylor`]) instead of
    /// evaluating their formula operation by operation.
    fn first_order(&self) -> Option<(f64, Interval)> {
        None
    }
    /// Whether two first-order values depend on a common noise symbol (are correlated).
    fn shares_symbols(&self, o: &Self) -> bool {
        let _ = o;
        false
    }
    /// f(x₁, …, xₙ) ∈ `value` + Σ gₖ·(xₖ − cₖ) ± `delta` for `(xₖ, cₖ, gₖ)` in `xs`: the caller
    /// has bounded the remainder of the expansion at c by `delta` over the whole range of the
    /// xₖ; the result lies in `iv`. Only called when every xₖ has [`Real::first_order`].
    fn taylor(xs: &[(&Self, f64, f64)], value: f64, delta: f64, iv: Interval) -> Self {
        let _ = (xs, value, delta);
        Self::from_interval(iv)
    }
    /// The sign over the whole range.
    fn sign(&self) -> Sign {
        let b = self.bounds();
        if b.hi < 0.0 {
            Sign::Negative
        } else if b.lo >= 0.0 {
            Sign::NonNegative
        } else {
            Sign::Both
        }
    }
}

/// The point semantics of `pow`.
pub fn pow_point(x: f64, y: f64) -> f64 {
    if y.fract() == 0.0 && y.abs() <= MAX_INTEGER_POWER {
        powi_point(x, y as i32)
    } else {
        x.max(0.0).powf(y)
    }
}

impl Real for f64 {
    const NAME: &'static str = "point";
    fn constant(x: f64) -> Self {
        x
    }
    fn from_interval(iv: Interval) -> Self {
        iv.mid()
    }
    fn input(lo: f64, hi: f64) -> Self {
        0.5 * (lo + hi)
    }
    fn bounds(&self) -> Interval {
        Interval::point(*self)
    }
    fn as_constant(&self) -> Option<f64> {
        Some(*self)
    }
    fn add(&self, o: &Self) -> Self {
        self + o
    }
    fn sub(&self, o: &Self) -> Self {
        self - o
    }
    fn mul(&self, o: &Self) -> Self {
        self * o
    }
    fn sqr(&self) -> Self {
        self * self
    }
    fn div(&self, o: &Self) -> Self {
        if *o == 0.0 {
            0.0
        } else {
            self / o
        }
    }
    fn neg(&self) -> Self {
        -self
    }
    fn sqrt(&self) -> Self {
        f64::max(*self, 0.0).sqrt()
    }
    fn exp(&self) -> Self {
        f64::exp(*self)
    }
    fn ln(&self) -> Self {
        f64::max(*self, f64::MIN_POSITIVE).ln()
    }
    fn sin(&self) -> Self {
        f64::sin(*self)
    }
    fn cos(&self) -> Self {
        f64::cos(*self)
    }
    fn abs(&self) -> Self {
        f64::abs(*self)
    }
    fn floor(&self) -> Self {
        f64::floor(*self)
    }
    fn min(&self, o: &Self) -> Self {
        f64::min(*self, *o)
    }
    fn max(&self, o: &Self) -> Self {
        f64::max(*self, *o)
    }
    fn pow(&self, o: &Self) -> Self {
        pow_point(*self, *o)
    }
    fn step0(&self) -> Self {
        if *self >= 0.0 {
            1.0
        } else {
            0.0
        }
    }
    fn smooth01(&self) -> Self {
        smooth01_point(*self)
    }
    fn fade(&self) -> Self {
        fade_point(*self)
    }
    fn join(&self, _o: &Self) -> Self {
        // A point condition is never ambiguous, so the interpreter never joins points.
        *self
    }
    fn sign(&self) -> Sign {
        if *self < 0.0 {
            Sign::Negative
        } else {
            Sign::NonNegative
        }
    }
}

/// Interval extension of `pow` (module docs): monotone pieces for a constant exponent, the
/// corners of the box (plus x⁰ = 1) otherwise — x^y is monotone in x for fixed y and in y for
/// fixed x > 0.
pub fn pow_interval(x: Interval, y: Interval) -> Interval {
    let widen = |lo: f64, hi: f64| {
        if lo.is_nan() || hi.is_nan() {
            Interval::ENTIRE
        } else {
            Interval::new(down_by(lo, LIBM_ULPS + 1), up_by(hi, LIBM_ULPS + 1))
        }
    };
    let hull = |v: &[f64]| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        widen(lo, hi)
    };
    if y.is_point() && y.lo.fract() == 0.0 && y.lo.abs() <= MAX_INTEGER_POWER {
        let n = y.lo as i32;
        if n < 0 && x.lo <= 0.0 && x.hi >= 0.0 {
            return Interval::ENTIRE;
        }
        let mut v = vec![powi_point(x.lo, n), powi_point(x.hi, n)];
        if x.lo < 0.0 && x.hi > 0.0 {
            v.push(powi_point(0.0, n));
        }
        return hull(&v);
    }
    let (b0, b1) = (x.lo.max(0.0), x.hi.max(0.0));
    let mut v = vec![b0.powf(y.lo), b0.powf(y.hi), b1.powf(y.lo), b1.powf(y.hi)];
    if y.lo <= 0.0 && y.hi >= 0.0 {
        v.push(1.0);
    }
    // A varying exponent that takes an integer value uses the signed power there:
    // ±|x|^y, bounded by the corners of the |x| × y box.
    let first_int = y.lo.max(-MAX_INTEGER_POWER).ceil();
    if x.lo < 0.0 && first_int <= y.hi.min(MAX_INTEGER_POWER) {
        let ax = x.abs();
        for c in [ax.lo.powf(y.lo), ax.lo.powf(y.hi), ax.hi.powf(y.lo), ax.hi.powf(y.hi)] {
            v.push(c);
            v.push(-c);
        }
    }
    hull(&v)
}

fn smooth01_interval(x: Interval) -> Interval {
    Interval::new(down_by(smooth01_point(x.lo), 4), up_by(smooth01_point(x.hi), 4))
}

/// fade is monotone increasing (f' = 30t²(t − 1)² ≥ 0).
fn fade_interval(x: Interval) -> Interval {
    let s = fade_slack(x.lo.abs().max(x.hi.abs()));
    Interval::new(down_by(fade_point(x.lo) - s, 1), up_by(fade_point(x.hi) + s, 1))
}

fn step0_interval(x: Interval) -> Interval {
    Interval::new(x.lo.step0(), x.hi.step0())
}

impl Real for Interval {
    const NAME: &'static str = "interval";
    fn constant(x: f64) -> Self {
        Interval::point(x)
    }
    fn from_interval(iv: Interval) -> Self {
        iv
    }
    fn input(lo: f64, hi: f64) -> Self {
        Interval::new(lo, hi)
    }
    fn bounds(&self) -> Interval {
        *self
    }
    fn as_constant(&self) -> Option<f64> {
        self.is_point().then_some(self.lo)
    }
    fn add(&self, o: &Self) -> Self {
        match (self.as_constant(), o.as_constant()) {
            (Some(a), Some(b)) => Interval::point(a + b),
            _ => Interval::add(*self, *o),
        }
    }
    fn sub(&self, o: &Self) -> Self {
        match (self.as_constant(), o.as_constant()) {
            (Some(a), Some(b)) => Interval::point(a - b),
            _ => Interval::sub(*self, *o),
        }
    }
    fn mul(&self, o: &Self) -> Self {
        match (self.as_constant(), o.as_constant()) {
            (Some(a), Some(b)) => Interval::point(a * b),
            _ => Interval::mul(*self, *o),
        }
    }
    fn sqr(&self) -> Self {
        match self.as_constant() {
            Some(a) => Interval::point(a * a),
            None => Interval::sqr(*self),
        }
    }
    fn div(&self, o: &Self) -> Self {
        match (self.as_constant(), o.as_constant()) {
            (Some(a), Some(b)) => Interval::point(Real::div(&a, &b)),
            _ => Interval::div(*self, *o),
        }
    }
    fn neg(&self) -> Self {
        Interval::neg(*self)
    }
    fn sqrt(&self) -> Self {
        match self.as_constant() {
            Some(c) => Interval::point(Real::sqrt(&c)),
            None => Interval::sqrt(*self),
        }
    }
    fn exp(&self) -> Self {
        match self.as_constant() {
            Some(c) => Interval::point(Real::exp(&c)),
            None => Interval::exp(*self),
        }
    }
    fn ln(&self) -> Self {
        match self.as_constant() {
            Some(c) => Interval::point(Real::ln(&c)),
            None => Interval::ln(*self),
        }
    }
    fn sin(&self) -> Self {
        match self.as_constant() {
            Some(c) => Interval::point(Real::sin(&c)),
            None => Interval::sin(*self),
        }
    }
    fn cos(&self) -> Self {
        match self.as_constant() {
            Some(c) => Interval::point(Real::cos(&c)),
            None => Interval::cos(*self),
        }
    }
    fn abs(&self) -> Self {
        Interval::abs(*self)
    }
    fn floor(&self) -> Self {
        Interval::floor(*self)
    }
    fn min(&self, o: &Self) -> Self {
        Interval::min(*self, *o)
    }
    fn max(&self, o: &Self) -> Self {
        Interval::max(*self, *o)
    }
    fn pow(&self, o: &Self) -> Self {
        match (self.as_constant(), o.as_constant()) {
            (Some(a), Some(b)) => Interval::point(pow_point(a, b)),
            _ => pow_interval(*self, *o),
        }
    }
    fn step0(&self) -> Self {
        step0_interval(*self)
    }
    fn smooth01(&self) -> Self {
        match self.as_constant() {
            Some(c) => Interval::point(smooth01_point(c)),
            None => smooth01_interval(*self),
        }
    }
    fn fade(&self) -> Self {
        match self.as_constant() {
            Some(c) => Interval::point(fade_point(c)),
            None => fade_interval(*self),
        }
    }
    fn join(&self, o: &Self) -> Self {
        self.hull(*o)
    }
}

impl Affine {
    /// max(x, 0) via the paper's max⁰ approximation.
    fn max0(&self) -> Affine {
        let r = self.range();
        self.apply(approx::max0(r.lo, r.hi), r.max(Interval::point(0.0)))
    }

    fn unary(
        &self,
        point: fn(f64) -> f64,
        iv: fn(Interval) -> Interval,
        ap: fn(f64, f64) -> Option<approx::Approx>,
    ) -> Affine {
        if let Some(c) = self.as_constant() {
            return Affine::constant(point(c));
        }
        let r = self.range();
        self.apply(ap(r.lo, r.hi), iv(r))
    }
}

impl Real for Affine {
    const NAME: &'static str = "affine";
    fn constant(x: f64) -> Self {
        Affine::constant(x)
    }
    fn from_interval(iv: Interval) -> Self {
        Affine::from_interval(iv)
    }
    fn input(lo: f64, hi: f64) -> Self {
        // û = u₀ + (Δu/2)·ε (§3.1); node corners are dyadic, so centre and radius are exact
        // (otherwise the interval is enclosed with outward rounding).
        let (c, r) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        if c - r == lo && c + r == hi {
            Affine::symbol(c, r)
        } else {
            Affine::from_interval(Interval::new(lo, hi))
        }
    }
    fn bounds(&self) -> Interval {
        self.range()
    }
    fn as_constant(&self) -> Option<f64> {
        Affine::as_constant(self)
    }
    fn add(&self, o: &Self) -> Self {
        Affine::add(self, o)
    }
    fn sub(&self, o: &Self) -> Self {
        Affine::sub(self, o)
    }
    fn mul(&self, o: &Self) -> Self {
        Affine::mul(self, o)
    }
    fn sqr(&self) -> Self {
        Affine::sqr(self)
    }
    fn div(&self, o: &Self) -> Self {
        Affine::div(self, o)
    }
    fn neg(&self) -> Self {
        Affine::neg(self)
    }
    fn sqrt(&self) -> Self {
        if let Some(c) = self.as_constant() {
            return Affine::constant(Real::sqrt(&c));
        }
        let base = if self.range().lo < 0.0 { self.max0() } else { self.clone() };
        let r = base.range();
        base.apply(approx::sqrt(r.lo.max(0.0), r.hi.max(0.0)), r.sqrt())
    }
    fn exp(&self) -> Self {
        self.unary(f64::exp, Interval::exp, approx::exp)
    }
    fn ln(&self) -> Self {
        if let Some(c) = self.as_constant() {
            return Affine::constant(Real::ln(&c));
        }
        let tiny = f64::MIN_POSITIVE;
        let base = if self.range().lo < tiny { Real::max(self, &Affine::constant(tiny)) } else { self.clone() };
        let r = base.range();
        base.apply(approx::ln(r.lo.max(tiny), r.hi.max(tiny)), r.ln())
    }
    fn sin(&self) -> Self {
        self.unary(f64::sin, Interval::sin, approx::sin)
    }
    fn cos(&self) -> Self {
        self.unary(f64::cos, Interval::cos, approx::cos)
    }
    fn abs(&self) -> Self {
        self.unary(f64::abs, Interval::abs, approx::abs)
    }
    fn floor(&self) -> Self {
        self.unary(f64::floor, Interval::floor, approx::floor)
    }
    fn min(&self, o: &Self) -> Self {
        if let (Some(a), Some(b)) = (self.as_constant(), o.as_constant()) {
            return Affine::constant(a.min(b));
        }
        // One operand below the other over the whole range: min is that operand, exactly.
        let (rx, ro) = (self.range(), o.range());
        if rx.hi <= ro.lo {
            return self.clone();
        }
        if ro.hi <= rx.lo {
            return o.clone();
        }
        // min(x, y) = x − max⁰(x − y).
        let mut z = self.sub(&self.sub(o).max0());
        z = z.with_interval(self.range().min(o.range()));
        z
    }
    fn max(&self, o: &Self) -> Self {
        if let (Some(a), Some(b)) = (self.as_constant(), o.as_constant()) {
            return Affine::constant(a.max(b));
        }
        let (rx, ro) = (self.range(), o.range());
        if rx.lo >= ro.hi {
            return self.clone();
        }
        if ro.lo >= rx.hi {
            return o.clone();
        }
        // max(x, y) = y + max⁰(x − y) (§3).
        let z = o.add(&self.sub(o).max0());
        z.with_interval(self.range().max(o.range()))
    }
    fn pow(&self, o: &Self) -> Self {
        if let (Some(a), Some(b)) = (self.as_constant(), o.as_constant()) {
            return Affine::constant(pow_point(a, b));
        }
        let r = self.range();
        let iv = pow_interval(r, o.range());
        let Some(p) = o.as_constant() else { return Affine::from_interval(iv) };
        if p.fract() == 0.0 && p.abs() <= MAX_INTEGER_POWER {
            return self.apply(approx::powi(r.lo, r.hi, p as i32), iv);
        }
        let base = if r.lo < 0.0 { self.max0() } else { self.clone() };
        let rb = base.range();
        base.apply(approx::powf(rb.lo.max(0.0), rb.hi.max(0.0), p), iv)
    }
    fn step0(&self) -> Self {
        self.unary(|x| x.step0(), step0_interval, approx::step0)
    }
    fn smooth01(&self) -> Self {
        self.unary(smooth01_point, smooth01_interval, approx::smooth01)
    }
    fn fade(&self) -> Self {
        self.unary(fade_point, fade_interval, approx::fade)
    }
    fn join(&self, o: &Self) -> Self {
        Affine::join(self, o)
    }
    fn first_order(&self) -> Option<(f64, Interval)> {
        (!self.is_unbounded()).then(|| (self.centre(), self.range()))
    }
    fn shares_symbols(&self, o: &Self) -> bool {
        Affine::shares_symbols(self, o)
    }
    fn taylor(xs: &[(&Self, f64, f64)], value: f64, delta: f64, iv: Interval) -> Self {
        Affine::taylor(xs, value, delta, iv)
    }
}
