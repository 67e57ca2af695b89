//! The `sh-project` stage as one library call: project an environment map onto spherical
//! harmonics (Ramamoorthi & Hanrahan 2002, §6.1, App. C step 1), choosing the order from a
//! tolerance (§5.1) if asked, and synthesize the reconstruction and the irradiance map.
//!
//! **Choosing the order from ε.** R&H's criterion keeps 1 − ε of the map's energy. A sun 10⁴×
//! brighter than the sky holds most of an HDR map's energy in a few texels, and its energy spreads
//! over every band: ε = 1 % then asks for orders in the hundreds (order 246 and a 5.9 MB
//! document for the demo sky), which no display or shader wants, and which still rings. So ε is
//! measured on the map with its compact bright sources clipped (the threshold of
//! [`crate::envmap::bright`]): the order is that of the map's smooth part. The coefficients
//! written are those of the whole map; the document records the clipping level and both ε.
//!
//! **Synthesis.** Reconstructions and irradiance maps are synthesized with a window
//! ([`super::window`]) and its non-negativity guard; the coefficients stay raw. The
//! reconstruction's default is `lanczos`, not the `nonneg` of the bakes: a reconstruction has no
//! BRDF kernel to damp its top bands, and a step such as the horizon rings through the whole
//! ground. On the demo sky at
//! order 30, a 10:1 horizon leaves row means of the ground 0.69–1.28 × the map's under `nonneg`
//! (non-negative, still banded) and 0.96–1.03 × under Lanczos's σ-factors, whose horizon is the
//! sharpest of the three fixed windows (`docs/results/windows.md`). The irradiance map keeps
//! `nonneg` by default: Â_l falls as l^-5/2, so it does not ring, and at the usual F = 2 the
//! σ-factors would scale bands 1 and 2 by 0.83 and 0.41.
//!
//! **Reconstruction, bright sources apart.** At any finite order a sun rings (Gibbs), and no
//! window removes rings 10⁴ times the ground's radiance without blurring the sky away. So the
//! reconstruction is the map as prtkit's bakes represent it: the order-F expansion of the map
//! with its compact bright sources clipped, plus those sources' excess put back texel by texel
//! (energy kept). The irradiance map needs no such care: the clamped cosine's coefficients fall
//! as l⁻⁵/² and ring far below the map's detail.

use super::document::{OrderSelection, ShBody, SourceMap, Synthesis, FORMAT, VERSION};
use super::project::{project_choosing_order, OrderChoice, Projection, SelectError};
use super::synth::{synthesize_latlong, SynthError};
use super::window::{self, Window};
use super::{convolve, ShCoeffs};
use crate::envmap::bright::{split, BrightRule, BrightSources};
use crate::envmap::{EnvMap, Layout};
use crate::io::{Document, Provenance, RgbImage};
use crate::limits::MAX_SH_ORDER;
use crate::progress::Progress;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// What `sh-project` computes.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// The order, or the tolerance it is chosen from.
    pub order: OrderChoice,
    /// Synthesize the order-F reconstruction.
    pub reconstruction: bool,
    /// Synthesize the irradiance map E(n) = ∫ L(ω) max(n·ω, 0) dω.
    pub irradiance: bool,
    /// Size of the lat-long images; `None`: the input's size for a lat-long input, else 2S × S
    /// with S ≈ √(texels/2).
    pub size: Option<(usize, usize)>,
    /// The window of the reconstruction (the coefficients written stay raw).
    pub window: Window,
    /// The window of the irradiance map.
    pub irradiance_window: Window,
    /// The input's name, for the document.
    pub source: String,
    /// The command line, for the document's provenance.
    pub args: Vec<String>,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            order: OrderChoice::Order(2),
            reconstruction: false,
            irradiance: false,
            size: None,
            window: Window::Lanczos,
            irradiance_window: Window::Nonneg,
            source: String::new(),
            args: Vec::new(),
        }
    }
}

/// What `sh-project` produces.
#[derive(Clone, Debug)]
pub struct Output {
    /// The `prtkit.sh` document.
    pub document: Document<ShBody>,
    /// The order-F reconstruction, if asked.
    pub reconstruction: Option<RgbImage>,
    /// The irradiance map, if asked.
    pub irradiance: Option<RgbImage>,
    /// The `--json` summary.
    pub summary: Summary,
}

