//! Image error metrics shared by tests, benchmarks and stages: every comparison in prtkit uses
//! these definitions (`docs/conventions.md`).

use crate::io::RgbImage;

/// Relative RMS error of `image` against `reference` over all pixels and channels:
/// √(Σ (a − b)² / Σ b²).
pub fn relative_rms(image: &RgbImage, reference: &RgbImage) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (p, q) in image.pixels.iter().zip(&reference.pixels) {
        for k in 0..3 {
            num += (p[k] as f64 - q[k] as f64).powi(2);
            den += (q[k] as f64).powi(2);
        }
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else {
        num.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ten_percent_brighter_is_ten_percent_off() {
        let b = RgbImage::from_fn(4, 3, |x, y| [x as f32 + 1.0, y as f32 + 1.0, 2.0]);
        let mut a = b.clone();
        a.pixels.iter_mut().for_each(|p| p.iter_mut().for_each(|c| *c *= 1.1));
        assert!((relative_rms(&a, &b) - 0.1).abs() < 1e-6);
        assert_eq!(relative_rms(&b, &b), 0.0);
    }
}
