//! GGX (Trowbridge–Reitz) microfacet distribution, the height-correlated Smith visibility, and
//! the split-sum prefilter lobe with its zonal spherical-harmonic coefficients.
//!
//! Conventions (those of glTF and Filament): a material states its **perceptual roughness** r ∈
//! [0, 1]; the distribution's width is **α = r²** (Burley 2012; Karis 2013, "Real Shading in
//! Unreal Engine 4", §"Specular D").
//!
//! - D(h) = α² / (π ((n·h)²(α² − 1) + 1)²) (Walter et al. 2007, "Microfacet Models for Refraction
//!   through Rough Surfaces", eq. 33), normalized so that ∫ D(h) (n·h) dω_h = 1.
//! - Smith's Λ for GGX: Λ(ω) = (−1 + √(1 + α² tan² θ)) / 2 (Heitz 2014, "Understanding the
//!   Masking-Shadowing Function in Microfacet-Based BRDFs", eq. 72).
//! - Height-correlated masking-shadowing G2 = 1 / (1 + Λ(v) + Λ(l)) (Heitz 2014, eq. 99), and the
//!   visibility V = G2 / (4 (n·l)(n·v)), which simplifies to Filament's `V_SmithGGXCorrelated`
//!   0.5 / ((n·v)√((n·l)²(1 − α²) + α²) + (n·l)√((n·v)²(1 − α²) + α²)).
//!
//! ## The split-sum prefilter lobe
//!
//! Karis (2013) prefilters the environment for a roughness under the assumption N = V = R and
//! estimates it by importance sampling: half vectors h are drawn with pdf_h = D(h)(n·h), the light
//! direction is l = reflect(−v, h), and the estimate is Σ L(l_k)(n·l_k) / Σ (n·l_k). The change of
//! variables from h to l has Jacobian 1/(4 v·h) (Walter et al. 2007, eq. 14), so
//! pdf_l = D(h)(n·h)/(4 v·h); with v = n, v·h = n·h and pdf_l = D(h)/4. The estimator therefore
//! converges to
//!
//!   ∫ L(l) max(n·l, 0) D(h) dω_l / ∫ max(n·l, 0) D(h) dω_l,
//!
//! a normalized zonal kernel about R whose weight at angle θ from R is D(h)·max(cos θ, 0), with h
//! halfway between N = R and L: n·h = cos(θ/2). Filament's cmgen and Khronos' glTF-IBL-Sampler
//! compute this same lobe. prtkit evaluates it without sampling: [`SplitSumLobe`] holds the kernel
//! k(θ) = D(cos(θ/2)) max(cos θ, 0) / Z with Z = ∫ D(cos(θ/2)) max(cos θ, 0) dω, so ∫ k dω = 1.
//!
//! All integrals here are deterministic Gauss–Legendre quadratures in the angle, on pieces that
//! grow geometrically from the lobe width (≈ 2α in θ), so that lobes of any sharpness are resolved
//! and the rule converges to ~1e-13.

use crate::quadrature::gauss_legendre_cached as gauss_legendre;
use crate::sh::legendre::LegendreTable;
use std::f64::consts::{FRAC_PI_2, PI};

/// Errors of the GGX constructors.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GgxError {
    /// The perceptual roughness is outside [0, 1] or not a number.
    #[error("GGX perceptual roughness must be in [0, 1], got {0}")]
    Roughness(f64),
    /// The split-sum lobe of roughness 0 is a Dirac delta: there is no kernel to evaluate.
    #[error("the split-sum lobe needs a perceptual roughness > 0 (roughness 0 is the mirror direction itself)")]
    ZeroRoughness,
}

/// α = r²: the GGX width for a perceptual roughness r (Karis 2013).
#[inline]
pub fn alpha(perceptual_roughness: f64) -> f64 {
    perceptual_roughness * perceptual_roughness
}

/// The GGX (Trowbridge–Reitz) distribution and its height-correlated Smith visibility.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    alpha: f64,
}

impl Ggx {
    /// GGX of perceptual roughness r ∈ [0, 1] (α = r²).
    pub fn new(perceptual_roughness: f64) -> Result<Self, GgxError> {
        if !(0.0..=1.0).contains(&perceptual_roughness) {
            return Err(GgxError::Roughness(perceptual_roughness));
        }
        Ok(Ggx { alpha: alpha(perceptual_roughness) })
    }

