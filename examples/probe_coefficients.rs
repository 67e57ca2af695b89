//! Lists the order-2 SH coefficients of every light probe in `../shared/testdata/envmaps` in its
//! native layout, as a Markdown section (scripts/probe-coefficients.sh writes it into docs/).
//!
//! `cargo run --release --example probe_coefficients -- OUT.md`

mod common;

use prtkit::envmap::{EnvMap, LoadOptions};
use prtkit::progress::NoProgress;
use prtkit::sh::project::project;
use std::fmt::Write;

fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| "docs/results/probes.md".into());
    let Some((dir, names)) = common::shared_probes() else {
        return;
    };
    // Read as every stage reads an environment map: the layout from the aspect ratio (a
    // directory is six faces), NaN, infinite and negative radiance refused.
    let mut inputs: Vec<(String, EnvMap)> = Vec::new();
    for name in names {
        match LoadOptions::default().load(&dir.join(&name)) {
            Ok(loaded) => inputs.push((name, loaded.map)),
            Err(e) => {
                eprintln!("error: {e}");
                std::process::exit(2);
            }
        }
    }
    let labels = ["L00", "L1-1", "L10", "L11", "L2-2", "L2-1", "L20", "L21", "L22"];
    let mut md = String::from(
        "## Order-2 SH coefficients of the shared light probes\n\n\
         `scripts/probe-coefficients.sh`: `sh-project --order 2` on each file of `../shared/testdata/envmaps` \
         in its native layout (prtkit's frame: +Z up; SH convention of `docs/conventions.md`). Values are \
         R, G, B. Absolute scales differ between files (SOURCES.md there); `grace_latlong.exr` is stored \
         floor-up by pbrt, so its odd-in-z coefficients (L10, L2-1, L21) have the opposite sign of the \
         probe's.\n\n",
    );
    for (name, map) in &inputs {
        let sh = project(map, 2, &NoProgress).expect("projection");
        let img = map.image();
        let _ = writeln!(md, "### `{name}` ({}, {}×{})\n", map.layout(), img.width, img.height);
        let _ = writeln!(md, "| coefficient | R | G | B |\n| --- | ---: | ---: | ---: |");
        for (label, c) in labels.iter().zip(&sh.rgb) {
            let _ = writeln!(md, "| {label} | {:.5} | {:.5} | {:.5} |", c[0], c[1], c[2]);
        }
        md.push('\n');
    }
    std::fs::write(&out, md).expect("write");
    eprintln!("wrote {out}");
}
