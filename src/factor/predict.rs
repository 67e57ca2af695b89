//! Closed-form term-count predictions (Mahajan, Tseng & Ramamoorthi 2008, §3.3, §3.4, §4),
//! computed from 1-D transforms of the BRDF, never from an SVD.
//!
//! **Radially symmetric BRDFs** (Phong, Lambert): ρ = f(R·ω_i). By the Funk–Hecke theorem
//! (the addition theorem, eq. 8) ∫ f(R·L) Y_lm(L) dL = F_l Y_lm(R) with
//! F_l = 2π ∫_{−1}^{1} f(t) P_l(t) dt = f_l √(4π/(2l+1)) (eq. 9), f_l the zonal SH coefficients
//! of the lobe. On the full sphere eq. 9 *is* the SVD: σ = F_l, repeated 2l+1 times. So the
//! K for an energy fraction E is fixed by the band energy: with l* the smallest L whose bands
//! hold E of Σ_l (2l+1) F_l², K = (l*+1)² on the sphere (eq. 10), and about half,
//! (l*+1)²/2, on the visible hemispheres (eq. 13, §3.4).
//!
//! **Half-angle BRDFs** (Torrance-Sparrow eq. 14, Blinn-Phong, measured data): the frequency
//! content lives in the half-angle curve ρ(θ_h). Its Legendre transform, normalized to F_0 = 1,
//! F_l = ∫ ρ(θ_h) P_l(cos θ_h) sin θ_h dθ_h / ∫ ρ(θ_h) sin θ_h dθ_h, gives l*, and K ≈ (l*)²/4
//! on the visible hemispheres (§4, Fig. 7C; no sphere form: see [`no_prediction_reason`]).
//! For measured data the curve is
//! the mean over θ_d below 60° (grazing angles skipped) and all φ_d (§4).
//!
//! **The threshold for l\* (derived, see `docs/count-terms.md`).** For eq. 14, ρ(θ_h) is a
//! Gaussian exp(−θ_h²/σ²) on the sphere of half vectors; its zonal transform is
//! F_l ≈ exp(−l(l+1)σ²/4). The paper's conservative cut F_l < e⁻³ (§3.3) gives
//! l* ≈ √12/σ ≈ 3.46/σ; a 99 % band-energy cut, Σ_{l≤L}(2l+1)F_l² ≈ 1 − exp(−σ²L²/2), gives
//! l* ≈ √(2 ln 100)/σ ≈ 3.03/σ. The numerical transform gives l* = 17 / 15 at σ = 0.2 and
//! 9 / 7 at σ = 0.4, so K ≈ (l*)²/4 predicts 73 / 57 and 21 / 13 terms; fine hemisphere
//! SVDs measure 75 (n = 160; 73 at n = 256) and 21 (docs/results/terms.md), and the paper says
//! ~60 and 10–20. prtkit therefore uses the **e⁻³ coefficient cut** for
//! half-angle curves. The paper's printed shortcut l* ≈ 1/(2σ²) (12.5 at σ = 0.2, 3.1 at
//! σ = 0.4 → K ≈ 39 and 2.4) contradicts its own K values and is reported only as
//! `paper_shortcut_k`.

use super::grid::Domain;
use crate::brdf::{halfdiff, merl, Brdf};
use std::f64::consts::PI;

/// The paper's conservative coefficient threshold e⁻³ (§3.3).
pub const E3: f64 = 0.049_787_068_367_863_944;

/// Largest θ_d averaged into a measured half-angle curve (grazing angles skipped, §4).
pub const MAX_THETA_D: f64 = PI / 3.0;

/// Gauss–Legendre nodes and weights on [−1, 1] as two vectors (the rule itself lives in
/// [`crate::quadrature`]).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    crate::quadrature::gauss_legendre_cached(n).iter().copied().unzip()
}

pub use crate::sh::legendre::legendre_polynomials;

