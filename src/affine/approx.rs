//! Affine (Chebyshev / min-range) approximations of univariate functions over a range [a, b]:
//! f(x) = α·x + ζ ± δ for every x in [a, b] (Heidrich, Slusallek & Seidel 1998, §3: the best
//! affine approximation of a univariate function of an affine form is a linear Chebyshev
//! approximation of f on the form's range; Comba & Stolfi 1993).
//!
//! Each approximation is derived the same way, and the derivation is rigorous for any slope:
//! 1. the slope α is the secant slope (f(b) − f(a))/(b − a) (the Chebyshev slope for convex or
//!    concave f);
//! 2. the error e(x) = f(x) − α·x is bounded over [a, b]: for convex e its maximum is at the
//!    endpoints and its minimum is bounded below by the tangent line at the (computed) tangent
//!    point u where f'(u) ≈ α: e(x) ≥ e(u) − |e'(u)|·max(u − a, b − u). For functions whose
//!    curvature changes sign (sin, cos, odd powers, smoothstep) e is evaluated at the endpoints
//!    and at every critical point (f'(x) = α) in the range, and the displacement of a computed
//!    critical point by at most Δ is covered by M₂·(2Δ)² with M₂ ≥ max |f''|;
//! 3. ζ = (max e + min e)/2, δ = (max e − min e)/2, each widened by a slack that covers the
//!    floating-point evaluation of f (libm error, ≤ 2 ulps) and of α·x, for both the exact
//!    function and the `f64` value the point interpreter computes.
//!
//! The property tests in `affine::tests` check ≥ 10⁶ random points per operation.

use super::interval::up;
use std::f64::consts::{PI, TAU};

/// Unit roundoff 2⁻⁵³.
pub const UNIT_ROUNDOFF: f64 = 1.1102230246251565e-16;

/// f(x) ∈ α·x + ζ ± δ on the range the approximation was made for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Approx {
    /// Slope.
    pub alpha: f64,
    /// Intercept.
    pub zeta: f64,
    /// Half-width of the error band (≥ 0); carried by a new noise symbol.
    pub delta: f64,
}

impl Approx {
    /// A constant with error band `delta`.
    pub fn constant(value: f64, delta: f64) -> Approx {
        Approx { alpha: 0.0, zeta: value, delta }
    }

    fn is_finite(&self) -> bool {
        self.alpha.is_finite() && self.zeta.is_finite() && self.delta.is_finite()
    }
}

/// Slack for evaluating e(x) = f(x) − α·x in floating point, |f| ≤ `fmag`, |x| ≤ `xmag`:
/// libm error of f (≤ 2u|f| for the evaluation here and again for the point interpreter's),
/// the rounding of α·x and of the subtraction, and the cancellation in f'(u) − α: 8u(|f| + 2|α x|).
fn slack(fmag: f64, alpha: f64, xmag: f64) -> f64 {
    8.0 * UNIT_ROUNDOFF * (fmag + 2.0 * (alpha * xmag).abs()) + 1e-300
}

/// Approximation with e(x) ∈ [e_lo, e_hi]: ζ at the centre, δ covering both ends after rounding.
fn centred(alpha: f64, e_lo: f64, e_hi: f64) -> Option<Approx> {
    let zeta = 0.5 * e_lo + 0.5 * e_hi;
    let delta = up(e_hi - zeta).max(up(zeta - e_lo)).max(0.0);
    let a = Approx { alpha, zeta, delta };
    a.is_finite().then_some(a)
}

