//! The `prefilter` stage as one library call: frequency-space prefiltering into a spherical
//! harmonic reflection map and the maps derived from it (Ramamoorthi & Hanrahan 2002), or the
//! angular reference (App. D).
//!
//! [`run`] follows the paper's algorithm: check the request, decide once how to bake it (a
//! [`Plan`]), bake (a [`Bake`]: the maps, the SHRM, the orders and what was done), then derive
//! the irradiance map, check texels against the angular integral if asked, and write the
//! document from the bake.

use super::angular::as_latlong;
use super::brdf_sh::BrdfSh;
use super::document::{layer_name, Lighting as DocLighting, MapEntry, ShrmBody, FORMAT, VERSION};
use super::in_angle::{self, angle_maps};
use super::model::{residual_bound, Centre, Model, ModelError};
use super::orders::OrderRule;
use super::pipeline::{self, AngularReport, AngularSettings, Lighting, Orders, PrefilterError};
use super::ring_free::{self, Report, Settings};
use super::shrm::{self, Shrm};
use super::tuning::ANGULAR_EPSILON;
use super::verify::{self, MapCheck, Verification, Verifier, VerifyError};
use crate::brdf::Brdf;
use crate::envmap::bright::{BrightReport, BrightRule};
use crate::envmap::{self, EnvMap, EnvMapError, Layout};
use crate::io::{Document, Provenance, RgbImage};
use crate::progress::Progress;
use crate::sh::window::{Window, WindowReport};
use crate::sh::ShCoeffs;
use crate::sh::{count, lm};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::time::Instant;

/// Frequency space or the angular reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Spherical-harmonic prefiltering (R&H 2002 App. C).
    Frequency,
    /// Direct integration over the environment per output texel, BRDF truncated at ε (App. D),
    /// bright sources apart with a wider cone (--bright).
    Angular,
}

impl Method {
    /// The name used on the command line and in documents.
    pub fn name(self) -> &'static str {
        match self {
            Method::Frequency => "frequency",
            Method::Angular => "angular",
        }
    }
}

/// One reflection map to compute: its file (recorded in the document) and view direction.
#[derive(Clone, Debug, PartialEq)]
pub struct MapRequest {
    /// The file the caller writes it to.
    pub file: String,
    /// View direction, unit, towards the viewer (ignored by radially symmetric BRDFs).
    pub view: DVec3,
}

/// What `prefilter` computes.
#[derive(Clone, Debug)]
pub struct Config {
    /// The BRDF.
    pub brdf: Brdf,
    /// Fold max(N·ω_i, 0) into ρ̂ on the general path (off: eq. 11 used as ρ̂ itself).
    pub cosine: bool,
    /// Frequency space or the angular reference.
    pub method: Method,
    /// Tolerance: F_B, P_B keep 1 − ε of the BRDF energy (§5.1); the angular truncation.
    pub epsilon: f64,
    /// Fixed orders (F_B, P_B) instead of choosing them from ε.
    pub orders: Option<(usize, usize)>,
    /// Largest P_B the ε search considers.
    pub max_p: usize,
    /// How the orders are chosen from ε.
    pub order_rule: OrderRule,
    /// Bright sources apart (filtered in angle).
    pub bright: BrightRule,
    /// The window at synthesis.
    pub window: Window,
    /// Compute App. B's bound.
    pub bound: bool,
    /// Size of the lat-long grid of reflection vectors; default 2S × S, S = clamp(10 F_B, 32, 512).
    pub size: Option<(usize, usize)>,
    /// Layout of the images produced (lat-long or a cross).
    pub output_layout: Layout,
    /// Produce the SHRM layers, recorded in the document under this file name.
    pub shrm_file: Option<String>,
    /// Store global coefficients (eq. 7–8) instead of local ones (eq. 6).
    pub global: bool,
    /// Reflection maps (eq. 12).
    pub maps: Vec<MapRequest>,
    /// Kautz–McCool slices B(α, β, θ_o) to produce (0: none).
    pub kautz_mccool_slices: usize,
    /// Produce the irradiance map (Lambert only).
    pub irradiance: bool,
    /// Check this many texels of every map against the angular integral (`--verify`).
    pub verify: Option<usize>,
    /// The lighting's name, for the document.
    pub source: String,
    /// The command line, for the document's provenance.
    pub args: Vec<String>,
}

