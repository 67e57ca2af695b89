//! The angular-domain reference (R&H 2002 §6.2, App. D): direct integration of the environment
//! against the BRDF for every output texel, with the lobe truncated where it holds less than ε of
//! its weight.
//!
//! **What is computed.** The environment is a lat-long map, constant over each texel t. For a
//! reflection vector R (and a view, for 3-D BRDFs) the reference keeps the texels whose centre
//! c_t lies within the cone of half-angle θ* around R and integrates ρ̂ over each one's extent:
//!
//!   B(R) = Σ_{t : R·c_t ≥ cos θ*} L_t ∫_t ρ̂(ω) dω,
//!
//! the texel integrals by the n × n Gauss–Legendre rule of [`TexelRule`]. Nothing else is
//! approximated: the result is exact for the piecewise-constant map up to the truncation (App. D)
//! and the texel rule, whose n is chosen by measurement so that it misplaces at most ε/10 of the
//! lobe's weight ([`super::truncation::reference_rule`], [`ConeIntegrator::rule_for_view`]). So a narrow lobe over
//! coarse texels (Phong s = 512 on a 256 × 128 map) is integrated over their extent instead of
//! being sampled at their centres, which would be wrong by several per cent.
//!
//! **θ*.** The cone holds 1 − ε of ∫ ρ̂ dω_i (App. D: cos θ* = ε^{1/(s+1)} for Phong); for 3-D
//! BRDFs it is tabulated against the view angle θ_o ([`CutoffTable`], `super::truncation`).
//!
//! **Two paths.** A radially symmetric lobe on an output grid as wide as the input is a zonal
//! filter: each (output row, source row) pair is a circular convolution in φ, done by FFT
//! ([`crate::envmap::zonal`]). Everything else is the cone sum of [`ConeIntegrator`]: per output
//! row and source row the admissible φ window of texel centres is solved in closed form (cached
//! per distinct θ*), per texel the centre is tested exactly, and the n² sub-sample directions come
//! from tables (no trigonometry per texel). Both paths compute the same sum, and both are held to
//! the direct sum over every texel ([`ConeIntegrator::integrate_reference`],
//! [`crate::envmap::zonal::zonal_filter_reference`]) by the tests.
//!
//! **Determinism.** Output rows run in parallel; each texel is one sequential sum in a fixed
//! order (source rows, columns, sub-samples), so the result is the same for any thread count.

use super::model::Model;
use super::truncation::CutoffTable;
use super::tuning::TEXELS_PER_CONE;
use crate::envmap::zonal::{self, choose_rule, Rows, RuleChoice, SubRow, TexelRule, ZonalError};
use crate::envmap::{self, EnvMap, Layout};
use crate::io::RgbImage;
use crate::progress::Progress;
use crate::sphere::{self, LatLong};
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};
use std::sync::Arc;

