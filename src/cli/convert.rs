//! `prtkit convert`: resample an environment map into another layout (e.g. a light probe to
//! lat-long), or write it in another format.

use super::common::parse_size;
use super::common::{Execution, Outcome};
use super::envinput::EnvInput;
use crate::envmap::{self, Layout};
use crate::io;
use anyhow::{Context, Result};
use clap::Parser;
use std::path::PathBuf;

/// Resample an environment map into another layout (lat-long, angular, cube crosses, six faces).
#[derive(Debug, Parser)]
#[command(name = "convert", version, about, long_about = None)]
pub struct Args {
    #[command(flatten)]
    pub input: EnvInput,

    /// Output layout.
    #[arg(long = "to", default_value = "latlong", value_parser = clap::value_parser!(Layout))]
    pub to: Layout,

    /// Output size WxH (per face for `faces`). Default: 2S x S for lat-long, where S keeps the
    /// input's texel count; S x S for the others.
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(usize, usize)>,

    /// Sub-samples per texel edge (k x k bilinear lookups averaged per output texel).
    #[arg(long, default_value_t = 3)]
    pub supersample: usize,

    /// Output file (.exr, .pfm, .png). For `--to faces`, a directory that receives
    /// px/nx/py/ny/pz/nz with the extension of `--face-format`.
    #[arg(short, long)]
    pub output: PathBuf,

    /// Extension of the face files when writing `--to faces`.
    #[arg(long, default_value = "exr")]
    pub face_format: String,

    /// Exposure in stops for PNG output.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,

    #[command(flatten)]
    pub run: Execution,
}

/// Runs `convert`.
pub fn run(args: Args) -> Result<Outcome> {
    let map = args.input.load()?;
    let texels = map.texel_count();
    let (w, h) = match (args.size, args.to) {
        (Some(s), _) => s,
        (None, Layout::LatLong) => {
            let s = ((texels as f64 / 2.0).sqrt().round() as usize).max(1);
            (2 * s, s)
        }
        (None, Layout::CrossHorizontal) => {
            let n = ((texels as f64 / 6.0).sqrt().round() as usize).max(1);
            (4 * n, 3 * n)
        }
        (None, Layout::CrossVertical) => {
            let n = ((texels as f64 / 6.0).sqrt().round() as usize).max(1);
            (3 * n, 4 * n)
        }
        (None, Layout::Faces) => {
            let n = ((texels as f64 / 6.0).sqrt().round() as usize).max(1);
            (n, n)
        }
        (None, Layout::Angular) => {
            let s = ((texels as f64).sqrt().round() as usize).max(1);
            (s, s)
        }
    };
    let out = envmap::resample(&map, args.to, w, h, args.supersample)
        .with_context(|| format!("cannot write a {} map of {w}x{h}", args.to))?;
    if args.to == Layout::Faces {
        std::fs::create_dir_all(&args.output)
            .with_context(|| format!("cannot create directory {}", args.output.display()))?;
        for (face, img) in envmap::FACES.iter().zip(out.images()) {
            let path = args.output.join(format!("{}.{}", face.short_name(), args.face_format));
            io::image::write_image(&path, img, args.exposure)?;
        }
    } else {
        io::image::write_image(&args.output, out.image(), args.exposure)?;
    }
    Ok(Outcome::Success)
}
