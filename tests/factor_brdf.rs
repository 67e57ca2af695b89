//! `factor-brdf` end to end: the document read back as the library's `FactorBody`, factor maps,
//! bad input (exit 2, no partial output).

mod common;

use common::{cmd as bin, parse, read};
use predicates::prelude::*;
use prtkit::factor::document::FactorBody;
use prtkit::factor::{Domain, Method};
use prtkit::io::Document;

fn cmd() -> assert_cmd::Command {
    bin("factor-brdf")
}

#[test]
fn writes_a_factor_document_with_consistent_energy() {
    let out = cmd().args(["phong:s=30", "--domain", "hemisphere", "--resolution", "40"]).output().unwrap();
    assert!(out.status.success(), "{}", common::stderr(&out));
    let doc: Document<FactorBody> = parse(&out.stdout);
    assert_eq!(doc.format, "prtkit.factor");
    let b = &doc.body;
    assert_eq!((b.domain, b.resolution, b.directions_per_side, b.method), (Domain::Hemisphere, 40, 1600, Method::Fft));
    assert!(b.factors.is_none() && b.maps.is_none());
    let s = &b.singular_values;
    assert_eq!(s.len(), 1600);
    assert!(s.windows(2).all(|w| w[0] >= w[1]));
    // The FFT method labels each σ with its azimuthal frequency.
    assert_eq!(b.azimuthal_frequency.len(), s.len());
    let total: f64 = s.iter().map(|x| x * x).sum();
    assert!((total - b.total_energy).abs() <= 1e-12 * total);
    let k99 = b.terms["99%"];
    assert!(b.cumulative_energy[k99 - 1] >= 0.99 && b.cumulative_energy[k99 - 2] < 0.99);
    // The paper's Fig. 3A/6: K ≈ 2.5 s = 75 on the hemisphere for s = 30.
    assert!((68..=82).contains(&k99), "K99 = {k99}");
    assert!(b.terms["90%"] < k99 && k99 <= b.terms["99.9%"]);
    // Eckart–Young: the K-term error is √(1 − energy of K terms).
    for r in &b.reconstruction {
        assert!((r.relative_frobenius_error - (1.0 - r.energy).max(0.0).sqrt()).abs() < 1e-9, "K = {}", r.terms);
    }
}

#[test]
fn factor_maps_show_spherical_harmonics() {
    let dir = tempfile::tempdir().unwrap();
    let maps = dir.path().join("maps");
    let doc = dir.path().join("f.json");
    cmd()
        .args(["phong:s=8", "--domain", "sphere", "--resolution", "48", "--terms", "4", "-o"])
        .arg(&doc)
        .arg("--maps")
        .arg(&maps)
        .assert()
        .success();
    let doc: Document<FactorBody> = read(&doc);
    assert_eq!(doc.body.maps.as_deref(), Some(maps.to_str().unwrap()));
    assert!(doc.body.reconstruction.iter().any(|r| r.terms == 4), "the kept terms' error is listed");
    let bytes = std::fs::read(maps.join("factors.exr")).unwrap();
    let layers = prtkit::io::exr::decode_layers(&maps.join("factors.exr"), &bytes).unwrap();
    assert_eq!(layers.len(), 8);
    assert!(maps.join("factors.png").exists());
    // g_0 is Y_00 = 1/√(4π) everywhere (up to sign): one colour, constant magnitude (to the
    // grid's quadrature error: 2 % at n = 24, under 1.5 % at n = 48).
    let g0 = &layers.iter().find(|(n, _)| n == "g_000").unwrap().1;
    let y00 = 1.0 / (4.0 * std::f64::consts::PI).sqrt();
    let mags: Vec<f64> = g0.pixels.iter().map(|p| (p[0] - p[2]) as f64).collect();
    let (lo, hi) = mags.iter().fold((f64::MAX, f64::MIN), |(a, b), m| (a.min(m.abs()), b.max(m.abs())));
    assert!((lo - y00).abs() < 0.015 * y00 && (hi - y00).abs() < 0.015 * y00, "g_0 spans {lo}..{hi}, Y_00 = {y00}");
    assert!(mags.iter().all(|m| m.signum() == mags[0].signum()));
    // g_1..g_3 span band 1: each is a linear function of (x, y, z), so it changes sign.
    for k in 1..4 {
        let g = &layers.iter().find(|(n, _)| *n == format!("g_{k:03}")).unwrap().1;
        assert!(g.pixels.iter().any(|p| p[0] > 0.1) && g.pixels.iter().any(|p| p[2] > 0.1), "g_{k}");
    }
}

#[test]
fn bad_specs_are_errors_with_exit_2_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.json");
    for (spec, needle) in [
        ("glossy:s=3", "accepted: lambert"),
        ("phong:s=-2", "s must be > 0"),
        ("phong:s=0", "s must be > 0"),
        ("torrance-sparrow:roughness=0.2", "does not take parameter"),
    ] {
        cmd().arg(spec).arg("-o").arg(&out).assert().code(2).stderr(predicate::str::contains(needle));
        assert!(!out.exists());
    }
    // Malformed MERL files are in testdata/bad/cli (tests/conventions.rs).
    cmd().arg("merl:/nonexistent/x.binary").assert().code(2).stderr(predicate::str::contains("x.binary"));
}

#[test]
fn absurd_resolutions_say_how_much_memory_they_need() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.json");
    cmd()
        .args(["kajiya-kay:s=4", "--resolution", "2000", "-o"])
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("needs about").and(predicate::str::contains("TiB")));
    cmd()
        .args(["phong:s=4", "--resolution", "5000", "-o"])
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicate::str::contains("needs about").and(predicate::str::contains("--max-memory")));
    cmd().args(["phong:s=4", "--resolution", "1"]).assert().code(2).stderr(predicate::str::contains("at least 2"));
    assert!(!out.exists());
}
