//! The `sample-shader` stage as one library call: bake a procedural shader into a texture or a
//! lat-long environment map by adaptive area sampling with guaranteed per-texel bounds
//! (Heidrich, Slusallek & Seidel 1998, §3.1), or compare affine, interval and point sampling.

use super::report::{self, Histogram, Verification, WidthStats};
use super::sampler::{self, Arith, Domain, Raster, SampleConfig};
use super::{ParamValue, Shader, ShaderError};
use crate::io::{Document, Provenance, RgbImage};
use crate::limits::MAX_QUADTREE_DEPTH;
use crate::progress::Progress;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Document kind of the statistics.
pub const STATS_FORMAT: &str = "prtkit.shader-stats";
/// Its schema version.
pub const STATS_VERSION: u32 = 1;

/// What `sample-shader` computes.
#[derive(Clone, Debug)]
pub struct Config {
    /// Subdivide a node while its bound width exceeds this.
    pub tolerance: f64,
    /// Deepest level; `None`: one leaf per pixel of the raster.
    pub max_depth: Option<u32>,
    /// Raster size.
    pub resolution: (usize, usize),
    /// A texture over \[0,1\]² or a lat-long map over directions.
    pub domain: Domain,
    /// The arithmetics to run: the first one's run gives the outputs; several make a comparison.
    pub arithmetics: Vec<Arith>,
    /// Point samples per node in point mode.
    pub points_per_node: usize,
    /// Seed of point sampling and of the verification.
    pub seed: u64,
    /// Verify the bounds with N random points per leaf (area arithmetics).
    pub verify: Option<usize>,
    /// Sample this many times and keep the fastest time of each arithmetic.
    pub repeat: usize,
    /// The shader's file, for the document.
    pub file: String,
    /// The command line, for the document's provenance.
    pub args: Vec<String>,
}

/// What `sample-shader` produces (from the first arithmetic's run).
#[derive(Debug)]
pub struct Output {
    /// The texture (area-sample means).
    pub texture: RgbImage,
    /// Per-pixel bound width (upper − lower).
    pub width: RgbImage,
    /// Per-pixel quadtree depth.
    pub depth: RgbImage,
    /// The `prtkit.shader-stats` document of every run, in the config's order.
    pub stats: Vec<Document<Stats>>,
    /// The comparison rows, when several arithmetics ran.
    pub comparison: Option<Vec<CompareRow>>,
    /// Points found outside their leaf's bounds by the verification (0 when not verified).
    pub violations: u64,
    /// Seconds of sampling of each run (the fastest of `repeat`), in the config's order.
    pub seconds: Vec<f64>,
}

/// The statistics body (`docs/formats/shader-stats.md`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
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
    /// Wall-clock seconds of sampling (the fastest of `repeat`): in the `--json` summary only,
    /// so that documents are the same bytes for the same inputs.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seconds: Option<f64>,
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
    /// Result of the verification.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub verify: Option<Verification>,
}

/// One row of the comparison table.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CompareRow {
    /// affine, interval or point.
    pub arith: String,
    /// Nodes evaluated.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Shader evaluations.
    pub evaluations: u64,
    /// Median per-pixel width (`null` in JSON when unbounded).
    #[serde(deserialize_with = "super::report::null_as_infinity")]
    pub median_width: f64,
    /// 95th percentile (`null` when unbounded).
    #[serde(deserialize_with = "super::report::null_as_infinity")]
    pub p95_width: f64,
    /// Maximum (`null` when unbounded).
    #[serde(deserialize_with = "super::report::null_as_infinity")]
    pub max_width: f64,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Seconds per evaluation.
    pub seconds_per_evaluation: f64,
    /// Guaranteed bounds?
    pub guaranteed: bool,
}

/// Errors of the stage. They speak of the sampling, not of the flags that set it: the CLI
/// (`cli/sample_shader.rs`) words them with the flag's name.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The tolerance is not a finite number ≥ 0.
    #[error("the tolerance must be a finite number >= 0, got {0}")]
    Tolerance(f64),
    /// The subdivision would go deeper than [`MAX_QUADTREE_DEPTH`].
    #[error("a subdivision depth of {0} is too deep (at most {MAX_QUADTREE_DEPTH}: 4^{MAX_QUADTREE_DEPTH} nodes)")]
    Depth(u32),
    /// Evaluating the shader failed.
    #[error(transparent)]
    Shader(#[from] ShaderError),
}

