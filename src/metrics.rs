//! Image error metrics: every comparison in prtkit (render's `--compare`, the prefilter's
//! accuracy figures and `--verify`, `sh-project --reconstruct`'s report, the benchmarks) uses
//! these definitions. `docs/render.md` lists them.
//!
//! Beside the relative RMS error, which an energy criterion optimizes and which hides rings, the
//! figures a person sees: the share of negative texels, and the per-texel relative error
//! ‖a − r‖/‖r‖ (RGB vectors) at its 99th percentile and maximum, over the texels whose reference
//! is at least [`TEXEL_FLOOR`] of the mean (darker texels would make any relative figure
//! meaningless), with the location of the worst one.

use crate::io::RgbImage;
use serde::{Deserialize, Serialize};

/// Errors of comparing.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// Different sizes.
    #[error("the reference is {rw}x{rh}, the render {w}x{h}")]
    Size {
        /// Reference width.
        rw: usize,
        /// Reference height.
        rh: usize,
        /// Render width.
        w: usize,
        /// Render height.
        h: usize,
    },
    /// No pixel to compare.
    #[error("the object covers no pixel: nothing to compare")]
    Empty,
    /// The reference is zero over the object.
    #[error("the reference is zero over the object: relative error undefined")]
    ZeroReference,
}

/// Texels whose reference ‖r‖ is below this fraction of the mean are left out of the per-texel
/// relative error (1 %).
pub const TEXEL_FLOOR: f64 = 0.01;

/// Error metrics (all channels pooled).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Metrics {
    /// Pixels compared.
    pub pixels: usize,
    /// √(mean (a − r)²).
    pub rms: f64,
    /// ‖a − r‖₂ / ‖r‖₂: the relative L² error.
    pub rel_error: f64,
    /// max |a − r| / max r.
    pub max_rel_error: f64,
    /// 20 log10(max r / rms), in dB.
    pub psnr: f64,
    /// Largest reference value (the PSNR peak).
    pub peak: f64,
    /// Fraction of the compared texels with a negative channel in the image.
    pub negative_fraction: f64,
    /// 99th percentile of the per-texel relative error ‖a − r‖/‖r‖ over texels with
    /// ‖r‖ ≥ [`TEXEL_FLOOR`] × mean ‖r‖.
    pub p99_texel_error: f64,
    /// Largest per-texel relative error over the same texels.
    pub max_texel_error: f64,
    /// (column, row) of that texel.
    pub worst_texel: [usize; 2],
}

impl std::fmt::Display for Metrics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "rel error {:.2} %, per texel p99 {:.2} % and max {:.2} % at ({}, {}), {:.2} % negative texels, \
             PSNR {:.2} dB over {} pixels",
            100.0 * self.rel_error,
            100.0 * self.p99_texel_error,
            100.0 * self.max_texel_error,
            self.worst_texel[0],
            self.worst_texel[1],
            100.0 * self.negative_fraction,
            self.psnr,
            self.pixels
        )
    }
}

/// Relative L² error ‖a − r‖₂/‖r‖₂ of `image` against `reference` over all pixels and channels:
/// [`compare`] without a mask. Infinite when the sizes differ or the reference is zero.
pub fn relative_rms(image: &RgbImage, reference: &RgbImage) -> f64 {
    compare(image, reference, &[]).map(|(m, _)| m.rel_error).unwrap_or(f64::INFINITY)
}

