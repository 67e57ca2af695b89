//! The MERL reader against `../shared/testdata/merl`: a file in the exact MERL format written by
//! an independent (numpy) writer, whose expected lookups, l* and K are in its `.expected.json`.
//! Skips with a message when the shared test data is absent.

use prtkit::brdf::{halfdiff, merl, Brdf};
use prtkit::factor::{energy, factor, predict, Channel, Domain, Method, Sampling};
use prtkit::progress::NoProgress;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

const STEM: &str = "synthetic-merl-R_ts0.20_G_ts0.40_B_phong10";

/// The reference file `<STEM>.expected.json` (format `research.synthetic-merl-expected`), read as
/// far as these tests use it.
#[derive(Deserialize)]
struct Expected {
    test_vectors: Vec<TestVector>,
    l_star_from_theta_h_curve: Rgb<LStar>,
    /// Per case (`hemi_40^4_no_cos`, `hemi_64^4_cos_i`, …), per channel (`R`, `G`, `B`, `mean_rgb`).
    #[serde(rename = "K")]
    k: BTreeMap<String, BTreeMap<String, TermCounts>>,
}

/// One lookup: the directions, their half/difference angles and MERL bins, and the RGB value.
#[derive(Debug, Deserialize)]
struct TestVector {
    theta_i: f64,
    phi_i: f64,
    theta_o: f64,
    phi_o: f64,
    theta_h: f64,
    theta_d: f64,
    phi_d: f64,
    i_theta_h: usize,
    i_theta_d: usize,
    i_phi_d: usize,
    flat_index: usize,
    rgb_lookup: [f64; 3],
}

#[derive(Deserialize)]
#[allow(non_snake_case)]
struct Rgb<T> {
    R: T,
    G: T,
    B: T,
}

#[derive(Deserialize)]
struct LStar {
    l_star_e3: usize,
    l_star_99: usize,
}

#[derive(Deserialize)]
#[allow(non_snake_case)]
struct TermCounts {
    K99_via_merl_lookup: usize,
    /// Absent for `mean_rgb`.
    K99_analytic_same_grid: Option<usize>,
}

fn testdata() -> Option<(Brdf, Expected)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/testdata/merl");
    let bin = dir.join(format!("{STEM}.binary"));
    let json = dir.join(format!("{STEM}.expected.json"));
    if !bin.exists() || !json.exists() {
        eprintln!("skipping: {} not found (shared test data absent)", bin.display());
        return None;
    }
    let brdf = Brdf::parse(&format!("merl:{}", bin.display())).expect("the shared MERL file reads");
    let expected: Expected = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    Some((brdf, expected))
}

/// The grid size n and whether the cosine is folded in, from a case name like `hemi_40^4_cos_i`.
fn case(name: &str) -> (usize, bool) {
    let n = name.trim_start_matches("hemi_").split('^').next().unwrap().parse().unwrap();
    (n, name.ends_with("cos_i"))
}

#[test]
fn lookup_test_vectors_match_merls_convention() {
    let Some((brdf, expected)) = testdata() else { return };
    let Brdf::Merl(table) = &brdf else { panic!("not a MERL BRDF") };
    assert_eq!(table.missing(), [0, 0, 0]);
    assert!(!expected.test_vectors.is_empty());
    for tv in &expected.test_vectors {
        let wi = prtkit::sphere::direction(tv.theta_i, tv.phi_i);
        let wo = prtkit::sphere::direction(tv.theta_o, tv.phi_o);
        let hd = halfdiff::from_directions(wi, wo);
        let ill_conditioned = tv.theta_h < 1e-6;
        if !ill_conditioned {
            assert!((hd.theta_h - tv.theta_h).abs() < 1e-12, "{tv:?}");
            assert!((hd.theta_d - tv.theta_d).abs() < 1e-12, "{tv:?}");
            assert!((hd.phi_d - tv.phi_d).abs() < 1e-12, "{tv:?}");
            let idx = merl::index_of(&hd);
            assert_eq!((idx.theta_h, idx.theta_d, idx.phi_d), (tv.i_theta_h, tv.i_theta_d, tv.i_phi_d), "{tv:?}");
            assert_eq!(idx.flat(), tv.flat_index, "{tv:?}");
        }
        // At θ_h ≈ 0 the φ_d bin is implementation-defined but the value is not (isotropic channels).
        let rgb = brdf.eval(wi, wo);
        for c in 0..3 {
            let want = tv.rgb_lookup[c];
            assert!((rgb[c] - want).abs() <= 1e-12 * want.abs(), "channel {c}: {} vs {want} ({tv:?})", rgb[c]);
        }
    }
}

#[test]
fn half_angle_l_star_matches_the_reference() {
    let Some((brdf, expected)) = testdata() else { return };
    let want = &expected.l_star_from_theta_h_curve;
    for (key, channel, want) in [("R", Channel::R, &want.R), ("G", Channel::G, &want.G), ("B", Channel::B, &want.B)] {
        let spectrum = predict::half_angle_spectrum_of(&brdf, channel, predict::HALF_ANGLE_LMAX).unwrap();
        assert_eq!(predict::l_star_coefficient(&spectrum, predict::E3), Some(want.l_star_e3), "{key}");
        assert_eq!(predict::l_star_band_energy(&spectrum, 0.99), Some(want.l_star_99), "{key}");
    }
}

#[test]
fn term_counts_via_lookup_match_the_reference() {
    let Some((brdf, expected)) = testdata() else { return };
    for (name, per_channel) in &expected.k {
        let (n, cosine) = case(name);
        if n > 64 {
            continue; // 100⁴ is covered by the reproduction script, not a CI test.
        }
        for (key, channel) in [("R", Channel::R), ("G", Channel::G), ("B", Channel::B), ("mean_rgb", Channel::Mean)] {
            let sampling = Sampling { resolution: n, domain: Domain::Hemisphere, cosine, channel };
            let s = factor(&brdf, &sampling, Method::Fft, 0, &NoProgress).unwrap().singular_values;
            let k = energy::terms_for_fraction(&s, 0.99);
            assert_eq!(k, per_channel[key].K99_via_merl_lookup, "{name} {key}");
        }
    }
}

#[test]
fn analytic_channels_match_the_reference_on_the_same_grid() {
    // The analytic BRDFs the file was written from, factored by prtkit's own models.
    let Some((_, expected)) = testdata() else { return };
    let specs = [("R", "torrance-sparrow:sigma=0.2"), ("G", "torrance-sparrow:sigma=0.4"), ("B", "phong:s=10")];
    for (name, per_channel) in &expected.k {
        let (n, cosine) = case(name);
        if n > 64 {
            continue;
        }
        for (key, spec) in specs {
            let brdf = Brdf::parse(spec).unwrap();
            let sampling = Sampling { resolution: n, domain: Domain::Hemisphere, cosine, channel: Channel::Luminance };
            let s = factor(&brdf, &sampling, Method::Fft, 0, &NoProgress).unwrap().singular_values;
            let want = per_channel[key].K99_analytic_same_grid.expect("analytic counts for R, G, B");
            assert_eq!(energy::terms_for_fraction(&s, 0.99), want, "{name} {spec}");
        }
    }
}
