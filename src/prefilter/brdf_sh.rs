//! BRDF spherical-harmonic coefficients ρ̂_lpq in the reflection-vector parameterization
//! (Ramamoorthi & Hanrahan 2002, §3.1, eq. 13, App. C step 1), and order selection (§5.1).
//!
//! In the frame whose +Z is the reflection vector R, an isotropic ρ̂ depends on θ_i, θ_o and
//! φ = φ_o − φ_i only, and with prtkit's real SH
//!
//!   ρ̂(ω_i, ω_o) = Σ_{l,p} Σ_{|q| ≤ min(l,p)} ρ̂_{lp|q|} Y_lq(ω_i) Y_pq(ω_o),
//!
//! (the paper's eq. 13; real SH keep it diagonal in q because ρ̂ is even in φ). Integrating the
//! φ_i, φ_o dependence of Y_lq Y_pq out gives, for every q ≥ 0,
//!
//!   ρ̂_lpq = ∫∫ P̄_l^q(cos θ_i) P̄_p^q(cos θ_o) ρ̂_q(θ_i, θ_o) sin θ_i sin θ_o dθ_i dθ_o,
//!   ρ̂_q(θ_i, θ_o) = 2π ∫_0^{2π} ρ̂(θ_i, θ_o, φ) cos(qφ) dφ,
//!
//! computed in the three separable steps of App. C: a φ-sum per (θ_i, θ_o), a θ_o-sum per
//! (θ_i, p, q), a θ_i-sum per (l, p, q). Gauss–Legendre in θ (nodes uniform in angle resolve
//! lobes near θ = 0) and the trapezoid rule in φ (exact for the trigonometric polynomials).

use crate::quadrature::gauss_legendre_cached as gauss_legendre;
use crate::sh::legendre::{column_sums, LegendreTable};
use crate::sh::{count, index};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Quadrature resolution for the BRDF transform.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BrdfGrid {
    /// Gauss–Legendre nodes in θ_i ∈ [0, π] (S_ρ of the paper).
    pub theta_i: usize,
    /// Gauss–Legendre nodes in θ_o ∈ [0, π] (T_ρ).
    pub theta_o: usize,
    /// Uniform samples in φ ∈ [0, 2π) (T_ρ).
    pub phi: usize,
}

/// ρ̂_lpq up to orders (F, P), per RGB channel, with the BRDF's total energy.
#[derive(Clone, Debug, PartialEq)]
pub struct BrdfSh {
    /// Highest l.
    pub f: usize,
    /// Highest p.
    pub p: usize,
    coeffs: Vec<[f64; 3]>,
    /// ∫∫ |ρ̂|² dω_i dω_o summed over RGB: the energy ε is relative to.
    pub total_energy: f64,
}

impl BrdfSh {
    fn slot(&self, l: usize, p: usize, q: usize) -> usize {
        (l * (self.p + 1) + p) * (self.p + 1) + q
    }

    /// ρ̂_{lp|q|} (zero where |q| > min(l, p) or beyond the computed orders).
    pub fn get(&self, l: usize, p: usize, q: isize) -> [f64; 3] {
        let q = q.unsigned_abs();
        if l > self.f || p > self.p || q > l.min(p) {
            return [0.0; 3];
        }
        self.coeffs[self.slot(l, p, q)]
    }

    /// Σ_{l ≤ F, p ≤ P, |q| ≤ min(l,p)} |ρ̂_{lp|q|}|² over RGB (each q > 0 counted for ±q).
    pub fn energy(&self, f: usize, p: usize) -> f64 {
        let mut e = 0.0;
        for l in 0..=f.min(self.f) {
            for pp in 0..=p.min(self.p) {
                for q in 0..=l.min(pp) {
                    let c = self.coeffs[self.slot(l, pp, q)];
                    let mult = if q == 0 { 1.0 } else { 2.0 };
                    e += mult * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
                }
            }
        }
        e
    }

