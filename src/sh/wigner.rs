//! A few rows of the real SH rotation about +Y, to high order, from Wigner's small d.
//!
//! The local SHRM (R&H 2002, App. C) needs, per row of reflection vectors at polar angle α, the
//! rows |q| ≤ P_B of D^l(R_y(α)) for every band l ≤ F_B. [`super::rotate::ShRotation`] builds
//! the whole (2l+1)² blocks by the Ivanic–Ruedenberg recurrence, which runs down every row of
//! band l − 1 to make one of band l: O(F³) a rotation, most of it rows nobody reads when
//! P_B ≪ F_B. Here each wanted element comes from the three-term recurrence of d^l_{q m}(α) in
//! l at fixed (q, m) (d^l is a Jacobi polynomial in cos α times powers of cos α/2 and sin α/2,
//! and this is the Jacobi polynomials' recurrence in degree):
//!
//!   (l − 1) √((l² − m²)(l² − q²)) d^l = (2l − 1)(l(l − 1) cos α − q m) d^{l−1}
//!                                       − l √(((l−1)² − m²)((l−1)² − q²)) d^{l−2},
//!
//! started at l₀ = max(|q|, |m|) from the one term of Wigner's sum that survives there (taken in
//! logarithms, so the tiny starts near α = 0 and π do not underflow before they need to), with
//! d^{l₀−1} = 0: O(P·F²) a rotation. The starts' logarithms and the recurrence's coefficients
//! do not depend on α, so a [`YRotationPlan`] computes them once for the rows of every angle. The recurrence runs up in degree like Legendre's; the tests
//! hold every element to the Ivanic–Ruedenberg matrix at order 40 and Σ_m (d^l_{qm})² = 1 at
//! l = 255 next to both poles, each to 10⁻¹⁰.
//!
//! Rotation about +Y preserves parity in y (φ → −φ), so the real matrix does not mix the cos qφ
//! (q ≥ 0) and sin qφ (q < 0) harmonics; its blocks are sums and differences of d^l_{q,±m}.

/// What the rows of every angle share: for each (q, m), the start of d^l_{q m} at l₀ and the
/// recurrence's coefficients, so that an angle costs three multiply-adds per element.
#[derive(Clone, Debug)]
pub struct YRotationPlan {
    p: usize,
    order: usize,
    /// Chains (q, m), q = 0..=min(p, order) major, m = −order..=order.
    chains: Vec<Chain>,
}

/// The recurrence of d^l_{q m} in l for one (q, m).
#[derive(Clone, Debug)]
struct Chain {
    q: isize,
    m: isize,
    /// ln |d^{l₀}| without its powers of cos α/2 and sin α/2, and those powers.
    ln_magnitude: f64,
    powers: (isize, isize),
    /// (−1)^{q − m + k} of Wigner's term.
    sign: f64,
    /// (c_l, e_l, b_l) for l = l₀ + 1 …: d^l = (c_l cos α − e_l) d^{l−1} − b_l d^{l−2}.
    steps: Vec<[f64; 3]>,
}

impl YRotationPlan {
    /// The plan for rows |q| ≤ `p` of bands 0 to `order`.
    pub fn new(order: usize, p: usize) -> Self {
        let ln_fact: Vec<f64> = std::iter::once(0.0)
            .chain((1..=2 * order + 2).scan(0.0, |acc, k| {
                *acc += (k as f64).ln();
                Some(*acc)
            }))
            .collect();
        let mut chains = Vec::new();
        for q in 0..=p.min(order) as isize {
            for m in -(order as isize)..=order as isize {
                let l0 = q.abs().max(m.abs());
                // The one surviving term of Wigner's sum at j = l₀: s_k = max(0, m − q) (the
                // bounds j + m − s_k ≥ 0, j − q − s_k ≥ 0 and q − m + s_k ≥ 0 then pin it).
                let (j, k) = (l0, (m - q).max(0));
                let lf = |n: isize| ln_fact[n as usize];
                let ln_magnitude = 0.5 * (lf(j + q) + lf(j - q) + lf(j + m) + lf(j - m))
                    - lf(j + m - k)
                    - lf(k)
                    - lf(q - m + k)
                    - lf(j - q - k);
                let powers = (2 * j + m - q - 2 * k, q - m + 2 * k);
                let sign = if (q - m + k) % 2 == 0 { 1.0 } else { -1.0 };
                let (qf, mf) = (q as f64, m as f64);
                let steps = ((l0 + 1) as usize..=order)
                    .map(|l| {
                        if l == 1 {
                            // l₀ = 0 (q = m = 0): Legendre's P₁, where the general step divides
                            // 0 by 0.
                            return [1.0, 0.0, 0.0];
                        }
                        let lf = l as f64;
                        let den = (lf - 1.0) * ((lf * lf - mf * mf) * (lf * lf - qf * qf)).sqrt();
                        let a = (2.0 * lf - 1.0) / den;
                        let b = lf * (((lf - 1.0).powi(2) - mf * mf) * ((lf - 1.0).powi(2) - qf * qf)).sqrt() / den;
                        [a * lf * (lf - 1.0), a * qf * mf, b]
                    })
                    .collect();
                chains.push(Chain { q, m, ln_magnitude, powers, sign, steps });
            }
        }
        YRotationPlan { p, order, chains }
    }

