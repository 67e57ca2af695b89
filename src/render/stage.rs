//! The `render` stage as one library call: a sphere or mesh shaded with one of the bakes (SH
//! irradiance, an SHRM, a K-term factorization, an `ibl` bake, a transfer bake) or the reference
//! integrator, compared with a reference render, and laid out in a labelled panel. The shading
//! path is decided once, its inputs checked, in a plan (`render::plan`), then executed.

use super::grid::{legend, GridCell, GridError, MaterialGrid};
use super::ibl::{IblBake, OtherSource};
use super::panel::{layout, layout_grid, Cell};
use super::plan::{Plan, Report, Shaded, Shot};
use super::reference::Integrand;
use super::transfer::{OtherFactors, OtherMesh, TransferBake};
use super::{Camera, Frame, Scene};
use crate::brdf::Brdf;
use crate::envmap::bright::BrightRule;
use crate::envmap::EnvMap;
use crate::factor::Factorization;
use crate::io::{Document, Provenance, RgbImage};
use crate::metrics::{compare, CompareError, Metrics};
use crate::prefilter::document::ShrmBody;
use crate::prefilter::model::ModelError;
use crate::prefilter::shrm::Shrm;
use crate::progress::Progress;
use crate::sh::window::{Window, WindowReport};
use crate::sh::ShCoeffs;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// Grid bins n of a factorization made by `render` itself.
pub const DEFAULT_FACTOR_RESOLUTION: usize = 64;

/// Document kind of the metrics written with `--metrics`.
pub const METRICS_FORMAT: &str = "prtkit.render-metrics";
/// Its schema version.
pub const METRICS_VERSION: u32 = 1;

/// How the object is shaded.
#[derive(Clone, Debug)]
pub enum Shading {
    /// Lambert from SH lighting of order `order`: `coefficients` (truncated), or the map
    /// projected when `None`.
    Irradiance {
        /// The SH order used.
        order: usize,
        /// Given coefficients (a `prtkit.sh` document's).
        coefficients: Option<ShCoeffs>,
        /// The window on the lighting's bands at synthesis.
        window: Window,
    },
    /// From an SHRM and its document.
    Shrm {
        /// The SHRM.
        shrm: Shrm,
        /// Its document.
        body: Box<ShrmBody>,
        /// The window on the SHRM's view bands p at synthesis (its lighting bands carry the
        /// prefilter's window).
        window: Window,
    },
    /// K-term in-out factorization (Mahajan et al. 2008, eq. 3–4).
    Factored {
        /// Terms K.
        terms: usize,
        /// A stored factorization (`factor-brdf --factors`); `None`: factor here on the
        /// hemisphere with the cosine folded in, at `resolution`.
        factors: Option<Box<StoredFactors>>,
        /// Grid bins n: of the factorization made here, or (when given) the stored one's.
        resolution: Option<usize>,
        /// Lighting samples per grid cell along each axis.
        cell_samples: usize,
        /// Size of the lat-long table of normals (sphere).
        normal_table: (usize, usize),
        /// Bright sources apart: shaded exactly, the remainder through the factors.
        bright: BrightRule,
    },
    /// From an `ibl` bake with the split sum, as a glTF/PBR engine shades (glTF materials).
    Ibl {
        /// The bake.
        bake: Box<IblBake>,
        /// A roughness × metalness grid of spheres, each with its reference, instead of one
        /// render of the BRDF's material.
        grid: Option<MaterialGrid>,
    },
    /// From a `transfer` bake: the per-vertex dot product with the environment's SH (Sloan,
    /// Kautz & Snyder 2002), interpolated over the triangles.
    Transfer {
        /// The bake, read from its `.glb`.
        bake: Box<TransferBake>,
        /// The factorization a glossy bake was made with, checked against the bake.
        factors: Option<Box<StoredFactors>>,
        /// The per-texel lightmap to shade from instead of the vertices.
        lightmap: Option<Box<super::transfer::LightmapImage>>,
    },
    /// Ground truth: a sum over every environment texel.
    Reference {
        /// The rendering equation, or the ρ̂ the prefilter represents.
        integrand: Integrand,
    },
}

