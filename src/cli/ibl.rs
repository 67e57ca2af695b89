//! `ibl`: clap arguments → [`ibl::stage::Config`] → one library call → the files of DIR, all or
//! none.
//!
//! [`ibl::stage::Config`]: crate::ibl::stage::Config

mod args;

use super::common::{Context, Outcome, Stage};
use super::options::Execution;
use super::outputs::{check_output_dir, Outputs};
use crate::ibl::manifest;
use crate::ibl::stage::{self, Config, Error, FaceSize};
use crate::io::Output;
use crate::limits::MAX_IBL_FACE_SIZE;
use anyhow::{anyhow, bail, Result};
pub use args::*;
use std::path::Path;
use std::time::Instant;

impl From<&Args> for Config {
    fn from(args: &Args) -> Config {
        Config {
            size: args.size,
            min_size: args.min_size,
            irradiance_size: args.irradiance_size,
            roughness_map: args.roughness_map,
            format: args.format.format(),
            container: args.container.container(),
            up: args.up,
            rotate_degrees: args.rotate,
            mirror: args.mirror,
            clamp: args.clamp,
            dfg: args.dfg.variant(),
            samples: args.samples as usize,
            source: args.input.name(),
            args: std::env::args().collect(),
            ..Config::default()
        }
    }
}

impl Stage for Args {
    const NAME: &'static str = "ibl";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        if crate::io::read::is_stdin(&self.output) {
            bail!("-o -: a bake is a directory of files (ibl.json, the textures, the SH), not one stream; give a directory");
        }
        let config = Config::from(&self);
        config.check().map_err(flag_error)?;
        // DIR is created by the commit's output set (and removed if anything fails); an
        // existing directory with files in it is refused so that no stale file is mixed in.
        if self.output.exists() {
            let empty = self.output.is_dir()
                && std::fs::read_dir(&self.output).map(|mut d| d.next().is_none()).unwrap_or(false);
            if !empty {
                bail!("{}: exists and is not an empty directory", self.output.display());
            }
        }
        // Before the long work: DIR's parent exists (DIR is created, not the path to it).
        check_output_dir(&self.output)?;
        let map = self.input.load(ctx)?;
        let out = stage::run(&config, &map, ctx.progress()).map_err(|error| match error {
            Error::Project(e) => anyhow!("{}: too coarse for the SH irradiance: {e}", self.input.name()),
            error => error.into(),
        })?;

        let body = &out.document.body;
        for level in body.specular.levels.iter().chain(std::iter::once(&body.irradiance.level)) {
            let errors = match (level.rms_rel_error, level.max_rel_error) {
                (Some(rms), Some(max)) => format!(", error {:.3} % RMS, {:.3} % max", 100.0 * rms, 100.0 * max),
                _ => String::new(),
            };
            ctx.note(format!(
                "{} {}² r={:.3}: {} from {} in {:.3} s{errors}",
                if level.level == 0 && level.roughness == 1.0 {
                    "irradiance".to_string()
                } else {
                    format!("level {}", level.level)
                },
                level.size,
                level.roughness,
                level.method,
                level.source,
                level.seconds
            ));
        }
        // The files are encoded before the narration ends, so that it says how long that took.
        let mut outputs = Outputs::new();
        outputs.create_dir(&self.output)?;
        let t_encode = Instant::now();
        stage_bake(&mut outputs, &self.output, &out)?;
        let t = &body.timings;
        ctx.note(format!(
            "baked in {:.3} s (prepare {:.3}, specular {:.3}, irradiance and SH {:.3}, DFG {:.3} and the reference {:.3} beside them), encoded in {:.3} s, measured in {:.3} s",
            t.bake,
            t.prepare,
            t.specular,
            t.irradiance,
            t.dfg,
            t.reference,
            t_encode.elapsed().as_secs_f64(),
            t.measure
        ));

        // Values above what the format holds are saturated by its encoding: said, with the remedy.
        let cubes = out.specular.levels().iter().chain(std::iter::once(&out.irradiance));
        let saturated: usize = cubes.map(|cube| config.format.saturated_texels(cube.texels(), 3)).sum();
        if let (true, Some(max)) = (saturated > 0, config.format.max_value()) {
            let format = clap::ValueEnum::to_possible_value(&self.format).map(|v| v.get_name().to_string());
            ctx.note(format!(
                "{saturated} texels of the specular and irradiance cubes are above {max}, the largest {} holds, \
                 and were saturated to it; pass --clamp to choose the ceiling, or --format rgba32f to keep them",
                format.unwrap_or_default()
            ));
        }
        outputs.commit()?;
        Ok(Outcome::Success)
    }
}

/// The library's refusal of a flag's value, worded with the flag (the library speaks of the
/// bake, not of the command line).
fn flag_error(error: Error) -> anyhow::Error {
    match error {
        Error::Size { which, size } => {
            let flag = match which {
                FaceSize::First => "--size",
                FaceSize::Last => "--min-size",
                FaceSize::Irradiance => "--irradiance-size",
            };
            anyhow!("{flag} {size}: a face size must be a power of two between 1 and {MAX_IBL_FACE_SIZE}")
        }
        Error::MinSize { min, size } => anyhow!("--min-size {min} is larger than --size {size}"),
        Error::Rotation(degrees) => anyhow!("--rotate {degrees} must be a finite angle"),
        Error::Clamp(max) => anyhow!("--clamp {max} must be positive"),
        error => error.into(),
    }
}

/// Stages every file of the bake in `dir` under the name the manifest gives it, the manifest
/// last: the textures in their container, the documents as JSON, the shader snippets as text.
fn stage_bake(outputs: &mut Outputs, dir: &Path, bake: &stage::Output) -> Result<()> {
    let file = |name: &str| Output::File(dir.join(name));
    for (name, texture, format) in bake.textures() {
        outputs.texture(&file(name), bake.container, &texture, format)?;
    }
    outputs.json(&file(&bake.document.body.sh.file), &bake.sh_document)?;
    for (name, text) in bake.shaders() {
        outputs.bytes(&file(name), text.into_bytes())?;
    }
    outputs.json(&file(manifest::FILE), &bake.document)
}
