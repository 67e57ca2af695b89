//! `factor-brdf`: clap arguments → [`factor::stage::Config`] → one library call → outputs.
//!
//! [`factor::stage::Config`]: crate::factor::stage::Config

mod args;

use super::common::{Context, Outcome, Stage};
use super::options::Execution;
use super::outputs::{check_output_dir, check_outputs, Holds, Outputs};
use crate::factor::stage::{self, Config};
use crate::factor::svd::{FactorError, Method};
use crate::io::{self, Output};
use anyhow::Result;
pub use args::*;

impl TryFrom<&Args> for Config {
    type Error = anyhow::Error;
    fn try_from(args: &Args) -> Result<Config> {
        Ok(Config {
            sampling: args.matrix.sampling(),
            method: args.matrix.method,
            terms: args.terms,
            maps: args.maps.is_some(),
            maps_dir: args.maps.as_ref().map(|d| d.display().to_string()),
            factors_file: args.factors.as_ref().map(|p| p.display().to_string()),
            max_memory: args.matrix.max_memory,
            args: std::env::args().collect(),
        })
    }
}

/// The stage's error in the words of the flags that set the refused values; the others as they
/// are.
fn flagged(error: stage::Error) -> anyhow::Error {
    let message = match &error {
        stage::Error::NoTerms => Some("--terms must be at least 1 with --maps or --factors".to_string()),
        stage::Error::Factor(e) => factor_flagged(e),
    };
    message.map_or_else(|| error.into(), anyhow::Error::msg)
}

/// A factorization's error in the words of the matrix flags (`--resolution`, `--method`,
/// `--max-memory`, which `count-terms` shares); `None` when no flag set the refused value.
pub(super) fn factor_flagged(error: &FactorError) -> Option<String> {
    match error {
        FactorError::TooLarge { n, domain, dirs, method, need, limit } => Some(format!(
            "resolution {n} on the {domain} ({dirs} directions per side) with the {method} method needs about {need} \
             of memory (limit {limit}); lower --resolution{} or raise --max-memory",
            if *method == Method::Dense { ", use an isotropic BRDF with --method fft" } else { "" }
        )),
        FactorError::Anisotropic(brdf) => {
            Some(format!("--method fft needs an isotropic BRDF; {brdf} is anisotropic (use --method dense)"))
        }
        _ => None,
    }
}

impl Stage for Args {
    const NAME: &'static str = "factor-brdf";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        super::options::check_json_output(&self.output, self.json)?;
        let factors_out = self.factors.clone().map(Output::File);
        check_outputs(std::iter::once((&self.output, Holds::Text)).chain(factors_out.iter().map(|o| (o, Holds::Exr))))?;
        if let Some(dir) = &self.maps {
            check_output_dir(dir)?;
        }
        let config = Config::try_from(&self)?;
        let out = stage::run(&config, &self.brdf, ctx.progress()).map_err(flagged)?;

        let mut outputs = Outputs::new();
        if let (Some(dir), Some((layers, sheet))) = (&self.maps, &out.maps) {
            outputs.create_dir(dir)?;
            outputs.layers(&Output::File(dir.join("factors.exr")), layers)?;
            outputs.image(&Output::File(dir.join("factors.png")), sheet, 0.0)?;
        }
        if let (Some(path), Some(f)) = (&factors_out, &out.factors) {
            let bytes = io::exr::encode_grey_layers(f.width, f.height, &[("g", &f.g), ("h", &f.h)])
                .map_err(anyhow::Error::msg)?;
            outputs.bytes(path, bytes)?;
        }
        outputs.json(&self.output, &out.document)?;
        if self.json {
            outputs.json(&Output::Stdout, &out.summary)?;
        }
        outputs.commit()?;
        let counts: Vec<String> = out.summary.terms.iter().map(|(k, v)| format!("{k}: {v}")).collect();
        ctx.note(format!(
            "{} on the {} at n = {} ({} method): K {}",
            out.summary.brdf,
            out.summary.domain,
            out.summary.resolution,
            out.summary.method,
            counts.join(", ")
        ));
        Ok(Outcome::Success)
    }
}
