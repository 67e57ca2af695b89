//! Affine forms x̂ = x₀ + Σᵢ xᵢ·εᵢ + e·η (Comba & Stolfi 1993; Heidrich, Slusallek & Seidel
//! 1998, §2.1): the εᵢ ∈ [−1, 1] are noise symbols shared between forms (so dependencies
//! cancel), e ≥ 0 collects floating-point rounding errors on a symbol η private to this form.
//! Each form also carries an interval enclosure computed by interval arithmetic alongside
//! (Stolfi's mixed mode): the range used for approximations and reported as bounds is the
//! intersection of the two.
//!
//! Non-affine operations add one new noise symbol carrying the approximation error (§3).
//! Forms longer than [`MAX_TERMS`] are condensed: the smallest terms are replaced by one new
//! symbol with the sum of their magnitudes (sound: a new symbol that is a function of old ones
//! still ranges in [−1, 1], and every operation is conservative over the whole hypercube).

use super::approx::{self, Approx, UNIT_ROUNDOFF};
use super::interval::{up, Interval};
use std::cell::Cell;

/// A form with more terms than this is condensed down to [`KEEP_TERMS`].
pub const MAX_TERMS: usize = 24;
/// Terms kept (the largest) when condensing.
pub const KEEP_TERMS: usize = 12;

/// (symbol, coefficient) pairs.
type Terms = Vec<(u64, f64)>;

/// Rounding allowance per computed coefficient: u for the form's own rounding plus u for the
/// rounding the point (`f64`) evaluation of the same operation makes, with margin for the
/// accumulated magnitude sum.
const ROUND: f64 = 2.5 * UNIT_ROUNDOFF;

thread_local! {
    static NEXT_SYMBOL: Cell<u64> = const { Cell::new(1) };
}

/// A new noise symbol: ids increase, so appending one keeps a term list sorted. Ids are only
/// compared within one evaluation on one thread, so results do not depend on the thread.
fn fresh_symbol() -> u64 {
    NEXT_SYMBOL.with(|n| {
        let id = n.get();
        n.set(id + 1);
        id
    })
}

/// An affine form with its mixed-mode interval.
#[derive(Clone, Debug)]
pub struct Affine {
    centre: f64,
    /// (symbol, coefficient), sorted by symbol, no zero coefficients.
    terms: Terms,
    /// Upper bound of Σ|xᵢ|, kept up to date by every operation so that the range is O(1)
    /// (`+∞` or NaN when a coefficient is not finite).
    rad: f64,
    /// Rounding error on a private symbol; `+∞` marks an unbounded form (only `iv` is meaningful).
    err: f64,
    iv: Interval,
}

/// Equal value representations (`rad` is derived from the terms and not compared).
impl PartialEq for Affine {
    fn eq(&self, o: &Affine) -> bool {
        self.centre == o.centre && self.err == o.err && self.iv == o.iv && self.terms == o.terms
    }
}

/// Upper bound of a plain left-to-right sum `s` of `n` non-negative numbers: its relative
/// error is ≤ (n−1)u.
fn sum_bound(s: f64, n: usize) -> f64 {
    up(s * (1.0 + (n as f64 + 1.0) * UNIT_ROUNDOFF))
}

/// Upper bound of a sum of non-negative numbers.
fn sum_up(values: impl Iterator<Item = f64>) -> f64 {
    let (mut s, mut n) = (0.0, 0usize);
    for v in values {
        s += v;
        n += 1;
    }
    sum_bound(s, n)
}

/// Rounding error bound for results whose magnitudes sum to `mags`, `n` of them (the absolute
/// term covers products that underflow, each off by at most half the smallest subnormal; it is
/// a normal number so that no subnormal arithmetic follows).
fn rounding(mags: f64, n: usize) -> f64 {
    up(mags * ROUND) + n as f64 * f64::MIN_POSITIVE
}

#[allow(clippy::should_implement_trait)]
impl Affine {
    /// The exact constant `x`.
    pub fn constant(x: f64) -> Affine {
        let err = if x.is_finite() { 0.0 } else { f64::INFINITY };
        Affine { centre: x, terms: Terms::new(), rad: 0.0, err, iv: Interval::point(x) }
    }