/// Compares `image` with `reference` where `mask` is true (the whole image when `mask` is
/// empty), and returns the metrics and the error image |a − r| (zero outside the mask).
pub fn compare(image: &RgbImage, reference: &RgbImage, mask: &[bool]) -> Result<(Metrics, RgbImage), CompareError> {
    if image.width != reference.width || image.height != reference.height {
        return Err(CompareError::Size { rw: reference.width, rh: reference.height, w: image.width, h: image.height });
    }
    let mut err = RgbImage::new(image.width, image.height);
    let (mut se, mut sr, mut peak, mut maxe, mut n, mut negative) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0usize, 0usize);
    let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let mut norms: Vec<(usize, f64, f64)> = Vec::new();
    for i in 0..image.pixels.len() {
        if !mask.is_empty() && !mask[i] {
            continue;
        }
        n += 1;
        let (a, r) = (image.pixels[i].map(f64::from), reference.pixels[i].map(f64::from));
        let d = [a[0] - r[0], a[1] - r[1], a[2] - r[2]];
        for c in 0..3 {
            se += d[c] * d[c];
            sr += r[c] * r[c];
            peak = peak.max(r[c].abs());
            maxe = maxe.max(d[c].abs());
            err.pixels[i][c] = d[c].abs() as f32;
        }
        if a.iter().any(|&v| v < 0.0) {
            negative += 1;
        }
        norms.push((i, norm(d), norm(r)));
    }
    if n == 0 {
        return Err(CompareError::Empty);
    }
    if sr == 0.0 {
        return Err(CompareError::ZeroReference);
    }
    let floor = TEXEL_FLOOR * norms.iter().map(|t| t.2).sum::<f64>() / n as f64;
    let mut relative: Vec<(f64, usize)> =
        norms.iter().filter(|t| t.2 >= floor && t.2 > 0.0).map(|&(i, e, r)| (e / r, i)).collect();
    relative.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let (p99, worst) = match relative.len() {
        0 => (0.0, (0.0, 0)),
        len => (relative[((len as f64 * 0.99).ceil() as usize).clamp(1, len) - 1].0, relative[len - 1]),
    };
    let rms = (se / (3 * n) as f64).sqrt();
    let psnr = if rms == 0.0 { f64::INFINITY } else { 20.0 * (peak / rms).log10() };
    let metrics = Metrics {
        pixels: n,
        rms,
        rel_error: (se / sr).sqrt(),
        max_rel_error: maxe / peak,
        psnr,
        peak,
        negative_fraction: negative as f64 / n as f64,
        p99_texel_error: p99,
        max_texel_error: worst.0,
        worst_texel: [worst.1 % image.width, worst.1 / image.width],
    };
    Ok((metrics, err))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_of_a_uniform_offset() {
        let r = RgbImage::from_fn(4, 2, |_, _| [2.0; 3]);
        let a = RgbImage::from_fn(4, 2, |x, _| if x == 0 { [2.5; 3] } else { [2.0; 3] });
        let (m, e) = compare(&a, &r, &[]).unwrap();
        // Two of eight pixels off by 0.5 in every channel: mean square 0.25·2/8.
        assert!((m.rms - (0.25f64 * 2.0 / 8.0).sqrt()).abs() < 1e-12);
        assert!((m.rel_error - (0.25f64 * 2.0 / (4.0 * 8.0)).sqrt()).abs() < 1e-12);
        assert!((m.psnr - 20.0 * (2.0 / m.rms).log10()).abs() < 1e-12);
        assert_eq!(e.get(0, 1), [0.5; 3]);
        let mask: Vec<bool> = (0..8).map(|i| i % 4 != 0).collect();
        assert_eq!(compare(&a, &r, &mask).unwrap().0.rms, 0.0);
    }

    #[test]
    fn per_texel_figures_count_negatives_and_find_the_worst_texel_above_the_floor() {
        // 100 texels of reference 1, one of 1e-4 (below 1 % of the mean: left out).
        let r = RgbImage::from_fn(101, 1, |x, _| if x == 100 { [1e-4; 3] } else { [1.0; 3] });
        let mut a = r.clone();
        a.pixels[7] = [1.5; 3]; // 50 % off
        a.pixels[8] = [1.02; 3]; // 2 % off
        a.pixels[100] = [-1.0; 3]; // negative, and hugely off, but below the floor
        let (m, _) = compare(&a, &r, &[]).unwrap();
        assert_eq!(m.negative_fraction, 1.0 / 101.0);
        assert!((m.max_texel_error - 0.5).abs() < 1e-6 && m.worst_texel == [7, 0], "{m:?}");
        // The 99th percentile of 100 values is the 99th smallest: the 2 % texel.
        assert!((m.p99_texel_error - 0.02).abs() < 1e-6, "{m:?}");
    }

    #[test]
    fn ten_percent_brighter_is_ten_percent_off() {
        let b = RgbImage::from_fn(4, 3, |x, y| [x as f32 + 1.0, y as f32 + 1.0, 2.0]);
        let mut a = b.clone();
        a.pixels.iter_mut().for_each(|p| p.iter_mut().for_each(|c| *c *= 1.1));
        assert!((relative_rms(&a, &b) - 0.1).abs() < 1e-6);
        assert_eq!(relative_rms(&b, &b), 0.0);
        assert_eq!(relative_rms(&a, &RgbImage::new(2, 2)), f64::INFINITY);
    }
}
