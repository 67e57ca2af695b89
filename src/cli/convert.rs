//! `convert`: clap arguments → [`envmap::stage::Config`] → one library call → outputs.
//!
//! [`envmap::stage::Config`]: crate::envmap::stage::Config

mod args;

use super::common::{Context, Outcome, Stage};
use super::options::{parse_output, Execution};
use super::outputs::{check_output_dir, check_outputs, Holds, Outputs};
use crate::envmap::stage::{self, Config};
use crate::envmap::{Layout, FACES};
use crate::io::Output;
use crate::limits::MAX_SUPERSAMPLE;
use anyhow::Result;
pub use args::*;

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
            check_outputs([(&single, Holds::Image)])?;
        } else {
            check_output_dir(&self.output)?;
        }
        let map = self.input.load(ctx)?;
        let out = stage::run(&config, &map).map_err(|error| match error {
            stage::Error::Supersample(n) => anyhow::anyhow!("--supersample {n} must be in 1..={MAX_SUPERSAMPLE}"),
            error => error.into(),
        })?;

        let mut outputs = Outputs::new();
        if self.to == Layout::Faces {
            outputs.create_dir(&self.output)?;
            let ext = clap::ValueEnum::to_possible_value(&self.face_format)
                .map(|v| v.get_name().to_string())
                .unwrap_or_default();
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