    /// `centre + radius·ε` for a new symbol ε (the inputs u, v of an area sample, §3.1:
    /// û = u₀ + (Δu/2)·ε₁). Exact: no rounding happens.
    pub fn symbol(centre: f64, radius: f64) -> Affine {
        let mut terms = Terms::new();
        if radius != 0.0 {
            terms.push((fresh_symbol(), radius));
        }
        let iv = Interval::new(centre, centre).add(Interval::new(-radius.abs(), radius.abs()));
        Affine { centre, terms, rad: radius.abs(), err: 0.0, iv }
    }

    /// A value known only to lie in `iv`: its midpoint plus a new symbol (unbounded if `iv` is).
    pub fn from_interval(iv: Interval) -> Affine {
        if !iv.is_finite() {
            return Affine { centre: iv.mid(), terms: Terms::new(), rad: 0.0, err: f64::INFINITY, iv };
        }
        let c = iv.mid();
        let r = up(iv.hi - c).max(up(c - iv.lo));
        let mut terms = Terms::new();
        if r > 0.0 {
            terms.push((fresh_symbol(), r));
        }
        Affine { centre: c, terms, rad: r, err: 0.0, iv }
    }

    /// The central value x₀.
    pub fn centre(&self) -> f64 {
        self.centre
    }

    /// Number of noise terms.
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// No noise terms.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// The form's terms (symbol, coefficient), for tests.
    pub fn terms(&self) -> &[(u64, f64)] {
        &self.terms
    }

    /// The private rounding error bound.
    pub fn rounding_error(&self) -> f64 {
        self.err
    }

    /// The mixed-mode interval carried beside the form.
    pub fn interval(&self) -> Interval {
        self.iv
    }

    /// Only the interval is meaningful (a division by a range with 0, an overflow…).
    pub fn is_unbounded(&self) -> bool {
        !self.err.is_finite()
    }

    /// Radius Σ|xᵢ| + e, rounded up.
    pub fn radius(&self) -> f64 {
        if self.is_unbounded() {
            return f64::INFINITY;
        }
        up(self.rad + self.err)
    }

    /// Guaranteed bounds: the affine range [x₀ − r, x₀ + r] intersected with the interval.
    pub fn range(&self) -> Interval {
        // Every form keeps its interval inside its affine range (see `finish`).
        self.iv
    }

    /// An exact constant (no noise terms, no error).
    pub fn as_constant(&self) -> Option<f64> {
        (self.terms.is_empty() && self.err == 0.0).then_some(self.centre)
    }

    /// Intersects the carried interval with another valid enclosure of the same value.
    pub fn with_interval(mut self, iv: Interval) -> Affine {
        if self.is_unbounded() {
            return Affine::from_interval(self.iv.intersect(iv));
        }
        self.iv = self.iv.intersect(iv);
        self
    }

    /// Appends a term on a new symbol (ids increase, so the list stays sorted).
    fn push_fresh(&mut self, coef: f64) {
        self.terms.push((fresh_symbol(), coef));
        self.rad = up(self.rad + coef.abs());
    }

    /// Checks finiteness and condenses; a non-finite form falls back to its interval.
    #[inline(always)]
    fn finish(mut self) -> Affine {
        // `rad` bounds Σ|xᵢ|: it is finite exactly when every coefficient is (short of an
        // overflow of the sum, which the interval fallback covers as well).
        if !(self.centre.is_finite() && self.err.is_finite() && self.rad.is_finite()) {
            return Affine::from_interval(self.iv);
        }
        if self.terms.len() > MAX_TERMS {
            self.condense();
        }
        // The carried interval becomes the intersection with the affine range, so that the
        // range is known without summing the terms again (and later interval operands are
        // no wider than the form's own bounds).
        let r = up(self.rad + self.err);
        self.iv = Interval::new(super::interval::down(self.centre - r), up(self.centre + r)).intersect(self.iv);
        self
    }

    /// Replaces all but the [`KEEP_TERMS`] largest terms by one new symbol carrying the sum of
    /// their magnitudes.
    fn condense(&mut self) {
        let mut mags: Vec<f64> = self.terms.iter().map(|t| t.1.abs()).collect();
        // The KEEP_TERMS-th largest magnitude (what a descending sort would put at KEEP_TERMS − 1).
        let (_, threshold, _) = mags.select_nth_unstable_by(KEEP_TERMS - 1, |a, b| b.total_cmp(a));
        let threshold = *threshold;
        let mut kept = Terms::with_capacity(KEEP_TERMS + 2);
        let (mut folded, mut n) = (0.0, 0usize);
        for &(id, x) in &self.terms {
            if x.abs() >= threshold && kept.len() < KEEP_TERMS {
                kept.push((id, x));
            } else {
                folded += x.abs();
                n += 1;
            }
        }
        kept.push((fresh_symbol(), sum_bound(folded, n)));
        self.rad = sum_up(kept.iter().map(|t| t.1.abs()));
        self.terms = kept;
    }

