//! Synthesis: evaluating Σ L_lm Y_lm, at one direction or over a whole lat-long image.
//!
//! The lat-long path is the projection run backwards (Ramamoorthi & Hanrahan 2002, App. C
//! step 3): per row, a_m(θ) = Σ_l L_lm √2 P̄_l^m(cos θ) in O(F²), then one inverse real FFT over
//! φ gives all W pixels in O(W log W).

use super::legendre::LegendreTable;
use super::{basis, count, index, ShCoeffs};
use crate::io::RgbImage;
use glam::DVec3;
use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::RealFftPlanner;
use std::f64::consts::{PI, SQRT_2};

/// Errors of synthesis.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// The output is too narrow for the bands.
    #[error("a {width}-pixel-wide lat-long image cannot hold order {order} (needs width >= {need})")]
    TooNarrow {
        /// Order.
        order: usize,
        /// Width.
        width: usize,
        /// Needed width.
        need: usize,
    },
}

/// Evaluates RGB coefficients at one direction.
pub fn eval(coeffs: &ShCoeffs, table: &LegendreTable, dir: DVec3, scratch: &mut Vec<f64>) -> [f64; 3] {
    scratch.resize(count(table.order()), 0.0);
    basis::eval_basis_dir(table, dir, scratch);
    let mut out = [0.0; 3];
    for (c, y) in coeffs.rgb.iter().zip(scratch.iter()) {
        for k in 0..3 {
            out[k] += c[k] * y;
        }
    }
    out
}

/// Renders the coefficients into a `width`×`height` lat-long image (texel centres).
pub fn synthesize_latlong(coeffs: &ShCoeffs, width: usize, height: usize) -> Result<RgbImage, SynthError> {
    let order = coeffs.order;
    if 2 * order > width {
        return Err(SynthError::TooNarrow { order, width, need: 2 * order });
    }
    let table = LegendreTable::new(order);
    let ifft = RealFftPlanner::<f64>::new().plan_fft_inverse(width);
    let mut image = RgbImage::new(width, height);
    image.pixels.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let theta = PI * (y as f64 + 0.5) / height as f64;
        let (st, ct) = theta.sin_cos();
        let mut plm = vec![0.0; count(order)];
        table.eval(ct, st, &mut plm);
        let mut spectrum = ifft.make_input_vec();
        let mut samples = ifft.make_output_vec();
        let mut scratch = ifft.make_scratch_vec();
        for c in 0..3 {
            spectrum.iter_mut().for_each(|z| *z = Complex::new(0.0, 0.0));
            for m in 0..=order {
                // f(φ) = a_0 + Σ_m a_m cos(mφ) + b_m sin(mφ) = Re Σ_m (a_m − i b_m) e^{imφ}.
                let (mut a, mut b) = (0.0, 0.0);
                for l in m..=order {
                    let p = plm[index(l, m as isize)];
                    if m == 0 {
                        a += coeffs.rgb[index(l, 0)][c] * p;
                    } else {
                        a += coeffs.rgb[index(l, m as isize)][c] * p * SQRT_2;
                        b += coeffs.rgb[index(l, -(m as isize))][c] * p * SQRT_2;
                    }
                }
                if m == 0 {
                    spectrum[0] = Complex::new(a, 0.0);
                } else if 2 * m == width {
                    // Nyquist: at φ_x = 2π(x+½)/W, cos(mφ_x) = 0 and sin(mφ_x) = (−1)^x.
                    spectrum[m] = Complex::new(b, 0.0);
                } else {
                    // The inverse FFT sums X_m e^{2πimx/W} over ±m, i.e. 2 Re(X_m e^{…}); the
                    // half-texel shift of the samples is the phase e^{iπm/W}.
                    let (s, co) = (PI * m as f64 / width as f64).sin_cos();
                    let z = Complex::new(a, -b) * Complex::new(co, s) * 0.5;
                    spectrum[m] = z;
                }
            }
            // The spectrum's DC and Nyquist bins are real by construction.
            let _ = ifft.process_with_scratch(&mut spectrum, &mut samples, &mut scratch);
            for (px, v) in row.iter_mut().zip(&samples) {
                px[c] = *v as f32;
            }
        }
    });
    Ok(image)
}

/// Evaluates the coefficients at every texel of any layout by direct summation.
pub fn synthesize_map(coeffs: &ShCoeffs, map: &mut crate::envmap::EnvMap) {
    let table = LegendreTable::new(coeffs.order);
    let geometry = map.clone();
    for (face, img) in map.images_mut().iter_mut().enumerate() {
        let width = img.width;
        img.pixels.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
            let mut scratch = Vec::new();
            for (x, px) in row.iter_mut().enumerate() {
                *px = match geometry.texel_geometry(face, x, y) {
                    Some((dir, _)) => {
                        let v = eval(coeffs, &table, dir, &mut scratch);
                        [v[0] as f32, v[1] as f32, v[2] as f32]
                    }
                    None => [0.0; 3],
                };
            }
        });
    }
}
