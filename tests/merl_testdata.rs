//! The MERL reader against `../shared/testdata/merl`: a file in the exact MERL format written by
//! an independent (numpy) writer, whose expected lookups, l* and K are in its `.expected.json`.
//! Skips with a message when the shared test data is absent.

use prtkit::brdf::{halfdiff, merl, Brdf};
use prtkit::factor::{energy, factor, predict, Channel, Domain, Method, Sampling};
use prtkit::progress::NoProgress;
use serde_json::Value;
use std::path::PathBuf;

const STEM: &str = "synthetic-merl-R_ts0.20_G_ts0.40_B_phong10";

fn testdata() -> Option<(Brdf, Value)> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/testdata/merl");
    let bin = dir.join(format!("{STEM}.binary"));
    let json = dir.join(format!("{STEM}.expected.json"));
    if !bin.exists() || !json.exists() {
        eprintln!("skipping: {} not found (shared test data absent)", bin.display());
        return None;
    }
    let brdf = Brdf::parse(&format!("merl:{}", bin.display())).expect("the shared MERL file reads");
    let expected: Value = serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    Some((brdf, expected))
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

fn u(v: &Value) -> usize {
    v.as_u64().unwrap() as usize
}

#[test]
fn lookup_test_vectors_match_merls_convention() {
    let Some((brdf, expected)) = testdata() else { return };
    let Brdf::Merl(table) = &brdf else { panic!("not a MERL BRDF") };
    assert_eq!(table.missing(), [0, 0, 0]);
    for tv in expected["test_vectors"].as_array().unwrap() {
        let wi = prtkit::sphere::direction(f(&tv["theta_i"]), f(&tv["phi_i"]));
        let wo = prtkit::sphere::direction(f(&tv["theta_o"]), f(&tv["phi_o"]));
        let hd = halfdiff::from_directions(wi, wo);
        let ill_conditioned = f(&tv["theta_h"]) < 1e-6;
        if !ill_conditioned {
            assert!((hd.theta_h - f(&tv["theta_h"])).abs() < 1e-12, "{tv}");
            assert!((hd.theta_d - f(&tv["theta_d"])).abs() < 1e-12, "{tv}");
            assert!((hd.phi_d - f(&tv["phi_d"])).abs() < 1e-12, "{tv}");
            let idx = merl::index_of(&hd);
            assert_eq!(idx.theta_h, u(&tv["i_theta_h"]), "{tv}");
            assert_eq!(idx.theta_d, u(&tv["i_theta_d"]), "{tv}");
            assert_eq!(idx.phi_d, u(&tv["i_phi_d"]), "{tv}");
            assert_eq!(idx.flat(), u(&tv["flat_index"]), "{tv}");
        }
        // At θ_h ≈ 0 the φ_d bin is implementation-defined but the value is not (isotropic channels).
        let rgb = brdf.eval(wi, wo);
        for c in 0..3 {
            let want = f(&tv["rgb_lookup"][c]);
            assert!((rgb[c] - want).abs() <= 1e-12 * want.abs(), "channel {c}: {} vs {want} ({tv})", rgb[c]);
        }
    }
}

#[test]
fn half_angle_l_star_matches_the_reference() {
    let Some((brdf, expected)) = testdata() else { return };
    for (key, channel) in [("R", Channel::R), ("G", Channel::G), ("B", Channel::B)] {
        let spectrum = predict::half_angle_spectrum_of(&brdf, channel, predict::HALF_ANGLE_LMAX).unwrap();
        let want = &expected["l_star_from_theta_h_curve"][key];
        assert_eq!(predict::l_star_coefficient(&spectrum, predict::E3), Some(u(&want["l_star_e3"])), "{key}");
        assert_eq!(predict::l_star_band_energy(&spectrum, 0.99), Some(u(&want["l_star_99"])), "{key}");
    }
}

#[test]
fn term_counts_via_lookup_match_the_reference() {
    let Some((brdf, expected)) = testdata() else { return };
    for (case, per_channel) in expected["K"].as_object().unwrap() {
        // Keys look like "hemi_40^4_no_cos" / "hemi_64^4_cos_i".
        let n: usize = case.trim_start_matches("hemi_").split('^').next().unwrap().parse().unwrap();
        if n > 64 {
            continue; // 100⁴ is covered by the reproduction script, not a CI test.
        }
        let cosine = case.ends_with("cos_i");
        for (key, channel) in [("R", Channel::R), ("G", Channel::G), ("B", Channel::B), ("mean_rgb", Channel::Mean)] {
            let sampling = Sampling { resolution: n, domain: Domain::Hemisphere, cosine, channel };
            let s = factor(&brdf, &sampling, Method::Fft, 0, &NoProgress).unwrap().singular_values;
            let k = energy::terms_for_fraction(&s, 0.99);
            assert_eq!(k, u(&per_channel[key]["K99_via_merl_lookup"]), "{case} {key}");
        }
    }
}

#[test]
fn analytic_channels_match_the_reference_on_the_same_grid() {
    // The analytic BRDFs the file was written from, factored by prtkit's own models.
    let Some((_, expected)) = testdata() else { return };
    let specs = [("R", "torrance-sparrow:sigma=0.2"), ("G", "torrance-sparrow:sigma=0.4"), ("B", "phong:s=10")];
    for (case, per_channel) in expected["K"].as_object().unwrap() {
        let n: usize = case.trim_start_matches("hemi_").split('^').next().unwrap().parse().unwrap();
        if n > 64 {
            continue;
        }
        let cosine = case.ends_with("cos_i");
        for (key, spec) in specs {
            let brdf = Brdf::parse(spec).unwrap();
            let sampling = Sampling { resolution: n, domain: Domain::Hemisphere, cosine, channel: Channel::Luminance };
            let s = factor(&brdf, &sampling, Method::Fft, 0, &NoProgress).unwrap().singular_values;
            assert_eq!(
                energy::terms_for_fraction(&s, 0.99),
                u(&per_channel[key]["K99_analytic_same_grid"]),
                "{case} {spec}"
            );
        }
    }
}
