//! `render`: clap arguments → [`render::stage::Config`] (reading the bakes it names) → one
//! library call → outputs.

use super::common::{Context, Outcome, Stage};
use super::options::{parse_brdf, parse_output, parse_size, parse_xyz, EnvArgs, Execution, Exposure};
use super::outputs::{check_writable, Outputs};
use crate::brdf::Brdf;
use crate::io::{self, Output};
use crate::render::mesh::Mesh;
use crate::render::reference::Integrand;
use crate::render::stage::{self, Config, PanelItem, Shading, StoredFactors};
use crate::render::{Camera, Scene};
use anyhow::{bail, Context as _, Result};
use clap::{Parser, ValueEnum};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// Shading modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ShadingArg {
    /// Lambert from SH lighting: (albedo/π) Σ Â_l L_lm Y_lm(n).
    Irradiance,
    /// From a prefilter SHRM (global: distant viewer, eq. 12; local: per pixel, eq. 6).
    Shrm,
    /// K-term in-out factorization, lighting projected onto the factors (Mahajan eq. 4).
    Factored,
    /// Ground truth: sum over every environment texel of L ρ cos (× visibility on meshes).
    Reference,
}

/// Render a sphere or an OBJ mesh under an environment map with one of the bakes, or the
/// reference, and compare.
#[derive(Debug, Parser)]
#[command(name = "render", version)]
pub struct Args {
    #[command(flatten)]
    pub input: EnvArgs,

    /// The object: `sphere` (unit sphere at the origin) or an OBJ file.
    #[arg(long, default_value = "sphere")]
    pub scene: String,

    /// Shading mode.
    #[arg(long, value_enum, default_value_t = ShadingArg::Reference)]
    pub shading: ShadingArg,

    /// BRDF spec (docs/brdf-specs.md). For `shrm` it must equal the SHRM's.
    #[arg(long, default_value = "lambert", value_parser = parse_brdf)]
    pub brdf: Brdf,

    /// Camera position x,y,z (+Z up).
    #[arg(long, value_parser = parse_xyz, allow_hyphen_values = true, default_value = "0,-4,0")]
    pub eye: DVec3,

    /// Point the camera looks at.
    #[arg(long, value_parser = parse_xyz, allow_hyphen_values = true, default_value = "0,0,0")]
    pub target: DVec3,

    /// Vertical field of view in degrees.
    #[arg(long, default_value_t = 32.0)]
    pub fov: f64,

    /// Image size WxH.
    #[arg(long, value_parser = parse_size, default_value = "256x256")]
    pub res: (usize, usize),

    /// irradiance: a prtkit.sh document with the lighting (default: project the environment).
    #[arg(long, value_name = "SH.json")]
    pub sh: Option<PathBuf>,

    /// irradiance: SH order used (truncates --sh; the projection order otherwise).
    #[arg(short = 'F', long, default_value_t = 2)]
    pub order: usize,

    /// shrm: the prtkit.shrm document written by `prefilter --shrm` (names the EXR).
    #[arg(long, value_name = "SHRM.json")]
    pub shrm: Option<PathBuf>,

    /// factored: number of terms K.
    #[arg(short = 'K', long, default_value_t = 12)]
    pub terms: usize,

    /// factored: a prtkit.factor document written by `factor-brdf --factors FILE.exr` (names
    /// the EXR). Without it the BRDF is factored here, on the hemisphere with the cosine folded in.
    #[arg(long, value_name = "FACTOR.json")]
    pub factors: Option<PathBuf>,

    /// factored: bins n of the BRDF matrix's (cos θ, φ) hemisphere grid (n² directions);
    /// default 64. With --factors it must equal the document's resolution.
    #[arg(long)]
    pub factor_resolution: Option<usize>,

    /// factored: lighting samples per grid cell along each axis (averaged: a box prefilter).
    #[arg(long, default_value_t = 2)]
    pub cell_samples: usize,

    /// factored (sphere): size WxH of the lat-long table of normals the lighting is projected at.
    #[arg(long, value_parser = parse_size, default_value = "128x64")]
    pub normal_table: (usize, usize),

    /// reference: `brdf-cosine` (the rendering equation, ρ max(n·ω,0) V) or `prefilter` (the
    /// ρ̂ the prefilter represents: Phong's lobe about R on the whole sphere, §6.3).
    #[arg(long, value_enum, default_value_t = Integrand::BrdfCosine)]
    pub integrand: Integrand,

    /// Linear EXR output (`-`: stdout).
    #[arg(short, long, value_name = "FILE.exr", value_parser = parse_output)]
    pub output: Option<Output>,

    /// Tone-mapped PNG output (× 2^exposure, sRGB).
    #[arg(long, value_name = "FILE.png", value_parser = parse_output)]
    pub png: Option<Output>,

    #[command(flatten)]
    pub exposure: Exposure,

    /// Compare with a reference render of the same size, over the object's pixels.
    #[arg(long, value_name = "REF.exr")]
    pub compare: Option<PathBuf>,

    /// With --compare: write |render − reference| here (EXR, or PNG tone-mapped).
    #[arg(long, value_name = "FILE", value_parser = parse_output)]
    pub error_image: Option<Output>,

    /// With --compare: write the prtkit.render-metrics document here (`-`: stdout).
    #[arg(long, value_name = "FILE.json", value_parser = parse_output)]
    pub metrics: Option<Output>,

    /// Write a labelled panel PNG: the --panel-item images in order, then this render (unless an
    /// item placed it).
    #[arg(long, value_name = "FILE.png", value_parser = parse_output)]
    pub panel: Option<Output>,

