//! The `prefilter` stage through the library: the sky prefiltered with normalized Phong s = 32
//! in frequency space (Ramamoorthi & Hanrahan 2002), orders F_B, P_B chosen from ε = 0.01, and
//! the reflection map seen from +Z. The README's command:
//!
//! ```sh
//! prefilter out/examples/sky.exr --brdf phong:s=32 --reflection-map out/examples/phong32.png
//! ```
//!
//! `cargo run --release --example prefilter [OUT_DIR]` (default `out/examples`; run the
//! `sample_shader` example first).

use anyhow::Context;
use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::envmap::LoadOptions;
use prtkit::prefilter::pipeline::Lighting;
use prtkit::prefilter::stage::{self, Config, MapRequest};
use prtkit::progress::NoProgress;
use std::path::{Path, PathBuf};

fn main() -> anyhow::Result<()> {
    run(&PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/examples".into())))
}

/// Reads `sky.exr` from `out` and writes `phong32.png` there.
pub fn run(out: &Path) -> anyhow::Result<()> {
    let sky = out.join("sky.exr");
    let map = LoadOptions::default().load(&sky).context("run the sample_shader example first")?.map;
    let file = out.join("phong32.png");
    let config = Config {
        maps: vec![MapRequest { file: file.display().to_string(), view: DVec3::Z }],
        source: sky.display().to_string(),
        args: std::env::args().collect(),
        ..Config::new(Brdf::parse("phong:s=32")?)
    };
    let prefiltered = stage::run(&config, Lighting::Map(&map), &NoProgress)?;
    prtkit::io::image::write_image(&file, &prefiltered.maps[0], 0.0)?;
    let s = &prefiltered.summary;
    println!(
        "phong32.png: F_B = {}, P_B = {}, ε achieved {:.4}, {}x{}",
        s.f_b, s.p_b, s.epsilon_achieved, s.width, s.height
    );
    Ok(())
}
