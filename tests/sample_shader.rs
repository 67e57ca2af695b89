//! Integration tests of the `sample-shader` binary (and its `prtkit sample-shader` form). The
//! statistics are read into the library's own types (`shader::stage::Stats`, `CompareRow`).

mod common;

use common::cmd;
use predicates::prelude::*;
use prtkit::shader::stage::{CompareRow, Stats, STATS_FORMAT, STATS_VERSION};
use std::path::{Path, PathBuf};

fn shader(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/shaders").join(format!("{name}.sl"))
}

fn bin() -> assert_cmd::Command {
    cmd("sample-shader")
}

#[test]
fn texture_exr_has_width_and_depth_layers_matching_the_stats() {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let out = dir.path().join("wood.exr");
    let stats = dir.path().join("wood.json");
    bin()
        .arg(shader("wood"))
        .args(["--res", "64x64", "--tolerance", "0.05", "-q", "-o"])
        .arg(&out)
        .arg("--stats")
        .arg(&stats)
        .assert()
        .success();
    let bytes = std::fs::read(&out).unwrap_or_default();
    let layers = prtkit::io::exr::decode_layers(&out, &bytes).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
    for want in ["", "width", "depth"] {
        assert!(names.contains(&want), "layers {names:?}");
    }
    let text = std::fs::read_to_string(&stats).unwrap_or_default();
    let doc = prtkit::io::document::parse_document::<Stats>(&text, STATS_FORMAT, STATS_VERSION)
        .unwrap_or_else(|e| panic!("{e}"))
        .body;
    assert_eq!(doc.arith, "affine");
    assert_eq!(doc.resolution, [64, 64]);
    assert_eq!(doc.seconds, None, "timings stay out of documents");
    let width = &layers.iter().find(|(n, _)| n == "width").map(|l| l.1.clone()).unwrap_or_else(|| panic!("no width"));
    let depth = &layers.iter().find(|(n, _)| n == "depth").map(|l| l.1.clone()).unwrap_or_else(|| panic!("no depth"));
    let max_width = width.pixels.iter().map(|p| p[0].max(p[1]).max(p[2])).fold(0.0f32, f32::max) as f64;
    let stats_max = doc.width.max;
    assert!((max_width - stats_max).abs() <= 1e-6 * stats_max.max(1.0), "{max_width} vs {stats_max}");
    // Leaves stop at the tolerance or at the default depth log2(64) = 6.
    let max_depth = depth.pixels.iter().map(|p| p[0]).fold(0.0f32, f32::max);
    assert!(max_depth <= 6.0);
    for (p, d) in width.pixels.iter().zip(&depth.pixels) {
        let w = p[0].max(p[1]).max(p[2]) as f64;
        assert!(w <= 0.05 + 1e-6 || d[0] == 6.0, "a leaf above tolerance before max depth: {w} at depth {}", d[0]);
    }
    // Histogram counts every pixel once.
    let counts: u64 = doc.error_histogram.counts.iter().sum();
    assert_eq!(counts + doc.error_histogram.overflow, 64 * 64);
    // And every leaf once, by depth.
    assert_eq!(doc.depth_histogram.iter().sum::<u64>(), doc.leaves as u64);
}

#[test]
fn compare_json_rows_show_affine_tighter_than_interval() {
    let out = bin()
        .arg(shader("wood"))
        .args(["--res", "64x64", "--max-depth", "6", "--tolerance", "0", "--compare", "--json", "-q"])
        .output()
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(out.status.success());
    let rows: Vec<CompareRow> = serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}"));
    let arith: Vec<&str> = rows.iter().map(|r| r.arith.as_str()).collect();
    assert_eq!(arith, ["affine", "interval", "point"]);
    for r in &rows {
        assert!(r.seconds > 0.0 && r.max_width >= r.p95_width && r.p95_width >= r.median_width, "{r:?}");
    }
    // Equal depth (tolerance 0): same node count; affine bounds much tighter than interval.
    assert_eq!(rows[0].nodes, rows[1].nodes);
    let (a, i) = (rows[0].median_width, rows[1].median_width);
    assert!(a < 0.5 * i, "affine {a} vs interval {i}");
    // Point sampling at 8 samples per node spends 8 evaluations per node.
    assert_eq!(rows[2].evaluations, 8 * rows[2].nodes as u64);
    assert!(rows[0].guaranteed && rows[1].guaranteed && !rows[2].guaranteed);
}

