//! `count-terms`: how many in-out BRDF terms each material needs — predicted by the closed forms
//! of Mahajan, Tseng & Ramamoorthi 2008 and measured by SVD — with a `--check` mode for CI.

use super::common::{Execution, Outcome};
use super::factor_brdf::parse_memory;
use crate::brdf::BrdfSpec;
use crate::factor::count::{self, CountConfig, Material, Row};
use crate::factor::{manifest, plot, svd, Channel};
use crate::io::{self, Output};
use anyhow::{Context, Result};
use clap::Parser;
use std::path::PathBuf;

/// Predict and measure the number of in-out BRDF terms each material needs.
#[derive(Debug, Parser)]
#[command(name = "count-terms", version, about, long_about = None)]
pub struct Args {
    /// A BRDF spec (docs/brdf-specs.md); repeat for several materials. Its name is the spec
    /// (the file stem for merl:).
    #[arg(long = "brdf", value_name = "SPEC")]
    pub brdfs: Vec<String>,

    #[command(flatten)]
    pub matrix: super::factor_brdf::MatrixArgs,

    /// A manifest of `name spec [budget]` lines (docs/count-terms.md).
    #[arg(long, value_name = "FILE")]
    pub manifest: Option<PathBuf>,

    /// Term budget for every material without a budget of its own.
    #[arg(long, value_name = "N")]
    pub max_terms: Option<usize>,

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

    /// Write an SVG plot: singular values vs predicted F_l, and K vs (l*)².
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<PathBuf>,

    /// CI mode: exit 1 naming each material whose measured K exceeds its budget or whose
    /// prediction misses the measurement by more than --tolerance.
    #[arg(long)]
    pub check: bool,

    /// Allowed |predicted − measured| / measured, as a fraction (0.25) or percent (25%).
    #[arg(long, default_value = "25%", value_parser = parse_tolerance)]
    pub tolerance: f64,

    /// Memory budget per SVD, e.g. 512M, 4G.
    #[arg(long, default_value = "4G", value_parser = parse_memory)]
    pub max_memory: u128,

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

fn default_name(spec: &BrdfSpec, text: &str) -> String {
    match spec {
        BrdfSpec::Merl(p) => p.file_stem().map_or(text.to_string(), |s| s.to_string_lossy().into_owned()),
        other => other.to_string(),
    }
}

/// Runs `count-terms`.
pub fn run(args: Args) -> Result<Outcome> {
    if !(args.energy > 0.0 && args.energy < 1.0) {
        anyhow::bail!("--energy must be in (0, 1), got {}", args.energy);
    }
    if args.max_terms == Some(0) {
        anyhow::bail!("--max-terms must be at least 1");
    }
    let mut entries: Vec<(String, BrdfSpec, Option<usize>)> = Vec::new();
    for text in &args.brdfs {
        let spec = BrdfSpec::parse(text)?;
        entries.push((default_name(&spec, text), spec, args.max_terms));
    }
    if let Some(path) = &args.manifest {
        let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
        let base = path.parent().map(|p| p.to_path_buf()).unwrap_or_default();
        for e in manifest::parse(&text, &path.display().to_string(), &base)? {
            entries.push((e.name, e.spec, e.budget.or(args.max_terms)));
        }
    }
    if entries.is_empty() {
        anyhow::bail!("no material: give --brdf SPEC (repeatable) or --manifest FILE");
    }
    let plot_out = args.plot.as_ref().map(|p| Output::File(p.clone()));
    if let Some(p) = &plot_out {
        p.check_writable()?;
    }
    let sampling = args.matrix.sampling();
    // Load every material and check every budget before the first SVD.
    let mut materials = Vec::new();
    for (name, spec, budget) in entries {
        let brdf = spec.load()?;
        if !args.predict_only {
            let method = svd::resolve_method(&brdf, args.matrix.method)?;
            svd::check_budget(&sampling, method, 0, args.max_memory).with_context(|| format!("material {name}"))?;
        }
        if args.per_channel && brdf.is_rgb() {
            for (suffix, channel) in [("r", Channel::R), ("g", Channel::G), ("b", Channel::B)] {
                materials.push(Material { name: format!("{name}/{suffix}"), brdf: brdf.clone(), channel, budget });
            }
        } else {
            materials.push(Material { name, brdf, channel: args.matrix.channel, budget });
        }
    }
    let config = CountConfig {
        sampling,
        energy: args.energy,
        predict_only: args.predict_only,
        method: args.matrix.method,
        tolerance: args.tolerance,
    };
    let bar = args.run.start()?;
    let mut rows: Vec<Row> = Vec::new();
    let mut spectra = Vec::new();
    for m in &materials {
        let (row, spectrum) = count::count(m, &config, &bar).with_context(|| format!("material {}", m.name))?;
        rows.push(row);
        spectra.push(spectrum);
    }
    if let Some(out) = &plot_out {
        let title = format!(
            "count-terms: {} , n = {}, {:.1} % energy",
            args.matrix.domain,
            args.matrix.resolution,
            100.0 * args.energy
        );
        let svg = plot::count_plot(&title, &rows, &spectra).map_err(anyhow::Error::msg)?;
        out.write(svg.as_bytes())?;
    }
    let text = if args.json { io::document::to_json_pretty(&rows) } else { count::markdown_table(&rows) };
    Output::Stdout.write(text.as_bytes())?;
    let failing: Vec<&Row> = rows.iter().filter(|r| !r.failures.is_empty()).collect();
    if args.check && !failing.is_empty() {
        for r in &failing {
            eprintln!("count-terms: check failed: {}: {}", r.name, r.failures.join("; "));
        }
        return Ok(Outcome::Negative);
    }
    Ok(Outcome::Success)
}