impl Config {
    /// A frequency-space config for `brdf` with the defaults of the command line.
    pub fn new(brdf: Brdf) -> Self {
        Config {
            brdf,
            cosine: true,
            method: Method::Frequency,
            epsilon: 0.01,
            orders: None,
            max_p: 6,
            order_rule: OrderRule::Texel,
            bright: BrightRule::Auto,
            window: Window::Nonneg,
            bound: false,
            size: None,
            output_layout: Layout::LatLong,
            shrm_file: None,
            global: false,
            maps: Vec::new(),
            kautz_mccool_slices: 0,
            irradiance: false,
            verify: None,
            source: String::new(),
            args: Vec::new(),
        }
    }
}

/// What `prefilter` produces; images are in the config's output layout.
#[derive(Clone, Debug)]
pub struct Output {
    /// The `prtkit.shrm` document.
    pub document: Document<ShrmBody>,
    /// The reflection maps, in the order of the config's requests.
    pub maps: Vec<RgbImage>,
    /// The SHRM as named layers `B<p><±q>`, if asked.
    pub shrm_layers: Option<Vec<(String, RgbImage)>>,
    /// Kautz–McCool slices as named layers theta00…, if asked.
    pub kautz_mccool: Option<Vec<(String, RgbImage)>>,
    /// The irradiance map E(N), if asked.
    pub irradiance: Option<RgbImage>,
    /// The `--json` summary.
    pub summary: Summary,
}

/// The machine-readable summary (`prefilter --json`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    /// Canonical BRDF spec.
    pub brdf: String,
    /// The method.
    pub method: Method,
    /// F_B.
    pub f_b: usize,
    /// P_B.
    pub p_b: usize,
    /// BRDF energy missed by (F_B, P_B).
    pub epsilon_achieved: f64,
    /// App. B's bound, if asked.
    pub epsilon_bound: Option<f64>,
    /// Grid width.
    pub width: usize,
    /// Grid height.
    pub height: usize,
    /// The `--verify` figures.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verification: Option<Verification>,
    /// Seconds per step.
    pub timings: Timings,
}

/// Seconds spent in each step.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Timings {
    /// The SHRM: the bright split, the projection, the order search and the SHRM itself.
    pub shrm_seconds: f64,
    /// Reflection maps from the SHRM.
    pub maps_seconds: f64,
    /// The angular reference.
    pub angular_seconds: f64,
    /// `--verify`.
    #[serde(default)]
    pub verify_seconds: f64,
    /// Everything.
    pub total_seconds: f64,
}

