//! The whole prefilter, both ways: frequency space (App. C steps 1–3) and the angular reference.

use super::angular::{self, ConeIntegrator, CutoffTable};
use super::brdf_sh::BrdfSh;
use super::model::{Model, ModelError};
use super::shrm::{self, Shrm, ShrmError};
use crate::envmap::bright::{luminance, split, BrightReport, BrightRule, BrightSources};
use crate::envmap::zonal::RuleChoice;
use crate::envmap::EnvMap;
use crate::io::RgbImage;
use crate::progress::Progress;
use crate::sh::project::{project, ProjectError};
use crate::sh::ShCoeffs;
use crate::sphere::LatLong;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;
use std::time::Instant;

/// How F_B and P_B are chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Orders {
    /// The smallest orders keeping 1 − ε of the BRDF energy (§5.1), P searched up to `max_p`.
    Epsilon {
        /// ε.
        epsilon: f64,
        /// Largest P considered.
        max_p: usize,
    },
    /// Given orders.
    Fixed {
        /// F_B.
        f: usize,
        /// P_B (0 for radially symmetric BRDFs).
        p: usize,
    },
}

/// The lighting: an environment map (projected to F_B as needed) or given coefficients.
#[derive(Clone, Copy)]
pub enum Lighting<'a> {
    /// An environment map.
    Map(&'a EnvMap),
    /// SH coefficients (from a `prtkit.sh` document).
    Coefficients(&'a ShCoeffs),
}

/// Errors of the prefilter.
#[derive(Debug, thiserror::Error)]
pub enum PrefilterError {
    /// BRDF problems.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Projection problems (order beyond the map's resolution).
    #[error(transparent)]
    Project(#[from] ProjectError),
    /// SHRM problems.
    #[error(transparent)]
    Shrm(#[from] ShrmError),
    /// Angular reference problems.
    #[error(transparent)]
    Angular(#[from] angular::AngularError),
    /// Resampling the map to lat-long for the angular passes failed.
    #[error("cannot resample the map to lat-long: {0}")]
    Resample(String),
    /// Given coefficients are of too low an order.
    #[error("the SH coefficients have order {have}, but F_B = {need} is needed: re-run sh-project with --order {need} (or give the environment map)")]
    LightingOrder {
        /// Order given.
        have: usize,
        /// Order needed.
        need: usize,
    },
}

/// Seconds spent in each step of the frequency-space prefilter.
#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Timings {
    /// Step 1: BRDF coefficients (with the order search).
    pub brdf_seconds: f64,
    /// Step 1: lighting coefficients to F_B.
    pub lighting_seconds: f64,
    /// Steps 2–3: the SHRM.
    pub shrm_seconds: f64,
}

/// The frequency-space result.
pub struct Frequency {
    /// ρ̂_lpq, truncated to (F_B, P_B).
    pub brdf: BrdfSh,
    /// L_lm up to F_B.
    pub lighting: ShCoeffs,
    /// The local SHRM.
    pub shrm: Shrm,
    /// BRDF energy missed by (F_B, P_B).
    pub epsilon_achieved: f64,
    /// Per-step times.
    pub timings: Timings,
}

/// BRDF coefficients for the requested orders.
pub fn brdf_coefficients(model: &Model, orders: Orders) -> Result<BrdfSh, PrefilterError> {
    Ok(match orders {
        Orders::Epsilon { epsilon, max_p } => model.coefficients_for_epsilon(epsilon, max_p)?,
        Orders::Fixed { f, p } => {
            let p = if model.centre().is_some() { 0 } else { p };
            model.coefficients(f, p)
        }
    })
}

/// Frequency-space prefiltering into a local SHRM on a `width`×`height` lat-long grid.
pub fn frequency(
    model: &Model,
    lighting: Lighting<'_>,
    orders: Orders,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> Result<Frequency, PrefilterError> {
    let t = Instant::now();
    let brdf = brdf_coefficients(model, orders)?;
    let brdf_seconds = t.elapsed().as_secs_f64();
    let f_b = brdf.f;

    let t = Instant::now();
    let light = match lighting {
        Lighting::Map(map) => project(map, f_b, progress)?,
        Lighting::Coefficients(c) => {
            if c.order < f_b {
                return Err(PrefilterError::LightingOrder { have: c.order, need: f_b });
            }
            c.truncated(f_b)
        }
    };
    let lighting_seconds = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let shrm =
        if model.centre().is_some() {
            // 1-D path: B(R) = Σ Λ_l ρ̂_l L_lm Y_lm(R); the SHRM's single layer is B_00 = √(4π) B.
            let kernel = |l: usize| brdf.radial_kernel(l);
            let mut conv = light.clone();
            for (i, c) in conv.rgb.iter_mut().enumerate() {
                let (l, _) = crate::sh::lm(i);
                let k = kernel(l);
                for ch in 0..3 {
                    c[ch] *= k[ch] * (4.0 * std::f64::consts::PI).sqrt();
                }
            }
            if width < 2 * f_b + 2 {
                return Err(ShrmError::TooSmall { width, f_b, need: 2 * f_b + 2 }.into());
            }
            let layer = crate::sh::synth::synthesize_latlong(&conv, width, height)
                .map_err(|_| ShrmError::TooSmall { width, f_b, need: 2 * f_b + 2 })?;
            Shrm { f_b, p_b: 0, global: false, layers: vec![layer] }
        } else {
            shrm::local_shrm(&light, &brdf, width, height, progress)?
        };
    let shrm_seconds = t.elapsed().as_secs_f64();
    let epsilon_achieved = brdf.residual(brdf.f, brdf.p);
    Ok(Frequency {
        brdf,
        lighting: light,
        shrm,
        epsilon_achieved,
        timings: Timings { brdf_seconds, lighting_seconds, shrm_seconds },
    })
}

/// How the angular reference computed its maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum AngularPath {
    /// A radially symmetric lobe on an output as wide as the input: FFT convolutions in φ
    /// ([`crate::envmap::zonal`]).
    Zonal,
    /// The cone sum per output texel (3-D BRDFs, or other output widths).
    ConeSum,
}

/// What the angular reference used: no SH orders, only the truncation and the texel rule.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AngularReport {
    /// The requested truncation ε.
    pub epsilon: f64,
    /// The largest share of the lobe's weight a cone leaves out (≤ ε).
    pub epsilon_achieved: f64,
    /// The widest cone half-angle θ* used, in radians.
    pub cone_angle: f64,
    /// Sub-samples per texel axis of the texel integrals (n; n² per texel).
    pub subsamples: usize,
    /// The measured share of the lobe's weight the texel rule misplaces (≤ ε/10 unless the
    /// largest rule was needed).
    pub quadrature_error: f64,
    /// Zonal FFT or cone sum.
    pub path: AngularPath,
    /// The bright sources summed apart, with a cone that leaves out at most ε M / e_max of the
    /// lobe (M: the remainder's largest luminance, e_max: the largest excess).
    pub bright: BrightReport,
}

/// The angular reference's maps and what it used.
pub struct AngularMaps {
    /// One map per view (one map in all for radially symmetric BRDFs).
    pub maps: Vec<RgbImage>,
    /// Truncation and texel rule.
    pub report: AngularReport,
}

/// How the angular reference truncates its lobes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngularSettings {
    /// The share ε of the lobe's weight a cone may leave out (App. D).
    pub epsilon: f64,
    /// The bright sources apart ([`crate::envmap::bright`]): their texels are summed with a cone
    /// that leaves out ε M / e_max of the lobe (M: the remainder's largest luminance, e_max: the
    /// largest excess), so that what any texel misses is at most 2 ε M ∫ρ̂ whatever the sun.
    /// `Off`: the paper's truncation, which misses up to ε L_max ∫ρ̂: under a sun 10⁴ × the sky,
    /// 10⁴ ε of the sky's level.
    pub bright: BrightRule,
}

impl AngularSettings {
    /// ε with the bright sources apart (`--method angular`'s default).
    pub fn new(epsilon: f64) -> Self {
        AngularSettings { epsilon, bright: BrightRule::Auto }
    }

    /// ε over the whole map, as App. D (the paper's timings).
    pub fn paper(epsilon: f64) -> Self {
        AngularSettings { epsilon, bright: BrightRule::Off }
    }
}

/// The lobe's truncation cone: one angle for radially symmetric lobes, θ*(θ_o) otherwise.
enum Cone {
    Radial(angular::Truncation),
    View(CutoffTable),
}

impl Cone {
    /// The cone of `model`'s lobe that leaves out ε of its weight.
    fn new(model: &Model, epsilon: f64) -> Self {
        match model.centre() {
            Some(_) => Cone::Radial(angular::radial_truncation(|x| model.lobe(x)[0], epsilon)),
            None => Cone::View(CutoffTable::new(|wi, wo| model.rho_hat_grey(wi, wo), epsilon, 65)),
        }
    }

    /// A lat-long `env` ready for the cone sums of `model`'s lobe truncated at ε: the cone, and
    /// the texel rule that misplaces at most ε/10 of the lobe's weight on an output of `height`
    /// rows.
    fn prepared(
        model: &Model,
        env: &EnvMap,
        epsilon: f64,
        height: usize,
    ) -> Result<(ConeIntegrator, Cone, RuleChoice), PrefilterError> {
        let env = ConeIntegrator::new(env)?;
        let cone = Cone::new(model, epsilon);
        let choice = match &cone {
            Cone::Radial(t) => {
                angular::reference_rule(env.grid(), &|x: f64| model.lobe(x)[0], t.theta_star, height, epsilon)
            }
            Cone::View(cutoff) => env.rule_for_view(model, cutoff, epsilon / 10.0),
        };
        Ok((env.with_rule(choice.rule.clone()), cone, choice))
    }

    /// The widest half-angle θ*.
    fn widest(&self) -> f64 {
        match self {
            Cone::Radial(t) => t.theta_star,
            Cone::View(cutoff) => cutoff.max(),
        }
    }

    /// The share of the lobe's weight left out.
    fn left_out(&self) -> f64 {
        match self {
            Cone::Radial(t) => t.left_out,
            Cone::View(cutoff) => cutoff.left_out(),
        }
    }
}

/// The bright texels of the environment, summed one by one with their own, wider cone.
struct BrightPass {
    /// The excess over the threshold (zero elsewhere), with the reference's texel rule.
    env: ConeIntegrator,
    /// Row-major indices of the texels with an excess.
    texels: Vec<usize>,
    cone: Cone,
    report: BrightReport,
}

/// The angular reference's integral for one model and environment, set up as `--method angular`
/// sets it up for an output of a given height: the lobe truncated at ε (App. D), the bright
/// sources apart with a wider cone, and the texel rule that misplaces at most ε/10 of its weight
/// ([`angular`]). [`angular_reference`] computes whole maps with it, [`AngularIntegral::texel`]
/// single texels (`prefilter --verify`).
pub struct AngularIntegral<'m> {
    model: &'m Model,
    /// The environment (its remainder when the bright sources are apart).
    env: ConeIntegrator,
    cone: Cone,
    bright: Option<BrightPass>,
    choice: RuleChoice,
    epsilon: f64,
}