/// Chebyshev approximation of a convex (`convex = true`) or concave f on [a, b]. `df` is f',
/// `tangent(α)` returns (an approximation of) the point where f' = α.
fn convex_or_concave(
    a: f64,
    b: f64,
    f: impl Fn(f64) -> f64,
    df: impl Fn(f64) -> f64,
    tangent: impl Fn(f64) -> f64,
    convex: bool,
) -> Option<Approx> {
    if a == b {
        let fa = f(a);
        return centred(0.0, fa - slack(fa.abs(), 0.0, 0.0), fa + slack(fa.abs(), 0.0, 0.0));
    }
    // Work with g = s·f, convex.
    let s = if convex { 1.0 } else { -1.0 };
    let (fa, fb) = (s * f(a), s * f(b));
    let alpha = (fb - fa) / (b - a);
    if !alpha.is_finite() {
        return None;
    }
    let mut u = tangent(s * alpha);
    if !(u >= a && u <= b) {
        u = if u.is_nan() { 0.5 * (a + b) } else { u.clamp(a, b) };
    }
    let fu = s * f(u);
    let (ea, eb, eu) = (fa - alpha * a, fb - alpha * b, fu - alpha * u);
    let dev = up((s * df(u) - alpha).abs() * (u - a).max(b - u));
    let fmag = fa.abs().max(fb.abs()).max(fu.abs());
    let sl = slack(fmag, alpha, a.abs().max(b.abs()));
    let (e_lo, e_hi) = (eu - dev - sl, ea.max(eb) + sl);
    if !(e_lo.is_finite() && e_hi.is_finite()) {
        return None;
    }
    let g = centred(alpha, e_lo, e_hi)?;
    Some(Approx { alpha: s * g.alpha, zeta: s * g.zeta, delta: g.delta })
}

/// Error band of f − α·x on [a, b] from the endpoints and the candidate critical points `crits`
/// (points where f' = α, or kinks). `m2` bounds |f''| near the critical points.
fn critical(a: f64, b: f64, alpha: f64, f: impl Fn(f64) -> f64, crits: &[f64], m2: f64) -> Option<Approx> {
    let e = |x: f64| f(x) - alpha * x;
    let (mut lo, mut hi) = (e(a).min(e(b)), e(a).max(e(b)));
    let mut fmag = f(a).abs().max(f(b).abs());
    let mut margin: f64 = 0.0;
    for &c in crits {
        let d = 1e-7 * c.abs().max(1.0);
        if c >= a - d && c <= b + d {
            let x = c.clamp(a, b);
            let ex = e(x);
            lo = lo.min(ex);
            hi = hi.max(ex);
            fmag = fmag.max(f(x).abs());
            margin = margin.max(m2 * 4.0 * d * d);
        }
    }
    let sl = slack(fmag, alpha, a.abs().max(b.abs())) + margin;
    centred(alpha, lo - sl, hi + sl)
}

/// f(x) = s·g(−x) from an approximation of g on [−b, −a]: α_f = −s·α_g, ζ_f = s·ζ_g.
fn mirrored(g: Option<Approx>, s: f64) -> Option<Approx> {
    g.map(|g| Approx { alpha: -s * g.alpha, zeta: s * g.zeta, delta: g.delta })
}

/// exp on [a, b]: convex, f' = exp, tangent point ln α.
pub fn exp(a: f64, b: f64) -> Option<Approx> {
    convex_or_concave(a, b, f64::exp, f64::exp, f64::ln, true)
}

/// ln on [a, b], a ≥ the smallest positive normal: concave, f' = 1/x, tangent point 1/α.
pub fn ln(a: f64, b: f64) -> Option<Approx> {
    convex_or_concave(a, b, f64::ln, |x| 1.0 / x, |alpha| 1.0 / alpha, false)
}

/// sqrt on [a, b], a ≥ 0: concave, f' = 1/(2√x), tangent point 1/(4α²).
pub fn sqrt(a: f64, b: f64) -> Option<Approx> {
    if a == 0.0 && b == 0.0 {
        return Some(Approx::constant(0.0, 0.0));
    }
    convex_or_concave(a, b, f64::sqrt, |x| 0.5 / x.sqrt(), |alpha| 0.25 / (alpha * alpha), false)
}