/// Errors of the angular reference.
#[derive(Debug, thiserror::Error)]
pub enum AngularError {
    /// The environment is not lat-long.
    #[error("the angular reference integrates lat-long environments; this one is {0} (resample it to lat-long first)")]
    NotLatLong(&'static str),
    /// The zonal filter refused the request.
    #[error(transparent)]
    Zonal(#[from] ZonalError),
    /// A grid made for the integral does not fit its layout.
    #[error(transparent)]
    Geometry(#[from] crate::envmap::EnvMapError),
}

/// The map a [`ConeIntegrator`] reads, shared between rules.
struct Source {
    grid: LatLong,
    image: RgbImage,
    radiance: Vec<[f64; 3]>,
    /// Unit centre direction of every texel, row-major.
    centres: Vec<DVec3>,
}

/// A lat-long environment prepared for cone sums with one texel rule.
#[derive(Clone)]
pub struct ConeIntegrator {
    source: Arc<Source>,
    rule: TexelRule,
    /// n sub-rows per source row.
    sub_rows: Vec<SubRow>,
    /// cos φ and sin φ of the n sub-columns of every column, column-major in blocks of n.
    cos_phi: Vec<f64>,
    sin_phi: Vec<f64>,
    /// Weights in φ of the n sub-columns.
    phi_weights: Vec<f64>,
    /// For the one-node rule, the node direction of every texel (row-major); else empty.
    single_nodes: Vec<DVec3>,
}

/// The texel centres of one source row within θ* of an output row's reflection vectors: |Δφ| of
/// the centres at most `half` (π: the whole row).
#[derive(Clone, Copy, Debug)]
struct Window {
    y: usize,
    half: f64,
}

impl ConeIntegrator {
    /// Prepares a lat-long environment with the midpoint rule (one node per texel).
    pub fn new(env: &EnvMap) -> Result<Self, AngularError> {
        if env.layout() != Layout::LatLong {
            return Err(AngularError::NotLatLong(env.layout().name()));
        }
        let image = env.image().clone();
        let grid = LatLong::new(image.width, image.height);
        let radiance = image.pixels.iter().map(|p| [p[0] as f64, p[1] as f64, p[2] as f64]).collect();
        let centres = (0..grid.height).flat_map(|y| (0..grid.width).map(move |x| grid.texel_direction(x, y))).collect();
        let source = Arc::new(Source { grid, image, radiance, centres });
        Ok(Self::tabulate(source, TexelRule::midpoint()))
    }

    fn tabulate(source: Arc<Source>, rule: TexelRule) -> Self {
        let grid = source.grid;
        let columns = rule.sub_columns(grid);
        let h = TAU / grid.width as f64;
        let (mut cos_phi, mut sin_phi) = (Vec::new(), Vec::new());
        for x in 0..grid.width {
            for &(offset, _) in &columns {
                let (s, c) = ((x as f64 + 0.5 + offset) * h).sin_cos();
                cos_phi.push(c);
                sin_phi.push(s);
            }
        }
        let sub_rows: Vec<SubRow> = (0..grid.height).flat_map(|y| rule.sub_rows(grid, y)).collect();
        let single_nodes = if rule.subsamples() == 1 {
            let row_node = |y: usize| (sub_rows[y].sin_theta, sub_rows[y].z);
            (0..grid.height)
                .flat_map(|y| (0..grid.width).map(move |x| (x, y)))
                .map(|(x, y)| DVec3::new(row_node(y).0 * cos_phi[x], row_node(y).0 * sin_phi[x], row_node(y).1))
                .collect()
        } else {
            Vec::new()
        };
        ConeIntegrator {
            single_nodes,
            sub_rows,
            phi_weights: columns.iter().map(|c| c.1).collect(),
            cos_phi,
            sin_phi,
            rule,
            source,
        }
    }

    /// The same environment with another texel rule.
    pub fn with_rule(&self, rule: TexelRule) -> Self {
        Self::tabulate(self.source.clone(), rule)
    }

    /// The environment's lat-long grid.
    pub fn grid(&self) -> LatLong {
        self.source.grid
    }

    /// The source rows whose texel centres can lie within θ* of a reflection vector at polar
    /// angle θ_R, with their φ windows (closed form of cos θ_c cos θ_R + sin θ_c sin θ_R cos Δφ
    /// ≥ cos θ*).
    fn windows(&self, theta_r: f64, theta_star: f64) -> Vec<Window> {
        let grid = self.source.grid;
        let cos_star = theta_star.min(PI).cos();
        let (st_r, ct_r) = theta_r.sin_cos();
        (0..grid.height)
            .filter_map(|y| {
                let theta = grid.row_theta(y);
                if (theta - theta_r).abs() > theta_star {
                    return None;
                }
                let (st, ct) = theta.sin_cos();
                let denom = st * st_r;
                let c = if denom > 1e-300 { (cos_star - ct * ct_r) / denom } else { -2.0 };
                // c ≤ −1: every centre of the row; c slightly above 1 by rounding: the nearest.
                let half = if c <= -1.0 { PI } else { c.min(1.0).acos() };
                Some(Window { y, half })
            })
            .collect()
    }

    /// Calls `visit(x, y)` for every texel of the windows whose centre is within θ* of `r`, in
    /// a fixed order (windows, then columns).
    fn for_each_in_cone(&self, r: DVec3, windows: &[Window], theta_star: f64, mut visit: impl FnMut(usize, usize)) {
        let src = &*self.source;
        let w = src.grid.width;
        let cos_star = if theta_star >= PI { f64::NEG_INFINITY } else { theta_star.cos() };
        let h = TAU / w as f64;
        let phi_r = sphere::phi(r);
        let mut test = |x: usize, y: usize| {
            if r.dot(src.centres[y * w + x]) >= cos_star {
                visit(x, y);
            }
        };
        for win in windows {
            // Columns whose centres (x + ½)h lie within `half` of φ_R, one more each side for
            // rounding (the centre test decides).
            let lo = ((phi_r - win.half) / h - 0.5).ceil() as i64 - 1;
            let hi = ((phi_r + win.half) / h - 0.5).floor() as i64 + 1;
            if win.half >= PI || hi - lo + 1 >= w as i64 {
                (0..w).for_each(|x| test(x, win.y));
            } else {
                (lo..=hi).for_each(|x| test(x.rem_euclid(w as i64) as usize, win.y));
            }
        }
    }

    /// ∫_t f dω over texel (x, y) by the rule: Σ_kj w_k w_j f(ω_kj), directions from the tables.
    #[inline]
    fn texel_integral(&self, x: usize, y: usize, mut f: impl FnMut(DVec3) -> [f64; 3]) -> [f64; 3] {
        let n = self.phi_weights.len();
        let (cos_phi, sin_phi) = (&self.cos_phi[x * n..(x + 1) * n], &self.sin_phi[x * n..(x + 1) * n]);
        let mut texel = [0.0; 3];
        for row in &self.sub_rows[y * n..(y + 1) * n] {
            for j in 0..n {
                let v = f(DVec3::new(row.sin_theta * cos_phi[j], row.sin_theta * sin_phi[j], row.z));
                let wt = row.weight * self.phi_weights[j];
                for k in 0..3 {
                    texel[k] += wt * v[k];
                }
            }
        }
        texel
    }

    /// Σ over the windows' texels whose centre is within θ* of `r` of L_t ∫_t f dω.
    fn sum(&self, r: DVec3, windows: &[Window], theta_star: f64, mut f: impl FnMut(DVec3) -> [f64; 3]) -> [f64; 3] {
        let mut acc = [0.0; 3];
        if !self.single_nodes.is_empty() {
            // One node per texel: its direction and weight from the tables, nothing else.
            let (w, n) = (self.source.grid.width, &self.single_nodes);
            self.for_each_in_cone(r, windows, theta_star, |x, y| {
                let t = y * w + x;
                let l = self.source.radiance[t];
                if l == [0.0; 3] {
                    return;
                }
                let v = f(n[t]);
                let wt = self.sub_rows[y].weight * self.phi_weights[0];
                for k in 0..3 {
                    acc[k] += l[k] * wt * v[k];
                }
            });
            return acc;
        }
        self.for_each_in_cone(r, windows, theta_star, |x, y| {
            // A part of a map (a luminance band) is mostly zero: no integral for those.
            let l = self.source.radiance[y * self.source.grid.width + x];
            if l == [0.0; 3] {
                return;
            }
            let texel = self.texel_integral(x, y, &mut f);
            for k in 0..3 {
                acc[k] += l[k] * texel[k];
            }
        });
        acc
    }

    /// Σ over the texels whose centre is within θ* of `axis` of L_t ∫_t weight(ω) dω (texel
    /// integrals by this integrator's rule).
    pub fn integrate(&self, axis: DVec3, theta_star: f64, weight: impl FnMut(DVec3) -> [f64; 3]) -> [f64; 3] {
        let windows = self.windows(sphere::theta(axis), theta_star);
        self.sum(axis, &windows, theta_star, weight)
    }

    /// The sum of [`ConeIntegrator::integrate`] over the listed texels only (row-major indices,
    /// in the order given): for sparse maps, such as the bright part of one, whose few texels
    /// are cheaper to test one by one than the cone's rows.
    pub fn integrate_texels(
        &self,
        texels: &[usize],
        axis: DVec3,
        theta_star: f64,
        mut weight: impl FnMut(DVec3) -> [f64; 3],
    ) -> [f64; 3] {
        let src = &*self.source;
        let cos_star = if theta_star >= PI { f64::NEG_INFINITY } else { theta_star.cos() };
        let mut acc = [0.0; 3];
        for &t in texels {
            if axis.dot(src.centres[t]) < cos_star {
                continue;
            }
            let texel = self.texel_integral(t % src.grid.width, t / src.grid.width, &mut weight);
            for k in 0..3 {
                acc[k] += src.radiance[t][k] * texel[k];
            }
        }
        acc
    }

    /// The same sum as [`ConeIntegrator::integrate`], directly: every texel, its centre tested,
    /// every sub-sample's direction from [`sphere::direction`]. For tests.
    pub fn integrate_reference(
        &self,
        axis: DVec3,
        theta_star: f64,
        mut weight: impl FnMut(DVec3) -> [f64; 3],
    ) -> [f64; 3] {
        let src = &*self.source;
        let grid = src.grid;
        let cos_star = if theta_star >= PI { f64::NEG_INFINITY } else { theta_star.cos() };
        let mut acc = [0.0; 3];
        for y in 0..grid.height {
            for x in 0..grid.width {
                if axis.dot(grid.texel_direction(x, y)) < cos_star {
                    continue;
                }
                for row in self.rule.sub_rows(grid, y) {
                    for (offset, w_phi) in self.rule.sub_columns(grid) {
                        let phi = (x as f64 + 0.5 + offset) * TAU / grid.width as f64;
                        let v = weight(sphere::direction(row.z.acos(), phi));
                        let l = src.radiance[y * grid.width + x];
                        for k in 0..3 {
                            acc[k] += l[k] * row.weight * w_phi * v[k];
                        }
                    }
                }
            }
        }
        acc
    }

    /// The grey texel integrals ∫_t weight dω of the texels within θ* of `axis`, in visiting
    /// order: what [`choose_rule`] compares between rules.
    fn texel_integrals(&self, axis: DVec3, theta_star: f64, mut weight: impl FnMut(DVec3) -> f64) -> Vec<f64> {
        let windows = self.windows(sphere::theta(axis), theta_star);
        let mut out = Vec::new();
        self.for_each_in_cone(axis, &windows, theta_star, |x, y| {
            out.push(self.texel_integral(x, y, |l| [weight(l), 0.0, 0.0])[0]);
        });
        out
    }

    /// The texel rule for a 3-D ρ̂ (view-dependent lobes): [`choose_rule`] over the texel
    /// integrals seen from probe reflection vectors at the equator and at 45° (where the texels
    /// are largest and mid-sized), each with views at θ_o = 0, 60° and 81°.
    pub fn rule_for_view(&self, model: &Model, cutoff: &CutoffTable, tolerance: f64) -> RuleChoice {
        let mut probes = Vec::new();
        for theta_r in [0.5 * PI, 0.25 * PI] {
            let r = sphere::direction(theta_r, 0.5 * TAU / self.source.grid.width as f64);
            let e = sphere::frame_of(r) * DVec3::X;
            for theta_o in [0.0f64, PI / 3.0, 0.45 * PI] {
                probes.push((r, theta_o.cos() * r + theta_o.sin() * e, cutoff.at(theta_o)));
            }
        }
        choose_rule(tolerance, |rule| {
            let with = self.with_rule(rule.clone());
            probes
                .iter()
                .flat_map(|&(r, v, theta_star)| match model.prepare_view(r, v) {
                    Some(p) => with.texel_integrals(r, theta_star, |l| {
                        let x = model.rho_hat_prepared(&p, l);
                        (x[0] + x[1] + x[2]) / 3.0
                    }),
                    None => Vec::new(),
                })
                .collect()
        })
    }
}

/// A pyramid of a smooth lat-long map for cone sums: each level halves the last (2 × 2 texels
/// averaged with their solid angles, so every level keeps the map's integral), and a lobe is
/// summed on the coarsest level whose texels are at most 1/[`TEXELS_PER_CONE`] of
/// its cone angle θ* ([`ConePyramid::level`]). Midpoint sums of a smooth lobe over box-filtered
/// texels err by O((Δ/θ*)²), so on a smooth map (the remainder once bright sources are apart)
/// wide lobes read a fraction of the full-resolution texels at no visible loss; the ring-free
/// fallback ([`super::view_axis`]) takes its source from here.
pub struct ConePyramid {
    levels: Vec<EnvMap>,
}

impl ConePyramid {
    /// The pyramid of `env` (lat-long) down to rows of at least 8 texels. The levels are maps
    /// only: the view-frame passes read one level's texels, so no level pays for a
    /// [`ConeIntegrator`] it does not use (its tables are most of a pyramid's cost).
    pub fn new(env: &EnvMap) -> Result<Self, AngularError> {
        if env.layout() != Layout::LatLong {
            return Err(AngularError::NotLatLong(env.layout().name()));
        }
        let mut levels = vec![env.clone()];
        loop {
            let last = levels[levels.len() - 1].image();
            if last.height < 16 || last.height % 2 != 0 || last.width % 2 != 0 {
                return Ok(ConePyramid { levels });
            }
            let half = crate::envmap::resample::box_latlong(last, last.width / 2, last.height / 2);
            // Halving keeps the 2:1 shape, so this cannot fail for a map that was lat-long.
            levels.push(EnvMap::latlong(half).map_err(|_| AngularError::NotLatLong(Layout::LatLong.name()))?);
        }
    }

    /// The level a cone of half-angle `theta_star` is summed on: the coarsest whose texels are
    /// at most θ*/[`TEXELS_PER_CONE`] (the finest when none is).
    pub fn level(&self, theta_star: f64) -> &EnvMap {
        let fits = |m: &&EnvMap| PI / m.image().height as f64 <= theta_star / TEXELS_PER_CONE;
        self.levels.iter().rev().find(fits).unwrap_or(&self.levels[0])
    }

    /// [`ConePyramid::level`], or the finest coarser level of at most `max_texels` texels (the
    /// coarsest level when none is that small).
    pub fn level_within(&self, theta_star: f64, max_texels: usize) -> &EnvMap {
        let height = self.level(theta_star).image().height;
        let small = |m: &&EnvMap| m.image().height <= height && m.image().width * m.image().height <= max_texels;
        self.levels.iter().find(small).unwrap_or(&self.levels[self.levels.len() - 1])
    }
}

/// The angular passes integrate lat-long maps: other layouts are resampled at a resolution that
/// keeps their texel count ([`latlong_grid`]).
pub fn as_latlong(env: &EnvMap) -> Result<EnvMap, envmap::EnvMapError> {
    if env.layout() == Layout::LatLong {
        return Ok(env.clone());
    }
    let grid = latlong_grid(env);
    envmap::resample(env, Layout::LatLong, grid.width, grid.height, 3)
}

/// The lat-long grid [`as_latlong`] puts `env` on.
pub fn latlong_grid(env: &EnvMap) -> LatLong {
    if env.layout() == Layout::LatLong {
        return LatLong::new(env.image().width, env.image().height);
    }
    let s = env.max_order().max(16);
    LatLong::new(2 * s, s)
}

/// Angular reflection map of a radially symmetric lobe u(R·ω): B(R) = Σ_{cone} L_t ∫_t u(R·ω) dω,
/// on a `width`×`height` lat-long grid of R. An output as wide as the environment takes the
/// zonal filter (FFT); any other width the cone sum. Both use `env`'s texel rule.
pub fn radial_map(
    env: &ConeIntegrator,
    u: impl Fn(f64) -> f64 + Sync,
    theta_star: f64,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> Result<RgbImage, AngularError> {
    if width == env.grid().width {
        let map = zonal::zonal_filter(
            &env.source.image,
            u,
            theta_star.clamp(1e-9, PI),
            &env.rule,
            height,
            Rows::Lit,
            progress,
        )?;
        return Ok(map.to_image());
    }
    Ok(radial_cone_sum(env, u, theta_star, width, height, progress))
}

/// The same map as [`radial_map`] by the cone sum, whatever the width: per output texel, the
/// texels of the cone one by one (the paper's angular method, App. D, with exact texel
/// integrals). [`radial_map`] takes it for outputs narrower or wider than the environment.
pub fn radial_cone_sum(
    env: &ConeIntegrator,
    u: impl Fn(f64) -> f64 + Sync,
    theta_star: f64,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> RgbImage {
    let theta_star = theta_star.clamp(1e-9, PI);
    let out_grid = LatLong::new(width, height);
    progress.start("angular", height as u64);
    let mut image = RgbImage::new(width, height);
    image.pixels.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let windows = env.windows(out_grid.row_theta(y), theta_star);
        for (x, px) in row.iter_mut().enumerate() {
            let r = out_grid.texel_direction(x, y);
            let v = env.sum(r, &windows, theta_star, |l| [u(r.dot(l)); 3]);
            *px = [v[0] as f32, v[1] as f32, v[2] as f32];
        }
        progress.advance(1);
    });
    progress.finish();
    image
}

/// Angular reflection map for a distant viewer in direction `view`: for each reflection vector
/// R, B̃(R) = Σ_{cone(θ*(θ_o))} L_t ∫_t ρ̂(ω, view) dω with cos θ_o = R·view. The normal and its
/// frame are computed once per output texel, the φ windows once per output row and θ*.
pub fn view_map(
    env: &ConeIntegrator,
    model: &super::model::Model,
    cutoff: &CutoffTable,
    view: DVec3,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> RgbImage {
    let out_grid = LatLong::new(width, height);
    let mut image = RgbImage::new(width, height);
    image.pixels.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let theta_r = out_grid.row_theta(y);
        // θ* takes few distinct values (the table's bins): windows per value.
        let mut cache: Vec<(f64, Vec<Window>)> = Vec::new();
        for (x, px) in row.iter_mut().enumerate() {
            let r = out_grid.texel_direction(x, y);
            let Some(prepared) = model.prepare_view(r, view) else { continue };
            let theta_star = cutoff.at(r.dot(view).clamp(-1.0, 1.0).acos());
            let i = match cache.iter().position(|c| c.0 == theta_star) {
                Some(i) => i,
                None => {
                    cache.push((theta_star, env.windows(theta_r, theta_star)));
                    cache.len() - 1
                }
            };
            let v = env.sum(r, &cache[i].1, theta_star, |l| model.rho_hat_prepared(&prepared, l));
            *px = [v[0] as f32, v[1] as f32, v[2] as f32];
        }
        progress.advance(1);
    });
    image
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::prefilter::model::Model;
    use crate::prefilter::truncation::radial_cutoff;
    use crate::progress::NoProgress;

    #[test]
    fn a_texel_budget_moves_the_pyramid_to_coarser_levels_only() {
        let env = EnvMap::latlong(RgbImage::new(256, 128)).unwrap();
        let pyramid = ConePyramid::new(&env).unwrap();
        let height = |m: &EnvMap| m.image().height;
        // Within budget: the level the cone picks (0.1 rad: the full map; 3 rad: 32 rows).
        assert_eq!(height(pyramid.level_within(0.1, usize::MAX)), 128);
        assert_eq!(height(pyramid.level_within(3.0, usize::MAX)), 32);
        // Over it: the finest level of at most that many texels, never a finer one than picked.
        assert_eq!(height(pyramid.level_within(0.1, 64 * 32)), 32);
        assert_eq!(height(pyramid.level_within(3.0, 128 * 64)), 32);
        // Nothing small enough: the coarsest.
        assert_eq!(height(pyramid.level_within(0.1, 1)), 8);
    }

    #[test]
    fn each_pyramid_level_keeps_the_integral_and_wide_lobes_read_coarse_levels() {
        // A smooth map: every level's texel integrals sum to the same ∫ L dω (solid-angle
        // weights), and a wide Phong lobe summed on the coarse level it picks agrees with the
        // full-resolution sum to well under the prefilter's tolerance.
        let smooth = |d: DVec3| [(1.0 + 0.5 * d.z + 0.3 * (3.0 * d.x).sin()) as f32, 1.0, (2.0 + d.y) as f32];
        let img = RgbImage::from_fn(256, 128, |x, y| smooth(LatLong::new(256, 128).texel_direction(x, y)));
        let env = EnvMap::latlong(img).unwrap();
        let pyramid = ConePyramid::new(&env).unwrap();
        assert_eq!(pyramid.levels.len(), 5, "256x128 down to 16x8");
        let sums = |m: &EnvMap| ConeIntegrator::new(m).unwrap();
        let whole = |m: &EnvMap| sums(m).integrate(DVec3::Z, PI, |_| [1.0; 3]);
        let base = whole(&pyramid.levels[0]);
        for level in &pyramid.levels[1..] {
            let v = whole(level);
            let size = (level.image().width, level.image().height);
            assert!((0..3).all(|k| (v[k] - base[k]).abs() < 1e-5 * base[k]), "{size:?}: {v:?} vs {base:?}");
        }
        let axis = DVec3::new(0.3, -0.5, 0.6).normalize();
        for s in [4.0f64, 16.0] {
            let theta_star = radial_cutoff(|x| if x > 0.0 { x.powf(s) } else { 0.0 }, 1e-5);
            let lobe = |l: DVec3| [axis.dot(l).max(0.0).powf(s); 3];
            let coarse = sums(pyramid.level(theta_star)).integrate(axis, theta_star, lobe);
            let fine = sums(&pyramid.levels[0]).integrate(axis, theta_star, lobe);
            assert!((0..3).all(|k| (coarse[k] - fine[k]).abs() < 1e-3 * fine[k]), "s={s}: {coarse:?} vs {fine:?}");
        }
        // The wide lobe reads a coarser level than the full map.
        let chosen = |theta_star: f64| {
            pyramid.levels.iter().rposition(|m| PI / m.image().height as f64 <= theta_star / TEXELS_PER_CONE)
        };
        assert_eq!((chosen(1.5), chosen(3.0), chosen(0.1)), (Some(1), Some(2), None));
    }

    #[test]
    fn a_full_cone_integrates_the_whole_sphere() {
        let img = RgbImage::from_fn(64, 32, |_, _| [1.0, 2.0, 3.0]);
        let env = ConeIntegrator::new(&EnvMap::latlong(img).unwrap()).unwrap();
        let v = env.integrate(DVec3::new(0.3, 0.4, 0.5).normalize(), PI, |_| [1.0; 3]);
        assert!((v[0] - 4.0 * PI).abs() < 1e-9 && (v[2] - 12.0 * PI).abs() < 1e-9);
        // A cone of half-angle θ* covers 2π(1 − cos θ*) up to the texel discretization.
        let cap = env.integrate(DVec3::new(0.3, 0.4, 0.5).normalize(), 0.5, |_| [1.0; 3]);
        let want = 2.0 * PI * (1.0 - 0.5f64.cos());
        assert!((cap[0] / want - 1.0).abs() < 0.05, "{} vs {want}", cap[0]);
    }

    #[test]
    fn the_cone_visits_exactly_the_texels_within_theta_star() {
        let img = RgbImage::from_fn(96, 48, |_, _| [1.0; 3]);
        let map = EnvMap::latlong(img).unwrap();
        let env = ConeIntegrator::new(&map).unwrap();
        for axis in [DVec3::Z, DVec3::new(1.0, -2.0, 0.3).normalize(), DVec3::new(-0.1, 0.05, -1.0).normalize()] {
            for theta_star in [0.1, 0.7, 2.0] {
                let got = env.integrate(axis, theta_star, |_| [1.0; 3])[0];
                let mut want = 0.0;
                map.for_each_texel(|t| {
                    if t.dir.dot(axis) >= theta_star.cos() {
                        want += t.solid_angle;
                    }
                });
                assert!((got - want).abs() < 1e-9, "axis {axis} θ* {theta_star}: {got} vs {want}");
            }
        }
    }

    fn sky(w: usize, h: usize) -> EnvMap {
        let sun = DVec3::new(0.4, 0.3, 0.6).normalize();
        EnvMap::latlong(RgbImage::from_fn(w, h, |x, y| {
            let d = LatLong::new(w, h).texel_direction(x, y);
            let s = 40.0 * d.dot(sun).max(0.0).powi(20);
            let v = if d.z > 0.0 { 1.0 + 0.5 * (1.0 - d.z) } else { 0.3 + 0.1 * (3.0 * d.x).sin().abs() };
            [(v + s) as f32, (0.9 * v + s) as f32, (0.8 * v + x as f64 * 0.01) as f32]
        }))
        .unwrap()
    }

    fn relative(a: [f64; 3], b: [f64; 3]) -> f64 {
        (0..3).map(|k| (a[k] - b[k]).abs() / b[k].abs().max(1e-300)).fold(0.0, f64::max)
    }

    #[test]
    fn the_cone_sum_equals_the_direct_sum() {
        let env = ConeIntegrator::new(&sky(36, 18)).unwrap();
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.3").unwrap(), true).unwrap();
        for n in [1, 3] {
            let env = env.with_rule(TexelRule::new(n).unwrap());
            for (axis, view) in [
                (DVec3::new(0.2, 0.5, 0.8).normalize(), DVec3::Z),
                (DVec3::new(-0.9, 0.1, -0.2).normalize(), DVec3::new(0.3, -0.4, 0.5).normalize()),
                (DVec3::new(0.01, 0.0, 1.0).normalize(), DVec3::new(1.0, 0.0, 0.1).normalize()),
            ] {
                let p = model.prepare_view(axis, view).unwrap();
                for theta_star in [PI, 0.9, 0.37] {
                    let fast = env.integrate(axis, theta_star, |l| model.rho_hat_prepared(&p, l));
                    let slow = env.integrate_reference(axis, theta_star, |l| model.rho_hat_prepared(&p, l));
                    assert!(relative(fast, slow) < 1e-9, "n={n} θ*={theta_star}: {fast:?} vs {slow:?}");
                }
            }
        }
    }

    #[test]
    fn both_radial_paths_compute_the_same_sum() {
        // The zonal filter (output as wide as the input) and the cone sum (any other width, here
        // forced by asking for the same width through the cone path) agree to rounding.
        let env = ConeIntegrator::new(&sky(32, 16)).unwrap().with_rule(TexelRule::new(2).unwrap());
        let u = |x: f64| if x > 0.0 { 17.0 / TAU * x.powi(16) } else { 0.0 };
        let zonal = zonal::zonal_filter(&env.source.image, u, 0.8, &env.rule, 16, Rows::All, &NoProgress).unwrap();
        let grid = LatLong::new(32, 16);
        for y in 0..16 {
            for x in 0..32 {
                let r = grid.texel_direction(x, y);
                let cone = env.integrate(r, 0.8, |l| [u(r.dot(l)); 3]);
                assert!(relative(zonal.pixels[y * 32 + x], cone) < 1e-9, "({x}, {y})");
            }
        }
    }

    #[test]
    fn view_maps_are_the_same_for_any_thread_count() {
        let env = ConeIntegrator::new(&sky(32, 16)).unwrap().with_rule(TexelRule::new(2).unwrap());
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.2").unwrap(), false).unwrap();
        let cutoff = CutoffTable::of_model(&model, 1e-2, 17);
        let view = DVec3::new(0.3, -0.5, 0.4).normalize();
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| view_map(&env, &model, &cutoff, view, 24, 12, &NoProgress))
        };
        let one = run(1);
        assert!(one.pixels.iter().flatten().any(|v| *v > 0.0));
        assert_eq!(run(2), one);
        assert_eq!(run(3), one);
    }

    #[test]
    fn the_view_rule_meets_its_tolerance() {
        // σ = 0.05 on 48 × 24 texels (7.5°): far narrower than a texel, so the midpoint is off.
        let env = ConeIntegrator::new(&sky(48, 24)).unwrap();
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.05").unwrap(), true).unwrap();
        let cutoff = CutoffTable::of_model(&model, 1e-3, 17);
        let choice = env.rule_for_view(&model, &cutoff, 1e-4);
        assert!(choice.rule.subsamples() > 1 && choice.estimated_error <= 1e-4, "{choice:?}");
    }
}