/// The machine-readable summary (`sh-project --json`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    /// The input.
    pub input: String,
    /// Its layout.
    pub layout: String,
    /// The order F.
    pub order: usize,
    /// (F+1)².
    pub coefficients: usize,
    /// 1 − captured/total energy.
    pub epsilon_achieved: f64,
    /// Energy per band.
    pub band_energy: Vec<f64>,
    /// Total energy of the map.
    pub total_energy: f64,
    /// Time of the projection.
    pub project_seconds: f64,
}

/// Errors of the stage.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The order is beyond [`MAX_SH_ORDER`].
    #[error("order {0} is absurd (at most {MAX_SH_ORDER})")]
    Order(usize),
    /// Projection or order selection failed.
    #[error("{source_name}: cannot project: {error}")]
    Select {
        /// The input.
        source_name: String,
        /// Why.
        error: SelectError,
    },
    /// The images cannot hold the order.
    #[error(transparent)]
    Synth(#[from] SynthError),
}

/// Runs `sh-project` on `map`.
pub fn run(config: &Config, map: &EnvMap, progress: &dyn Progress) -> Result<Output, Error> {
    if let OrderChoice::Order(order) = config.order {
        if order > MAX_SH_ORDER {
            return Err(Error::Order(order));
        }
    }
    let start = Instant::now();
    let (clipped, bright) = split(map, BrightRule::Auto);
    let (projection, selection) = project(config, map, &clipped, &bright, progress)?;
    let project_seconds = start.elapsed().as_secs_f64();
    let order = projection.coeffs.order;
    let images = synthesize(config, map, &projection.coeffs, &clipped, &bright, progress)?;
    let img = map.image();
    let body = ShBody {
        order,
        coefficients: projection.coeffs.rgb.clone(),
        band_energy: projection.coeffs.band_energy(),
        total_energy: projection.total_energy,
        selection,
        source: SourceMap {
            path: config.source.clone(),
            layout: map.layout().name().to_string(),
            width: img.width,
            height: img.height,
            max_order: map.max_order(),
        },
        synthesis: images.synthesis,
    };
    let provenance = Provenance::new("sh-project", &config.args, vec![config.source.clone()]);
    let summary = Summary {
        input: config.source.clone(),
        layout: map.layout().name().into(),
        order,
        coefficients: super::count(order),
        epsilon_achieved: projection.epsilon_achieved,
        band_energy: body.band_energy.clone(),
        total_energy: projection.total_energy,
        project_seconds,
    };
    let document =
        Document::new(FORMAT, VERSION, provenance, body).with_input_orientation(map.orientation().describe());
    Ok(Output { document, reconstruction: images.reconstruction, irradiance: images.irradiance, summary })
}

/// The whole map's coefficients at the order `config` gives or its ε chooses, and how the order
/// was chosen. ε is measured on the `clipped` map (module docs): the order is then that of the
/// map's smooth part, and the coefficients are those of the whole map.
fn project(
    config: &Config,
    map: &EnvMap,
    clipped: &EnvMap,
    bright: &BrightSources,
    progress: &dyn Progress,
) -> Result<(Projection, OrderSelection), Error> {
    let select = |error| Error::Select { source_name: config.source.clone(), error };
    let (projection, epsilon, clipped_selection) = match config.order {
        OrderChoice::Order(_) => (project_choosing_order(map, config.order, progress).map_err(select)?, None, None),
        OrderChoice::Epsilon { epsilon, .. } => {
            let smooth = project_choosing_order(clipped, config.order, progress).map_err(select)?;
            let full =
                project_choosing_order(map, OrderChoice::Order(smooth.coeffs.order), progress).map_err(select)?;
            (full, Some(epsilon), Some((bright.threshold, smooth.epsilon_achieved)))
        }
    };
    let selection = OrderSelection {
        method: if epsilon.is_some() { "epsilon" } else { "order" }.into(),
        epsilon,
        epsilon_achieved: projection.epsilon_achieved,
        clipped_at: clipped_selection.map(|c| c.0),
        epsilon_achieved_clipped: clipped_selection.map(|c| c.1),
    };
    Ok((projection, selection))
}

