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
use std::sync::{Arc, Mutex};

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
///
/// Each coefficient depends on (l, m) alone and sits at index(l, m) whatever the order, so one
/// process-wide set serves every table as a prefix ([`Recurrence::shared`]): building it takes
/// two square roots and two divisions per (l, m), a real share of a prefilter bake at high order,
/// which asks for four tables. The set is kept for the
/// process's life: 16 bytes per (l, m) up to the highest order asked for (0.13 MB at 127), as
/// much as a table at that order took while it was in use.
#[derive(Clone, Debug)]
pub struct LegendreTable {
    order: usize,
    recurrence: Arc<Recurrence>,
}

/// The recurrence's coefficients up to some order (see the module's formulas).
#[derive(Debug)]
struct Recurrence {
    order: usize,
    a: Vec<f64>,
    b: Vec<f64>,
    diag: Vec<f64>,
    /// √(2l + 1): P̄_l^{l−1} = √(2l + 1) cos θ P̄_{l−1}^{l−1}.
    sub_diag: Vec<f64>,
}

impl Recurrence {
    fn new(order: usize) -> Self {
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
        let sub_diag = (0..=order).map(|l| ((2 * l + 1) as f64).sqrt()).collect();
        Recurrence { order, a, b, diag, sub_diag }
    }

    /// The process's coefficients, rebuilt only when an order beyond them is asked for (then
    /// to the next multiple of 64, so that a few rebuilds serve a run whose orders grow).
    fn shared(order: usize) -> Arc<Recurrence> {
        static SHARED: Mutex<Option<Arc<Recurrence>>> = Mutex::new(None);
        let mut shared = SHARED.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        match &*shared {
            Some(r) if r.order >= order => r.clone(),
            _ => {
                let r = Arc::new(Recurrence::new((order + 1).next_multiple_of(64) - 1));
                *shared = Some(r.clone());
                r
            }
        }
    }
}

