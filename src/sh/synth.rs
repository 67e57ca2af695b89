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

/// Synthesizes one lat-long row f(φ_x) = a_0 + Σ_{m≥1} a_m cos(mφ_x) + b_m sin(mφ_x) at the
/// texel centres φ_x = 2π(x+½)/W with one inverse real FFT: the shared last step of every
/// lat-long synthesis (SH maps here, SHRMs in `prefilter`).
pub struct RowSynth {
    width: usize,
    ifft: std::sync::Arc<dyn realfft::ComplexToReal<f64>>,
}

impl RowSynth {
    /// A synthesizer for rows of `width` texels.
    pub fn new(width: usize) -> Self {
        RowSynth { width, ifft: RealFftPlanner::<f64>::new().plan_fft_inverse(width) }
    }

    /// The highest frequency a row can hold (W/2).
    pub fn max_frequency(&self) -> usize {
        self.width / 2
    }

    /// Scratch buffers for [`RowSynth::synth`]: (spectrum, samples, fft scratch).
    pub fn buffers(&self) -> (Vec<Complex<f64>>, Vec<f64>, Vec<Complex<f64>>) {
        (self.ifft.make_input_vec(), self.ifft.make_output_vec(), self.ifft.make_scratch_vec())
    }

    /// Writes f(φ_x) into `samples` (length W) from `a[m]`, `b[m]` for m < a.len() ≤ W/2 + 1
    /// (`b[0]` is ignored).
    pub fn synth(&self, a: &[f64], b: &[f64], buffers: &mut (Vec<Complex<f64>>, Vec<f64>, Vec<Complex<f64>>)) {
        let (spectrum, samples, scratch) = buffers;
        let w = self.width;
        spectrum.iter_mut().for_each(|z| *z = Complex::new(0.0, 0.0));
        for m in 0..a.len().min(w / 2 + 1) {
            spectrum[m] = if m == 0 {
                Complex::new(a[0], 0.0)
            } else if 2 * m == w {
                // Nyquist: at φ_x = 2π(x+½)/W, cos(mφ_x) = 0 and sin(mφ_x) = (−1)^x.
                Complex::new(b[m], 0.0)
            } else {
                // f = Re Σ_m (a_m − i b_m) e^{imφ}; the inverse FFT sums X_m e^{2πimx/W} over
                // ±m, i.e. 2 Re(X_m e^{…}), and the half-texel shift is the phase e^{iπm/W}.
                let (s, c) = (PI * m as f64 / w as f64).sin_cos();
                Complex::new(a[m], -b[m]) * Complex::new(c, s) * 0.5
            };
        }
        // The DC and Nyquist bins are real by construction, so this cannot fail.
        let _ = self.ifft.process_with_scratch(spectrum, samples, scratch);
    }
}

/// Renders the coefficients into a `width`×`height` lat-long image (texel centres).
pub fn synthesize_latlong(coeffs: &ShCoeffs, width: usize, height: usize) -> Result<RgbImage, SynthError> {
    let order = coeffs.order;
    if 2 * order > width {
        return Err(SynthError::TooNarrow { order, width, need: 2 * order });
    }
    let table = LegendreTable::new(order);
    let rows = RowSynth::new(width);
    let mut image = RgbImage::new(width, height);
    image.pixels.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let theta = PI * (y as f64 + 0.5) / height as f64;
        let (st, ct) = theta.sin_cos();
        let mut plm = vec![0.0; count(order)];
        table.eval(ct, st, &mut plm);
        let mut buffers = rows.buffers();
        let (mut a, mut b) = (vec![0.0; order + 1], vec![0.0; order + 1]);
        for c in 0..3 {
            for m in 0..=order {
                // a_m(θ) = Σ_l L_lm √2 P̄_l^m(cos θ), b_m likewise with L_l,−m (m = 0: no √2).
                let (mut am, mut bm) = (0.0, 0.0);
                let scale = if m == 0 { 1.0 } else { SQRT_2 };
                for l in m..=order {
                    let p = plm[index(l, m as isize)] * scale;
                    am += coeffs.rgb[index(l, m as isize)][c] * p;
                    if m > 0 {
                        bm += coeffs.rgb[index(l, -(m as isize))][c] * p;
                    }
                }
                a[m] = am;
                b[m] = bm;
            }
            rows.synth(&a, &b, &mut buffers);
            for (px, v) in row.iter_mut().zip(&buffers.1) {
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