impl Shading {
    /// The mode's name.
    pub fn name(&self) -> &'static str {
        match self {
            Shading::Irradiance { .. } => "irradiance",
            Shading::Shrm { .. } => "shrm",
            Shading::Factored { .. } => "factored",
            Shading::Ibl { .. } => "ibl",
            Shading::Transfer { .. } => "transfer",
            Shading::Reference { .. } => "reference",
        }
    }
}

/// A factorization read back from `factor-brdf`'s document and factor file.
#[derive(Clone, Debug)]
pub struct StoredFactors {
    /// The document's name, for messages.
    pub name: String,
    /// The factorization.
    pub factorization: Factorization,
    /// Whether max(cos θ_i, 0) is folded into it.
    pub cosine: bool,
    /// The BRDF it is of (canonical spec).
    pub brdf: String,
}

/// A cell of the panel: a label (lines separated by `|`) and an image, `None` for this render.
#[derive(Clone, Debug)]
pub struct PanelItem {
    /// The label.
    pub label: String,
    /// The image; `None` places this render here.
    pub image: Option<RgbImage>,
}

/// What `render` computes.
#[derive(Clone, Debug)]
pub struct Config {
    /// The BRDF.
    pub brdf: Brdf,
    /// The shading mode.
    pub shading: Shading,
    /// The camera.
    pub camera: Camera,
    /// The environment turned by this many degrees about +Z (transfer and reference), the
    /// background with it.
    pub env_rotation: f64,
    /// A reference render to compare with (same size), and its name.
    pub compare: Option<(String, RgbImage)>,
    /// The panel's cells, if a panel is asked for.
    pub panel: Option<Vec<PanelItem>>,
    /// This render's label (default: the mode and its parameters).
    pub label: Option<String>,
    /// Exposure (stops) the panel will be tone-mapped with: its labels are drawn to stay white.
    pub exposure: f32,
    /// The file the render is written to, for the metrics document.
    pub output_name: Option<String>,
    /// The command line, for the metrics document's provenance.
    pub args: Vec<String>,
}

/// What `render` produces.
#[derive(Clone, Debug)]
pub struct Output {
    /// The render (linear RGB) and its object mask.
    pub frame: Frame,
    /// Metrics against the reference, with the error image |render − reference|.
    pub comparison: Option<(Document<MetricsBody>, RgbImage)>,
    /// The labelled panel, if asked.
    pub panel: Option<RgbImage>,
    /// The `--json` summary.
    pub summary: Summary,
}

/// The `prtkit.render-metrics` document (`docs/formats/render-metrics.md`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MetricsBody {
    /// The render's file, if written.
    pub render: Option<String>,
    /// The reference's file.
    pub reference: String,
    /// Shading mode.
    pub shading: String,
    /// Canonical BRDF spec.
    pub brdf: String,
    /// The render's label.
    pub label: String,
    /// The metrics over the object's pixels.
    pub metrics: Metrics,
}

/// The machine-readable summary (`render --json`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    /// Shading mode.
    pub shading: String,
    /// Canonical BRDF spec.
    pub brdf: String,
    /// Image width.
    pub width: usize,
    /// Image height.
    pub height: usize,
    /// Time of the render.
    pub seconds: f64,
    /// The label.
    pub label: String,
    /// SH order (irradiance).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub order: Option<usize>,
    /// F_B, P_B (shrm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orders: Option<(usize, usize)>,
    /// The SHRM's ε achieved (shrm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon_achieved: Option<f64>,
    /// K and the energy of K terms (factored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub terms: Option<(usize, f64)>,
    /// The bright sources shaded exactly (factored).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bright: Option<BrightShare>,
    /// The window at synthesis (irradiance, shrm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window: Option<WindowReport>,
    /// Metrics against the reference, if compared.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metrics: Option<Metrics>,
    /// Every cell of an ibl grid, with its error against its reference (ibl --grid).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid: Option<Vec<GridCell>>,
    /// The relighting from a transfer bake (transfer).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transfer: Option<RelightSummary>,
}

