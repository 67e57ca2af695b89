//! Gauss–Legendre quadrature on [−1, 1]: exact for polynomials of degree < 2n, the natural rule
//! for integrals over cos θ.

use rayon::prelude::*;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::{Arc, Mutex, OnceLock};

/// A quadrature rule: (node, weight) pairs.
pub type Rule = Arc<Vec<(f64, f64)>>;

/// [`gauss_legendre`], computed once per n and shared (rules are pure functions of n).
pub fn gauss_legendre_cached(n: usize) -> Rule {
    static CACHE: OnceLock<Mutex<HashMap<usize, Rule>>> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(rule) = cache.lock().ok().and_then(|c| c.get(&n).cloned()) {
        return rule;
    }
    let rule = Arc::new(gauss_legendre(n));
    if let Ok(mut c) = cache.lock() {
        c.insert(n, rule.clone());
    }
    rule
}

/// n Gauss–Legendre nodes and weights on [−1, 1], ascending, by Newton's method on P_n from the
/// Tricomi initial guesses. Accurate to ~1e-15 for n up to several thousand.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    // Each node is its own Newton iteration (O(n) per step): in parallel, the same bits.
    let mut out: Vec<(f64, f64)> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            for _ in 0..100 {
                let (p, d) = legendre_and_derivative(n, x);
                let dx = p / d;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre_and_derivative(n, x);
            (x, 2.0 / ((1.0 - x * x) * d * d))
        })
        .collect();
    out.reverse();
    out
}

fn legendre_and_derivative(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
        p0 = p1;
        p1 = p2;
    }
    (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integrates_polynomials_exactly() {
        for n in [1usize, 2, 5, 17, 64] {
            let rule = gauss_legendre(n);
            assert!((rule.iter().map(|(_, w)| w).sum::<f64>() - 2.0).abs() < 1e-13);
            for k in 0..2 * n {
                let got: f64 = rule.iter().map(|(x, w)| w * x.powi(k as i32)).sum();
                let want = if k % 2 == 1 { 0.0 } else { 2.0 / (k as f64 + 1.0) };
                assert!((got - want).abs() < 1e-12, "n={n} k={k}: {got} vs {want}");
            }
        }
    }
}