    /// The perceptual roughness r = √α.
    pub fn perceptual_roughness(&self) -> f64 {
        self.alpha.sqrt()
    }

    /// α = r².
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// D(h) from n·h (Walter et al. 2007, eq. 33).
    pub fn d(&self, n_dot_h: f64) -> f64 {
        let c2 = n_dot_h * n_dot_h;
        self.d_half_angle(c2, (1.0 - c2).max(0.0))
    }

    /// D from cos² θ_h and sin² θ_h separately: α² / (π (α² cos² θ_h + sin² θ_h)²), the same
    /// function as [`Ggx::d`] without the cancellation of 1 − cos² θ_h near the peak, which
    /// matters when α² is below the rounding error of n·h.
    #[inline]
    pub fn d_half_angle(&self, cos2_h: f64, sin2_h: f64) -> f64 {
        let a2 = self.alpha * self.alpha;
        let t = a2 * cos2_h + sin2_h;
        a2 / (PI * t * t)
    }

    /// Smith's Λ for GGX at a direction with cosine μ to the normal (Heitz 2014, eq. 72):
    /// (−1 + √(1 + α² tan² θ)) / 2.
    pub fn lambda(&self, cos_theta: f64) -> f64 {
        let c2 = cos_theta * cos_theta;
        let tan2 = (1.0 - c2).max(0.0) / c2;
        0.5 * (-1.0 + (1.0 + self.alpha * self.alpha * tan2).sqrt())
    }

    /// Height-correlated masking-shadowing G2(v, l) = 1 / (1 + Λ(v) + Λ(l)) (Heitz 2014, eq. 99).
    pub fn smith_g2(&self, n_dot_v: f64, n_dot_l: f64) -> f64 {
        1.0 / (1.0 + self.lambda(n_dot_v) + self.lambda(n_dot_l))
    }

    /// V = G2 / (4 (n·l)(n·v)) in Filament's `V_SmithGGXCorrelated` form, finite as n·l or n·v → 0.
    #[inline]
    pub fn visibility(&self, n_dot_v: f64, n_dot_l: f64) -> f64 {
        let a2 = self.alpha * self.alpha;
        let ggx_v = n_dot_l * (n_dot_v * n_dot_v * (1.0 - a2) + a2).sqrt();
        let ggx_l = n_dot_v * (n_dot_l * n_dot_l * (1.0 - a2) + a2).sqrt();
        0.5 / (ggx_v + ggx_l)
    }
}

/// Gauss–Legendre nodes and weights on [lo, hi] for integrands with a lobe of width `width` at
/// 0: pieces [0, w/8], [w/8, w/4], … double in length up to `max_piece`, then stay that long.
/// Each piece gets `order` nodes. The integrand's poles lie ~`width` off the real axis at 0,
/// so on every piece they are at least a piece length away and the rule converges geometrically.
///
/// `roots` are points in (lo, hi] where the integrand behaves like a power of √|θ − t| (the
/// DFG integral's horizon cuts): they become piece boundaries, and the pieces that end there use
/// θ = t ∓ (b − a)u², which makes √|θ − t| = √(b − a)·u smooth in u.
pub(crate) fn lobe_rule(width: f64, lo: f64, hi: f64, max_piece: f64, order: usize, roots: &[f64]) -> Vec<(f64, f64)> {
    let mut cuts = vec![lo, hi];
    cuts.extend(roots.iter().copied().filter(|&t| t > lo && t < hi));
    let mut edge = (width / 8.0).max(f64::MIN_POSITIVE);
    while edge < hi {
        if edge > lo {
            cuts.push(edge);
        }
        edge *= 2.0;
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    let is_root = |t: f64| roots.contains(&t);
    let rule = gauss_legendre(order.max(1));
    let mut out = Vec::new();
    for pair in cuts.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        let count = ((b - a) / max_piece).ceil().max(1.0) as usize;
        let h = (b - a) / count as f64;
        for p in 0..count {
            let pa = a + p as f64 * h;
            let pb = if p + 1 == count { b } else { a + (p + 1) as f64 * h };
            let pieces = match (p == 0 && is_root(a), p + 1 == count && is_root(b)) {
                (true, true) => {
                    let mid = 0.5 * (pa + pb);
                    vec![(pa, mid, Some(pa)), (mid, pb, Some(pb))]
                }
                (true, false) => vec![(pa, pb, Some(pa))],
                (false, true) => vec![(pa, pb, Some(pb))],
                (false, false) => vec![(pa, pb, None)],
            };
            for (a, b, root) in pieces {
                let len = b - a;
                for &(x, w) in rule.iter() {
                    let (u, wu) = (0.5 * (x + 1.0), 0.5 * w);
                    out.push(match root {
                        None => (a + len * u, len * wu),
                        Some(t) if t == a => (a + len * u * u, 2.0 * len * u * wu),
                        Some(_) => (b - len * u * u, 2.0 * len * u * wu),
                    });
                }
            }
        }
    }
    out
}