    /// Merges two sorted term lists as a·x + b·y into `out`; returns a bound on the magnitudes
    /// involved (the coefficients and, where two products are summed, the second product) and
    /// the plain sum of the magnitudes of the result's coefficients.
    fn merge(x: &[(u64, f64)], a: f64, y: &[(u64, f64)], b: f64, out: &mut Terms) -> (f64, f64) {
        let (mut mags, mut sum) = (0.0, 0.0);
        if y.is_empty() {
            // Scaling (k·x, an approximation's slope): no symbols to match.
            for &(id, c) in x {
                let v = a * c;
                mags += v.abs();
                if v != 0.0 {
                    out.push((id, v));
                }
            }
            return (mags, mags);
        }
        let (mut i, mut j) = (0, 0);
        while i < x.len() || j < y.len() {
            let (id, v) = if j >= y.len() || (i < x.len() && x[i].0 < y[j].0) {
                i += 1;
                (x[i - 1].0, a * x[i - 1].1)
            } else if i >= x.len() || y[j].0 < x[i].0 {
                j += 1;
                (y[j - 1].0, b * y[j - 1].1)
            } else {
                i += 1;
                j += 1;
                mags += (b * y[j - 1].1).abs();
                (x[i - 1].0, a * x[i - 1].1 + b * y[j - 1].1)
            };
            mags += v.abs();
            sum += v.abs();
            if v != 0.0 {
                out.push((id, v));
            }
        }
        (mags, sum)
    }

    /// a·x + b·y + k for constants a, b, k (every affine operation), with its rounding error.
    /// Constant operands fold to the `f64` value the point evaluation computes.
    fn linear(x: &Affine, a: f64, y: &Affine, b: f64, k: f64, iv: Interval) -> Affine {
        Affine::linear_raw(x, a, y, b, k, iv).finish()
    }

    /// [`Affine::linear`] before `finish`, for operations that add terms or error afterwards
    /// (the interval must not be clipped to the range before they are in).
    fn linear_raw(x: &Affine, a: f64, y: &Affine, b: f64, k: f64, iv: Interval) -> Affine {
        if x.is_unbounded() || y.is_unbounded() {
            return Affine::from_interval(iv);
        }
        let centre = a * x.centre + b * y.centre + k;
        if x.as_constant().is_some() && y.as_constant().is_some() {
            return Affine::constant(centre);
        }
        // One slot spare for the new symbol of a non-affine operation.
        let mut terms = Terms::with_capacity(x.terms.len() + y.terms.len() + 1);
        let (mags, sum) = Affine::merge(&x.terms, a, &y.terms, b, &mut terms);
        // Rounding of each coefficient (two products and a sum) and of the centre, for this
        // form and for the point evaluation of the same operation, plus the carried private
        // errors |a|·e_x + |b|·e_y.
        let centre_mags = (a * x.centre).abs() + (b * y.centre).abs() + k.abs() + centre.abs();
        let own = rounding(2.0 * (mags + centre_mags), terms.len() + 3);
        let carried = up(up(a.abs() * x.err) + up(b.abs() * y.err));
        let err = up(carried + own);
        let rad = sum_bound(sum, terms.len());
        Affine { centre, terms, rad, err, iv }
    }

    /// Sum.
    pub fn add(&self, o: &Affine) -> Affine {
        Affine::linear(self, 1.0, o, 1.0, 0.0, self.iv.add(o.iv))
    }

    /// Difference.
    pub fn sub(&self, o: &Affine) -> Affine {
        Affine::linear(self, 1.0, o, -1.0, 0.0, self.iv.sub(o.iv))
    }

    /// Negation (exact).
    pub fn neg(&self) -> Affine {
        Affine {
            centre: -self.centre,
            terms: self.terms.iter().map(|&(id, x)| (id, -x)).collect(),
            rad: self.rad,
            err: self.err,
            iv: self.iv.neg(),
        }
    }

