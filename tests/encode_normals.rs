//! Integration tests of the `encode-normals` binary: exit codes, outputs, JSON deserialized.

mod common;

use assert_cmd::Command;
use predicates::prelude::*;
use prtkit::normals::report::{self, EncodeReport};
use prtkit::normals::table::Row;
use prtkit::normals::{encode, pack::Stream, sources, Codec, InvalidPolicy, Scheme};
use prtkit::progress::NoProgress;
use std::path::{Path, PathBuf};

fn cmd() -> Command {
    Command::cargo_bin("encode-normals").unwrap()
}

/// A deterministic spread of unit normals (golden-angle spiral), including the six axes.
fn spiral(n: usize) -> Vec<[f32; 3]> {
    let mut v = common::spiral_normals(n);
    v.extend([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]);
    v
}

fn write_raw(path: &Path, normals: &[[f32; 3]]) {
    std::fs::write(path, sources::raw_to_bytes(normals)).unwrap();
}

fn angle(a: [f32; 3], b: [f32; 3]) -> f64 {
    let a = a.map(f64::from);
    let b = b.map(f64::from);
    let c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
    (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt().atan2(a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
}

/// Paths of one encode run's files.
struct Run {
    input: PathBuf,
    codes: PathBuf,
    report: PathBuf,
    decoded: PathBuf,
}

/// Writes `normals` as raw f32 into `dir` and encodes them with `args`, writing codes, report and
/// decoded normals.
fn encode_to_files(dir: &Path, normals: &[[f32; 3]], args: &[&str]) -> Run {
    let [input, codes, report, decoded] = ["n.f32", "codes.bin", "report.json", "decoded.f32"].map(|f| dir.join(f));
    write_raw(&input, normals);
    let mut c = cmd();
    c.arg(&input).args(args).arg("-o").arg(&codes).arg("--report").arg(&report).arg("--decoded").arg(&decoded);
    c.assert().success();
    Run { input, codes, report, decoded }
}

#[test]
fn encode_raw_writes_codes_report_and_decoded_normals() {
    let dir = tempfile::tempdir().unwrap();
    let normals = spiral(2000);
    let Run { codes, report, decoded, .. } =
        encode_to_files(dir.path(), &normals, &["--scheme", "onv-range", "--bits", "24"]);
    // 24 bits -> one u32 word per normal.
    assert_eq!(std::fs::read(&codes).unwrap().len(), normals.len() * 4);
    let doc = report::parse(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let r = doc.body;
    assert_eq!((r.scheme, r.bits, r.count), (Scheme::OnvRange, 24, normals.len() as u64));
    assert_eq!(r.bound, Codec::new(Scheme::OnvRange, 24).unwrap().bound());
    assert!(r.error.max > 0.0 && r.error.max <= r.bound * 1.0001, "{} vs {}", r.error.max, r.bound);
    assert!(r.error.mean < r.error.rms && r.error.rms <= r.error.max);
    assert_eq!(r.histogram.counts.iter().sum::<u64>(), normals.len() as u64);
    // The decoded file holds the same number of normals, each within the bound (+ f32 rounding).
    let back = sources::raw_from_bytes(&decoded, &std::fs::read(&decoded).unwrap()).unwrap();
    assert_eq!(back.len(), normals.len());
    for (a, b) in normals.iter().zip(&back) {
        assert!(angle(*a, *b) <= r.bound + 2e-7);
    }
    // Axes come back exactly.
    assert_eq!(&back[back.len() - 6..], &normals[normals.len() - 6..]);
}

#[test]
fn packed_codes_decode_to_the_same_normals() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("n.raw");
    write_raw(&input, &spiral(777));
    let codes = dir.path().join("c.bits");
    let decoded = dir.path().join("d.raw");
    cmd()
        .arg(&input)
        .args(["--scheme", "cm", "--bits", "19", "--packed", "-o"])
        .arg(&codes)
        .arg("--decoded")
        .arg(&decoded)
        .assert()
        .success();
    assert_eq!(std::fs::read(&codes).unwrap().len(), (783 * 19usize).div_ceil(8));
    let out = dir.path().join("out.raw");
    cmd()
        .arg(&codes)
        .args(["--decode", "--scheme", "cm", "--bits", "19", "--packed", "-o"])
        .arg(&out)
        .assert()
        .success();
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&decoded).unwrap());
    // The encode run's report can stand in for --scheme/--bits/--packed.
    let report = dir.path().join("r.json");
    cmd().arg(&input).args(["--scheme", "cm", "--bits", "19", "--packed", "--report"]).arg(&report).assert().success();
    let out2 = dir.path().join("out2.raw");
    cmd().arg(&codes).arg("--decode").arg("--header").arg(&report).arg("-o").arg(&out2).assert().success();
    assert_eq!(std::fs::read(&out2).unwrap(), std::fs::read(&decoded).unwrap());
    // --decode to OBJ and PLY writes the same numbers.
    let obj = dir.path().join("out.obj");
    cmd()
        .arg(&codes)
        .args(["--decode", "--scheme", "cm", "--bits", "19", "--packed", "-o"])
        .arg(&obj)
        .assert()
        .success();
    let text = std::fs::read_to_string(&obj).unwrap();
    assert_eq!(text.lines().filter(|l| l.starts_with("vn ")).count(), 783);
}