/// Gauss–Legendre nodes per piece of the kernel quadratures (converged: the tests compare 32
/// with 64 and find agreement to 1e-13).
const ORDER: usize = 32;

/// The normalized split-sum prefilter kernel of GGX for a perceptual roughness r > 0 (see the
/// module docs): k(θ) = D(cos(θ/2)) max(cos θ, 0) / Z, ∫ k dω = 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplitSumLobe {
    ggx: Ggx,
    /// 1/Z.
    norm: f64,
}

impl SplitSumLobe {
    /// The lobe of perceptual roughness r ∈ (0, 1].
    pub fn new(perceptual_roughness: f64) -> Result<Self, GgxError> {
        let ggx = Ggx::new(perceptual_roughness)?;
        if ggx.alpha <= 0.0 {
            return Err(GgxError::ZeroRoughness);
        }
        let mut lobe = SplitSumLobe { ggx, norm: 1.0 };
        lobe.norm = 1.0 / lobe.mass(FRAC_PI_2, ORDER);
        Ok(lobe)
    }

    /// The underlying distribution.
    pub fn ggx(&self) -> Ggx {
        self.ggx
    }

    /// Z = ∫ D(cos(θ/2)) max(cos θ, 0) dω, the normalization (4 as α → 0, 1 at α = 1).
    pub fn normalization(&self) -> f64 {
        1.0 / self.norm
    }

    /// The normalized kernel from s = sin²(θ/2) = |R − ω|²/4, the form the angular prefilter
    /// uses: it stays accurate for angles far below √(machine ε), unlike 1 − cos θ.
    #[inline]
    pub fn kernel_from_half_chord(&self, sin2_half: f64) -> f64 {
        let cos_theta = 1.0 - 2.0 * sin2_half;
        // A select rather than an early return, so that loops over many texels vectorize.
        let k = self.norm * self.ggx.d_half_angle(1.0 - sin2_half, sin2_half) * cos_theta;
        if cos_theta > 0.0 {
            k
        } else {
            0.0
        }
    }

    /// The normalized kernel at angle θ from R.
    pub fn kernel_at_angle(&self, theta: f64) -> f64 {
        let s = (0.5 * theta).sin();
        self.kernel_from_half_chord(s * s)
    }

    /// The normalized kernel at cos θ.
    #[inline]
    pub fn kernel(&self, cos_theta: f64) -> f64 {
        self.kernel_from_half_chord(0.5 * (1.0 - cos_theta))
    }

    /// 1/k(0): the solid angle of a flat lobe with the same peak and mass, 4πα² for small α and
    /// π at α = 1. The angular prefilter sizes its source texels against it.
    pub fn equivalent_solid_angle(&self) -> f64 {
        1.0 / self.kernel_from_half_chord(0.0)
    }

    /// The lobe width in θ, ≈ 2α (the half-vector angle is θ/2).
    pub fn width(&self) -> f64 {
        2.0 * self.ggx.alpha
    }

    /// ∫_{angle < θ} k dω (with the current normalization) by the lobe rule of `order` nodes per piece.
    fn mass(&self, theta: f64, order: usize) -> f64 {
        let theta = theta.clamp(0.0, FRAC_PI_2);
        lobe_rule(self.width(), 0.0, theta, FRAC_PI_2 / 8.0, order, &[])
            .iter()
            .map(|&(t, w)| w * 2.0 * PI * self.kernel_at_angle(t) * t.sin())
            .sum()
    }

    /// The share of the kernel's weight within angle θ of R.
    pub fn mass_within(&self, theta: f64) -> f64 {
        self.mass(theta, ORDER)
    }

