//! Benchmark of `sh-project` on a 2048×1024 lat-long map at F = 30: EXR decode time, separable
//! projection time, and the naive per-texel O(F²·S²) projection, measured in one run.
//!
//! `cargo bench --bench sh_project -- [--out FILE.md]` (scripts/bench-sh-project.sh)

use prtkit::envmap::EnvMap;
use prtkit::io::{exr, RgbImage};
use prtkit::progress::NoProgress;
use prtkit::sh::project::{project, project_naive};
use std::path::Path;

mod common;
use common::best_of;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = args.iter().position(|a| a == "--out").and_then(|i| args.get(i + 1)).cloned();
    let (w, h, order) = (2048usize, 1024usize, 30usize);
    // A sky-like map with detail at every scale (sun, horizon, texture), so the EXR compresses
    // like a real probe rather than like a constant.
    let image = RgbImage::from_fn(w, h, |x, y| {
        let d = prtkit::sphere::LatLong::new(w, h).texel_direction(x, y);
        let sun = d.dot(glam::DVec3::new(0.5, 0.3, 0.81).normalize()).max(0.0).powi(400) * 500.0;
        let sky = 0.5 + d.z.max(0.0);
        let texture = 0.1 * (((x * 2654435761usize) ^ (y * 40503)) % 1000) as f64 / 1000.0;
        let v = (sun + sky + texture) as f32;
        [v, v * 0.9, v * 0.75]
    });
    let bytes = exr::encode_layers(&[("", &image)]).expect("encode");
    let (decode_s, decoded) = best_of(5, || exr::decode(Path::new("bench.exr"), &bytes).expect("decode"));
    let map = EnvMap::latlong(decoded).expect("latlong");
    let (project_s, fast) = best_of(5, || project(&map, order, &NoProgress).expect("project"));
    let (naive_s, slow) = best_of(1, || project_naive(&map, order));
    let max_diff =
        fast.rgb.iter().flatten().zip(slow.rgb.iter().flatten()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    let threads = rayon::current_num_threads();
    let json = format!(
        "{{\"width\": {w}, \"height\": {h}, \"order\": {order}, \"threads\": {threads}, \"exr_bytes\": {}, \"decode_seconds\": {decode_s:.6}, \"project_seconds\": {project_s:.6}, \"naive_seconds\": {naive_s:.6}, \"decode_over_project\": {:.2}, \"naive_over_project\": {:.1}, \"max_coefficient_difference\": {max_diff:.3e}}}",
        bytes.len(),
        decode_s / project_s,
        naive_s / project_s
    );
    println!("{json}");
    if let Some(path) = out {
        let md = format!(
            "## sh-project: projection speed\n\n\
             `scripts/bench-sh-project.sh` (`cargo bench --bench sh_project`), one run, {threads} threads, \
             a {w}×{h} float RGB lat-long map (ZIP-compressed EXR, {:.1} MB), order F = {order}. \
             Times are the best of 5 runs (the naive projection: 1 run).\n\n\
             | step | seconds | ratio |\n| --- | --- | --- |\n\
             | EXR decode | {decode_s:.4} | — |\n\
             | separable projection (FFT over φ, then θ sums; R&H 2002 App. C) | {project_s:.4} | decode / projection = **{:.1}×** (target ≥ 4×) |\n\
             | naive per-texel projection, O(F²·S²) | {naive_s:.3} | naive / separable = **{:.0}×** (target ≥ 20×) |\n\n\
             The two projections agree to {max_diff:.1e} (largest coefficient difference).\n",
            bytes.len() as f64 / 1e6,
            decode_s / project_s,
            naive_s / project_s
        );
        std::fs::write(&path, md).expect("write results");
        eprintln!("wrote {path}");
    }
}