/// Errors of the stage. None names a flag: the command line words those that come from one.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// ε is out of range.
    #[error("ε = {0} is outside (0, 1)")]
    Epsilon(f64),
    /// The output layout is not one the maps can be written in.
    #[error("the output layout must be latlong, cross-horizontal or cross-vertical, got {0}")]
    Layout(Layout),
    /// The BRDF cannot be prefiltered.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The irradiance map needs Lambert.
    #[error("an irradiance map needs a Lambert BRDF (it is Lambert's reflection map × π/albedo)")]
    IrradianceNeedsLambert,
    /// The angular reference was asked for an SHRM or Kautz–McCool slices.
    #[error("the angular reference writes reflection maps only (and the irradiance map)")]
    AngularMapsOnly,
    /// The angular reference was given SH coefficients.
    #[error("the angular reference needs the environment map, not SH coefficients")]
    AngularNeedsMap,
    /// The angular reference was given orders.
    #[error("the angular reference takes no orders: it uses no spherical harmonics (ε is its truncation)")]
    AngularTakesNoOrders,
    /// The prefilter failed.
    #[error("cannot prefilter {source_name}: {error}")]
    Prefilter {
        /// The lighting.
        source_name: String,
        /// Why.
        error: PrefilterError,
    },
    /// Resampling to the output layout failed.
    #[error(transparent)]
    Resample(#[from] EnvMapError),
    /// The verification needs the environment map.
    #[error("checking texels needs the environment map, not SH coefficients (the exact values integrate the map)")]
    VerifyNeedsMap,
    /// The verification failed.
    #[error(transparent)]
    Verify(#[from] VerifyError),
}

/// Runs `prefilter` with `lighting` (a map, or SH coefficients for the frequency method).
pub fn run(config: &Config, lighting: Lighting<'_>, progress: &dyn Progress) -> Result<Output, Error> {
    let start = Instant::now();
    let model = checked_model(config, lighting)?;
    let plan = Plan::new(config, &model, lighting)?;
    let mut bake = plan.bake(config, &model, lighting, progress)?;
    // Lambert's map is radiance (albedo/π)·E(N): the irradiance is that × π/albedo.
    let irradiance_scale = irradiance_scale(&model);
    let irradiance = config.irradiance.then(|| {
        let mut e = bake.maps[0].clone();
        e.pixels.iter_mut().flatten().for_each(|c| *c *= irradiance_scale);
        e
    });
    let verification = match (config.verify, lighting) {
        (Some(n), Lighting::Map(env)) => {
            let t = Instant::now();
            let checks = map_checks(config, &bake.maps, irradiance.as_ref(), irradiance_scale);
            let verifier = Verifier::new(&model, &as_latlong(env)?, bake.size.1, n)?;
            let verification = verifier.verify(&checks, progress)?;
            bake.timings.verify_seconds = t.elapsed().as_secs_f64();
            Some(verification)
        }
        _ => None,
    };
    let layout = config.output_layout;
    let irradiance = irradiance.map(|e| to_output_layout(&e, layout)).transpose()?;
    let maps: Vec<RgbImage> =
        bake.maps.iter().take(config.maps.len()).map(|m| to_output_layout(m, layout)).collect::<Result<_, _>>()?;
    let layer_names: Vec<String> = (0..count(bake.p_b))
        .map(|i| {
            let (p, q) = lm(i);
            layer_name(p, q)
        })
        .collect();
    let shrm_layers = match (&config.shrm_file, &bake.shrm) {
        (Some(_), Some(s)) => Some(named_layers(layer_names.iter().cloned().zip(&s.layers), layout)?),
        _ => None,
    };
    let kautz_mccool = match (config.kautz_mccool_slices, &bake.shrm) {
        (0, _) | (_, None) => None,
        (slices, Some(s)) => {
            let slices = shrm::kautz_mccool(s, slices);
            Some(named_layers((0..).map(|k| format!("theta{k:02}")).zip(&slices), layout)?)
        }
    };
    bake.timings.total_seconds = start.elapsed().as_secs_f64();
    let (document, summary) = document(config, &model, lighting, &bake, layer_names, &shrm_layers, verification);
    Ok(Output { document, maps, shrm_layers, kautz_mccool, irradiance, summary })
}

/// The request checked before any work: ε, the output layout, the BRDF (its prefilter model),
/// and what the irradiance map and the texel check need.
fn checked_model(config: &Config, lighting: Lighting<'_>) -> Result<Model, Error> {
    if !(config.epsilon > 0.0 && config.epsilon < 1.0) {
        return Err(Error::Epsilon(config.epsilon));
    }
    if !matches!(config.output_layout, Layout::LatLong | Layout::CrossHorizontal | Layout::CrossVertical) {
        return Err(Error::Layout(config.output_layout));
    }
    let model = Model::new(config.brdf.clone(), config.cosine)?;
    if config.irradiance && model.centre() != Some(Centre::Normal) {
        return Err(Error::IrradianceNeedsLambert);
    }
    if let Some(n) = config.verify {
        verify::check_texels(n)?;
        if matches!(lighting, Lighting::Coefficients(_)) {
            return Err(Error::VerifyNeedsMap);
        }
    }
    Ok(model)
}

/// π/albedo: Lambert's reflection map times it is the irradiance. The model is
/// view-independent, so any of its maps will do.
fn irradiance_scale(model: &Model) -> f32 {
    let albedo = model.brdf().reflection_lobe(1.0).unwrap_or(1.0 / PI) * PI;
    (PI / albedo.max(1e-12)) as f32
}

/// What `--verify` checks: every requested map, and the irradiance map at its scale.
fn map_checks<'a>(
    config: &Config,
    maps: &'a [RgbImage],
    irradiance: Option<&'a RgbImage>,
    irradiance_scale: f32,
) -> Vec<MapCheck<'a>> {
    let mut checks: Vec<MapCheck> = config
        .maps
        .iter()
        .zip(maps)
        .map(|(m, image)| MapCheck { name: m.file.clone(), image, view: m.view, scale: 1.0 })
        .collect();
    if let Some(image) = irradiance {
        let scale = irradiance_scale as f64;
        checks.push(MapCheck { name: "irradiance".into(), image, view: DVec3::Z, scale });
    }
    checks
}

