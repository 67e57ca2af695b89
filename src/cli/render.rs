//! `render`: images of each bake next to ground truth — SH irradiance, SHRMs, K-term factored
//! relighting and a reference integrator — with error images, metrics and labelled panels.

use super::common::{parse_size, parse_xyz, Execution, Outcome};
use super::envinput::EnvInput;
use crate::brdf::Brdf;
use crate::factor::{Channel, Domain, Method, Sampling};
use crate::io::{self, Output, RgbImage};
use crate::metrics::{compare, Metrics};
use crate::render::factored::{Factored, Transport};
use crate::render::irradiance::Irradiance;
use crate::render::mesh::Mesh;
use crate::render::panel::{layout, Cell};
use crate::render::reference::{Integrand, Reference};
use crate::render::reflection::{self, ShrmShader};
use crate::render::{render, Camera, Frame, Scene, Shade};
use anyhow::{bail, Context, Result};
use clap::{Parser, ValueEnum};
use glam::DVec3;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Shading modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Shading {
    /// Lambert from SH lighting: (albedo/π) Σ Â_l L_lm Y_lm(n).
    Irradiance,
    /// From a prefilter SHRM (global: distant viewer, eq. 12; local: per pixel, eq. 6).
    Shrm,
    /// K-term in-out factorization, lighting projected onto the factors (Mahajan eq. 4).
    Factored,
    /// Ground truth: sum over every environment texel of L ρ cos (× visibility on meshes).
    Reference,
}

impl Shading {
    fn name(self) -> &'static str {
        match self {
            Shading::Irradiance => "irradiance",
            Shading::Shrm => "shrm",
            Shading::Factored => "factored",
            Shading::Reference => "reference",
        }
    }
}

/// Render a sphere or an OBJ mesh under an environment map with one of the bakes, or the
/// reference, and compare.
#[derive(Debug, Parser)]
#[command(name = "render", version, about, long_about)]
pub struct Args {
    #[command(flatten)]
    pub input: EnvInput,

    /// The object: `sphere` (unit sphere at the origin) or an OBJ file.
    #[arg(long, default_value = "sphere")]
    pub scene: String,

    /// Shading mode.
    #[arg(long, value_enum, default_value_t = Shading::Reference)]
    pub shading: Shading,

    /// BRDF spec (docs/brdf-specs.md). For `shrm` it must equal the SHRM's.
    #[arg(long, default_value = "lambert")]
    pub brdf: String,

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

    /// Linear EXR output.
    #[arg(short, long, value_name = "FILE.exr")]
    pub output: Option<PathBuf>,

    /// Tone-mapped PNG output (× 2^exposure, sRGB).
    #[arg(long, value_name = "FILE.png")]
    pub png: Option<PathBuf>,

    /// Exposure in stops for PNG outputs.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,

    /// Compare with a reference render of the same size, over the object's pixels.
    #[arg(long, value_name = "REF.exr")]
    pub compare: Option<PathBuf>,

    /// With --compare: write |render − reference| here (EXR, or PNG tone-mapped).
    #[arg(long, value_name = "FILE")]
    pub error_image: Option<PathBuf>,

    /// With --compare: write the metrics JSON here.
    #[arg(long, value_name = "FILE.json")]
    pub metrics: Option<PathBuf>,

    /// Write a labelled panel PNG: the --panel-item images in order, then this render (unless an
    /// item placed it).
    #[arg(long, value_name = "FILE.png")]
    pub panel: Option<PathBuf>,

    /// A panel cell `LABEL=FILE.exr` (repeatable; with --compare its error is added to the label).
    /// `LABEL=-` places this render there, under that label.
    #[arg(long, value_name = "LABEL=FILE.exr")]
    pub panel_item: Vec<String>,

    /// Label of this render in the panel (default: the shading mode and its parameters).
    #[arg(long)]
    pub label: Option<String>,

    /// Print a one-line JSON summary on stdout.
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub run: Execution,
}

fn parse_item(s: &str) -> Result<(String, PathBuf)> {
    let (label, file) = s.rsplit_once('=').with_context(|| format!("--panel-item {s:?}: expected LABEL=FILE.exr"))?;
    Ok((label.to_string(), PathBuf::from(file)))
}

fn write_image(path: &Path, image: &RgbImage, exposure: f32) -> Result<()> {
    io::image::write_image(path, image, exposure).with_context(|| format!("cannot write {}", path.display()))
}

