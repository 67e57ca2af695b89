//! Decode time of EXR files as prtkit's stages read them (`io::exr::decode`: headers checked
//! against the ceilings, then the `exr` crate's parallel decompression), best of five, one line
//! per file: `FILE BYTES WIDTH HEIGHT SECONDS`.
//!
//! `cargo bench --bench exr_decode -- FILE.exr…` (scripts/ibl-scaling.sh times OpenEXR's own
//! decoder beside it)

use prtkit::io::exr;
use std::path::Path;

mod common;
use common::best_of;

fn main() {
    for arg in std::env::args().skip(1).filter(|a| a.ends_with(".exr")) {
        let path = Path::new(&arg);
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{arg}: {e}"));
        let (seconds, image) = best_of(5, || exr::decode(path, &bytes).unwrap_or_else(|e| panic!("{e}")));
        println!("{arg} {} {} {} {seconds:.4}", bytes.len(), image.width, image.height);
    }
}
