//! The `encode-normals` stage through the library: the vertex normals of `testdata/meshes/sphere.obj`
//! stored in 24 bits each with the range-mapped octahedral encoding (Meyer et al. 2010), with
//! the report of every normal's angular error against the closed-form bound and the decoded
//! OBJ; then the paper's Table 1 at 32 bits, the README's command, on 2¹⁶ random directions
//! (plus the adversarial ones) instead of 10⁷:
//!
//! ```sh
//! encode-normals testdata/meshes/sphere.obj --scheme onv-range --bits 24 -o out/examples/sphere.codes \
//!     --report out/examples/sphere.normals.json --decoded out/examples/sphere-decoded.obj
//! encode-normals --table --bits 32 --samples 65536 > out/examples/table32.md
//! ```
//!
//! `cargo run --release --example encode_normals [OUT_DIR]` (default `out/examples`).

use prtkit::normals::encode::{self, Config, Files};
use prtkit::normals::pack::Stream;
use prtkit::normals::sources::NormalSource;
use prtkit::normals::table::{self, TableConfig};
use prtkit::normals::{InvalidPolicy, Scheme};
use prtkit::progress::NoProgress;
use std::path::{Path, PathBuf};

fn main() -> anyhow::Result<()> {
    run(&PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/examples".into())))
}

/// Writes `sphere.codes`, `sphere.normals.json`, `sphere-decoded.obj` and `table32.md` into `out`.
pub fn run(out: &Path) -> anyhow::Result<()> {
    std::fs::create_dir_all(out)?;
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/sphere.obj");
    let source = NormalSource::read(&input, false)?;
    let [codes, report, decoded] = ["sphere.codes", "sphere.normals.json", "sphere-decoded.obj"].map(|f| out.join(f));
    let name = |p: &Path| Some(p.display().to_string());
    let config = Config {
        scheme: Scheme::OnvRange,
        bits: 24,
        stream: Stream::Words,
        on_invalid: InvalidPolicy::Error,
        histogram_bins: 32,
        files: Files::new(&input, name(&codes), name(&decoded)),
        args: std::env::args().collect(),
    };
    let encoded = encode::run(&config, &source.normals, &NoProgress)?;
    prtkit::io::write_atomic(&codes, &encoded.stream)?;
    prtkit::io::write_atomic(&report, encoded.report.to_json().as_bytes())?;
    prtkit::io::write_atomic(&decoded, &source.write_back(&decoded, &encoded.decoded)?)?;
    println!("sphere.codes: {}", encoded.report.body.summary());

    let config = TableConfig { bits: 32, samples: 1 << 16, seed: 1 };
    let rows = table::run(&config, &NoProgress)?;
    prtkit::io::write_atomic(&out.join("table32.md"), table::markdown(&rows, &config).as_bytes())?;
    println!("table32.md: Meyer et al. 2010, Table 1 at 32 bits ({} schemes)", rows.len());
    Ok(())
}