    /// d^l_{q m}(α) for the chain's l ≥ l₀ into `out[l]` (lower entries untouched), given
    /// cos α, cos α/2 and sin α/2.
    fn small_d(chain: &Chain, cos_a: f64, c: f64, s: f64, out: &mut [f64]) {
        let l0 = chain.q.abs().max(chain.m.abs()) as usize;
        if l0 >= out.len() {
            return;
        }
        let (pc, ps) = chain.powers;
        let magnitude = (chain.ln_magnitude + pc as f64 * c.abs().ln() + ps as f64 * s.abs().ln()).exp();
        let mut sign = chain.sign;
        if c < 0.0 && pc % 2 == 1 {
            sign = -sign;
        }
        if s < 0.0 && ps % 2 == 1 {
            sign = -sign;
        }
        // 0^0 = 1: a power that is zero contributes nothing whatever its base.
        let start = if (pc > 0 && c == 0.0) || (ps > 0 && s == 0.0) { 0.0 } else { sign * magnitude };
        let (mut prev2, mut prev) = (0.0, start);
        out[l0] = start;
        for (o, [cl, el, bl]) in out[l0 + 1..].iter_mut().zip(&chain.steps) {
            let cur = (cl * cos_a - el) * prev - bl * prev2;
            *o = cur;
            prev2 = prev;
            prev = cur;
        }
    }

    /// The rows |q| ≤ p of D^l(R_y(`alpha`)) for l ≤ order.
    pub fn rows(&self, alpha: f64) -> YRotationRows {
        let (p, order) = (self.p, self.order);
        let mut values = vec![0.0; (2 * p + 1) * (order + 1) * (order + 1)];
        let offset = |l: usize, q: isize, m: isize| offset(p, l, q, m);
        let cos_a = alpha.cos();
        let (c, s) = ((0.5 * alpha).cos(), (0.5 * alpha).sin());
        let sqrt2 = std::f64::consts::SQRT_2;
        let mut d = vec![0.0; order + 1];
        let mut d_neg = vec![0.0; order + 1];
        let width = 2 * order + 1;
        for q in 0..=p.min(order) as isize {
            let chains = &self.chains[q as usize * width..(q as usize + 1) * width];
            for m in 0..=order as isize {
                Self::small_d(&chains[(order as isize + m) as usize], cos_a, c, s, &mut d);
                Self::small_d(&chains[(order as isize - m) as usize], cos_a, c, s, &mut d_neg);
                // Real Y_{l,±m} ∝ (Y_l^m ± (−1)^m Y_l^{−m}); prtkit's real harmonics and the
                // active rotation add the factor (−1)^{q+m} (d^l_{qm}(−α) = d^l_{mq}(α)).
                let parity = |k: isize| if k % 2 == 0 { 1.0 } else { -1.0 };
                let (sign_m, sign_qm) = (parity(m), parity(q + m));
                for l in q.max(m) as usize..=order {
                    let (plus, minus) = (d[l] + sign_m * d_neg[l], d[l] - sign_m * d_neg[l]);
                    match (q, m) {
                        (0, 0) => values[offset(l, 0, 0)] = d[l],
                        (0, _) | (_, 0) => values[offset(l, q, m)] = sign_qm * sqrt2 * d[l],
                        _ => {
                            values[offset(l, q, m)] = sign_qm * plus;
                            values[offset(l, -q, -m)] = sign_qm * minus;
                        }
                    }
                }
            }
        }
        YRotationRows { p, order, values }
    }
}

