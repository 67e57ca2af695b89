//! `count-terms`: clap arguments → [`factor::count::CountConfig`] and the materials → one
//! library call → the table, the plot and the check's exit status.

use super::common::{Context, Outcome, Stage};
use super::options::{parse_brdf, parse_output, Execution, MatrixArgs};
use super::outputs::{check_writable, Outputs};
use crate::brdf::Brdf;
use crate::factor::count::{self, CountConfig, Material};
use crate::factor::{manifest, plot};
use crate::io::Output;
use anyhow::{Context as _, Result};
use clap::Parser;
use std::path::PathBuf;

/// Predict and measure how many in-out BRDF terms each material needs (Mahajan et al. 2008).
///
/// Prints a table (or JSON rows) of predicted K from the closed forms and measured K from the
/// SVD; `--check` exits 1 naming each material over its budget or mispredicted.
#[derive(Debug, Parser)]
#[command(name = "count-terms", version)]
pub struct Args {
    /// A BRDF spec (docs/brdf-specs.md); repeat for several materials. Its name is the spec
    /// (the file stem for merl:).
    #[arg(long = "brdf", value_name = "SPEC", value_parser = parse_brdf)]
    pub brdfs: Vec<Brdf>,

    #[command(flatten)]
    pub matrix: MatrixArgs,

    /// A manifest of `name spec [budget]` lines (docs/count-terms.md).
    #[arg(long, value_name = "FILE")]
    pub manifest: Option<PathBuf>,

    /// Term budget for every material without a budget of its own.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub max_terms: Option<u64>,

    /// One row per R, G, B channel for RGB (measured) materials, named NAME/r, NAME/g, NAME/b.
    #[arg(long)]
    pub per_channel: bool,

    /// Energy fraction that K must reach.
    #[arg(long, default_value_t = 0.99)]
    pub energy: f64,

    /// Only the closed-form prediction; no SVD.
    #[arg(long)]
    pub predict_only: bool,

    /// Print a JSON array of rows on stdout instead of the table.
    #[arg(long)]
    pub json: bool,

    /// Write an SVG plot: singular values vs predicted F_l, and K vs (l*)² (`-`: stdout).
    #[arg(long, value_name = "FILE.svg", value_parser = parse_output)]
    pub plot: Option<Output>,

    /// CI mode: exit 1 naming each material whose measured K exceeds its budget or whose
    /// prediction misses the measurement by more than --tolerance.
    #[arg(long)]
    pub check: bool,

    /// Allowed |predicted − measured| / measured, as a fraction (0.25) or percent (25%).
    #[arg(long, default_value = "25%", value_parser = parse_tolerance)]
    pub tolerance: f64,

    #[command(flatten)]
    pub run: Execution,
}

/// Parses `25%` or `0.25`.
pub fn parse_tolerance(s: &str) -> Result<f64, String> {
    let t = s.trim();
    let v =
        if let Some(p) = t.strip_suffix('%') { p.trim().parse::<f64>().map(|v| v / 100.0) } else { t.parse::<f64>() }
            .map_err(|_| format!("expected a fraction like 0.25 or a percentage like 25%, got {s:?}"))?;
    if !(v.is_finite() && v >= 0.0) {
        return Err(format!("tolerance must be >= 0, got {s:?}"));
    }
    Ok(v)
}

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
    /// manifest's lines (their MERL files read here, errors naming the manifest line).
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
            let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
            let base = path.parent().map(|p| p.to_path_buf()).unwrap_or_default();
            for e in manifest::parse(&text, &path.display().to_string(), &base)? {
                let brdf =
                    e.spec.load().with_context(|| format!("{}:{}: material {}", path.display(), e.line, e.name))?;
                out.push(Material { name: e.name, brdf, channel, budget: e.budget.or(budget) });
            }
        }
        Ok(out)
    }
}

impl Stage for Args {
    const NAME: &'static str = "count-terms";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        check_writable(self.plot.iter().chain([&Output::Stdout]))?;
        let config = CountConfig::try_from(&self)?;
        let out = count::run(&config, self.materials()?, ctx.progress())?;

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
        if self.json {
            outputs.json(&Output::Stdout, &out.rows)?;
        } else {
            outputs.bytes(&Output::Stdout, count::markdown_table(&out.rows).into_bytes())?;
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
