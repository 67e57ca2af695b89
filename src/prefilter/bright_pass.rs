//! The bright-source pass (`docs/prefilter.md`, "Bright sources apart"): the excess of a map's
//! compact, very bright texels over a threshold ([`crate::envmap::bright`]) is filtered with the
//! exact lobe, apart from the clipped remainder that goes through spherical harmonics. Each
//! bright texel t_j of excess e_j adds e_j ∫_{t_j} ρ̂(ω; R, V) dω to every texel R of a map.
//!
//! One type, [`BrightPass`], and one selector, [`BrightPass::path`], which reads the lobe and its
//! width against the texels the sources were split on ([`tuning::NARROW_LOBE_TEXELS`]):
//!
//! - **a radially symmetric lobe, wide** ([`Path::Harmonics`]): the texels' exact integrals
//!   projected onto spherical harmonics, synthesized with the remainder
//!   ([`BrightPass::through_harmonics`]);
//! - **a radially symmetric lobe, narrow** ([`Path::Zonal`]), or a wide one whose harmonics
//!   declined: the zonal filter of their excess on a map as wide as their grid, else the sum over
//!   the bright texels per map texel ([`BrightPass::add_to_map`]; in an SHRM file, its single
//!   layer: [`BrightPass::add_to_shrm`]);
//! - **a view-dependent lobe** ([`Path::View`]): the sum per map texel for each view
//!   ([`BrightPass::add_to_map`]), the projection onto the view basis in an SHRM file
//!   ([`BrightPass::add_to_shrm`]), and, for maps integrated in the view's frame, a splat of
//!   their energy into that frame ([`BrightPass::splat`]).

use super::angular::as_latlong;
use super::model::Model;
use super::pipeline::{Lighting, PrefilterError};
use super::shrm::{texel_frame, Shrm};
use super::truncation::{radial_cutoff, radial_truncation, CutoffTable};
use super::tuning::{
    self, ANGULAR_EPSILON, BRIGHT_Z_NODES, RULE_TOLERANCE, VIEW_PROJECTION_BINS, VIEW_PROJECTION_NODES,
};
use crate::envmap::bright::{split, BrightReport, BrightRule, BrightSources};
use crate::envmap::zonal::{rule_for_kernel, zonal_filter, Rows};
use crate::envmap::{EnvMap, Layout};
use crate::io::RgbImage;
use crate::progress::{NoProgress, Progress};
use crate::sh::convolve::convolve_zonal_rgb;
use crate::sh::project::{project_latlong_texels, TexelQuadrature};
use crate::sh::ShCoeffs;
use crate::sphere::latlong::bilinear_taps;
use crate::sphere::LatLong;
use glam::{DQuat, DVec3};
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

/// The bright texels split off a bake's lighting and the way they are filtered.
pub struct BrightPass {
    sources: BrightSources,
    /// The lat-long grid they were split on (`None` for given coefficients: nothing is split).
    grid: Option<LatLong>,
    /// Their reflected radiance as spherical harmonics, when they took [`Path::Harmonics`].
    harmonics: Option<ShCoeffs>,
}

/// How a lobe takes the bright texels: [`BrightPass::path`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    /// A radially symmetric lobe at least [`tuning::NARROW_LOBE_TEXELS`] wide: spherical harmonics.
    Harmonics,
    /// A narrower radially symmetric lobe: the zonal filter, or the sum per map texel.
    Zonal,
    /// A view-dependent lobe: the sum per map texel, the view projection, or the splat.
    View,
}

/// The lobe the bright texels are filtered with in one map.
#[derive(Clone, Copy)]
pub enum Lobe<'a> {
    /// Radially symmetric.
    Radial,
    /// View-dependent: the view and the cones per view angle.
    View(DVec3, &'a CutoffTable),
}

impl BrightPass {
    /// The lighting as lat-long ([`as_latlong`]) split into its clipped remainder and bright
    /// texels by `rule`; given coefficients have no texels to split (no remainder map).
    pub fn split(lighting: Lighting<'_>, rule: BrightRule) -> Result<(Option<EnvMap>, BrightPass), PrefilterError> {
        let Lighting::Map(map) = lighting else {
            let none = BrightSources { threshold: f64::INFINITY, ..Default::default() };
            return Ok((None, BrightPass { sources: none, grid: None, harmonics: None }));
        };
        let (remainder, sources) = if map.layout() == Layout::LatLong {
            // The split's remainder is the one copy of the map.
            split(map, rule)
        } else {
            split(&as_latlong(map).map_err(PrefilterError::Resample)?, rule)
        };
        let grid = Some(LatLong::new(remainder.image().width, remainder.image().height));
        Ok((Some(remainder), BrightPass { sources, grid, harmonics: None }))
    }

    /// The bright texels.
    pub fn sources(&self) -> &BrightSources {
        &self.sources
    }

