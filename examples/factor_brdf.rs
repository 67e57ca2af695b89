//! The `factor-brdf` stage through the library: the in-out SVD of normalized Phong s = 30 on the
//! 40 × 40 hemisphere grid (Mahajan, Tseng & Ramamoorthi 2008), its `prtkit.factor` document and
//! the first 75 factors g_k, h_k in the factor file `render` relights with. The README's command:
//!
//! ```sh
//! factor-brdf phong:s=30 --terms 75 --factors out/examples/p30.exr -o out/examples/p30.json
//! ```
//!
//! `cargo run --release --example factor_brdf [OUT_DIR]` (default `out/examples`).

use prtkit::brdf::Brdf;
use prtkit::factor::stage::{self, Config};
use prtkit::factor::{Channel, Domain, Method, Sampling};
use prtkit::progress::NoProgress;
use std::path::{Path, PathBuf};

fn main() -> anyhow::Result<()> {
    run(&PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/examples".into())))
}

/// Writes `p30.json` and `p30.exr` into `out`.
pub fn run(out: &Path) -> anyhow::Result<()> {
    let factors = out.join("p30.exr");
    let config = Config {
        sampling: Sampling { resolution: 40, domain: Domain::Hemisphere, cosine: false, channel: Channel::Luminance },
        method: Method::Auto,
        terms: 75,
        maps: false,
        maps_dir: None,
        // The document names the factor file as given, so the pair can be moved together.
        factors_file: Some(factors.display().to_string()),
        max_memory: 4 << 30,
        args: std::env::args().collect(),
    };
    let factored = stage::run(&config, &Brdf::parse("phong:s=30")?, &NoProgress)?;
    std::fs::create_dir_all(out)?;
    if let Some(f) = &factored.factors {
        prtkit::io::exr::write_grey_layers(&factors, f.width, f.height, &[("g", &f.g), ("h", &f.h)])?;
    }
    prtkit::io::write_atomic(&out.join("p30.json"), factored.document.to_json().as_bytes())?;
    let terms: Vec<String> = factored.summary.terms.iter().map(|(e, k)| format!("{e}: {k}")).collect();
    println!("p30.json: K for {}", terms.join(", "));
    Ok(())
}
