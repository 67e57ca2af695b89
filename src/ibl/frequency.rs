//! The frequency-space path of a prefiltered level: the split-sum GGX lobe is radially symmetric
//! about R (N = V = R), so filtering the environment with it is a zonal filter, computed exactly
//! for the piecewise-constant lat-long map by row-pair FFTs in φ
//! ([`crate::envmap::zonal::zonal_filter`]); the cube texels then read the filtered sphere at
//! their directions.
//!
//! **Working grid.** Two needs set the grid's row height h = π/H for a lobe of width w = 2α
//! in θ ([`super::ggx`]):
//! - *the source*: a coarse texel loses where in it the light is, an error first order in h/w
//!   near small bright sources; h ≤ w/[`ROWS_PER_LOBE`], but never finer than the input, whose
//!   texels are what the environment is;
//! - *the read-back*: B is smooth on the scale of the lobe; h ≤ w/[`INTERPOLATION_ROWS_PER_LOBE`].
//!
//! and at least [`MIN_ROWS`] rows, so that wide lobes still see where small bright sources are.
//! The grid is the input box-resampled to that many rows (rounded up to a multiple of
//! [`GRID_STEP`]; [`box_latlong`]: texels are exact means over their footprints, ∫ L dω is
//! kept), or the input itself, or — when the read-back needs more rows than the input has — the
//! input with every texel split f × f, which is the same piecewise-constant function (nothing is
//! interpolated).
//!
//! The filter keeps every texel whose centre lies within π/2 + 2h of R (the kernel vanishes
//! beyond π/2: no truncation of the lobe) and integrates the kernel over each texel's extent by
//! a Gauss–Legendre rule chosen by measurement ([`crate::envmap::zonal::rule_for_kernel`]).
//! Dividing by the kernel weight of the texels kept makes a white environment exactly white.
//!
//! **Reading it back.** A cube texel takes B at its centre direction by Catmull–Rom
//! interpolation between the grid's texel centres (exact for quadratics: third-order error),
//! continued across the poles (rows −1, −2 are rows 0, 1 turned by π), so that it is as accurate
//! at the poles as anywhere. The result is limited to the range of the 4 × 4 texels read, so it
//! makes no new extremum and no negative value. Measured on `grace_latlong.exr` at r = 0.2 with
//! h = w/6.4: bilinear read-back 0.30 % RMS and 1.4 % max, Catmull–Rom 0.13 % and 0.58 %.
//!
//! **Cost.** O(H_out·H_cone·(W log W + n²·W_cone)) for W × H grids: cheap for wide lobes (few
//! rows), largest for the sharpest level. [`zonal_cost`] estimates it in kernel evaluations for
//! the stage's cost model.

use super::ggx::SplitSumLobe;
use crate::envmap::resample::box_latlong;
use crate::envmap::zonal::{rule_for_kernel, zonal_filter, ZonalError};
use crate::io::RgbImage;
use crate::progress::Progress;
use crate::sphere::LatLong;
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI};

/// Grid rows per lobe width w = 2α that the source needs: row height at most w/4 (capped at the
/// input's own rows).
pub const ROWS_PER_LOBE: f64 = 4.0;

/// Grid rows per lobe width that the read-back needs (Catmull–Rom: row height ≤ w/3).
pub const INTERPOLATION_ROWS_PER_LOBE: f64 = 3.0;

/// Fewest rows of a working grid (the widest lobes still see the sky's structure).
pub const MIN_ROWS: usize = 128;

/// Texel-rule tolerance: the rule may misplace at most this share of the kernel's weight.
pub const RULE_TOLERANCE: f64 = 1e-4;

/// Working-grid heights are multiples of this (widths of twice it): FFT sizes with small factors.
pub const GRID_STEP: usize = 16;

/// A lat-long input and the working grids the zonal path filters it on.
#[derive(Clone, Debug)]
pub struct LatLongSource {
    base: RgbImage,
}

impl LatLongSource {
    /// Wraps a W × H lat-long image.
    pub fn new(base: RgbImage) -> Self {
        LatLongSource { base }
    }

    /// The input.
    pub fn base(&self) -> &RgbImage {
        &self.base
    }

    /// Rows of the working grid for a lobe of width `lobe_width` radians (module docs).
    fn working_rows(&self, lobe_width: f64) -> usize {
        let source = ((ROWS_PER_LOBE * PI / lobe_width).ceil() as usize).min(self.base.height);
        let interpolation = (INTERPOLATION_ROWS_PER_LOBE * PI / lobe_width).ceil() as usize;
        source.max(interpolation).max(MIN_ROWS)
    }