    /// 1 − energy(F, P)/total: the fraction of BRDF energy an (F, P) expansion misses.
    pub fn residual(&self, f: usize, p: usize) -> f64 {
        if self.total_energy <= 0.0 {
            return 0.0;
        }
        (1.0 - self.energy(f, p) / self.total_energy).max(0.0)
    }

    /// The orders for tolerance ε (R&H 2002 §5.1, App. C): the smallest P for which the full
    /// F keeps 1 − ε of the energy, then the smallest F with that P. `None` if even (F, P) of
    /// this table falls short.
    pub fn select_orders(&self, epsilon: f64) -> Option<(usize, usize)> {
        if self.residual(self.f, self.p) > epsilon {
            return None;
        }
        let p = (0..=self.p).find(|&p| self.residual(self.f, p) <= epsilon)?;
        let f = (0..=self.f).find(|&f| self.residual(f, p) <= epsilon)?;
        Some((f, p))
    }

    /// The same coefficients cut to (F, P) (the total energy is kept).
    pub fn truncated(&self, f: usize, p: usize) -> BrdfSh {
        let (f, p) = (f.min(self.f), p.min(self.p));
        let mut out =
            BrdfSh { f, p, coeffs: vec![[0.0; 3]; (f + 1) * (p + 1) * (p + 1)], total_energy: self.total_energy };
        for l in 0..=f {
            for pp in 0..=p {
                for q in 0..=l.min(pp) {
                    let s = out.slot(l, pp, q);
                    out.coeffs[s] = self.get(l, pp, q as isize);
                }
            }
        }
        out
    }

    /// For a radially symmetric BRDF: the zonal kernel k_l = Λ_l ρ̂_l that multiplies lighting
    /// coefficients to give the reflection map's, B_lm = k_l L_lm (eq. 5 with ρ̂_l = ρ̂_l00/√(4π)).
    pub fn radial_kernel(&self, l: usize) -> [f64; 3] {
        let c = self.get(l, 0, 0);
        let k = crate::sh::convolve::lambda(l) / (4.0 * PI).sqrt();
        [c[0] * k, c[1] * k, c[2] * k]
    }
}