/// The `--json` report of encoding `spiral(n)` with `args`.
fn json_report(n: usize, args: &[&str]) -> EncodeReport {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("n.raw");
    write_raw(&input, &spiral(n));
    let out = cmd().arg(&input).args(args).arg("--json").output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    report::parse(std::str::from_utf8(&out.stdout).unwrap()).unwrap().body
}

#[test]
fn json_report_on_stdout_deserializes() {
    let r = json_report(300, &["--scheme", "sc", "--bits", "16"]);
    assert_eq!(r.scheme, Scheme::Sc);
    // The mixed-radix digits use the whole budget: at most 2^16 codes, and more than half of them.
    let used: u64 = r.layout.digits.iter().map(|d| d.radix).product();
    assert!(used <= 1 << 16 && used > 1 << 15, "{used}");
    assert!(r.error.max <= r.bound * (1.0 + 1e-9));
}

#[test]
fn zero_normal_is_an_error_naming_file_and_line_with_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("m.obj");
    std::fs::write(&input, "v 0 0 0\nvn 0 0 1\nvn 0 0 0\n").unwrap();
    let codes = dir.path().join("codes.bin");
    cmd().arg(&input).arg("-o").arg(&codes).assert().code(2).stderr(
        predicate::str::contains("m.obj")
            .and(predicate::str::contains("normal #1"))
            .and(predicate::str::contains("line 3")),
    );
    assert!(!codes.exists());
    // With --on-invalid replace the same file encodes and the report counts it.
    let out = cmd().arg(&input).args(["--on-invalid", "replace", "--json"]).output().unwrap();
    assert!(out.status.success());
    let doc = report::parse(std::str::from_utf8(&out.stdout).unwrap()).unwrap();
    assert_eq!((doc.body.replaced.count, doc.body.replaced.indices.clone()), (1, vec![1]));
}

#[test]
fn bad_inputs_exit_2_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let codes = dir.path().join("codes.bin");
    let bad = dir.path().join("bad.raw");
    std::fs::write(&bad, [0u8; 13]).unwrap();
    cmd().arg(&bad).arg("-o").arg(&codes).assert().code(2).stderr(predicate::str::contains("bad.raw"));
    let nan = dir.path().join("nan.raw");
    write_raw(&nan, &[[0.0, 0.0, 1.0], [f32::NAN, 0.0, 1.0]]);
    cmd().arg(&nan).arg("-o").arg(&codes).assert().code(2).stderr(predicate::str::contains("NaN"));
    let ply = dir.path().join("t.ply");
    std::fs::write(&ply, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n0 0 1\n0 zz 1\n").unwrap();
    cmd().arg(&ply).arg("-o").arg(&codes).assert().code(2).stderr(predicate::str::contains("line 9, column 3"));
    cmd().arg(dir.path().join("missing.raw")).arg("-o").arg(&codes).assert().code(2);
    assert!(!codes.exists());
    // Usage errors: budget out of range, unknown scheme.
    cmd().args(["--table", "--bits", "7"]).assert().code(2);
    cmd().args(["--emit-decoder", "glsl", "--scheme", "hex"]).assert().code(2);
    // Codes whose length does not match the word size.
    cmd().arg(&bad).args(["--decode", "--bits", "32", "-o"]).arg(dir.path().join("x.raw")).assert().code(2);
    assert!(!dir.path().join("x.raw").exists());
}

