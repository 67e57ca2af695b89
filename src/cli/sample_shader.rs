//! `sample-shader`: bake a procedural shader into a texture or a lat-long environment map with
//! guaranteed per-texel bounds (Heidrich, Slusallek & Seidel 1998, §3.1), or compare affine,
//! interval and point sampling.

use super::common::{parse_size, Bar, Execution, Outcome};
use crate::io::{self, Document, Output, Provenance, RgbImage};
use crate::shader::report::{self, Histogram, Verification, WidthStats};
use crate::shader::sampler::{self, Arith, Domain, SampleConfig};
use crate::shader::{ParamValue, Shader};
use anyhow::{bail, Context, Result};
use clap::{Parser, ValueEnum};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// The arithmetic used to evaluate a quadtree node.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ArithArg {
    /// Affine arithmetic: guaranteed, tight bounds.
    Affine,
    /// Interval arithmetic: guaranteed, looser bounds.
    Interval,
    /// Random point samples per node: an estimate, not a bound.
    Point,
}

impl From<ArithArg> for Arith {
    fn from(a: ArithArg) -> Arith {
        match a {
            ArithArg::Affine => Arith::Affine,
            ArithArg::Interval => Arith::Interval,
            ArithArg::Point => Arith::Point,
        }
    }
}

/// Bake a procedural shader with guaranteed error bounds (adaptive area sampling).
#[derive(Debug, Parser)]
#[command(name = "sample-shader", version, about, long_about = None)]
pub struct Args {
    /// Shader source file (prtkit shading language, docs/shading-language.md).
    #[arg(value_name = "SHADER")]
    pub shader: PathBuf,

    /// Output texture: .exr (float; with extra layers `width` = bound width and `depth` = quadtree
    /// depth), .png (tone-mapped) or .pfm.
    #[arg(short, long)]
    pub output: Option<PathBuf>,

    /// Also write the texture, bound-width and depth layers into this EXR (useful with a PNG -o).
    #[arg(long, value_name = "EXR")]
    pub layers: Option<PathBuf>,

    /// Subdivide a quadtree node while its bound width (upper − lower, widest channel) exceeds this.
    #[arg(long, default_value_t = 0.02)]
    pub tolerance: f64,

    /// Deepest quadtree level (root = 0). Default: enough levels for one leaf per pixel of --res.
    #[arg(long)]
    pub max_depth: Option<u32>,

    /// Texture resolution WxH.
    #[arg(long, value_parser = parse_size, default_value = "256x256")]
    pub res: (usize, usize),

    /// Sample over directions into a WxH lat-long environment map (u = φ/2π, v = θ/π, +Z up);
    /// overrides --res.
    #[arg(long, value_parser = parse_size, value_name = "WxH")]
    pub latlong: Option<(usize, usize)>,

    /// Arithmetic for the area samples.
    #[arg(long, value_enum, default_value_t = ArithArg::Affine)]
    pub arith: ArithArg,

    /// Run affine, interval and point sampling with the same settings and print the comparison
    /// table (Markdown; an array of rows with --json). Outputs (-o, --stats) are from the affine run.
    #[arg(long)]
    pub compare: bool,

    /// Point samples per node in point mode (the paper measures one affine area sample to cost
    /// about as much as 5–10 point samples).
    #[arg(long, default_value_t = 8)]
    pub points_per_node: usize,

    /// Seed for point sampling and --verify.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,

    /// Shader parameter override NAME=VALUE (a number, or r,g,b); repeatable.
    #[arg(short = 'p', long = "param", value_name = "NAME=VALUE", value_parser = parse_param)]
    pub params: Vec<(String, String)>,

    /// Write JSON statistics (format prtkit.shader-stats) to this file (`-` for stdout).
    #[arg(long, value_name = "JSON")]
    pub stats: Option<String>,

    /// Print the JSON statistics (or, with --compare, the rows) on stdout.
    #[arg(long)]
    pub json: bool,

    /// Check the bounds: evaluate N random points (plus the corners) inside every leaf; exit 1 if
    /// any value lies outside its leaf's bounds (area arithmetics only).
    #[arg(long, value_name = "N")]
    pub verify: Option<usize>,

    /// Sample N times (with --compare, the arithmetics alternate) and report the fastest time
    /// of each arithmetic: on a loaded machine one run can be slowed by other processes. The
    /// results themselves are the same every time.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub repeat: usize,

    /// Exposure in stops for PNG output.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,

    #[command(flatten)]
    pub run: Execution,
}

fn parse_param(s: &str) -> Result<(String, String), String> {
    let (k, v) = s.split_once('=').ok_or_else(|| format!("expected NAME=VALUE, got {s:?}"))?;
    if k.trim().is_empty() {
        return Err(format!("empty parameter name in {s:?}"));
    }
    Ok((k.trim().to_string(), v.trim().to_string()))
}

