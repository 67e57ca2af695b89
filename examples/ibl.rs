//! The `ibl` stage through the library: the sky of the `sample_shader` example baked into the
//! files a glTF engine loads (`docs/ibl.md`): the GGX mip chain, the irradiance cube, the SH and
//! the DFG table, with each level's error measured against the angular integral:
//!
//! ```sh
//! ibl out/examples/sky.exr -o out/examples/ibl --size 64
//! ```
//!
//! `cargo run --release --example ibl [OUT_DIR]` (default `out/examples`; run the
//! `sample_shader` example first).

use anyhow::Context;
use prtkit::envmap::LoadOptions;
use prtkit::ibl::manifest;
use prtkit::ibl::stage::{self, Config};
use prtkit::io::write_atomic;
use prtkit::progress::NoProgress;
use std::path::{Path, PathBuf};

fn main() -> anyhow::Result<()> {
    run(&PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/examples".into())))
}

/// Reads `sky.exr` from `out` and writes the bake into `out/ibl`.
pub fn run(out: &Path) -> anyhow::Result<()> {
    let sky = out.join("sky.exr");
    let map = LoadOptions::default().load(&sky).context("run the sample_shader example first")?.map;
    let config = Config { size: 64, source: sky.display().to_string(), ..Config::default() };
    let bake = stage::run(&config, &map, &NoProgress)?;
    let dir = out.join("ibl");
    std::fs::create_dir_all(&dir)?;
    write_bake(&bake, &dir)?;
    for level in &bake.document.body.specular.levels {
        if let Some(rms) = level.rms_rel_error {
            println!("level {} ({}², r = {:.2}): {:.3} % RMS", level.level, level.size, level.roughness, 100.0 * rms);
        }
    }
    Ok(())
}

/// Writes every file of the bake into `dir` under the name the manifest gives it, encoded as
/// the binary encodes it: the textures in their container, the documents as JSON, the snippets
/// as text.
fn write_bake(bake: &stage::Output, dir: &Path) -> anyhow::Result<()> {
    for (name, texture, format) in bake.textures() {
        write_atomic(&dir.join(name), &bake.container.encode(&texture, format)?)?;
    }
    write_atomic(&dir.join(&bake.document.body.sh.file), bake.sh_document.to_json().as_bytes())?;
    for (name, text) in bake.shaders() {
        write_atomic(&dir.join(name), text.as_bytes())?;
    }
    Ok(write_atomic(&dir.join(manifest::FILE), bake.document.to_json().as_bytes())?)
}
