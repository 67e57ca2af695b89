//! A render's shading path, decided once. [`Plan::new`] checks the [`Config`] against the scene
//! and the environment and settles each mode's alternatives — the SH lighting given or projected,
//! the factorization stored or made here, one glTF material or a grid of them, a transfer bake
//! relit per vertex, per lightmap texel or through its h_k — so that every fault of the inputs is
//! found before any work; [`Plan::execute`] then draws the object and reports what the mode did.

use super::factored::{Factored, Transport};
use super::grid::{render_grid, GridCell, MaterialGrid};
use super::ibl::{IblBake, SplitSum};
use super::irradiance::Irradiance;
use super::panel::Cell;
use super::reference::{Integrand, Reference};
use super::reflection::ShrmShader;
use super::stage::{BrightShare, Config, Error, RelightSummary, Shading, StoredFactors};
use super::stage::{DEFAULT_FACTOR_RESOLUTION, MAX_ENV_ROTATION};
use super::transfer::{relight, rotation_about_z, GlossyBake, LightmapImage, LightmapShader};
use super::transfer::{TransferBake, TransferShader};
use super::{render, render_turned, Camera, Frame, Scene, Shade, Sum};
use crate::brdf::models::GltfMaterial;
use crate::brdf::Brdf;
use crate::envmap::bright::{split, BrightRule};
use crate::envmap::EnvMap;
use crate::factor::{Channel, Domain, Factorization, Method, Sampling};
use crate::limits::MAX_CELL_SAMPLES;
use crate::mesh::Mesh;
use crate::prefilter::document::ShrmBody;
use crate::prefilter::shrm::Shrm;
use crate::progress::{NoProgress, Progress};
use crate::sh::convolve::clamped_cosine;
use crate::sh::rotate::ShRotation;
use crate::sh::window::{self, Window, WindowReport};
use crate::sh::ShCoeffs;
use glam::DMat3;
use std::borrow::Cow;
use std::time::Instant;

/// Frames of relighting timed for [`RelightSummary`].
const RELIGHT_FRAMES: usize = 31;
/// Grid bins n of a factorization made here: at least 2, at most 256 (an n² × n² matrix).
const FACTOR_RESOLUTIONS: std::ops::RangeInclusive<usize> = 2..=256;

/// How the object is shaded, its inputs checked.
pub(super) enum Plan<'a> {
    /// Lambert from SH lighting of order `order` (R&H 2001, eq. 8–9): the `given` coefficients
    /// truncated, or the environment projected.
    Irradiance { albedo: f64, order: usize, given: Option<&'a ShCoeffs>, window: Window },
    /// An SHRM (R&H 2002, eq. 6 and 12), windowed on its view bands.
    Shrm { shrm: &'a Shrm, body: &'a ShrmBody, window: Window },
    /// The K-term in-out factorization (Mahajan et al. 2008, eq. 3–4), bright sources shaded
    /// exactly.
    Factored {
        factors: Factors<'a>,
        terms: usize,
        cell_samples: usize,
        normal_table: (usize, usize),
        bright: BrightRule,
    },
    /// The split sum of one glTF material from an `ibl` bake.
    Ibl { bake: &'a IblBake, material: GltfMaterial },
    /// The split sum of a roughness × metalness grid in the base colour `base`, each cell above its
    /// reference.
    IblGrid { bake: &'a IblBake, base: [f64; 3], grid: &'a MaterialGrid },
    /// A transfer bake's relighting of its mesh (Sloan, Kautz & Snyder 2002) under the
    /// environment turned by `turn`.
    Transfer { bake: &'a TransferBake, mesh: &'a Mesh, relit: Relit<'a>, turn: DMat3 },
    /// Ground truth over every texel of the environment turned by `turn`.
    Reference { integrand: Integrand, turn: DMat3 },
}

/// Where a factored render's factorization comes from.
pub(super) enum Factors<'a> {
    /// `factor-brdf`'s, read back; `cosine`: max(cos θ_i, 0) is folded into it.
    Stored { factorization: &'a Factorization, cosine: bool },
    /// Made here, on the hemisphere with the cosine folded in, at `resolution` bins.
    Here { resolution: usize },
}

/// How a transfer bake's lighting reaches the pixels.
pub(super) enum Relit<'a> {
    /// A glossy bake: B = Σ_k h_k(ω_o) c_k, h_k the bake's, c_k interpolated over the triangles.
    Glossy(&'a GlossyBake),
    /// A diffuse bake's per-vertex radiance, interpolated over the triangles.
    Vertices,
    /// A diffuse lightmap, looked up at the mesh's UVs.
    Lightmap { lightmap: &'a LightmapImage, uvs: &'a [[f64; 2]] },
}

/// What is drawn: the object and its BRDF, the camera, and the environment that lights the object
/// and shows behind it.
pub(super) struct Shot<'a> {
    /// The sphere or the mesh.
    pub scene: &'a Scene,
    /// Its BRDF.
    pub brdf: &'a Brdf,
    /// The camera.
    pub camera: &'a Camera,
    /// The environment.
    pub env: &'a EnvMap,
}

impl Shot<'_> {
    fn draw(&self, shader: &dyn Shade, progress: &dyn Progress) -> Frame {
        render(self.scene, self.camera, self.env, shader, progress)
    }

    fn draw_turned(&self, turn: DMat3, shader: &dyn Shade, progress: &dyn Progress) -> Frame {
        render_turned(self.scene, self.camera, self.env, turn, shader, progress)
    }
}