impl<'m> AngularIntegral<'m> {
    /// The integral of `model` over the lat-long `env`, truncated as `settings` say, with the
    /// texel rule chosen for an output of `height` rows.
    pub fn new(
        model: &'m Model,
        env: &EnvMap,
        settings: AngularSettings,
        height: usize,
    ) -> Result<Self, PrefilterError> {
        let epsilon = settings.epsilon;
        let (remainder, sources) = split(env, settings.bright);
        let (env_rest, cone, choice) = Cone::prepared(model, &remainder, epsilon, height)?;
        let bright = match sources.is_empty() {
            true => None,
            false => Some(BrightPass::new(model, env, &remainder, &sources, epsilon, height)?),
        };
        Ok(AngularIntegral { model, env: env_rest, cone, bright, choice, epsilon })
    }

    /// The widest cone half-angle θ*, in radians: no reflection vector farther than this from a
    /// texel of the environment sees it (the bright sources' cones are wider).
    pub fn cone_angle(&self) -> f64 {
        self.cone.widest()
    }

    /// Sub-samples per texel axis of the texel rule.
    pub fn subsamples(&self) -> usize {
        self.choice.rule.subsamples()
    }

    /// Truncation and texel rule, for a document.
    pub fn report(&self, path: AngularPath) -> AngularReport {
        AngularReport {
            epsilon: self.epsilon,
            epsilon_achieved: self.cone.left_out(),
            cone_angle: self.cone_angle(),
            subsamples: self.subsamples(),
            quadrature_error: self.choice.estimated_error,
            path,
            bright: self.bright.as_ref().map(|b| b.report).unwrap_or_default(),
        }
    }

