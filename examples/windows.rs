//! Each window's error (`--window`), written to `docs/results/windows.md`:
//!
//! - `sh-project --order 30 --reconstruct` on every probe given, resampled to 256×128,
//!   against the map itself: negative texels, the guard's heat parameter t, relative RMS and the
//!   99th-percentile per-texel error; on the demo sky, also how far the ground's row means
//!   stray from the map's (the ripples a 10:1 horizon leaves across the ground);
//! - the default `prefilter` reflection map with each window for Phong s = 32 and
//!   Torrance-Sparrow σ = 0.2 (view +Z), against the angular reference at ε = 0.001.
//!
//! `cargo run --release --example windows -- OUT.md CACHE_DIR PROBE...`
//! (`scripts/windows-table.sh`). The references are those of `examples/ring_free.rs`, read from
//! CACHE_DIR when that example has written them, else computed and cached.

mod common;

use anyhow::{bail, Context};
use common::{bake, probe_map, probe_name, reference, reference_file, LOOSE, SIZE};
use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::envmap::bright::BrightRule;
use prtkit::envmap::EnvMap;
use prtkit::io::RgbImage;
use prtkit::metrics::{compare, Metrics};
use prtkit::prefilter::stage::Config;
use prtkit::progress::NoProgress;
use prtkit::sh::project::OrderChoice;
use prtkit::sh::stage as sh_stage;
use prtkit::sh::window::Window;
use std::fmt::Write as _;
use std::path::Path;

const WINDOWS: [Window; 5] = [Window::None, Window::Nonneg, Window::Hann, Window::Lanczos, Window::Sigma];

/// The BRDFs of the prefilter table, both at view +Z ("+Z" in the reference cache's names).
const BRDFS: [&str; 2] = ["phong:s=32", "torrance-sparrow:sigma=0.2"];

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [out, cache, probes @ ..] = args.as_slice() else {
        bail!("usage: windows OUT.md CACHE_DIR PROBE...");
    };
    std::fs::create_dir_all(cache)?;
    let (mut reconstructions, mut ground, mut bakes) = (String::new(), String::new(), String::new());
    for probe in probes {
        let map = probe_map(Path::new(probe))?;
        let name = probe_name(probe);
        for window in WINDOWS {
            let (image, order, t) = reconstruction(&map, window)?;
            let (m, _) = compare(&image, map.image(), &[])?;
            let row = format!(
                "| {name} | `{}` | {order} | {:.2} % | {} | {:.2} % | {:.2} % |",
                window.name(),
                100.0 * m.negative_fraction,
                guard(t),
                100.0 * m.rel_error,
                100.0 * m.p99_texel_error
            );
            eprintln!("{row}");
            writeln!(reconstructions, "{row}")?;
            if name == "sky" {
                let (lo, hi) = ground_rows(&image, map.image());
                writeln!(ground, "| `{}` | {lo:.3} | {hi:.3} |", window.name())?;
            }
        }
        for spec in BRDFS {
            let brdf = Brdf::parse(spec)?;
            let reference_map = reference(
                &map,
                &brdf,
                DVec3::Z,
                0.001,
                BrightRule::Auto,
                &reference_file(cache, &name, spec, "+Z", LOOSE),
            )?;
            for window in WINDOWS {
                // A view-dependent BRDF's maps go through the SHRM, where the window acts, only
                // when --bound asks about the expansion (else they are integrated in angle).
                let (mut out, _) = bake(&map, &brdf, DVec3::Z, |c| Config { window, bound: true, ..c })?;
                let t = out.document.body.bake.as_ref().and_then(|b| b.window.t);
                let (image, f_b) = (out.maps.remove(0), out.summary.f_b);
                let (m, _) = compare(&image, &reference_map, &[])?;
                let row = bake_row(&name, spec, window, f_b, t, &m);
                eprintln!("{row}");
                writeln!(bakes, "{row}")?;
            }
        }
    }
    let mut doc = String::new();
    writeln!(doc, "# Windows at synthesis\n")?;
    writeln!(
        doc,
        "Written by `scripts/windows-table.sh` (`examples/windows.rs`). Each probe resampled to a 256×128 \
         lat-long map. Every window but `none` ends with the non-negativity guard (the gentlest \
         exp(−t·l(l+1)) on top of it that leaves no negative texel; `nonneg` is the guard alone): t is \
         in its column, `–` for `none`. Per-texel errors over texels ≥ 1 % of the mean \
         (`src/metrics.rs`).\n"
    )?;
    writeln!(doc, "## `sh-project --order 30 --reconstruct`, against the map\n")?;
    writeln!(
        doc,
        "The reconstruction is the order-F expansion of the map with its bright sources clipped, \
         windowed, plus their excess put back texel by texel (docs/sh-project.md); its error \
         against the map is mostly the blur of a finite order, which a window adds to.\n"
    )?;
    writeln!(doc, "| probe | window | F | negative texels | guard t | rel. RMS | p99 per-texel |")?;
    writeln!(doc, "| --- | --- | ---: | ---: | ---: | ---: | ---: |")?;
    doc.push_str(&reconstructions);
    if !ground.is_empty() {
        writeln!(
            doc,
            "\nThe demo sky's ground (rows 9/16 H to H − 1, below the horizon's own transition): the \
             smallest and largest ratio of a row's mean in the reconstruction to the map's. A 10:1 \
             horizon rings through the ground; the ratios are those ripples.\n"
        )?;
        writeln!(doc, "| window | lowest row ratio | highest row ratio |")?;
        writeln!(doc, "| --- | ---: | ---: |")?;
        doc.push_str(&ground);
    }
    writeln!(doc, "\n## `prefilter` reflection maps (view +Z), against the angular reference at ε = 0.001\n")?;
    writeln!(
        doc,
        "The default bake (texel order rule, bright sources apart) with each window; the BRDF's \
         kernel damps the lighting's top bands already, so windows matter less here than in a \
         reconstruction.\n"
    )?;
    writeln!(
        doc,
        "| probe | BRDF | window | F_B | negative texels | guard t | p99 per-texel | max per-texel | rel. RMS |"
    )?;
    writeln!(doc, "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")?;
    doc.push_str(&bakes);
    std::fs::write(out, doc).with_context(|| format!("cannot write {out}"))?;
    Ok(())
}