/// A plan executed: the frame, its default label, and what the mode reports.
pub(super) struct Shaded {
    pub frame: Frame,
    pub label: String,
    pub report: Report,
}

/// What a mode reports in the summary.
pub(super) enum Report {
    /// The SH order and the window at synthesis.
    Irradiance { order: usize, window: WindowReport },
    /// F_B, P_B, the ε the SHRM achieved, and the window at synthesis.
    Shrm { orders: (usize, usize), epsilon_achieved: f64, window: WindowReport },
    /// K and the energy of K terms; the bright sources shaded exactly.
    Factored { terms: (usize, f64), bright: Option<BrightShare> },
    /// Nothing more.
    Ibl,
    /// Every cell's errors, and the panel's rows (split sum above reference).
    IblGrid { cells: Vec<GridCell>, rows: Vec<Vec<Cell>> },
    /// What relighting cost.
    Transfer(RelightSummary),
    /// Nothing more.
    Reference,
}

impl<'a> Plan<'a> {
    /// Checks `config` against `scene` and `env` and decides the path.
    pub(crate) fn new(config: &'a Config, env: &EnvMap, scene: &'a Scene) -> Result<Self, Error> {
        let turn = environment_turn(config)?;
        let brdf = &config.brdf;
        Ok(match &config.shading {
            Shading::Irradiance { order, coefficients, window } => {
                let Brdf::Lambert(m) = brdf else {
                    return Err(Error::NotLambert { shading: "irradiance", brdf: brdf.spec() });
                };
                if let Some(c) = coefficients.as_ref().filter(|c| c.order < *order) {
                    return Err(Error::ShOrder { available: c.order, wanted: *order });
                }
                Plan::Irradiance { albedo: m.albedo, order: *order, given: coefficients.as_ref(), window: *window }
            }
            Shading::Shrm { shrm, body, window } => {
                if body.brdf != brdf.spec() {
                    return Err(Error::ShrmBrdf { shrm: body.brdf.clone(), brdf: brdf.spec() });
                }
                Plan::Shrm { shrm, body, window: *window }
            }
            Shading::Factored { terms, factors, resolution, cell_samples, normal_table, bright } => {
                if *terms == 0 {
                    return Err(Error::NoTerms);
                }
                if !(1..=MAX_CELL_SAMPLES).contains(cell_samples) {
                    return Err(Error::CellSamples(*cell_samples));
                }
                let factors = match factors {
                    Some(stored) => stored_factors(stored, brdf, *terms, *resolution)?,
                    None => factors_here(*terms, *resolution)?,
                };
                Plan::Factored {
                    factors,
                    terms: *terms,
                    cell_samples: *cell_samples,
                    normal_table: *normal_table,
                    bright: *bright,
                }
            }
            Shading::Ibl { bake, grid } => {
                bake.check_source(env)?;
                let Brdf::Gltf(material) = brdf else { return Err(Error::NotGltf { brdf: brdf.spec() }) };
                match grid {
                    None => Plan::Ibl { bake, material: *material },
                    Some(grid) => {
                        if config.compare.is_some() || config.panel.as_ref().is_some_and(|p| !p.is_empty()) {
                            return Err(Error::GridReferences);
                        }
                        // The base colour is the BRDF's; roughness and metalness are the grid's.
                        Plan::IblGrid { bake, base: material.base, grid }
                    }
                }
            }
            Shading::Transfer { bake, factors, lightmap } => {
                let Scene::Mesh(mesh) = scene else { return Err(Error::TransferOfSphere) };
                bake.check_mesh(mesh)?;
                let relit = match &bake.glossy {
                    Some(glossy) => Relit::Glossy(glossy_bake(bake, glossy, factors.as_deref(), brdf)?),
                    None => {
                        diffuse_bake(bake, factors.is_some(), brdf)?;
                        match lightmap.as_deref() {
                            Some(lightmap) => {
                                let uvs = mesh
                                    .uvs
                                    .as_deref()
                                    .ok_or_else(|| Error::NoLightmapUvs { lightmap: lightmap.name.clone() })?;
                                Relit::Lightmap { lightmap, uvs }
                            }
                            None => Relit::Vertices,
                        }
                    }
                };
                Plan::Transfer { bake, mesh, relit, turn }
            }
            Shading::Reference { integrand } => Plan::Reference { integrand: *integrand, turn },
        })
    }