    /// `k·x` for a constant k.
    pub fn scale(&self, k: f64) -> Affine {
        let zero = Affine::constant(0.0);
        Affine::linear(self, k, &zero, 0.0, 0.0, self.iv.scale(k))
    }

    /// Applies an approximation f(x) ∈ α·x + ζ ± δ (valid on this form's range); `iv` is the
    /// interval extension of f on that range.
    pub fn apply(&self, ap: Option<Approx>, iv: Interval) -> Affine {
        let Some(ap) = ap else { return Affine::from_interval(iv) };
        if self.is_unbounded() {
            return Affine::from_interval(iv);
        }
        let zero = Affine::constant(0.0);
        let mut z = Affine::linear_raw(self, ap.alpha, &zero, 0.0, ap.zeta, iv);
        if z.is_unbounded() {
            return z;
        }
        if ap.delta > 0.0 {
            z.push_fresh(ap.delta);
        }
        z.finish()
    }

    /// Product (§2.1): x₀y₀ + Σ(x₀yᵢ + y₀xᵢ)εᵢ + (r_x·r_y + |x₀|e_y + |y₀|e_x)·ε_new.
    /// A product of a form with itself is a square: the quadratic part Σxᵢεᵢ·Σxᵢεᵢ ∈ [0, A²]
    /// gives centre A²/2 and a half as large new term.
    pub fn mul(&self, o: &Affine) -> Affine {
        let iv = if self == o && self.err == 0.0 { self.range().sqr() } else { self.range().mul(o.range()) };
        if self.is_unbounded() || o.is_unbounded() {
            return Affine::from_interval(iv);
        }
        if let Some(k) = self.as_constant() {
            return Affine::linear(o, k, &Affine::constant(0.0), 0.0, 0.0, iv);
        }
        if let Some(k) = o.as_constant() {
            return Affine::linear(self, k, &Affine::constant(0.0), 0.0, 0.0, iv);
        }
        let same_terms = self.centre == o.centre && self.terms == o.terms;
        let mut terms = Terms::with_capacity(self.terms.len() + o.terms.len() + 1);
        let (mags, sum) = Affine::merge(&self.terms, o.centre, &o.terms, self.centre, &mut terms);
        let (ex, ey) = (self.err, o.err);
        let (mut centre, delta);
        if same_terms {
            // (x₀ + a + e_xη_x)(x₀ + a + e_yη_y), a = Σxᵢεᵢ, |a| ≤ A: a² ∈ [0, A²].
            let a = self.rad;
            let q = up(a * a);
            let cross = up(up((self.centre.abs() + a) * up(ex + ey)) + up(ex * ey));
            centre = self.centre * self.centre + 0.5 * q;
            delta = up(0.5 * q + cross);
        } else {
            let (rx, ry) = (self.radius(), o.radius());
            centre = self.centre * o.centre;
            delta = up(up(rx * ry) + up(up(self.centre.abs() * ey) + up(o.centre.abs() * ex)));
        }
        let prod = (self.centre * o.centre).abs();
        let err = rounding(2.0 * (mags + centre.abs() + prod + delta), terms.len() + 2);
        if !centre.is_finite() {
            centre = 0.0;
        }
        let rad = sum_bound(sum, terms.len());
        let mut z = Affine { centre, terms, rad, err, iv };
        if delta > 0.0 {
            z.push_fresh(delta);
        }
        z.finish()
    }

    /// A value times itself: the product form with the non-negative interval of the square.
    pub fn sqr(&self) -> Affine {
        let iv = self.range().sqr();
        self.mul(self).with_interval(iv)
    }

    /// Quotient with the language's rule x/0 = 0: a divisor whose range contains 0 gives an
    /// unbounded form (interval [`Interval::ENTIRE`]) unless the divisor or dividend is exactly 0.
    pub fn div(&self, o: &Affine) -> Affine {
        let iv = self.range().div(o.range());
        if o.as_constant() == Some(0.0) || self.as_constant() == Some(0.0) {
            return Affine::constant(0.0);
        }
        if let (Some(x), Some(k)) = (self.as_constant(), o.as_constant()) {
            return Affine::constant(x / k);
        }
        if let Some(k) = o.as_constant() {
            // Divide each coefficient: the same rounding as the point evaluation's x/k.
            let zero = Affine::constant(0.0);
            let mut z = Affine::linear_raw(self, 1.0 / k, &zero, 0.0, 0.0, iv);
            if !z.is_unbounded() {
                // 1/k is itself rounded: |x|·|fl(1/k) − 1/k| ≤ |x|·u/|k|.
                let xmax = self.range().lo.abs().max(self.range().hi.abs());
                z.err = up(z.err + up(xmax * 2.0 * UNIT_ROUNDOFF / k.abs()));
            }
            return z.finish();
        }
        let r = o.range();
        if r.lo <= 0.0 && r.hi >= 0.0 {
            return Affine::from_interval(iv);
        }
        let recip = o.apply(approx::recip(r.lo, r.hi), Interval::point(1.0).div(r));
        let mut z = self.mul(&recip);
        // The point quotient fl(x/y) is one rounding of x·(1/y); the allowance of `mul` covers
        // it, and the directly computed interval quotient is a second valid enclosure.
        z.iv = z.iv.intersect(iv);
        z
    }

