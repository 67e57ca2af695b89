//! The `render` stage through the library: a sphere under the sky, shaded by direct integration
//! (the reference), then relit with the 75 in-out terms of the `factor_brdf` example and compared
//! with it, side by side in a labelled panel. The README's two commands, at 64 × 64 pixels with
//! a 32 × 16 table of normals (the default 128 × 64 table takes half a minute at K = 75):
//!
//! ```sh
//! render out/examples/sky.exr --brdf phong:s=30 --res 64x64 -o out/examples/ref.exr
//! render out/examples/sky.exr --brdf phong:s=30 --res 64x64 --shading factored \
//!     --factors out/examples/p30.json -K 75 --normal-table 32x16 --compare out/examples/ref.exr \
//!     --panel out/examples/k75.png --panel-item "reference=out/examples/ref.exr"
//! ```
//!
//! `cargo run --release --example render [OUT_DIR]` (default `out/examples`; run the
//! `sample_shader` and `factor_brdf` examples first).

use anyhow::Context;
use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::envmap::LoadOptions;
use prtkit::progress::NoProgress;
use prtkit::render::reference::Integrand;
use prtkit::render::stage::{self, Config, PanelItem, Shading, StoredFactors};
use prtkit::render::{Camera, Scene};
use std::path::{Path, PathBuf};

fn main() -> anyhow::Result<()> {
    run(&PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/examples".into())))
}

/// Reads `sky.exr` and `p30.json` from `out`; writes `ref.exr` and `k75.png` there.
pub fn run(out: &Path) -> anyhow::Result<()> {
    let sky = LoadOptions::default().load(&out.join("sky.exr")).context("run the sample_shader example first")?.map;
    let sphere = Scene::unit_sphere();
    // The command line's default camera: 4 units along −Y, looking at the origin, 32° field.
    let camera = Camera::look_at(DVec3::new(0.0, -4.0, 0.0), DVec3::ZERO, 32.0, 64, 64)?;
    let reference_file = out.join("ref.exr");
    let mut config = Config {
        brdf: Brdf::parse("phong:s=30")?,
        shading: Shading::Reference { integrand: Integrand::BrdfCosine },
        camera,
        env_rotation: 0.0,
        compare: None,
        panel: None,
        label: None,
        exposure: 0.0,
        output_name: Some(reference_file.display().to_string()),
        args: std::env::args().collect(),
    };
    let reference = stage::run(&config, &sky, &sphere, &NoProgress)?.frame.image;
    prtkit::io::image::write_image(&reference_file, &reference, 0.0)?;

    let document = out.join("p30.json");
    let (body, factorization) =
        prtkit::factor::document::load(&document).context("run the factor_brdf example first")?;
    let factors =
        StoredFactors { name: document.display().to_string(), factorization, cosine: body.cosine, brdf: body.brdf };
    config.shading = Shading::Factored {
        terms: 75,
        factors: Some(Box::new(factors)),
        resolution: None,
        cell_samples: 2,
        normal_table: (32, 16),
        bright: prtkit::envmap::bright::BrightRule::Auto,
    };
    config.compare = Some((reference_file.display().to_string(), reference.clone()));
    config.panel = Some(vec![PanelItem { label: "reference".into(), image: Some(reference) }]);
    config.output_name = None;
    let relit = stage::run(&config, &sky, &sphere, &NoProgress)?;
    let panel = relit.panel.as_ref().context("asked for a panel")?;
    prtkit::io::image::write_image(&out.join("k75.png"), panel, 0.0)?;
    if let Some((metrics, _)) = &relit.comparison {
        println!("k75.png: K = 75 against the reference: {}", metrics.body.metrics);
    }
    Ok(())
}
