//! The frequency-space path of a prefiltered level: the split-sum GGX lobe is radially symmetric
//! about R (N = V = R), so filtering the environment with it is a zonal filter, computed exactly
//! for the piecewise-constant lat-long map by row-pair FFTs in φ
//! ([`crate::envmap::zonal::zonal_filter`]); the cube texels then read the filtered sphere at
//! their directions.
//!
//! **Working grid.** Two needs set the grid's row height h = π/H for a lobe of width w = 2α
//! in θ ([`crate::brdf::ggx`]):
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
//! **Peak and tail.** GGX's tail is heavy (the kernel falls as 1/θ⁴ out to π/2), so a sharp
//! level's filter reaches over half the sphere at the fine grid its peak needs: every output row
//! pairs with ~¾ of the source rows. But beyond a few lobe widths the kernel is smooth, and a
//! smooth kernel needs only a coarse grid. So when the fine grid has at least twice the rows the
//! tail needs, the kernel is split at γ_s = [`TAIL_SPLIT`] lobe widths with a C² step s in
//! cos γ, 1 within γ_s and 0 beyond 2γ_s ([`Step`]):
//!
//!   k = k·s + k·(1 − s) = peak + tail.
//!
//! The peak is filtered on the fine grid within its own support (2γ_s plus two rows), the tail
//! on the grid its width γ_s needs, over the whole support. Each pass is normalized by its own
//! texel weights and weighted by its exact share of the kernel's mass (m_peak = ∫ k·s dω by the
//! lobe's quadrature, m_tail = 1 − m_peak), so a white environment stays exactly white. Both
//! are exact integrals of the piecewise-constant source over their grids; the tail's coarser
//! grid only moves light within texels γ_s/4 wide, where its kernel varies on the scale of γ_s.
//! Measured on `grace_latlong.exr` at r = 0.134 (the sharpest level of Filament's mapping at
//! 128² faces): the split map differs from the whole-kernel map by 5e-6 RMS and 0.27 % at
//! worst, in 60 % of the time (0.081 s against 0.136 s); against the angular
//! integral the level stays at 0.26 % RMS and 0.98 % max. γ_s = 4w was 0.82 % at worst, 8w
//! 0.18 % at 66 % of the time. `split_matches_the_whole_kernel` holds a sun 10⁴ times the sky
//! to it.
//!
//! **Cost.** O(H_out·H_cone·(W log W + n²·W_cone)) for W × H grids: cheap for wide lobes (few
//! rows), largest for the sharpest level. [`zonal_cost`] estimates it in kernel evaluations for
//! the stage's cost model.

use crate::brdf::ggx::SplitSumLobe;
use crate::envmap::resample::box_latlong;
use crate::envmap::zonal::{rule_for_kernel, zonal_filter, Rows, ZonalError};
use crate::io::RgbImage;
use crate::progress::Progress;
use crate::quadrature::gauss_legendre_cached as gauss_legendre;
use crate::sphere::LatLong;
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::{Arc, Mutex};

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

/// Where the kernel splits into peak and tail, in lobe widths (module docs): γ_s = 6w leaves
/// about 1 % of GGX's mass to the tail for small α (the step's middle, 1.5γ_s, is θ_h = 9α,
/// beyond which the half-vector share is α²/(α² + tan² 9α) ≈ 1/82; measured 0.93 % at
/// r = 0.134), and the tail is smooth on the scale of γ_s.
pub const TAIL_SPLIT: f64 = 6.0;

/// Which part of the kernel a zonal pass filters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Part {
    /// The whole kernel.
    Whole,
    /// k·s: the peak, within 2γ_s.
    Peak(Step),
    /// k·(1 − s): the tail beyond γ_s.
    Tail(Step),
}

impl Part {
    /// The part's kernel at cos γ.
    fn kernel(&self, lobe: &SplitSumLobe, cos_gamma: f64) -> f64 {
        match self {
            Part::Whole => lobe.kernel(cos_gamma),
            Part::Peak(step) => lobe.kernel(cos_gamma) * step.share(cos_gamma),
            Part::Tail(step) => lobe.kernel(cos_gamma) * (1.0 - step.share(cos_gamma)),
        }
    }