fn guard(t: Option<f64>) -> String {
    match t {
        None => "–".into(),
        Some(0.0) => "0".into(),
        Some(t) => format!("{t:.2e}"),
    }
}

fn bake_row(probe: &str, spec: &str, window: Window, f_b: usize, t: Option<f64>, m: &Metrics) -> String {
    format!(
        "| {probe} | `{spec}` | `{}` | {f_b} | {:.2} % | {} | {:.2} % | {:.2} % | {:.2} % |",
        window.name(),
        100.0 * m.negative_fraction,
        guard(t),
        100.0 * m.p99_texel_error,
        100.0 * m.max_texel_error,
        100.0 * m.rel_error
    )
}

/// The order of the reconstructions: what a display of the lighting uses (the demo sky's ε = 1 %
/// gives 27; on the probes ε = 1 % asks for orders near the 256×128 map's limit).
const ORDER: usize = 30;

/// `sh-project --order 30 --window W --reconstruct` at the map's size: (image, F, t).
fn reconstruction(map: &EnvMap, window: Window) -> anyhow::Result<(RgbImage, usize, Option<f64>)> {
    let config = sh_stage::Config {
        order: OrderChoice::Order(ORDER),
        reconstruction: true,
        size: Some(SIZE),
        window,
        ..sh_stage::Config::default()
    };
    let out = sh_stage::run(&config, map, &NoProgress)?;
    let synthesis = out.document.body.synthesis.context("no synthesis recorded")?;
    Ok((out.reconstruction.context("no reconstruction")?, out.document.body.order, synthesis.reconstruction_t))
}

/// The lowest and highest ratio of a ground row's mean (rows 9H/16 to H − 1) in `image` to the
/// same row's mean in `map`.
fn ground_rows(image: &RgbImage, map: &RgbImage) -> (f64, f64) {
    let (w, h) = (image.width, image.height);
    let row_mean = |img: &RgbImage, y: usize| -> f64 {
        img.pixels[y * w..(y + 1) * w].iter().map(|p| p.iter().map(|&v| v as f64).sum::<f64>()).sum::<f64>()
    };
    (9 * h / 16..h)
        .map(|y| row_mean(image, y) / row_mean(map, y))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| (lo.min(r), hi.max(r)))
}
