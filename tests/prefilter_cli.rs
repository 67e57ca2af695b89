//! Integration tests of the `prefilter` binary: outputs, the document, exit codes, bad input.

use assert_cmd::Command;
use prtkit::io::{pfm, RgbImage};
use std::path::{Path, PathBuf};

fn prefilter() -> Command {
    Command::cargo_bin("prefilter").unwrap()
}

fn sky(dir: &Path) -> PathBuf {
    let (w, h) = (64, 32);
    let img = RgbImage::from_fn(w, h, |x, y| {
        let d = prtkit::sphere::LatLong::new(w, h).texel_direction(x, y);
        let v = (0.3 + d.z.max(0.0) + 3.0 * d.dot(glam::DVec3::new(0.6, 0.0, 0.8)).max(0.0).powi(8)) as f32;
        [v, v, v]
    });
    let path = dir.join("sky.pfm");
    std::fs::write(&path, pfm::encode(&img)).unwrap();
    path
}

#[test]
fn writes_an_shrm_its_document_and_reflection_maps() {
    let dir = tempfile::tempdir().unwrap();
    let env = sky(dir.path());
    let (doc, exr, map) = (dir.path().join("m.json"), dir.path().join("m.exr"), dir.path().join("v.exr"));
    prefilter()
        .arg(&env)
        .args(["--brdf", "torrance-sparrow:sigma=0.3", "--no-cosine", "--epsilon", "0.03", "--size", "64x32"])
        .arg("--shrm")
        .arg(&exr)
        .args(["--view", "0,0.3,1", "--reflection-map"])
        .arg(&map)
        .arg("-o")
        .arg(&doc)
        .assert()
        .success();
    let d: serde_json::Value = serde_json::from_slice(&std::fs::read(&doc).unwrap()).unwrap();
    assert_eq!(d["format"], "prtkit.shrm");
    let (f, p) = (d["f_b"].as_u64().unwrap() as usize, d["p_b"].as_u64().unwrap() as usize);
    assert!(d["epsilon_achieved"].as_f64().unwrap() <= 0.03);
    let layers = prtkit::io::exr::decode_layers(&exr, &std::fs::read(&exr).unwrap()).unwrap();
    assert_eq!(layers.len(), (p + 1) * (p + 1));
    assert_eq!(d["layers"].as_array().unwrap().len(), layers.len());
    assert!(f >= 1 && map.exists());
}

#[test]
fn the_sh_document_path_equals_the_map_path() {
    let dir = tempfile::tempdir().unwrap();
    let env = sky(dir.path());
    let sh = dir.path().join("sky.sh.json");
    Command::cargo_bin("sh-project").unwrap().arg(&env).args(["--order", "12", "-o"]).arg(&sh).assert().success();
    let (a, b) = (dir.path().join("a.pfm"), dir.path().join("b.pfm"));
    let common = ["--brdf", "phong:s=16", "--order", "8", "--size", "64x32", "--reflection-map"];
    prefilter().arg(&env).args(common).arg(&a).arg("-o").arg(dir.path().join("a.json")).assert().success();
    prefilter().arg("--sh").arg(&sh).args(common).arg(&b).arg("-o").arg(dir.path().join("b.json")).assert().success();
    let read = |p: &Path| prtkit::io::image::read_image(p).unwrap();
    let err = prtkit::metrics::relative_rms(&read(&a), &read(&b));
    assert!(err < 1e-6, "{err}");
}

#[test]
fn bad_inputs_exit_2_and_leave_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let env = sky(dir.path());
    let low = dir.path().join("low.sh.json");
    Command::cargo_bin("sh-project").unwrap().arg(&env).args(["--order", "2", "-o"]).arg(&low).assert().success();
    let garbled = dir.path().join("garbled.sh.json");
    std::fs::write(&garbled, "{\"format\": \"prtkit.sh\", \"version\": 1, \"order\": 2, \"coefficients\": [[1,2,3]]}")
        .unwrap();
    let out = dir.path().join("out.json");
    let map = dir.path().join("map.exr");
    let env_s = env.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec![env_s, "--brdf", "glossy:s=3"], "glossy"),
        (vec![env_s, "--brdf", "phong:s=-3"], "phong"),
        (vec!["--sh", low.to_str().unwrap(), "--brdf", "phong:s=64"], "--order"),
        (vec!["--sh", garbled.to_str().unwrap(), "--brdf", "lambert"], "garbled.sh.json"),
        (vec![env_s, "--brdf", "phong:s=16", "--order", "60"], "resolves"),
        (vec![env_s, "--brdf", "phong:s=16", "--output-layout", "faces"], "output-layout"),
        (vec![env_s, "--brdf", "phong:s=16", "--irradiance", "x.exr"], "lambert"),
        (vec![env_s, "--brdf", "phong:s=16", "--epsilon", "2"], "epsilon"),
    ];
    for (args, needle) in cases {
        let output = prefilter().args(&args).arg("--reflection-map").arg(&map).arg("-o").arg(&out).output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: stderr lacks {needle:?}: {stderr}");
        assert!(!out.exists() && !map.exists(), "{args:?} left an output");
    }
}