/// The images `sh-project` synthesizes, and the document's account of them.
struct Images {
    /// The window, size and guard of the synthesis (absent when no image is asked).
    synthesis: Option<Synthesis>,
    /// The order-F reconstruction.
    reconstruction: Option<RgbImage>,
    /// The irradiance map.
    irradiance: Option<RgbImage>,
}

/// The reconstruction (the `clipped` map's expansion with the `bright` sources put back, module
/// docs) and the irradiance map of `coeffs`, as `config` asks.
fn synthesize(
    config: &Config,
    map: &EnvMap,
    coeffs: &ShCoeffs,
    clipped: &EnvMap,
    bright: &BrightSources,
    progress: &dyn Progress,
) -> Result<Images, Error> {
    if !(config.reconstruction || config.irradiance) {
        return Ok(Images { synthesis: None, reconstruction: None, irradiance: None });
    }
    let (w, h) = image_size(map, coeffs.order, config.size);
    let reconstruction = if config.reconstruction {
        let smooth = crate::sh::project::project(clipped, coeffs.order, progress)
            .map_err(|e| Error::Select { source_name: config.source.clone(), error: e.into() })?;
        let (mut image, t) = windowed_synthesis(&smooth, &vec![1.0; coeffs.order + 1], config.window, w, h)?;
        bright.add_to_latlong(&mut image);
        Some((image, t))
    } else {
        None
    };
    let irradiance = if config.irradiance {
        let cosine: Vec<f64> = (0..=coeffs.order).map(convolve::clamped_cosine).collect();
        Some(windowed_synthesis(coeffs, &cosine, config.irradiance_window, w, h)?)
    } else {
        None
    };
    let synthesis = Synthesis {
        window: config.window,
        irradiance_window: config.irradiance_window,
        size: [w, h],
        reconstruction_t: reconstruction.as_ref().and_then(|r| r.1),
        irradiance_t: irradiance.as_ref().and_then(|r| r.1),
    };
    Ok(Images {
        synthesis: Some(synthesis),
        reconstruction: reconstruction.map(|r| r.0),
        irradiance: irradiance.map(|r| r.0),
    })
}

/// Synthesizes `coeffs` convolved with the zonal `kernel` (Â_l for irradiance, 1 for a
/// reconstruction) under `window`, with the non-negativity guard unless `none`; also the guard's
/// heat parameter t.
fn windowed_synthesis(
    coeffs: &ShCoeffs,
    kernel: &[f64],
    kind: Window,
    w: usize,
    h: usize,
) -> Result<(RgbImage, Option<f64>), SynthError> {
    let convolved = convolve::convolve_zonal(coeffs, |l| kernel[l]);
    let base = kind.factors(coeffs.order);
    // The first synthesis reports a bad size; past it synthesis cannot fail (same size and
    // order), so the search may unwrap into an empty image without hiding an error.
    let first = synthesize_latlong(&window::apply(&convolved, &base), w, h)?;
    let min = |img: &RgbImage| img.pixels.iter().flatten().fold(0.0f64, |m, &v| m.min(v as f64));
    if !kind.guarded() {
        return Ok((first, None));
    }
    if min(&first) >= 0.0 {
        return Ok((first, Some(0.0)));
    }
    let found = window::nonneg(
        &base,
        kernel,
        |f| synthesize_latlong(&window::apply(&convolved, f), w, h).unwrap_or_else(|_| RgbImage::new(w, h)),
        min,
    );
    Ok((found.map, Some(found.t)))
}

/// The lat-long image size: as asked, else the input's for a lat-long input wide enough for the
/// order, else 2S × S with S ≈ √(texels/2) (at least F + 1 and 8).
fn image_size(map: &EnvMap, order: usize, size: Option<(usize, usize)>) -> (usize, usize) {
    if let Some(s) = size {
        return s;
    }
    if map.layout() == Layout::LatLong {
        let img = map.image();
        if img.width >= 2 * order {
            return (img.width, img.height);
        }
    }
    let s = ((map.texel_count() as f64 / 2.0).sqrt().round() as usize).max(order + 1).max(8);
    (2 * s, s)
}