    /// A panel cell `LABEL=FILE.exr` (repeatable; with --compare its error is added to the label).
    /// `LABEL=-` places this render there, under that label.
    #[arg(long, value_name = "LABEL=FILE.exr")]
    pub panel_item: Vec<String>,

    /// Label of this render in the panel (default: the shading mode and its parameters).
    #[arg(long)]
    pub label: Option<String>,

    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub run: Execution,
}

impl Args {
    fn outputs(&self) -> impl Iterator<Item = &Output> {
        [&self.output, &self.png, &self.error_image, &self.metrics, &self.panel].into_iter().flatten()
    }

    /// The mode with the bakes it reads (documents and their EXRs).
    fn shading(&self) -> Result<Shading> {
        Ok(match self.shading {
            ShadingArg::Irradiance => Shading::Irradiance {
                order: self.order,
                coefficients: match &self.sh {
                    Some(p) => {
                        let text =
                            std::fs::read_to_string(p).with_context(|| format!("cannot read {}", p.display()))?;
                        let doc =
                            crate::sh::document::parse(&text).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
                        Some(doc.body.coeffs())
                    }
                    None => None,
                },
            },
            ShadingArg::Shrm => {
                let doc =
                    self.shrm.as_ref().context("--shading shrm needs --shrm SHRM.json (from prefilter --shrm)")?;
                let (shrm, body) = crate::render::reflection::load(doc)?;
                Shading::Shrm { shrm, body: Box::new(body) }
            }
            ShadingArg::Factored => {
                let factors = match &self.factors {
                    Some(doc) => {
                        let (body, factorization) = crate::factor::document::load(doc)?;
                        let name = doc.display().to_string();
                        Some(Box::new(StoredFactors { name, factorization, cosine: body.cosine, brdf: body.brdf }))
                    }
                    None => None,
                };
                Shading::Factored {
                    terms: self.terms,
                    factors,
                    resolution: self.factor_resolution,
                    cell_samples: self.cell_samples,
                    normal_table: self.normal_table,
                }
            }
            ShadingArg::Reference => Shading::Reference { integrand: self.integrand },
        })
    }

    /// The panel items: `LABEL=FILE.exr` read, `LABEL=-` for this render.
    fn panel_items(&self) -> Result<Option<Vec<PanelItem>>> {
        if self.panel.is_none() {
            if !self.panel_item.is_empty() {
                bail!("--panel-item needs --panel FILE.png");
            }
            return Ok(None);
        }
        let mut items = Vec::new();
        for s in &self.panel_item {
            let (label, file) =
                s.rsplit_once('=').with_context(|| format!("--panel-item {s:?}: expected LABEL=FILE.exr"))?;
            let image = if file == "-" { None } else { Some(io::image::read_image(Path::new(file))?) };
            items.push(PanelItem { label: label.to_string(), image });
        }
        if items.iter().filter(|item| item.image.is_none()).count() > 1 {
            bail!("--panel-item LABEL=- (this render) may be given once");
        }
        Ok(Some(items))
    }
}

impl Stage for Args {
    const NAME: &'static str = "render";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        if self.outputs().next().is_none() && !self.json {
            bail!("nothing to write: give -o FILE.exr, --png, --panel or --json");
        }
        if (self.error_image.is_some() || self.metrics.is_some()) && self.compare.is_none() {
            bail!("--error-image and --metrics need --compare REF.exr");
        }
        let json_out = self.json.then_some(Output::Stdout);
        check_writable(self.outputs().chain(&json_out))?;
        let camera = Camera::look_at(self.eye, self.target, self.fov, self.res.0, self.res.1)?;
        let scene = if self.scene == "sphere" {
            Scene::unit_sphere()
        } else {
            let mesh = Mesh::load(Path::new(&self.scene))?;
            if mesh.normals_computed {
                ctx.note(format!(
                    "{}: no vertex normals in the file; computed area-weighted normals for {} vertices",
                    self.scene,
                    mesh.positions.len()
                ));
            }
            Scene::Mesh(Box::new(mesh))
        };
        let compare = match &self.compare {
            Some(p) => Some((p.display().to_string(), io::image::read_image(p)?)),
            None => None,
        };
        let config = Config {
            brdf: self.brdf.clone(),
            shading: self.shading()?,
            camera,
            compare,
            panel: self.panel_items()?,
            label: self.label.clone(),
            exposure: self.exposure.stops,
            output_name: self.output.as_ref().map(|o| o.display()),
            args: std::env::args().collect(),
        };
        let env = self.input.load(ctx)?;
        let out = stage::run(&config, &env, &scene, ctx.progress())?;

        let mut outputs = Outputs::new();
        let stops = self.exposure.stops;
        for o in self.output.iter().chain(&self.png) {
            outputs.image(o, &out.frame.image, stops)?;
        }
        if let Some((doc, error_image)) = &out.comparison {
            let m = &doc.body.metrics;
            ctx.note(format!(
                "vs {}: rel error {:.4} ({:.2} %), RMS {:.4e}, PSNR {:.2} dB over {} pixels",
                doc.body.reference,
                m.rel_error,
                100.0 * m.rel_error,
                m.rms,
                m.psnr,
                m.pixels
            ));
            if let Some(o) = &self.error_image {
                outputs.image(o, error_image, stops)?;
            }
            if let Some(o) = &self.metrics {
                outputs.json(o, doc)?;
            }
        }
        if let (Some(o), Some(panel)) = (&self.panel, &out.panel) {
            let bytes = io::png::encode_png(panel, stops).map_err(|e| anyhow::anyhow!("{}: {e}", o.display()))?;
            outputs.bytes(o, bytes)?;
        }
        if let Some(o) = &json_out {
            outputs.json(o, &out.summary)?;
        }
        outputs.commit()?;
        Ok(Outcome::Success)
    }
}
