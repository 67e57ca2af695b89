//! The whole prefilter, both ways: frequency space (App. C steps 1–3) and the angular reference.

use super::angular::{self, ConeIntegrator, CutoffTable};
use super::brdf_sh::BrdfSh;
use super::model::{Model, ModelError};
use super::shrm::{self, Shrm, ShrmError};
use crate::envmap::zonal::RuleChoice;
use crate::envmap::EnvMap;
use crate::io::RgbImage;
use crate::progress::Progress;
use crate::sh::project::{project, ProjectError};
use crate::sh::ShCoeffs;
use glam::DVec3;
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
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum AngularPath {
    /// A radially symmetric lobe on an output as wide as the input: FFT convolutions in φ
    /// ([`crate::envmap::zonal`]).
    Zonal,
    /// The cone sum per output texel (3-D BRDFs, or other output widths).
    ConeSum,
}

/// What the angular reference used: no SH orders, only the truncation and the texel rule.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
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
}

/// The angular reference's maps and what it used.
pub struct AngularMaps {
    /// One map per view (one map in all for radially symmetric BRDFs).
    pub maps: Vec<RgbImage>,
    /// Truncation and texel rule.
    pub report: AngularReport,
}

/// The lobe's truncation cone: one angle for radially symmetric lobes, θ*(θ_o) otherwise.
enum Cone {
    Radial(angular::Truncation),
    View(CutoffTable),
}

/// The angular reference's integral for one model and environment, set up as `--method angular`
/// sets it up for an output of a given height: the lobe truncated at ε (App. D) and the texel
/// rule that misplaces at most ε/10 of its weight ([`angular`]). [`angular_reference`] computes
/// whole maps with it, [`AngularIntegral::texel`] single texels (`prefilter --verify`).
pub struct AngularIntegral<'m> {
    model: &'m Model,
    env: ConeIntegrator,
    cone: Cone,
    choice: RuleChoice,
    epsilon: f64,
}

impl<'m> AngularIntegral<'m> {
    /// The integral of `model` over the lat-long `env`, truncated at `epsilon`, with the texel
    /// rule chosen for an output of `height` rows.
    pub fn new(model: &'m Model, env: &EnvMap, epsilon: f64, height: usize) -> Result<Self, PrefilterError> {
        let env = ConeIntegrator::new(env)?;
        let (cone, choice) = if model.centre().is_some() {
            let u = |x: f64| model.lobe(x)[0];
            let truncation = angular::radial_truncation(u, epsilon);
            let choice = angular::reference_rule(env.grid(), &u, truncation.theta_star, height, epsilon);
            (Cone::Radial(truncation), choice)
        } else {
            let cutoff = CutoffTable::new(|wi, wo| model.rho_hat_grey(wi, wo), epsilon, 65);
            let choice = env.rule_for_view(model, &cutoff, epsilon / 10.0);
            (Cone::View(cutoff), choice)
        };
        let env = env.with_rule(choice.rule.clone());
        Ok(AngularIntegral { model, env, cone, choice, epsilon })
    }

    /// The widest cone half-angle θ*, in radians: no reflection vector farther than this from a
    /// texel of the environment sees it.
    pub fn cone_angle(&self) -> f64 {
        match &self.cone {
            Cone::Radial(t) => t.theta_star,
            Cone::View(cutoff) => cutoff.max(),
        }
    }

    /// Sub-samples per texel axis of the texel rule.
    pub fn subsamples(&self) -> usize {
        self.choice.rule.subsamples()
    }

    /// Truncation and texel rule, for a document.
    pub fn report(&self, path: AngularPath) -> AngularReport {
        AngularReport {
            epsilon: self.epsilon,
            epsilon_achieved: match &self.cone {
                Cone::Radial(t) => t.left_out,
                Cone::View(cutoff) => cutoff.left_out(),
            },
            cone_angle: self.cone_angle(),
            subsamples: self.subsamples(),
            quadrature_error: self.choice.estimated_error,
            path,
        }
    }

    /// B(R) for one reflection vector `r` (unit) and `view` (ignored by radially symmetric
    /// lobes): the sum [`angular::radial_map`] and [`angular::view_map`] compute per texel.
    pub fn texel(&self, r: DVec3, view: DVec3) -> [f64; 3] {
        let model = self.model;
        match &self.cone {
            Cone::Radial(t) => {
                self.env.integrate(r, t.theta_star.clamp(1e-9, std::f64::consts::PI), |l| [model.lobe(r.dot(l))[0]; 3])
            }
            Cone::View(cutoff) => match model.prepare_view(r, view) {
                Some(p) => {
                    let theta_star = cutoff.at(r.dot(view).clamp(-1.0, 1.0).acos());
                    self.env.integrate(r, theta_star, |l| model.rho_hat_prepared(&p, l))
                }
                None => [0.0; 3],
            },
        }
    }
}

/// The angular reference (App. D): for radially symmetric BRDFs one map (views ignored),
/// otherwise one reflection map per view, on a `width`×`height` lat-long grid. The lobe is
/// truncated at ε, and its texel integrals use the smallest Gauss–Legendre rule that misplaces
/// at most ε/10 of its weight ([`angular`]). No spherical harmonics are involved.
pub fn angular_reference(
    model: &Model,
    env: &EnvMap,
    views: &[DVec3],
    epsilon: f64,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> Result<AngularMaps, PrefilterError> {
    let integral = AngularIntegral::new(model, env, epsilon, height)?;
    let cone = &integral.env;
    match &integral.cone {
        Cone::Radial(t) => {
            let u = |x: f64| model.lobe(x)[0];
            let map = angular::radial_map(cone, u, t.theta_star, width, height, progress)?;
            let path = if width == cone.grid().width { AngularPath::Zonal } else { AngularPath::ConeSum };
            Ok(AngularMaps { maps: vec![map], report: integral.report(path) })
        }
        Cone::View(cutoff) => {
            progress.start("angular", (views.len() * height) as u64);
            let maps =
                views.iter().map(|&v| angular::view_map(cone, model, cutoff, v, width, height, progress)).collect();
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
    epsilon: f64,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> Result<Vec<RgbImage>, PrefilterError> {
    Ok(angular_reference(model, env, views, epsilon, width, height, progress)?.maps)
}