    /// B(R) for one reflection vector `r` (unit) and `view` (ignored by radially symmetric
    /// lobes): the sum [`angular::radial_map`] and [`angular::view_map`] compute per texel, plus
    /// the bright sources. With bright sources the remainder's sum is rounded to f32 first, as a
    /// map holds it before they are added, so that a map and its texels agree to the bit.
    pub fn texel(&self, r: DVec3, view: DVec3) -> [f64; 3] {
        let rest = cone_sum(self.model, &self.cone, r, view, |theta_star, f| self.env.integrate(r, theta_star, f));
        match &self.bright {
            None => rest,
            Some(b) => {
                let bright = b.texel(self.model, r, view);
                [0, 1, 2].map(|c| rest[c] as f32 as f64 + bright[c])
            }
        }
    }

    /// Adds the bright sources to a `width`×`height` lat-long map for `view`.
    fn add_bright(&self, map: &mut RgbImage, view: DVec3) {
        let Some(bright) = &self.bright else { return };
        let grid = LatLong::new(map.width, map.height);
        map.pixels.par_chunks_mut(grid.width).enumerate().for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let v = bright.texel(self.model, grid.texel_direction(x, y), view);
                for c in 0..3 {
                    px[c] = (px[c] as f64 + v[c]) as f32;
                }
            }
        });
    }
}

