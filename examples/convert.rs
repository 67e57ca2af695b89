//! The `convert` stage through the library: the sky of the `sample_shader` example resampled
//! from lat-long into a horizontal cube cross (`docs/envmap-layouts.md`):
//!
//! ```sh
//! convert out/examples/sky.exr --to cross-horizontal -o out/examples/sky-cross.exr
//! ```
//!
//! `cargo run --release --example convert [OUT_DIR]` (default `out/examples`; run the
//! `sample_shader` example first).

use anyhow::Context;
use prtkit::envmap::stage::{self, Config};
use prtkit::envmap::{Layout, LoadOptions};
use std::path::{Path, PathBuf};

fn main() -> anyhow::Result<()> {
    run(&PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/examples".into())))
}

/// Reads `sky.exr` from `out` and writes `sky-cross.exr` there.
pub fn run(out: &Path) -> anyhow::Result<()> {
    let sky = out.join("sky.exr");
    // The bad-pixel policy of every stage: NaN, infinities and negative radiance are refused.
    let map = LoadOptions::default().load(&sky).context("run the sample_shader example first")?.map;
    let config = Config { to: Layout::CrossHorizontal, size: None, supersample: 3 };
    let cross = stage::run(&config, &map)?;
    prtkit::io::image::write_image(&out.join("sky-cross.exr"), cross.image(), 0.0)?;
    let img = cross.image();
    println!("sky-cross.exr: {}x{} ({} texels from {})", img.width, img.height, cross.texel_count(), map.texel_count());
    Ok(())
}