    /// Draws `shot` as planned.
    pub(crate) fn execute(&self, shot: &Shot, progress: &dyn Progress) -> Result<Shaded, Error> {
        match self {
            Plan::Irradiance { albedo, order, given, window } => {
                irradiance(shot, *albedo, *order, *given, *window, progress)
            }
            Plan::Shrm { shrm, body, window } => Ok(reflection(shot, shrm, body, *window, progress)),
            Plan::Factored { factors, terms, cell_samples, normal_table, bright } => {
                factored(shot, factors, *terms, *cell_samples, *normal_table, *bright, progress)
            }
            Plan::Ibl { bake, material } => {
                let frame = shot.draw(&SplitSum::new(*bake, *material), progress);
                let label = format!("ibl r={} m={}", material.specular.roughness(), material.metalness);
                Ok(Shaded { frame, label, report: Report::Ibl })
            }
            Plan::IblGrid { bake, base, grid } => {
                let g = render_grid(grid, *base, bake, shot.env, shot.scene, shot.camera, progress)?;
                let report = Report::IblGrid { cells: g.cells, rows: g.rows };
                Ok(Shaded { frame: g.mosaic, label: "ibl grid".into(), report })
            }
            Plan::Transfer { bake, mesh, relit, turn } => transfer(shot, bake, mesh, relit, *turn, progress),
            Plan::Reference { integrand, turn } => {
                let shader = Reference::new(shot.env, shot.brdf.clone(), *integrand, shot.scene)?.turned(*turn);
                let frame = shot.draw_turned(*turn, &shader, progress);
                Ok(Shaded { frame, label: "reference".into(), report: Report::Reference })
            }
        }
    }
}

/// The turn of the environment about +Z: only transfer and reference shading turn it.
fn environment_turn(config: &Config) -> Result<DMat3, Error> {
    let degrees = config.env_rotation;
    if degrees.is_nan() || degrees.abs() > MAX_ENV_ROTATION {
        return Err(Error::EnvRotation(degrees));
    }
    if degrees != 0.0 && !matches!(config.shading, Shading::Transfer { .. } | Shading::Reference { .. }) {
        return Err(Error::EnvRotationShading { shading: config.shading.name() });
    }
    Ok(rotation_about_z(degrees))
}

/// A stored factorization, if it is of `brdf`, at the `resolution` asked for (if any), with at
/// least `terms` terms.
fn stored_factors<'a>(
    stored: &'a StoredFactors,
    brdf: &Brdf,
    terms: usize,
    resolution: Option<usize>,
) -> Result<Factors<'a>, Error> {
    let (name, f) = (&stored.name, &stored.factorization);
    if stored.brdf != brdf.spec() {
        return Err(Error::FactorsBrdf { factors: name.clone(), factored: stored.brdf.clone(), brdf: brdf.spec() });
    }
    if let Some(asked) = resolution.filter(|&n| n != f.grid.n) {
        return Err(Error::FactorsResolution { factors: name.clone(), stored: f.grid.n, asked });
    }
    if f.g.len() < terms {
        return Err(Error::FactorsTerms { factors: name.clone(), stored: f.g.len(), asked: terms });
    }
    Ok(Factors::Stored { factorization: f, cosine: stored.cosine })
}

/// A factorization to make here, at `resolution` bins (default [`DEFAULT_FACTOR_RESOLUTION`]).
fn factors_here<'a>(terms: usize, resolution: Option<usize>) -> Result<Factors<'a>, Error> {
    let resolution = resolution.unwrap_or(DEFAULT_FACTOR_RESOLUTION);
    if !FACTOR_RESOLUTIONS.contains(&resolution) {
        return Err(Error::FactorResolution(resolution));
    }
    // An n² × n² matrix has at most n² terms: refuse before the factorization.
    if terms > resolution * resolution {
        return Err(Error::TermsAboveRank { terms, resolution });
    }
    Ok(Factors::Here { resolution })
}