/// The JSON statistics body (`docs/formats/shader-stats.md`).
#[derive(Debug, Serialize)]
pub struct Stats {
    /// Shader name.
    pub shader: String,
    /// Parameter values used.
    pub params: Vec<ParamValue>,
    /// affine, interval or point.
    pub arith: String,
    /// texture or latlong.
    pub domain: String,
    /// Subdivision tolerance.
    pub tolerance: f64,
    /// Deepest level.
    pub max_depth: u32,
    /// Raster size [W, H].
    pub resolution: [usize; 2],
    /// Nodes evaluated.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Shader evaluations.
    pub evaluations: u64,
    /// Wall-clock seconds of sampling.
    pub seconds: f64,
    /// Whether the widths are guaranteed bounds (false for point sampling).
    pub guaranteed: bool,
    /// Per-pixel bound widths.
    pub width: WidthStats,
    /// Fig. 3 error histogram.
    pub error_histogram: Histogram,
    /// Leaves per depth.
    pub depth_histogram: Vec<u64>,
    /// Leaves whose bounds are infinite (a division by a range containing 0, overflow).
    pub unbounded_leaves: usize,
    /// Result of --verify.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verify: Option<Verification>,
}

/// One row of the --compare table.
#[derive(Debug, Serialize)]
pub struct CompareRow {
    /// affine, interval or point.
    pub arith: String,
    /// Nodes evaluated.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Shader evaluations.
    pub evaluations: u64,
    /// Median per-pixel width.
    pub median_width: f64,
    /// 95th percentile.
    pub p95_width: f64,
    /// Maximum.
    pub max_width: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Seconds per evaluation.
    pub seconds_per_evaluation: f64,
    /// Guaranteed bounds?
    pub guaranteed: bool,
}

struct Run {
    stats: Stats,
    raster: sampler::Raster,
}

fn run_one(shader: &Shader, cfg: &SampleConfig, args: &Args, res: (usize, usize), bar: &Bar) -> Result<Run> {
    let start = Instant::now();
    let sampled = sampler::sample(shader, cfg, bar)?;
    let seconds = start.elapsed().as_secs_f64();
    let raster = sampler::rasterize(&sampled.leaves, res.0, res.1);
    let widths = report::pixel_widths(&raster);
    let verify = match (args.verify, cfg.arith) {
        (Some(n), Arith::Affine | Arith::Interval) => Some(report::verify(shader, &sampled, cfg.domain, n, cfg.seed)?),
        _ => None,
    };
    let stats = Stats {
        shader: shader.name().to_string(),
        params: shader.params(),
        arith: cfg.arith.name().to_string(),
        domain: match cfg.domain {
            Domain::Texture => "texture".into(),
            Domain::LatLong => "latlong".into(),
        },
        tolerance: cfg.tolerance,
        max_depth: cfg.max_depth,
        resolution: [res.0, res.1],
        nodes: sampled.nodes,
        leaves: sampled.leaves.len(),
        evaluations: sampled.evaluations,
        seconds,
        guaranteed: cfg.arith != Arith::Point,
        width: report::width_stats(&widths),
        error_histogram: report::histogram(&widths),
        depth_histogram: report::depth_histogram(&sampled.leaves, cfg.max_depth),
        unbounded_leaves: sampled.leaves.iter().filter(|l| !l.width().is_finite()).count(),
        verify,
    };
    Ok(Run { stats, raster })
}

fn images(r: &sampler::Raster) -> (RgbImage, RgbImage, RgbImage) {
    let f = |v: f64| v as f32;
    let tex = RgbImage::from_fn(r.width, r.height, |x, y| r.mid[y * r.width + x].map(f));
    let wid = RgbImage::from_fn(r.width, r.height, |x, y| r.bound_width[y * r.width + x].map(f));
    let dep = RgbImage::from_fn(r.width, r.height, |x, y| [r.depth[y * r.width + x] as f32; 3]);
    (tex, wid, dep)
}

