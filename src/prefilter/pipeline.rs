//! The whole prefilter, both ways: frequency space (App. C steps 1–3) and the angular reference.

use super::angular::{self, ConeIntegrator};
use super::brdf_sh::BrdfSh;
use super::model::{Model, ModelError};
use super::shrm::{self, Shrm, ShrmError};
use super::truncation::{self, CutoffTable};
use super::tuning::REFERENCE_CUTOFF_BINS;
use crate::envmap::bright::{luminance_bands, mean_luminance, split, BrightReport, BrightRule};
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
    Resample(crate::envmap::EnvMapError),
    /// Given coefficients are of too low an order.
    #[error("the SH coefficients have order {have}, but F_B = {need} is needed")]
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

/// The grid size for F_B: 2S × S with S = clamp(10·F_B, 32, 512) (§5.2: S ≈ 10F), at least
/// F_B + 1.
pub fn default_size(f_b: usize) -> (usize, usize) {
    let s = (10 * f_b).clamp(32, 512).max(f_b + 1);
    (2 * s, s)
}

/// Frequency-space prefiltering into a local SHRM (R&H 2002 App. C): the BRDF's coefficients to
/// the orders, the lighting's to F_B, and the SHRM on a `size` lat-long grid ([`default_size`]
/// when `None`).
pub fn frequency(
    model: &Model,
    lighting: Lighting<'_>,
    orders: Orders,
    size: Option<(usize, usize)>,
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
    let (width, height) = size.unwrap_or_else(|| default_size(f_b));
    let shrm = shrm::from_lighting(model.centre().is_some(), &light, &brdf, None, width, height, progress)?;
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
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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
    /// The bright sources split off (as the frequency method splits them).
    pub bright: BrightReport,
    /// F: the luminance below which texels take the cone of ε (the remainder's mean; absent
    /// when the map was not cut into parts: `--bright off`, where the whole map takes that cone,
    /// or a map with nothing above F).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub floor_luminance: Option<f64>,
    /// The luminance bands above F, brightest first, then the bright sources' excess, each
    /// summed with a cone that leaves out ε F / its largest luminance ([`AngularIntegral`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<PassReport>,
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
    /// The bright sources split off as the frequency method splits them
    /// ([`crate::envmap::bright`]), and the map summed in parts, each with its own cone
    /// ([`AngularIntegral`]), so that what any texel misses is a few ε F ∫ρ̂, F the map's mean
    /// luminance, whatever the sun. `Off`: the paper's truncation, one cone for the whole map,
    /// which misses up to ε L_max ∫ρ̂: under a sun 10⁴ × the sky, 10⁴ ε of the sky's level.
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
    Radial(truncation::Truncation),
    View(CutoffTable),
}