    /// The split, in figures.
    pub fn report(&self) -> BrightReport {
        self.sources.report()
    }

    /// The one selector: [`Path::View`] for a view-dependent lobe, else [`Path::Harmonics`] when
    /// the lobe spans at least [`tuning::NARROW_LOBE_TEXELS`] texels of the grid the sources
    /// were split on, [`Path::Zonal`] when it is narrower. The texel integrals keep the harmonics
    /// exact for any width; the bound is one of cost: the band they need grows as the lobe
    /// narrows, while the zonal filter's cost falls with the cone.
    pub fn path(&self, model: &Model) -> Path {
        match (model.centre(), self.grid) {
            (None, _) => Path::View,
            (Some(_), Some(grid)) if !tuning::is_narrow(lobe_truncation(model).width, grid.height) => Path::Harmonics,
            (Some(_), _) => Path::Zonal,
        }
    }

    /// On [`Path::Harmonics`], projects the bright texels onto spherical harmonics with the
    /// lobe's zonal `kernel` k_l for an output `width` texels wide ([`harmonics`]): then the
    /// SHRM's synthesis carries them ([`BrightPass::harmonics`]) and every other method of the
    /// pass leaves them out. Otherwise, or when the harmonics decline, nothing.
    pub fn through_harmonics(&mut self, model: &Model, kernel: &[[f64; 3]], width: usize) {
        if let (Path::Harmonics, Some(grid), false) = (self.path(model), self.grid, self.sources.is_empty()) {
            self.harmonics = harmonics(model, &self.sources, grid, kernel, width);
        }
    }

    /// The bright texels' reflected radiance as spherical harmonics (kernel applied, no window),
    /// when they took them.
    pub fn harmonics(&self) -> Option<&ShCoeffs> {
        self.harmonics.as_ref()
    }

    /// True when the bright texels are still to be added in angle.
    fn in_angle(&self) -> bool {
        !self.sources.is_empty() && self.harmonics.is_none()
    }

    /// The bright texels' exact contribution to a `width`×`height` lat-long reflection map of R
    /// (of N for Lambert) under `lobe`, or `None` when there is nothing to add in angle.
    pub fn add_to_map(&self, model: &Model, lobe: Lobe<'_>, (width, height): (usize, usize)) -> Option<RgbImage> {
        if !self.in_angle() {
            return None;
        }
        let mut map = RgbImage::new(width, height);
        add_to_map(&mut map, model, &self.sources, self.grid, lobe);
        Some(map)
    }

    /// Adds the bright texels to a local SHRM: for a radially symmetric lobe, its exact map in
    /// the single layer B_00 = √(4π) B; for a view-dependent one, projected onto the view basis
    /// texel by texel ([`add_view_projection`]).
    pub fn add_to_shrm(&self, shrm: &mut Shrm, model: &Model, progress: &dyn Progress) {
        if !self.in_angle() {
            return;
        }
        if self.path(model) == Path::View {
            return add_view_projection(shrm, model, &self.sources, progress);
        }
        let Some(layer) = self.add_to_map(model, Lobe::Radial, (shrm.width(), shrm.height())) else { return };
        let s = (4.0 * PI).sqrt() as f32;
        for (o, b) in shrm.layers[0].pixels.iter_mut().zip(&layer.pixels) {
            for c in 0..3 {
                o[c] += s * b[c];
            }
        }
    }

    /// Adds the bright texels' excess to `frame`, the lighting on `grid` in the frame `to_frame`
    /// takes world directions to, as energy. Each texel of the grid they were split on is cut
    /// into k × k parts of equal solid angle (uniform in φ and in z), k keeping two parts per
    /// texel of `grid`; each part, rotated into the frame, is spread over the four texel centres
    /// around it with bilinear weights. That keeps both its energy and its centre, so moving it
    /// onto the grid errs only at second order in the grid's spacing against the lobe's width; a
    /// point lookup (as the smooth remainder is rotated) would catch a sun smaller than its
    /// sample spacing by chance.
    pub fn splat(&self, frame: &mut RgbImage, grid: LatLong, to_frame: DQuat) {
        let Some(source) = self.grid else { return };
        let k = (2 * grid.height).div_ceil(source.height).max(1);
        let parts = (k * k) as f64;
        let row_solid_angle: Vec<f64> = (0..grid.height).map(|y| grid.row_solid_angle(y)).collect();
        for t in &self.sources.texels {
            let (x, y) = source.texel_of(t.dir);
            let (z0, z1) =
                ((PI * y as f64 / source.height as f64).cos(), (PI * (y + 1) as f64 / source.height as f64).cos());
            for j in 0..k {
                let z = z0 + (z1 - z0) * (j as f64 + 0.5) / k as f64;
                let s = (1.0 - z * z).max(0.0).sqrt();
                for i in 0..k {
                    let phi = TAU * (x as f64 + (i as f64 + 0.5) / k as f64) / source.width as f64;
                    let d = to_frame * DVec3::new(s * phi.cos(), s * phi.sin(), z);
                    let (px, py) = grid.position(d);
                    for (texel, w) in bilinear_taps(grid.width, grid.height, px - 0.5, py - 0.5, true) {
                        let per_area = w * t.solid_angle / parts / row_solid_angle[texel / grid.width];
                        let p = &mut frame.pixels[texel];
                        for c in 0..3 {
                            p[c] += (t.excess[c] * per_area) as f32;
                        }
                    }
                }
            }
        }
    }
}