#[test]
fn syntax_and_type_errors_name_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let bad = dir.path().join("bad.sl");
    std::fs::write(&bad, "shader s(float k = 1) {\n    color c = P;\n    Ci = c;\n}\n")
        .unwrap_or_else(|e| panic!("{e}"));
    let out = dir.path().join("never.exr");
    bin()
        .arg(&bad)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("bad.sl:2:15: initial value of 'c': expected color, found point"));
    assert!(!out.exists(), "no output after an error");
    std::fs::write(&bad, "shader s() {\n    Ci = (u + ;\n}\n").unwrap_or_else(|e| panic!("{e}"));
    bin().arg(&bad).assert().code(2).stderr(predicate::str::contains("bad.sl:2:15: expected an expression"));
}

#[test]
fn unknown_parameter_is_an_error_and_overrides_change_the_result() {
    bin()
        .arg(shader("wood"))
        .args(["-p", "rings=3", "--res", "8x8"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("unknown parameter 'rings'").and(predicate::str::contains("ringscale")));
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (dir.path().join("a.pfm"), dir.path().join("b.pfm"));
    for (path, p) in [(&a, "ringscale=12"), (&b, "ringscale=3")] {
        bin().arg(shader("wood")).args(["--res", "16x16", "-q", "-p", p, "-o"]).arg(path).assert().success();
    }
    assert_ne!(std::fs::read(&a).unwrap_or_default(), std::fs::read(&b).unwrap_or_default());
}

#[test]
fn latlong_sky_feeds_sh_project() {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let sky = dir.path().join("sky.exr");
    bin()
        .arg(shader("sky"))
        .args(["--latlong", "64x32", "--tolerance", "0.5", "-q", "-o"])
        .arg(&sky)
        .assert()
        .success();
    let img = prtkit::io::image::read_image(&sky).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((img.width, img.height), (64, 32));
    assert!(img.pixels.iter().all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    // Sky above the horizon (top rows) is brighter than the ground (bottom rows).
    let mean = |rows: std::ops::Range<usize>| {
        let mut s = 0.0;
        for y in rows.clone() {
            for x in 0..64 {
                s += img.get(x, y)[2] as f64;
            }
        }
        s / (64 * rows.len()) as f64
    };
    assert!(mean(2..10) > 2.0 * mean(22..30));
    cmd("sh-project").arg(&sky).assert().success();
}

#[test]
fn umbrella_and_thread_count_give_identical_bytes_and_verify_passes() {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    bin()
        .arg(shader("marble"))
        .args(["--res", "32x32", "--threads", "1", "--verify", "50", "-o"])
        .arg(&a)
        .assert()
        .success()
        .stderr(predicate::str::contains(", 0 outside their bounds"));
    cmd("prtkit")
        .arg("sample-shader")
        .arg(shader("marble"))
        .args(["--res", "32x32", "--threads", "2", "-q", "-o"])
        .arg(&b)
        .assert()
        .success();
    assert_eq!(std::fs::read(&a).unwrap_or_default(), std::fs::read(&b).unwrap_or_default());
}

#[test]
fn division_by_a_range_with_zero_is_reported_not_a_crash() {
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("{e}"));
    let src = dir.path().join("div.sl");
    std::fs::write(&src, "shader d() { Ci = color(1 / (u - 0.3)); }\n").unwrap_or_else(|e| panic!("{e}"));
    let out = bin().arg(&src).args(["--res", "16x16", "--json", "-q"]).output().unwrap_or_else(|e| panic!("{e}"));
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap_or_default();
    let stats = prtkit::io::document::parse_document::<Stats>(&text, STATS_FORMAT, STATS_VERSION)
        .unwrap_or_else(|e| panic!("{e}"))
        .body;
    assert!(stats.unbounded_leaves > 0);
    // An unbounded width is written as null and read back as infinity.
    assert_eq!(stats.width.max, f64::INFINITY);
    assert!(stats.seconds.is_some(), "the --json summary carries the timing");
}
