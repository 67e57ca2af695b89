//! The flags of `sample-shader` (clap declarations only; their help text is the user's reference).

use crate::cli::options::{parse_output, parse_size, Execution, Exposure};
use crate::io::Output;
use anyhow::Result;
use clap::{Parser, ValueEnum};
use std::path::PathBuf;

/// The arithmetic used to evaluate a quadtree node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ArithArg {
    /// Affine arithmetic: guaranteed, tight bounds.
    Affine,
    /// Interval arithmetic: guaranteed, looser bounds.
    Interval,
    /// Random point samples per node: an estimate, not a bound.
    Point,
}

/// Bake a procedural shader with guaranteed error bounds (adaptive area sampling with affine
/// arithmetic, Heidrich, Slusallek & Seidel 1998).
#[derive(Debug, Parser)]
#[command(name = "sample-shader", version)]
pub struct Args {
    /// Shader source file (prtkit shading language, docs/shading-language.md), or `-` for stdin.
    #[arg(value_name = "SHADER")]
    pub shader: PathBuf,

    /// Output texture: .exr (float; with extra layers `width` = bound width and `depth` = quadtree
    /// depth), .png (tone-mapped) or .pfm; `-`: EXR on stdout.
    #[arg(short, long, value_parser = parse_output)]
    pub output: Option<Output>,

    /// Also write the texture, bound-width and depth layers into this EXR (useful with a PNG -o).
    #[arg(long, value_name = "EXR", value_parser = parse_output)]
    pub layers: Option<Output>,

    /// Subdivide a quadtree node while its bound width (upper − lower, widest channel) exceeds this.
    #[arg(long, default_value_t = 0.02)]
    pub tolerance: f64,

    /// Deepest quadtree level (root = 0; at most 16). Default: one leaf per pixel of --res.
    #[arg(long)]
    pub max_depth: Option<u32>,

    /// Texture resolution WxH.
    #[arg(long, value_parser = parse_size, default_value = "256x256")]
    pub res: (usize, usize),

    /// Sample over directions into a WxH lat-long environment map (u = φ/2π, v = θ/π, +Z up);
    /// overrides --res.
    #[arg(long, value_parser = parse_size, value_name = "WxH")]
    pub latlong: Option<(usize, usize)>,

    /// Arithmetic for the area samples.
    #[arg(long, value_enum, default_value_t = ArithArg::Affine)]
    pub arith: ArithArg,

    /// Run affine, interval and point sampling with the same settings and print the comparison
    /// table (Markdown; an array of rows with --json). Outputs (-o, --stats) are from the affine run.
    #[arg(long)]
    pub compare: bool,

    /// Point samples per node in point mode (the paper measures one affine area sample to cost
    /// about as much as 5–10 point samples).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub points_per_node: u64,

    /// Seed for point sampling and --verify.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,

    /// Shader parameter override NAME=VALUE (a number, or r,g,b); repeatable.
    #[arg(short = 'p', long = "param", value_name = "NAME=VALUE", value_parser = parse_param)]
    pub params: Vec<(String, String)>,

    /// Write the statistics (format prtkit.shader-stats) to this file (`-` for stdout).
    #[arg(long, value_name = "JSON", value_parser = parse_output)]
    pub stats: Option<Output>,

    /// Print the statistics with timings (or, with --compare, the rows) on stdout.
    #[arg(long)]
    pub json: bool,

    /// Check the bounds: evaluate N random points (plus the corners) inside every leaf; exit 1 if
    /// any value lies outside its leaf's bounds (area arithmetics only).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=4096))]
    pub verify: Option<u64>,

    /// Sample N times (with --compare, the arithmetics alternate) and report the fastest time of
    /// each arithmetic. The results themselves are the same every time.
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=100))]
    pub repeat: u64,

    /// The exposure of PNG previews.
    #[command(flatten)]
    pub exposure: Exposure,

    /// Threads, quiet, progress.
    #[command(flatten)]
    pub run: Execution,
}

fn parse_param(s: &str) -> Result<(String, String), String> {
    let (k, v) = s.split_once('=').ok_or_else(|| format!("expected NAME=VALUE, got {s:?}"))?;
    if k.trim().is_empty() {
        return Err(format!("empty parameter name in {s:?}"));
    }
    Ok((k.trim().to_string(), v.trim().to_string()))
}
