//! Speed and accuracy of the `ibl` building blocks, measured in one run:
//! the split-sum DFG table (time, quadrature convergence) and the angular GGX prefilter of a
//! 256² cube (time per level, source level, cone, error against the exact reference).
//!
//! `cargo bench --bench ibl_blocks [-- --quick]` prints one JSON line per measurement on stdout.
//! The input is `../shared/testdata/envmaps/grace_latlong.exr` resampled to a 256² cube in glTF's
//! frame; without the shared test data, a procedural sky with a sun.

use glam::DVec3;
use prtkit::envmap::EnvMap;
use prtkit::ibl::angular::{AngularOptions, AngularPrefilter};
use prtkit::ibl::cube::{CubeMap, CubeMipChain, PRTKIT_FROM_WORLD};
use prtkit::ibl::dfg::{DfgTable, DfgVariant};
use prtkit::io::image::read_image;
use prtkit::progress::NoProgress;
use std::path::PathBuf;

mod common;
use common::best_of;

fn input(size: usize) -> (CubeMap, &'static str) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/testdata/envmaps/grace_latlong.exr");
    if let Ok(img) = read_image(&path) {
        let env = EnvMap::latlong(img).expect("lat-long");
        return (CubeMap::resample(&env, size, 2, PRTKIT_FROM_WORLD).expect("cube"), "grace_latlong.exr");
    }
    eprintln!("../shared/testdata is absent: using a procedural sky");
    let sun = DVec3::new(0.3, 0.8, -0.5).normalize();
    let cube = CubeMap::from_fn(size, |d| {
        let v = (if d.y > 0.0 { 1.0 } else { 0.3 }) + 200.0 * d.dot(sun).max(0.0).powi(400);
        [v as f32, (0.9 * v) as f32, (0.8 * v) as f32]
    })
    .expect("cube");
    (cube, "procedural sky")
}

fn dfg() {
    for variant in [DfgVariant::ScaleBias, DfgVariant::MultiScatter] {
        let (secs, _) = best_of(3, || DfgTable::new(128, variant).expect("table"));
        println!("{{\"bench\": \"dfg_table\", \"size\": 128, \"variant\": \"{variant:?}\", \"seconds\": {secs:.4}}}");
    }
    let a = DfgTable::with_quadrature_order(128, DfgVariant::ScaleBias, 16).expect("table");
    let b = DfgTable::with_quadrature_order(128, DfgVariant::ScaleBias, 24).expect("table");
    let c = DfgTable::with_quadrature_order(128, DfgVariant::ScaleBias, 48).expect("table");
    let d = DfgTable::with_quadrature_order(128, DfgVariant::ScaleBias, 8).expect("table");
    let worst = |x: &DfgTable, y: &DfgTable| {
        x.values()
            .iter()
            .zip(y.values())
            .map(|(p, q)| (p[0] - q[0]).abs().max((p[1] - q[1]).abs()))
            .fold(0.0f32, f32::max)
    };
    println!(
        "{{\"bench\": \"dfg_convergence\", \"size\": 128, \"max_diff_8_vs_48\": {:.3e}, \"max_diff_16_vs_48\": {:.3e}, \"max_diff_24_vs_48\": {:.3e}}}",
        worst(&d, &c),
        worst(&a, &c),
        worst(&b, &c)
    );
}

/// One configuration: (label, ε, texel ratio, levels as (face size, roughness)).
type Run = (&'static str, f64, f64, Vec<(usize, f64)>);

/// Every level with the fast options, and the levels whose cost stays in seconds with the default
/// and the accurate ones.
fn runs(quick: bool) -> Vec<Run> {
    let all = vec![(256, 0.1), (128, 0.2), (64, 0.4), (32, 0.6), (16, 0.8), (8, 1.0)];
    if quick {
        return vec![("default", 1e-4, 1.0 / 64.0, vec![(32, 0.6), (8, 1.0)])];
    }
    vec![
        ("fast", 1e-2, 1.0 / 16.0, all),
        ("default", 1e-4, 1.0 / 64.0, vec![(128, 0.2), (64, 0.4), (32, 0.6), (16, 0.8), (8, 1.0)]),
        ("accurate", 1e-4, 1.0 / 256.0, vec![(64, 0.4), (32, 0.6), (16, 0.8), (8, 1.0)]),
    ]
}

fn angular(quick: bool) {
    let (base, name) = input(256);
    let pre = AngularPrefilter::new(CubeMipChain::pyramid(base, 1).expect("pyramid")).expect("prefilter");
    let samples = if quick { 32 } else { 128 };
    for (label, epsilon, ratio, levels) in runs(quick) {
        let options = AngularOptions { epsilon, texel_ratio: ratio };
        for (size, r) in levels {
            let (secs, (out, source)) = best_of(1, || pre.prefilter(size, r, &options, &NoProgress).expect("level"));
            let err = pre.measure(&out, r, samples, 1).expect("measure");
            println!(
                "{{\"bench\": \"angular\", \"options\": \"{label}\", \"input\": \"{name}\", \"size\": {size}, \"roughness\": {r}, \"epsilon\": {epsilon}, \"texel_ratio\": {ratio}, \"seconds\": {secs:.4}, \"source_size\": {}, \"cone_deg\": {:.3}, \"samples\": {}, \"counted\": {}, \"max_rel_error\": {:.5}, \"rms_rel_error\": {:.5}}}",
                source.source_size,
                source.cone_angle.to_degrees(),
                err.samples,
                err.counted,
                err.max_rel_error,
                err.rms_rel_error
            );
        }
    }
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    dfg();
    angular(quick);
}
