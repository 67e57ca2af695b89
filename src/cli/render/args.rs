//! The flags of `render` (clap declarations only; their help text is the user's reference).

use crate::brdf::Brdf;
use crate::cli::options::{parse_brdf, parse_output, parse_size, parse_xyz, EnvArgs, Execution, Exposure};
use crate::io::Output;
use crate::render::reference::Integrand;
use clap::{Parser, ValueEnum};
use glam::DVec3;
use std::path::PathBuf;

/// Shading modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ShadingArg {
    /// Lambert from SH lighting: (albedo/π) Σ Â_l L_lm Y_lm(n).
    Irradiance,
    /// From a prefilter SHRM (global: distant viewer, eq. 12; local: per pixel, eq. 6).
    Shrm,
    /// K-term in-out factorization, lighting projected onto the factors (Mahajan eq. 4).
    Factored,
    /// From an `ibl` bake (--ibl), with the split sum a glTF/PBR engine uses; --brdf gltf:….
    Ibl,
    /// From a `transfer` bake (--transfer FILE.glb): the per-vertex dot product of the transfer
    /// with the environment's SH, interpolated over the triangles; --scene the baked mesh. A
    /// glossy bake is relit as B = Σ_k h_k(ω_o) (T_k · L), h_k from the bake.
    Transfer,
    /// Ground truth: sum over every environment texel of L ρ cos (× visibility on meshes).
    Reference,
}

/// Render a sphere or a mesh (OBJ, PLY, glTF) under an environment map with one of the bakes, or the
/// reference, and compare.
#[derive(Debug, Parser)]
#[command(name = "render", version)]
pub struct Args {
    /// The environment map read and how (shared by every stage that reads one).
    #[command(flatten)]
    pub input: EnvArgs,

    /// The object: `sphere` (unit sphere at the origin) or a mesh file: .obj, .ply, or .gltf/.glb
    /// (the scene's meshes placed by their nodes, in the file's axes: glTF is +Y up).
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

    /// transfer: the `.glb` written by `transfer --glb` for the --scene mesh (its vertices must be
    /// the mesh's).
    #[arg(long, value_name = "FILE.glb")]
    pub transfer: Option<PathBuf>,

    /// transfer: shade from the per-texel lightmap `transfer --lightmap` wrote beside the .glb
    /// (its T0… layers, bilinear at the hit's UV from the --scene mesh's UVs) instead of the
    /// per-vertex transfer.
    #[arg(long, value_name = "FILE.exr", requires = "transfer")]
    pub lightmap: Option<PathBuf>,

    /// transfer and reference: turn the environment by DEG degrees about +Z (counter-clockwise
    /// seen from above: azimuth φ goes to φ + DEG), -360 to 360; transfer turns its SH lighting
    /// by one SH rotation. The background turns with it.
    #[arg(long, value_name = "DEG", default_value_t = 0.0, allow_hyphen_values = true)]
    pub env_rotation: f64,

    /// shrm: the prtkit.shrm document written by `prefilter --shrm` (names the EXR beside it, so a
    /// file: not `-`).
    #[arg(long, value_name = "SHRM.json")]
    pub shrm: Option<PathBuf>,

    /// irradiance and shrm: window at synthesis, on the lighting's bands l (irradiance) or the
    /// SHRM's view bands p (shrm; its lighting bands carry prefilter's window already): none,
    /// hann, lanczos, sigma, or nonneg. Every window but none is followed by the gentlest heat
    /// window that makes every pixel of the object non-negative; nonneg is that alone.
    /// [default: nonneg]
    #[arg(long, value_enum)]
    pub window: Option<crate::sh::window::Window>,

    /// factored: number of terms K.
    #[arg(short = 'K', long, default_value_t = 12)]
    pub terms: usize,

    /// factored: a prtkit.factor document written by `factor-brdf --factors FILE.exr` (names
    /// the EXR beside it, so a file: not `-`). Without it the BRDF is factored here, on the hemisphere with the cosine folded in.
    /// transfer: optional, the document a glossy bake was made from, checked against the bake.
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

    /// factored: bright sources apart: texels of compact, very bright sources (the sun) are
    /// shaded exactly with the BRDF (and visibility), the rest through the factorization.
    /// auto (the threshold from the map's histogram, docs/prefilter.md), off (the paper's
    /// method), or a luminance threshold.
    #[arg(long, value_name = "auto|off|Y", default_value = "auto", value_parser = crate::cli::options::parse_bright)]
    pub bright: crate::envmap::bright::BrightRule,

    /// ibl: the bake `ibl -o DIR` wrote: DIR, or its manifest DIR/ibl.json (which names the KTX2
    /// files read; so a directory or file, not `-`). The environment map given must be the one baked (the manifest's source_hash).
    #[arg(long, value_name = "DIR|IBL.json")]
    pub ibl: Option<PathBuf>,

    /// ibl: render a roughness × metalness grid of spheres (--res each), every one above its
    /// reference (the same material integrated over every environment texel: the cost of
    /// --shading reference per cell), labelled with its error; the base colour is --brdf's.
    /// --panel writes the labelled grid, -o/--png the split-sum spheres alone.
    #[arg(long)]
    pub grid: bool,

    /// ibl --grid: the roughness of each column.
    #[arg(long, value_delimiter = ',', value_name = "R,R,…", default_values_t = crate::render::grid::DEFAULT_ROUGHNESS)]
    pub grid_roughness: Vec<f64>,

    /// ibl --grid: the metalness of each row.
    #[arg(long, value_delimiter = ',', value_name = "M,M,…", default_values_t = crate::render::grid::DEFAULT_METALNESS)]
    pub grid_metalness: Vec<f64>,

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

    /// The exposure of PNG previews.
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
    #[arg(long, value_name = "LABEL=FILE.exr", value_parser = parse_panel_item)]
    pub panel_item: Vec<(String, PathBuf)>,

    /// Label of this render in the panel (default: the shading mode and its parameters).
    #[arg(long)]
    pub label: Option<String>,

    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,

    /// Threads, quiet, progress.
    #[command(flatten)]
    pub run: Execution,
}

/// `LABEL=FILE` (the last `=` splits, so labels may hold one).
fn parse_panel_item(s: &str) -> Result<(String, PathBuf), String> {
    let (label, file) = s.rsplit_once('=').ok_or_else(|| format!("expected LABEL=FILE.exr, got {s:?}"))?;
    Ok((label.to_string(), PathBuf::from(file)))
}

impl Args {
    /// The files this run writes.
    pub(super) fn outputs(&self) -> impl Iterator<Item = &Output> {
        [&self.output, &self.png, &self.error_image, &self.metrics, &self.panel].into_iter().flatten()
    }
}