/// ∫_a^b g(θ) P_l(cos θ) sin θ dθ for l = 0..=lmax by composite Gauss–Legendre in θ
/// (`panels` panels of 16 nodes; panels uniform in θ so narrow lobes near θ = 0 are resolved).
fn legendre_transform(g: impl Fn(f64) -> f64, a: f64, b: f64, lmax: usize, panels: usize) -> Vec<f64> {
    let (x, w) = gauss_legendre(16);
    let mut out = vec![0.0; lmax + 1];
    let mut p = vec![0.0; lmax + 1];
    let h = (b - a) / panels as f64;
    for panel in 0..panels {
        let mid = a + (panel as f64 + 0.5) * h;
        for (xi, wi) in x.iter().zip(&w) {
            let theta = mid + 0.5 * h * xi;
            let weight = 0.5 * h * wi * theta.sin() * g(theta);
            if weight == 0.0 {
                continue;
            }
            legendre_polynomials(theta.cos(), &mut p);
            for (o, pl) in out.iter_mut().zip(&p) {
                *o += weight * pl;
            }
        }
    }
    out
}

/// F_l = 2π ∫_{−1}^{1} f(t) P_l(t) dt for a lobe f(cos γ) about the reflection direction
/// (Funk–Hecke; Mahajan et al. 2008, eq. 9), l = 0..=lmax, by 1-D quadrature.
pub fn reflection_spectrum(lobe: impl Fn(f64) -> f64, lmax: usize) -> Vec<f64> {
    let panels = 256 + 2 * lmax;
    legendre_transform(|gamma| lobe(gamma.cos()), 0.0, PI, lmax, panels).into_iter().map(|v| 2.0 * PI * v).collect()
}

/// Normalized Legendre transform (F_0 = 1) of an analytic half-angle curve on [0, π/2]
/// (ρ = 0 beyond, half vectors lie in the upper hemisphere).
pub fn half_angle_spectrum(curve: impl Fn(f64) -> f64, lmax: usize) -> Vec<f64> {
    let raw = legendre_transform(curve, 0.0, PI / 2.0, lmax, 256 + 2 * lmax);
    normalize(raw)
}

/// Normalized Legendre transform of a sampled half-angle curve (trapezoid rule on the samples,
/// 0 beyond the last one), e.g. the 90 θ_h rows of a MERL table.
pub fn half_angle_spectrum_sampled(theta_h: &[f64], curve: &[f64], lmax: usize) -> Vec<f64> {
    let mut raw = vec![0.0; lmax + 1];
    let mut p = vec![0.0; lmax + 1];
    let mut integrand = |i: usize, w: f64, raw: &mut Vec<f64>| {
        legendre_polynomials(theta_h[i].cos(), &mut p);
        let f = w * curve[i] * theta_h[i].sin();
        for (o, pl) in raw.iter_mut().zip(&p) {
            *o += f * pl;
        }
    };
    for i in 0..theta_h.len().saturating_sub(1) {
        let h = theta_h[i + 1] - theta_h[i];
        integrand(i, 0.5 * h, &mut raw);
        integrand(i + 1, 0.5 * h, &mut raw);
    }
    normalize(raw)
}

fn normalize(raw: Vec<f64>) -> Vec<f64> {
    let f0 = raw.first().copied().unwrap_or(0.0);
    if f0 == 0.0 {
        return raw;
    }
    raw.into_iter().map(|v| v / f0).collect()
}

/// First l with |F_l| < threshold (F normalized to F_0 = 1); `None` if the spectrum never drops.
pub fn l_star_coefficient(spectrum: &[f64], threshold: f64) -> Option<usize> {
    spectrum.iter().position(|f| f.abs() < threshold)
}