/// Named lat-long layers in the output layout.
fn named_layers<'a>(
    layers: impl Iterator<Item = (String, &'a RgbImage)>,
    layout: Layout,
) -> Result<Vec<(String, RgbImage)>, Error> {
    layers.map(|(name, layer)| Ok((name, to_output_layout(layer, layout)?))).collect()
}

/// How a bake is made, decided once from the request and the lighting.
#[derive(Clone, Copy)]
enum Plan<'a> {
    /// R&H 2002 App. C as written ([`pipeline::frequency`]): orders from the BRDF's energy
    /// (§5.1) or given, the whole lighting through spherical harmonics, no window. The request
    /// asks for it with the energy rule (or fixed orders), no bright sources apart and no window.
    Paper { orders: Orders },
    /// The ring-free bake ([`ring_free`]): bright sources apart, orders for this lighting, the
    /// window; the maps from the SHRM, with the bright texels and the grazing texels in angle.
    RingFree { settings: Settings },
    /// Every texel of the maps in angle ([`in_angle`]), no SHRM: F_B = P_B = 0.
    InAngle { env: &'a EnvMap },
    /// The ring-free SHRM for its file, and the maps in angle on its grid where the grid allows
    /// ([`in_angle::fits`]), else from it.
    ShrmAndInAngle { env: &'a EnvMap, settings: Settings },
    /// The angular reference (App. D), no spherical harmonics.
    Angular { env: &'a EnvMap },
}

impl<'a> Plan<'a> {
    /// The plan for `config`: the method, then for the frequency method the paper's algorithm
    /// when asked for, else the ring-free bake with its maps in angle where [`in_angle`] prefers
    /// them (never under `bound`, which is about the expansion).
    fn new(config: &Config, model: &Model, lighting: Lighting<'a>) -> Result<Self, Error> {
        if config.method == Method::Angular {
            return match (shrm_wanted(config), lighting, config.orders) {
                (true, _, _) => Err(Error::AngularMapsOnly),
                (false, Lighting::Coefficients(_), _) => Err(Error::AngularNeedsMap),
                (false, Lighting::Map(_), Some(_)) => Err(Error::AngularTakesNoOrders),
                (false, Lighting::Map(env), None) => Ok(Plan::Angular { env }),
            };
        }
        let paper = config.bright == BrightRule::Off
            && config.window == Window::None
            && (config.orders.is_some() || config.order_rule == OrderRule::Energy);
        if paper {
            let orders = match config.orders {
                Some((f, p)) => Orders::Fixed { f, p },
                None => Orders::Epsilon { epsilon: config.epsilon, max_p: config.max_p },
            };
            return Ok(Plan::Paper { orders });
        }
        let settings = Settings {
            epsilon: config.epsilon,
            rule: config.order_rule,
            orders: config.orders,
            max_p: config.max_p,
            bright: config.bright,
            window: config.window,
            size: config.size,
        };
        Ok(match lighting {
            Lighting::Map(env)
                if !config.maps.is_empty()
                    && !config.bound
                    && in_angle::prefers_angle(model, &settings, env)
                    && in_angle::fits(model, env, settings.size) =>
            {
                match shrm_wanted(config) {
                    false => Plan::InAngle { env },
                    true => Plan::ShrmAndInAngle { env, settings },
                }
            }
            _ => Plan::RingFree { settings },
        })
    }

    /// Executes the plan.
    fn bake(
        self,
        config: &Config,
        model: &Model,
        lighting: Lighting<'_>,
        progress: &dyn Progress,
    ) -> Result<Bake, Error> {
        let fail = |error: PrefilterError| Error::Prefilter { source_name: config.source.clone(), error };
        // The views of the maps; the irradiance alone is Lambert's map for any view.
        let views: Vec<DVec3> = match config.maps.is_empty() {
            true if config.irradiance => vec![DVec3::Z],
            _ => config.maps.iter().map(|m| m.view).collect(),
        };
        match self {
            Plan::Paper { orders } => bake_paper(config, model, lighting, orders, &views, progress).map_err(fail),
            Plan::RingFree { settings } => bake_ring_free(config, model, lighting, &settings, None, &views, progress),
            Plan::ShrmAndInAngle { env, settings } => {
                bake_ring_free(config, model, lighting, &settings, Some(env), &views, progress)
            }
            Plan::InAngle { env } => {
                let t = Instant::now();
                let done = angle_maps(model, env, &views, config.bright, config.size, progress).map_err(fail)?;
                let mut bake = Bake::without_orders(done.maps, done.size, ANGULAR_EPSILON);
                bake.report = Some(done.report);
                bake.timings.maps_seconds = t.elapsed().as_secs_f64();
                Ok(bake)
            }
            Plan::Angular { env } => bake_angular(config, model, env, &views, progress),
        }
    }
}

/// True when the request asks for the SHRM itself (its file, or Kautz–McCool slices of it).
fn shrm_wanted(config: &Config) -> bool {
    config.shrm_file.is_some() || config.kautz_mccool_slices > 0
}

/// What a plan made: everything the outputs and the document are built from.
#[derive(Clone, Debug)]
struct Bake {
    /// Lat-long reflection maps, one per view (the irradiance's Lambert map when no view was
    /// asked for).
    maps: Vec<RgbImage>,
    /// The SHRM, when it was asked for.
    shrm: Option<Shrm>,
    /// F_B (0 without an expansion).
    f_b: usize,
    /// P_B.
    p_b: usize,
    /// The BRDF energy missed by (F_B, P_B), or the lobe weight the angular passes left out.
    epsilon_achieved: f64,
    /// The order of the lighting's expansion.
    light_order: usize,
    /// App. B's bound, when asked.
    bound: Option<f64>,
    /// The grid (W, H).
    size: (usize, usize),
    /// How the frequency method made it.
    report: Option<Report>,
    /// How the angular reference truncated its lobes.
    reference: Option<AngularReport>,
    /// Seconds per step.
    timings: Timings,
}

impl Bake {
    /// Maps made with no expansion: F_B = P_B = 0, ε achieved the lobe weight left out.
    fn without_orders(maps: Vec<RgbImage>, size: (usize, usize), epsilon_achieved: f64) -> Self {
        Bake {
            maps,
            shrm: None,
            f_b: 0,
            p_b: 0,
            epsilon_achieved,
            light_order: 0,
            bound: None,
            size,
            report: None,
            reference: None,
            timings: Timings::default(),
        }
    }
}

/// [`Plan::Paper`]: [`pipeline::frequency`] on the lighting as the ring-free bake reads it (a
/// map on its lat-long grid), the maps from its SHRM (eq. 12).
fn bake_paper(
    config: &Config,
    model: &Model,
    lighting: Lighting<'_>,
    orders: Orders,
    views: &[DVec3],
    progress: &dyn Progress,
) -> Result<Bake, PrefilterError> {
    let latlong = match lighting {
        Lighting::Map(env) => Some(as_latlong(env).map_err(PrefilterError::Resample)?),
        Lighting::Coefficients(_) => None,
    };
    let read = latlong.as_ref().map_or(lighting, Lighting::Map);
    let t = Instant::now();
    let done = pipeline::frequency(model, read, orders, config.size, progress)?;
    let shrm_seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let maps = shrm::maps_of_local(&done.shrm, views);
    let maps_seconds = t.elapsed().as_secs_f64();
    let report = Report {
        maps: ring_free::MapsFrom::Shrm,
        rule: if config.orders.is_some() { "fixed" } else { "energy" }.into(),
        texel: None,
        bright: BrightReport::default(),
        window: WindowReport { kind: Window::None, t: None },
    };
    Ok(Bake {
        bound: config.bound.then(|| app_b_bound(&done.brdf, &done.lighting, false, lighting)),
        shrm: shrm_wanted(config).then(|| if config.global { shrm::to_global(&done.shrm) } else { done.shrm.clone() }),
        size: (done.shrm.width(), done.shrm.height()),
        f_b: done.brdf.f,
        p_b: done.brdf.p,
        epsilon_achieved: done.epsilon_achieved,
        light_order: done.lighting.order,
        maps,
        report: Some(report),
        reference: None,
        timings: Timings { shrm_seconds, maps_seconds, ..Timings::default() },
    })
}

/// [`Plan::RingFree`] and [`Plan::ShrmAndInAngle`] (`in_angle`): the ring-free SHRM, then the
/// maps, in angle on its grid where [`in_angle::fits`] allows, else from it; then the SHRM file
/// (after the maps, whose window search it carries).
fn bake_ring_free(
    config: &Config,
    model: &Model,
    lighting: Lighting<'_>,
    settings: &Settings,
    in_angle: Option<&EnvMap>,
    views: &[DVec3],
    progress: &dyn Progress,
) -> Result<Bake, Error> {
    let fail = |error: PrefilterError| Error::Prefilter { source_name: config.source.clone(), error };
    let t = Instant::now();
    let mut pre = ring_free::prefilter(model, lighting, settings, progress).map_err(fail)?;
    let shrm_seconds = t.elapsed().as_secs_f64();
    let size = (pre.remainder_shrm.width(), pre.remainder_shrm.height());
    let t = Instant::now();
    // On the SHRM's grid, so the document's size holds for both.
    let maps = match in_angle.filter(|env| in_angle::fits(model, env, Some(size))) {
        Some(env) => {
            let done = angle_maps(model, env, views, config.bright, Some(size), progress).map_err(fail)?;
            pre.report.maps = done.report.maps;
            done.maps
        }
        None => pre.reflection_maps(model, views, progress).map_err(fail)?,
    };
    let maps_seconds = t.elapsed().as_secs_f64();
    let shrm = match shrm_wanted(config) {
        true => Some(pre.shrm(model, config.global, progress).map_err(fail)?),
        false => None,
    };
    let apart = !pre.bright.sources().is_empty();
    Ok(Bake {
        // BRDF energy missed by (F_B, P_B): against the total ∫∫ ρ̂² the coefficients' own
        // quadrature measured (not their sum), so no larger expansion is needed
        // (`tests/prefilter_cli.rs` holds it to one).
        epsilon_achieved: pre.brdf.residual(pre.brdf.f, pre.brdf.p),
        bound: config.bound.then(|| app_b_bound(&pre.brdf, &pre.lighting, apart, lighting)),
        f_b: pre.brdf.f,
        p_b: pre.brdf.p,
        light_order: pre.lighting.order,
        maps,
        shrm,
        size,
        report: Some(pre.report),
        reference: None,
        timings: Timings { shrm_seconds, maps_seconds, ..Timings::default() },
    })
}

/// [`Plan::Angular`]: the angular reference on the lighting's lat-long grid (there is no F_B to
/// size it by), one map for a radially symmetric BRDF whatever the view.
fn bake_angular(
    config: &Config,
    model: &Model,
    env: &EnvMap,
    views: &[DVec3],
    progress: &dyn Progress,
) -> Result<Bake, Error> {
    let latlong = as_latlong(env)?;
    let size = config.size.unwrap_or((latlong.image().width, latlong.image().height));
    let t = Instant::now();
    let settings = AngularSettings { epsilon: config.epsilon, bright: config.bright };
    let reference = pipeline::angular_reference(model, &latlong, views, settings, size.0, size.1, progress)
        .map_err(|error| Error::Prefilter { source_name: config.source.clone(), error })?;
    let images = reference.maps;
    let maps = if model.centre().is_some() { vec![images[0].clone(); views.len()] } else { images };
    let mut bake = Bake::without_orders(maps, size, reference.report.epsilon_achieved);
    bake.reference = Some(reference.report);
    bake.timings.angular_seconds = t.elapsed().as_secs_f64();
    Ok(bake)
}

/// The `prtkit.shrm` document and the `--json` summary of `bake`.
fn document(
    config: &Config,
    model: &Model,
    lighting: Lighting<'_>,
    bake: &Bake,
    layers: Vec<String>,
    shrm_layers: &Option<Vec<(String, RgbImage)>>,
    verification: Option<Verification>,
) -> (Document<ShrmBody>, Summary) {
    let radial = model.centre().is_some();
    let parameterization = match model.centre() {
        Some(Centre::Normal) => "normal",
        _ if model.is_tangent() => "tangent",
        _ => "reflection",
    };
    let body = ShrmBody {
        brdf: model.brdf().spec(),
        cosine: model.cosine(),
        method: config.method.name().into(),
        f_b: bake.f_b,
        p_b: bake.p_b,
        epsilon: config.orders.is_none().then_some(config.epsilon),
        epsilon_achieved: bake.epsilon_achieved,
        epsilon_bound: bake.bound,
        parameterization: parameterization.into(),
        layout: config.output_layout.name().into(),
        width: bake.size.0,
        height: bake.size.1,
        global: config.global,
        shrm_file: config.shrm_file.clone().filter(|_| shrm_layers.is_some()),
        layers,
        lighting: DocLighting { source: config.source.clone(), order: bake.light_order },
        maps: (config.maps.iter())
            .map(|m| MapEntry { file: m.file.clone(), view: (!radial).then(|| m.view.to_array()) })
            .collect(),
        timings: None,
        bake: bake.report.clone(),
        reference: bake.reference.clone(),
        verification: verification.clone(),
    };
    let summary = Summary {
        brdf: body.brdf.clone(),
        method: config.method,
        f_b: bake.f_b,
        p_b: bake.p_b,
        epsilon_achieved: bake.epsilon_achieved,
        epsilon_bound: bake.bound,
        width: bake.size.0,
        height: bake.size.1,
        verification,
        timings: bake.timings,
    };
    let provenance = Provenance::new("prefilter", &config.args, vec![config.source.clone()]);
    let document = Document::new(FORMAT, VERSION, provenance, body);
    let document = match lighting {
        Lighting::Map(env) => document.with_input_orientation(env.orientation().describe()),
        Lighting::Coefficients(_) => document,
    };
    (document, summary)
}

/// A lat-long image in the output layout (a cross is resampled at 4n × 3n, n = H/2).
fn to_output_layout(image: &RgbImage, layout: Layout) -> Result<RgbImage, EnvMapError> {
    if layout == Layout::LatLong {
        return Ok(image.clone());
    }
    let src = EnvMap::latlong(image.clone())?;
    let n = (image.height / 2).max(1);
    let (w, h) = if layout == Layout::CrossVertical { (3 * n, 4 * n) } else { (4 * n, 3 * n) };
    Ok(envmap::resample(&src, layout, w, h, 2)?.image().clone())
}

/// App. B: ε_B ≤ B_res/(Σ|B|² + B_res) with B_res = Λ_{F+1}(ε_L L_tot)(ε_ρ ρ_tot), for the
/// lighting the SH expansion carries (the remainder when `bright_apart`).
fn app_b_bound(brdf: &BrdfSh, light: &ShCoeffs, bright_apart: bool, lighting: Lighting<'_>) -> f64 {
    let f = brdf.f;
    let brdf_res = brdf.residual(f, brdf.p) * brdf.total_energy;
    let captured_light: f64 = light.band_energy().iter().sum();
    let light_total = match lighting {
        Lighting::Map(m) if !bright_apart => crate::sh::project::map_energy(m),
        _ => captured_light,
    };
    let light_res = (light_total - captured_light).max(0.0);
    // Σ|B_lmpq|² with B_lmpq = Λ_l L_lm ρ̂_lpq (eq. 5), per channel.
    let mut captured = 0.0;
    for (i, lc) in light.rgb.iter().enumerate() {
        let (l, _) = lm(i);
        let lambda2 = crate::sh::convolve::lambda(l).powi(2);
        for p in 0..=brdf.p {
            for q in -(p.min(l) as isize)..=(p.min(l) as isize) {
                let r = brdf.get(l, p, q);
                captured += lambda2 * (0..3).map(|c| (lc[c] * r[c]).powi(2)).sum::<f64>();
            }
        }
    }
    residual_bound(f, light_res, brdf_res, captured)
}

/// The views of Cabral et al.'s 12 icosahedral reflection maps, and of a T × T grid.
pub use super::shrm::{icosahedron_views, view_grid};
