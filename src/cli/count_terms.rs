//! `count-terms`: clap arguments → [`factor::count::CountConfig`] and the materials → one
//! library call → the table, the plot and the check's exit status.
//!
//! [`factor::count::CountConfig`]: crate::factor::count::CountConfig

mod args;

use super::common::{Context, Outcome, Stage};
use super::options::Execution;
use super::outputs::{check_outputs, Holds, Outputs};
use crate::brdf::Brdf;
use crate::factor::count::{self, CountConfig, CountError, Material};
use crate::factor::{manifest, plot};
use crate::io::Output;
use anyhow::Result;
pub use args::*;

impl TryFrom<&Args> for CountConfig {
    type Error = anyhow::Error;
    fn try_from(args: &Args) -> Result<CountConfig> {
        Ok(CountConfig {
            sampling: args.matrix.sampling(),
            per_channel: args.per_channel,
            max_memory: args.matrix.max_memory,
            energy: args.energy,
            predict_only: args.predict_only,
            method: args.matrix.method,
            tolerance: args.tolerance,
        })
    }
}

impl Args {
    /// The materials: each --brdf (named by its spec, or the MERL file's stem), then the
    /// manifest's lines (their MERL files read as the manifest is parsed, errors naming the
    /// manifest's line and column).
    fn materials(&self) -> Result<Vec<Material>> {
        let budget = self.max_terms.map(|b| b as usize);
        let channel = self.matrix.channel;
        let mut out: Vec<Material> = self
            .brdfs
            .iter()
            .map(|brdf| {
                let name = match brdf {
                    Brdf::Merl(m) => m.path().file_stem().map_or(brdf.spec(), |s| s.to_string_lossy().into_owned()),
                    _ => brdf.spec(),
                };
                Material { name, brdf: brdf.clone(), channel, budget }
            })
            .collect();
        if let Some(path) = &self.manifest {
            for e in manifest::read(path)? {
                out.push(Material { name: e.name, brdf: e.brdf, channel, budget: e.budget.or(budget) });
            }
        }
        Ok(out)
    }
}

/// The stage's error in the words of the flags that set the refused values; the others as they
/// are.
fn flagged(error: CountError) -> anyhow::Error {
    let message = match &error {
        CountError::NoMaterial => Some("no material: give --brdf SPEC (repeatable) or --manifest FILE".to_string()),
        CountError::Energy(energy) => Some(format!("--energy must be in (0, 1), got {energy}")),
        CountError::Material { name, error } => {
            super::factor_brdf::factor_flagged(error).map(|m| format!("material {name}: {m}"))
        }
    };
    message.map_or_else(|| error.into(), anyhow::Error::msg)
}

impl Stage for Args {
    const NAME: &'static str = "count-terms";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        // The table (or the --json rows) goes to stdout unless the plot claims it (`--plot -`).
        let table = match &self.plot {
            Some(Output::Stdout) if self.json => {
                anyhow::bail!("--json prints the rows on stdout: give the plot a file with --plot FILE.svg")
            }
            Some(Output::Stdout) => None,
            _ => Some(Output::Stdout),
        };
        check_outputs(self.plot.iter().chain(&table).map(|o| (o, Holds::Text)))?;
        let config = CountConfig::try_from(&self)?;
        let out = count::run(&config, self.materials()?, ctx.progress()).map_err(flagged)?;

        let mut outputs = Outputs::new();
        if let Some(plot_out) = &self.plot {
            let title = format!(
                "count-terms: {} , n = {}, {:.1} % energy",
                self.matrix.domain,
                self.matrix.resolution,
                100.0 * self.energy
            );
            let svg = plot::count_plot(&title, &out.rows, &out.spectra).map_err(anyhow::Error::msg)?;
            outputs.bytes(plot_out, svg.into_bytes())?;
        }
        match (&table, self.json) {
            (Some(o), true) => outputs.json(o, &out.rows)?,
            (Some(o), false) => outputs.bytes(o, count::markdown_table(&out.rows).into_bytes())?,
            (None, _) => {}
        }
        outputs.commit()?;
        let failing: Vec<_> = out.failing().collect();
        if self.check && !failing.is_empty() {
            for r in failing {
                eprintln!("count-terms: check failed: {}: {}", r.name, r.failures.join("; "));
            }
            return Ok(Outcome::Negative);
        }
        Ok(Outcome::Success)
    }
}
