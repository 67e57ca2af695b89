//! Windows applied to SH coefficients at synthesis, against ringing (Gibbs oscillation) and
//! negative values of truncated expansions (Sloan 2017, "Deringing Spherical Harmonics").
//!
//! A window multiplies band l of an order-F expansion by w_l, w_0 = 1. Synthesizing windowed
//! coefficients is a convolution of the function with the zonal kernel
//!
//!   K(cos γ) = Σ_{l ≤ F} (2l+1)/(4π) w_l P_l(cos γ),                                   (1)
//!
//! so a window trades sharpness for less ringing. Coefficients written to JSON stay raw; the
//! window is applied where a map is synthesized and recorded in the document beside it.
//!
//! The windows, with x = l/(F+1):
//! - `hann`: w_l = ½(1 + cos πx);
//! - `lanczos`: w_l = sinc x = sin(πx)/(πx), Lanczos's σ-factors;
//! - `sigma`: the Gaussian (heat-kernel) window w_l = exp(−l(l+1)/(2σ²)), σ chosen so that
//!   w = ½ where the Hann window is ½ (l = (F+1)/2);
//! - `nonneg`: the gentlest heat-kernel window w_l = exp(−t·l(l+1)) that makes the synthesized
//!   map non-negative: t is the smallest (to 1 %) for which every texel is ≥ 0, found by
//!   bisection; t = 0 (no window) when the raw map is already non-negative. The search is
//!   bracketed: for t large enough the kernel (1) is non-negative, and a non-negative kernel
//!   maps every non-negative environment to a non-negative result (the projection is a
//!   weighted sum of texels with positive solid angles), so a non-negative map is always found.
//!
//! **The non-negativity guard.** Every window but `none` ends with that search: `hann`,
//! `lanczos` and `sigma` damp Gibbs ripples but keep kernels with negative lobes, so next to a
//! bright window a dark texel can still go below zero (Lanczos on Grace at order 30 does: the
//! guard needs t = 1.7 · 10⁻³ there, `docs/results/windows.md`). A radiance map with negative
//! texels is never what a user wants (`convert` refuses it), so the fixed window is multiplied
//! by the gentlest exp(−t·l(l+1)) that makes the map non-negative — t = 0, the window alone,
//! whenever it already is — and the document records t. `nonneg` is the guard alone; `none` is the raw expansion, unguarded.

#[cfg(test)]
use super::index;
use super::legendre::legendre_polynomials;
use super::ShCoeffs;
use std::f64::consts::PI;

/// A window family (`--window`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Window {
    /// No window: the raw truncated expansion.
    None,
    /// ½(1 + cos(πl/(F+1))).
    Hann,
    /// sinc(l/(F+1)): Lanczos's σ-factors.
    Lanczos,
    /// exp(−l(l+1)/(2σ²)), half-width (F+1)/2.
    Sigma,
    /// The gentlest heat-kernel window that makes the map non-negative.
    #[default]
    Nonneg,
}

impl Window {
    /// Whether the synthesis ends with the non-negativity guard (every window but `none`).
    pub fn guarded(self) -> bool {
        self != Window::None
    }

    /// The name used on the command line and in documents.
    pub fn name(self) -> &'static str {
        match self {
            Window::None => "none",
            Window::Hann => "hann",
            Window::Lanczos => "lanczos",
            Window::Sigma => "sigma",
            Window::Nonneg => "nonneg",
        }
    }

    /// The factors w_0..=w_F of the window of order F before the guard (`nonneg`: the raw
    /// expansion, t = 0; its factors come from [`nonneg`]).
    pub fn factors(self, order: usize) -> Vec<f64> {
        let n = (order + 1) as f64;
        (0..=order)
            .map(|l| {
                let x = l as f64 / n;
                match self {
                    Window::None | Window::Nonneg => 1.0,
                    Window::Hann => 0.5 * (1.0 + (PI * x).cos()),
                    Window::Lanczos if l == 0 => 1.0,
                    Window::Lanczos => (PI * x).sin() / (PI * x),
                    Window::Sigma => {
                        let half = n / 2.0;
                        let sigma2 = half * (half + 1.0) / (2.0 * std::f64::consts::LN_2);
                        (-((l * (l + 1)) as f64) / (2.0 * sigma2)).exp()
                    }
                }
            })
            .collect()
    }
}

