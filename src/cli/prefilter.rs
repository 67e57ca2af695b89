//! `prefilter`: clap arguments → [`prefilter::stage::Config`] → one library call → outputs.

use super::common::{Context, Outcome, Stage};
use super::options::{check_json_output, parse_brdf, parse_direction, parse_output, parse_size, EnvArgs};
use super::options::{Execution, Exposure};
use super::outputs::{check_writable, Outputs};
use crate::brdf::Brdf;
use crate::envmap::Layout;
use crate::io::{self, Output, RgbImage};
use crate::prefilter::pipeline::Lighting;
use crate::prefilter::stage::{self, icosahedron_views, view_grid, Config, MapRequest, Method};
use anyhow::{bail, Context as _, Result};
use clap::{Parser, ValueEnum};
use glam::DVec3;
use std::path::PathBuf;

/// Layouts the prefilter writes its images in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum OutputLayout {
    /// Equirectangular, 2:1.
    Latlong,
    /// Horizontal cube cross, 4:3 (resampled from lat-long).
    CrossHorizontal,
    /// Vertical cube cross, 3:4 (resampled from lat-long).
    CrossVertical,
}

/// Prefilter an environment map with a BRDF: spherical harmonic reflection maps (SHRMs) and
/// reflection maps, orders of magnitude faster than angular integration (Ramamoorthi & Hanrahan
/// 2002).
#[derive(Debug, Parser)]
#[command(name = "prefilter", version)]
pub struct Args {
    /// Environment map (.exr/.hdr/.pfm, a face directory, or `-` for stdin). Omit with --sh.
    #[arg(value_name = "ENVMAP", required_unless_present = "sh")]
    pub env: Option<PathBuf>,

    /// Layout of the environment map (detected by default).
    #[arg(long)]
    pub layout: Option<Layout>,

    /// Negative pixel components: error, clamp (to 0) or keep.
    #[arg(long, default_value = "error")]
    pub negative: crate::envmap::NegativePolicy,

    /// Lighting as a `prtkit.sh` document from sh-project (`-`: stdin) instead of a map
    /// (frequency method).
    #[arg(long, value_name = "SH.json", conflicts_with = "env")]
    pub sh: Option<PathBuf>,

    /// BRDF spec, e.g. phong:s=32, lambert, torrance-sparrow:sigma=0.2, merl:FILE (docs/brdf-specs.md).
    #[arg(long, value_parser = parse_brdf)]
    pub brdf: Brdf,

    /// Tolerance: the smallest F_B, P_B keeping 1 - ε of the BRDF energy (§5.1). Also the angular
    /// method's truncation.
    #[arg(short = 'e', long, default_value_t = 0.01)]
    pub epsilon: f64,

    /// Fixed orders F_B[,P_B] instead of choosing them from ε.
    #[arg(long, value_parser = parse_orders)]
    pub order: Option<(usize, usize)>,

