//! The `count-terms` stage through the library: how many in-out terms Phong s = 30 and
//! Torrance–Sparrow σ = 0.2 need for 99 % of their energy, predicted by the closed forms and
//! measured by SVD (Mahajan, Tseng & Ramamoorthi 2008), checked against a budget of 80 terms.
//! The README's command:
//!
//! ```sh
//! count-terms --brdf phong:s=30 --brdf torrance-sparrow:sigma=0.2 --max-terms 80 --check
//! ```
//!
//! `cargo run --release --example count_terms` prints the table; it fails, as `--check` exits 1,
//! when a material is over its budget or mispredicted. It writes nothing (the optional argument
//! is accepted for symmetry with the other examples).

use prtkit::brdf::Brdf;
use prtkit::factor::count::{self, CountConfig, Material};
use prtkit::factor::{Channel, Domain, Sampling};
use prtkit::progress::NoProgress;
use std::path::{Path, PathBuf};

fn main() -> anyhow::Result<()> {
    run(&PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/examples".into())))
}

/// Prints the table; an error names every material that fails the check.
pub fn run(_out: &Path) -> anyhow::Result<()> {
    // The command line's defaults: the paper's 40 × 40 hemisphere grid, 99 %, 25 % tolerance.
    let config = CountConfig::new(Sampling {
        resolution: 40,
        domain: Domain::Hemisphere,
        cosine: false,
        channel: Channel::Luminance,
    });
    let mut materials = Vec::new();
    for spec in ["phong:s=30", "torrance-sparrow:sigma=0.2"] {
        let brdf = Brdf::parse(spec)?;
        materials.push(Material { name: brdf.spec(), brdf, channel: Channel::Luminance, budget: Some(80) });
    }
    let counted = count::run(&config, materials, &NoProgress)?;
    print!("{}", count::markdown_table(&counted.rows));
    let failing: Vec<String> = counted.failing().map(|r| format!("{}: {}", r.name, r.failures.join("; "))).collect();
    anyhow::ensure!(failing.is_empty(), "check failed: {}", failing.join(" | "));
    Ok(())
}