impl Cone {
    /// The cone of `model`'s lobe that leaves out ε of its weight.
    fn new(model: &Model, epsilon: f64) -> Self {
        match model.centre() {
            Some(_) => Cone::Radial(truncation::radial_truncation(|x| model.lobe(x)[0], epsilon)),
            None => Cone::View(CutoffTable::of_model(model, epsilon, REFERENCE_CUTOFF_BINS)),
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
                truncation::reference_rule(env.grid(), &|x: f64| model.lobe(x)[0], t.theta_star, height, epsilon)
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

/// One part of the environment (a luminance band, or the bright sources' excess) summed with
/// its own cone: the one that leaves out ε F / Y_max of the lobe, Y_max the part's largest
/// luminance, so that every part misses at most ε F ∫ρ̂ ([`AngularIntegral`]).
struct Pass {
    /// The part (zero elsewhere), with the texel rule chosen for its ε.
    env: ConeIntegrator,
    /// Row-major indices of its texels when they are fewer than a cone holds (then visited one
    /// by one); `None`: the cone's rows.
    texels: Option<Vec<usize>>,
    cone: Cone,
    report: PassReport,
}

/// One part of the angular reference's environment, in figures (for documents).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PassReport {
    /// The part's largest luminance (for the bright sources, the largest excess).
    pub max_luminance: f64,
    /// Texels with radiance.
    pub texels: usize,
    /// The share of the lobe's weight its cone leaves out.
    pub epsilon: f64,
    /// Its widest cone half-angle θ*, in radians.
    pub cone_angle: f64,
    /// Sub-samples per texel axis of its texel rule.
    pub subsamples: usize,
}

impl Pass {
    /// `part` (lat-long) summed with the cone that leaves out `epsilon` of `model`'s lobe and
    /// the texel rule that misplaces at most ε/10 of it on an output of `height` rows; `dense`:
    /// by the cone's rows whatever its texels, else one by one when fewer than a cone holds.
    fn new(
        model: &Model,
        part: &EnvMap,
        max_luminance: f64,
        epsilon: f64,
        height: usize,
        dense: bool,
    ) -> Result<(Self, RuleChoice), PrefilterError> {
        let (env, cone, choice) = Cone::prepared(model, part, epsilon, height)?;
        let lit: Vec<usize> =
            (part.image().pixels.iter().enumerate()).filter(|(_, p)| **p != [0.0; 3]).map(|(i, _)| i).collect();
        // A cone of half-angle θ holds (1 − cos θ)/2 of the sphere's texels, roughly.
        let in_cone = (1.0 - cone.widest().min(PI).cos()) / 2.0 * part.texel_count() as f64;
        let report = PassReport {
            max_luminance,
            texels: lit.len(),
            epsilon: cone.left_out(),
            cone_angle: cone.widest(),
            subsamples: choice.rule.subsamples(),
        };
        let texels = (!dense && (lit.len() as f64) < in_cone).then_some(lit);
        Ok((Pass { env, texels, cone, report }, choice))
    }

    /// The part's share of B(R) for `view`.
    fn texel(&self, model: &Model, r: DVec3, view: DVec3) -> [f64; 3] {
        cone_sum(model, &self.cone, r, view, |theta_star, f| match &self.texels {
            Some(texels) => self.env.integrate_texels(texels, r, theta_star, f),
            None => self.env.integrate(r, theta_star, f),
        })
    }

    /// The part's map for `view` on a `width`×`height` lat-long grid: for a dense part the
    /// paths of [`angular`] (the zonal FFT for a radial lobe on an output as wide as the
    /// input), for a sparse one its texels per output texel.
    fn map(
        &self,
        model: &Model,
        view: DVec3,
        width: usize,
        height: usize,
        progress: &dyn Progress,
    ) -> Result<RgbImage, PrefilterError> {
        match (&self.texels, &self.cone) {
            (None, Cone::Radial(t)) => {
                Ok(angular::radial_map(&self.env, |x| model.lobe(x)[0], t.theta_star, width, height, progress)?)
            }
            (None, Cone::View(cutoff)) => {
                Ok(angular::view_map(&self.env, model, cutoff, view, width, height, progress))
            }
            (Some(_), _) => {
                let grid = LatLong::new(width, height);
                let mut map = RgbImage::new(width, height);
                map.pixels.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
                    for (x, px) in row.iter_mut().enumerate() {
                        let v = self.texel(model, grid.texel_direction(x, y), view);
                        *px = v.map(|c| c as f32);
                    }
                });
                Ok(map)
            }
        }
    }
}