/// A glossy bake's h_k, if `brdf` is the BRDF it holds and `factors` (when given) the
/// factorization it was baked from: the reference and the labels use `brdf`.
fn glossy_bake<'a>(
    bake: &TransferBake,
    glossy: &'a GlossyBake,
    factors: Option<&StoredFactors>,
    brdf: &Brdf,
) -> Result<&'a GlossyBake, Error> {
    if let Some(stored) = factors {
        glossy.check_factors(&bake.name, &stored.factorization, &stored.name)?;
    }
    if brdf.spec() != glossy.brdf {
        return Err(Error::TransferBrdf { bake: bake.name.clone(), baked: glossy.brdf.clone(), brdf: brdf.spec() });
    }
    Ok(glossy)
}

/// Whether a diffuse bake relights `brdf`: a Lambertian one of the albedo baked, no factors.
fn diffuse_bake(bake: &TransferBake, with_factors: bool, brdf: &Brdf) -> Result<(), Error> {
    if with_factors {
        return Err(Error::FactorsForDiffuse { bake: bake.name.clone() });
    }
    let Brdf::Lambert(m) = brdf else {
        return Err(Error::DiffuseTransferNotLambert { bake: bake.name.clone(), brdf: brdf.spec() });
    };
    // A coloured bake's colour is in its transfer: it relights lambert of albedo 1.
    let albedo = bake.albedo.unwrap_or(1.0);
    if m.albedo != albedo {
        return Err(match bake.albedo {
            Some(albedo) => Error::TransferAlbedo { bake: bake.name.clone(), albedo, brdf: brdf.spec() },
            None => Error::ColouredTransferAlbedo { bake: bake.name.clone(), brdf: brdf.spec() },
        });
    }
    Ok(())
}

/// Lambert from SH lighting, B = (a/π) Σ Â_l L_lm Y_lm(n) (R&H 2001, eq. 8–9), the window on
/// the lighting's bands.
fn irradiance(
    shot: &Shot,
    albedo: f64,
    order: usize,
    given: Option<&ShCoeffs>,
    window: Window,
    progress: &dyn Progress,
) -> Result<Shaded, Error> {
    let light = match given {
        Some(c) => c.truncated(order),
        None => crate::sh::project::project(shot.env, order, progress)?,
    };
    // The window multiplies the lighting's bands; the bands it shapes are Â_l L_lm.
    let kernel: Vec<f64> = (0..=order).map(clamped_cosine).collect();
    let (frame, window) = windowed(window, &kernel, progress, |factors, progress| {
        shot.draw(&Irradiance::new(&window::apply(&light, factors), albedo), progress)
    });
    Ok(Shaded { frame, label: format!("irradiance F={order}"), report: Report::Irradiance { order, window } })
}

/// From an SHRM, global (R&H 2002, eq. 12) or local (eq. 6), the window on its view bands p.
fn reflection(shot: &Shot, shrm: &Shrm, body: &ShrmBody, window: Window, progress: &dyn Progress) -> Shaded {
    let by_normal = body.parameterization == "normal";
    let (frame, window) = windowed(window, &vec![1.0; body.p_b + 1], progress, |factors, progress| {
        let shader = ShrmShader::new(shrm.with_view_window(factors), by_normal, shot.camera.view_direction());
        shot.draw(&shader, progress)
    });
    let report = Report::Shrm { orders: (body.f_b, body.p_b), epsilon_achieved: body.epsilon_achieved, window };
    Shaded { frame, label: format!("SHRM F={} P={}", body.f_b, body.p_b), report }
}