/// Runs `render`.
pub fn run(args: Args) -> Result<Outcome> {
    let bar = args.run.start()?;
    let outputs: Vec<&PathBuf> =
        [&args.output, &args.png, &args.error_image, &args.metrics, &args.panel].into_iter().flatten().collect();
    if outputs.is_empty() && !args.json {
        bail!("nothing to write: give -o FILE.exr, --png, --panel or --json");
    }
    if (args.error_image.is_some() || args.metrics.is_some()) && args.compare.is_none() {
        bail!("--error-image and --metrics need --compare REF.exr");
    }
    for o in &outputs {
        Output::File(o.to_path_buf()).check_writable()?;
    }
    let items: Vec<(String, PathBuf)> = args.panel_item.iter().map(|s| parse_item(s)).collect::<Result<_>>()?;
    if !items.is_empty() && args.panel.is_none() {
        bail!("--panel-item needs --panel FILE.png");
    }
    let brdf = Brdf::parse(&args.brdf).map_err(|e| anyhow::anyhow!("--brdf {}: {e}", args.brdf))?;
    let env = args.input.load()?;
    let (w, h) = args.res;
    let camera = Camera::look_at(args.eye, args.target, args.fov, w, h)?;
    let scene = if args.scene == "sphere" {
        Scene::unit_sphere()
    } else {
        let mesh = Mesh::load(Path::new(&args.scene))?;
        if mesh.normals_computed {
            eprintln!(
                "render: {}: no vertex normals in the file; computed area-weighted normals for {} vertices",
                args.scene,
                mesh.positions.len()
            );
        }
        Scene::Mesh(Box::new(mesh))
    };
    // Read the reference before the long work, so a bad file fails fast.
    let reference = match &args.compare {
        Some(p) => Some(io::image::read_image(p)?),
        None => None,
    };
    if let Some(r) = &reference {
        if (r.width, r.height) != (w, h) {
            bail!(
                "{}: the reference is {}x{}, the render is {w}x{h} (--res)",
                args.compare.as_ref().map(|p| p.display().to_string()).unwrap_or_default(),
                r.width,
                r.height
            );
        }
    }
    // `None` marks the cell of this render (`LABEL=-`).
    let panel_images: Vec<(String, Option<RgbImage>)> = items
        .iter()
        .map(|(l, p)| Ok((l.clone(), if p.as_os_str() == "-" { None } else { Some(io::image::read_image(p)?) })))
        .collect::<Result<_>>()?;
    if panel_images.iter().filter(|(_, i)| i.is_none()).count() > 1 {
        bail!("--panel-item LABEL=- (this render) may be given once");
    }

    let start = Instant::now();
    let mut extra = serde_json::Map::new();
    let label;
    let frame: Frame = match args.shading {
        Shading::Irradiance => {
            let Brdf::Lambert(m) = &brdf else {
                bail!("--shading irradiance shades Lambertian surfaces; --brdf {} is not lambert", brdf.spec());
            };
            let light = match &args.sh {
                Some(p) => {
                    let text = std::fs::read_to_string(p).with_context(|| format!("cannot read {}", p.display()))?;
                    let doc = crate::sh::document::parse(&text).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
                    let c = doc.body.coeffs();
                    if c.order < args.order {
                        bail!(
                            "{}: the coefficients have order {}, --order asks for {}",
                            p.display(),
                            c.order,
                            args.order
                        );
                    }
                    c.truncated(args.order)
                }
                None => crate::sh::project::project(&env, args.order, &bar)?,
            };
            extra.insert("order".into(), args.order.into());
            label = format!("irradiance F={}", args.order);
            render(&scene, &camera, &env, &Irradiance::new(&light, m.albedo), &bar)
        }
        Shading::Shrm => {
            let doc = args.shrm.as_ref().context("--shading shrm needs --shrm SHRM.json (from prefilter --shrm)")?;
            let (shrm, body) = reflection::load(doc)?;
            if body.brdf != brdf.spec() {
                bail!("{}: the SHRM was computed for {}, --brdf says {}", doc.display(), body.brdf, brdf.spec());
            }
            extra.insert("f_b".into(), body.f_b.into());
            extra.insert("p_b".into(), body.p_b.into());
            extra.insert("epsilon_achieved".into(), body.epsilon_achieved.into());
            extra.insert("global".into(), body.global.into());
            label = format!("SHRM F={} P={}", body.f_b, body.p_b);
            let shader = ShrmShader::new(shrm, body.parameterization == "normal", camera.view_direction());
            render(&scene, &camera, &env, &shader, &bar)
        }
        Shading::Factored => {
            if args.terms == 0 {
                bail!("--terms must be at least 1");
            }
            if !(1..=8).contains(&args.cell_samples) {
                bail!("--cell-samples {} must be in 1..=8", args.cell_samples);
            }
            let (f, cosine_in_factors) = match &args.factors {
                Some(doc) => {
                    let (body, f) = crate::factor::document::load(doc)?;
                    if body.brdf != brdf.spec() {
                        bail!("{}: the factorization is of {}, --brdf says {}", doc.display(), body.brdf, brdf.spec());
                    }
                    if let Some(n) = args.factor_resolution.filter(|&n| n != body.resolution) {
                        bail!(
                            "{}: a factorization of another resolution: n = {}, --factor-resolution asks for {n}",
                            doc.display(),
                            body.resolution
                        );
                    }
                    if f.g.len() < args.terms {
                        bail!(
                            "{}: the factor file holds {} terms, --terms asks for {} (factor-brdf --terms {})",
                            doc.display(),
                            f.g.len(),
                            args.terms,
                            args.terms
                        );
                    }
                    (f, body.cosine)
                }
                None => {
                    let resolution = args.factor_resolution.unwrap_or(64);
                    if !(2..=256).contains(&resolution) {
                        bail!("--factor-resolution {resolution} must be in 2..=256");
                    }
                    let sampling =
                        Sampling { resolution, domain: Domain::Hemisphere, cosine: true, channel: Channel::Mean };
                    (crate::factor::factor(&brdf, &sampling, Method::Auto, args.terms, &bar)?, true)
                }
            };
            let transport = match &scene {
                Scene::Sphere { .. } => Transport::sphere(args.normal_table.0, args.normal_table.1),
                Scene::Mesh(_) => Transport::mesh(&scene, &f.grid, &bar),
            };
            extra.insert("k".into(), args.terms.into());
            extra.insert("energy".into(), f.cumulative_energy().get(args.terms - 1).copied().unwrap_or(1.0).into());
            let shader = Factored::new(&f, args.terms, cosine_in_factors, transport, &env, args.cell_samples);
            label = format!("K={}", shader.terms());
            render(&scene, &camera, &env, &shader, &bar)
        }
        Shading::Reference => {
            let shader = Reference::new(&env, brdf.clone(), args.integrand, &scene).map_err(|e| anyhow::anyhow!(e))?;
            extra.insert("texels".into(), shader.texel_count().into());
            label = "reference".to_string();
            render(&scene, &camera, &env, &shader as &dyn Shade, &bar)
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    let label = args.label.clone().unwrap_or(label);

    let mut metrics: Option<Metrics> = None;
    if let (Some(r), Some(rp)) = (&reference, &args.compare) {
        let (m, err) =
            compare(&frame.image, r, &frame.mask).with_context(|| format!("comparing with {}", rp.display()))?;
        eprintln!(
            "render: vs {}: rel error {:.4} ({:.2} %), RMS {:.4e}, PSNR {:.2} dB over {} pixels",
            rp.display(),
            m.rel_error,
            100.0 * m.rel_error,
            m.rms,
            m.psnr,
            m.pixels
        );
        if let Some(p) = &args.error_image {
            write_image(p, &err, args.exposure)?;
        }
        if let Some(p) = &args.metrics {
            let doc = serde_json::json!({
                "format": "prtkit.render-metrics", "version": 1,
                "render": args.output.as_ref().map(|p| p.display().to_string()),
                "reference": rp.display().to_string(),
                "shading": args.shading.name(), "brdf": brdf.spec(), "label": label,
                "metrics": m,
            });
            io::write_atomic(p, io::document::to_json_pretty(&doc).as_bytes())?;
        }
        metrics = Some(m);
    }
    if let Some(p) = &args.output {
        write_image(p, &frame.image, args.exposure)?;
    }
    if let Some(p) = &args.png {
        write_image(p, &frame.image, args.exposure)?;
    }
    if let Some(p) = &args.panel {
        let with_error = |mut lines: Vec<String>, m: Option<Metrics>| {
            if let Some(m) = m.filter(|m| m.rel_error > 0.0) {
                lines.push(format!("{:.2}%", 100.0 * m.rel_error));
            }
            lines
        };
        let split = |l: &str| -> Vec<String> { l.split('|').map(str::to_string).collect() };
        let own = |l: &str| Cell { image: frame.image.clone(), label: with_error(split(l), metrics) };
        let mut cells = Vec::new();
        for (l, img) in panel_images {
            cells.push(match img {
                Some(image) => {
                    let m = reference.as_ref().and_then(|r| compare(&image, r, &frame.mask).ok()).map(|(m, _)| m);
                    Cell { label: with_error(split(&l), m), image }
                }
                None => own(&l),
            });
        }
        if !items.iter().any(|(_, p)| p.as_os_str() == "-") {
            cells.push(own(&label));
        }
        let img = layout(&cells, args.exposure);
        let bytes = io::png::encode_png(&img, args.exposure).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
        io::write_atomic(p, &bytes)?;
    }
    if args.json {
        let mut summary = serde_json::Map::new();
        summary.insert("shading".into(), args.shading.name().into());
        summary.insert("brdf".into(), brdf.spec().into());
        summary.insert("width".into(), w.into());
        summary.insert("height".into(), h.into());
        summary.insert("seconds".into(), seconds.into());
        summary.extend(extra);
        if let Some(m) = metrics {
            summary.insert("rel_error".into(), m.rel_error.into());
            summary.insert("rms".into(), m.rms.into());
            summary.insert("psnr".into(), if m.psnr.is_finite() { m.psnr.into() } else { serde_json::Value::Null });
        }
        println!("{}", serde_json::Value::Object(summary));
    }
    Ok(Outcome::Success)
}