/// The window a synthesis used, in figures (documents and `--json`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WindowReport {
    /// `none`, `hann`, `lanczos`, `sigma` or `nonneg`.
    pub kind: Window,
    /// The heat parameter t of exp(−t·l(l+1)) the non-negativity guard multiplied the window
    /// by (0: the window alone was non-negative); absent for `none`, which is not guarded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t: Option<f64>,
}

/// Heat-kernel window factors exp(−t·l(l+1)), l = 0..=F.
pub fn heat_factors(order: usize, t: f64) -> Vec<f64> {
    (0..=order).map(|l| (-t * (l * (l + 1)) as f64).exp()).collect()
}

/// Coefficients with band l multiplied by `factors[l]` (bands beyond the factors are dropped).
pub fn apply(coeffs: &ShCoeffs, factors: &[f64]) -> ShCoeffs {
    super::convolve::convolve_zonal(coeffs, |l| factors.get(l).copied().unwrap_or(0.0))
}

/// The smallest heat parameter t for which the windowed kernel (1) of band factors
/// `kernel[l]·exp(−t·l(l+1))` is non-negative on a fine grid of cos γ: beyond it, every
/// non-negative input gives a non-negative output. `kernel` holds the zonal factors the window
/// multiplies (1 for a plain reconstruction, the BRDF's Λ_l ρ̂_l for a reflection map).
pub fn kernel_nonneg_t(kernel: &[f64]) -> f64 {
    let order = kernel.len().saturating_sub(1);
    if order == 0 {
        return 0.0;
    }
    let samples = (8 * order).max(64);
    let mut p = vec![0.0; order + 1];
    let table: Vec<Vec<f64>> = (0..=samples)
        .map(|i| {
            let x = (PI * i as f64 / samples as f64).cos();
            legendre_polynomials(x, &mut p);
            p.iter().enumerate().map(|(l, pl)| (2 * l + 1) as f64 / (4.0 * PI) * kernel[l] * pl).collect()
        })
        .collect();
    let min_kernel = |t: f64| -> f64 {
        let w = heat_factors(order, t);
        table.iter().map(|row| row.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>()).fold(f64::INFINITY, f64::min)
    };
    let (mut lo, mut hi) = (0.0, 1.0 / (order * (order + 1)) as f64);
    if min_kernel(lo) >= 0.0 {
        return 0.0;
    }
    while min_kernel(hi) < 0.0 {
        lo = hi;
        hi *= 2.0;
        if hi > 1e3 {
            return hi;
        }
    }
    bisect(lo, hi, |t| min_kernel(t) >= 0.0)
}

/// The outcome of the `nonneg` search.
#[derive(Clone, Debug, PartialEq)]
pub struct NonNeg<T> {
    /// The heat parameter t (0: no window was needed).
    pub t: f64,
    /// Its factors exp(−t·l(l+1)).
    pub factors: Vec<f64>,
    /// The synthesized map with those factors.
    pub map: T,
}

/// The guard: the gentlest heat factor exp(−t·l(l+1)) on top of the window's `base` factors
/// that makes `synthesize(factors)` non-negative (`min_of` gives the map's smallest value),
/// given the zonal `kernel` the window multiplies (see [`kernel_nonneg_t`], the bracket of the
/// search). One synthesis when the window alone is non-negative, about a dozen otherwise.
pub fn nonneg<T>(
    base: &[f64],
    kernel: &[f64],
    synthesize: impl Fn(&[f64]) -> T,
    min_of: impl Fn(&T) -> f64,
) -> NonNeg<T> {
    let order = kernel.len().saturating_sub(1);
    let with = |t: f64| -> Vec<f64> { heat_factors(order, t).iter().zip(base).map(|(h, b)| h * b).collect() };
    let raw = synthesize(&with(0.0));
    if min_of(&raw) >= 0.0 {
        return NonNeg { t: 0.0, factors: with(0.0), map: raw };
    }
    // The kernel bound guarantees a non-negative result for exact, non-negative inputs; grow it
    // until this map is non-negative (inputs may carry small negative noise of their own).
    let ok = |t: f64| min_of(&synthesize(&with(t))) >= 0.0;
    let windowed: Vec<f64> = kernel.iter().zip(base).map(|(k, b)| k * b).collect();
    let mut hi = kernel_nonneg_t(&windowed).max(1e-6 / (order * (order + 1)).max(1) as f64);
    while !ok(hi) && hi < 1e3 {
        hi *= 2.0;
    }
    let t = bisect(0.0, hi, ok);
    let factors = with(t);
    let map = synthesize(&factors);
    NonNeg { t, factors, map }
}