/// One cone sum of `model`'s lobe about `r` for `view`: `integrate(θ*, weight)` with the
/// cone's θ* (per view angle for 3-D BRDFs) and the lobe as the weight.
fn cone_sum(
    model: &Model,
    cone: &Cone,
    r: DVec3,
    view: DVec3,
    integrate: impl FnOnce(f64, &mut dyn FnMut(DVec3) -> [f64; 3]) -> [f64; 3],
) -> [f64; 3] {
    match cone {
        Cone::Radial(t) => integrate(t.theta_star.clamp(1e-9, PI), &mut |l| [model.lobe(r.dot(l))[0]; 3]),
        Cone::View(cutoff) => match model.prepare_view(r, view) {
            Some(p) => {
                let theta_star = cutoff.at(r.dot(view).clamp(-1.0, 1.0).acos());
                integrate(theta_star, &mut |l| model.rho_hat_prepared(&p, l))
            }
            None => [0.0; 3],
        },
    }
}

impl BrightPass {
    /// The excess of `env` over its `remainder` (the split into `sources`), summed with a cone
    /// that leaves out ε_b = ε M / e_max of the lobe (M: the remainder's largest luminance,
    /// e_max: the largest excess) and a texel rule that misplaces at most ε_b/10 of it, so that
    /// it misses at most ε M ∫ρ̂, as the remainder's cone does.
    fn new(
        model: &Model,
        env: &EnvMap,
        remainder: &EnvMap,
        sources: &BrightSources,
        epsilon: f64,
        height: usize,
    ) -> Result<Self, PrefilterError> {
        let (whole, rest) = (env.image(), remainder.image());
        let mut excess = RgbImage::new(whole.width, whole.height);
        let mut texels = Vec::new();
        for (i, (px, (a, b))) in excess.pixels.iter_mut().zip(whole.pixels.iter().zip(&rest.pixels)).enumerate() {
            *px = [0, 1, 2].map(|c| a[c] - b[c]);
            if px.iter().any(|&v| v != 0.0) {
                texels.push(i);
            }
        }
        let excess = EnvMap::latlong(excess).map_err(|e| PrefilterError::Resample(e.to_string()))?;
        let m_rest = rest.pixels.iter().map(|&p| luminance(p)).fold(0.0, f64::max);
        let e_max = sources.texels.iter().map(|t| t.excess.iter().sum::<f64>() / 3.0).fold(0.0, f64::max);
        // Never looser than ε, and no tighter than 10⁻¹² unless ε itself is.
        let epsilon_b = (epsilon * m_rest / e_max.max(1e-300)).max(1e-12).min(epsilon);
        let (env, cone, _) = Cone::prepared(model, &excess, epsilon_b, height)?;
        Ok(BrightPass { env, texels, cone, report: sources.report() })
    }

    /// The bright texels' share of B(R) for `view`.
    fn texel(&self, model: &Model, r: DVec3, view: DVec3) -> [f64; 3] {
        cone_sum(model, &self.cone, r, view, |theta_star, f| self.env.integrate_texels(&self.texels, r, theta_star, f))
    }
}