/// The truncation of a radially symmetric lobe that leaves out [`ANGULAR_EPSILON`] (green).
fn lobe_truncation(model: &Model) -> super::truncation::Truncation {
    radial_truncation(|x| model.lobe(x)[1], ANGULAR_EPSILON)
}

/// Adds the bright texels' exact contribution Σ_j e_j ΔΩ_j ρ̂(ω_j; R, V) to every texel of a
/// lat-long map of R (of N for Lambert). On a map as wide as the `source` grid the texels were
/// split on, a radially symmetric lobe takes the zonal filter of their excess ([`add_zonal`]:
/// FFT rows, whose cost does not grow with the number of bright texels); otherwise
/// [`add_texel_sums`].
fn add_to_map(map: &mut RgbImage, model: &Model, bright: &BrightSources, source: Option<LatLong>, lobe: Lobe<'_>) {
    if bright.is_empty() {
        return;
    }
    let radial_star = match lobe {
        Lobe::Radial => radial_cutoff(|x| model.lobe(x)[1], ANGULAR_EPSILON),
        Lobe::View(_, cutoff) => cutoff.max(),
    };
    if let (Lobe::Radial, Some(source)) = (lobe, source) {
        if source.width == map.width && add_zonal(map, model, bright, source, radial_star) {
            return;
        }
    }
    add_texel_sums(map, model, bright, lobe, radial_star);
}

/// [`add_to_map`] texel by texel: a texel visits only the bright texels within its lobe's cone
/// (1 − [`ANGULAR_EPSILON`] of the lobe; for view-dependent BRDFs per view angle, from the
/// cutoff table, whose widest cone is `widest`): the bright texels are sorted by θ, and a row of
/// texels at θ_R takes the range θ_R ± θ*.
fn add_texel_sums(map: &mut RgbImage, model: &Model, bright: &BrightSources, lobe: Lobe<'_>, widest: f64) {
    let view = match lobe {
        Lobe::View(v, cutoff) => Some((v, cutoff)),
        Lobe::Radial => None,
    };
    let (w, h) = (map.width, map.height);
    let grid = LatLong::new(w, h);
    let mut sorted: Vec<(f64, usize)> =
        bright.texels.iter().enumerate().map(|(i, t)| (crate::sphere::theta(t.dir), i)).collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    map.pixels.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let theta_r = grid.row_theta(y);
        let lo = sorted.partition_point(|t| t.0 < theta_r - widest);
        let hi = sorted.partition_point(|t| t.0 <= theta_r + widest);
        if lo == hi {
            return;
        }
        for (x, px) in row.iter_mut().enumerate() {
            let r = grid.texel_direction(x, y);
            let (prepared, cos_star) = match view {
                None => (None, widest.cos()),
                Some((v, cutoff)) => match model.prepare_view(r, v) {
                    Some(p) => (Some(p), cutoff.at(r.dot(v).clamp(-1.0, 1.0).acos()).cos()),
                    None => continue,
                },
            };
            let mut acc = [0.0f64; 3];
            for &(_, i) in &sorted[lo..hi] {
                let t = &bright.texels[i];
                let c = r.dot(t.dir);
                if c < cos_star {
                    continue;
                }
                let rho = match &prepared {
                    Some(p) => model.rho_hat_prepared(p, t.dir),
                    None => model.lobe(c),
                };
                for k in 0..3 {
                    acc[k] += rho[k] * t.excess[k] * t.solid_angle;
                }
            }
            for k in 0..3 {
                px[k] += acc[k] as f32;
            }
        }
    });
}

