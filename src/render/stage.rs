//! The `render` stage as one library call: a sphere or mesh shaded with one of the bakes (SH
//! irradiance, an SHRM, a K-term factorization) or the reference integrator, compared with a
//! reference render, and laid out in a labelled panel.

use super::factored::{Factored, Transport};
use super::grid::{render_grid, GridCell, MaterialGrid};
use super::ibl::{IblBake, SplitSum};
use super::irradiance::Irradiance;
use super::panel::{layout, layout_grid, Cell};
use super::reference::{Integrand, Reference};
use super::reflection::ShrmShader;
use super::transfer::TransferBake;
use super::{render, render_turned, Camera, Frame, Scene, Sum};
use crate::brdf::Brdf;
use crate::envmap::bright::{split, BrightRule};
use crate::envmap::EnvMap;
use crate::factor::{Channel, Domain, Factorization, Method, Sampling};
use crate::io::{Document, Provenance, RgbImage};
use crate::metrics::{compare, Metrics};
use crate::prefilter::document::ShrmBody;
use crate::prefilter::shrm::Shrm;
use crate::progress::NoProgress;
use crate::progress::Progress;
use crate::sh::convolve::clamped_cosine;
use crate::sh::window::{self, Window, WindowReport};
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
        /// render of `--brdf`'s material.
        grid: Option<MaterialGrid>,
    },
    /// From a `transfer` bake: the per-vertex dot product with the environment's SH (Sloan,
    /// Kautz & Snyder 2002), interpolated over the triangles.
    Transfer {
        /// The bake, read from its `.glb`.
        bake: Box<TransferBake>,
        /// The factorization a glossy bake was made with (`--factors`), for h_k.
        factors: Option<Box<StoredFactors>>,
        /// The per-texel lightmap to shade from instead of the vertices (`--lightmap`).
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

/// Most degrees `--env-rotation` turns the environment by, either way.
pub const MAX_ENV_ROTATION: f64 = 360.0;
/// Frames of relighting timed for [`RelightSummary`].
const RELIGHT_FRAMES: usize = 31;

/// The bright texels a factored render shades exactly, and their share of the map's energy.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct BrightShare {
    /// Texels shaded exactly.
    pub texels: usize,
    /// Their excess over the threshold, as a share of the map's radiant energy.
    pub energy_fraction: f64,
}

