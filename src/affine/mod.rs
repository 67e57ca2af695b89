//! Interval and affine arithmetic: number types whose operations return guaranteed bounds of a
//! value over a whole range of inputs (Heidrich, Slusallek & Seidel 1998, §2–3; Comba & Stolfi
//! 1993). The shading-language interpreter is generic over [`Real`], implemented by `f64`
//! (point sampling), [`Interval`] and [`Affine`].

pub mod approx;
pub mod form;
pub mod interval;
pub mod real;

pub use form::Affine;
pub use interval::Interval;
pub use real::{Real, Sign};

#[cfg(test)]
mod tests {
    //! Property tests: for random affine forms over shared noise symbols and random points of
    //! their range, the `f64` value of each operation lies inside (a) the result form evaluated
    //! at the same noise values, with the new symbols and rounding error free, (b) the form's
    //! range and (c) the interval result. Inputs are dyadic rationals with few bits, so the
    //! input values are exact and any violation is the operation's fault. The check itself is
    //! done in outward-rounded interval arithmetic, so it cannot raise false alarms.
    #![allow(clippy::redundant_closure)]
    use super::*;
    use crate::rng::SplitMix64;

    const FORMS: usize = 20_000;
    const POINTS: usize = 50; // 10⁶ trials per operation
    const SYMBOLS: usize = 3;

    struct Case {
        syms: Vec<u64>,
        x: Affine,
        y: Affine,
        xs: Vec<f64>,
        ys: Vec<f64>,
        xc: f64,
        yc: f64,
    }

    /// A random form c + Σ aₖ·sₖ over the shared base symbols, scaled by 2^scale.
    fn random_form(rng: &mut SplitMix64, base: &[Affine], scale: i32, centre_bias: f64) -> (Affine, f64, Vec<f64>) {
        let s = 2f64.powi(scale);
        let c = (rng.range_i64(-1024, 1024) as f64 + centre_bias) * s;
        let mut form = Affine::constant(c);
        let mut coef = Vec::new();
        for b in base {
            let a = if rng.next_u64() % 4 == 0 { 0.0 } else { rng.range_i64(-1024, 1024) as f64 * s / 4.0 };
            form = form.add(&b.scale(a));
            coef.push(a);
        }
        (form, c, coef)
    }

    fn case(rng: &mut SplitMix64, scale: (i32, i32), bias: (f64, f64)) -> Case {
        let base: Vec<Affine> = (0..SYMBOLS).map(|_| Affine::symbol(0.0, 1.0)).collect();
        let syms = base.iter().map(|b| b.terms()[0].0).collect();
        let sx = rng.range_i64(scale.0 as i64, scale.1 as i64) as i32;
        let sy = rng.range_i64(scale.0 as i64, scale.1 as i64) as i32;
        let (x, xc, xs) = random_form(rng, &base, sx, bias.0 * 1024.0);
        let (y, yc, ys) = random_form(rng, &base, sy, bias.1 * 1024.0);
        Case { syms, x, y, xs, ys, xc, yc }
    }

    /// The interval of values `z` can take when its base symbols equal `eps`.
    fn enclosure_at(z: &Affine, syms: &[u64], eps: &[f64]) -> Interval {
        if z.is_unbounded() {
            return z.range();
        }
        let mut acc = Interval::point(z.centre());
        let mut free = 0.0f64;
        for &(id, coef) in z.terms() {
            match syms.iter().position(|&s| s == id) {
                Some(k) => acc = acc.add(Interval::point(coef).mul(Interval::point(eps[k]))),
                None => free += coef.abs(),
            }
        }
        let free = interval::up(interval::up(free * (1.0 + 1e-12)) + z.rounding_error());
        acc.add(Interval::new(-free, free))
    }

    /// Runs `FORMS × POINTS` trials of a binary operation; returns the violation count.
    fn check(
        name: &str,
        seed: u64,
        scale: (i32, i32),
        bias: (f64, f64),
        point: impl Fn(f64, f64) -> f64,
        affine: impl Fn(&Affine, &Affine) -> Affine,
        interval: impl Fn(Interval, Interval) -> Interval,
    ) {
        let mut rng = SplitMix64::new(seed);
        let (mut violations, mut trials, mut first) = (0usize, 0usize, None);
        for _ in 0..FORMS {
            let c = case(&mut rng, scale, bias);
            let z = affine(&c.x, &c.y);
            let zr = z.range();
            let zi = interval(c.x.range(), c.y.range());
            for _ in 0..POINTS {
                let eps: Vec<f64> = (0..SYMBOLS).map(|_| rng.range_i64(-1024, 1024) as f64 / 1024.0).collect();
                let xv = c.xc + c.xs.iter().zip(&eps).map(|(a, e)| a * e).sum::<f64>();
                let yv = c.yc + c.ys.iter().zip(&eps).map(|(a, e)| a * e).sum::<f64>();
                let fv = point(xv, yv);
                trials += 1;
                let ok = enclosure_at(&z, &c.syms, &eps).contains(fv) && zr.contains(fv) && zi.contains(fv);
                if !ok && !fv.is_nan() {
                    violations += 1;
                    first.get_or_insert((xv, yv, fv, z.clone(), zi));
                }
            }
        }
        assert!(trials >= 1_000_000);
        assert_eq!(violations, 0, "{name}: {violations} violations in {trials} trials; first {first:?}");
    }