/// Runs `sample-shader` on a compiled `shader` (parameters set).
pub fn run(config: &Config, shader: &Shader, progress: &dyn Progress) -> Result<Output, Error> {
    if !(config.tolerance >= 0.0 && config.tolerance.is_finite()) {
        return Err(Error::Tolerance(config.tolerance));
    }
    let res = config.resolution;
    let max_depth = config.max_depth.unwrap_or_else(|| (res.0.max(res.1) as f64).log2().ceil() as u32);
    if max_depth > MAX_QUADTREE_DEPTH {
        return Err(Error::Depth(max_depth));
    }
    let arithmetics = if config.arithmetics.is_empty() { vec![Arith::Affine] } else { config.arithmetics.clone() };
    let cfg = |arith: Arith| SampleConfig {
        tolerance: config.tolerance,
        max_depth,
        arith,
        domain: config.domain,
        points_per_node: config.points_per_node,
        seed: config.seed,
    };
    let mut runs = Vec::new();
    let mut seconds = Vec::new();
    for &a in &arithmetics {
        let (stats, raster, secs) = run_one(shader, &cfg(a), config, res, progress)?;
        runs.push((stats, raster));
        seconds.push(secs);
    }
    for _ in 1..config.repeat.max(1) {
        for (s, &a) in seconds.iter_mut().zip(&arithmetics) {
            let start = Instant::now();
            sampler::sample(shader, &cfg(a), progress)?;
            *s = s.min(start.elapsed().as_secs_f64());
        }
    }
    let violations = runs.iter().filter_map(|(s, _)| s.verify.as_ref()).map(|v| v.violations).sum();
    let comparison = (arithmetics.len() > 1).then(|| {
        runs.iter()
            .zip(&seconds)
            .map(|((s, _), &secs)| CompareRow {
                arith: s.arith.clone(),
                nodes: s.nodes,
                leaves: s.leaves,
                evaluations: s.evaluations,
                median_width: s.width.median,
                p95_width: s.width.p95,
                max_width: s.width.max,
                seconds: secs,
                seconds_per_evaluation: secs / s.evaluations.max(1) as f64,
                guaranteed: s.guaranteed,
            })
            .collect()
    });
    let (texture, width, depth) = images(&runs[0].1);
    let stats = runs
        .into_iter()
        .map(|(s, _)| {
            let provenance = Provenance::new("sample-shader", &config.args, vec![config.file.clone()]);
            Document::new(STATS_FORMAT, STATS_VERSION, provenance, s)
        })
        .collect();
    Ok(Output { texture, width, depth, stats, comparison, violations, seconds })
}

/// The comparison as a Markdown table, with each arithmetic's cost per evaluation relative to a
/// point sample's (the paper's Table 1 measure).
pub fn comparison_table(shader: &str, rows: &[CompareRow]) -> String {
    let point_cost = rows.iter().find(|r| r.arith == "point").map(|r| r.seconds_per_evaluation);
    let mut t = String::from(
        "| shader | arith | nodes | leaves | evaluations | median width | p95 width | max width | seconds | cost per evaluation (point = 1) | guaranteed |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|\n",
    );
    for r in rows {
        let cost = point_cost.map(|p| format!("{:.2}", r.seconds_per_evaluation / p)).unwrap_or_default();
        t += &format!(
            "| {shader} | {} | {} | {} | {} | {:.4} | {:.4} | {:.4} | {:.3} | {cost} | {} |\n",
            r.arith,
            r.nodes,
            r.leaves,
            r.evaluations,
            r.median_width,
            r.p95_width,
            r.max_width,
            r.seconds,
            if r.guaranteed { "yes" } else { "no (estimate)" }
        );
    }
    t
}

fn run_one(
    shader: &Shader,
    cfg: &SampleConfig,
    config: &Config,
    res: (usize, usize),
    progress: &dyn Progress,
) -> Result<(Stats, Raster, f64), Error> {
    let start = Instant::now();
    let sampled = sampler::sample(shader, cfg, progress)?;
    let seconds = start.elapsed().as_secs_f64();
    let raster = sampler::rasterize(&sampled.leaves, res.0, res.1);
    let widths = report::pixel_widths(&raster);
    let verify = match (config.verify, cfg.arith) {
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
        seconds: None,
        guaranteed: cfg.arith != Arith::Point,
        width: report::width_stats(&widths),
        error_histogram: report::histogram(&widths),
        depth_histogram: report::depth_histogram(&sampled.leaves, cfg.max_depth),
        unbounded_leaves: sampled.leaves.iter().filter(|l| !l.width().is_finite()).count(),
        verify,
    };
    Ok((stats, raster, seconds))
}

fn images(r: &Raster) -> (RgbImage, RgbImage, RgbImage) {
    let f = |v: f64| v as f32;
    let tex = RgbImage::from_fn(r.width, r.height, |x, y| r.mid[y * r.width + x].map(f));
    let wid = RgbImage::from_fn(r.width, r.height, |x, y| r.bound_width[y * r.width + x].map(f));
    let dep = RgbImage::from_fn(r.width, r.height, |x, y| [r.depth[y * r.width + x] as f32; 3]);
    (tex, wid, dep)
}