/// The K-term factorization, B = Σ_k σ_k h_k(ω_o) Σ_i T_k(ω_i) L(ω_i) (Mahajan et al. 2008,
/// eq. 3–4), with the bright texels shaded exactly.
fn factored(
    shot: &Shot,
    factors: &Factors,
    terms: usize,
    cell_samples: usize,
    normal_table: (usize, usize),
    bright: BrightRule,
    progress: &dyn Progress,
) -> Result<Shaded, Error> {
    let (f, cosine_in_factors): (Cow<Factorization>, bool) = match factors {
        Factors::Stored { factorization, cosine } => (Cow::Borrowed(*factorization), *cosine),
        Factors::Here { resolution } => {
            let sampling =
                Sampling { resolution: *resolution, domain: Domain::Hemisphere, cosine: true, channel: Channel::Mean };
            (Cow::Owned(crate::factor::factor(shot.brdf, &sampling, Method::Auto, terms, progress)?), true)
        }
    };
    let transport = match shot.scene {
        Scene::Sphere { .. } => Transport::sphere(normal_table.0, normal_table.1),
        Scene::Mesh(_) => Transport::mesh(shot.scene, &f.grid, progress),
    };
    let energy = f.cumulative_energy().get(terms - 1).copied().unwrap_or(1.0);
    // A truncated factorization spreads a sun 10⁴ times the sky into blotches and negative
    // texels: the bright texels are shaded exactly, the smooth remainder by the factors.
    let (remainder, sources) = split(shot.env, bright);
    let shader = Factored::new(&f, terms, cosine_in_factors, transport, &remainder, cell_samples);
    let label = format!("K={}", shader.terms());
    let exact = sources.texels.iter().map(|t| (t.dir, t.solid_angle, t.excess)).collect();
    let exact = Reference::from_texels(exact, shot.brdf.clone(), Integrand::BrdfCosine, shot.scene)?;
    let bright = (!sources.is_empty())
        .then_some(BrightShare { texels: sources.texels.len(), energy_fraction: sources.energy_fraction });
    let frame = shot.draw(&Sum(&shader, &exact), progress);
    Ok(Shaded { frame, label, report: Report::Factored { terms: (terms, energy), bright } })
}

/// Relighting from a transfer bake: the lighting's SH at the bake's bands, projected once; each
/// timed frame turns it and takes the dot products (K per vertex for a glossy bake).
fn transfer(
    shot: &Shot,
    bake: &TransferBake,
    mesh: &Mesh,
    relit: &Relit,
    turn: DMat3,
    progress: &dyn Progress,
) -> Result<Shaded, Error> {
    let light = crate::sh::project::project(shot.env, bake.order - 1, progress)?;
    let (radiance, summary) = timed_relight(bake, mesh, &light, turn);
    let (frame, label) = match relit {
        // B(x, ω_o) = Σ_k h_k(F_xᵀ ω_o) c_k(x), c_k interpolated over the triangle.
        Relit::Glossy(g) => {
            let coeffs = radiance.iter().map(|c| c.map(f64::from)).collect();
            let shader = Factored::from_vertex_coefficients(g.grid(), &g.h, mesh.triangles.clone(), coeffs);
            let label = format!("transfer glossy {} n={} K={}", bake.mode, bake.order, bake.terms());
            (shot.draw_turned(turn, &shader, progress), label)
        }
        Relit::Lightmap { lightmap, uvs } => {
            let rotation = ShRotation::new(turn, bake.order - 1);
            let shader = LightmapShader::new(lightmap, &light, &rotation, uvs, mesh);
            (shot.draw_turned(turn, &shader, progress), format!("transfer lightmap {} n={}", bake.mode, bake.order))
        }
        Relit::Vertices => {
            let shader = TransferShader::new(radiance, mesh);
            (shot.draw_turned(turn, &shader, progress), format!("transfer {} n={}", bake.mode, bake.order))
        }
    };
    Ok(Shaded { frame, label, report: Report::Transfer(summary) })
}

/// [`RELIGHT_FRAMES`] frames of relighting `bake` by `light` turned by `turn`, each an SH rotation
/// and the per-vertex dot products: the last frame's values and what the frames cost.
fn timed_relight(bake: &TransferBake, mesh: &Mesh, light: &ShCoeffs, turn: DMat3) -> (Vec<[f32; 3]>, RelightSummary) {
    let mut relit = Vec::new();
    let mut times = Vec::with_capacity(RELIGHT_FRAMES);
    for _ in 0..RELIGHT_FRAMES {
        let t = Instant::now();
        let rotation = ShRotation::new(turn, bake.order - 1);
        relight(bake, light, &rotation, &mut relit);
        times.push(t.elapsed().as_secs_f64().max(1e-9));
    }
    times.sort_by(f64::total_cmp);
    let summary = RelightSummary {
        order: bake.order,
        mode: bake.mode.clone(),
        terms: bake.terms(),
        vertices: mesh.positions.len(),
        frames: RELIGHT_FRAMES,
        frames_per_second: 1.0 / times[0],
        median_frames_per_second: 1.0 / times[RELIGHT_FRAMES / 2],
    };
    (relit, summary)
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
