//! The ring-free table of `docs/results/ring-free.md` (issue: "ring-free, non-negative
//! frequency-space bakes"): on every light probe given, resampled to 256×128, the default
//! `prefilter` reflection maps for Phong s ∈ {8, 32, 128, 512} and Torrance-Sparrow
//! σ ∈ {0.1, 0.2, 0.3} (views +Z and a grazing one) against the angular reference with
//! ε = 0.001 at the same size: negative texels, per-texel relative error (99th percentile and
//! maximum, texels ≥ 1 % of the mean), relative RMS, and the time of the default bake beside the
//! paper-order bake (energy rule, no bright split, no window) timed in the same run.
//!
//! `cargo run --release --example ring_free -- OUT.md CACHE_DIR PROBE...` (a probe is a map
//! file or a cube-face directory; `scripts/ring-free-table.sh` runs it on the shared probes and
//! the demo sky). References are cached in CACHE_DIR: they take most of the time.

mod common;

use anyhow::{bail, Context};
use common::{bake, grazing, probe_map, probe_name, reference, reference_file, LOOSE};
use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::envmap::bright::BrightRule;
use prtkit::metrics::{compare, Metrics};
use prtkit::prefilter::orders::OrderRule;
use prtkit::prefilter::stage::Config;
use prtkit::sh::window::Window;
use std::fmt::Write as _;
use std::path::Path;

/// The tight reference's ε: the ε = 0.001 leaves 0.1 % of each lobe out, which under a
/// sun 10⁴ times the ground is itself a visible error in the ground's texels.
const TIGHT: f64 = 1e-5;

/// Timed runs of each bake; the table reports the fastest. A millisecond bake on a shared
/// two-core machine varies by ±30 % from run to run (wake-ups, page faults): with 7 runs the
/// same code's Phong ratios moved by up to 0.5 between two tables.
const TIMED_RUNS: usize = 15;

/// The acceptance figures of the table.
const MAX_P99: f64 = 0.05;
const MAX_REL_RMS: f64 = 0.02;