/// The bright texels' reflected radiance for a radially symmetric lobe as spherical harmonics.
/// The excess, constant e_j over each bright texel t_j of the `source` grid, has coefficients
/// E_lm = Σ_j e_j ∫_{t_j} Y_lm dω, and its reflection map is Σ_l k_l Σ_m E_lm Y_lm(R)
/// (Funk–Hecke): these are k_l E_lm. The texel integrals are exact in φ (∫ cos or sin mφ over a
/// column is the centre's value × Δφ · sinc(mΔφ/2)) and take [`BRIGHT_Z_NODES`] Gauss–Legendre
/// nodes in z, so a lobe a few texels wide sees the texels' extent, as the zonal filter's texel
/// rule does. By the addition theorem |Σ_m Y_lm(ω) Y_lm(R)| ≤ (2l + 1)/4π, so cutting at band F
/// changes a texel by at most Σ_j e_j ΔΩ_j · Σ_{l > F} |k_l| (2l + 1)/4π: F is the smallest band
/// that keeps the second factor under u(cos θ*), what the cone of the angular passes may drop per
/// unit of energy. They are synthesized with the remainder's coefficients in one pass rather than
/// a synthesis of their own clamped at zero: the clamp moved no texel by more than that bound.
/// `None` when the kernel has not died out by its last band (k_l is known no further), or for
/// an output `width` too narrow for band F.
fn harmonics(
    model: &Model,
    bright: &BrightSources,
    source: LatLong,
    kernel: &[[f64; 3]],
    width: usize,
) -> Option<ShCoeffs> {
    if kernel.is_empty() {
        return None;
    }
    let dropped = model.lobe(lobe_truncation(model).theta_star.cos())[1];
    let per_band: Vec<f64> = kernel
        .iter()
        .enumerate()
        .map(|(l, k)| k.iter().fold(0.0f64, |m, v| m.max(v.abs())) * (2 * l + 1) as f64 / (4.0 * PI))
        .collect();
    // Bands beyond the kernel's last are taken as nothing: only when that band itself is
    // under a thousandth of the allowance.
    if per_band[per_band.len() - 1] > 1e-3 * dropped {
        return None;
    }
    let mut order = per_band.len() - 1;
    let mut tail = 0.0;
    while order > 0 && tail + per_band[order] <= dropped {
        tail += per_band[order];
        order -= 1;
    }
    if 2 * order > width.min(source.width) {
        return None;
    }
    let quadrature = TexelQuadrature::Integral { z_nodes: BRIGHT_Z_NODES };
    let texels = bright.on_latlong(source);
    let coeffs = project_latlong_texels((source.width, source.height), &texels, order, quadrature).ok()?;
    Some(convolve_zonal_rgb(&coeffs, |l| kernel[l]))
}

/// [`add_to_map`] for a radially symmetric lobe on a map as wide as the `source` grid the
/// texels were split on: the zonal filter of their excess, truncated at `cone`. The texel rule
/// integrates a lobe narrow against the texels over their extent (a sun's few texels under Phong
/// s = 512), chosen by measurement as the references do. False, leaving `map` alone, beyond the
/// filter's size bound.
fn add_zonal(map: &mut RgbImage, model: &Model, bright: &BrightSources, source: LatLong, cone: f64) -> bool {
    let mut excess = RgbImage::new(source.width, source.height);
    bright.add_to_latlong(&mut excess);
    let kernel = |x: f64| model.lobe(x)[1];
    let rule = rule_for_kernel(source.width, source.height, &kernel, cone, map.height, RULE_TOLERANCE).rule;
    let Ok(filtered) = zonal_filter(&excess, kernel, cone, &rule, map.height, Rows::Lit, &NoProgress) else {
        return false;
    };
    for (px, f) in map.pixels.iter_mut().zip(&filtered.pixels) {
        for c in 0..3 {
            px[c] += f[c] as f32;
        }
    }
    true
}

/// Adds the bright texels to a local SHRM of a view-dependent BRDF: per texel R,
/// B_pq(R) += Σ_j e_j ΔΩ_j T_pq(R⁻¹ω_j) with T_pq(ω_i) = ∫ ρ̂(ω_i, ω_o) Y_pq(ω_o) dω_o, the
/// BRDF's view-basis projection (isotropy: T_p|q| depends on θ_i only, times cos/sin qφ_i).
fn add_view_projection(shrm: &mut Shrm, model: &Model, bright: &BrightSources, progress: &dyn Progress) {
    let table = ViewProjection::new(model, shrm.p_b);
    let (w, h, n) = (shrm.width(), shrm.height(), crate::sh::count(shrm.p_b));
    let energy: Vec<[f64; 3]> = bright.texels.iter().map(|b| b.excess.map(|e| e * b.solid_angle)).collect();
    progress.start("bright", h as u64);
    let rows: Vec<Vec<[f32; 3]>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut out = vec![[0.0f32; 3]; n * w];
            let mut t = vec![0.0; n];
            // Per channel, one accumulator per layer: contiguous, so the sums vectorize.
            let mut acc = [vec![0.0f64; n], vec![0.0f64; n], vec![0.0f64; n]];
            for x in 0..w {
                let to_local = texel_frame(w, h, x, y).transpose();
                acc.iter_mut().for_each(|a| a.fill(0.0));
                for (b, e) in bright.texels.iter().zip(&energy) {
                    let local = to_local * b.dir;
                    if local.z < table.cull_cos {
                        continue;
                    }
                    table.eval(local, &mut t);
                    for (a, e) in acc.iter_mut().zip(e) {
                        for (a, tv) in a.iter_mut().zip(&t) {
                            *a += tv * e;
                        }
                    }
                }
                for i in 0..n {
                    out[i * w + x] = [acc[0][i] as f32, acc[1][i] as f32, acc[2][i] as f32];
                }
            }
            progress.advance(1);
            out
        })
        .collect();
    progress.finish();
    for (y, row) in rows.iter().enumerate() {
        for (i, layer) in shrm.layers.iter_mut().enumerate() {
            for x in 0..w {
                let px = &mut layer.pixels[y * w + x];
                for c in 0..3 {
                    px[c] += row[i * w + x][c];
                }
            }
        }
    }
}