/// Errors of the stage.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The configuration is inconsistent (BRDF vs mode, sizes, counts).
    #[error("{0}")]
    Config(String),
    /// Projection of the lighting failed.
    #[error(transparent)]
    Project(#[from] crate::sh::project::ProjectError),
    /// The factorization failed.
    #[error(transparent)]
    Factor(#[from] crate::factor::FactorError),
    /// The `ibl` bake was made from another map.
    #[error(transparent)]
    OtherSource(#[from] super::ibl::OtherSource),
    /// Comparing failed.
    #[error("comparing with {reference}: {error}")]
    Compare {
        /// The reference's name.
        reference: String,
        /// Why.
        error: crate::metrics::CompareError,
    },
}

/// Runs `render` of `scene` under `env`.
pub fn run(config: &Config, env: &EnvMap, scene: &Scene, progress: &dyn Progress) -> Result<Output, Error> {
    let bad = |m: String| Error::Config(m);
    let (w, h) = (config.camera.width, config.camera.height);
    if let Some((name, r)) = &config.compare {
        if (r.width, r.height) != (w, h) {
            return Err(bad(format!(
                "{name}: the reference is {}x{}, the render is {w}x{h} (--res)",
                r.width, r.height
            )));
        }
    }
    if let Shading::Ibl { bake, .. } = &config.shading {
        bake.check_source(env)?;
    }
    if config.env_rotation.is_nan() || config.env_rotation.abs() > MAX_ENV_ROTATION {
        return Err(bad(format!("--env-rotation {} is outside -360..=360 degrees", config.env_rotation)));
    }
    if config.env_rotation != 0.0 && !matches!(config.shading, Shading::Transfer { .. } | Shading::Reference { .. }) {
        return Err(bad("--env-rotation is for --shading transfer and reference".into()));
    }
    let turn = super::transfer::rotation_about_z(config.env_rotation);
    let brdf = &config.brdf;
    let start = Instant::now();
    let mut summary = Summary {
        shading: config.shading.name().into(),
        brdf: brdf.spec(),
        width: w,
        height: h,
        seconds: 0.0,
        label: String::new(),
        order: None,
        orders: None,
        epsilon_achieved: None,
        terms: None,
        bright: None,
        window: None,
        metrics: None,
        grid: None,
        transfer: None,
    };
    let mut grid_panel = None;
    let (frame, label) = match &config.shading {
        Shading::Irradiance { order, coefficients, window } => {
            let Brdf::Lambert(m) = brdf else {
                return Err(bad(format!(
                    "--shading irradiance shades Lambertian surfaces; --brdf {} is not lambert",
                    brdf.spec()
                )));
            };
            let light = match coefficients {
                Some(c) if c.order < *order => {
                    return Err(bad(format!("the coefficients have order {}, --order asks for {order}", c.order)))
                }
                Some(c) => c.truncated(*order),
                None => crate::sh::project::project(env, *order, progress)?,
            };
            summary.order = Some(*order);
            // The window multiplies the lighting's bands; the bands it shapes are Â_l L_lm.
            let kernel: Vec<f64> = (0..=*order).map(clamped_cosine).collect();
            let (frame, report) = windowed(*window, &kernel, progress, |factors, progress| {
                let shader = Irradiance::new(&window::apply(&light, factors), m.albedo);
                render(scene, &config.camera, env, &shader, progress)
            });
            summary.window = Some(report);
            (frame, format!("irradiance F={order}"))
        }
        Shading::Shrm { shrm, body, window } => {
            if body.brdf != brdf.spec() {
                return Err(bad(format!("the SHRM was computed for {}, --brdf says {}", body.brdf, brdf.spec())));
            }
            summary.orders = Some((body.f_b, body.p_b));
            summary.epsilon_achieved = Some(body.epsilon_achieved);
            let by_normal = body.parameterization == "normal";
            let (frame, report) = windowed(*window, &vec![1.0; body.p_b + 1], progress, |factors, progress| {
                let shader = ShrmShader::new(shrm.with_view_window(factors), by_normal, config.camera.view_direction());
                render(scene, &config.camera, env, &shader, progress)
            });
            summary.window = Some(report);
            (frame, format!("SHRM F={} P={}", body.f_b, body.p_b))
        }
        Shading::Factored { terms, factors, resolution, cell_samples, normal_table, bright } => {
            if *terms == 0 {
                return Err(bad("--terms must be at least 1".into()));
            }
            if !(1..=8).contains(cell_samples) {
                return Err(bad(format!("--cell-samples {cell_samples} must be in 1..=8")));
            }
            let (f, cosine_in_factors) = match factors {
                Some(stored) => {
                    let (name, f) = (&stored.name, &stored.factorization);
                    if stored.brdf != brdf.spec() {
                        return Err(bad(format!(
                            "{name}: the factorization is of {}, --brdf says {}",
                            stored.brdf,
                            brdf.spec()
                        )));
                    }
                    if let Some(n) = resolution.filter(|&n| n != f.grid.n) {
                        return Err(bad(format!(
                            "{name}: a factorization of another resolution: n = {}, --factor-resolution asks for {n}",
                            f.grid.n
                        )));
                    }
                    if f.g.len() < *terms {
                        return Err(bad(format!(
                            "{name}: the factor file holds {} terms, --terms asks for {terms} (factor-brdf --terms {terms})",
                            f.g.len()
                        )));
                    }
                    (f.clone(), stored.cosine)
                }
                None => {
                    let resolution = &resolution.unwrap_or(DEFAULT_FACTOR_RESOLUTION);
                    if !(2..=256).contains(resolution) {
                        return Err(bad(format!("--factor-resolution {resolution} must be in 2..=256")));
                    }
                    // An n² × n² matrix has at most n² terms: refuse before the factorization.
                    if *terms > resolution * resolution {
                        return Err(bad(format!(
                            "--terms {terms} is more than the {} a factorization at --factor-resolution {resolution} has",
                            resolution * resolution
                        )));
                    }
                    let sampling = Sampling {
                        resolution: *resolution,
                        domain: Domain::Hemisphere,
                        cosine: true,
                        channel: Channel::Mean,
                    };
                    (crate::factor::factor(brdf, &sampling, Method::Auto, *terms, progress)?, true)
                }
            };
            let transport = match scene {
                Scene::Sphere { .. } => Transport::sphere(normal_table.0, normal_table.1),
                Scene::Mesh(_) => Transport::mesh(scene, &f.grid, progress),
            };
            let energy = f.cumulative_energy().get(terms - 1).copied().unwrap_or(1.0);
            summary.terms = Some((*terms, energy));
            // A truncated factorization spreads a sun 10⁴ times the sky into blotches and negative
            // texels: the bright texels are shaded exactly, the smooth remainder by the factors.
            let (remainder, sources) = split(env, *bright);
            let shader = Factored::new(&f, *terms, cosine_in_factors, transport, &remainder, *cell_samples);
            let label = format!("K={}", shader.terms());
            let exact = sources.texels.iter().map(|t| (t.dir, t.solid_angle, t.excess)).collect();
            let exact = Reference::from_texels(exact, brdf.clone(), Integrand::BrdfCosine, scene).map_err(bad)?;
            summary.bright = (!sources.is_empty())
                .then_some(BrightShare { texels: sources.texels.len(), energy_fraction: sources.energy_fraction });
            (render(scene, &config.camera, env, &Sum(&shader, &exact), progress), label)
        }
        Shading::Ibl { bake, grid } => {
            let Brdf::Gltf(material) = brdf else {
                return Err(bad(format!(
                    "--shading ibl shades glTF metallic-roughness materials; --brdf {} is not gltf:base=R/G/B,metalness=M,roughness=R",
                    brdf.spec()
                )));
            };
            match grid {
                None => {
                    let frame = render(scene, &config.camera, env, &SplitSum::new(bake.as_ref(), *material), progress);
                    let r = material.specular.roughness();
                    (frame, format!("ibl r={r} m={}", material.metalness))
                }
                Some(grid) => {
                    if config.compare.is_some() || config.panel.as_ref().is_some_and(|p| !p.is_empty()) {
                        return Err(bad("--grid renders its own references: no --compare or --panel-item".into()));
                    }
                    // The base colour is --brdf's; roughness and metalness are the grid's.
                    let g =
                        render_grid(grid, material.base, bake, env, scene, &config.camera, progress).map_err(bad)?;
                    summary.grid = Some(g.cells);
                    grid_panel = Some(layout_grid(&g.rows, &super::grid::legend(), config.exposure));
                    (g.mosaic, "ibl grid".to_string())
                }
            }
        }
        Shading::Transfer { bake, factors, lightmap } => {
            let Scene::Mesh(mesh) = scene else {
                return Err(
                    bad("--shading transfer relights a mesh: --scene FILE.obj, the mesh the bake is of".into()),
                );
            };
            bake.check_mesh(mesh, "the --scene mesh").map_err(bad)?;
            // The BRDF the bake holds must be --brdf's (the reference and the labels use it).
            // A glossy bake carries h_k; --factors, when given, must be what it was baked from.
            let glossy = match (&bake.glossy, factors) {
                (Some(glossy), stored) => {
                    if let Some(stored) = stored {
                        glossy.check_factors(&bake.name, &stored.factorization, &stored.name).map_err(bad)?;
                    }
                    if brdf.spec() != glossy.brdf {
                        return Err(bad(format!(
                            "{}: the transfer holds {}, --brdf says {}",
                            bake.name,
                            glossy.brdf,
                            brdf.spec()
                        )));
                    }
                    Some(glossy)
                }
                (None, Some(_)) => {
                    return Err(bad(format!("{}: a diffuse transfer; --factors is for glossy bakes", bake.name)))
                }
                (None, None) => {
                    let Brdf::Lambert(m) = brdf else {
                        return Err(bad(format!(
                            "{}: a diffuse transfer relights a lambert BRDF; --brdf {} is not lambert",
                            bake.name,
                            brdf.spec()
                        )));
                    };
                    if m.albedo != bake.albedo {
                        return Err(bad(format!(
                            "{}: the transfer was baked with albedo {}, --brdf says {}",
                            bake.name,
                            bake.albedo,
                            brdf.spec()
                        )));
                    }
                    None
                }
            };
            // The lighting's SH at the bake's bands, projected once; each frame turns it and
            // takes the dot products (K per vertex for a glossy bake).
            let light = crate::sh::project::project(env, bake.order - 1, progress)?;
            let mut relit = Vec::new();
            let mut times = Vec::with_capacity(RELIGHT_FRAMES);
            for _ in 0..RELIGHT_FRAMES {
                let t = Instant::now();
                let rotation = crate::sh::rotate::ShRotation::new(turn, bake.order - 1);
                super::transfer::relight(bake, &light, &rotation, &mut relit);
                times.push(t.elapsed().as_secs_f64().max(1e-9));
            }
            times.sort_by(f64::total_cmp);
            summary.transfer = Some(RelightSummary {
                order: bake.order,
                mode: bake.mode.clone(),
                terms: bake.terms(),
                vertices: mesh.positions.len(),
                frames: RELIGHT_FRAMES,
                frames_per_second: 1.0 / times[0],
                median_frames_per_second: 1.0 / times[RELIGHT_FRAMES / 2],
            });
            match glossy {
                // B(x, ω_o) = Σ_k h_k(F_xᵀ ω_o) c_k(x), c_k interpolated over the triangle.
                Some(g) => {
                    let coeffs = relit.iter().map(|c| c.map(f64::from)).collect();
                    let shader = Factored::from_vertex_coefficients(g.grid(), &g.h, mesh.triangles.clone(), coeffs);
                    let frame = render_turned(scene, &config.camera, env, turn, &shader, progress);
                    (frame, format!("transfer glossy {} n={} K={}", bake.mode, bake.order, bake.terms()))
                }
                None if lightmap.is_some() => {
                    let lightmap = lightmap.as_deref().expect("matched");
                    let uvs = mesh.uvs.as_deref().ok_or_else(|| {
                        bad(format!(
                            "{}: the --scene mesh has no lightmap UVs (TEXCOORD_1/TEXCOORD_0 or vt) to look the lightmap up with",
                            lightmap.name
                        ))
                    })?;
                    let rotation = crate::sh::rotate::ShRotation::new(turn, bake.order - 1);
                    let shader = super::transfer::LightmapShader::new(lightmap, &light, &rotation, uvs, mesh);
                    let frame = render_turned(scene, &config.camera, env, turn, &shader, progress);
                    (frame, format!("transfer lightmap {} n={}", bake.mode, bake.order))
                }
                None => {
                    let shader = super::transfer::TransferShader::new(relit, mesh);
                    let frame = render_turned(scene, &config.camera, env, turn, &shader, progress);
                    (frame, format!("transfer {} n={}", bake.mode, bake.order))
                }
            }
        }
        Shading::Reference { integrand } => {
            let shader = Reference::new(env, brdf.clone(), *integrand, scene).map_err(bad)?.turned(turn);
            (render_turned(scene, &config.camera, env, turn, &shader, progress), "reference".to_string())
        }
    };
    summary.seconds = start.elapsed().as_secs_f64();
    let label = config.label.clone().unwrap_or(label);
    summary.label = label.clone();

    let comparison = match &config.compare {
        Some((name, reference)) => {
            let (metrics, error_image) = compare(&frame.image, reference, &frame.mask)
                .map_err(|error| Error::Compare { reference: name.clone(), error })?;
            summary.metrics = Some(metrics);
            let body = MetricsBody {
                render: config.output_name.clone(),
                reference: name.clone(),
                shading: config.shading.name().into(),
                brdf: brdf.spec(),
                label: label.clone(),
                metrics,
            };
            let provenance = Provenance::new("render", &config.args, vec![name.clone()]);
            let document = Document::new(METRICS_FORMAT, METRICS_VERSION, provenance, body)
                .with_input_orientation(env.orientation().describe());
            Some((document, error_image))
        }
        None => None,
    };
    let panel = match grid_panel {
        Some(grid) => config.panel.is_some().then_some(grid),
        None => config.panel.as_ref().map(|items| panel(items, &frame, &label, config, summary.metrics)),
    };
    Ok(Output { frame, comparison, panel, summary })
}

/// Renders with `window`'s band factors for bands 0..=F (F + 1 = `kernel.len()`), then, unless
/// the window is `none`, the non-negativity guard [`window::nonneg`] on the object's pixels (one
/// render when none is negative; the search renders without progress). `kernel` is the zonal
/// factors the window multiplies, which bracket the search.
fn windowed(
    kind: Window,
    kernel: &[f64],
    progress: &dyn Progress,
    draw: impl Fn(&[f64], &dyn Progress) -> Frame,
) -> (Frame, WindowReport) {
    let order = kernel.len().saturating_sub(1);
    let base = kind.factors(order);
    if !kind.guarded() || order == 0 {
        let t = kind.guarded().then_some(0.0);
        return (draw(&base, progress), WindowReport { kind, t });
    }
    let object_min = |frame: &Frame| {
        frame
            .image
            .pixels
            .iter()
            .zip(&frame.mask)
            .filter(|(_, &m)| m)
            .flat_map(|(p, _)| p)
            .fold(0.0f64, |a, &v| a.min(v as f64))
    };
    let found = window::nonneg(&base, kernel, |factors| draw(factors, &NoProgress), object_min);
    (found.map, WindowReport { kind, t: Some(found.t) })
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
