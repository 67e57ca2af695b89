//! `transfer --sh-energy F` (issue 32, item 3: the SH order for a tolerance, said in the manifest):
//! the fewest bands holding F of the transfer kernel's energy. A Lambertian BRDF factored (one
//! term, the cosine folded into the factors or left to the transport) is the clamped cosine
//! again, so its fractions must be Ramamoorthi & Hanrahan 2001's 3/8, 7/8 and 127/128 within 1, 2
//! and 3 bands, to the factor grid's resolution; a sharper lobe needs more bands.

mod common;

use common::{cmd, run_in, stderr, test_mesh};
use prtkit::brdf::Brdf;
use prtkit::factor::{factor, Channel, Domain, Method, Sampling};
use prtkit::progress::NoProgress;
use prtkit::transfer::order::for_energy;
use prtkit::transfer::stage::GlossyConfig;

fn glossy(spec: &str, cosine: bool, terms: usize) -> GlossyConfig {
    let sampling = Sampling { resolution: 32, domain: Domain::Hemisphere, cosine, channel: Channel::Luminance };
    let brdf = Brdf::parse(spec).unwrap();
    let factorization = factor(&brdf, &sampling, Method::Auto, terms, &NoProgress).unwrap();
    GlossyConfig {
        factorization,
        cosine,
        terms,
        terms_reason: String::new(),
        cell_samples: 2,
        factors: spec.into(),
        brdf: spec.into(),
    }
}

#[test]
fn a_factored_lambertian_holds_the_clamped_cosines_fractions() {
    for cosine in [true, false] {
        let g = glossy("lambert", cosine, 1);
        for (fraction, order, held) in [(0.3, 1, 3.0 / 8.0), (0.8, 2, 7.0 / 8.0), (0.99, 3, 127.0 / 128.0)] {
            let chosen = for_energy(fraction, Some(&g)).unwrap();
            assert_eq!(chosen.order, order, "cosine in factors {cosine}, {fraction}: {chosen:?}");
            assert!(
                (chosen.held - held).abs() < 2e-3,
                "cosine in factors {cosine}, {order} bands: {chosen:?} against {held}"
            );
        }
        let diffuse = for_energy(0.99, None).unwrap();
        assert_eq!((diffuse.order, diffuse.held), (3, 127.0 / 128.0));
    }
}

#[test]
fn a_sharper_lobe_needs_more_bands() {
    let orders: Vec<usize> = ["phong:s=2", "phong:s=8", "phong:s=32"]
        .iter()
        .map(|spec| for_energy(0.9, Some(&glossy(spec, true, 16))).unwrap().order)
        .collect();
    assert!(orders.windows(2).all(|w| w[0] < w[1]), "{orders:?}");
}

#[test]
fn the_manifest_says_which_order_and_why_and_bad_fractions_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = test_mesh("bowl-ball.obj");
    run_in(d, "transfer", &[&mesh, "--sh-energy", "0.8", "--rays", "16", "--glb", "t.glb", "-o", "t.json"]);
    let manifest: serde_json::Value = common::read(&d.join("t.json"));
    assert_eq!(manifest["order"], 2);
    let reason = manifest["order_reason"].as_str().unwrap();
    assert!(reason.contains("0.8750 within 2 bands") && reason.contains("--sh-energy 0.8"), "{reason}");
    run_in(d, "transfer", &[&mesh, "-n", "2", "--rays", "16", "--glb", "n.glb", "-o", "n.json"]);
    assert!(common::read::<serde_json::Value>(&d.join("n.json")).get("order_reason").is_none());
    for (args, message) in [
        (vec!["--sh-energy", "0"], "--sh-energy 0 must be in (0, 1]"),
        (vec!["--sh-energy", "0.9", "-n", "4"], "cannot be used with"),
    ] {
        let out = cmd("transfer").arg(&mesh).args(&args).args(["--glb", "x.glb"]).current_dir(d).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(stderr(&out).contains(message), "{args:?}: {}", stderr(&out));
        assert!(!d.join("x.glb").exists());
    }
}
