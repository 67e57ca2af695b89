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
    /// The half-texel shift e^{iπm/W} of each bin m ≤ W/2, as (sin, cos).
    shift: Vec<(f64, f64)>,
}

impl RowSynth {
    /// A synthesizer for rows of `width` texels.
    pub fn new(width: usize) -> Self {
        let shift = (0..=width / 2).map(|m| (PI * m as f64 / width as f64).sin_cos()).collect();
        RowSynth { width, ifft: RealFftPlanner::<f64>::new().plan_fft_inverse(width), shift }
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
                let (s, c) = self.shift[m];
                Complex::new(a[m], -b[m]) * Complex::new(c, s) * 0.5
            };
        }
        // The DC and Nyquist bins are real by construction, so this cannot fail.
        let _ = self.ifft.process_with_scratch(spectrum, samples, scratch);
    }
}

/// Renders the coefficients into a `width`×`height` lat-long image (texel centres).
///
/// Rows are taken in mirrored pairs, θ and π − θ: P̄_l^m(−z) = (−1)^{l+m} P̄_l^m(z), so one
/// Legendre evaluation serves both. With E_m and O_m the parts of a_m(θ) = Σ_l L_lm √2 P̄_l^m
/// over the bands with l + m even and odd, a_m(θ) = E_m + O_m and a_m(π − θ) = E_m − O_m (b_m
/// likewise). The sums are taken one order m at a time, the column P̄_l^m, l ≥ m, run over every
/// row pair at once ([`LegendreTable::column`]), and the rows' inverse FFTs follow; each sum
/// over l is in the same order as row by row, so the image is too.
pub fn synthesize_latlong(coeffs: &ShCoeffs, width: usize, height: usize) -> Result<RgbImage, SynthError> {
    let order = coeffs.order;
    if 2 * order > width {
        return Err(SynthError::TooNarrow { order, width, need: 2 * order });
    }
    let table = LegendreTable::new(order);
    let rows = RowSynth::new(width);
    let pairs: Vec<(usize, Option<usize>)> = crate::sphere::LatLong::new(width, height).mirrored_row_pairs().collect();
    let n = pairs.len();
    let (sin_theta, cos_theta): (Vec<f64>, Vec<f64>) =
        pairs.iter().map(|&(y, _)| (PI * (y as f64 + 0.5) / height as f64).sin_cos()).unzip();
    let diagonals = table.diagonals(&sin_theta);
    // Per order m: [part][cos or sin][channel][pair] with part 0 the bands with l + m even (the
    // even part in z) and 1 the rest, each summed over l in order, the column of Legendre
    // values run over all pairs at once.
    let columns: Vec<Vec<f64>> = (0..=order)
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |column_scratch, m| {
                let mut parts = vec![0.0; 12 * n];
                let kinds = if m == 0 { 1 } else { 2 };
                table.column(m, &cos_theta, &diagonals[m * n..(m + 1) * n], column_scratch, |l, values| {
                    let part = &mut parts[((l + m) % 2) * 6 * n..][..6 * n];
                    for k in 0..kinds {
                        let coefficient = coeffs.rgb[index(l, if k == 0 { m as isize } else { -(m as isize) })];
                        for c in 0..3 {
                            for (acc, p) in part[(k * 3 + c) * n..][..n].iter_mut().zip(values) {
                                *acc += p * coefficient[c];
                            }
                        }
                    }
                });
                parts
            },
        )
        .collect();
    let buffers = || (rows.buffers(), vec![0.0; order + 1], vec![0.0; order + 1]);
    let synthesized: Vec<[Vec<[f32; 3]>; 2]> = (0..n)
        .into_par_iter()
        .map_init(buffers, |(buffers, a, b), j| {
            let mirror = pairs[j].1;
            let mut out = [vec![[0.0f32; 3]; width], vec![[0.0f32; 3]; if mirror.is_some() { width } else { 0 }]];
            for (half, sign) in [(0, 1.0), (1, -1.0)] {
                if half == 1 && mirror.is_none() {
                    break;
                }
                for c in 0..3 {
                    for (m, column) in columns.iter().enumerate() {
                        let at = |part: usize, k: usize| column[((part * 2 + k) * 3 + c) * n + j];
                        let scale = if m == 0 { 1.0 } else { SQRT_2 };
                        a[m] = scale * (at(0, 0) + sign * at(1, 0));
                        b[m] = scale * (at(0, 1) + sign * at(1, 1));
                    }
                    rows.synth(a, b, buffers);
                    for (px, v) in out[half].iter_mut().zip(&buffers.1) {
                        px[c] = *v as f32;
                    }
                }
            }
            out
        })
        .collect();
    let mut image = RgbImage::new(width, height);
    for (&(y, mirror), [top, bottom]) in pairs.iter().zip(synthesized) {
        image.pixels[y * width..(y + 1) * width].copy_from_slice(&top);
        if let Some(y) = mirror {
            image.pixels[y * width..(y + 1) * width].copy_from_slice(&bottom);
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_latlong_synthesis_is_the_direct_sum_at_every_texel_centre() {
        // Mirrored row pairs (and a lone middle row at odd heights), bands of both parities,
        // m = ±order at the Nyquist limit of the narrower width.
        let order = 11;
        let mut coeffs = ShCoeffs::zeros(order);
        let mut rng = crate::rng::SplitMix64::new(5);
        for v in &mut coeffs.rgb {
            for c in v.iter_mut() {
                *c = rng.next_f64() - 0.5;
            }
        }
        let table = LegendreTable::new(order);
        for (w, h) in [(24, 12), (22, 11), (30, 17)] {
            let image = synthesize_latlong(&coeffs, w, h).unwrap();
            let grid = crate::sphere::LatLong::new(w, h);
            let mut scratch = Vec::new();
            for y in 0..h {
                for x in 0..w {
                    let direct = eval(&coeffs, &table, grid.texel_direction(x, y), &mut scratch);
                    let got = image.pixels[y * w + x];
                    for c in 0..3 {
                        assert!(
                            (got[c] as f64 - direct[c]).abs() < 1e-5,
                            "{w}x{h} texel ({x}, {y}) channel {c}: {} against {}",
                            got[c],
                            direct[c]
                        );
                    }
                }
            }
        }
    }
}