    fn unary(
        name: &str,
        seed: u64,
        scale: (i32, i32),
        bias: f64,
        point: fn(f64) -> f64,
        a: fn(&Affine) -> Affine,
        i: fn(Interval) -> Interval,
    ) {
        check(name, seed, scale, (bias, 0.0), |x, _| point(x), |x, _| a(x), |x, _| i(x));
    }

    #[test]
    fn add_sub_mul_never_violate() {
        check("add", 1, (-8, 4), (0.0, 0.0), |x, y| x + y, |x, y| x.add(y), |x, y| x.add(y));
        check("sub", 2, (-8, 4), (0.0, 0.0), |x, y| x - y, |x, y| x.sub(y), |x, y| x.sub(y));
        check("mul", 3, (-8, 4), (0.0, 0.0), |x, y| x * y, |x, y| x.mul(y), |x, y| x.mul(y));
        check("sqr", 4, (-8, 4), (0.0, 0.0), |x, _| x * x, |x, _| Real::sqr(x), |x, _| Real::sqr(&x));
    }

    #[test]
    fn div_never_violates() {
        // Divisors centred away from 0 (bias) and across 0 (unbounded results).
        check(
            "div",
            5,
            (-8, 4),
            (0.0, 1.5),
            |x, y| Real::div(&x, &y),
            |x, y| Real::div(x, y),
            |x, y| Real::div(&x, &y),
        );
        check(
            "div0",
            6,
            (-8, 4),
            (0.0, 0.0),
            |x, y| Real::div(&x, &y),
            |x, y| Real::div(x, y),
            |x, y| Real::div(&x, &y),
        );
    }

    #[test]
    fn sqrt_exp_log_never_violate() {
        unary("sqrt", 7, (-8, 4), 0.8, |x| Real::sqrt(&x), |x| Real::sqrt(x), |x| Real::sqrt(&x));
        unary("sqrt0", 8, (-8, 4), 0.0, |x| Real::sqrt(&x), |x| Real::sqrt(x), |x| Real::sqrt(&x));
        unary("exp", 9, (-12, -1), 0.0, |x| Real::exp(&x), |x| Real::exp(x), |x| Real::exp(&x));
        unary("log", 10, (-8, 4), 1.2, |x| Real::ln(&x), |x| Real::ln(x), |x| Real::ln(&x));
        unary("log0", 11, (-8, 4), 0.0, |x| Real::ln(&x), |x| Real::ln(x), |x| Real::ln(&x));
    }

    #[test]
    fn sin_cos_never_violate() {
        unary("sin", 12, (-10, 0), 0.0, |x| Real::sin(&x), |x| Real::sin(x), |x| Real::sin(&x));
        unary("cos", 13, (-10, 0), 0.3, |x| Real::cos(&x), |x| Real::cos(x), |x| Real::cos(&x));
        unary("sin-far", 14, (-6, 3), 5.0, |x| Real::sin(&x), |x| Real::sin(x), |x| Real::sin(&x));
    }

    #[test]
    fn piecewise_functions_never_violate() {
        unary("abs", 15, (-8, 4), 0.0, |x| Real::abs(&x), |x| Real::abs(x), |x| Real::abs(&x));
        unary("floor", 16, (-8, 2), 0.0, |x| Real::floor(&x), |x| Real::floor(x), |x| Real::floor(&x));
        unary("step", 17, (-8, 2), 0.0, |x| Real::step0(&x), |x| Real::step0(x), |x| Real::step0(&x));
        unary("fade", 22, (-12, -8), 0.5, |x| Real::fade(&x), |x| Real::fade(x), |x| Real::fade(&x));
        unary("fade-wide", 23, (-9, -7), 0.5, |x| Real::fade(&x), |x| Real::fade(x), |x| Real::fade(&x));
        unary("smooth", 18, (-12, -8), 0.4, |x| Real::smooth01(&x), |x| Real::smooth01(x), |x| Real::smooth01(&x));
        check("min", 19, (-8, 4), (0.0, 0.0), |x, y| x.min(y), |x, y| Real::min(x, y), |x, y| Real::min(&x, &y));
        check("max", 20, (-8, 4), (0.0, 0.0), |x, y| x.max(y), |x, y| Real::max(x, y), |x, y| Real::max(&x, &y));
        // mod(x, y) = x − y·floor(x/y), as the interpreter composes it.
        let m = |x: &Affine, y: &Affine| x.sub(&y.mul(&Real::floor(&Real::div(x, y))));
        let mi = |x: Interval, y: Interval| Real::sub(&x, &Real::mul(&y, &Real::floor(&Real::div(&x, &y))));
        let mp = |x: f64, y: f64| x - y * Real::div(&x, &y).floor();
        check("mod", 21, (-8, 2), (0.0, 2.0), mp, m, mi);
    }