    /// The dimensions of [`Self::working_grid`]: the input's; a box resampling to the rows needed
    /// (rounded up to a multiple of [`GRID_STEP`]) when that is coarser; or the input split an
    /// integer number of ways when the read-back needs more rows than it has.
    pub fn working_size(&self, lobe_width: f64) -> (usize, usize) {
        let (w, h) = (self.base.width, self.base.height);
        let rows = self.working_rows(lobe_width);
        if rows > h {
            let f = rows.div_ceil(h);
            return (w * f, h * f);
        }
        let rows = rows.div_ceil(GRID_STEP) * GRID_STEP;
        if rows >= h {
            return (w, h);
        }
        // The input's aspect kept, the width even.
        let cols = ((w as f64 * rows as f64 / h as f64 / 2.0).round() as usize * 2).max(2);
        (cols, rows)
    }

    /// The working grid for a lobe of width `lobe_width` radians (see the module docs).
    pub fn working_grid(&self, lobe_width: f64) -> RgbImage {
        let (w, h) = self.working_size(lobe_width);
        let base = &self.base;
        if (w, h) == (base.width, base.height) {
            return base.clone();
        }
        if h > base.height {
            let f = h / base.height;
            return RgbImage::from_fn(w, h, |x, y| base.get(x / f, y / f));
        }
        box_latlong(base, w, h)
    }
}

/// A filtered sphere on a lat-long grid, read by direction.
#[derive(Clone, Debug)]
pub struct FilteredSphere {
    /// The filtered map (normalized: a white environment gives 1).
    pub image: RgbImage,
    /// Sub-samples per axis of the texel rule used.
    pub rule_subsamples: usize,
}

impl FilteredSphere {
    /// B at direction `d` (prtkit's frame): Catmull–Rom between texel centres, continued
    /// across the poles, limited to the range of the 4 × 4 texels it reads (module docs).
    pub fn sample(&self, d: DVec3) -> [f32; 3] {
        let img = &self.image;
        let (w, h) = (img.width, img.height);
        let (px, py) = LatLong::new(w, h).position(d);
        let (fx, fy) = (px - 0.5, py - 0.5);
        let y0 = fy.floor();
        let wy = catmull_rom(fy - y0);
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let mut out = [0.0f64; 3];
        for (j, wj) in wy.iter().enumerate() {
            // Rows −1, −2 are rows 0, 1 seen across the pole (φ + π); likewise below row H − 1.
            let y = y0 as i64 - 1 + j as i64;
            let (row, shift) = if y < 0 {
                ((-1 - y) as usize, 0.5 * w as f64)
            } else if y >= h as i64 {
                ((2 * h as i64 - 1 - y) as usize, 0.5 * w as f64)
            } else {
                (y as usize, 0.0)
            };
            let x = fx + shift;
            let x0 = x.floor();
            for (i, wi) in catmull_rom(x - x0).iter().enumerate() {
                let v = img.get((x0 as i64 - 1 + i as i64).rem_euclid(w as i64) as usize, row.min(h - 1));
                for c in 0..3 {
                    out[c] += wj * wi * v[c] as f64;
                    lo[c] = lo[c].min(v[c]);
                    hi[c] = hi[c].max(v[c]);
                }
            }
        }
        [0, 1, 2].map(|c| (out[c] as f32).clamp(lo[c], hi[c]))
    }
}

/// Catmull–Rom weights of the taps at −1, 0, 1, 2 for a position t ∈ [0, 1) past tap 0: a cubic
/// that reproduces quadratics exactly, so its error is third order in the spacing.
fn catmull_rom(t: f64) -> [f64; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [0.5 * (-t3 + 2.0 * t2 - t), 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0), 0.5 * (-3.0 * t3 + 4.0 * t2 + t), 0.5 * (t3 - t2)]
}

/// The cone the filter keeps: the kernel's support (π/2) plus two rows, so that texels whose
/// centre is just beyond the horizon but whose extent reaches inside it are integrated.
fn support_cone(height: usize) -> f64 {
    (FRAC_PI_2 + 2.0 * PI / height as f64).min(PI)
}

/// Filters `grid` (a W × H lat-long map in prtkit's frame) with the split-sum lobe.
pub fn filter(grid: &RgbImage, lobe: &SplitSumLobe, progress: &dyn Progress) -> Result<FilteredSphere, ZonalError> {
    let kernel = |c: f64| lobe.kernel(c);
    let cone = support_cone(grid.height);
    let choice = rule_for_kernel(grid.width, grid.height, &kernel, cone, grid.height, RULE_TOLERANCE);
    let map = zonal_filter(grid, kernel, cone, &choice.rule, grid.height, progress)?;
    let mut image = map.normalized_image();
    // The FFT's rounding can leave −1e-16-sized values where the map is black; radiance is
    // non-negative.
    for p in &mut image.pixels {
        for v in p.iter_mut() {
            *v = v.max(0.0);
        }
    }
    Ok(FilteredSphere { image, rule_subsamples: choice.rule.subsamples() })
}