/// Smallest L with Σ_{l≤L} (2l+1) F_l² ≥ fraction · Σ_l (2l+1) F_l².
pub fn l_star_band_energy(spectrum: &[f64], fraction: f64) -> Option<usize> {
    let band = |(l, f): (usize, &f64)| (2 * l + 1) as f64 * f * f;
    let total: f64 = spectrum.iter().enumerate().map(band).sum();
    if total == 0.0 {
        return None;
    }
    let mut acc = 0.0;
    for (l, f) in spectrum.iter().enumerate() {
        acc += band((l, f));
        if acc >= fraction * total * (1.0 - 1e-12) {
            return Some(l);
        }
    }
    None
}

/// Which closed form a prediction used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PredictionKind {
    /// Radially symmetric lobe: exact SH spectrum, K = (l*+1)² (sphere) or half (hemisphere).
    ReflectionLobe,
    /// Half-angle curve: K ≈ (l*)²/4 on the visible hemispheres.
    HalfAngle,
}

/// A term-count prediction.
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// The closed form used.
    pub kind: PredictionKind,
    /// The frequency cut-off.
    pub l_star: usize,
    /// Predicted K.
    pub predicted_k: f64,
    /// The spectrum l* was read from: F_l (reflection lobe, unnormalized) or normalized
    /// half-angle F_l.
    pub spectrum: Vec<f64>,
    /// The rule for l*, in words.
    pub rule: String,
}

/// Why no prediction is made, if none is.
pub fn no_prediction_reason(brdf: &Brdf, domain: Domain, cosine: bool) -> Option<String> {
    if cosine {
        Some("the paper's closed forms are for rho without the cosine (--cosine off)".into())
    } else if !brdf.is_isotropic() {
        Some(format!("{} is anisotropic: no closed form", brdf.name()))
    } else if !brdf.is_radially_symmetric() && domain == Domain::Sphere {
        // Extended to the sphere, a half-angle model also lights pairs with ω_i and ω_o in
        // opposite hemispheres; its sphere SVD is not twice the hemisphere one (measured:
        // σ = 0.4 needs 59 terms on the sphere, 21 on the hemisphere), and §4 only covers the
        // visible hemispheres.
        Some("the half-angle closed form (section 4) is for the visible hemispheres only".into())
    } else {
        None
    }
}

/// Predicts K at energy `fraction` (reflection lobes) or with the e⁻³ cut (half-angle curves,
/// hemisphere only). `None` with --cosine, for anisotropic BRDFs and for half-angle models on
/// the sphere ([`no_prediction_reason`]).
pub fn predict(
    brdf: &Brdf,
    domain: Domain,
    cosine: bool,
    channel: super::Channel,
    fraction: f64,
) -> Option<Prediction> {
    if no_prediction_reason(brdf, domain, cosine).is_some() {
        return None;
    }
    if brdf.is_radially_symmetric() {
        let lmax = reflection_lmax(brdf);
        let spectrum = reflection_spectrum(|t| brdf.reflection_lobe(t).unwrap_or(0.0), lmax);
        let l_star = l_star_band_energy(&spectrum, fraction)?;
        let full = ((l_star + 1) * (l_star + 1)) as f64;
        let predicted_k = match domain {
            Domain::Sphere => full,
            Domain::Hemisphere => full / 2.0,
        };
        return Some(Prediction {
            kind: PredictionKind::ReflectionLobe,
            l_star,
            predicted_k,
            spectrum,
            rule: format!("smallest l* with {:.4} of the band energy sum (2l+1) F_l^2", fraction),
        });
    }
    let spectrum = half_angle_spectrum_of(brdf, channel, HALF_ANGLE_LMAX)?;
    let l_star = l_star_coefficient(&spectrum, E3)?;
    let predicted_k = (l_star * l_star) as f64 / 4.0;
    Some(Prediction {
        kind: PredictionKind::HalfAngle,
        l_star,
        predicted_k,
        spectrum,
        rule: "first l* with normalized half-angle F_l < e^-3".into(),
    })
}