impl LegendreTable {
    /// Coefficients for bands 0..=order.
    pub fn new(order: usize) -> Self {
        LegendreTable { order, recurrence: Recurrence::shared(order) }
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
    ///
    /// Band by band: the orders m ≤ l − 2 of band l follow from bands l − 1 and l − 2 alone,
    /// each independently of the others, and sit contiguously (at l² + l + m), as do their
    /// coefficients a_lm, b_lm. The loop over m therefore has no dependency chain and
    /// vectorizes, where running the recurrence up l one m at a time is a chain of dependent
    /// multiplies through scattered memory (about ten times slower at order 127). The two
    /// diagonal terms P̄_l^{l−1} and P̄_l^l close each band. Each value is the same expression of
    /// the same operands in either order, so the results are identical.
    pub fn eval_to_m(&self, cos_theta: f64, sin_theta: f64, max_m: usize, out: &mut [f64]) {
        let order = self.order;
        debug_assert!(out.len() >= super::count(order));
        let mut pmm = 0.5 / PI.sqrt();
        out[0] = pmm;
        for l in 1..=order {
            // Bands below l, and band l's orders m ≥ 0 (at l² + l + m).
            let (below, rest) = out.split_at_mut(l * l);
            let band = &mut rest[l..=2 * l];
            if l >= 2 {
                let k = (l - 2).min(max_m) + 1;
                let one = &below[(l - 1) * l..][..k];
                let two = &below[(l - 2) * (l - 1)..][..k];
                let at = super::index(l, 0);
                let (a, b) = (&self.recurrence.a[at..at + k], &self.recurrence.b[at..at + k]);
                for ((((p, &a), &b), &one), &two) in band[..k].iter_mut().zip(a).zip(b).zip(one).zip(two) {
                    *p = a * (cos_theta * one - b * two);
                }
            }
            if l - 1 <= max_m {
                // P̄_l^{l−1} = √(2l + 1) cos θ P̄_{l−1}^{l−1}.
                band[l - 1] = self.recurrence.sub_diag[l] * cos_theta * below[(l - 1) * (l + 1)];
            }
            if l <= max_m {
                pmm *= self.recurrence.diag[l] * sin_theta;
                band[l] = pmm;
            }
        }
    }

    /// The sectoral values P̄_m^m(cos θ_j) = P̄_{m−1}^{m−1} · √((2m+1)/(2m)) sin θ_j for every
    /// m ≤ order at many points, given sin θ_j ≥ 0: `out[m · n + j]` (n points). They start
    /// [`LegendreTable::column`], one column per m.
    pub fn diagonals(&self, sin_theta: &[f64]) -> Vec<f64> {
        let n = sin_theta.len();
        let mut out = vec![0.5 / PI.sqrt(); (self.order + 1) * n];
        for m in 1..=self.order {
            let (below, here) = out.split_at_mut(m * n);
            for ((p, &below), &s) in here[..n].iter_mut().zip(&below[(m - 1) * n..]).zip(sin_theta) {
                *p = below * (self.recurrence.diag[m] * s);
            }
        }
        out
    }

    /// The column of order m at many points at once: calls `visit(l, values)` for l = m..=order
    /// in turn, with values\[j\] = P̄_l^m(cos θ_j), from P̄_m^m at each point (`diagonal`, a row of
    /// [`LegendreTable::diagonals`]). The recurrence's coefficients a_lm, b_lm are the same at
    /// every point, so the loop over points has no dependency chain and vectorizes: the
    /// separable projection and synthesis run one column over all of a map's rows this way.
    /// Each value is the same expression as in [`LegendreTable::eval`], so it is identical.
    pub fn column(
        &self,
        m: usize,
        cos_theta: &[f64],
        diagonal: &[f64],
        scratch: &mut (Vec<f64>, Vec<f64>),
        mut visit: impl FnMut(usize, &[f64]),
    ) {
        let (two, one) = scratch;
        two.clear();
        two.extend_from_slice(diagonal);
        visit(m, two);
        if m == self.order {
            return;
        }
        one.clear();
        one.extend(two.iter().zip(cos_theta).map(|(&p, &c)| self.recurrence.sub_diag[m + 1] * c * p));
        visit(m + 1, one);
        for l in (m + 2)..=self.order {
            let i = super::index(l, m as isize);
            let (a, b) = (self.recurrence.a[i], self.recurrence.b[i]);
            // P̄_{l−2} is overwritten by P̄_l, then the two swap roles.
            for ((p2, &p1), &c) in two.iter_mut().zip(one.iter()).zip(cos_theta) {
                *p2 = a * (c * p1 - b * *p2);
            }
            std::mem::swap(two, one);
            visit(l, one);
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
            out[l] = self.recurrence.a[i] * (x * out[l - 1] - self.recurrence.b[i] * out[l - 2]);
        }
    }
}

/// Σ_j values\[j\] · parts\[q·n + j\] for the first `kinds` of q < K (n = values.len(); the rest
/// 0): a column's values against K weight vectors, as the projections sum them. Four
/// interleaved partial sums per q combined in a fixed order: vectorizable, and the same bits on
/// every run and thread count. When all K are asked for, the K sums advance together, four
/// nodes at a time, so their chains of additions overlap where one sum after another waits on
/// each addition (the projection's six sums over 64 rows).
pub fn column_sums<const K: usize>(values: &[f64], parts: &[f64], kinds: usize) -> [f64; K] {
    let n = values.len();
    if kinds >= K {
        return dot_rows(values, std::array::from_fn(|q| &parts[q * n..(q + 1) * n]));
    }
    std::array::from_fn(|q| if q < kinds { dot_rows(values, [&parts[q * n..(q + 1) * n]])[0] } else { 0.0 })
}

/// Σ_j values[j] · rows[q][j] for every q, in four lanes per q (j mod 4 below the last multiple
/// of 4, the rest after), combined as (lane 0 + lane 1) + (lane 2 + lane 3) + rest.
fn dot_rows<const K: usize>(values: &[f64], rows: [&[f64]; K]) -> [f64; K] {
    const LANES: usize = 4;
    let n = values.len();
    let whole = n - n % LANES;
    let mut lanes = [[0.0; LANES]; K];
    for (j, v) in values[..whole].chunks_exact(LANES).enumerate() {
        for (lanes, row) in lanes.iter_mut().zip(&rows) {
            let p = &row[j * LANES..][..LANES];
            for i in 0..LANES {
                lanes[i] += v[i] * p[i];
            }
        }
    }
    std::array::from_fn(|q| {
        let tail: f64 = values[whole..].iter().zip(&rows[q][whole..n]).map(|(v, p)| v * p).sum();
        let lanes = &lanes[q];
        (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + tail
    })
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

    /// The recurrence run up each column one m at a time, l rising (the textbook order): the
    /// band-by-band and many-point forms must give the same values to the bit.
    fn by_columns(t: &LegendreTable, c: f64, s: f64) -> Vec<f64> {
        let order = t.order();
        let mut out = vec![0.0; crate::sh::count(order)];
        let mut pmm = 0.5 / PI.sqrt();
        for m in 0..=order {
            if m > 0 {
                pmm *= t.recurrence.diag[m] * s;
            }
            out[crate::sh::index(m, m as isize)] = pmm;
            if m == order {
                break;
            }
            let mut p_prev = pmm;
            let mut p = ((2 * m + 3) as f64).sqrt() * c * pmm;
            out[crate::sh::index(m + 1, m as isize)] = p;
            for l in (m + 2)..=order {
                let i = crate::sh::index(l, m as isize);
                let next = t.recurrence.a[i] * (c * p - t.recurrence.b[i] * p_prev);
                out[i] = next;
                p_prev = p;
                p = next;
            }
        }
        out
    }

    #[test]
    fn bands_and_columns_are_the_textbook_recurrence_to_the_bit() {
        let order = 127;
        let t = LegendreTable::new(order);
        let xs = [-1.0, -0.999, -0.6, -0.01, 0.0, 0.3, 0.77, 0.9999, 1.0];
        let sins: Vec<f64> = xs.iter().map(|&x: &f64| (1.0 - x * x).max(0.0).sqrt()).collect();
        let diagonals = t.diagonals(&sins);
        let mut band_wise = vec![0.0; crate::sh::count(order)];
        let mut scratch = (Vec::new(), Vec::new());
        let expected: Vec<Vec<f64>> = xs.iter().zip(&sins).map(|(&c, &s)| by_columns(&t, c, s)).collect();
        for (j, (&c, &s)) in xs.iter().zip(&sins).enumerate() {
            t.eval(c, s, &mut band_wise);
            for l in 0..=order {
                for m in 0..=l {
                    let i = crate::sh::index(l, m as isize);
                    assert_eq!(band_wise[i].to_bits(), expected[j][i].to_bits(), "x = {c}, l = {l}, m = {m}");
                }
            }
        }
        for m in 0..=order {
            let mut next = m;
            t.column(m, &xs, &diagonals[m * xs.len()..(m + 1) * xs.len()], &mut scratch, |l, values| {
                assert_eq!(l, next);
                next += 1;
                for (j, v) in values.iter().enumerate() {
                    let want = expected[j][crate::sh::index(l, m as isize)];
                    assert_eq!(v.to_bits(), want.to_bits(), "x = {}, l = {l}, m = {m}", xs[j]);
                }
            });
            assert_eq!(next, order + 1);
        }
    }

    #[test]
    fn a_table_is_the_same_whichever_orders_were_asked_for_before() {
        // The process's coefficients grow with the largest order asked for: a low-order table
        // made before and after a high-order one, and the high-order one's low bands, agree to
        // the bit, with coefficients the formulas give afresh.
        let (c, s) = (-0.41f64, (1.0f64 - 0.41 * 0.41).sqrt());
        let eval = |t: &LegendreTable, order: usize| {
            let mut out = vec![0.0; crate::sh::count(t.order())];
            t.eval(c, s, &mut out);
            out.truncate(crate::sh::count(order));
            out
        };
        let before = eval(&LegendreTable::new(5), 5);
        let high = LegendreTable::new(300);
        assert!(high.recurrence.order >= 300);
        assert_eq!(eval(&high, 5), before);
        assert_eq!(eval(&LegendreTable::new(5), 5), before);
        let fresh = Recurrence::new(300);
        for i in 0..crate::sh::count(300) {
            assert_eq!((high.recurrence.a[i], high.recurrence.b[i]), (fresh.a[i], fresh.b[i]), "entry {i}");
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