/// Estimated cost of [`filter`] on a W × H grid, in kernel evaluations: per output row and
/// source row within the support, one real FFT of W (≈ W log₂ W / 4 evaluation-equivalents)
/// and the kernel over the W/2 columns in the cone (one node per texel assumed).
pub fn zonal_cost(width: usize, height: usize) -> f64 {
    let (w, h) = (width as f64, height as f64);
    // Source rows within π/2 + of an output row: between H/2 (poles) and H (equator), ~0.75 H.
    h * 0.75 * h * (0.25 * w * w.log2() + 0.5 * w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    #[test]
    fn working_grid_splits_texels_when_the_input_is_too_coarse() {
        let img = RgbImage::from_fn(32, 16, |x, y| [x as f32, y as f32, 0.0]);
        let p = LatLongSource::new(img.clone());
        // A lobe of width 0.05 rad: the source needs no more than the input's 16 rows, the
        // read-back ⌈3π/0.05⌉ = 189: the input split 12 ways.
        let g = p.working_grid(0.05);
        assert_eq!((g.width, g.height), (384, 192));
        assert_eq!(p.working_size(0.05), (384, 192));
        assert_eq!(g.get(12 + 5, 24 + 7), img.get(1, 2));
        // A fine input: the rows the lobe needs, rounded up to GRID_STEP, at least MIN_ROWS.
        let fine = LatLongSource::new(RgbImage::new(1024, 512));
        assert_eq!(fine.working_size(2.0), (2 * MIN_ROWS, MIN_ROWS));
        // w = 0.08: ⌈4π/0.08⌉ = 158 rows → 160.
        assert_eq!(fine.working_size(0.08), (320, 160));
        assert_eq!(fine.working_grid(0.08).height, 160);
    }

    #[test]
    fn sampling_is_exact_at_texel_centres_and_continuous_across_the_poles() {
        let (w, h) = (32, 16);
        let g = LatLong::new(w, h);
        let b = DVec3::new(0.2, -0.4, 0.7);
        let f = |d: DVec3| 2.0 + b.dot(d);
        let img = RgbImage::from_fn(w, h, |x, y| [f(g.texel_direction(x, y)) as f32, 0.0, 0.0]);
        let s = FilteredSphere { image: img.clone(), rule_subsamples: 1 };
        for (x, y) in [(0, 0), (5, 3), (31, 15)] {
            assert!((s.sample(g.texel_direction(x, y))[0] - img.get(x, y)[0]).abs() < 1e-5);
        }
        // Near and at the poles the interpolation crosses over: a smooth field is read to
        // second order whatever the azimuth (clamping the row would be first order: b·Δ/2).
        let half_row = PI / h as f64 / 2.0;
        for pole in [1.0, -1.0] {
            for phi in [0.0, 1.0, 2.5, 4.0] {
                for theta in [0.0, 0.3 * half_row, 0.9 * half_row] {
                    let d = crate::sphere::direction(if pole > 0.0 { theta } else { PI - theta }, phi);
                    let err = (s.sample(d)[0] as f64 - f(d)).abs();
                    assert!(err < 4e-3, "pole {pole} φ={phi} θ={theta}: {err}");
                }
            }
        }
    }

    #[test]
    fn read_back_makes_no_new_extremum() {
        // One bright texel on black: Catmull–Rom alone would ring negative beside it.
        let mut img = RgbImage::new(32, 16);
        img.set(10, 7, [100.0, 1.0, 0.0]);
        let s = FilteredSphere { image: img, rule_subsamples: 1 };
        let g = LatLong::new(32, 16);
        for k in 0..400 {
            let d = g.direction_at(8.0 + 5.0 * (k % 20) as f64 / 20.0, 5.0 + 5.0 * (k / 20) as f64 / 20.0);
            let v = s.sample(d);
            assert!(v.iter().all(|&c| c >= 0.0) && v[0] <= 100.0, "{v:?}");
        }
    }

    #[test]
    fn white_stays_white_and_a_linear_sky_gets_the_band_one_factor() {
        // L = 1 + b·ω is band-limited to l ≤ 1: the filtered map is 1 + Λ_1 k_1 b·R exactly
        // (the convolution theorem; the factor from the lobe's own quadrature).
        let b = DVec3::new(0.1, -0.2, 0.3);
        let (w, h) = (128, 64);
        let g = LatLong::new(w, h);
        let img = RgbImage::from_fn(w, h, |x, y| [1.0, (1.0 + b.dot(g.texel_direction(x, y))) as f32, 0.0]);
        for r in [0.5, 1.0] {
            let lobe = SplitSumLobe::new(r).unwrap();
            let factor = lobe.convolution_factors(1)[1];
            let f = filter(&img, &lobe, &NoProgress).unwrap();
            for d in [DVec3::X, DVec3::new(0.3, 0.4, -0.866).normalize(), DVec3::Z] {
                let v = f.sample(d);
                assert!((v[0] - 1.0).abs() < 1e-5, "{v:?}");
                let want = 1.0 + factor * b.dot(d);
                // Piecewise-constant source: O(h²) from the texel means of a linear function.
                assert!((v[1] as f64 - want).abs() < 2e-3, "r={r} {d}: {} vs {want}", v[1]);
            }
        }
    }
}