/// The angular reference (App. D): for radially symmetric BRDFs one map (views ignored),
/// otherwise one reflection map per view, on a `width`×`height` lat-long grid. The lobe is
/// truncated as `settings` say, and its texel integrals use the smallest Gauss–Legendre rule
/// that misplaces at most ε/10 of its weight ([`angular`]). No spherical harmonics are involved.
pub fn angular_reference(
    model: &Model,
    env: &EnvMap,
    views: &[DVec3],
    settings: AngularSettings,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> Result<AngularMaps, PrefilterError> {
    let integral = AngularIntegral::new(model, env, settings, height)?;
    let cone = &integral.env;
    match &integral.cone {
        Cone::Radial(t) => {
            let u = |x: f64| model.lobe(x)[0];
            let mut map = angular::radial_map(cone, u, t.theta_star, width, height, progress)?;
            integral.add_bright(&mut map, DVec3::Z);
            let path = if width == cone.grid().width { AngularPath::Zonal } else { AngularPath::ConeSum };
            Ok(AngularMaps { maps: vec![map], report: integral.report(path) })
        }
        Cone::View(cutoff) => {
            progress.start("angular", (views.len() * height) as u64);
            let maps = views
                .iter()
                .map(|&v| {
                    let mut map = angular::view_map(cone, model, cutoff, v, width, height, progress);
                    integral.add_bright(&mut map, v);
                    map
                })
                .collect();
            progress.finish();
            Ok(AngularMaps { maps, report: integral.report(AngularPath::ConeSum) })
        }
    }
}

/// The maps of [`angular_reference`].
pub fn angular_maps(
    model: &Model,
    env: &EnvMap,
    views: &[DVec3],
    settings: AngularSettings,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> Result<Vec<RgbImage>, PrefilterError> {
    Ok(angular_reference(model, env, views, settings, width, height, progress)?.maps)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::metrics::compare;
    use crate::progress::NoProgress;

    /// A sky 1 + z⁺ with a sun of 4 texels 10⁴ × brighter, low in the west.
    fn sun_sky() -> EnvMap {
        let grid = LatLong::new(64, 32);
        let (sx, sy) = (40, 13);
        EnvMap::latlong(RgbImage::from_fn(64, 32, |x, y| {
            let sun = (x == sx || x == sx + 1) && (y == sy || y == sy + 1);
            let v = if sun { 2e4 } else { 1.0 + grid.texel_direction(x, y).z.max(0.0) };
            [v as f32, v as f32, (0.8 * v) as f32]
        }))
        .unwrap()
    }

    #[test]
    fn bright_sources_apart_make_the_reference_honest_per_texel() {
        // The paper's truncation at ε = 10⁻³ leaves 0.1 % of each lobe out, 20 × the sky's level
        // under this sun: dark texels come out several per cent low. With the sun summed apart
        // (its cone leaves out ε M / e_max), the same ε agrees with a 10⁻⁷ truncation of the
        // whole map within its bound, and both ways agree when nothing is cut.
        let env = sun_sky();
        let view = DVec3::new(0.3, 0.0, 1.0).normalize();
        for (spec, cosine) in [("phong:s=32", true), ("torrance-sparrow:sigma=0.3", false)] {
            let model = Model::new(Brdf::parse(spec).unwrap(), cosine).unwrap();
            let map = |settings| angular_maps(&model, &env, &[view], settings, 64, 32, &NoProgress).unwrap().remove(0);
            let exact = map(AngularSettings::paper(1e-7));
            let (paper, _) = compare(&map(AngularSettings::paper(1e-3)), &exact, &[]).unwrap();
            let honest =
                angular_reference(&model, &env, &[view], AngularSettings::new(1e-3), 64, 32, &NoProgress).unwrap();
            let (apart, _) = compare(&honest.maps[0], &exact, &[]).unwrap();
            assert!(paper.max_texel_error > 0.03, "{spec}: the paper's truncation is off by {paper:?}");
            // The bound 2 ε M ∫ρ̂ is ~1 % of the darkest texels here (M ≈ 4 × the sky's mean).
            assert!(apart.max_texel_error < 5e-3, "{spec}: bright apart is off by {apart:?}");
            assert_eq!(honest.report.bright.texels, 4, "{spec}: {:?}", honest.report.bright);
            assert!(honest.report.bright.energy_fraction > 0.9, "{:?}", honest.report.bright);
            let (same, _) = compare(&map(AngularSettings::new(1e-7)), &exact, &[]).unwrap();
            // Within the texel rules' tolerance (ε/10 of the lobe, times a sun of 2 · 10⁴).
            assert!(same.max_texel_error < 1e-3, "{spec}: {same:?}");
        }
    }

    #[test]
    fn an_epsilon_below_the_bright_floor_is_taken_as_it_is() {
        // The bright sources' cone is at most ε and at least 10⁻¹² unless ε is smaller: with
        // ε = 10⁻¹³ both parts use ε itself (it used to panic in `clamp`), and the split map
        // is the whole map's sum within the texel rules' tolerance.
        let env = sun_sky();
        let model = Model::new(Brdf::parse("phong:s=32").unwrap(), true).unwrap();
        let map = |settings| angular_maps(&model, &env, &[DVec3::Z], settings, 64, 32, &NoProgress).unwrap().remove(0);
        let (m, _) = compare(&map(AngularSettings::new(1e-13)), &map(AngularSettings::paper(1e-13)), &[]).unwrap();
        assert!(m.max_texel_error < 1e-3, "{m:?}");
    }
}
