//! The `sample-shader` stage through the library: the procedural sky of `testdata/shaders/sky.sl`
//! baked into a lat-long environment map by adaptive area sampling with affine arithmetic, every
//! texel with a guaranteed bound (Heidrich, Slusallek & Seidel 1998). The README's first command,
//! at a quarter of its size (the other examples read this sky):
//!
//! ```sh
//! sample-shader testdata/shaders/sky.sl --latlong 128x64 -o out/examples/sky.exr
//! ```
//!
//! `cargo run --release --example sample_shader [OUT_DIR]` (default `out/examples`).

use prtkit::progress::NoProgress;
use prtkit::shader::sampler::{Arith, Domain};
use prtkit::shader::stage::{self, Config};
use prtkit::shader::Shader;
use std::path::{Path, PathBuf};

fn main() -> anyhow::Result<()> {
    run(&PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/examples".into())))
}

/// Writes `sky.exr` into `out`: the texture, with the bound widths and quadtree depths as the
/// layers `width` and `depth`.
pub fn run(out: &Path) -> anyhow::Result<()> {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/shaders/sky.sl");
    let source = prtkit::shader::read_source(&file)?;
    let shader = Shader::compile(&source, &file.display().to_string())?;
    // The command line's defaults, over directions instead of a texture.
    let config = Config {
        tolerance: 0.02,
        max_depth: None,
        resolution: (128, 64),
        domain: Domain::LatLong,
        arithmetics: vec![Arith::Affine],
        points_per_node: 8,
        seed: 1,
        verify: None,
        repeat: 1,
        file: file.display().to_string(),
        args: std::env::args().collect(),
    };
    let sky = stage::run(&config, &shader, &NoProgress)?;
    let layers = [("", &sky.texture), ("width", &sky.width), ("depth", &sky.depth)];
    let exr = prtkit::io::exr::encode_layers(&layers).map_err(anyhow::Error::msg)?;
    std::fs::create_dir_all(out)?;
    prtkit::io::write_atomic(&out.join("sky.exr"), &exr)?;
    let stats = &sky.stats[0].body;
    println!("sky.exr: {} nodes, {} leaves, median bound width {:.4}", stats.nodes, stats.leaves, stats.width.median);
    Ok(())
}