const BRDFS: [&str; 7] = [
    "phong:s=8",
    "phong:s=32",
    "phong:s=128",
    "phong:s=512",
    "torrance-sparrow:sigma=0.1",
    "torrance-sparrow:sigma=0.2",
    "torrance-sparrow:sigma=0.3",
];

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [out, cache, probes @ ..] = args.as_slice() else {
        bail!("usage: ring_free OUT.md CACHE_DIR PROBE...");
    };
    std::fs::create_dir_all(cache)?;
    let grazing = grazing();
    let mut table = String::new();
    let (mut worst_p99, mut worst_rms, mut negatives, mut worst_ratio) = (0.0f64, 0.0f64, 0usize, 0.0f64);
    let mut worst_tight = 0.0f64;
    // The ε = 0.001 reference against the tight one: how honest the reference itself is.
    let (mut reference_p99, mut reference_max) = (0.0f64, 0.0f64);
    for probe in probes {
        let map = probe_map(Path::new(probe))?;
        let name = probe_name(probe);
        for spec in BRDFS {
            let brdf = Brdf::parse(spec)?;
            let views: &[(&str, DVec3)] = if spec.starts_with("phong") {
                &[("any", DVec3::Z)]
            } else {
                &[("+Z", DVec3::Z), ("grazing", grazing)]
            };
            for &(view_name, view) in views {
                let file = |suffix: &str| reference_file(cache, &name, spec, view_name, suffix);
                let loose = reference(&map, &brdf, view, 0.001, BrightRule::Auto, &file(LOOSE))?;
                let tight = reference(&map, &brdf, view, TIGHT, BrightRule::Off, &file("-tight"))?;
                // The fastest of a few alternating runs of each: a single run's time includes
                // one-off costs (first use of the thread pool and of cached quadratures) that
                // fall on whichever bake happens to run first.
                let (mut default, mut default_s) = bake(&map, &brdf, view, defaults)?;
                let mut paper_s = f64::INFINITY;
                for _ in 0..TIMED_RUNS {
                    paper_s = paper_s.min(bake(&map, &brdf, view, paper)?.1);
                    default_s = default_s.min(bake(&map, &brdf, view, defaults)?.1);
                }
                let (f_b, p_b) = (default.summary.f_b, default.summary.p_b);
                let default = default.maps.remove(0);
                let (m, _) = compare(&default, &loose, &[])?;
                let (t, _) = compare(&default, &tight, &[])?;
                let (r, _) = compare(&loose, &tight, &[])?;
                reference_p99 = reference_p99.max(r.p99_texel_error);
                reference_max = reference_max.max(r.max_texel_error);
                let ratio = default_s / paper_s;
                worst_p99 = worst_p99.max(m.p99_texel_error);
                worst_tight = worst_tight.max(t.p99_texel_error);
                worst_rms = worst_rms.max(m.rel_error);
                negatives += usize::from(m.negative_fraction > 0.0);
                worst_ratio = worst_ratio.max(ratio);
                let row = row(&name, spec, view_name, f_b, p_b, &m, &t, default_s, paper_s);
                eprintln!("{row}");
                writeln!(table, "{row}")?;
            }
        }
    }
    let verdict = |ok: bool| if ok { "met" } else { "NOT met" };
    let mut doc = String::new();
    writeln!(doc, "# Ring-free reflection maps on real lighting\n")?;
    writeln!(
        doc,
        "Written by `scripts/ring-free-table.sh` (`examples/ring_free.rs`). Each probe resampled to a \
         256×128 lat-long map; the default `prefilter` (texel order rule, bright sources apart, \
         `nonneg` window) against the angular reference (`--method angular --epsilon 0.001`: the map summed in \
         luminance parts, each with its own cone, docs/prefilter.md \"The angular reference\") at \
         the same size, and against a tight reference (App. D as written at ε = 10⁻⁵, `--bright \
         off`: an independent check of the first; how far the two references are apart is in the \
         last line). Per-texel errors over texels ≥ 1 % of the mean (`src/metrics.rs`). Times are \
         wall-clock seconds of the library call, the fastest of {TIMED_RUNS} alternating runs of each in one \
         process, each in the worker pool as the CLI runs its stage, the paper-order bake \
         (`--order-rule energy --bright off --window none`) beside the default. The default \
         integrates the maps of a view-dependent BRDF, and of a radially symmetric lobe narrower \
         than 8 texels (Phong s = 512), in angle, with no orders (F_B reads `angle`; \
         docs/prefilter.md, \"Maps in angle\").\n"
    )?;
    writeln!(
        doc,
        "| probe | BRDF | view | F_B | P_B | negative texels | p99 per-texel | max per-texel (texel) | rel. RMS | p99 vs ε = 1e-5 | max vs ε = 1e-5 | default (s) | paper order (s) | ratio |"
    )?;
    writeln!(doc, "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")?;
    doc.push_str(&table);
    writeln!(
        doc,
        "\nWorst p99 {:.2} % (target ≤ {:.0} %: {}; against the tight reference {:.2} %: {}), worst rel. RMS {:.2} % (≤ {:.0} %: {}), maps with a \
         negative texel: {negatives} (none: {}), largest cost ratio {worst_ratio:.1}× (≤ 3×: {}). The ε = 0.001 \
         reference against the ε = 10⁻⁵ one: worst p99 {:.2} %, worst max {:.2} %.",
        100.0 * worst_p99,
        100.0 * MAX_P99,
        verdict(worst_p99 <= MAX_P99),
        100.0 * worst_tight,
        verdict(worst_tight <= MAX_P99),
        100.0 * worst_rms,
        100.0 * MAX_REL_RMS,
        verdict(worst_rms <= MAX_REL_RMS),
        verdict(negatives == 0),
        verdict(worst_ratio <= 3.0),
        100.0 * reference_p99,
        100.0 * reference_max
    )?;
    std::fs::write(out, doc).with_context(|| format!("cannot write {out}"))?;
    Ok(())
}

#[allow(clippy::too_many_arguments)]
fn row(
    probe: &str,
    spec: &str,
    view: &str,
    f_b: usize,
    p_b: usize,
    m: &Metrics,
    t: &Metrics,
    default_s: f64,
    paper_s: f64,
) -> String {
    // No orders: the maps were integrated in angle (docs/prefilter.md, "Maps in angle").
    let (f_b, p_b) =
        if f_b == 0 { ("angle".to_string(), "–".to_string()) } else { (f_b.to_string(), p_b.to_string()) };
    format!(
        "| {probe} | `{spec}` | {view} | {f_b} | {p_b} | {:.2} % | {:.2} % | {:.2} % ({}, {}) | {:.2} % | {:.2} % | {:.2} % | {default_s:.4} | {paper_s:.4} | {:.1}× |",
        100.0 * m.negative_fraction,
        100.0 * m.p99_texel_error,
        100.0 * m.max_texel_error,
        m.worst_texel[0],
        m.worst_texel[1],
        100.0 * m.rel_error,
        100.0 * t.p99_texel_error,
        100.0 * t.max_texel_error,
        default_s / paper_s
    )
}

fn defaults(config: Config) -> Config {
    config
}

fn paper(config: Config) -> Config {
    Config { order_rule: OrderRule::Energy, bright: BrightRule::Off, window: Window::None, ..config }
}
