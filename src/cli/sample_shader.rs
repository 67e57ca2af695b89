//! `sample-shader`: clap arguments → [`shader::stage::Config`] → one library call → outputs.

use super::common::{Context, Outcome, Stage};
use super::options::{parse_output, parse_size, Execution, Exposure};
use super::outputs::{check_writable, Outputs};
use crate::io::{self, Output, RgbImage};
use crate::shader::sampler::{Arith, Domain};
use crate::shader::stage::{self, comparison_table, Config};
use crate::shader::Shader;
use anyhow::{Context as _, Result};
use clap::{Parser, ValueEnum};
use std::path::{Path, PathBuf};

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

/// Bake a procedural shader with guaranteed error bounds (adaptive area sampling with affine
/// arithmetic, Heidrich, Slusallek & Seidel 1998).
#[derive(Debug, Parser)]
#[command(name = "sample-shader", version)]
pub struct Args {
    /// Shader source file (prtkit shading language, docs/shading-language.md).
    #[arg(value_name = "SHADER")]
    pub shader: PathBuf,

    /// Output texture: .exr (float; with extra layers `width` = bound width and `depth` = quadtree
    /// depth), .png (tone-mapped) or .pfm; `-`: EXR on stdout.
    #[arg(short, long, value_parser = parse_output)]
    pub output: Option<Output>,

    /// Also write the texture, bound-width and depth layers into this EXR (useful with a PNG -o).
    #[arg(long, value_name = "EXR", value_parser = parse_output)]
    pub layers: Option<Output>,

    /// Subdivide a quadtree node while its bound width (upper − lower, widest channel) exceeds this.
    #[arg(long, default_value_t = 0.02)]
    pub tolerance: f64,

    /// Deepest quadtree level (root = 0; at most 16). Default: one leaf per pixel of --res.
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
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub points_per_node: u64,

    /// Seed for point sampling and --verify.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,

    /// Shader parameter override NAME=VALUE (a number, or r,g,b); repeatable.
    #[arg(short = 'p', long = "param", value_name = "NAME=VALUE", value_parser = parse_param)]
    pub params: Vec<(String, String)>,

    /// Write the statistics (format prtkit.shader-stats) to this file (`-` for stdout).
    #[arg(long, value_name = "JSON", value_parser = parse_output)]
    pub stats: Option<Output>,

    /// Print the statistics with timings (or, with --compare, the rows) on stdout.
    #[arg(long)]
    pub json: bool,

    /// Check the bounds: evaluate N random points (plus the corners) inside every leaf; exit 1 if
    /// any value lies outside its leaf's bounds (area arithmetics only).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=4096))]
    pub verify: Option<u64>,

    /// Sample N times (with --compare, the arithmetics alternate) and report the fastest time of
    /// each arithmetic. The results themselves are the same every time.
    #[arg(long, default_value_t = 1, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=100))]
    pub repeat: u64,

    #[command(flatten)]
    pub exposure: Exposure,

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

impl TryFrom<&Args> for Config {
    type Error = anyhow::Error;
    fn try_from(args: &Args) -> Result<Config> {
        let arith = match args.arith {
            ArithArg::Affine => Arith::Affine,
            ArithArg::Interval => Arith::Interval,
            ArithArg::Point => Arith::Point,
        };
        Ok(Config {
            tolerance: args.tolerance,
            max_depth: args.max_depth,
            resolution: args.latlong.unwrap_or(args.res),
            domain: if args.latlong.is_some() { Domain::LatLong } else { Domain::Texture },
            arithmetics: if args.compare { vec![Arith::Affine, Arith::Interval, Arith::Point] } else { vec![arith] },
            points_per_node: args.points_per_node as usize,
            seed: args.seed,
            verify: args.verify.map(|n| n as usize),
            repeat: args.repeat as usize,
            file: args.shader.display().to_string(),
            args: std::env::args().collect(),
        })
    }
}

fn layered(texture: &RgbImage, width: &RgbImage, depth: &RgbImage) -> Result<Vec<u8>> {
    io::exr::encode_layers(&[("", texture), ("width", width), ("depth", depth)]).map_err(anyhow::Error::msg)
}

impl Stage for Args {
    const NAME: &'static str = "sample-shader";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        let json_out = self.json.then_some(Output::Stdout);
        check_writable(self.output.iter().chain(&self.layers).chain(&self.stats).chain(&json_out))?;
        let config = Config::try_from(&self)?;
        let source = std::fs::read_to_string(&self.shader)
            .with_context(|| format!("cannot read shader {}", self.shader.display()))?;
        let mut shader = Shader::compile(&source, &config.file)?;
        shader.set_params(&self.params)?;
        let out = stage::run(&config, &shader, ctx.progress())?;

        let mut outputs = Outputs::new();
        if let Some(o) = &self.output {
            match o {
                Output::File(p) if !is_exr(p) => outputs.image(o, &out.texture, self.exposure.stops)?,
                _ => outputs.bytes(o, layered(&out.texture, &out.width, &out.depth)?)?,
            }
        }
        if let Some(o) = &self.layers {
            outputs.bytes(o, layered(&out.texture, &out.width, &out.depth)?)?;
        }
        if let Some(o) = &self.stats {
            outputs.json(o, &out.stats[0])?;
        }
        match (&out.comparison, &json_out) {
            (Some(rows), Some(o)) => outputs.json(o, rows)?,
            (Some(rows), None) => outputs.bytes(&Output::Stdout, comparison_table(shader.name(), rows).into_bytes())?,
            (None, Some(o)) => {
                let mut timed = out.stats[0].clone();
                timed.body.seconds = out.seconds.first().copied();
                outputs.json(o, &timed)?
            }
            (None, None) => {}
        }
        outputs.commit()?;
        for (doc, seconds) in out.stats.iter().zip(&out.seconds) {
            let s = &doc.body;
            if let Some(v) = &s.verify {
                let line = format!(
                    "verify ({}): {} points in {} leaves, {} outside their bounds",
                    s.arith, v.points, v.leaves, v.violations
                );
                if v.violations > 0 {
                    // The reason for exit status 1: said even with --quiet.
                    eprintln!("sample-shader: {line}");
                } else {
                    ctx.note(line);
                }
            }
            if out.comparison.is_none() {
                ctx.note(format!(
                    "{} ({}): {} nodes, {} leaves, median width {:.4}, p95 {:.4}, max {:.4}, {seconds:.2} s",
                    s.shader, s.arith, s.nodes, s.leaves, s.width.median, s.width.p95, s.width.max
                ));
            }
        }
        Ok(if out.violations > 0 { Outcome::Negative } else { Outcome::Success })
    }
}

fn is_exr(p: &Path) -> bool {
    p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}