    /// The part's share of the kernel's mass: 1, m_peak, or 1 − m_peak.
    pub fn mass(&self, lobe: &SplitSumLobe) -> f64 {
        match self {
            Part::Whole => 1.0,
            Part::Peak(step) => step.peak_mass(lobe),
            Part::Tail(step) => 1.0 - step.peak_mass(lobe),
        }
    }
}

/// One zonal pass of a level: its working grid and the part of the kernel it filters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pass {
    /// Grid width.
    pub width: usize,
    /// Grid height (also the filtered map's rows).
    pub height: usize,
    /// The part of the kernel.
    pub part: Part,
}

impl Pass {
    /// The cone of source texel centres the pass keeps: the part's support plus two rows, so
    /// that texels whose centre lies just outside but whose extent reaches in are integrated.
    pub fn cone(&self) -> f64 {
        let support = match self.part {
            Part::Whole | Part::Tail(_) => FRAC_PI_2,
            Part::Peak(step) => 2.0 * step.split,
        };
        (support + 2.0 * PI / self.height as f64).min(PI)
    }

    /// Estimated cost in kernel evaluations ([`zonal_cost`]).
    pub fn cost(&self) -> f64 {
        zonal_cost(self.width, self.height, self.cone())
    }
}

/// The peak's share s(γ) of the kernel: 1 within γ_s of R, 0 beyond 2γ_s, and between them the
/// C² step 1 − t³(10 − 15t + 6t²) in t = (cos γ_s − cos γ)/(cos γ_s − cos 2γ_s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// γ_s (radians).
    pub split: f64,
    inner: f64,
    outer: f64,
}

impl Step {
    /// The step that starts at γ_s = `split`.
    pub fn new(split: f64) -> Self {
        Step { split, inner: split.cos(), outer: (2.0 * split).cos() }
    }

    /// s at cos γ (branch-free, so kernel loops vectorize).
    #[inline]
    pub fn share(&self, cos_gamma: f64) -> f64 {
        let t = ((self.inner - cos_gamma) / (self.inner - self.outer)).clamp(0.0, 1.0);
        1.0 - t * t * t * (10.0 + t * (6.0 * t - 15.0))
    }

    /// m_peak = ∫ k·s dω: the lobe's mass within γ_s, plus the step's span by Gauss–Legendre on
    /// four pieces (k and s are smooth there).
    pub fn peak_mass(&self, lobe: &SplitSumLobe) -> f64 {
        let rule = gauss_legendre(16);
        let pieces = 4;
        let h = self.split / pieces as f64;
        let mut blend = 0.0;
        for p in 0..pieces {
            let a = self.split + p as f64 * h;
            for &(x, w) in rule.iter() {
                let g = a + 0.5 * h * (x + 1.0);
                blend += 0.5 * h * w * TAU * g.sin() * lobe.kernel_at_angle(g) * self.share(g.cos());
            }
        }
        lobe.mass_within(self.split) + blend
    }
}

/// A lat-long input and the working grids the zonal path filters it on (each size made once:
/// the wide levels and the irradiance cube share theirs).
#[derive(Debug)]
pub struct LatLongSource<'a> {
    base: &'a RgbImage,
    grids: Mutex<Vec<Arc<RgbImage>>>,
}

/// A working grid of a [`LatLongSource`]: the input itself, or one of its resamplings.
pub enum WorkingGrid<'a> {
    /// The input, when the lobe needs its rows as they are.
    Input(&'a RgbImage),
    /// A box filtering or a split of the input, made once per size.
    Resampled(Arc<RgbImage>),
}

impl std::ops::Deref for WorkingGrid<'_> {
    type Target = RgbImage;
    fn deref(&self) -> &RgbImage {
        match self {
            WorkingGrid::Input(image) => image,
            WorkingGrid::Resampled(image) => image,
        }
    }
}

impl<'a> LatLongSource<'a> {
    /// Wraps a W × H lat-long image (borrowed: the largest inputs are not copied).
    pub fn new(base: &'a RgbImage) -> Self {
        LatLongSource { base, grids: Mutex::new(Vec::new()) }
    }