    /// Largest P_B the ε search considers (at most 16).
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u64).range(0..=16))]
    pub max_p: u64,

    /// Use the model itself as ρ̂, without folding in max(N·ω_i, 0): the convention of R&H's
    /// microfacet (eq. 11) and Table 5. (Phong and Lambert always follow the paper's 1-D form.)
    #[arg(long)]
    pub no_cosine: bool,

    /// Report the conservative residual-energy bound of App. B in the JSON.
    #[arg(long)]
    pub bound: bool,

    /// Size WxH of the lat-long grid of reflection vectors (S_B). Default 2S x S with
    /// S = clamp(10·F_B, 32, 512) (§5.2: S ≈ 10F).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(usize, usize)>,

    /// Layout of the images written (cube crosses are resampled from lat-long).
    #[arg(long = "output-layout", value_enum, default_value_t = OutputLayout::Latlong)]
    pub output_layout: OutputLayout,

    /// `prtkit.shrm` document (`-` for stdout, the default when --json is not given).
    #[arg(short, long, value_parser = parse_output)]
    pub output: Option<Output>,

    /// Write the SHRM as one EXR with (P_B+1)² RGB layers named B<p><±q>.
    #[arg(long, value_name = "FILE.exr")]
    pub shrm: Option<PathBuf>,

    /// Store global coefficients (eq. 7–8) in --shrm instead of local ones (eq. 6).
    #[arg(long)]
    pub global: bool,

    /// View direction x,y,z (towards the viewer) for --reflection-map; repeatable, paired in order.
    #[arg(long, value_parser = parse_direction, allow_hyphen_values = true)]
    pub view: Vec<DVec3>,

    /// Reflection map for the matching --view (eq. 12): .exr, .pfm or .png; repeatable.
    #[arg(long, value_name = "FILE")]
    pub reflection_map: Vec<PathBuf>,

    /// Write Cabral's 12 icosahedral reflection maps ico00..ico11.exr into DIR (created).
    #[arg(long, value_name = "DIR")]
    pub icosahedral: Option<PathBuf>,

    /// Write a T x T grid of reflection maps view_<j>_<i>.exr into --views-dir (T ≤ 64).
    #[arg(long, value_name = "T", requires = "views_dir", value_parser = clap::value_parser!(u64).range(1..=64))]
    pub views: Option<u64>,

    /// Directory for --views (created).
    #[arg(long, value_name = "DIR")]
    pub views_dir: Option<PathBuf>,

    /// Kautz–McCool 3-D texture B(α, β, θ_o) from the q = 0 terms, one EXR layer per θ_o slice.
    #[arg(long, value_name = "FILE.exr")]
    pub kautz_mccool: Option<PathBuf>,

    /// Number of θ_o slices for --kautz-mccool (1..=256).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u64).range(1..=256))]
    pub slices: u64,

    /// Irradiance map E(N) for a lambert BRDF (the reflection map × π/albedo).
    #[arg(long, value_name = "FILE")]
    pub irradiance: Option<PathBuf>,

    /// frequency (default) or angular (the reference; reflection maps only).
    #[arg(long, value_enum, default_value_t = MethodArg::Frequency)]
    pub method: MethodArg,

    #[command(flatten)]
    pub exposure: Exposure,

    /// Print a summary (orders, ε, timings) on stdout.
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub run: Execution,
}

/// `--method`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Spherical-harmonic prefiltering (R&H 2002 App. C).
    Frequency,
    /// Direct integration over the environment per output texel, BRDF truncated at ε (App. D).
    Angular,
}

fn parse_orders(s: &str) -> Result<(usize, usize), String> {
    let mut parts = s.split(',');
    let f = parts.next().unwrap_or("").trim().parse().map_err(|_| format!("expected F or F,P, got {s:?}"))?;
    let p = match parts.next() {
        Some(p) => p.trim().parse().map_err(|_| format!("expected F or F,P, got {s:?}"))?,
        None => 0,
    };
    if parts.next().is_some() || f > 200 || p > 16 {
        return Err(format!("orders {s:?}: expected F,P with F <= 200 and P <= 16"));
    }
    Ok((f, p))
}

impl Args {
    /// Every reflection map asked for, with its file: --view/--reflection-map pairs, the
    /// icosahedron, the T×T grid.
    fn map_files(&self) -> Result<Vec<(PathBuf, DVec3)>> {
        if !self.reflection_map.is_empty() && !self.view.is_empty() && self.reflection_map.len() != self.view.len() {
            bail!(
                "give one --view per --reflection-map ({} views, {} maps)",
                self.view.len(),
                self.reflection_map.len()
            );
        }
        let mut out: Vec<(PathBuf, DVec3)> = self
            .reflection_map
            .iter()
            .enumerate()
            .map(|(i, p)| (p.clone(), self.view.get(i).copied().unwrap_or(DVec3::Z)))
            .collect();
        if let Some(dir) = &self.icosahedral {
            out.extend(
                icosahedron_views().into_iter().enumerate().map(|(i, v)| (dir.join(format!("ico{i:02}.exr")), v)),
            );
        }
        if let (Some(t), Some(dir)) = (self.views, &self.views_dir) {
            let t = t as usize;
            out.extend(
                view_grid(t)
                    .into_iter()
                    .enumerate()
                    .map(|(k, v)| (dir.join(format!("view_{:02}_{:02}.exr", k / t, k % t)), v)),
            );
        }
        if self.view.len() > self.reflection_map.len() {
            bail!("--view needs a matching --reflection-map FILE");
        }
        Ok(out)
    }

    fn document_output(&self) -> Option<Output> {
        match (&self.output, self.json) {
            (Some(o), _) => Some(o.clone()),
            (None, false) => Some(Output::Stdout),
            (None, true) => None,
        }
    }
}