/// T_p|q|(θ_i) = ∫ ρ̂(θ_i, φ_i = 0; ω_o) Y_p|q|(ω_o) dω_o tabulated in cos θ_i; the full
/// T_pq(θ_i, φ_i) is T_p|q|(θ_i) cos(qφ_i) for q ≥ 0 and T_p|q|(θ_i) sin(|q|φ_i) for q < 0
/// (rotating ω_i about R by φ_i rotates the view basis: real SH of order q pick up cos/sin qφ).
struct ViewProjection {
    p: usize,
    bins: usize,
    /// T_p|q| at [bin · (P+1)² + p(p+1)+q] for every q (±q alike, so a bin is read as one
    /// contiguous row), bins uniform in cos θ_i ∈ [min_cos, 1].
    values: Vec<f64>,
    min_cos: f64,
    /// Bright texels below this cos θ_i are skipped: the table's largest entry per bin, summed
    /// over the bins below it, is at most [`ANGULAR_EPSILON`] of its sum over all bins (the
    /// share of the lobe the angular passes' cones leave out). Torrance-Sparrow σ = 0.25 falls
    /// from 10⁻⁵ of its peak at cos θ_i = 0 to 10⁻¹³ at −0.8, so about half the sphere is skipped.
    cull_cos: f64,
}

impl ViewProjection {
    fn new(model: &Model, p: usize) -> Self {
        let bins = VIEW_PROJECTION_BINS;
        let min_cos = -1.0;
        let nodes = crate::quadrature::gauss_legendre_cached(VIEW_PROJECTION_NODES);
        let nphi = VIEW_PROJECTION_NODES;
        let table = crate::sh::legendre::LegendreTable::new(p);
        let values: Vec<f64> = (0..bins)
            .into_par_iter()
            .map(|b| {
                let ci = min_cos + (1.0 - min_cos) * b as f64 / (bins - 1) as f64;
                let wi = DVec3::new((1.0 - ci * ci).max(0.0).sqrt(), 0.0, ci);
                let mut out = vec![0.0; crate::sh::count(p)];
                let mut ylm = vec![0.0; crate::sh::count(p)];
                let even = |out: Vec<f64>| -> Vec<f64> {
                    (0..crate::sh::count(p))
                        .map(|i| {
                            let (pp, q) = crate::sh::lm(i);
                            out[crate::sh::index(pp, q.abs())]
                        })
                        .collect()
                };
                for &(co, wgt) in nodes.iter() {
                    let so = (1.0 - co * co).max(0.0).sqrt();
                    for k in 0..nphi {
                        let phi = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
                        let wo = DVec3::new(so * phi.cos(), so * phi.sin(), co);
                        let rho = model.rho_hat(wi, wo)[1];
                        if rho == 0.0 {
                            continue;
                        }
                        crate::sh::basis::eval_basis_dir(&table, wo, &mut ylm);
                        let d = wgt * 2.0 * PI / nphi as f64 * rho;
                        for (o, y) in out.iter_mut().zip(&ylm) {
                            *o += d * y;
                        }
                    }
                }
                even(out)
            })
            .flatten()
            .collect();
        let n = crate::sh::count(p);
        let largest: Vec<f64> = values.chunks(n).map(|row| row.iter().fold(0.0, |a: f64, v| a.max(v.abs()))).collect();
        let total: f64 = largest.iter().sum();
        let mut below = 0.0;
        let skipped = largest.iter().take_while(|&&m| {
            below += m;
            below <= ANGULAR_EPSILON * total
        });
        // A pair between the last negligible bin and the next reads both: the cut is at the
        // last negligible one.
        let first = skipped.count().saturating_sub(1);
        let cull_cos = min_cos + (1.0 - min_cos) * first as f64 / (bins - 1) as f64;
        ViewProjection { p, bins, values, min_cos, cull_cos }
    }