    #[test]
    fn powers_never_violate() {
        for (k, p) in [2.0, 3.0, 4.0, 5.0, -1.0, -2.0, -3.0, 0.5, 1.5, 2.7, -0.5, 0.3].into_iter().enumerate() {
            let bias = if p < 0.0 { 1.3 } else { 0.2 };
            check(
                &format!("pow {p}"),
                100 + k as u64,
                (-6, 1),
                (bias, 0.0),
                move |x, _| pow_point(x, p),
                move |x, _| Real::pow(x, &Affine::constant(p)),
                move |x, _| Real::pow(&x, &Interval::point(p)),
            );
        }
        check("pow xy", 120, (-8, -2), (1.0, 0.0), real::pow_point, |x, y| Real::pow(x, y), |x, y| Real::pow(&x, &y));
    }

    #[test]
    fn join_holds_both_values() {
        let mut rng = SplitMix64::new(7);
        for _ in 0..10_000 {
            let c = case(&mut rng, (-4, 2), (0.0, 0.0));
            let j = c.x.join(&c.y);
            for _ in 0..50 {
                let eps: Vec<f64> = (0..SYMBOLS).map(|_| rng.range_i64(-1024, 1024) as f64 / 1024.0).collect();
                let xv = c.xc + c.xs.iter().zip(&eps).map(|(a, e)| a * e).sum::<f64>();
                let yv = c.yc + c.ys.iter().zip(&eps).map(|(a, e)| a * e).sum::<f64>();
                let e = enclosure_at(&j, &c.syms, &eps);
                assert!(e.contains(xv) && e.contains(yv));
            }
        }
    }

    use super::real::pow_point;

    #[test]
    fn affine_is_tighter_than_interval_on_dependent_expressions() {
        // x − x is exactly 0 in affine arithmetic, the full width twice in interval arithmetic.
        let x = Affine::symbol(0.5, 0.25);
        let d = x.sub(&x);
        assert!(d.range().width() < 1e-12);
        let xi = x.range();
        assert!(Interval::sub(xi, xi).width() >= 1.0);
        // x·(1 − x) on [0.25, 0.75]: true range [0.1875, 0.25].
        let one = Affine::constant(1.0);
        let p = x.mul(&one.sub(&x));
        let pi = Interval::mul(xi, Interval::sub(Interval::point(1.0), xi));
        assert!(p.range().width() < pi.width());
        assert!(p.range().lo <= 0.1875 && p.range().hi >= 0.25);
    }

    #[test]
    fn abs_across_zero_is_chebyshev() {
        // |x| on [−1, 3]: slope 1/2, e(x) = |x| − x/2 ∈ [0, 3/2]: ζ = 3/4, δ = 3/4.
        let a = approx::abs(-1.0, 3.0).unwrap_or(approx::Approx::constant(f64::NAN, f64::NAN));
        assert!((a.alpha - 0.5).abs() < 1e-15);
        assert!((a.zeta - 0.75).abs() < 1e-12 && (a.delta - 0.75).abs() < 1e-12);
    }

    #[test]
    fn exp_chebyshev_matches_closed_form() {
        // exp on [0, 1]: α = e − 1, tangent point ln α, ζ = (1 + α − α ln α)/2, δ = (1 − α + α ln α)/2.
        let a = approx::exp(0.0, 1.0).unwrap_or(approx::Approx::constant(f64::NAN, f64::NAN));
        let alpha = std::f64::consts::E - 1.0;
        let (zeta, delta) = ((1.0 + alpha - alpha * alpha.ln()) / 2.0, (1.0 - alpha + alpha * alpha.ln()) / 2.0);
        assert!((a.alpha - alpha).abs() < 1e-14);
        assert!((a.zeta - zeta).abs() < 1e-12, "{} vs {zeta}", a.zeta);
        assert!((a.delta - delta).abs() < 1e-12 && a.delta >= delta);
    }
}
