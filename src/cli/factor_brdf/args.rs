//! The flags of `factor-brdf` (clap declarations only; their help text is the user's reference).

use crate::brdf::Brdf;
use crate::cli::options::{parse_brdf, parse_output, Execution, MatrixArgs};
use crate::io::Output;
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

    /// How the BRDF matrix is sampled and factored (shared by `factor-brdf` and `count-terms`).
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

    /// Threads, quiet, progress.
    #[command(flatten)]
    pub run: Execution,
}