#[test]
fn exr_unorm_normal_map_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("map.exr");
    let normals = spiral(58); // 64 with the axes: an 8x8 map
    let pixels: Vec<[f32; 3]> = normals.iter().map(|n| n.map(|c| 0.5 * c + 0.5)).collect();
    prtkit::io::exr::write_rgb(&input, &prtkit::io::RgbImage { width: 8, height: 8, pixels }).unwrap();
    let decoded = dir.path().join("decoded.exr");
    let out = cmd()
        .arg(&input)
        .args(["--unorm", "--scheme", "onv-domain", "--bits", "16", "--json", "--decoded"])
        .arg(&decoded)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let doc = report::parse(std::str::from_utf8(&out.stdout).unwrap()).unwrap();
    assert_eq!(doc.body.count, 64);
    let back = prtkit::io::image::read_image(&decoded).unwrap();
    assert_eq!((back.width, back.height), (8, 8));
    let bound = Codec::new(Scheme::OnvDomain, 16).unwrap().bound();
    for (p, n) in back.pixels.iter().zip(&normals) {
        // The unorm round trip (2c-1 of f32 input) adds ~1e-7 of its own.
        assert!(angle(p.map(|c| 2.0 * c - 1.0), *n) <= bound + 1e-6);
    }
}

#[test]
fn table_json_rows_deserialize_and_respect_the_bounds() {
    let out = cmd().args(["--table", "--bits", "32", "--samples", "65536", "--json", "--quiet"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let rows: Vec<Row> = serde_json::from_slice(&out.stdout).unwrap();
    let names: Vec<&str> = rows.iter().map(|r| r.scheme.as_str()).collect();
    for s in ["onv-range", "onv-domain", "sc", "pp", "spp", "cm", "fpnv"] {
        assert!(names.contains(&s), "{names:?}");
    }
    for r in rows.iter().filter(|r| r.scheme != "fpnv") {
        assert_eq!(r.bits, 32);
        // Every bound is derived for the split used (ONV_domain's eq. 10 is exceeded by ~ε²).
        assert!(r.max_error <= r.bound * (1.0 + 1e-6), "{r:?}");
        assert!(r.max_error >= 0.999 * r.bound, "adversarial directions must reach the bound: {r:?}");
        assert!(r.mean_error < r.max_error);
    }
    let range = rows.iter().find(|r| r.scheme == "onv-range").unwrap();
    let domain = rows.iter().find(|r| r.scheme == "onv-domain").unwrap();
    assert!(range.mean_error < domain.mean_error && range.max_error < domain.max_error);
    // The FPNV check (f32): eq. 3, eq. 4's 51 bits and ONV_range's 52 bits.
    let f32_row = rows.iter().find(|r| r.scheme == "fpnv" && r.bits == 96).unwrap();
    assert!((f32_row.bound - std::f64::consts::SQRT_2 / 3.0 * (-23f64).exp2()).abs() < 1e-3 * f32_row.bound);
    assert_eq!((f32_row.equivalent_bits, f32_row.onv_range_bits_needed), (Some(51), Some(52)));
    let measured = f32_row.onv_range_measured.as_ref().unwrap();
    assert!(measured.iter().any(|&(b, e)| b == 52 && e <= f32_row.bound));
    assert!(measured.iter().any(|&(b, e)| b == 51 && e > f32_row.bound));
    // Deterministic: a second run with 1 thread prints identical rows.
    let again = cmd()
        .args(["--table", "--bits", "32", "--samples", "65536", "--json", "--quiet", "--threads", "1"])
        .output()
        .unwrap();
    assert_eq!(again.stdout, out.stdout);
}

#[test]
fn table_defaults_to_the_papers_48_bits() {
    let out = cmd().args(["--table", "--samples", "65536", "--json", "--quiet"]).output().unwrap();
    assert!(out.status.success());
    let rows: Vec<Row> = serde_json::from_slice(&out.stdout).unwrap();
    assert!(rows.iter().filter(|r| r.scheme != "fpnv").all(|r| r.bits == 48));
    // Table 1, row 3: ONV_range 1.69e-7, ONV_domain 2.53e-7 (our splits equal the paper's here).
    let get = |s: &str| rows.iter().find(|r| r.scheme == s).unwrap().max_error;
    assert!((get("onv-range") - 1.69e-7).abs() < 0.01e-7);
    assert!((get("onv-domain") - 2.53e-7).abs() < 0.01e-7);
    // FPNV at 48 bits is three binary16 values: 4.60e-4.
    let half = rows.iter().find(|r| r.scheme == "fpnv" && r.bits == 48).unwrap();
    assert!((half.max_error - 4.60e-4).abs() < 0.01e-4);
}

#[test]
fn emit_decoder_prints_a_function_for_each_language() {
    for (lang, sig) in [
        ("glsl", "vec3 prtkit_decode_normal(uint code)"),
        ("hlsl", "float3 prtkit_decode_normal(uint code)"),
        ("wgsl", "fn prtkit_decode_normal(code: u32) -> vec3<f32>"),
    ] {
        cmd()
            .args(["--emit-decoder", lang, "--scheme", "onv-range", "--bits", "32"])
            .assert()
            .success()
            .stdout(predicate::str::contains(sig));
    }
    cmd()
        .args(["--emit-decoder", "glsl", "--bits", "48"])
        .assert()
        .success()
        .stdout(predicate::str::contains("uint lo, uint hi"));
    // The umbrella binary runs the same code.
    Command::cargo_bin("prtkit")
        .unwrap()
        .args(["encode-normals", "--emit-decoder", "wgsl", "--scheme", "cm", "--bits", "20"])
        .assert()
        .success()
        .stdout(predicate::str::contains("face"));
}

#[test]
fn library_entry_point_and_binary_give_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let normals = spiral(1000);
    let Run { input, codes, report, decoded } =
        encode_to_files(dir.path(), &normals, &["--scheme", "spp", "--bits", "40", "--packed", "--bins", "8"]);
    let config = encode::Config {
        scheme: Scheme::Spp,
        bits: 40,
        stream: Stream::Packed,
        on_invalid: InvalidPolicy::Error,
        histogram_bins: 8,
        files: encode::Files::new(&input, Some(codes.display().to_string()), Some(decoded.display().to_string())),
        args: Vec::new(),
    };
    let out = encode::run(&config, &normals, &NoProgress).unwrap();
    assert_eq!(std::fs::read(&codes).unwrap(), out.stream);
    assert_eq!(std::fs::read(&decoded).unwrap(), sources::raw_to_bytes(&out.decoded));
    // The report differs only in its provenance (the command line; tests/stage_library.rs gives
    // the library the binary's argv and compares every byte).
    let written: EncodeReport = report::parse(&std::fs::read_to_string(&report).unwrap()).unwrap().body;
    assert_eq!(written, out.report.body);
}

#[test]
fn mixed_radix_codes_use_the_whole_budget_and_stay_below_it() {
    // 48-bit CM codes: 6 faces x N_a x N_b <= 2^48 and more than 2^48 / 1.0001 of them used, where
    // three whole face bits would leave a quarter of the code space unused.
    let r = json_report(50, &["--scheme", "cm", "--bits", "48"]);
    let used: u128 = r.layout.digits.iter().map(|d| d.radix as u128).product();
    assert!(used <= 1 << 48 && used as f64 > (1u64 << 48) as f64 / 1.0001, "{used}");
    assert_eq!(r.layout.digits.last().map(|d| d.radix), Some(6));
    assert!(r.bound <= 2.38e-7, "Meyer et al.'s Table 1: {}", r.bound);
}