/// 1/x on [a, b] not containing 0: convex for x > 0 (tangent point √(−1/α) = √(ab)), and the
/// mirror image for x < 0.
pub fn recip(a: f64, b: f64) -> Option<Approx> {
    let pos =
        |a: f64, b: f64| convex_or_concave(a, b, |x| 1.0 / x, |x| -1.0 / (x * x), |alpha| (-1.0 / alpha).sqrt(), true);
    if a > 0.0 {
        pos(a, b)
    } else if b < 0.0 {
        mirrored(pos(-b, -a), -1.0)
    } else {
        None
    }
}

/// x^p for x ≥ 0 and a real exponent p (the language's `pow(max(x, 0), p)`): convex for p > 1
/// or p < 0, concave for 0 < p < 1; tangent point (α/p)^(1/(p−1)).
pub fn powf(a: f64, b: f64, p: f64) -> Option<Approx> {
    let (a, b) = (a.max(0.0), b.max(0.0));
    if p == 0.0 {
        return Some(Approx::constant(1.0, 0.0));
    }
    if p == 1.0 {
        return Some(Approx { alpha: 1.0, zeta: 0.0, delta: 0.0 });
    }
    if p < 0.0 && a == 0.0 {
        return None;
    }
    let convex = !(0.0..1.0).contains(&p);
    convex_or_concave(a, b, |x| x.powf(p), |x| p * x.powf(p - 1.0), |alpha| (alpha / p).powf(1.0 / (p - 1.0)), convex)
}

/// The language's integer power: sign(x)^n·|x|^n computed as `|x|.powf(n)` with the sign.
pub fn powi_point(x: f64, n: i32) -> f64 {
    let r = x.abs().powf(n as f64);
    if x < 0.0 && n % 2 != 0 {
        -r
    } else {
        r
    }
}

/// x^n for an integer n on [a, b]; `None` when n < 0 and 0 ∈ [a, b] (unbounded).
pub fn powi(a: f64, b: f64, n: i32) -> Option<Approx> {
    match n {
        0 => return Some(Approx::constant(1.0, 0.0)),
        1 => return Some(Approx { alpha: 1.0, zeta: 0.0, delta: 0.0 }),
        _ => {}
    }
    let nf = n as f64;
    // On y ≥ 0, g(y) = y^n is convex for n ≥ 2 and n < 0.
    let pos = |a: f64, b: f64| {
        convex_or_concave(
            a,
            b,
            |y| y.powf(nf),
            |y| nf * y.powf(nf - 1.0),
            |alpha| (alpha / nf).powf(1.0 / (nf - 1.0)),
            true,
        )
    };
    let parity = if n % 2 == 0 { 1.0 } else { -1.0 };
    if a >= 0.0 {
        return pos(a, b);
    }
    if b <= 0.0 {
        return mirrored(pos(-b, -a), parity);
    }
    if n < 0 {
        return None;
    }
    let f = |x: f64| powi_point(x, n);
    if n % 2 == 0 {
        // |x|^n is convex on the whole line; f'(u) = α at u = sign(α)(|α|/n)^(1/(n−1)).
        convex_or_concave(
            a,
            b,
            f,
            |x| nf * powi_point(x, n - 1),
            |alpha| alpha.signum() * (alpha.abs() / nf).powf(1.0 / (nf - 1.0)),
            true,
        )
    } else {
        // Odd power across 0: inflection at 0; critical points ±(α/n)^(1/(n−1)).
        let alpha = (f(b) - f(a)) / (b - a);
        let c = (alpha.max(0.0) / nf).powf(1.0 / (nf - 1.0));
        let xm = a.abs().max(b.abs());
        critical(a, b, alpha, f, &[c, -c, 0.0], nf * (nf - 1.0) * xm.powf(nf - 2.0))
    }
}

/// Largest |x| for which sin and cos enumerate their critical points: 2⁴⁰. Doubles there are
/// still 2⁻¹² apart (1/25 000 of a period), far from where the enumeration fails (k ≈ 2⁵³).
const TRIG_RANGE: f64 = 1_099_511_627_776.0;