/// Highest band of the half-angle transforms.
pub const HALF_ANGLE_LMAX: usize = 256;

/// Enough bands to hold a reflection lobe's energy: Phong's F_l ≈ exp(−l²/(2s)) (eq. 11) is
/// below 1e-12 by l = √(55 s).
fn reflection_lmax(brdf: &Brdf) -> usize {
    let s = match brdf {
        Brdf::Phong(p) => p.exponent,
        Brdf::Lafortune(l) => l.lobes.iter().map(|x| x.exponent).fold(0.0, f64::max),
        _ => 0.0,
    };
    ((55.0 * s).sqrt().ceil() as usize + 8).clamp(16, 4000)
}

/// The normalized half-angle spectrum of an isotropic BRDF: closed-form curve for half-angle
/// models, the θ_d-averaged table for MERL data, and for other isotropic models the same
/// average taken numerically.
pub fn half_angle_spectrum_of(brdf: &Brdf, channel: super::Channel, lmax: usize) -> Option<Vec<f64>> {
    if !brdf.is_isotropic() {
        return None;
    }
    if brdf.half_angle_curve(0.0).is_some() {
        return Some(half_angle_spectrum(|t| brdf.half_angle_curve(t).unwrap_or(0.0), lmax));
    }
    let (theta_h, curve) = half_angle_curve_samples(brdf, channel);
    Some(half_angle_spectrum_sampled(&theta_h, &curve, lmax))
}

/// The half-angle curve of an isotropic BRDF at MERL's θ_h samples: the mean over θ_d < 60° and
/// all φ_d (§4). MERL tables are averaged entry by entry, skipping missing entries.
pub fn half_angle_curve_samples(brdf: &Brdf, channel: super::Channel) -> (Vec<f64>, Vec<f64>) {
    if let Brdf::Merl(table) = brdf {
        let (theta_h, curves) = table.half_angle_curve(MAX_THETA_D);
        let w = channel.weights();
        let curve =
            (0..theta_h.len()).map(|i| w[0] * curves[0][i] + w[1] * curves[1][i] + w[2] * curves[2][i]).collect();
        return (theta_h, curve);
    }
    let theta_h: Vec<f64> = (0..merl::RES_THETA_H).map(merl::theta_h_of_index).collect();
    let (n_td, n_pd) = (60, 90);
    let curve = theta_h
        .iter()
        .map(|&th| {
            let mut sum = 0.0;
            for j in 0..n_td {
                let theta_d = (j as f64 + 0.5) * MAX_THETA_D / n_td as f64;
                for k in 0..n_pd {
                    let phi_d = (k as f64 + 0.5) * PI / n_pd as f64;
                    let hd = halfdiff::HalfDiff { theta_h: th, phi_h: 0.0, theta_d, phi_d };
                    let (wi, wo) = halfdiff::to_directions(&hd);
                    sum += channel.apply(brdf.eval(wi, wo));
                }
            }
            sum / (n_td * n_pd) as f64
        })
        .collect();
    (theta_h, curve)
}

/// The paper's own numbers: K ≈ 5s (sphere) and 2.5s (hemisphere) for Phong (Fig. 3A, eq. 13).
pub fn paper_phong_k(brdf: &Brdf, domain: Domain) -> Option<f64> {
    match brdf {
        Brdf::Phong(p) => Some(match domain {
            Domain::Sphere => 5.0 * p.exponent,
            Domain::Hemisphere => 2.5 * p.exponent,
        }),
        _ => None,
    }
}

