//! The flags of `count-terms` (clap declarations only; their help text is the user's reference).

use crate::brdf::Brdf;
use crate::cli::options::{parse_brdf, parse_output, Execution, MatrixArgs};
use crate::io::Output;
use anyhow::Result;
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

    /// How the BRDF matrix is sampled and factored (shared by `factor-brdf` and `count-terms`).
    #[command(flatten)]
    pub matrix: MatrixArgs,

    /// A manifest of `name spec [budget]` lines (docs/count-terms.md), or `-` for stdin (relative
    /// MERL paths then from the working directory).
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

    /// Write an SVG plot: singular values vs predicted F_l, and K vs (l*)² (`-`: stdout, in place
    /// of the table).
    #[arg(long, value_name = "FILE.svg", value_parser = parse_output)]
    pub plot: Option<Output>,

    /// CI mode: exit 1 naming each material whose measured K exceeds its budget or whose
    /// prediction misses the measurement by more than --tolerance.
    #[arg(long)]
    pub check: bool,

    /// Allowed |predicted − measured| / measured, as a fraction (0.25) or percent (25%).
    #[arg(long, default_value = "25%", value_parser = parse_tolerance)]
    pub tolerance: f64,

    /// Threads, quiet, progress.
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
