//! The `render --shading ibl --grid` numbers: on shared lat-long probes resampled to 256×128,
//! the default `ibl` bake read back from its files, every grid cell's error against the exact
//! split sum ("bake") and against the rendering equation ("ref"). Writes Markdown
//! (scripts/ibl-grid.sh writes it into docs/results/).
//!
//! `cargo run --release --example ibl_grid -- OUT.md`

mod common;

use prtkit::envmap::{resample, Layout, LoadOptions};
use prtkit::ibl::manifest;
use prtkit::ibl::stage::{self, Config};
use prtkit::progress::NoProgress;
use prtkit::render::grid::{render_grid, MaterialGrid, DEFAULT_METALNESS, DEFAULT_ROUGHNESS};
use prtkit::render::ibl::IblBake;
use prtkit::render::{Camera, Scene};
use std::fmt::Write;

/// The base colour of every cell (gold-like, as in docs/ibl.md).
const BASE: [f64; 3] = [1.0, 0.78, 0.34];

fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| "docs/results/ibl-grid.md".into());
    let Some((dir, _)) = common::shared_probes() else {
        return;
    };
    let mut md = String::from(
        "## `render --shading ibl`: the bake read back, against its own integrals and the rendering equation\n\n\
         `scripts/ibl-grid.sh` (`examples/ibl_grid.rs`): each probe resampled to a 256×128 lat-long map, baked \
         by `ibl` at its defaults (256² to 8², r = 0, 0.2, …, 1), the KTX2 files read back and a unit sphere \
         shaded with the split sum (`render --shading ibl --grid`, 48² cells, base colour 1/0.78/0.34, camera \
         at (0, −4, 0)). **bake**: rel. L² error over the sphere against the same split sum of the exact \
         integrals (the bake's own error); **ref**: against the glTF material integrated over every texel \
         (the bake's error and the split sum's). See docs/ibl.md, \"Seeing it\".\n\n\
         | probe | r | m = 0: bake | m = 0: ref | m = 1: bake | m = 1: ref |\n\
         | --- | ---: | ---: | ---: | ---: | ---: |\n",
    );
    let grid = MaterialGrid { roughness: DEFAULT_ROUGHNESS.to_vec(), metalness: DEFAULT_METALNESS.to_vec() };
    let camera = Camera::look_at([0.0, -4.0, 0.0].into(), glam::DVec3::ZERO, 32.0, 48, 48).expect("a valid camera");
    for name in ["grace_latlong.exr", "uffizi_ict_latlong_256x128.hdr"] {
        let loaded = LoadOptions::default().load(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let env = resample(&loaded.map, Layout::LatLong, 256, 128, 2).expect("resampling");
        let baked = stage::run(&Config::default(), &env, &NoProgress).expect("the bake");
        let tmp = tempfile::tempdir().expect("a temporary directory");
        // What the bake is read back from: its textures and its manifest.
        for (file, texture, format) in baked.textures() {
            let bytes = baked.container.encode(&texture, format).expect("encoding the bake");
            std::fs::write(tmp.path().join(file), bytes).expect("writing the bake");
        }
        let manifest = tmp.path().join(manifest::FILE);
        std::fs::write(&manifest, baked.document.to_json()).expect("writing the bake");
        let bake = IblBake::load(&manifest).expect("reading the bake back");
        let cells =
            render_grid(&grid, BASE, &bake, &env, &Scene::unit_sphere(), &camera, &NoProgress).expect("the grid").cells;
        let n = grid.roughness.len();
        for (dielectric, metal) in cells[..n].iter().zip(&cells[n..]) {
            let pct = |x: f64| format!("{:.2} %", 100.0 * x);
            writeln!(
                md,
                "| {name} | {} | {} | {} | {} | {} |",
                dielectric.roughness,
                pct(dielectric.bake.rel_error),
                pct(dielectric.reference.rel_error),
                pct(metal.bake.rel_error),
                pct(metal.reference.rel_error)
            )
            .expect("writing to a string");
        }
        eprintln!("{name}: done");
    }
    std::fs::write(&out, md).unwrap_or_else(|e| panic!("{out}: {e}"));
}