    /// The input.
    pub fn base(&self) -> &'a RgbImage {
        self.base
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
    pub fn working_grid(&self, lobe_width: f64) -> WorkingGrid<'a> {
        let (w, h) = self.working_size(lobe_width);
        let base = self.base;
        if (w, h) == (base.width, base.height) {
            return WorkingGrid::Input(base);
        }
        let mut grids = self.grids.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(g) = grids.iter().find(|g| (g.width, g.height) == (w, h)) {
            return WorkingGrid::Resampled(g.clone());
        }
        let grid = Arc::new(if h > base.height {
            let f = h / base.height;
            RgbImage::from_fn(w, h, |x, y| base.get(x / f, y / f))
        } else {
            box_latlong(base, w, h)
        });
        grids.push(grid.clone());
        WorkingGrid::Resampled(grid)
    }

    /// The zonal passes that filter with `lobe`: the whole kernel on the grid it needs, or, when
    /// that grid has at least twice the rows the tail needs, the peak on it and the tail on the
    /// tail's grid (module docs).
    pub fn passes(&self, lobe: &SplitSumLobe) -> Vec<Pass> {
        let width = lobe.width();
        let (w, h) = self.working_size(width);
        let split = TAIL_SPLIT * width;
        let (tail_w, tail_h) = self.working_size(split);
        if 2 * tail_h > h || 2.0 * split >= FRAC_PI_2 {
            return vec![Pass { width: w, height: h, part: Part::Whole }];
        }
        let step = Step::new(split);
        vec![
            Pass { width: w, height: h, part: Part::Peak(step) },
            Pass { width: tail_w, height: tail_h, part: Part::Tail(step) },
        ]
    }

    /// The environment filtered with `lobe` by [`Self::passes`].
    pub fn filter(&self, lobe: &SplitSumLobe, progress: &dyn Progress) -> Result<FilteredSphere, ZonalError> {
        let passes = self.passes(lobe);
        let mut parts = Vec::with_capacity(passes.len());
        let mut rule_subsamples = 0;
        let mut grids = Vec::new();
        for pass in &passes {
            let grid = self.working_grid(match pass.part {
                Part::Tail(step) => step.split,
                _ => lobe.width(),
            });
            let share = pass.part.mass(lobe);
            let (image, subsamples) = filter_pass(&grid, lobe, pass, progress)?;
            rule_subsamples = rule_subsamples.max(subsamples);
            grids.push(format!("{}x{}", grid.width, grid.height));
            parts.push((image, share));
        }
        let source = match grids.as_slice() {
            [whole] => format!("latlong {whole}"),
            [peak, tail] => format!("latlong {peak} (peak), {tail} (tail)"),
            _ => unreachable!("one or two passes"),
        };
        Ok(FilteredSphere { parts, rule_subsamples, source })
    }
}

/// A filtered sphere, read by direction: one lat-long map per pass, weighted by its share.
#[derive(Clone, Debug)]
pub struct FilteredSphere {
    /// (map, share): each map normalized (a white environment gives 1), the shares sum to 1.
    pub parts: Vec<(RgbImage, f64)>,
    /// Sub-samples per axis of the texel rule used (the largest over the passes).
    pub rule_subsamples: usize,
    /// The working grids, for the manifest.
    pub source: String,
}

impl FilteredSphere {
    /// B at direction `d` (prtkit's frame): the shares of the passes' read-backs.
    pub fn sample(&self, d: DVec3) -> [f32; 3] {
        let mut out = [0.0f32; 3];
        for (image, share) in &self.parts {
            let v = read_back(image, d);
            for c in 0..3 {
                out[c] += *share as f32 * v[c];
            }
        }
        out
    }
}

/// A filtered map at direction `d`: Catmull–Rom between texel centres, continued across the
/// poles, limited to the range of the 4 × 4 texels it reads (module docs).
pub fn read_back(img: &RgbImage, d: DVec3) -> [f32; 3] {
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

/// Catmull–Rom weights of the taps at −1, 0, 1, 2 for a position t ∈ [0, 1) past tap 0: a cubic
/// that reproduces quadratics exactly, so its error is third order in the spacing.
fn catmull_rom(t: f64) -> [f64; 4] {
    let (t2, t3) = (t * t, t * t * t);
    [0.5 * (-t3 + 2.0 * t2 - t), 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0), 0.5 * (-3.0 * t3 + 4.0 * t2 + t), 0.5 * (t3 - t2)]
}