/// Rows |q| ≤ p of the real SH rotation matrix of R_y(α), bands 0 to `order`: element (l, q, m)
/// equals [`super::rotate::ShRotation::element`] of
/// `ShRotation::new(DMat3::from_rotation_y(α), order)`.
#[derive(Clone, Debug)]
pub struct YRotationRows {
    p: usize,
    order: usize,
    /// Element (l, q, m) at [`offset`] (rows |q| > l stay zero).
    values: Vec<f64>,
}

impl YRotationRows {
    /// The rows |q| ≤ `p` of D^l(R_y(`alpha`)) for l ≤ `order` (one angle; many angles share a
    /// [`YRotationPlan`]).
    pub fn new(alpha: f64, order: usize, p: usize) -> Self {
        YRotationPlan::new(order, p).rows(alpha)
    }

    /// Element (q, m) of band l (|q| ≤ p, |m| ≤ l).
    #[inline]
    pub fn element(&self, l: usize, q: isize, m: isize) -> f64 {
        debug_assert!(l <= self.order && q.unsigned_abs() <= self.p && m.unsigned_abs() <= l);
        self.values[offset(self.p, l, q, m)]
    }
}

/// Where element (l, q, m) of rows |q| ≤ p is kept: band l at (2p+1)·l², row q + p of 2l + 1.
#[inline]
fn offset(p: usize, l: usize, q: isize, m: isize) -> usize {
    (2 * p + 1) * l * l + (q + p as isize) as usize * (2 * l + 1) + (m + l as isize) as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::rotate::ShRotation;
    use glam::DMat3;
    use std::f64::consts::PI;

    #[test]
    fn the_mirrored_angle_flips_signs_only() {
        // D^l(R_y(α − π)) = D^l(R_y(α)) D^l(R_y(π)), D^l(R_y(π)) = diag((−1)^l ε_m) (x, z → −x, −z:
        // the inversion times the mirror y → −y, ε_m = −1 for the sines m < 0), and
        // D^l(R_y(α)) = T D^l(R_y(−α)) T with T = diag((−1)^m ε_m) (the mirror x → −x turns
        // R_y(α) into R_y(−α)): element (q, m) at −(π − α) is (−1)^{l+q+m} ε_q times that at −α.
        let (order, p) = (30, 6);
        let parity = |k: isize| if k.rem_euclid(2) == 0 { 1.0 } else { -1.0 };
        for alpha in [0.1, 0.37, 1.3, 1.5] {
            let (rows, mirrored) = (YRotationRows::new(-alpha, order, p), YRotationRows::new(alpha - PI, order, p));
            for l in 0..=order {
                for q in -(p.min(l) as isize)..=p.min(l) as isize {
                    for m in -(l as isize)..=l as isize {
                        let epsilon = if q < 0 { -1.0 } else { 1.0 };
                        let expected = parity(l as isize + q + m) * epsilon * rows.element(l, q, m);
                        let got = mirrored.element(l, q, m);
                        assert!((got - expected).abs() < 1e-9, "α {alpha}, ({l}, {q}, {m}): {got} vs {expected}");
                    }
                }
            }
        }
    }

    #[test]
    fn rows_equal_the_ivanic_ruedenberg_matrix() {
        let (order, p) = (40, 6);
        for alpha in [0.0, 0.37, 1.3, 2.2, 3.1] {
            let full = ShRotation::new(DMat3::from_rotation_y(alpha), order);
            let rows = YRotationRows::new(alpha, order, p);
            let mut worst = (0.0f64, 0, 0, 0);
            for l in 0..=order {
                let li = l as isize;
                for q in -(p.min(l) as isize)..=(p.min(l) as isize) {
                    for m in -li..=li {
                        let e = (rows.element(l, q, m) - full.element(l, q, m)).abs();
                        if e > worst.0 {
                            worst = (e, l, q, m);
                        }
                    }
                }
            }
            assert!(worst.0 < 1e-10, "α = {alpha}: worst (error, l, q, m) {worst:?}");
        }
    }

    #[test]
    fn rows_stay_unit_vectors_to_band_255_near_the_poles() {
        let (order, p) = (255, 6);
        for alpha in [PI / 512.0, 0.7, PI - PI / 512.0] {
            let rows = YRotationRows::new(alpha, order, p);
            let mut worst = 0.0f64;
            for l in [p, 100, 200, 255] {
                let li = l as isize;
                for q in -(p as isize)..=(p as isize) {
                    let norm: f64 = (-li..=li).map(|m| rows.element(l, q, m).powi(2)).sum();
                    worst = worst.max((norm - 1.0).abs());
                }
            }
            assert!(worst < 1e-10, "α = {alpha}: |Σ_m d² − 1| up to {worst}");
        }
    }
}