    /// T_pq at local direction `l` into `out` (index p(p+1)+q), linear in cos θ_i. cos qφ and
    /// sin qφ come from cos φ and sin φ by the angle-addition recurrence, not from 2P
    /// trigonometric calls: this runs once per (SHRM texel, bright texel) pair, and with the
    /// calls it was most of an SHRM file's time (sky 512×256 with 1 263 bright texels, σ = 0.25,
    /// `--size 256x128`: 14.9 s with them, 4.8 s without, the same file to the bit).
    fn eval(&self, l: DVec3, out: &mut [f64]) {
        let f =
            ((l.z - self.min_cos) / (1.0 - self.min_cos) * (self.bins - 1) as f64).clamp(0.0, (self.bins - 1) as f64);
        let (b0, t) = (f.floor() as usize, f - f.floor());
        let b1 = (b0 + 1).min(self.bins - 1);
        // The azimuthal factor of each index first; φ = 0 on the poles, as `sphere::phi` has it.
        let r = (l.x * l.x + l.y * l.y).sqrt();
        let (cos_phi, sin_phi) = if r > 0.0 { (l.x / r, l.y / r) } else { (1.0, 0.0) };
        let (mut cos_q, mut sin_q) = (1.0, 0.0);
        for q in 0..=self.p {
            for pp in q..=self.p {
                out[crate::sh::index(pp, q as isize)] = cos_q;
                if q > 0 {
                    out[crate::sh::index(pp, -(q as isize))] = sin_q;
                }
            }
            (cos_q, sin_q) = (cos_q * cos_phi - sin_q * sin_phi, sin_q * cos_phi + cos_q * sin_phi);
        }
        let n = out.len();
        let (row0, row1) = (&self.values[b0 * n..(b0 + 1) * n], &self.values[b1 * n..(b1 + 1) * n]);
        for ((o, v0), v1) in out.iter_mut().zip(row0).zip(row1) {
            *o *= (1.0 - t) * v0 + t * v1;
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::prefilter::angular::ConePyramid;
    use crate::prefilter::view_axis;

    /// T_pq(ω_i) = ∫ ρ̂(ω_i; R = +Z, ω_o) Y_pq(ω_o) dω_o against a brute-force midpoint sum over
    /// ω_o, and the directions the bright pass skips (cos θ_i below the cut) hold next to nothing.
    #[test]
    fn the_view_projection_is_the_lobe_projected_on_the_view_basis_and_skips_only_a_negligible_part() {
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.3").unwrap(), true).unwrap();
        let p = 3;
        let n = crate::sh::count(p);
        let table = ViewProjection::new(&model, p);
        let basis = crate::sh::legendre::LegendreTable::new(p);
        let brute = |wi: DVec3| {
            let (rows, cols) = (300, 600);
            let (mut sum, mut y) = (vec![0.0; n], vec![0.0; n]);
            for a in 0..rows {
                let z = 1.0 - 2.0 * (a as f64 + 0.5) / rows as f64;
                let s = (1.0 - z * z).sqrt();
                for b in 0..cols {
                    let phi = 2.0 * PI * (b as f64 + 0.5) / cols as f64;
                    let wo = DVec3::new(s * phi.cos(), s * phi.sin(), z);
                    let rho = model.rho_hat(wi, wo)[1];
                    crate::sh::basis::eval_basis_dir(&basis, wo, &mut y);
                    for (o, v) in sum.iter_mut().zip(&y) {
                        *o += rho * v * 4.0 * PI / (rows * cols) as f64;
                    }
                }
            }
            sum
        };
        let peak = brute(DVec3::Z).iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut got = vec![0.0; n];
        for (cos_i, phi) in [(0.95f64, 0.4f64), (0.6, 2.5), (0.1, -1.2)] {
            let s = (1.0 - cos_i * cos_i).sqrt();
            let wi = DVec3::new(s * phi.cos(), s * phi.sin(), cos_i);
            table.eval(wi, &mut got);
            for (i, (g, w)) in got.iter().zip(brute(wi)).enumerate() {
                assert!((g - w).abs() <= 2e-3 * peak, "cos θ_i {cos_i}, index {i}: {g} against {w} (peak {peak})");
            }
        }
        assert!(table.cull_cos > -1.0 && table.cull_cos < 0.5, "cut at {}", table.cull_cos);
        let below = table.cull_cos - 0.05;
        let wi = DVec3::new((1.0 - below * below).sqrt(), 0.0, below);
        let skipped = brute(wi).iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(skipped <= 1e-4 * peak, "skipped {skipped} against peak {peak}");
    }

    /// The view projection's azimuthal factors by recurrence are cos qφ and sin |q|φ of the
    /// direction's own φ: against the trigonometric calls, on either side of φ = π and at a
    /// pole (φ = 0 there).
    #[test]
    fn the_view_projection_turns_with_the_azimuth() {
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.3").unwrap(), true).unwrap();
        let p = 5;
        let table = ViewProjection::new(&model, p);
        let mut got = vec![0.0; crate::sh::count(p)];
        let mut flat = vec![0.0; crate::sh::count(p)];
        for l in [DVec3::new(0.3, 0.4, 0.6), DVec3::new(-0.7, 0.1, -0.2), DVec3::new(-0.5, -0.6, 0.1), DVec3::Z] {
            let l = l.normalize();
            table.eval(l, &mut got);
            // φ = 0 gives the table's own values, T_p|q|(θ_i) for q ≥ 0.
            let r = l.x.hypot(l.y);
            table.eval(DVec3::new(r, 0.0, l.z), &mut flat);
            let phi = crate::sphere::phi(l);
            for pp in 0..=p {
                for q in -(pp as isize)..=(pp as isize) {
                    let base = flat[crate::sh::index(pp, q.abs())];
                    let a = q.unsigned_abs() as f64 * phi;
                    let want = if q >= 0 { base * a.cos() } else { base * a.sin() };
                    let g = got[crate::sh::index(pp, q)];
                    assert!((g - want).abs() <= 1e-12 * (1.0 + base.abs()), "{l}: ({pp}, {q}) {g} against {want}");
                }
            }
        }
    }

    /// A dim sky with a small sun on coarse texels (5.6°), 64×32.
    pub(in crate::prefilter) fn sunlit_sky() -> RgbImage {
        let grid = LatLong::new(64, 32);
        let sun = DVec3::new(0.6, 0.2, 0.5).normalize();
        RgbImage::from_fn(64, 32, |x, y| {
            let d = grid.texel_direction(x, y);
            let v = if d.dot(sun) > 0.995 { 5000.0 } else { 1.0 + 0.5 * d.z as f32 };
            [v, 0.5 * v, 0.25 * v]
        })
    }

    /// [`sunlit_sky`]'s grid and bright texels.
    fn sky_with_sun() -> (LatLong, BrightSources) {
        let grid = LatLong::new(64, 32);
        let (_, bright) = split(&EnvMap::latlong(sunlit_sky()).unwrap(), BrightRule::Auto);
        assert!(!bright.is_empty() && bright.texels.len() < 20, "{} bright texels", bright.texels.len());
        (grid, bright)
    }

    /// Every bright texel's integral of the lobe by a 32 × 32 midpoint rule in (z, φ), summed
    /// per texel of `grid` over the bright texels whose centres are within θ* (π: all).
    fn brute_force(grid: LatLong, model: &Model, bright: &BrightSources, theta_star: f64) -> Vec<[f64; 3]> {
        brute_force_lobe(grid, bright, theta_star, |r, w| model.lobe(r.dot(w))[1])
    }

    /// [`brute_force`] for any lobe `rho(R, ω)` (green channel).
    fn brute_force_lobe(
        grid: LatLong,
        bright: &BrightSources,
        theta_star: f64,
        rho: impl Fn(DVec3, DVec3) -> f64,
    ) -> Vec<[f64; 3]> {
        let (w, h, n) = (grid.width, grid.height, 32);
        let cos_star = theta_star.cos();
        (0..w * h)
            .map(|i| {
                let r = grid.texel_direction(i % w, i / w);
                let mut acc = [0.0; 3];
                for t in bright.texels.iter().filter(|t| theta_star >= PI || r.dot(t.dir) >= cos_star) {
                    let (px, py) = grid.position(t.dir);
                    let (x, y) = (px.floor(), py.floor());
                    let (z0, z1) = ((PI * y / h as f64).cos(), (PI * (y + 1.0) / h as f64).cos());
                    let mut integral = 0.0;
                    for j in 0..n {
                        for k in 0..n {
                            let z = z0 + (z1 - z0) * (j as f64 + 0.5) / n as f64;
                            let phi = 2.0 * PI * (x + (k as f64 + 0.5) / n as f64) / w as f64;
                            let weight = (z0 - z1) / n as f64 * 2.0 * PI / w as f64 / n as f64;
                            integral += weight * rho(r, crate::sphere::direction(z.acos(), phi));
                        }
                    }
                    // The texel's excess radiance: t.excess·ΔΩ_t is its energy.
                    let scale = t.solid_angle / grid.row_solid_angle(y as usize);
                    for c in 0..3 {
                        acc[c] += t.excess[c] * scale * integral;
                    }
                }
                acc
            })
            .collect()
    }

    /// Within `relative` of `expected` plus `absolute` (per channel).
    fn assert_close(spec: &str, got: &RgbImage, expected: &[[f64; 3]], relative: f64, absolute: [f64; 3]) {
        assert!(expected.iter().any(|p| p[0] > 0.0));
        for (i, (a, b)) in got.pixels.iter().zip(expected).enumerate() {
            for c in 0..3 {
                let a = a[c] as f64;
                assert!(
                    (a - b[c]).abs() <= relative * b[c].abs() + absolute[c],
                    "{spec}, texel {i} channel {c}: {a} against {}",
                    b[c]
                );
            }
        }
    }

    #[test]
    fn bright_texels_through_the_zonal_filter_are_their_texel_integrals() {
        // The zonal path's excess, filtered with a measured texel rule, against the brute-force
        // texel integrals in the same cone (an empty kernel keeps the harmonics out).
        let (grid, bright) = sky_with_sun();
        for spec in ["phong:s=8", "phong:s=128"] {
            let model = Model::new(Brdf::parse(spec).unwrap(), true).unwrap();
            let mut zonal = RgbImage::new(64, 32);
            add_to_map(&mut zonal, &model, &bright, Some(grid), Lobe::Radial);
            let theta_star = radial_cutoff(|x| model.lobe(x)[1], ANGULAR_EPSILON);
            let expected = brute_force(grid, &model, &bright, theta_star);
            let peak = expected.iter().map(|p| p[0]).fold(0.0, f64::max);
            assert_close(spec, &zonal, &expected, 3e-3, [1e-5 * peak; 3]);
        }
    }

    #[test]
    fn bright_texels_through_harmonics_are_their_texel_integrals() {
        // Lobes 8.5 and 4.3 texels wide (√(2π/(s+1)) against 5.6° texels): the harmonics take
        // the first and leave the second to the zonal filter. Against the whole lobe's texel
        // integrals (no cone): the cut at band F may differ from them by its bound, what the
        // cone may drop per unit of bright energy times that energy.
        let (grid, bright) = sky_with_sun();
        for (spec, wide) in [("phong:s=8", true), ("phong:s=32", false)] {
            let model = Model::new(Brdf::parse(spec).unwrap(), true).unwrap();
            let coefficients = model.coefficients(31, 0);
            let kernel: Vec<[f64; 3]> = (0..=31).map(|l| coefficients.radial_kernel(l)).collect();
            let theta_star = radial_cutoff(|x| model.lobe(x)[1], ANGULAR_EPSILON);
            let dropped = model.lobe(theta_star.cos())[1];
            let mut pass = BrightPass { sources: bright.clone(), grid: Some(grid), harmonics: None };
            pass.through_harmonics(&model, &kernel, 64);
            assert_eq!(pass.harmonics().is_some(), wide, "{spec}");
            if let Some(coeffs) = pass.harmonics() {
                let map = crate::sh::synth::synthesize_latlong(coeffs, 64, 32).unwrap();
                let energy = [0, 1, 2].map(|c| bright.texels.iter().map(|t| t.excess[c] * t.solid_angle).sum::<f64>());
                let bound = energy.map(|e| dropped * e);
                // The cut series may dip below zero by no more than its bound.
                for p in &map.pixels {
                    for c in 0..3 {
                        assert!(p[c] as f64 >= -bound[c], "{spec}: {} below −{}", p[c], bound[c]);
                    }
                }
                assert_close(spec, &map, &brute_force(grid, &model, &bright, PI), 1e-3, bound);
                // Cut before the kernel has died out, the path declines: k_l is not known further.
                assert!(harmonics(&model, &bright, grid, &kernel[..8], 64).is_none());
            }
        }
    }

    #[test]
    fn bright_texels_splatted_in_the_view_frame_are_their_texel_integrals() {
        // Only the sun (a black remainder): the view-frame integral of its splatted energy
        // against each bright texel's brute-force integral of the view-dependent lobe, for a
        // view at the pole and a tilted one (rotated into the frame).
        let (grid, bright) = sky_with_sun();
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.3").unwrap(), true).unwrap();
        let black = EnvMap::latlong(RgbImage::new(grid.width, grid.height)).unwrap();
        let pyramid = ConePyramid::new(&black).unwrap();
        let cutoff = CutoffTable::of_model(&model, ANGULAR_EPSILON, 65);
        let pass = BrightPass { sources: bright.clone(), grid: Some(grid), harmonics: None };
        for view in [DVec3::Z, DVec3::new(0.3, -0.5, 0.8).normalize()] {
            let got = view_axis::integrate_in_view_frame(&pyramid, &model, &cutoff, view, 0.0, grid, Some(&pass));
            assert_eq!(got.len(), grid.width * grid.height);
            let expected = brute_force_lobe(grid, &bright, PI, |r, w| {
                model.prepare_view(r, view).map_or(0.0, |p| model.rho_hat_prepared(&p, w)[1])
            });
            let peak = expected.iter().map(|p| p[1]).fold(0.0, f64::max);
            let mut worst = 0.0f64;
            for &(i, v) in &got {
                let (a, b) = (v[1] as f64, expected[i][1]);
                if b > 0.05 * peak {
                    worst = worst.max((a - b).abs() / b);
                }
            }
            assert!(worst < 0.05, "view {view}: worst relative error {worst} over texels ≥ 5 % of the peak");
        }
    }
}
