//! The flags of `prefilter` (clap declarations, whose help text is the user's reference) and
//! how they name the files.

use crate::brdf::Brdf;
use crate::cli::options::{parse_brdf, parse_bright, parse_direction, parse_output, parse_size};
use crate::cli::options::{Execution, Exposure};
use crate::envmap::bright::BrightRule;
use crate::envmap::Layout;
use crate::io::Output;
use crate::prefilter::orders::OrderRule;
use crate::prefilter::stage::{icosahedron_views, view_grid, Method};
use crate::sh::window::Window;
use anyhow::{bail, Result};
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

impl OutputLayout {
    /// The layout.
    pub fn layout(self) -> Layout {
        match self {
            OutputLayout::Latlong => Layout::LatLong,
            OutputLayout::CrossHorizontal => Layout::CrossHorizontal,
            OutputLayout::CrossVertical => Layout::CrossVertical,
        }
    }
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

    /// How the map is turned on reading.
    #[command(flatten)]
    pub orient: crate::cli::options::OrientArgs,

    /// Lighting as a `prtkit.sh` document from sh-project (`-`: stdin) instead of a map
    /// (frequency method).
    #[arg(long, value_name = "SH.json", conflicts_with = "env")]
    pub sh: Option<PathBuf>,

    /// BRDF spec, e.g. phong:s=32, lambert, torrance-sparrow:sigma=0.2, merl:FILE (docs/brdf-specs.md).
    #[arg(long, value_parser = parse_brdf)]
    pub brdf: Brdf,

    /// Tolerance ε. With --order-rule texel: the worst-case error of any texel, as a fraction of
    /// the darkest texels counted (1 % of the mean); with energy: the BRDF energy F_B, P_B may
    /// miss (§5.1). With --method angular: the share of each lobe its cone leaves out (App. D).
    #[arg(short = 'e', long, default_value_t = 0.01)]
    pub epsilon: f64,

    /// How F_B, P_B are chosen from ε: texel (bounds the error of every texel under this
    /// lighting; texels of grazing views the SHRM does not represent are integrated in angle,
    /// and a view-dependent BRDF's reflection maps are integrated in angle whole) or
    /// energy (the paper's rule, §5.1; it ignores the lighting and rings under HDR suns).
    #[arg(long, value_enum, default_value_t = OrderRule::Texel)]
    pub order_rule: OrderRule,

    /// Bright sources filtered in angle with the exact lobe, the rest through SH: auto (a
    /// threshold from the map's histogram, docs/prefilter.md), off (the paper's method), or a
    /// luminance threshold. With --method angular: the map is summed in luminance parts, each
    /// with its own cone, so that no texel misses more than a few ε × the map's mean luminance
    /// whatever the sun (off: one cone, App. D as written).
    #[arg(long, value_name = "auto|off|Y", default_value = "auto", value_parser = parse_bright)]
    pub bright: BrightRule,

    /// Window applied to the lighting's bands at synthesis: none, hann, lanczos, sigma, or
    /// nonneg. Every window but none is followed by the gentlest heat window that makes every
    /// texel non-negative; nonneg is that alone (the BRDF's kernel damps the top bands already).
    #[arg(long, value_enum, default_value_t = Window::Nonneg)]
    pub window: Window,

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

    /// Check N texels (1 … 100000) of every map written against the angular integral of --method angular
    /// (ε = 1e-5) and write the figures (negative texels, p99 and largest per-texel relative
    /// error, relative RMS, the worst texel) into the document and --json: texels beside the
    /// brightest sources, the darkest, the poles, and the rest spread evenly (docs/prefilter.md,
    /// "Verifying a bake"). Costs one cone sum per texel: for 3-D BRDFs N/(W·H) of an angular run.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=crate::limits::MAX_VERIFY_TEXELS as u64))]
    pub verify: Option<u64>,

    /// frequency (default) or angular (the reference; reflection maps only).
    #[arg(long, value_enum, default_value_t = Method::Frequency)]
    pub method: Method,

    /// The exposure of PNG previews.
    #[command(flatten)]
    pub exposure: Exposure,

    /// Print a summary (orders, ε, timings) on stdout.
    #[arg(long)]
    pub json: bool,

    /// Threads, quiet, progress.
    #[command(flatten)]
    pub run: Execution,
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
    pub(super) fn map_files(&self) -> Result<Vec<(PathBuf, DVec3)>> {
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

    pub(super) fn document_output(&self) -> Option<Output> {
        match (&self.output, self.json) {
            (Some(o), _) => Some(o.clone()),
            (None, false) => Some(Output::Stdout),
            (None, true) => None,
        }
    }
}
