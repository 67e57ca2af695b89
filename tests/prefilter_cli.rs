//! Integration tests of the `prefilter` binary: outputs and the document read back into the
//! library's types, the `prtkit.sh` path, and options that are refused.

mod common;

use common::{cmd, read, sky_pfm};
use prtkit::io::Document;
use prtkit::prefilter::document::ShrmBody;
use std::path::Path;

#[test]
fn writes_an_shrm_its_document_and_reflection_maps() {
    let dir = tempfile::tempdir().unwrap();
    let env = sky_pfm(dir.path(), 64, 32);
    let (doc, exr, map) = (dir.path().join("m.json"), dir.path().join("m.exr"), dir.path().join("v.exr"));
    cmd("prefilter")
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
    let d: Document<ShrmBody> = read(&doc);
    let b = &d.body;
    assert_eq!((d.format.as_str(), b.method.as_str(), b.cosine), ("prtkit.shrm", "frequency", false));
    assert_eq!((b.width, b.height, b.layout.as_str(), b.global), (64, 32, "latlong", false));
    assert!(b.epsilon_achieved <= 0.03 && b.epsilon == Some(0.03), "{b:?}");
    // ε achieved is the bake's own residual against its quadrature's total energy: the same as a
    // second, larger expansion of the BRDF says (the measure before, independent of the bake).
    let model = prtkit::prefilter::model::Model::new(prtkit::brdf::Brdf::parse(&b.brdf).unwrap(), false).unwrap();
    let larger = model.coefficients((2 * b.f_b).max(32), b.p_b + 3).residual(b.f_b, b.p_b);
    assert!((b.epsilon_achieved - larger).abs() <= 2e-3 * larger, "{} against {larger}", b.epsilon_achieved);
    assert_eq!(b.shrm_file.as_deref(), Some(exr.to_str().unwrap()));
    assert_eq!(b.lighting.order, b.f_b);
    let layers = prtkit::io::exr::decode_layers(&exr, &std::fs::read(&exr).unwrap()).unwrap();
    assert_eq!(layers.len(), (b.p_b + 1) * (b.p_b + 1));
    // The document lists the EXR's layers in index order p(p+1)+q (the EXR itself sorts them).
    let mut names: Vec<&String> = layers.iter().map(|(n, _)| n).collect();
    names.sort();
    let mut listed: Vec<&String> = b.layers.iter().collect();
    assert_eq!(listed[..2], ["B0+0", "B1-1"]);
    listed.sort();
    assert_eq!(names, listed);
    // The map is listed with its view direction, normalized.
    assert_eq!(b.maps.len(), 1);
    assert_eq!(b.maps[0].file, map.display().to_string());
    let v = b.maps[0].view.expect("a view-dependent BRDF records the view");
    let n = (0.3f64 * 0.3 + 1.0).sqrt();
    assert!((v[0]).abs() < 1e-12 && (v[1] - 0.3 / n).abs() < 1e-12 && (v[2] - 1.0 / n).abs() < 1e-12, "{v:?}");
    assert!(b.f_b >= 1 && map.exists());
}

#[test]
fn ggx_prefilters_a_white_environment_to_white() {
    // The split-sum kernel is normalized (∫ k dω = 1, docs/brdf-specs.md), so a constant
    // environment prefilters to the same constant at every reflection direction, up to the SH
    // projection's texel quadrature (measured: 8e-4 at 128×64, and 1.3 % at 32×16 for Phong as
    // for GGX).
    let dir = tempfile::tempdir().unwrap();
    let white = common::write_pfm(dir.path(), "white.pfm", &common::latlong(128, 64, |_| [1.0; 3]));
    let (doc, map) = (dir.path().join("g.json"), dir.path().join("g.exr"));
    cmd("prefilter")
        .arg(&white)
        .args(["--brdf", "ggx:roughness=0.5", "--size", "32x16", "--view", "1,0,0.2", "--reflection-map"])
        .arg(&map)
        .arg("-o")
        .arg(&doc)
        .assert()
        .success();
    let d: Document<ShrmBody> = read(&doc);
    assert_eq!((d.body.brdf.as_str(), d.body.p_b), ("ggx:roughness=0.5", 0));
    assert_eq!(d.body.maps[0].view, None, "a lobe about R is the same for every view");
    let image = prtkit::io::image::read_image(&map).unwrap();
    for p in &image.pixels {
        assert!(p.iter().all(|&c| (c - 1.0).abs() < 2e-3), "{p:?}");
    }
}