/// One pass on its grid: the normalized map and the rule's sub-samples per axis.
fn filter_pass(
    grid: &RgbImage,
    lobe: &SplitSumLobe,
    pass: &Pass,
    progress: &dyn Progress,
) -> Result<(RgbImage, usize), ZonalError> {
    let kernel = |c: f64| pass.part.kernel(lobe, c);
    let cone = pass.cone();
    let choice = rule_for_kernel(grid.width, grid.height, &kernel, cone, grid.height, RULE_TOLERANCE);
    let map = zonal_filter(grid, kernel, cone, &choice.rule, grid.height, Rows::All, progress)?;
    let mut image = map.normalized_image().expect("Rows::All measures the row weights");
    // The FFT's rounding can leave −1e-16-sized values where the map is black; radiance is
    // non-negative.
    for p in &mut image.pixels {
        for v in p.iter_mut() {
            *v = v.max(0.0);
        }
    }
    Ok((image, choice.rule.subsamples()))
}

/// Filters `grid` (a W × H lat-long map in prtkit's frame) with the whole split-sum lobe.
pub fn filter(grid: &RgbImage, lobe: &SplitSumLobe, progress: &dyn Progress) -> Result<FilteredSphere, ZonalError> {
    let pass = Pass { width: grid.width, height: grid.height, part: Part::Whole };
    let (image, rule_subsamples) = filter_pass(grid, lobe, &pass, progress)?;
    Ok(FilteredSphere {
        parts: vec![(image, 1.0)],
        rule_subsamples,
        source: format!("latlong {}x{}", grid.width, grid.height),
    })
}