    /// The cone half-angle θ_ε ∈ (0, π/2] whose cone holds 1 − ε of the kernel's weight (the
    /// lobe-truncation radius of the angular prefilter). GGX has a heavy tail: θ_ε ≈ 2α√(1/ε − 1)
    /// for small α. ε ≤ 0 gives π/2, the whole support.
    pub fn cone_angle(&self, epsilon: f64) -> f64 {
        if epsilon <= 0.0 {
            return FRAC_PI_2;
        }
        let target = 1.0 - epsilon;
        let (mut lo, mut hi) = (0.0f64, FRAC_PI_2);
        // Bisection on the monotone mass; 64 halvings reach the resolution of f64.
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if self.mass_within(mid) >= target {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        hi
    }

    /// Zonal SH coefficients k_l = 2π ∫ k(θ) Y_l0(θ) sin θ dθ for l = 0..=order, in prtkit's
    /// orthonormal convention (`docs/conventions.md`), so k_0 = 1/√(4π) for the normalized kernel.
    pub fn zonal_coefficients(&self, order: usize) -> Vec<f64> {
        self.zonal_coefficients_with(order, ORDER)
    }

    fn zonal_coefficients_with(&self, order: usize, nodes: usize) -> Vec<f64> {
        let table = LegendreTable::new(order);
        let mut y = vec![0.0; order + 1];
        let mut k = vec![0.0; order + 1];
        // Pieces no longer than 8/(order + 1) keep P_l's oscillation to ~1.3 periods per piece.
        let max_piece = (8.0 / (order + 1) as f64).min(FRAC_PI_2 / 8.0);
        for (t, w) in lobe_rule(self.width(), 0.0, FRAC_PI_2, max_piece, nodes, &[]) {
            let weight = w * 2.0 * PI * self.kernel_at_angle(t) * t.sin();
            table.eval_zonal(t.cos(), &mut y);
            for l in 0..=order {
                k[l] += weight * y[l];
            }
        }
        k
    }

    /// The convolution factors Λ_l k_l = √(4π/(2l+1)) k_l that multiply radiance coefficients to
    /// give the prefiltered map's, B_lm = Λ_l k_l L_lm (Ramamoorthi & Hanrahan 2002, eq. 5; the
    /// form [`crate::sh::convolve::clamped_cosine`] uses). Λ_0 k_0 = 1: a white environment stays
    /// white. At r = 1 the kernel is the clamped cosine over π, so these are Â_l/π.
    pub fn convolution_factors(&self, order: usize) -> Vec<f64> {
        self.zonal_coefficients(order).iter().enumerate().map(|(l, k)| crate::sh::convolve::lambda(l) * k).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::convolve::clamped_cosine;
    use crate::sh::legendre::LegendreTable;
    use crate::sh::{count, eval_basis_dir, index};
    use glam::DVec3;

    const ROUGHNESSES: [f64; 7] = [0.01, 0.05, 0.1, 0.25, 0.5, 0.8, 1.0];

    #[test]
    fn distribution_is_normalized() {
        // ∫ D(h)(n·h) dω_h = 2π ∫ D(θ_h) cos θ_h sin θ_h dθ_h = 1, by the lobe rule in θ_h.
        for r in [0.005, 0.02, 0.1, 0.3, 0.6, 1.0] {
            let g = Ggx::new(r).unwrap();
            let total: f64 = lobe_rule(g.alpha(), 0.0, FRAC_PI_2, 0.2, 32, &[])
                .iter()
                .map(|&(t, w)| {
                    let (s, c) = t.sin_cos();
                    w * 2.0 * PI * g.d_half_angle(c * c, s * s) * c * s
                })
                .sum();
            assert!((total - 1.0).abs() < 1e-12, "r={r}: {total}");
        }
    }

    #[test]
    fn visibility_is_g2_over_four_cosines() {
        for r in [0.05, 0.4, 1.0] {
            let g = Ggx::new(r).unwrap();
            for (v, l) in [(0.9, 0.2), (0.3, 0.7), (0.05, 0.99), (1.0, 1.0)] {
                let want = g.smith_g2(v, l) / (4.0 * v * l);
                let got = g.visibility(v, l);
                assert!((got / want - 1.0).abs() < 1e-13, "r={r} v={v} l={l}: {got} vs {want}");
            }
        }
        // Λ vanishes at normal incidence and G2 = 1 there.
        let g = Ggx::new(0.7).unwrap();
        assert_eq!(g.lambda(1.0), 0.0);
        assert_eq!(g.smith_g2(1.0, 1.0), 1.0);
    }

    #[test]
    fn normalization_matches_closed_form() {
        // With u = cos²(θ/2), cos θ = 2u − 1 and dω = 4π du:
        // Z = 4α² ∫_{1/2}^1 (2u − 1)/(1 + bu)² du, b = α² − 1, whose antiderivative gives
        // Z = 4α²/b² [2 ln(2α²/(1 + α²)) + (1 − α²)/α²]. (Ill-conditioned as α → 1, hence the range.)
        for r in [0.01, 0.1, 0.3, 0.6, 0.9] {
            let lobe = SplitSumLobe::new(r).unwrap();
            let a2 = alpha(r) * alpha(r);
            let b = a2 - 1.0;
            let closed = 4.0 * a2 / (b * b) * (2.0 * (2.0 * a2 / (1.0 + a2)).ln() + (1.0 - a2) / a2);
            assert!((lobe.normalization() / closed - 1.0).abs() < 1e-11, "r={r}: {} vs {closed}", lobe.normalization());
        }
        // Limits: Z → 4 as α → 0 (dω_l = 4(v·h) dω_h), Z = 1 at α = 1 (D = 1/π).
        assert!((SplitSumLobe::new(1e-3).unwrap().normalization() - 4.0).abs() < 1e-5);
        assert!((SplitSumLobe::new(1.0).unwrap().normalization() - 1.0).abs() < 1e-13);
    }

    #[test]
    fn white_furnace_by_brute_force_sphere_quadrature() {
        // The normalized kernel about an off-axis R integrates to 1 over a lat-long grid that
        // knows nothing of the lobe rule (midpoint in θ and φ, exact cell solid angles).
        let axis = DVec3::new(0.3, -0.5, 0.8).normalize();
        for r in [0.3, 0.6, 1.0] {
            let lobe = SplitSumLobe::new(r).unwrap();
            let (nt, np) = (1500, 3000);
            let mut total = 0.0;
            for i in 0..nt {
                let (t0, t1) = (PI * i as f64 / nt as f64, PI * (i + 1) as f64 / nt as f64);
                let omega = 2.0 * PI / np as f64 * (t0.cos() - t1.cos());
                let theta = 0.5 * (t0 + t1);
                for j in 0..np {
                    let phi = 2.0 * PI * (j as f64 + 0.5) / np as f64;
                    let w = crate::sphere::direction(theta, phi);
                    total += lobe.kernel(axis.dot(w)) * omega;
                }
            }
            assert!((total - 1.0).abs() < 2e-5, "r={r}: {total}");
        }
    }

    #[test]
    fn zonal_coefficients_are_converged_and_normalized() {
        for r in ROUGHNESSES {
            let lobe = SplitSumLobe::new(r).unwrap();
            let a = lobe.zonal_coefficients_with(64, 32);
            let b = lobe.zonal_coefficients_with(64, 64);
            for l in 0..=64 {
                assert!((a[l] - b[l]).abs() < 1e-12, "r={r} l={l}: {} vs {}", a[l], b[l]);
            }
            assert!((a[0] - 0.5 / PI.sqrt()).abs() < 1e-12, "r={r}: k_0 = {}", a[0]);
            assert!((lobe.convolution_factors(0)[0] - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn roughness_one_is_the_clamped_cosine_over_pi() {
        // At α = 1, D = 1/π and Z = 1: k = max(cos θ, 0)/π, whose factors are Â_l/π exactly.
        let f = SplitSumLobe::new(1.0).unwrap().convolution_factors(20);
        for l in 0..=20 {
            assert!((f[l] - clamped_cosine(l) / PI).abs() < 1e-12, "l={l}: {} vs {}", f[l], clamped_cosine(l) / PI);
        }
    }

    #[test]
    fn wide_lobes_match_brute_force_sh_projection() {
        // Project k(R·ω) onto Y_lm by brute-force sphere quadrature and compare with the addition
        // theorem: c_lm = Λ_l k_l Y_lm(R).
        let axis = DVec3::new(-0.4, 0.2, 0.6).normalize();
        let order = 6;
        let table = LegendreTable::new(order);
        for r in [0.6, 1.0] {
            let lobe = SplitSumLobe::new(r).unwrap();
            let factors = lobe.convolution_factors(order);
            let (nt, np) = (1200, 2400);
            let mut c = vec![0.0; count(order)];
            let mut y = vec![0.0; count(order)];
            for i in 0..nt {
                let (t0, t1) = (PI * i as f64 / nt as f64, PI * (i + 1) as f64 / nt as f64);
                let omega = 2.0 * PI / np as f64 * (t0.cos() - t1.cos());
                for j in 0..np {
                    let w = crate::sphere::direction(0.5 * (t0 + t1), 2.0 * PI * (j as f64 + 0.5) / np as f64);
                    let k = lobe.kernel(axis.dot(w)) * omega;
                    if k != 0.0 {
                        eval_basis_dir(&table, w, &mut y);
                        for (ci, yi) in c.iter_mut().zip(&y) {
                            *ci += k * yi;
                        }
                    }
                }
            }
            eval_basis_dir(&table, axis, &mut y);
            for l in 0..=order {
                for m in -(l as isize)..=(l as isize) {
                    let want = factors[l] * y[index(l, m)];
                    let got = c[index(l, m)];
                    assert!((got - want).abs() < 2e-5, "r={r} ({l},{m}): {got} vs {want}");
                }
            }
        }
    }

    #[test]
    fn factors_decay_monotonically_until_the_horizon_ripple() {
        // The lobe only removes detail: Λ_l k_l falls from 1 monotonically through the leading
        // bands. The clamp max(cos θ, 0) has a kink at θ = π/2 whose weight, D(cos π/4)/Z, grows
        // with roughness; it adds an oscillating tail that decays only like l⁻² (at r = 1 the
        // whole kernel is the clamped cosine: factors 1, 2/3, 1/4, 0, −1/24, 0, 1/64, …). So the
        // decay is monotone down to 1e-3 for r ≤ 0.5 (the ripple is 4e-5 at r = 0.5, l = 26), and
        // for rough lobes only through the first bands (r = 0.8 turns at l = 5: 0.0049, 0.0019,
        // 0.0084).
        for r in ROUGHNESSES {
            let f = SplitSumLobe::new(r).unwrap().convolution_factors(200);
            assert!(f[0] > f[1] && f[1] > f[2] && f[2] > f[3].abs(), "r={r}: {:?}", &f[..4]);
            if r <= 0.5 {
                for l in 1..=200 {
                    if f[l - 1] > 1e-3 {
                        assert!(f[l] < f[l - 1], "r={r} l={l}: {} after {}", f[l], f[l - 1]);
                    }
                }
            }
            // Sharp lobes keep the low bands: at r = 0.01 band 100 is still above 0.9.
            if r == 0.01 {
                assert!(f[100] > 0.9, "{}", f[100]);
            }
        }
    }

    #[test]
    fn cone_angle_holds_the_requested_mass() {
        for r in ROUGHNESSES {
            let lobe = SplitSumLobe::new(r).unwrap();
            for eps in [1e-1, 1e-2, 1e-3] {
                let theta = lobe.cone_angle(eps);
                let inside = lobe.mass_within(theta);
                assert!((inside - (1.0 - eps)).abs() < 1e-9 || theta == FRAC_PI_2, "r={r} ε={eps}: {inside}");
                // The heavy GGX tail: for small angles k ≈ α²/(4π(α² + θ²/4)²), whose mass beyond θ
                // is α²/(α² + θ²/4), so θ_ε ≈ 2α√(1/ε − 1) while that is small.
                let guess = 2.0 * alpha(r) * (1.0 / eps - 1.0).sqrt();
                if guess < 0.05 {
                    assert!((theta / guess - 1.0).abs() < 1e-2, "r={r} ε={eps}: {theta} vs {guess}");
                }
            }
        }
        assert_eq!(SplitSumLobe::new(0.5).unwrap().cone_angle(0.0), FRAC_PI_2);
    }

    #[test]
    fn equivalent_solid_angle_limits() {
        let a = alpha(0.05);
        let small = SplitSumLobe::new(0.05).unwrap().equivalent_solid_angle();
        assert!((small / (4.0 * PI * a * a) - 1.0).abs() < 1e-3, "{small}");
        assert!((SplitSumLobe::new(1.0).unwrap().equivalent_solid_angle() - PI).abs() < 1e-12);
    }

    #[test]
    fn bad_roughness_is_an_error() {
        assert_eq!(Ggx::new(-0.1), Err(GgxError::Roughness(-0.1)));
        assert!(Ggx::new(f64::NAN).is_err());
        assert_eq!(SplitSumLobe::new(0.0), Err(GgxError::ZeroRoughness));
        assert!(Ggx::new(1.5).is_err());
    }
}
