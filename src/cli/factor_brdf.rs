//! `factor-brdf`: clap arguments → [`factor::stage::Config`] → one library call → outputs.

use super::common::{Context, Outcome, Stage};
use super::options::{parse_brdf, parse_output, Execution, MatrixArgs};
use super::outputs::{check_writable, Outputs};
use crate::brdf::Brdf;
use crate::factor::stage::{self, Config};
use crate::io::{self, Output};
use anyhow::Result;
use clap::Parser;
use std::path::PathBuf;

/// Factor a BRDF into in-out terms by SVD and report how many terms each energy fraction needs.
///
/// Writes a `prtkit.factor` document (singular values, energy curve, K at 90/95/99/99.9 %,
/// reconstruction errors) and, optionally, the factor maps and the factor file that
/// `render --shading factored --factors` relights with.
#[derive(Debug, Parser)]
#[command(name = "factor-brdf", version)]
pub struct Args {
    /// BRDF spec, e.g. `phong:s=30`, `torrance-sparrow:sigma=0.2`, `merl:gold.binary`
    /// (docs/brdf-specs.md).
    #[arg(value_name = "SPEC", value_parser = parse_brdf)]
    pub brdf: Brdf,

    #[command(flatten)]
    pub matrix: MatrixArgs,

    /// Write the factor maps g_k, h_k (factors.exr with layers g_000, h_000, …, and a
    /// factors.png contact sheet) into this directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub maps: Option<PathBuf>,

    /// Write the leading factors g_k, h_k sampled on the grid to this EXR (the document names
    /// it), for `render --shading factored --factors DOC.json` (docs/formats/factor.md).
    #[arg(long, value_name = "FILE.exr")]
    pub factors: Option<PathBuf>,

    /// Number of leading terms drawn by --maps and stored by --factors.
    #[arg(long, default_value_t = 16, value_name = "N")]
    pub terms: usize,

    /// The JSON document (`prtkit.factor`, docs/formats/factor.md); `-` is stdout.
    #[arg(short, long, default_value = "-", value_parser = parse_output)]
    pub output: Output,

    /// Print a JSON summary on stdout (the document then needs -o FILE).
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub run: Execution,
}

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

impl Stage for Args {
    const NAME: &'static str = "factor-brdf";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        super::options::check_json_output(&self.output, self.json)?;
        let factors_out = self.factors.clone().map(Output::File);
        check_writable(std::iter::once(&self.output).chain(&factors_out))?;
        let config = Config::try_from(&self)?;
        let out = stage::run(&config, &self.brdf, ctx.progress())?;

        let mut outputs = Outputs::new();
        if let (Some(dir), Some((layers, sheet))) = (&self.maps, &out.maps) {
            outputs.create_dir(dir)?;
            let refs: Vec<(&str, &io::RgbImage)> = layers.iter().map(|(n, i)| (n.as_str(), i)).collect();
            outputs.bytes(
                &Output::File(dir.join("factors.exr")),
                io::exr::encode_layers(&refs).map_err(anyhow::Error::msg)?,
            )?;
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