/// Every x = base + 2kπ near [a, b].
fn periodic(a: f64, b: f64, base: f64, out: &mut Vec<f64>) {
    let k0 = ((a - base) / TAU).floor() - 1.0;
    let k1 = ((b - base) / TAU).ceil() + 1.0;
    let mut k = k0;
    while k <= k1 {
        out.push(base + k * TAU);
        k += 1.0;
    }
}

/// sin or cos on [a, b]: the better (smaller δ) of the secant slope and slope 0, each with its
/// error evaluated at every critical point (cos x = α for sin; −sin x = α for cos). Ranges wider
/// than 4π use slope 0 and [−1, 1].
fn trig(a: f64, b: f64, is_sin: bool) -> Option<Approx> {
    // Far from 0 the critical points x = base + 2kπ cannot be enumerated (k + 1 rounds back
    // to k beyond 2⁵³, and `periodic` would never end): there the bound 0 ± 1, which always
    // holds.
    if (b - a).is_nan() || b - a > 4.0 * PI || a.abs().max(b.abs()) > TRIG_RANGE {
        return Some(Approx::constant(0.0, 1.0));
    }
    let f = if is_sin { f64::sin } else { f64::cos };
    let with_slope = |alpha: f64| {
        let alpha = alpha.clamp(-1.0, 1.0);
        let mut crits = Vec::with_capacity(12);
        if is_sin {
            let c = alpha.acos();
            periodic(a, b, c, &mut crits);
            periodic(a, b, -c, &mut crits);
        } else {
            let c = (-alpha).asin();
            periodic(a, b, c, &mut crits);
            periodic(a, b, PI - c, &mut crits);
        }
        critical(a, b, alpha, f, &crits, 1.0)
    };
    if a == b {
        return with_slope(0.0);
    }
    let secant = with_slope((f(b) - f(a)) / (b - a));
    let flat = with_slope(0.0);
    match (secant, flat) {
        (Some(s), Some(z)) => Some(if s.delta <= z.delta { s } else { z }),
        (s, z) => s.or(z),
    }
}

/// sin on [a, b].
pub fn sin(a: f64, b: f64) -> Option<Approx> {
    trig(a, b, true)
}

/// cos on [a, b].
pub fn cos(a: f64, b: f64) -> Option<Approx> {
    trig(a, b, false)
}

/// |x| on [a, b]: the identity or negation when 0 ∉ (a, b); across 0 the secant slope
/// (a + b)/(b − a) with e(x) = |x| − αx evaluated at a, b and the kink 0 (e(0) = 0 is the
/// minimum, so ζ = δ = e(a)/2 up to rounding). Not the identity's range [0, max] with slope 0,
/// and never the "invalid abs across zero" of a plain |x0| ± Σ|xi|.
pub fn abs(a: f64, b: f64) -> Option<Approx> {
    if a >= 0.0 {
        return Some(Approx { alpha: 1.0, zeta: 0.0, delta: 0.0 });
    }
    if b <= 0.0 {
        return Some(Approx { alpha: -1.0, zeta: 0.0, delta: 0.0 });
    }
    critical(a, b, (a + b) / (b - a), f64::abs, &[0.0], 0.0)
}

/// max(x, 0) on [a, b]; across 0 the secant slope b/(b − a), kink at 0 (the paper's max⁰, §3).
pub fn max0(a: f64, b: f64) -> Option<Approx> {
    if a >= 0.0 {
        return Some(Approx { alpha: 1.0, zeta: 0.0, delta: 0.0 });
    }
    if b <= 0.0 {
        return Some(Approx::constant(0.0, 0.0));
    }
    critical(a, b, b / (b - a), |x| x.max(0.0), &[0.0], 0.0)
}