/// Runs `sample-shader`.
pub fn run(args: Args) -> Result<Outcome> {
    if !(args.tolerance >= 0.0 && args.tolerance.is_finite()) {
        bail!("--tolerance must be a finite number >= 0, got {}", args.tolerance);
    }
    let source = std::fs::read_to_string(&args.shader)
        .with_context(|| format!("cannot read shader {}", args.shader.display()))?;
    let file = args.shader.display().to_string();
    let mut shader = Shader::compile(&source, &file)?;
    shader.set_params(&args.params)?;
    let (domain, res) = match args.latlong {
        Some(size) => (Domain::LatLong, size),
        None => (Domain::Texture, args.res),
    };
    let max_depth = args.max_depth.unwrap_or_else(|| (res.0.max(res.1) as f64).log2().ceil() as u32);
    if max_depth > 16 {
        bail!("--max-depth {max_depth} is too deep (at most 16: 4^16 nodes)");
    }
    for out in [&args.output, &args.layers].into_iter().flatten() {
        Output::File(out.clone()).check_writable()?;
        let ok = matches!(
            out.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref(),
            Some("exr" | "png" | "pfm")
        );
        if !ok {
            bail!("{}: unknown image format (expected .exr, .png or .pfm)", out.display());
        }
    }
    if let Some(s) = &args.stats {
        Output::parse(s).check_writable()?;
    }
    let bar = args.run.start()?;
    let cfg = |arith: Arith| SampleConfig {
        tolerance: args.tolerance,
        max_depth,
        arith,
        domain,
        points_per_node: args.points_per_node,
        seed: args.seed,
    };
    let arithmetics: Vec<Arith> =
        if args.compare { vec![Arith::Affine, Arith::Interval, Arith::Point] } else { vec![args.arith.into()] };
    let mut runs = Vec::new();
    for &a in &arithmetics {
        runs.push(run_one(&shader, &cfg(a), &args, res, &bar)?);
    }
    for _ in 1..args.repeat {
        for (run, &a) in runs.iter_mut().zip(&arithmetics) {
            let start = Instant::now();
            sampler::sample(&shader, &cfg(a), &bar)?;
            run.stats.seconds = run.stats.seconds.min(start.elapsed().as_secs_f64());
        }
    }
    let main = &runs[0];
    let (tex, wid, dep) = images(&main.raster);
    if let Some(out) = &args.output {
        if out.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
            io::exr::write_layers(out, &[("", &tex), ("width", &wid), ("depth", &dep)])?;
        } else {
            io::image::write_image(out, &tex, args.exposure)?;
        }
    }
    if let Some(path) = &args.layers {
        io::exr::write_layers(path, &[("", &tex), ("width", &wid), ("depth", &dep)])?;
    }
    let doc = |stats: &Stats| {
        Document::new("prtkit.shader-stats", 1, Provenance::current("sample-shader", vec![file.clone()]), stats)
            .to_json()
    };
    if let Some(s) = &args.stats {
        Output::parse(s).write(doc(&main.stats).as_bytes())?;
    }
    let mut negative = false;
    for r in &runs {
        if let Some(v) = &r.stats.verify {
            eprintln!(
                "sample-shader: verify ({}): {} points in {} leaves, {} outside their bounds",
                r.stats.arith, v.points, v.leaves, v.violations
            );
            negative |= v.violations > 0;
        }
    }
    if args.compare {
        let point_cost =
            runs.iter().find(|r| r.stats.arith == "point").map(|r| r.stats.seconds / r.stats.evaluations as f64);
        let rows: Vec<CompareRow> = runs
            .iter()
            .map(|r| CompareRow {
                arith: r.stats.arith.clone(),
                nodes: r.stats.nodes,
                leaves: r.stats.leaves,
                evaluations: r.stats.evaluations,
                median_width: r.stats.width.median,
                p95_width: r.stats.width.p95,
                max_width: r.stats.width.max,
                seconds: r.stats.seconds,
                seconds_per_evaluation: r.stats.seconds / r.stats.evaluations.max(1) as f64,
                guaranteed: r.stats.guaranteed,
            })
            .collect();
        if args.json {
            Output::Stdout.write(io::document::to_json_pretty(&rows).as_bytes())?;
        } else {
            let mut t = String::from(
                "| shader | arith | nodes | leaves | evaluations | median width | p95 width | max width | seconds | cost per evaluation (point = 1) | guaranteed |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
            );
            for r in &rows {
                let cost = point_cost.map(|p| format!("{:.2}", r.seconds_per_evaluation / p)).unwrap_or_default();
                t += &format!(
                    "| {} | {} | {} | {} | {} | {:.4} | {:.4} | {:.4} | {:.3} | {} | {} |\n",
                    shader.name(),
                    r.arith,
                    r.nodes,
                    r.leaves,
                    r.evaluations,
                    r.median_width,
                    r.p95_width,
                    r.max_width,
                    r.seconds,
                    cost,
                    if r.guaranteed { "yes" } else { "no (estimate)" }
                );
            }
            Output::Stdout.write(t.as_bytes())?;
        }
    } else if args.json && args.stats.as_deref() != Some("-") {
        Output::Stdout.write(doc(&main.stats).as_bytes())?;
    }
    if !args.run.quiet && !args.json {
        let s = &main.stats;
        eprintln!(
            "sample-shader: {} ({}): {} nodes, {} leaves, median width {:.4}, p95 {:.4}, max {:.4}, {:.2} s",
            s.shader, s.arith, s.nodes, s.leaves, s.width.median, s.width.p95, s.width.max, s.seconds
        );
    }
    Ok(if negative { Outcome::Negative } else { Outcome::Success })
}