/// The paper's printed shortcut for eq. 14, l* ≈ 1/(2σ²) with K ≈ (l*)²/4 (§4): reported for
/// comparison only, since it contradicts the paper's own K values.
pub fn paper_shortcut_k(brdf: &Brdf) -> Option<f64> {
    match brdf {
        Brdf::TorranceSparrow(t) => {
            let l = 1.0 / (2.0 * t.sigma * t.sigma);
            Some(l * l / 4.0)
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let (x, w) = gauss_legendre(16);
        for k in 0..32 {
            let got: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k)).sum();
            let want = if k % 2 == 1 { 0.0 } else { 2.0 / (k as f64 + 1.0) };
            assert!((got - want).abs() < 1e-14, "x^{k}: {got} vs {want}");
        }
    }

    #[test]
    fn legendre_polynomials_match_the_normalized_sh_table() {
        // P̄_l^0 = √((2l+1)/(4π)) P_l: cross-check against the sh module's recurrence.
        let order = 60;
        let table = crate::sh::legendre::LegendreTable::new(order);
        let mut norm = vec![0.0; crate::sh::count(order)];
        let (c, s) = (0.37f64, (1.0f64 - 0.37 * 0.37).sqrt());
        table.eval(c, s, &mut norm);
        let mut p = vec![0.0; order + 1];
        legendre_polynomials(c, &mut p);
        for l in 0..=order {
            let want = norm[crate::sh::index(l, 0)] / ((2 * l + 1) as f64 / (4.0 * PI)).sqrt();
            assert!((p[l] - want).abs() < 1e-12, "l={l}");
        }
    }

    #[test]
    fn phong_spectrum_matches_the_closed_form() {
        // F_l = (s+1) ∫_0^1 t^s P_l(t) dt; for l = 0, 1, 2: 1, (s+1)/(s+2), (s+1)s/((s+3)(s+2))…
        // derived from ∫_0^1 t^s dt = 1/(s+1), ∫ t^{s+1} = 1/(s+2), P_2 = (3t² − 1)/2.
        let s = 30.0;
        let f = reflection_spectrum(|t| if t > 0.0 { (s + 1.0) / (2.0 * PI) * t.powf(s) } else { 0.0 }, 40);
        assert!((f[0] - 1.0).abs() < 1e-12);
        assert!((f[1] - (s + 1.0) / (s + 2.0)).abs() < 1e-12);
        let f2 = (s + 1.0) * 0.5 * (3.0 / (s + 3.0) - 1.0 / (s + 1.0));
        assert!((f[2] - f2).abs() < 1e-12);
        // And eq. 11's approximation F_l ≈ exp(−l²/(2s)) holds to a few percent at low l.
        assert!((f[5] - (-25.0 / 60.0f64).exp()).abs() < 0.05);
    }

    #[test]
    fn torrance_sparrow_l_star_follows_the_gaussian_derivation() {
        // e⁻³ cut: l* ≈ √12/σ; 99 % band energy: l* ≈ √(2 ln 100)/σ (module docs). Both within
        // one band (plus the O(1) shift of l(l+1) versus l²).
        for sigma in [0.1, 0.15, 0.2, 0.25, 0.3, 0.4] {
            let b = Brdf::parse(&format!("torrance-sparrow:sigma={sigma}")).unwrap();
            let f = half_angle_spectrum_of(&b, super::super::Channel::Luminance, 200).unwrap();
            let e3 = l_star_coefficient(&f, E3).unwrap() as f64;
            let e99 = l_star_band_energy(&f, 0.99).unwrap() as f64;
            assert!((e3 - 12f64.sqrt() / sigma).abs() <= 1.6, "σ={sigma}: e3 {e3}");
            assert!((e99 - (2.0 * 100f64.ln()).sqrt() / sigma).abs() <= 1.6, "σ={sigma}: 99% {e99}");
        }
    }

    #[test]
    fn lambert_needs_one_term() {
        let b = Brdf::parse("lambert").unwrap();
        let p = predict(&b, Domain::Sphere, false, super::super::Channel::Luminance, 0.99).unwrap();
        assert_eq!((p.l_star, p.predicted_k), (0, 1.0));
        // F_0 = 2π ∫ (1/π) dt = 4.
        assert!((p.spectrum[0] - 4.0).abs() < 1e-12);
    }
}
