//! The `prefilter` stage as one library call: frequency-space prefiltering into a spherical
//! harmonic reflection map and the maps derived from it (Ramamoorthi & Hanrahan 2002), or the
//! angular reference (App. D).

use super::brdf_sh::BrdfSh;
use super::document::{layer_name, Lighting as DocLighting, MapEntry, ShrmBody, FORMAT, VERSION};
use super::hybrid::{self, Settings};
use super::model::{residual_bound, Centre, Model, ModelError};
use super::orders::OrderRule;
use super::pipeline::{self, AngularSettings, Lighting, PrefilterError};
use super::shrm;
use super::verify::{MapCheck, Verification, Verifier, VerifyError};
use crate::brdf::Brdf;
use crate::envmap::bright::{BrightRule, BrightSources};
use crate::envmap::{self, EnvMap, EnvMapError, Layout};
use crate::io::{Document, Provenance, RgbImage};
use crate::progress::Progress;
use crate::sh::window::Window;
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
    /// The SHRM as named layers B<p><±q>, if asked.
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

/// Errors of the stage.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// ε is out of range.
    #[error("--epsilon must be in (0, 1), got {0}")]
    Epsilon(f64),
    /// The output layout is not one the maps can be written in.
    #[error("the output layout must be latlong, cross-horizontal or cross-vertical, got {0}")]
    Layout(Layout),
    /// The BRDF cannot be prefiltered.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The irradiance map needs Lambert.
    #[error("an irradiance map needs --brdf lambert (it is Lambert's reflection map × π/albedo)")]
    IrradianceNeedsLambert,
    /// The angular reference writes reflection maps only and needs the map itself.
    #[error("--method angular {0}")]
    Angular(&'static str),
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
    #[error("--verify needs the environment map, not SH coefficients (the exact values integrate the map)")]
    VerifyNeedsMap,
    /// The verification failed.
    #[error(transparent)]
    Verify(#[from] VerifyError),
}

/// Runs `prefilter` with `lighting` (a map, or SH coefficients for the frequency method).
pub fn run(config: &Config, lighting: Lighting<'_>, progress: &dyn Progress) -> Result<Output, Error> {
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
        super::verify::check_texels(n)?;
        if matches!(lighting, Lighting::Coefficients(_)) {
            return Err(Error::VerifyNeedsMap);
        }
    }
    let fail = |error: PrefilterError| Error::Prefilter { source_name: config.source.clone(), error };
    let views: Vec<DVec3> = config.maps.iter().map(|m| m.view).collect();
    let start = Instant::now();
    let mut timings = Timings::default();
    let mut bake = None;
    let mut angular = None;
    let (maps, shrm_out, f_b, p_b, epsilon_achieved, light_order, bound, (width, height)) = match config.method {
        Method::Frequency => {
            let settings = Settings {
                epsilon: config.epsilon,
                rule: config.order_rule,
                orders: config.orders,
                max_p: config.max_p,
                bright: config.bright,
                window: config.window,
                size: config.size,
            };
            // A view-dependent BRDF's maps, and a narrow radially symmetric lobe's, are
            // integrated in angle (`hybrid::maps_in_angle`), unless --bound asks about their
            // expansion; the SHRM is then made only for its file.
            let in_angle = match lighting {
                Lighting::Map(env)
                    if !views.is_empty() && !config.bound && hybrid::maps_in_angle(&model, &settings, env) =>
                {
                    Some(env)
                }
                _ => None,
            };
            let shrm_wanted = config.shrm_file.is_some() || config.kautz_mccool_slices > 0;
            match in_angle {
                Some(env) if !shrm_wanted => {
                    let t = Instant::now();
                    let done =
                        hybrid::angle_maps(&model, env, &views, config.bright, config.size, progress).map_err(fail)?;
                    timings.maps_seconds = t.elapsed().as_secs_f64();
                    bake = Some(done.report);
                    // No expansion: F_B = P_B = 0; ε achieved is the lobe weight outside the cones.
                    (done.maps, None, 0, 0, hybrid::ANGULAR_EPSILON, 0, None, done.size)
                }
                _ => {
                    let t = Instant::now();
                    let mut pre = hybrid::prefilter(&model, lighting, &settings, progress).map_err(fail)?;
                    timings.shrm_seconds = t.elapsed().as_secs_f64();
                    let size = (pre.remainder_shrm.width(), pre.remainder_shrm.height());
                    let t = Instant::now();
                    // On the SHRM's grid, so the document's size holds for both (a radially
                    // symmetric lobe's zonal filter keeps the lighting's width: else the SHRM's).
                    let on_grid = Settings { size: Some(size), ..settings };
                    let maps = match in_angle.filter(|env| hybrid::maps_in_angle(&model, &on_grid, env)) {
                        Some(env) => {
                            let done = hybrid::angle_maps(&model, env, &views, config.bright, Some(size), progress)
                                .map_err(fail)?;
                            pre.report.maps = done.report.maps;
                            done.maps
                        }
                        None => {
                            let wanted =
                                if config.irradiance && views.is_empty() { vec![DVec3::Z] } else { views.clone() };
                            pre.reflection_maps(&model, &wanted, progress).map_err(fail)?
                        }
                    };
                    timings.maps_seconds = t.elapsed().as_secs_f64();
                    let (f_b, p_b) = (pre.brdf.f, pre.brdf.p);
                    // BRDF energy missed by (F_B, P_B): against the total ∫∫ ρ̂² the coefficients'
                    // own quadrature measured (not their sum), so no larger expansion is needed. A
                    // second one at (2F_B, P_B + 3) agreed within 0.07 % on Phong and
                    // Torrance-Sparrow and cost up to a third of the bake (`tests/prefilter_cli.rs`
                    // holds the agreement).
                    let epsilon_achieved = pre.brdf.residual(f_b, p_b);
                    let bound = config.bound.then(|| app_b_bound(&pre.brdf, &pre.lighting, &pre.bright, lighting));
                    let shrm =
                        if shrm_wanted { Some(pre.shrm(&model, config.global, progress).map_err(fail)?) } else { None };
                    bake = Some(pre.report.clone());
                    (maps, shrm, f_b, p_b, epsilon_achieved, pre.lighting.order, bound, size)
                }
            }
        }
        Method::Angular => {
            if config.shrm_file.is_some() || config.kautz_mccool_slices > 0 {
                return Err(Error::Angular("writes reflection maps only (and the irradiance map)"));
            }
            let Lighting::Map(env) = lighting else {
                return Err(Error::Angular("needs the environment map, not SH coefficients"));
            };
            if config.orders.is_some() {
                return Err(Error::Angular("takes no --order: it uses no spherical harmonics (ε is its truncation)"));
            }
            let latlong = hybrid::as_latlong(env)?;
            // No SH, so no F_B to size the grid by: the input's own lat-long grid by default.
            let size = config.size.unwrap_or((latlong.image().width, latlong.image().height));
            let t = Instant::now();
            let wanted = if config.irradiance && views.is_empty() { vec![DVec3::Z] } else { views.clone() };
            let settings = AngularSettings { epsilon: config.epsilon, bright: config.bright };
            let reference = pipeline::angular_reference(&model, &latlong, &wanted, settings, size.0, size.1, progress)
                .map_err(fail)?;
            let epsilon_achieved = reference.report.epsilon_achieved;
            angular = Some(reference.report);
            timings.angular_seconds = t.elapsed().as_secs_f64();
            // Radially symmetric BRDFs give one map whatever the view.
            let images = reference.maps;
            let maps = if model.centre().is_some() { vec![images[0].clone(); wanted.len()] } else { images };
            // F_B = P_B = 0: no orders; ε achieved is the lobe weight the truncation left out.
            (maps, None, 0, 0, epsilon_achieved, 0, None, size)
        }
    };

    // Lambert's map is radiance (albedo/π)·E(N); the irradiance is that × π/albedo. Any map
    // will do (the model is view-independent), else the SHRM's.
    let albedo = model.brdf().reflection_lobe(1.0).unwrap_or(1.0 / PI) * PI;
    let irradiance_scale = (PI / albedo.max(1e-12)) as f32;
    let irradiance = config.irradiance.then(|| {
        let mut e = match (maps.first(), &shrm_out) {
            (Some(map), _) => map.clone(),
            (None, Some(s)) => shrm::reflection_map(s, DVec3::Z),
            (None, None) => unreachable!("the angular method computed a map for the irradiance"),
        };
        e.pixels.iter_mut().flatten().for_each(|c| *c *= irradiance_scale);
        e
    });
    let verification = match (config.verify, lighting) {
        (Some(n), Lighting::Map(env)) => {
            let t = Instant::now();
            let mut checks: Vec<MapCheck> = config
                .maps
                .iter()
                .zip(&maps)
                .map(|(m, image)| MapCheck { name: m.file.clone(), image, view: m.view, scale: 1.0 })
                .collect();
            if let Some(image) = &irradiance {
                let scale = irradiance_scale as f64;
                checks.push(MapCheck { name: "irradiance".into(), image, view: DVec3::Z, scale });
            }
            let verifier = Verifier::new(&model, &hybrid::as_latlong(env)?, height, n)?;
            let verification = verifier.verify(&checks, progress)?;
            timings.verify_seconds = t.elapsed().as_secs_f64();
            Some(verification)
        }
        _ => None,
    };
    let irradiance = irradiance.map(|e| to_output_layout(&e, config.output_layout)).transpose()?;
    let maps: Vec<RgbImage> = maps
        .iter()
        .take(config.maps.len())
        .map(|m| to_output_layout(m, config.output_layout))
        .collect::<Result<_, _>>()?;
    let layer_names: Vec<String> = (0..count(p_b))
        .map(|i| {
            let (p, q) = lm(i);
            layer_name(p, q)
        })
        .collect();
    let shrm_layers = match (&config.shrm_file, &shrm_out) {
        (Some(_), Some(s)) => Some(
            layer_names
                .iter()
                .zip(&s.layers)
                .map(|(n, l)| Ok((n.clone(), to_output_layout(l, config.output_layout)?)))
                .collect::<Result<_, Error>>()?,
        ),
        _ => None,
    };
    let kautz_mccool = match (config.kautz_mccool_slices, &shrm_out) {
        (0, _) | (_, None) => None,
        (slices, Some(s)) => Some(
            shrm::kautz_mccool(s, slices)
                .iter()
                .enumerate()
                .map(|(k, l)| Ok((format!("theta{k:02}"), to_output_layout(l, config.output_layout)?)))
                .collect::<Result<_, Error>>()?,
        ),
    };
    timings.total_seconds = start.elapsed().as_secs_f64();

    let radial = model.centre().is_some();
    let body = ShrmBody {
        brdf: model.brdf().spec(),
        cosine: model.cosine(),
        method: config.method.name().into(),
        f_b,
        p_b,
        epsilon: config.orders.is_none().then_some(config.epsilon),
        epsilon_achieved,
        epsilon_bound: bound,
        parameterization: if model.centre() == Some(Centre::Normal) {
            "normal"
        } else if model.is_tangent() {
            "tangent"
        } else {
            "reflection"
        }
        .into(),
        layout: config.output_layout.name().into(),
        width,
        height,
        global: config.global,
        shrm_file: config.shrm_file.clone().filter(|_| shrm_layers.is_some()),
        layers: layer_names,
        lighting: DocLighting { source: config.source.clone(), order: light_order },
        maps: config
            .maps
            .iter()
            .map(|m| MapEntry { file: m.file.clone(), view: (!radial).then(|| m.view.to_array()) })
            .collect(),
        timings: None,
        bake,
        reference: angular,
        verification: verification.clone(),
    };
    let provenance = Provenance::new("prefilter", &config.args, vec![config.source.clone()]);
    let summary = Summary {
        brdf: body.brdf.clone(),
        method: config.method,
        f_b,
        p_b,
        epsilon_achieved,
        epsilon_bound: bound,
        width,
        height,
        verification,
        timings,
    };
    let document = Document::new(FORMAT, VERSION, provenance, body);
    let document = match lighting {
        Lighting::Map(env) => document.with_input_orientation(env.orientation().describe()),
        Lighting::Coefficients(_) => document,
    };
    Ok(Output { document, maps, shrm_layers, kautz_mccool, irradiance, summary })
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
/// lighting the SH expansion carries (the remainder when bright sources are apart).
fn app_b_bound(brdf: &BrdfSh, light: &ShCoeffs, bright: &BrightSources, lighting: Lighting<'_>) -> f64 {
    let f = brdf.f;
    let brdf_res = brdf.residual(f, brdf.p) * brdf.total_energy;
    let captured_light: f64 = light.band_energy().iter().sum();
    let light_total = match lighting {
        Lighting::Map(m) if bright.is_empty() => crate::sh::project::map_energy(m),
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