#[test]
fn the_sh_document_path_equals_the_map_path() {
    let dir = tempfile::tempdir().unwrap();
    let env = sky_pfm(dir.path(), 64, 32);
    let sh = dir.path().join("sky.sh.json");
    cmd("sh-project").arg(&env).args(["--order", "12", "-o"]).arg(&sh).assert().success();
    let (a, b) = (dir.path().join("a.pfm"), dir.path().join("b.pfm"));
    // The same coefficients either way: no bright sources apart (the document has no texels).
    let common = ["--brdf", "phong:s=16", "--order", "8", "--bright", "off", "--size", "64x32", "--reflection-map"];
    cmd("prefilter").arg(&env).args(common).arg(&a).arg("-o").arg(dir.path().join("a.json")).assert().success();
    let doc_b = dir.path().join("b.json");
    cmd("prefilter").arg("--sh").arg(&sh).args(common).arg(&b).arg("-o").arg(&doc_b).assert().success();
    let read_image = |p: &Path| prtkit::io::image::read_image(p).unwrap();
    let err = prtkit::metrics::relative_rms(&read_image(&a), &read_image(&b));
    assert!(err < 1e-6, "{err}");
    let doc: Document<ShrmBody> = read(&doc_b);
    assert_eq!(doc.body.lighting.source, sh.display().to_string());
    assert_eq!((doc.body.f_b, doc.body.p_b), (8, 0));
}

#[test]
fn refused_options_exit_2_and_leave_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let env = sky_pfm(dir.path(), 64, 32);
    let low = dir.path().join("low.sh.json");
    cmd("sh-project").arg(&env).args(["--order", "2", "-o"]).arg(&low).assert().success();
    let out = dir.path().join("out.json");
    let map = dir.path().join("map.exr");
    let env_s = env.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec![env_s, "--brdf", "glossy:s=3"], "glossy"),
        (vec![env_s, "--brdf", "phong:s=-3"], "phong"),
        (vec!["--sh", low.to_str().unwrap(), "--brdf", "phong:s=64"], "--order"),
        (vec![env_s, "--brdf", "phong:s=16", "--order", "60"], "resolves"),
        (vec![env_s, "--brdf", "phong:s=16", "--output-layout", "faces"], "output-layout"),
        (vec![env_s, "--brdf", "phong:s=16", "--irradiance", "x.exr"], "lambert"),
        (vec![env_s, "--brdf", "phong:s=16", "--epsilon", "2"], "epsilon"),
    ];
    for (args, needle) in cases {
        let output =
            cmd("prefilter").args(&args).arg("--reflection-map").arg(&map).arg("-o").arg(&out).output().unwrap();
        let stderr = common::stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: stderr lacks {needle:?}: {stderr}");
        assert!(!out.exists() && !map.exists(), "{args:?} left an output");
    }
}

#[test]
fn a_window_on_maps_integrated_in_angle_is_said_to_have_no_effect() {
    // A view-dependent BRDF's maps are integrated in angle: no SH synthesis for a window to act
    // on. The stage says so on stderr and records the window as none.
    let dir = tempfile::tempdir().unwrap();
    let env = sky_pfm(dir.path(), 32, 16);
    let (doc, map) = (dir.path().join("m.json"), dir.path().join("v.exr"));
    let run = |window: &str| {
        cmd("prefilter")
            .arg(&env)
            .args(["--brdf", "torrance-sparrow:sigma=0.3", "--window", window, "--reflection-map"])
            .arg(&map)
            .arg("-o")
            .arg(&doc)
            .assert()
            .success()
            .get_output()
            .stderr
            .clone()
    };
    let said = String::from_utf8(run("hann")).unwrap();
    assert!(said.contains("--window hann has no effect"), "{said}");
    let d: Document<ShrmBody> = read(&doc);
    let bake = d.body.bake.expect("a bake report");
    assert_eq!(bake.maps, prtkit::prefilter::ring_free::MapsFrom::Angle);
    assert_eq!(bake.window.kind, prtkit::sh::window::Window::None);
    let quiet = String::from_utf8(run("nonneg")).unwrap();
    assert!(!quiet.contains("no effect"), "the default window is not worth a note: {quiet}");
}