impl TryFrom<&Args> for Config {
    type Error = anyhow::Error;
    fn try_from(args: &Args) -> Result<Config> {
        Ok(Config {
            brdf: args.brdf.clone(),
            cosine: !args.no_cosine,
            method: match args.method {
                MethodArg::Frequency => Method::Frequency,
                MethodArg::Angular => Method::Angular,
            },
            epsilon: args.epsilon,
            orders: args.order,
            max_p: args.max_p as usize,
            bound: args.bound,
            size: args.size,
            output_layout: match args.output_layout {
                OutputLayout::Latlong => Layout::LatLong,
                OutputLayout::CrossHorizontal => Layout::CrossHorizontal,
                OutputLayout::CrossVertical => Layout::CrossVertical,
            },
            shrm_file: args.shrm.as_ref().map(|p| p.display().to_string()),
            global: args.global,
            maps: args
                .map_files()?
                .into_iter()
                .map(|(file, view)| MapRequest { file: file.display().to_string(), view })
                .collect(),
            kautz_mccool_slices: if args.kautz_mccool.is_some() { args.slices as usize } else { 0 },
            irradiance: args.irradiance.is_some(),
            source: match (&args.env, &args.sh) {
                (Some(p), _) | (None, Some(p)) if p.as_os_str() == "-" => "<stdin>".into(),
                (Some(p), _) | (None, Some(p)) => p.display().to_string(),
                (None, None) => String::new(),
            },
            args: std::env::args().collect(),
        })
    }
}

impl Stage for Args {
    const NAME: &'static str = "prefilter";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        let document = self.document_output();
        if let Some(o) = &document {
            check_json_output(o, self.json)?;
        }
        let map_files = self.map_files()?;
        let files: Vec<Output> = map_files
            .iter()
            .map(|(p, _)| p)
            .chain(&self.shrm)
            .chain(&self.kautz_mccool)
            .chain(&self.irradiance)
            .filter(|p| p.parent().is_none_or(|d| !d.as_os_str().is_empty() && d.is_dir() || d.as_os_str().is_empty()))
            .map(|p| Output::File(p.clone()))
            .collect();
        check_writable(document.iter().chain(&files))?;
        let config = Config::try_from(&self)?;

        let env_args =
            self.env.as_ref().map(|path| EnvArgs { path: path.clone(), layout: self.layout, negative: self.negative });
        let map = env_args.as_ref().map(|e| e.load(ctx)).transpose()?;
        let coefficients = match &self.sh {
            Some(path) => Some(read_sh(path)?),
            None => None,
        };
        let lighting = match (&map, &coefficients) {
            (Some(m), _) => Lighting::Map(m),
            (None, Some(c)) => Lighting::Coefficients(c),
            (None, None) => bail!("give an environment map or --sh FILE"),
        };
        let out = stage::run(&config, lighting, ctx.progress())?;

        let mut outputs = Outputs::new();
        for dir in self.icosahedral.iter().chain(&self.views_dir) {
            outputs.create_dir(dir)?;
        }
        for ((path, _), image) in map_files.iter().zip(&out.maps) {
            if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                outputs.create_dir(dir)?;
            }
            outputs.image(&Output::File(path.clone()), image, self.exposure.stops)?;
        }
        if let (Some(path), Some(image)) = (&self.irradiance, &out.irradiance) {
            outputs.image(&Output::File(path.clone()), image, self.exposure.stops)?;
        }
        for (path, layers) in [(&self.shrm, &out.shrm_layers), (&self.kautz_mccool, &out.kautz_mccool)] {
            if let (Some(path), Some(layers)) = (path, layers) {
                let refs: Vec<(&str, &RgbImage)> = layers.iter().map(|(n, i)| (n.as_str(), i)).collect();
                outputs
                    .bytes(&Output::File(path.clone()), io::exr::encode_layers(&refs).map_err(anyhow::Error::msg)?)?;
            }
        }
        if let Some(o) = &document {
            outputs.json(o, &out.document)?;
        }
        if self.json {
            outputs.json(&Output::Stdout, &out.summary)?;
        }
        outputs.commit()?;
        Ok(Outcome::Success)
    }
}

/// Reads the SH coefficients of a `prtkit.sh` document (`-`: stdin).
fn read_sh(path: &std::path::Path) -> Result<crate::sh::ShCoeffs> {
    let text = if path.as_os_str() == "-" {
        std::io::read_to_string(std::io::stdin().lock()).context("cannot read standard input")?
    } else {
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?
    };
    let name = if path.as_os_str() == "-" { "<stdin>".to_string() } else { path.display().to_string() };
    let doc = crate::sh::document::parse(&text).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    Ok(doc.body.coeffs())
}