/// ρ̂_lpq of an isotropic ρ̂(cos θ_i, cos θ_o, φ) given in the reflection frame, up to (F, P).
pub fn from_isotropic(
    rho_hat: impl Fn(f64, f64, f64) -> [f64; 3] + Sync,
    f: usize,
    p: usize,
    grid: BrdfGrid,
) -> BrdfSh {
    let nodes_i = angle_nodes(grid.theta_i);
    let nodes_o = angle_nodes(grid.theta_o);
    // ρ̂ is even in φ (reciprocity and isotropy), so the trapezoid rule over the full circle
    // with an even number of samples equals samples k = 0..=n/2 with weights 1, 2, …, 2, 1.
    let nphi = (grid.phi.max(2 * p + 2) + 1) & !1;
    let dphi = 2.0 * PI / nphi as f64;
    let half = nphi / 2;
    let phi_weight: Vec<f64> = (0..=half).map(|k| if k == 0 || k == half { 1.0 } else { 2.0 }).collect();
    let cos_q: Vec<Vec<f64>> =
        (0..=p).map(|q| (0..=half).map(|k| phi_weight[k] * (q as f64 * k as f64 * dphi).cos()).collect()).collect();
    let table_o = LegendreTable::new(p);

    // Steps 1 and 2 per θ_i node (parallel; each node's result is independent, so the order of
    // the final θ_i sum is fixed and the output deterministic).
    let per_theta_i: Vec<(Vec<[f64; 3]>, f64)> = nodes_i
        .par_iter()
        .map(|&(theta_i, w_i)| {
            let cos_i = theta_i.cos();
            let mut rho_pq = vec![[0.0; 3]; (p + 1) * (p + 1)]; // [p][q]
            let mut energy = 0.0;
            let mut plm = vec![0.0; count(p)];
            let mut samples = vec![[0.0; 3]; half + 1];
            for &(theta_o, w_o) in nodes_o.iter() {
                let cos_o = theta_o.cos();
                for (k, s) in samples.iter_mut().enumerate() {
                    *s = rho_hat(cos_i, cos_o, k as f64 * dphi);
                    energy += phi_weight[k] * w_o * (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
                }
                table_o.eval(cos_o, theta_o.sin(), &mut plm);
                for q in 0..=p {
                    // Step 1: ρ̂_q(θ_i, θ_o) = 2π ∫ ρ̂ cos(qφ) dφ.
                    let mut rq = [0.0; 3];
                    for (s, c) in samples.iter().zip(&cos_q[q]) {
                        for ch in 0..3 {
                            rq[ch] += s[ch] * c;
                        }
                    }
                    // Step 2: ρ̂_pq(θ_i) = ∫ ρ̂_q P̄_p^q(cos θ_o) sin θ_o dθ_o (w_o includes sin θ_o).
                    for pp in q..=p {
                        let weight = 2.0 * PI * dphi * w_o * plm[index(pp, q as isize)];
                        let slot = &mut rho_pq[pp * (p + 1) + q];
                        for ch in 0..3 {
                            slot[ch] += weight * rq[ch];
                        }
                    }
                }
            }
            (rho_pq, w_i * energy * 2.0 * PI * dphi)
        })
        .collect();

    step_3(f, p, &nodes_i, &per_theta_i)
}

/// App. C step 3: ρ̂_lpq = ∫ ρ̂_pq(θ_i) P̄_l^q(cos θ_i) sin θ_i dθ_i from steps 1–2's ρ̂_pq and
/// energy per θ_i node, summed in the nodes' order.
fn step_3(f: usize, p: usize, nodes_i: &[(f64, f64)], per_theta_i: &[(Vec<[f64; 3]>, f64)]) -> BrdfSh {
    let table_i = LegendreTable::new(f);
    let mut out = BrdfSh { f, p, coeffs: vec![[0.0; 3]; (f + 1) * (p + 1) * (p + 1)], total_energy: 0.0 };
    let mut plm = vec![0.0; count(f)];
    for (&(theta_i, w_i), (rho_pq, energy)) in nodes_i.iter().zip(per_theta_i) {
        // Only the orders q ≤ P are read: O(F·P) per node, not O(F²).
        table_i.eval_to_m(theta_i.cos(), theta_i.sin(), p, &mut plm);
        out.total_energy += energy;
        for l in 0..=f {
            for pp in 0..=p {
                for q in 0..=l.min(pp) {
                    let w = w_i * plm[index(l, q as isize)];
                    let src = rho_pq[pp * (p + 1) + q];
                    let s = out.slot(l, pp, q);
                    for ch in 0..3 {
                        out.coeffs[s][ch] += w * src[ch];
                    }
                }
            }
        }
    }
    out
}

/// ρ̂_l00 of a radially symmetric ρ̂ = u(R·ω_i) (independent of ω_o), up to order F:
/// ρ̂_l00 = √(4π) · 2π ∫ u(x) P̄_l^0(x) dx, and the energy ∫∫ ρ̂² = 4π · 2π ∫ u² dx.
/// Gauss–Legendre with `nodes` nodes on each of [−1, 0] and [0, 1]: lobes such as Phong's and the
/// clamped cosine are polynomials on each half with a kink at 0, so the rule is exact for them
/// whenever the degree (s + F) is below 2·nodes.
pub fn from_radial(u: impl Fn(f64) -> [f64; 3] + Sync, f: usize, nodes: usize) -> BrdfSh {
    let table = LegendreTable::new(f);
    let scale = (4.0 * PI).sqrt() * 2.0 * PI;
    let half = gauss_legendre(nodes);
    let points: Vec<(f64, f64)> = half
        .iter()
        .map(|&(t, w)| (0.5 * (t - 1.0), 0.5 * w))
        .chain(half.iter().map(|&(t, w)| (0.5 * (t + 1.0), 0.5 * w)))
        .collect();
    // Fixed chunks of nodes, summed in order: the same for any thread count. Within a chunk the
    // zonal column P̄_l^0 runs over all its nodes at once (`LegendreTable::column`).
    let chunks: Vec<(Vec<[f64; 3]>, f64)> = points
        .par_chunks(256)
        .map(|chunk| {
            // Lobes about R vanish on a whole half (Phong's below the horizon of R): no work
            // there.
            let lit: Vec<(f64, f64, [f64; 3])> =
                chunk.iter().map(|&(x, w)| (x, w, u(x))).filter(|p| p.2 != [0.0; 3]).collect();
            let energy: f64 =
                lit.iter().map(|(_, w, v)| 4.0 * PI * 2.0 * PI * w * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])).sum();
            let n = lit.len();
            let xs: Vec<f64> = lit.iter().map(|p| p.0).collect();
            // A grey lobe (every radially symmetric model's) needs one dot product per band.
            let channels = if lit.iter().all(|(_, _, v)| v[1] == v[0] && v[2] == v[0]) { 1 } else { 3 };
            // [channel][node]: the weight times the lobe.
            let weighted: Vec<f64> = (0..channels).flat_map(|c| lit.iter().map(move |(_, w, v)| w * v[c])).collect();
            let mut coeffs = vec![[0.0; 3]; f + 1];
            let diagonal = vec![0.5 / PI.sqrt(); n];
            table.column(0, &xs, &diagonal, &mut (Vec::new(), Vec::new()), |l, values| {
                let sums = column_sums::<3>(values, &weighted, channels).map(|s| scale * s);
                coeffs[l] = if channels == 1 { [sums[0]; 3] } else { sums };
            });
            (coeffs, energy)
        })
        .collect();
    let mut out = BrdfSh { f, p: 0, coeffs: vec![[0.0; 3]; f + 1], total_energy: 0.0 };
    for (coeffs, energy) in &chunks {
        out.total_energy += energy;
        for (o, c) in out.coeffs.iter_mut().zip(coeffs) {
            for ch in 0..3 {
                o[ch] += c[ch];
            }
        }
    }
    out
}