/// floor on [a, b]: exact when a and b lie in one cell; otherwise slope 1 with
/// e(x) = floor(x) − x ∈ [−1, 0] (exact in floating point), i.e. x − ½ ± ½. Slope 1 keeps the
/// correlation with x, so `x − floor(x)` (mod, fract) comes out as exactly ½ ± ½.
pub fn floor(a: f64, b: f64) -> Option<Approx> {
    let (fa, fb) = (a.floor(), b.floor());
    if fa == fb {
        return Some(Approx::constant(fa, 0.0));
    }
    Some(Approx { alpha: 1.0, zeta: -0.5, delta: 0.5 })
}

/// The language's step of the difference: 1 if t ≥ 0 else 0. Across 0 the Chebyshev
/// approximation of a unit jump is the constant ½ ± ½.
pub fn step0(a: f64, b: f64) -> Option<Approx> {
    if a >= 0.0 {
        Some(Approx::constant(1.0, 0.0))
    } else if b < 0.0 {
        Some(Approx::constant(0.0, 0.0))
    } else {
        Some(Approx::constant(0.5, 0.5))
    }
}

/// The Hermite smoothstep of a clamped parameter, h(t) = s²(3 − 2s) with s = clamp(t, 0, 1).
pub fn smooth01_point(t: f64) -> f64 {
    let s = t.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// h(t) on [a, b]: secant slope; e evaluated at the kinks 0 and 1 and at the critical points
/// 6s − 6s² = α, s = (1 ± √(1 − 2α/3))/2; |h''| ≤ 6.
pub fn smooth01(a: f64, b: f64) -> Option<Approx> {
    if b <= 0.0 {
        return Some(Approx::constant(0.0, 0.0));
    }
    if a >= 1.0 {
        return Some(Approx::constant(1.0, 0.0));
    }
    let alpha = if a == b { 0.0 } else { (smooth01_point(b) - smooth01_point(a)) / (b - a) };
    let disc = 1.0 - 2.0 * alpha / 3.0;
    let mut crits = vec![0.0, 1.0];
    if disc >= 0.0 {
        let r = disc.sqrt();
        crits.push(0.5 * (1.0 - r));
        crits.push(0.5 * (1.0 + r));
    }
    critical(a, b, alpha, smooth01_point, &crits, 6.0)
}

/// The quintic fade of Perlin noise, 6t⁵ − 15t⁴ + 10t³, evaluated as t³·(t·(6t − 15) + 10)
/// (the operation order the point evaluation uses).
pub fn fade_point(t: f64) -> f64 {
    let t3 = t * t * t;
    t3 * (t * (t * 6.0 - 15.0) + 10.0)
}

/// Rounding allowance of [`fade_point`] on |t| ≤ m: a few ulps of the largest partial term.
pub fn fade_slack(m: f64) -> f64 {
    64.0 * UNIT_ROUNDOFF * (1.0 + 31.0 * m.powi(5))
}

/// fade on [a, b]: monotone (f' = 30t²(t − 1)² ≥ 0) with an inflection at ½; secant slope and
/// the critical points 30t²(t − 1)² = α, i.e. t(1 − t) = ±√(α/30):
/// t = (1 ± √(1 − 4s))/2 and t = (1 ± √(1 + 4s))/2 with s = √(α/30);
/// |f''| = 60|t(t − 1)(2t − 1)| ≤ 60·M(M + 1)(2M + 1), M = max |t|.
pub fn fade(a: f64, b: f64) -> Option<Approx> {
    let alpha = if a == b { 0.0 } else { ((fade_point(b) - fade_point(a)) / (b - a)).max(0.0) };
    let s = (alpha / 30.0).sqrt();
    let mut crits = Vec::with_capacity(4);
    for disc in [1.0 - 4.0 * s, 1.0 + 4.0 * s] {
        if disc >= 0.0 {
            let r = disc.sqrt();
            crits.push(0.5 * (1.0 - r));
            crits.push(0.5 * (1.0 + r));
        }
    }
    let m = a.abs().max(b.abs());
    let ap = critical(a, b, alpha, fade_point, &crits, 60.0 * m * (m + 1.0) * (2.0 * m + 1.0))?;
    Some(Approx { delta: up(ap.delta + fade_slack(m)), ..ap })
}