/// What relighting from a transfer bake cost (`render --shading transfer --json`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RelightSummary {
    /// The bake's SH order n (bands).
    pub order: usize,
    /// Its mode.
    pub mode: String,
    /// Terms K of a glossy bake (1: diffuse): dot products per vertex.
    #[serde(default = "one")]
    pub terms: usize,
    /// Vertices relit per frame.
    pub vertices: usize,
    /// Frames timed: each an SH rotation of the lighting and the dot product at every vertex
    /// (one thread, single precision).
    pub frames: usize,
    /// 1 / the fastest frame's seconds.
    pub frames_per_second: f64,
    /// 1 / the median frame's seconds.
    pub median_frames_per_second: f64,
}

fn one() -> usize {
    1
}

/// Most degrees the environment turns by, either way.
pub const MAX_ENV_ROTATION: f64 = 360.0;

/// The bright texels a factored render shades exactly, and their share of the map's energy.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct BrightShare {
    /// Texels shaded exactly.
    pub texels: usize,
    /// Their excess over the threshold, as a share of the map's radiant energy.
    pub energy_fraction: f64,
}

/// Errors of the stage: inputs that do not fit together, and the failures of the steps.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A rendering of this shading mode other than transfer and reference with the environment
    /// turned.
    #[error("the environment turns for transfer and reference shading only, not {shading}")]
    EnvRotationShading {
        /// The shading mode.
        shading: &'static str,
    },
    /// The environment's turn is not a number or beyond ±[`MAX_ENV_ROTATION`] degrees.
    #[error("an environment turn of {0} degrees is outside -360..=360")]
    EnvRotation(f64),
    /// A shading mode of Lambertian surfaces given another BRDF.
    #[error("{shading} shading is of Lambertian surfaces; {brdf} is not lambert")]
    NotLambert {
        /// The shading mode.
        shading: &'static str,
        /// The BRDF's spec.
        brdf: String,
    },
    /// The SH lighting given has fewer bands than the order asked for.
    #[error("the coefficients have order {available}, the irradiance asks for order {wanted}")]
    ShOrder {
        /// The coefficients' order.
        available: usize,
        /// The order asked for.
        wanted: usize,
    },
    /// The SHRM is of another BRDF.
    #[error("the SHRM was computed for {shrm}, not {brdf}")]
    ShrmBrdf {
        /// The SHRM's BRDF.
        shrm: String,
        /// The BRDF of the rendering.
        brdf: String,
    },
    /// A factored rendering of no term.
    #[error("a factored rendering needs at least one term")]
    NoTerms,
    /// Lighting samples per grid cell outside 1..=8.
    #[error("{0} lighting samples per factor-grid cell is outside 1..=8")]
    CellSamples(usize),
    /// A stored factorization of another BRDF.
    #[error("{factors}: the factorization is of {factored}, not {brdf}")]
    FactorsBrdf {
        /// The factor document.
        factors: String,
        /// Its BRDF.
        factored: String,
        /// The BRDF of the rendering.
        brdf: String,
    },
    /// A stored factorization of another resolution than asked for.
    #[error("{factors}: a factorization of another resolution: n = {stored}, not {asked}")]
    FactorsResolution {
        /// The factor document.
        factors: String,
        /// Its bins n.
        stored: usize,
        /// The bins asked for.
        asked: usize,
    },
    /// A stored factorization of fewer terms than asked for.
    #[error("{factors}: the factor file holds {stored} terms, not the {asked} asked for")]
    FactorsTerms {
        /// The factor document.
        factors: String,
        /// Its terms.
        stored: usize,
        /// The terms asked for.
        asked: usize,
    },
    /// A factorization to make at a resolution outside 2..=256.
    #[error("a factorization of {0} bins is outside 2..=256")]
    FactorResolution(usize),
    /// More terms than an n² × n² matrix has.
    #[error("{terms} terms are more than the {} a factorization at {resolution} bins has", resolution * resolution)]
    TermsAboveRank {
        /// The terms asked for.
        terms: usize,
        /// The bins n.
        resolution: usize,
    },
    /// The split sum given a BRDF other than the glTF material.
    #[error(
        "ibl shading shades glTF metallic-roughness materials; {brdf} is not gltf:base=R/G/B,metalness=M,roughness=R"
    )]
    NotGltf {
        /// The BRDF's spec.
        brdf: String,
    },
    /// A material grid asked to compare with a reference or to lay out panel items.
    #[error("a material grid renders its own references: no reference to compare with, no panel items")]
    GridReferences,
    /// A transfer bake given the sphere.
    #[error("transfer shading relights a mesh, the mesh the bake is of, not the sphere")]
    TransferOfSphere,
    /// A glossy transfer bake of another BRDF.
    #[error("{bake}: the transfer holds {baked}, not {brdf}")]
    TransferBrdf {
        /// The bake's file.
        bake: String,
        /// Its BRDF.
        baked: String,
        /// The BRDF of the rendering.
        brdf: String,
    },
    /// A factorization given with a diffuse bake.
    #[error("{bake}: a diffuse transfer has no factorization to check")]
    FactorsForDiffuse {
        /// The bake's file.
        bake: String,
    },
    /// A diffuse bake given a BRDF other than Lambert.
    #[error("{bake}: a diffuse transfer relights a lambert BRDF; {brdf} is not lambert")]
    DiffuseTransferNotLambert {
        /// The bake's file.
        bake: String,
        /// The BRDF's spec.
        brdf: String,
    },
    /// A diffuse bake of another albedo.
    #[error("{bake}: the transfer was baked with albedo {albedo}, not {brdf}")]
    TransferAlbedo {
        /// The bake's file.
        bake: String,
        /// The albedo baked.
        albedo: f64,
        /// The BRDF of the rendering.
        brdf: String,
    },
    /// A coloured bake given a Lambert BRDF of an albedo other than 1.
    #[error(
        "{bake}: the transfer holds a coloured albedo (transfer --albedo R,G,B or mesh), so its colour is in the \
         bake: relight it with lambert of albedo 1, not {brdf}"
    )]
    ColouredTransferAlbedo {
        /// The bake's file.
        bake: String,
        /// The BRDF of the rendering.
        brdf: String,
    },
    /// A lightmap given with a mesh that has no UVs.
    #[error("{lightmap}: the mesh has no lightmap UVs (TEXCOORD_1/TEXCOORD_0, vt, or a PLY's s t / u v) to look the lightmap up with")]
    NoLightmapUvs {
        /// The lightmap's file.
        lightmap: String,
    },
    /// The transfer bake is of another mesh.
    #[error(transparent)]
    OtherMesh(#[from] OtherMesh),
    /// The factorization given is not the one the glossy bake was made from.
    #[error(transparent)]
    OtherFactors(#[from] OtherFactors),
    /// The `ibl` bake was made from another map.
    #[error(transparent)]
    OtherSource(#[from] OtherSource),
    /// The BRDF has no ρ̂ for the reference to integrate.
    #[error(transparent)]
    Integrand(#[from] ModelError),
    /// Projection of the lighting failed.
    #[error(transparent)]
    Project(#[from] crate::sh::project::ProjectError),
    /// The factorization failed.
    #[error(transparent)]
    Factor(#[from] crate::factor::FactorError),
    /// The material grid failed.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// Comparing failed.
    #[error("comparing with {reference}: {error}")]
    Compare {
        /// The reference's name.
        reference: String,
        /// Why.
        error: CompareError,
    },
}

/// Runs `render` of `scene` under `env`.
pub fn run(config: &Config, env: &EnvMap, scene: &Scene, progress: &dyn Progress) -> Result<Output, Error> {
    check_reference_size(config)?;
    let plan = Plan::new(config, env, scene)?;
    let shot = Shot { scene, brdf: &config.brdf, camera: &config.camera, env };
    let start = Instant::now();
    let Shaded { frame, label, report } = plan.execute(&shot, progress)?;
    let seconds = start.elapsed().as_secs_f64();
    let label = config.label.clone().unwrap_or(label);
    let comparison = match &config.compare {
        Some((name, reference)) => Some(comparison(config, env, &frame, &label, name, reference)?),
        None => None,
    };
    let metrics = comparison.as_ref().map(|(document, _)| document.body.metrics);
    let panel = config.panel.as_ref().map(|items| match &report {
        Report::IblGrid { rows, .. } => layout_grid(rows, &legend(), config.exposure),
        _ => panel(items, &frame, &label, config, metrics),
    });
    let summary = summary(config, report, seconds, label, metrics);
    Ok(Output { frame, comparison, panel, summary })
}

/// The reference must be of the render's size: refused before the render, not after.
fn check_reference_size(config: &Config) -> Result<(), Error> {
    let (w, h) = (config.camera.width, config.camera.height);
    match &config.compare {
        Some((name, r)) if (r.width, r.height) != (w, h) => Err(Error::Compare {
            reference: name.clone(),
            error: CompareError::Size { rw: r.width, rh: r.height, w, h },
        }),
        _ => Ok(()),
    }
}

/// The metrics of `frame` against `reference` (the file `name`) over the object's pixels, as the
/// `prtkit.render-metrics` document, and the error image |render − reference|.
fn comparison(
    config: &Config,
    env: &EnvMap,
    frame: &Frame,
    label: &str,
    name: &str,
    reference: &RgbImage,
) -> Result<(Document<MetricsBody>, RgbImage), Error> {
    let (metrics, error_image) = compare(&frame.image, reference, &frame.mask)
        .map_err(|error| Error::Compare { reference: name.to_string(), error })?;
    let body = MetricsBody {
        render: config.output_name.clone(),
        reference: name.to_string(),
        shading: config.shading.name().into(),
        brdf: config.brdf.spec(),
        label: label.to_string(),
        metrics,
    };
    let provenance = Provenance::new("render", &config.args, vec![name.to_string()]);
    let document = Document::new(METRICS_FORMAT, METRICS_VERSION, provenance, body)
        .with_input_orientation(env.orientation().describe());
    Ok((document, error_image))
}

/// The `--json` summary: the run's shape, the mode's report and the metrics.
fn summary(config: &Config, report: Report, seconds: f64, label: String, metrics: Option<Metrics>) -> Summary {
    let mut summary = Summary {
        shading: config.shading.name().into(),
        brdf: config.brdf.spec(),
        width: config.camera.width,
        height: config.camera.height,
        seconds,
        label,
        order: None,
        orders: None,
        epsilon_achieved: None,
        terms: None,
        bright: None,
        window: None,
        metrics,
        grid: None,
        transfer: None,
    };
    match report {
        Report::Irradiance { order, window } => (summary.order, summary.window) = (Some(order), Some(window)),
        Report::Shrm { orders, epsilon_achieved, window } => {
            summary.orders = Some(orders);
            summary.epsilon_achieved = Some(epsilon_achieved);
            summary.window = Some(window);
        }
        Report::Factored { terms, bright } => (summary.terms, summary.bright) = (Some(terms), bright),
        Report::IblGrid { cells, .. } => summary.grid = Some(cells),
        Report::Transfer(relit) => summary.transfer = Some(relit),
        Report::Ibl | Report::Reference => {}
    }
    summary
}

/// Lays out the panel: the items in order (each labelled with its error against the reference
/// when comparing), this render in the item marked `None`, or last.
fn panel(items: &[PanelItem], frame: &Frame, label: &str, config: &Config, metrics: Option<Metrics>) -> RgbImage {
    let with_error = |mut lines: Vec<String>, m: Option<Metrics>| {
        if let Some(m) = m.filter(|m| m.rel_error > 0.0) {
            lines.push(format!("err {:.2}%", 100.0 * m.rel_error));
        }
        lines
    };
    let split = |l: &str| -> Vec<String> { l.split('|').map(str::to_string).collect() };
    let own = |l: &str| Cell { image: frame.image.clone(), label: with_error(split(l), metrics) };
    let mut cells: Vec<Cell> = items
        .iter()
        .map(|item| match &item.image {
            Some(image) => {
                let m = config.compare.as_ref().and_then(|(_, r)| compare(image, r, &frame.mask).ok()).map(|(m, _)| m);
                Cell { label: with_error(split(&item.label), m), image: image.clone() }
            }
            None => own(&item.label),
        })
        .collect();
    if !items.iter().any(|item| item.image.is_none()) {
        cells.push(own(label));
    }
    let legend = match &config.compare {
        Some((name, _)) => {
            let reference = Path::new(name).file_name().map_or(name.clone(), |f| f.to_string_lossy().into_owned());
            vec![format!("err: relative RMS error against {reference}, over the object pixels")]
        }
        None => Vec::new(),
    };
    layout(&cells, &legend, config.exposure)
}