/// The radial form of a grey lobe given by its zonal SH coefficients k_l = ∫ u(cos γ) Y_l0 dω
/// and its energy ∫ u² dω, for lobes whose own quadrature computes them (the GGX split-sum
/// lobe): ρ̂_l00 = √(4π) k_l and the energy of all three channels, as [`from_radial`] would
/// find by Gauss–Legendre.
pub fn from_zonal(k: &[f64], lobe_energy: f64) -> BrdfSh {
    let scale = (4.0 * PI).sqrt();
    BrdfSh {
        f: k.len() - 1,
        p: 0,
        coeffs: k.iter().map(|&k| [scale * k; 3]).collect(),
        total_energy: 3.0 * 4.0 * PI * lobe_energy,
    }
}

/// Gauss–Legendre nodes in θ ∈ [0, π] with weights that include sin θ.
fn angle_nodes(n: usize) -> Vec<(f64, f64)> {
    gauss_legendre(n.max(1))
        .iter()
        .map(|&(x, w)| {
            let theta = 0.5 * PI * (x + 1.0);
            (theta, 0.5 * PI * w * theta.sin())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn phong(s: f64) -> impl Fn(f64) -> [f64; 3] {
        move |x: f64| {
            let v = if x > 0.0 { (s + 1.0) / (2.0 * PI) * x.powf(s) } else { 0.0 };
            [v; 3]
        }
    }

    #[test]
    fn lambert_kernel_is_the_clamped_cosine_over_pi() {
        let b = from_radial(|x| [x.max(0.0) / PI; 3], 10, 400);
        for l in 0..=10 {
            let want = crate::sh::convolve::clamped_cosine(l) / PI;
            assert!((b.radial_kernel(l)[0] - want).abs() < 1e-5, "l={l}: {} vs {want}", b.radial_kernel(l)[0]);
        }
    }

    #[test]
    fn phong_kernel_matches_an_independent_integral_and_the_gaussian_approximation() {
        // Λ_l ρ̂_l = (s+1) ∫_0^1 x^s P_l(x) dx (Funk–Hecke), by a fine midpoint rule with the
        // plain Legendre recurrence — no Gauss nodes, no normalized tables.
        let legendre = |l: usize, x: f64| {
            let mut p = vec![0.0; l + 1];
            crate::sh::legendre::legendre_polynomials(x, &mut p);
            p[l]
        };
        for s in [8.0, 32.0, 128.0] {
            let b = from_radial(phong(s), 30, 400);
            let n = 200_000;
            for l in 0..=30usize {
                let exact: f64 = (0..n)
                    .map(|i| {
                        let x = (i as f64 + 0.5) / n as f64;
                        (s + 1.0) * x.powf(s) * legendre(l, x)
                    })
                    .sum::<f64>()
                    / n as f64;
                assert!(
                    (b.radial_kernel(l)[0] - exact).abs() < 1e-6,
                    "s={s} l={l}: {} vs {exact}",
                    b.radial_kernel(l)[0]
                );
                // R&H 2002 §6.3: Λ_l ρ̂_l ≈ exp(−l²/2s), "accurate" for large s only (at s = 8,
                // l = 2 it is off by 0.05).
                let approx = (-((l * l) as f64) / (2.0 * s)).exp();
                if s >= 32.0 {
                    assert!((exact - approx).abs() < 0.05, "s={s} l={l}: {exact} vs ≈{approx}");
                }
            }
            // A normalized lobe has Λ_0 ρ̂_0 = ∫ u dω = 1.
            assert!((b.radial_kernel(0)[0] - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn isotropic_transform_of_a_radial_lobe_has_only_p_zero() {
        // ρ̂ = u(cos θ_i) in the reflection frame: the 3-D transform must give ρ̂_l00 of the 1-D
        // one and nothing for p > 0.
        let s = 16.0;
        let u = phong(s);
        let general = from_isotropic(|ci, _co, _phi| u(ci), 20, 3, BrdfGrid { theta_i: 160, theta_o: 24, phi: 16 });
        let radial = from_radial(phong(s), 20, 400);
        for l in 0..=20 {
            assert!((general.get(l, 0, 0)[0] - radial.get(l, 0, 0)[0]).abs() < 1e-4 * radial.get(0, 0, 0)[0]);
            for p in 1..=3 {
                for q in 0..=p.min(l) {
                    assert!(general.get(l, p, q as isize)[0].abs() < 1e-10, "({l},{p},{q})");
                }
            }
        }
        assert!((general.total_energy / radial.total_energy - 1.0).abs() < 1e-4);
    }

    #[test]
    fn parseval_for_a_band_limited_brdf() {
        // ρ̂ = Y_{2,1}(ω_i) Y_{1,1}(ω_o) + Y_{2,-1}(ω_i) Y_{1,-1}(ω_o) + 0.5 Y_00 Y_00, written
        // through its (θ_i, θ_o, φ) form: ρ̂_{2,1,1} = 1, ρ̂_{0,0,0} = 0.5, energy 2·1 + 0.25.
        use crate::sh::basis::eval_basis;
        let table = LegendreTable::new(2);
        let rho = |ci: f64, co: f64, phi: f64| {
            let (mut yi, mut yo) = (vec![0.0; 9], vec![0.0; 9]);
            eval_basis(&table, ci, (1.0 - ci * ci).sqrt(), 0.0, &mut yi);
            eval_basis(&table, co, (1.0 - co * co).sqrt(), phi, &mut yo);
            let v =
                yi[index(2, 1)] * yo[index(1, 1)] + yi[index(2, -1isize)] * yo[index(1, -1isize)] + 0.5 * yi[0] * yo[0];
            [v, 0.0, 0.0]
        };
        let b = from_isotropic(rho, 4, 3, BrdfGrid { theta_i: 16, theta_o: 16, phi: 12 });
        assert!((b.get(2, 1, 1)[0] - 1.0).abs() < 1e-12);
        assert!((b.get(0, 0, 0)[0] - 0.5).abs() < 1e-12);
        assert!((b.energy(4, 3) - 2.25).abs() < 1e-12);
        assert!((b.total_energy - 2.25).abs() < 1e-12);
        assert_eq!(b.select_orders(1e-9), Some((2, 1)));
    }
}
