//! The `sh-project` stage through the library: the sky's SH coefficients at the smallest order
//! that captures 1 − ε of its energy (Ramamoorthi & Hanrahan 2002, §5.1), and its irradiance map.
//! The README's command with ε = 0.1 instead of 0.01: the sun disc of a 512×256 sky needs order
//! 246 for 0.01, more than the 128×64 sky of the `sample_shader` example resolves.
//!
//! ```sh
//! sh-project out/examples/sky.exr --epsilon 0.1 -o out/examples/sky.sh.json \
//!     --irradiance out/examples/sky-irr.png
//! ```
//!
//! `cargo run --release --example sh_project [OUT_DIR]` (default `out/examples`; run the
//! `sample_shader` example first).

use anyhow::Context;
use prtkit::envmap::LoadOptions;
use prtkit::limits::MAX_EPSILON_ORDER;
use prtkit::progress::NoProgress;
use prtkit::sh::project::OrderChoice;
use prtkit::sh::stage::{self, Config};
use std::path::{Path, PathBuf};

fn main() -> anyhow::Result<()> {
    run(&PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/examples".into())))
}

/// Reads `sky.exr` from `out` and writes `sky.sh.json` and `sky-irr.png` there.
pub fn run(out: &Path) -> anyhow::Result<()> {
    let sky = out.join("sky.exr");
    let map = LoadOptions::default().load(&sky).context("run the sample_shader example first")?.map;
    let config = Config {
        order: OrderChoice::Epsilon { epsilon: 0.1, max_search: MAX_EPSILON_ORDER },
        irradiance: true,
        source: sky.display().to_string(),
        args: std::env::args().collect(),
        ..Config::default()
    };
    let projected = stage::run(&config, &map, &NoProgress)?;
    prtkit::io::write_atomic(&out.join("sky.sh.json"), projected.document.to_json().as_bytes())?;
    let irradiance = projected.irradiance.as_ref().context("asked for the irradiance map")?;
    prtkit::io::image::write_image(&out.join("sky-irr.png"), irradiance, 0.0)?;
    let s = &projected.summary;
    println!("sky.sh.json: order {} ({} coefficients), ε achieved {:.4}", s.order, s.coefficients, s.epsilon_achieved);
    Ok(())
}
