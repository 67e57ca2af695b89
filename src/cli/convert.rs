//! `convert`: clap arguments → [`envmap::stage::Config`] → one library call → outputs.

use super::common::{Context, Outcome, Stage};
use super::options::{parse_output, parse_size, EnvArgs, Execution, Exposure};
use super::outputs::{check_writable, Outputs};
use crate::envmap::stage::{self, Config};
use crate::envmap::{Layout, FACES};
use crate::io::Output;
use anyhow::Result;
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

    #[command(flatten)]
    pub exposure: Exposure,

    #[command(flatten)]
    pub run: Execution,
}

impl TryFrom<&Args> for Config {
    type Error = anyhow::Error;
    fn try_from(args: &Args) -> Result<Config> {
        Ok(Config { to: args.to, size: args.size, supersample: args.supersample })
    }
}

impl Stage for Args {
    const NAME: &'static str = "convert";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        let config = Config::try_from(&self)?;
        let single = parse_output(&self.output.to_string_lossy()).map_err(anyhow::Error::msg)?;
        if self.to != Layout::Faces {
            check_writable([&single])?;
        } else if let Some(parent) = self.output.parent().filter(|p| !p.as_os_str().is_empty()) {
            check_writable([&Output::File(parent.join("faces"))])?;
        }
        let map = self.input.load(ctx)?;
        let out = stage::run(&config, &map)?;

        let mut outputs = Outputs::new();
        if self.to == Layout::Faces {
            outputs.create_dir(&self.output)?;
            let ext = self.face_format.to_possible_value().map(|v| v.get_name().to_string()).unwrap_or_default();
            for (face, img) in FACES.iter().zip(out.images()) {
                let path = self.output.join(format!("{}.{ext}", face.short_name()));
                outputs.image(&Output::File(path), img, self.exposure.stops)?;
            }
        } else {
            outputs.image(&single, out.image(), self.exposure.stops)?;
        }
        outputs.commit()?;
        Ok(Outcome::Success)
    }
}
