//! Image error metrics: every comparison in prtkit (render's `--compare`, the prefilter's
//! accuracy tests and benchmarks) uses these definitions. `docs/render.md` lists them.

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
}

impl std::fmt::Display for Metrics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "rel error {:.4} ({:.2} %), RMS {:.4e}, PSNR {:.2} dB over {} pixels",
            self.rel_error,
            100.0 * self.rel_error,
            self.rms,
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
    let (mut se, mut sr, mut peak, mut maxe, mut n) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0usize);
    for i in 0..image.pixels.len() {
        if !mask.is_empty() && !mask[i] {
            continue;
        }
        n += 1;
        for c in 0..3 {
            let (a, r) = (image.pixels[i][c] as f64, reference.pixels[i][c] as f64);
            let d = a - r;
            se += d * d;
            sr += r * r;
            peak = peak.max(r.abs());
            maxe = maxe.max(d.abs());
            err.pixels[i][c] = d.abs() as f32;
        }
    }
    if n == 0 {
        return Err(CompareError::Empty);
    }
    if sr == 0.0 {
        return Err(CompareError::ZeroReference);
    }
    let rms = (se / (3 * n) as f64).sqrt();
    let psnr = if rms == 0.0 { f64::INFINITY } else { 20.0 * (peak / rms).log10() };
    Ok((Metrics { pixels: n, rms, rel_error: (se / sr).sqrt(), max_rel_error: maxe / peak, psnr, peak }, err))
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
    fn ten_percent_brighter_is_ten_percent_off() {
        let b = RgbImage::from_fn(4, 3, |x, y| [x as f32 + 1.0, y as f32 + 1.0, 2.0]);
        let mut a = b.clone();
        a.pixels.iter_mut().for_each(|p| p.iter_mut().for_each(|c| *c *= 1.1));
        assert!((relative_rms(&a, &b) - 0.1).abs() < 1e-6);
        assert_eq!(relative_rms(&b, &b), 0.0);
        assert_eq!(relative_rms(&a, &RgbImage::new(2, 2)), f64::INFINITY);
    }
}