/// The angular reference's integral for one model and environment, set up as `--method angular`
/// sets it up for an output of a given height: App. D's truncation at ε with the texel rule
/// that misplaces at most ε/10 of the lobe ([`angular`]), and, unless the bright rule is `Off`,
/// the environment in parts, each with its own cone.
///
/// **Why parts.** One cone for the whole map leaves ε of each lobe out, so a texel misses up to
/// ε Y_max ∫ρ̂: under a sun 10⁴× the sky, at ε = 0.001, ten times the sky's level. So the map is
/// split as the frequency method splits it (the bright sources' excess over T, `--bright`), and
/// the remainder is cut into luminance bands of ratio 4 down to F, the remainder's mean
/// luminance ([`luminance_bands`]). The band below F takes the cone of ε; every other part, of
/// largest luminance Y_max, the cone that leaves out ε F / Y_max. Each part then misses at most
/// ε F ∫ρ̂, so a texel misses at most (parts) × ε F ∫ρ̂ whatever the sun: relative to the map's
/// mean, not to its brightest texel. The brighter parts are few texels, and those are visited one
/// by one ([`Pass`]). [`angular_reference`] computes whole maps with it,
/// [`AngularIntegral::texel`] single texels (`prefilter --verify`).
pub struct AngularIntegral<'m> {
    model: &'m Model,
    /// The whole map (`--bright off`) or its band below F, with the cone of ε.
    floor: Pass,
    /// The bands above F, brightest first, then the bright sources' excess.
    parts: Vec<Pass>,
    bright: BrightReport,
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
        if settings.bright == BrightRule::Off {
            let (floor, choice) = Pass::new(model, env, f64::NAN, epsilon, height, true)?;
            return Ok(AngularIntegral {
                model,
                floor,
                parts: Vec::new(),
                bright: BrightReport::default(),
                choice,
                epsilon,
            });
        }
        let (remainder, sources) = split(env, settings.bright);
        let floor_luminance = mean_luminance(&remainder);
        // Never looser than ε, and no tighter than 10⁻¹² unless ε itself is.
        let epsilon_of = |y_max: f64| (epsilon * floor_luminance / y_max.max(1e-300)).max(1e-12).min(epsilon);
        let mut bands = luminance_bands(&remainder, floor_luminance);
        let below = bands.pop().expect("luminance_bands returns the floor band");
        let (floor, choice) = Pass::new(model, &below.map, below.upper, epsilon, height, true)?;
        let mut parts = Vec::new();
        for band in bands.iter().filter(|b| b.texels > 0) {
            parts.push(Pass::new(model, &band.map, band.upper, epsilon_of(band.upper), height, false)?.0);
        }
        if !sources.is_empty() {
            let mut excess = RgbImage::new(env.image().width, env.image().height);
            sources.add_to_latlong(&mut excess);
            let excess = EnvMap::latlong(excess).map_err(PrefilterError::Resample)?;
            let e_max = sources.texels.iter().map(|t| t.excess.iter().sum::<f64>() / 3.0).fold(0.0, f64::max);
            parts.push(Pass::new(model, &excess, e_max, epsilon_of(e_max), height, false)?.0);
        }
        Ok(AngularIntegral { model, floor, parts, bright: sources.report(), choice, epsilon })
    }

    /// The widest cone half-angle θ* of the floor's cone, in radians (the brighter parts' cones
    /// are wider).
    pub fn cone_angle(&self) -> f64 {
        self.floor.cone.widest()
    }

    /// Sub-samples per texel axis of the floor's texel rule.
    pub fn subsamples(&self) -> usize {
        self.choice.rule.subsamples()
    }

    /// Truncation and texel rule, for a document.
    pub fn report(&self, path: AngularPath) -> AngularReport {
        AngularReport {
            epsilon: self.epsilon,
            epsilon_achieved: self.floor.cone.left_out(),
            cone_angle: self.cone_angle(),
            subsamples: self.subsamples(),
            quadrature_error: self.choice.estimated_error,
            path,
            bright: self.bright,
            floor_luminance: (!self.parts.is_empty()).then_some(self.floor.report.max_luminance),
            parts: self.parts.iter().map(|p| p.report).collect(),
        }
    }

    /// B(R) for one reflection vector `r` (unit) and `view` (ignored by radially symmetric
    /// lobes): the floor's cone sum (as [`angular::radial_map`] and [`angular::view_map`]
    /// compute it per texel) and every part's, added in the order and with the roundings of
    /// [`angular_reference`], so that a map and its texels agree to the bit.
    pub fn texel(&self, r: DVec3, view: DVec3) -> [f64; 3] {
        let floor = self.floor.texel(self.model, r, view);
        if self.parts.is_empty() {
            return floor;
        }
        let mut acc = floor.map(|c| c as f32 as f64);
        for part in &self.parts {
            let v = part.texel(self.model, r, view).map(|c| c as f32 as f64);
            acc = [0, 1, 2].map(|c| (acc[c] + v[c]) as f32 as f64);
        }
        acc
    }

    /// The whole map for `view`: the floor's, then every part's added.
    fn map(
        &self,
        view: DVec3,
        width: usize,
        height: usize,
        progress: &dyn Progress,
    ) -> Result<RgbImage, PrefilterError> {
        let mut map = self.floor.map(self.model, view, width, height, progress)?;
        for part in &self.parts {
            let add = part.map(self.model, view, width, height, &crate::progress::NoProgress)?;
            for (px, a) in map.pixels.iter_mut().zip(&add.pixels) {
                *px = [0, 1, 2].map(|c| (px[c] as f64 + a[c] as f64) as f32);
            }
        }
        Ok(map)
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

/// The angular reference (App. D): for radially symmetric BRDFs one map (views ignored),
/// otherwise one reflection map per view, on a `width`×`height` lat-long grid, as
/// [`AngularIntegral`] sets it up: the lobe truncated as `settings` say, its texel integrals by
/// the smallest Gauss–Legendre rule that misplaces at most ε/10 of its weight ([`angular`]). No
/// spherical harmonics are involved.
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
    match &integral.floor.cone {
        Cone::Radial(_) => {
            let map = integral.map(DVec3::Z, width, height, progress)?;
            let path = if width == integral.floor.env.grid().width { AngularPath::Zonal } else { AngularPath::ConeSum };
            Ok(AngularMaps { maps: vec![map], report: integral.report(path) })
        }
        Cone::View(_) => {
            progress.start("angular", (views.len() * height) as u64);
            let maps = views.iter().map(|&v| integral.map(v, width, height, progress)).collect::<Result<_, _>>()?;
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

    /// A 64×32 map's reference for `view` three ways: App. D at ε = 10⁻⁷ (nearly exact), App. D
    /// at ε = 10⁻³ (one cone) and the default at ε = 10⁻³ (in parts), with the errors of the
    /// latter two against the first.
    struct Truncations {
        exact: RgbImage,
        one_cone: crate::metrics::Metrics,
        honest: AngularMaps,
        parts: crate::metrics::Metrics,
    }

    fn truncations(model: &Model, env: &EnvMap, view: DVec3) -> Truncations {
        let map = |settings| angular_maps(model, env, &[view], settings, 64, 32, &NoProgress).unwrap().remove(0);
        let exact = map(AngularSettings::paper(1e-7));
        let (one_cone, _) = compare(&map(AngularSettings::paper(1e-3)), &exact, &[]).unwrap();
        let honest = angular_reference(model, env, &[view], AngularSettings::new(1e-3), 64, 32, &NoProgress).unwrap();
        let (parts, _) = compare(&honest.maps[0], &exact, &[]).unwrap();
        Truncations { exact, one_cone, honest, parts }
    }

    #[test]
    fn bright_sources_apart_make_the_reference_honest_per_texel() {
        // The paper's truncation at ε = 10⁻³ leaves 0.1 % of each lobe out, 20 × the sky's level
        // under this sun: dark texels come out several per cent low. With the sun summed apart
        // (its cone leaves out ε F / e_max, F the remainder's mean), the same ε agrees with a
        // 10⁻⁷ truncation of the whole map within its bound, and both ways agree when nothing
        // is cut.
        let env = sun_sky();
        let view = DVec3::new(0.3, 0.0, 1.0).normalize();
        for (spec, cosine) in [("phong:s=32", true), ("torrance-sparrow:sigma=0.3", false)] {
            let model = Model::new(Brdf::parse(spec).unwrap(), cosine).unwrap();
            let Truncations { exact, one_cone: paper, honest, parts: apart } = truncations(&model, &env, view);
            assert!(paper.max_texel_error > 0.03, "{spec}: the paper's truncation is off by {paper:?}");
            // The bound (parts + 1) ε F ∫ρ̂ is ~0.5 % of the darkest texels here.
            assert!(apart.max_texel_error < 5e-3, "{spec}: bright apart is off by {apart:?}");
            assert_eq!(honest.report.bright.texels, 4, "{spec}: {:?}", honest.report.bright);
            assert!(honest.report.bright.energy_fraction > 0.9, "{:?}", honest.report.bright);
            let tight = angular_maps(&model, &env, &[view], AngularSettings::new(1e-7), 64, 32, &NoProgress);
            let (same, _) = compare(&tight.unwrap()[0], &exact, &[]).unwrap();
            // Within the texel rules' tolerance (ε/10 of the lobe, times a sun of 2 · 10⁴).
            assert!(same.max_texel_error < 1e-3, "{spec}: {same:?}");
        }
    }

    #[test]
    fn luminance_bands_make_the_reference_honest_under_a_wide_bright_window() {
        // A window of 30 over a sixth of the sky's width, 1 + z⁺ elsewhere: too wide to be a
        // bright source (nothing lies above the threshold), so one cone of ε = 10⁻³ misses up
        // to ε × 29 ∫ρ̂ (29 the window's luminance), 1.5 % of a texel of 2. In luminance bands
        // each part misses at most ε F ∫ρ̂ with F the mean: the error against a 10⁻⁷
        // truncation drops by the ratio of the bounds.
        let grid = LatLong::new(64, 32);
        let env = EnvMap::latlong(RgbImage::from_fn(64, 32, |x, y| {
            let d = grid.texel_direction(x, y);
            let v = if (20..31).contains(&x) && (6..16).contains(&y) { 30.0 } else { 1.0 + d.z.max(0.0) };
            [v as f32, v as f32, (0.9 * v) as f32]
        }))
        .unwrap();
        let view = DVec3::new(0.3, 0.0, 1.0).normalize();
        for (spec, cosine) in [("phong:s=32", true), ("torrance-sparrow:sigma=0.3", false)] {
            let model = Model::new(Brdf::parse(spec).unwrap(), cosine).unwrap();
            let Truncations { one_cone, honest: banded, parts: bands, .. } = truncations(&model, &env, view);
            assert_eq!(banded.report.bright.texels, 0, "{:?}", banded.report.bright);
            // Bands (1.8, 7.25], (7.25, 29] above F = 1.81: the bound drops 29 / (3 × 1.81) ≈ 5×
            // (measured: 4.1× for Phong, 6.5× for Torrance-Sparrow).
            assert_eq!(banded.report.parts.len(), 2, "{:?}", banded.report);
            assert!(one_cone.max_texel_error > 0.006, "{spec}: {one_cone:?}");
            assert!(bands.max_texel_error < 0.3 * one_cone.max_texel_error, "{spec}: {bands:?} vs {one_cone:?}");
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