    /// Whether the two forms have a noise symbol in common (a merge of the sorted id lists).
    pub fn shares_symbols(&self, o: &Affine) -> bool {
        let (x, y) = (&self.terms, &o.terms);
        let (mut i, mut j) = (0, 0);
        while i < x.len() && j < y.len() {
            match x[i].0.cmp(&y[j].0) {
                std::cmp::Ordering::Less => i += 1,
                std::cmp::Ordering::Greater => j += 1,
                std::cmp::Ordering::Equal => return true,
            }
        }
        false
    }

    /// A first-order Taylor extension (§3's recipe for univariate functions — an affine
    /// approximation plus a new symbol for its error — applied to a multivariate one): the form
    /// `value + Σ gₖ·(x̂ₖ − cₖ) + delta·ε_new` for `(x̂ₖ, cₖ, gₖ)` in `xs`. The caller guarantees
    /// |f(x) − value − Σ gₖ·(xₖ − cₖ)| ≤ `delta` over the forms' joint range, including the
    /// rounding of its point evaluation; the rounding of this form's own coefficients and centre
    /// is added here. `iv` is a valid enclosure of f over the range.
    pub fn taylor(xs: &[(&Affine, f64, f64)], value: f64, delta: f64, iv: Interval) -> Affine {
        if xs.iter().any(|(x, _, _)| x.is_unbounded()) || !(value.is_finite() && delta.is_finite()) {
            return Affine::from_interval(iv);
        }
        let (mut centre, mut centre_mags) = (value, value.abs());
        let (mut terms, mut mags, mut sum, mut carried) = (Terms::new(), 0.0, 0.0, 0.0);
        for &(x, c, g) in xs {
            let d = x.centre - c;
            centre += g * d;
            centre_mags += d.abs() * (1.0 + g.abs()) + centre.abs();
            carried = up(carried + up(g.abs() * x.err));
            if x.terms.is_empty() {
                continue;
            }
            let mut out = Terms::with_capacity(terms.len() + x.terms.len() + 1);
            let (m, s) = Affine::merge(&terms, 1.0, &x.terms, g, &mut out);
            mags += m;
            sum = s;
            terms = out;
        }
        // Each coefficient and the centre take a few roundings (products, sums): bounded like
        // `linear`'s, with the magnitudes of every partial result.
        let own = rounding(4.0 * (mags + centre_mags), terms.len() + 2 * xs.len() + 1);
        let err = up(carried + own);
        let rad = sum_bound(sum, terms.len());
        let mut z = Affine { centre, terms, rad, err, iv };
        if delta > 0.0 {
            z.push_fresh(delta);
        }
        z.finish()
    }

    /// Join of two values (both branches of a condition over a range): ½(x + y) + M·ε_new with
    /// M ≥ max |½(x − y)|, so both x and y are values of the result and shared symbols survive.
    pub fn join(&self, o: &Affine) -> Affine {
        if self == o {
            return self.clone();
        }
        let iv = self.iv.hull(o.iv);
        if self.is_unbounded() || o.is_unbounded() {
            return Affine::from_interval(iv);
        }
        let mid = Affine::linear_raw(self, 0.5, o, 0.5, 0.0, iv);
        let half = Affine::linear(self, 0.5, o, -0.5, 0.0, Interval::ENTIRE);
        let m = half.range();
        let mut z = mid;
        if z.is_unbounded() || !m.is_finite() {
            return Affine::from_interval(iv);
        }
        let r = m.lo.abs().max(m.hi.abs());
        if r > 0.0 {
            z.push_fresh(r);
        }
        z.finish()
    }
}
