//! Normalized associated Legendre functions by the standard stable three-term recurrences.
//!
//! P̄_l^m(x) = N_l^m P_l^m(x) with N_l^m = √((2l+1)/(4π) · (l−m)!/(l+m)!), no (−1)^m phase.
//! Recurrences (e.g. Holmes & Featherstone 2002, "unnormalized" forms rescaled):
//!   P̄_0^0 = 1/√(4π)
//!   P̄_m^m = √((2m+1)/(2m)) · sin θ · P̄_{m−1}^{m−1}
//!   P̄_{m+1}^m = √(2m+3) · cos θ · P̄_m^m
//!   P̄_l^m = a_lm (cos θ P̄_{l−1}^m − b_lm P̄_{l−2}^m),
//!     a_lm = √((4l²−1)/(l²−m²)), b_lm = √(((l−1)²−m²)/(4(l−1)²−1)).
//! Every quantity stays O(1) (no factorials), so the recurrence is stable to orders in the
//! thousands; sin^m θ may underflow to 0 near the poles, where the true value is below 1e-300.

use std::f64::consts::PI;

/// Legendre polynomials P_0..P_lmax at x by Bonnet's recurrence
/// (l+1) P_{l+1} = (2l+1) x P_l − l P_{l−1} (stable for |x| ≤ 1). These are the plain
/// polynomials of the Funk–Hecke integral; the normalized SH functions are [`LegendreTable`].
pub fn legendre_polynomials(x: f64, out: &mut [f64]) {
    if out.is_empty() {
        return;
    }
    out[0] = 1.0;
    if out.len() > 1 {
        out[1] = x;
    }
    for l in 1..out.len().saturating_sub(1) {
        out[l + 1] = ((2 * l + 1) as f64 * x * out[l] - l as f64 * out[l - 1]) / (l + 1) as f64;
    }
}

/// Precomputed recurrence coefficients for all (l, m) up to an order.
#[derive(Clone, Debug)]
pub struct LegendreTable {
    order: usize,
    a: Vec<f64>,
    b: Vec<f64>,
    diag: Vec<f64>,
}

impl LegendreTable {
    /// Coefficients for bands 0..=order.
    pub fn new(order: usize) -> Self {
        let n = super::count(order);
        let mut a = vec![0.0; n];
        let mut b = vec![0.0; n];
        for m in 0..=order {
            for l in (m + 2)..=order {
                let (lf, mf) = (l as f64, m as f64);
                let i = super::index(l, m as isize);
                a[i] = ((4.0 * lf * lf - 1.0) / (lf * lf - mf * mf)).sqrt();
                b[i] = (((lf - 1.0) * (lf - 1.0) - mf * mf) / (4.0 * (lf - 1.0) * (lf - 1.0) - 1.0)).sqrt();
            }
        }
        let diag =
            (0..=order).map(|m| if m == 0 { 0.0 } else { ((2 * m + 1) as f64 / (2 * m) as f64).sqrt() }).collect();
        LegendreTable { order, a, b, diag }
    }

    /// The highest band.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Fills `out[index(l, m)]` (m ≥ 0 only; entries with m < 0 are left untouched) with
    /// P̄_l^m(cos θ) for all l ≤ order, given cos θ and sin θ ≥ 0.
    pub fn eval(&self, cos_theta: f64, sin_theta: f64, out: &mut [f64]) {
        self.eval_to_m(cos_theta, sin_theta, self.order, out);
    }

    /// [`LegendreTable::eval`] for the orders m ≤ `max_m` only (other entries untouched), in
    /// O(order · max_m): for sums that read a few orders of many bands.
    pub fn eval_to_m(&self, cos_theta: f64, sin_theta: f64, max_m: usize, out: &mut [f64]) {
        let order = self.order;
        debug_assert!(out.len() >= super::count(order));
        let mut pmm = 0.5 / PI.sqrt();
        for m in 0..=order.min(max_m) {
            if m > 0 {
                pmm *= self.diag[m] * sin_theta;
            }
            out[super::index(m, m as isize)] = pmm;
            if m == order {
                break;
            }
            let mut p_prev = pmm;
            let mut p = ((2 * m + 3) as f64).sqrt() * cos_theta * pmm;
            out[super::index(m + 1, m as isize)] = p;
            for l in (m + 2)..=order {
                let i = super::index(l, m as isize);
                let next = self.a[i] * (cos_theta * p - self.b[i] * p_prev);
                out[i] = next;
                p_prev = p;
                p = next;
            }
        }
    }

