//! `sample-shader`: clap arguments → [`shader::stage::Config`] → one library call → outputs.
//!
//! [`shader::stage::Config`]: crate::shader::stage::Config

mod args;

use super::common::{Context, Outcome, Stage};
use super::options::Execution;
use super::outputs::{check_outputs, Holds, Outputs};
use crate::io::{self, Output, RgbImage};
use crate::limits::MAX_QUADTREE_DEPTH;
use crate::shader::sampler::{Arith, Domain};
use crate::shader::stage::{self, comparison_table, Config, Error};
use crate::shader::Shader;
use anyhow::Result;
pub use args::*;

use std::path::Path;

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

/// The stage's error in the words of the flag that set the refused value; the others as they are.
fn flagged(error: Error) -> anyhow::Error {
    match error {
        Error::Tolerance(t) => anyhow::anyhow!("--tolerance must be a finite number >= 0, got {t}"),
        Error::Depth(d) => {
            anyhow::anyhow!("--max-depth {d} is too deep (at most {MAX_QUADTREE_DEPTH}: 4^{MAX_QUADTREE_DEPTH} nodes)")
        }
        error => error.into(),
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
        check_outputs(
            (self.output.iter().map(|o| (o, Holds::Image)))
                .chain(self.layers.iter().map(|o| (o, Holds::Exr)))
                .chain(self.stats.iter().chain(&json_out).map(|o| (o, Holds::Text))),
        )?;
        let config = Config::try_from(&self)?;
        let source = crate::shader::read_source(&self.shader)?;
        let mut shader = Shader::compile(&source, &config.file)?;
        shader.set_params(&self.params)?;
        let out = stage::run(&config, &shader, ctx.progress()).map_err(flagged)?;

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