/// The smallest t in (lo, hi] with `ok(t)`, to 1 % of hi, assuming ok(hi) (and monotone enough).
fn bisect(mut lo: f64, mut hi: f64, ok: impl Fn(f64) -> bool) -> f64 {
    let tolerance = 0.01 * hi;
    while hi - lo > tolerance {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::synth::synthesize_latlong;

    #[test]
    fn fixed_windows_start_at_one_and_decay() {
        for w in [Window::Hann, Window::Lanczos, Window::Sigma] {
            let f = w.factors(10);
            assert_eq!(f[0], 1.0);
            assert!(f.windows(2).all(|p| p[1] < p[0]), "{w:?}: {f:?}");
            assert!(f[10] < 0.25 && f[10] >= 0.0, "{w:?}: {f:?}");
        }
        assert!((Window::Hann.factors(9)[5] - 0.5).abs() < 1e-12);
        assert!((Window::Sigma.factors(9)[5] - 0.5).abs() < 1e-12);
        assert_eq!(Window::None.factors(3), vec![1.0; 4]);
    }

    /// A delta at +Z truncated at `order`: L_lm = Y_lm(+Z) = √((2l+1)/4π) for m = 0.
    fn spike(order: usize) -> ShCoeffs {
        let mut delta = ShCoeffs::zeros(order);
        for l in 0..=order {
            delta.rgb[index(l, 0)] = [((2 * l + 1) as f64 / (4.0 * PI)).sqrt(); 3];
        }
        delta
    }

    fn min(img: &crate::io::RgbImage) -> f64 {
        img.pixels.iter().flatten().fold(f64::INFINITY, |m, &v| m.min(v as f64))
    }

    /// The truncated expansion of a narrow positive spike rings negative; the nonneg window
    /// removes exactly that, gently: a slightly smaller t still rings.
    #[test]
    fn nonneg_finds_the_gentlest_heat_window() {
        let order = 12;
        let delta = spike(order);
        let synth = |w: &[f64]| synthesize_latlong(&apply(&delta, w), 64, 32).unwrap();
        assert!(min(&synth(&heat_factors(order, 0.0))) < 0.0, "the raw spike rings");
        let kernel = vec![1.0; order + 1];
        let found = nonneg(&kernel, &kernel, synth, min);
        assert!(found.t > 0.0 && min(&found.map) >= 0.0);
        assert!(min(&synth(&heat_factors(order, 0.9 * found.t))) < 0.0, "t = {} is not the gentlest", found.t);
        // The data-independent bracket is at least as strong.
        assert!(kernel_nonneg_t(&kernel) >= 0.99 * found.t);
    }

    /// A fixed window keeps negative lobes: Lanczos on a spike still rings below zero, and the
    /// guard multiplies it by the gentlest heat factor that does not: a slightly smaller t on
    /// top of Lanczos still rings.
    #[test]
    fn the_guard_completes_a_fixed_window() {
        let order = 12;
        let delta = spike(order);
        let synth = |w: &[f64]| synthesize_latlong(&apply(&delta, w), 64, 32).unwrap();
        let lanczos = Window::Lanczos.factors(order);
        assert!(min(&synth(&lanczos)) < 0.0, "Lanczos alone rings negative on a spike");
        let found = nonneg(&lanczos, &vec![1.0; order + 1], synth, min);
        assert!(found.t > 0.0 && min(&found.map) >= 0.0, "t = {}", found.t);
        let on_lanczos = |t: f64| -> Vec<f64> {
            lanczos.iter().enumerate().map(|(l, w)| w * (-t * (l * (l + 1)) as f64).exp()).collect()
        };
        for (l, (f, want)) in found.factors.iter().zip(on_lanczos(found.t)).enumerate() {
            assert!((f - want).abs() < 1e-15, "band {l}: {f} vs {want}");
        }
        assert!(min(&synth(&on_lanczos(0.9 * found.t))) < 0.0, "t = {} is not the gentlest", found.t);
    }

    #[test]
    fn a_non_negative_map_is_left_alone() {
        let mut c = ShCoeffs::zeros(4);
        c.rgb[0] = [1.0; 3];
        c.rgb[index(1, 0)] = [0.1; 3];
        let found = nonneg(&[1.0; 5], &[1.0; 5], |w| synthesize_latlong(&apply(&c, w), 16, 8).unwrap(), min);
        assert_eq!(found.t, 0.0);
        assert_eq!(found.factors, vec![1.0; 5]);
    }
}
