//! The flags of `convert` (clap declarations only; their help text is the user's reference).

use crate::cli::options::{parse_size, EnvArgs, Execution, Exposure};
use crate::envmap::Layout;
use clap::{Parser, ValueEnum};
use std::path::PathBuf;

/// File format of the six faces written by `--to faces`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum FaceFormat {
    /// OpenEXR, float.
    Exr,
    /// Portable float map.
    Pfm,
    /// Tone-mapped PNG (sRGB, --exposure).
    Png,
}

/// Resample an environment map into another layout (lat-long, angular probe, cube crosses, six
/// faces), or write it in another format.
#[derive(Debug, Parser)]
#[command(name = "convert", version)]
pub struct Args {
    /// The environment map read and how (shared by every stage that reads one).
    #[command(flatten)]
    pub input: EnvArgs,

    /// Output layout.
    #[arg(long = "to", default_value = "latlong")]
    pub to: Layout,

    /// Output size WxH (per face for `faces`). Default: 2S x S for lat-long, where S keeps the
    /// input's texel count; S x S for the others.
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(usize, usize)>,

    /// Sub-samples per texel edge (k x k bilinear lookups averaged per output texel), 1..=16.
    #[arg(long, default_value_t = 3)]
    pub supersample: usize,

    /// Output file (.exr, .pfm, .png; `-`: EXR on stdout). For `--to faces`, a directory that
    /// receives px/nx/py/ny/pz/nz with the extension of `--face-format` (created if missing).
    #[arg(short, long)]
    pub output: PathBuf,

    /// Format of the face files when writing `--to faces`.
    #[arg(long, value_enum, default_value_t = FaceFormat::Exr)]
    pub face_format: FaceFormat,

    /// The exposure of PNG previews.
    #[command(flatten)]
    pub exposure: Exposure,

    /// Threads, quiet, progress.
    #[command(flatten)]
    pub run: Execution,
}
