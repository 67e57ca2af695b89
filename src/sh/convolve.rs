//! Zonal convolution: the clamped cosine (irradiance) and the Funk–Hecke factor Λ_l.

use super::ShCoeffs;
use std::f64::consts::PI;

/// Λ_l = √(4π/(2l+1)), the factor in the convolution theorem B_lm = Λ_l ρ_l L_lm
/// (Ramamoorthi & Hanrahan 2002, eq. 5).
pub fn lambda(l: usize) -> f64 {
    (4.0 * PI / (2 * l + 1) as f64).sqrt()
}

/// Â_l = Λ_l A_l: the clamped-cosine kernel max(cos θ, 0) in the form that multiplies radiance
/// coefficients to give irradiance, E_lm = Â_l L_lm (Ramamoorthi & Hanrahan 2001, eq. 8–9):
/// Â_0 = π, Â_1 = 2π/3, Â_l = 0 for odd l > 1, and for even l
/// Â_l = 2π (−1)^(l/2−1) / ((l+2)(l−1)) · l! / (2^l (l/2)!²).
pub fn clamped_cosine(l: usize) -> f64 {
    match l {
        0 => PI,
        1 => 2.0 * PI / 3.0,
        l if l % 2 == 1 => 0.0,
        l => {
            // l!/(2^l (l/2)!²) = C(l, l/2)/2^l, built as a running product to avoid overflow.
            let half = l / 2;
            let mut central = 1.0f64;
            for k in 1..=half {
                central *= (half + k) as f64 / (4.0 * k as f64);
            }
            let sign = if half % 2 == 1 { 1.0 } else { -1.0 };
            2.0 * PI * sign / ((l + 2) as f64 * (l - 1) as f64) * central
        }
    }
}

/// Multiplies band l by `kernel(l)`.
pub fn convolve_zonal(coeffs: &ShCoeffs, kernel: impl Fn(usize) -> f64) -> ShCoeffs {
    convolve_zonal_rgb(coeffs, |l| [kernel(l); 3])
}

/// Multiplies band l of each channel by that channel's `kernel(l)` (a coloured zonal kernel,
/// such as a BRDF's Λ_l ρ̂_l per channel).
pub fn convolve_zonal_rgb(coeffs: &ShCoeffs, kernel: impl Fn(usize) -> [f64; 3]) -> ShCoeffs {
    let mut out = coeffs.clone();
    for l in 0..=coeffs.order {
        let k = kernel(l);
        for m in -(l as isize)..=(l as isize) {
            let c = &mut out.rgb[super::index(l, m)];
            for (v, k) in c.iter_mut().zip(k) {
                *v *= k;
            }
        }
    }
    out
}

/// Irradiance coefficients E_lm = Â_l L_lm from radiance coefficients.
pub fn irradiance(radiance: &ShCoeffs) -> ShCoeffs {
    convolve_zonal(radiance, clamped_cosine)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamped_cosine_matches_quadrature() {
        // Â_l = 2π √(4π/(2l+1)) ∫_0^1 N_l P_l(x) x dx, by Gauss–Legendre-free midpoint quadrature.
        let n = 200_000;
        for l in 0..12 {
            let mut sum = 0.0;
            for i in 0..n {
                let x = (i as f64 + 0.5) / n as f64;
                sum += legendre_p(l, x) * x;
            }
            let quad = 2.0 * PI * sum / n as f64; // Λ_l · 2π ∫ Y_l0 x dx = 2π ∫ P_l x dx
            assert!((quad - clamped_cosine(l)).abs() < 1e-8, "l={l}: {quad} vs {}", clamped_cosine(l));
        }
        assert!((clamped_cosine(2) - PI / 4.0).abs() < 1e-15);
    }

    fn legendre_p(l: usize, x: f64) -> f64 {
        let mut p = vec![0.0; l + 1];
        crate::sh::legendre::legendre_polynomials(x, &mut p);
        p[l]
    }
}
