//! `sh-project`: clap arguments → [`sh::stage::Config`] → one library call → outputs.

use super::common::{Context, Outcome, Stage};
use super::options::{check_json_output, parse_output, parse_size, EnvArgs, Execution, Exposure};
use super::outputs::{check_writable, Outputs};
use crate::io::Output;
use crate::sh::project::OrderChoice;
use crate::sh::stage::{self, Config, MAX_EPSILON_ORDER};
use anyhow::Result;
use clap::Parser;

/// Project an environment map onto real spherical harmonics.
///
/// Writes a `prtkit.sh` JSON document (coefficients indexed by l(l+1)+m, per-band energy) and,
/// optionally, the order-F reconstruction and the irradiance map (the map convolved with the
/// clamped cosine) as lat-long images.
#[derive(Debug, Parser)]
#[command(name = "sh-project", version)]
pub struct Args {
    #[command(flatten)]
    pub input: EnvArgs,

    /// SH order F (bands 0..=F, (F+1)² coefficients). Default 2 unless --epsilon is given.
    #[arg(short = 'F', long, conflicts_with = "epsilon")]
    pub order: Option<usize>,

    /// Choose the smallest order capturing 1 - EPSILON of the map's energy (searched up to 256).
    #[arg(short = 'e', long)]
    pub epsilon: Option<f64>,

    /// Output JSON document (`-` for stdout).
    #[arg(short, long, default_value = "-", value_parser = parse_output)]
    pub output: Output,

    /// Write the order-F reconstruction as a lat-long image (.exr, .pfm or .png; `-`: EXR on
    /// stdout; repeatable).
    #[arg(long, value_name = "FILE", value_parser = parse_output)]
    pub reconstruct: Vec<Output>,

    /// Write the irradiance map E(n) = ∫ L(ω) max(n·ω, 0) dω, from the order-F coefficients
    /// convolved with the clamped cosine (Â_l), as a lat-long image (repeatable).
    #[arg(long, value_name = "FILE", value_parser = parse_output)]
    pub irradiance: Vec<Output>,

    /// Size WxH of the lat-long images. Default: the input's size for a lat-long input, else
    /// 2S x S with S ≈ √(texels/2) (at least 2F+2 wide).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(usize, usize)>,

    #[command(flatten)]
    pub exposure: Exposure,

    /// Print a JSON summary (order, ε achieved, band energy, timings) on stdout.
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub run: Execution,
}

impl TryFrom<&Args> for Config {
    type Error = anyhow::Error;
    fn try_from(args: &Args) -> Result<Config> {
        let order = match (args.order, args.epsilon) {
            (Some(order), _) => OrderChoice::Order(order),
            (None, Some(epsilon)) => OrderChoice::Epsilon { epsilon, max_search: MAX_EPSILON_ORDER },
            (None, None) => OrderChoice::Order(2),
        };
        Ok(Config {
            order,
            reconstruction: !args.reconstruct.is_empty(),
            irradiance: !args.irradiance.is_empty(),
            size: args.size,
            source: args.input.name(),
            args: std::env::args().collect(),
        })
    }
}

impl Stage for Args {
    const NAME: &'static str = "sh-project";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        check_json_output(&self.output, self.json)?;
        check_writable(std::iter::once(&self.output).chain(&self.reconstruct).chain(&self.irradiance))?;
        let config = Config::try_from(&self)?;
        let map = self.input.load(ctx)?;
        let out = stage::run(&config, &map, ctx.progress())?;

        let mut outputs = Outputs::new();
        for (images, image) in [(&self.reconstruct, &out.reconstruction), (&self.irradiance, &out.irradiance)] {
            for (path, image) in images.iter().zip(std::iter::repeat(image).flatten()) {
                outputs.image(path, image, self.exposure.stops)?;
            }
        }
        outputs.json(&self.output, &out.document)?;
        if self.json {
            outputs.json(&Output::Stdout, &out.summary)?;
        }
        outputs.commit()?;
        Ok(Outcome::Success)
    }
}