/// Estimated cost of one pass on a W × H grid keeping source texels within `cone`, in kernel
/// evaluations: per output row and source row within the cone, one real FFT of W
/// (≈ W log₂ W / 4 evaluation-equivalents) and the kernel over the W/2 columns.
pub fn zonal_cost(width: usize, height: usize, cone: f64) -> f64 {
    let (w, h) = (width as f64, height as f64);
    // Source rows within π/2 of an output row: between H/2 (poles) and H (equator), ~0.75 H;
    // within a narrow cone c, 2c/π of them.
    let rows = (2.0 * cone / PI).min(0.75);
    h * rows * h * (0.25 * w * w.log2() + 0.5 * w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    #[test]
    fn working_grid_splits_texels_when_the_input_is_too_coarse() {
        let img = RgbImage::from_fn(32, 16, |x, y| [x as f32, y as f32, 0.0]);
        let p = LatLongSource::new(&img);
        // A lobe of width 0.05 rad: the source needs no more than the input's 16 rows, the
        // read-back ⌈3π/0.05⌉ = 189: the input split 12 ways.
        let g = p.working_grid(0.05);
        assert_eq!((g.width, g.height), (384, 192));
        assert_eq!(p.working_size(0.05), (384, 192));
        assert_eq!(g.get(12 + 5, 24 + 7), img.get(1, 2));
        // A fine input: the rows the lobe needs, rounded up to GRID_STEP, at least MIN_ROWS.
        let fine_input = RgbImage::new(1024, 512);
        let fine = LatLongSource::new(&fine_input);
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
        for (x, y) in [(0, 0), (5, 3), (31, 15)] {
            assert!((read_back(&img, g.texel_direction(x, y))[0] - img.get(x, y)[0]).abs() < 1e-5);
        }
        // Near and at the poles the interpolation crosses over: a smooth field is read to
        // second order whatever the azimuth (clamping the row would be first order: b·Δ/2).
        let half_row = PI / h as f64 / 2.0;
        for pole in [1.0, -1.0] {
            for phi in [0.0, 1.0, 2.5, 4.0] {
                for theta in [0.0, 0.3 * half_row, 0.9 * half_row] {
                    let d = crate::sphere::direction(if pole > 0.0 { theta } else { PI - theta }, phi);
                    let err = (read_back(&img, d)[0] as f64 - f(d)).abs();
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
        let g = LatLong::new(32, 16);
        for k in 0..400 {
            let d = g.direction_at(8.0 + 5.0 * (k % 20) as f64 / 20.0, 5.0 + 5.0 * (k / 20) as f64 / 20.0);
            let v = read_back(&img, d);
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

    #[test]
    fn split_matches_the_whole_kernel() {
        // A sky, a ground and a sun 10⁴ times brighter (3 × 2 texels), at the sharpest roughness
        // of Filament's mapping for 128² faces: the split into peak and tail (module docs)
        // against the whole kernel on the same fine grid.
        let (w, h) = (256, 128);
        let g = LatLong::new(w, h);
        let img = RgbImage::from_fn(w, h, |x, y| {
            let d = g.texel_direction(x, y);
            if (40..43).contains(&x) && (30..32).contains(&y) {
                [2e4, 1.8e4, 1.5e4]
            } else if d.z > 0.0 {
                [0.3 + 0.5 * d.z as f32, 0.5 + 0.4 * d.z as f32, 1.0]
            } else {
                [0.2 + 0.1 * ((x / 8 + y / 8) % 2) as f32, 0.15, 0.1]
            }
        });
        let source = LatLongSource::new(&img);
        let lobe = SplitSumLobe::new(0.134).unwrap();
        let passes = source.passes(&lobe);
        let [Pass { part: Part::Peak(step), .. }, Pass { part: Part::Tail(_), .. }] = passes[..] else {
            panic!("a sharp lobe on a fine grid splits: {passes:?}");
        };
        assert_eq!(source.passes(&SplitSumLobe::new(0.5).unwrap())[0].part, Part::Whole);
        // m_peak against a brute-force midpoint sum of 2π sin γ k(γ) s(γ) over [0, π/2], which
        // shares none of the piecewise rule; the tail keeps about 1 % (TAIL_SPLIT's docs).
        let n = 400_000;
        let dg = FRAC_PI_2 / n as f64;
        let brute: f64 = (0..n)
            .map(|i| (i as f64 + 0.5) * dg)
            .map(|g| TAU * g.sin() * lobe.kernel_at_angle(g) * step.share(g.cos()) * dg)
            .sum();
        let m_peak = step.peak_mass(&lobe);
        assert!((m_peak - brute).abs() < 1e-6, "{m_peak} vs {brute}");
        assert!(m_peak > 0.985 && m_peak < 0.995, "{m_peak}"); // measured 0.9907
        let split = source.filter(&lobe, &NoProgress).unwrap();
        let whole = filter(&source.working_grid(lobe.width()), &lobe, &NoProgress).unwrap();
        assert_eq!(split.parts.iter().map(|p| p.1).collect::<Vec<_>>(), [m_peak, 1.0 - m_peak]);
        let out = LatLong::new(200, 100);
        let mean = (0..100 * 200).map(|k| whole.sample(out.texel_direction(k % 200, k / 200))[1] as f64).sum::<f64>()
            / 20000.0;
        let (mut worst, mut err2, mut ref2) = (0.0f64, 0.0, 0.0);
        for k in 0..100 * 200 {
            let d = out.texel_direction(k % 200, k / 200);
            let (a, b) = (split.sample(d), whole.sample(d));
            for c in 0..3 {
                let e = (a[c] - b[c]) as f64;
                err2 += e * e;
                ref2 += (b[c] as f64).powi(2);
                if b[c] as f64 > 0.01 * mean {
                    worst = worst.max(e.abs() / b[c] as f64);
                }
            }
        }
        // Measured: 1.5e-6 RMS, 0.59 % at worst, in the dark texels beside the sun, which its tail
        // lights (the tail is read back from 128 rows instead of 384).
        assert!((err2 / ref2).sqrt() < 1e-5 && worst < 1e-2, "rms {:.2e} max {worst:.2e}", (err2 / ref2).sqrt());
        // Each pass is normalized and the shares sum to one: white stays exactly white.
        let white_input = RgbImage::from_fn(w, h, |_, _| [1.0; 3]);
        let white = LatLongSource::new(&white_input);
        let white_split = white.filter(&lobe, &NoProgress).unwrap();
        assert_eq!(white_split.parts.len(), 2);
        for d in [DVec3::X, DVec3::new(0.3, -0.2, 0.93).normalize(), -DVec3::Z] {
            assert!(white_split.sample(d).iter().all(|v| (v - 1.0).abs() < 1e-5), "{:?}", white_split.sample(d));
        }
    }
}
