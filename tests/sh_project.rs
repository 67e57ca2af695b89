//! Integration tests of the `sh-project` binary: outputs, JSON schema, exit codes, bad input.

use assert_cmd::Command;
use prtkit::io::{pfm, RgbImage};
use std::path::{Path, PathBuf};

fn sh_project() -> Command {
    Command::cargo_bin("sh-project").unwrap()
}

fn write_pfm(dir: &Path, name: &str, image: &RgbImage) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, pfm::encode(image)).unwrap();
    path
}

fn sky(w: usize, h: usize) -> RgbImage {
    RgbImage::from_fn(w, h, |x, y| {
        let d = prtkit::sphere::LatLong::new(w, h).texel_direction(x, y);
        let v = (0.2 + d.z.max(0.0) * 2.0 + 5.0 * d.dot(glam::DVec3::new(0.6, 0.0, 0.8)).max(0.0).powi(20)) as f32;
        [v, v * 0.9, v * 0.8]
    })
}

#[test]
fn writes_a_document_with_order_coefficients_and_band_energy() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_pfm(dir.path(), "sky.pfm", &sky(64, 32));
    let out = dir.path().join("sky.sh.json");
    sh_project().arg(&input).args(["--order", "3", "-o"]).arg(&out).assert().success();
    let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(doc["format"], "prtkit.sh");
    assert_eq!(doc["version"], 1);
    assert_eq!(doc["order"], 3);
    assert_eq!(doc["coefficients"].as_array().unwrap().len(), 16);
    assert_eq!(doc["band_energy"].as_array().unwrap().len(), 4);
    assert_eq!(doc["source"]["layout"], "latlong");
    // The document reads back through the library's own parser.
    let parsed = prtkit::sh::document::parse(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(parsed.body.order, 3);
}

#[test]
fn stdout_is_the_default_output_and_epsilon_picks_an_order() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_pfm(dir.path(), "sky.pfm", &sky(128, 64));
    let output = sh_project().arg(&input).args(["--epsilon", "0.05"]).output().unwrap();
    assert!(output.status.success());
    let doc: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let order = doc["order"].as_u64().unwrap() as usize;
    let achieved = doc["selection"]["epsilon_achieved"].as_f64().unwrap();
    assert!(achieved <= 0.05, "achieved {achieved}");
    // One order less must miss the tolerance (smallest order, §5.1).
    let bands: Vec<f64> = doc["band_energy"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let total = doc["total_energy"].as_f64().unwrap();
    let below: f64 = bands[..order].iter().sum();
    assert!(order == 0 || 1.0 - below / total > 0.05);
}

#[test]
fn reconstruction_and_irradiance_images_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_pfm(dir.path(), "sky.pfm", &sky(64, 32));
    let (recon, irr, png) = (dir.path().join("r.exr"), dir.path().join("e.exr"), dir.path().join("e.png"));
    sh_project()
        .arg(&input)
        .args(["-F", "2", "-o"])
        .arg(dir.path().join("x.json"))
        .arg("--reconstruct")
        .arg(&recon)
        .arg("--irradiance")
        .arg(&irr)
        .arg("--irradiance")
        .arg(&png)
        .assert()
        .success();
    let e = prtkit::io::image::read_image(&irr).unwrap();
    assert_eq!((e.width, e.height), (64, 32));
    assert!(png.exists());
    // A constant-free check: irradiance of a sky brighter above is larger facing up.
    assert!(e.get(10, 0)[0] > e.get(10, 31)[0]);
    assert!(recon.exists());
}

#[test]
fn bad_inputs_exit_2_and_leave_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.json");
    let good = write_pfm(dir.path(), "good.pfm", &sky(32, 16));

    let mut nan = sky(32, 16);
    nan.set(3, 4, [f32::NAN, 0.0, 0.0]);
    let nan = write_pfm(dir.path(), "nan.pfm", &nan);
    let mut neg = sky(32, 16);
    neg.set(5, 6, [-1.0, 0.0, 0.0]);
    let neg = write_pfm(dir.path(), "neg.pfm", &neg);
    let bytes = std::fs::read(&good).unwrap();
    let truncated = dir.path().join("trunc.pfm");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let garbled = dir.path().join("garbled.exr");
    std::fs::write(&garbled, b"\x76\x2f\x31\x01 definitely not an exr").unwrap();
    let empty = dir.path().join("empty.hdr");
    std::fs::write(&empty, b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 0 +X 0\n").unwrap();
    let odd = write_pfm(dir.path(), "odd.pfm", &sky(30, 17));

    let cases: Vec<(Vec<std::ffi::OsString>, &str)> = vec![
        (vec![nan.into_os_string()], "NaN"),
        (vec![neg.clone().into_os_string()], "negative"),
        (vec![truncated.into_os_string()], "truncated"),
        (vec![garbled.into_os_string()], "garbled.exr"),
        (vec![empty.into_os_string()], "empty"),
        (vec![odd.into_os_string()], "--layout"),
        (vec![good.clone().into_os_string(), "--order".into(), "100000".into()], "absurd"),
        (vec![good.clone().into_os_string(), "--order".into(), "40".into()], "resolves"),
        (vec![good.clone().into_os_string(), "--epsilon".into(), "1.5".into()], "epsilon"),
        (vec!["missing.exr".into()], "missing.exr"),
    ];
    for (args, needle) in cases {
        let output = sh_project().args(&args).arg("-o").arg(&out).output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: stderr lacks {needle:?}: {stderr}");
        assert!(!out.exists(), "{args:?} left an output file");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: one line, no repeated cause: {stderr}");
    }
    // Negative pixels are accepted when asked to clamp.
    sh_project().arg(&neg).args(["--negative", "clamp", "-o"]).arg(&out).assert().success();
}

#[test]
fn umbrella_binary_runs_the_same_stage() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_pfm(dir.path(), "sky.pfm", &sky(64, 32));
    let a = sh_project().arg(&input).output().unwrap().stdout;
    let b = Command::cargo_bin("prtkit").unwrap().arg("sh-project").arg(&input).output().unwrap().stdout;
    let strip = |v: &[u8]| {
        let mut d: serde_json::Value = serde_json::from_slice(v).unwrap();
        d["provenance"] = serde_json::Value::Null;
        d
    };
    assert_eq!(strip(&a), strip(&b));
}