    /// The zonal functions only: `out[l]` = P̄_l^0(x) for l ≤ order, in O(order).
    pub fn eval_zonal(&self, x: f64, out: &mut [f64]) {
        let order = self.order;
        out[0] = 0.5 / PI.sqrt();
        if order == 0 {
            return;
        }
        out[1] = 3f64.sqrt() * x * out[0];
        for l in 2..=order {
            let i = super::index(l, 0);
            out[l] = self.a[i] * (x * out[l - 1] - self.b[i] * out[l - 2]);
        }
    }

    /// P̄_l^m(cos θ) for m ≥ 0 laid out per m: `out[m][l - m]`, convenient for per-m sums.
    pub fn eval_by_m(&self, cos_theta: f64, sin_theta: f64, out: &mut [Vec<f64>]) {
        let order = self.order;
        let mut pmm = 0.5 / PI.sqrt();
        for m in 0..=order {
            if m > 0 {
                pmm *= self.diag[m] * sin_theta;
            }
            let col = &mut out[m];
            col[0] = pmm;
            if m == order {
                break;
            }
            let mut p_prev = pmm;
            let mut p = ((2 * m + 3) as f64).sqrt() * cos_theta * pmm;
            col[1] = p;
            for l in (m + 2)..=order {
                let i = super::index(l, m as isize);
                let next = self.a[i] * (cos_theta * p - self.b[i] * p_prev);
                col[l - m] = next;
                p_prev = p;
                p = next;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orders_up_to_m_are_those_of_the_full_table_and_the_rest_untouched() {
        let t = LegendreTable::new(40);
        let (c, s) = (0.37f64, (1.0f64 - 0.37 * 0.37).sqrt());
        let mut full = vec![0.0; crate::sh::count(40)];
        t.eval(c, s, &mut full);
        let mut part = vec![f64::NAN; crate::sh::count(40)];
        t.eval_to_m(c, s, 6, &mut part);
        for l in 0..=40usize {
            for m in 0..=l as isize {
                let i = crate::sh::index(l, m);
                if m <= 6 {
                    assert_eq!(part[i], full[i], "l = {l}, m = {m}");
                } else {
                    assert!(part[i].is_nan(), "l = {l}, m = {m} written");
                }
            }
        }
    }

    #[test]
    fn low_orders_match_closed_forms() {
        let t = LegendreTable::new(3);
        let mut out = vec![0.0; 16];
        let (c, s) = (0.3f64, (1.0f64 - 0.09).sqrt());
        t.eval(c, s, &mut out);
        let k = |l: f64| ((2.0 * l + 1.0) / (4.0 * PI)).sqrt();
        assert!((out[super::super::index(1, 0)] - k(1.0) * c).abs() < 1e-14);
        // P_1^1 = sin θ (no Condon–Shortley phase); N_1^1 = k(1)/√2.
        assert!((out[super::super::index(1, 1)] - k(1.0) * s / 2f64.sqrt()).abs() < 1e-14);
        // P_2^0 = (3c² − 1)/2.
        assert!((out[super::super::index(2, 0)] - k(2.0) * 0.5 * (3.0 * c * c - 1.0)).abs() < 1e-14);
        // P_3^2 = 15 c s², N_3^2 = k(3)·√(1/120).
        let n32 = k(3.0) * (1.0f64 / 120.0).sqrt();
        assert!((out[super::super::index(3, 2)] - n32 * 15.0 * c * s * s).abs() < 1e-13);
    }

    #[test]
    fn zonal_evaluation_equals_the_full_table() {
        let t = LegendreTable::new(40);
        let (mut full, mut zonal) = (vec![0.0; crate::sh::count(40)], vec![0.0; 41]);
        for x in [-0.9, -0.2, 0.0, 0.45, 0.999] {
            t.eval(x, (1.0f64 - x * x).sqrt(), &mut full);
            t.eval_zonal(x, &mut zonal);
            for l in 0..=40 {
                assert_eq!(zonal[l], full[crate::sh::index(l, 0)]);
            }
        }
    }
}
