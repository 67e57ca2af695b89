//! The `sh-project` stage as one library call: project an environment map onto spherical
//! harmonics (Ramamoorthi & Hanrahan 2002, §6.1, App. C step 1), choosing the order from a
//! tolerance (§5.1) if asked, and synthesize the reconstruction and the irradiance map.

use super::convolve;
use super::document::{OrderSelection, ShBody, SourceMap, FORMAT, VERSION};
use super::project::{project_choosing_order, OrderChoice, SelectError};
use super::synth::{synthesize_latlong, SynthError};
use crate::envmap::{EnvMap, Layout};
use crate::io::{Document, Provenance, RgbImage};
use crate::progress::Progress;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Highest order an ε search considers.
pub const MAX_EPSILON_ORDER: usize = 256;
/// Highest order that may be asked for at all.
pub const MAX_ORDER: usize = 2000;

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
    /// The order is beyond [`MAX_ORDER`].
    #[error("order {0} is absurd (at most {MAX_ORDER})")]
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
        if order > MAX_ORDER {
            return Err(Error::Order(order));
        }
    }
    let start = Instant::now();
    let projection = project_choosing_order(map, config.order, progress)
        .map_err(|error| Error::Select { source_name: config.source.clone(), error })?;
    let project_seconds = start.elapsed().as_secs_f64();
    let coeffs = &projection.coeffs;

    let (mut reconstruction, mut irradiance) = (None, None);
    if config.reconstruction || config.irradiance {
        let (w, h) = image_size(map, coeffs.order, config.size);
        if config.reconstruction {
            reconstruction = Some(synthesize_latlong(coeffs, w, h)?);
        }
        if config.irradiance {
            irradiance = Some(synthesize_latlong(&convolve::irradiance(coeffs), w, h)?);
        }
    }

    let img = map.image();
    let (method, epsilon) = match config.order {
        OrderChoice::Order(_) => ("order", None),
        OrderChoice::Epsilon { epsilon, .. } => ("epsilon", Some(epsilon)),
    };
    let body = ShBody {
        order: coeffs.order,
        coefficients: coeffs.rgb.clone(),
        band_energy: coeffs.band_energy(),
        total_energy: projection.total_energy,
        selection: OrderSelection { method: method.into(), epsilon, epsilon_achieved: projection.epsilon_achieved },
        source: SourceMap {
            path: config.source.clone(),
            layout: map.layout().name().to_string(),
            width: img.width,
            height: img.height,
            max_order: map.max_order(),
        },
    };
    let provenance = Provenance::new("sh-project", &config.args, vec![config.source.clone()]);
    let summary = Summary {
        input: config.source.clone(),
        layout: map.layout().name().into(),
        order: coeffs.order,
        coefficients: super::count(coeffs.order),
        epsilon_achieved: projection.epsilon_achieved,
        band_energy: body.band_energy.clone(),
        total_energy: projection.total_energy,
        project_seconds,
    };
    Ok(Output { document: Document::new(FORMAT, VERSION, provenance, body), reconstruction, irradiance, summary })
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
