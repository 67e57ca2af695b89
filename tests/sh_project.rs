//! Integration tests of the `sh-project` binary: the document read back into the library's
//! types, order selection, images, bad input, and the umbrella binary.

mod common;

use common::{cmd, parse, read, sky_image, write_pfm};
use prtkit::io::Document;
use prtkit::sh::document::ShBody;

#[test]
fn writes_a_document_with_order_coefficients_and_band_energy() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_pfm(dir.path(), "sky.pfm", &sky_image(64, 32));
    let out = dir.path().join("sky.sh.json");
    cmd("sh-project").arg(&input).args(["--order", "3", "-o"]).arg(&out).assert().success();
    let doc: Document<ShBody> = read(&out);
    assert_eq!((doc.format.as_str(), doc.version), ("prtkit.sh", 1));
    assert_eq!(doc.provenance.stage, "sh-project");
    assert_eq!(doc.body.order, 3);
    assert_eq!(doc.body.coefficients.len(), 16);
    assert_eq!(doc.body.band_energy.len(), 4);
    assert_eq!(doc.body.selection.method, "order");
    assert_eq!(doc.body.source.layout, "latlong");
    assert_eq!((doc.body.source.width, doc.body.source.height), (64, 32));
    // Band energy is Σ_m Σ_rgb L_lm² (Parseval), band by band.
    for l in 0..=3usize {
        let sum: f64 = (l * l..(l + 1) * (l + 1)).flat_map(|i| doc.body.coefficients[i]).map(|c| c * c).sum();
        assert!((sum - doc.body.band_energy[l]).abs() <= 1e-12 * sum, "band {l}");
    }
    // The library's own parser (which also checks the counts) reads the same document.
    let parsed = prtkit::sh::document::parse(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(parsed, doc);
}

#[test]
fn stdout_is_the_default_output_and_epsilon_picks_the_smallest_order() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_pfm(dir.path(), "sky.pfm", &sky_image(128, 64));
    let output = cmd("sh-project").arg(&input).args(["--epsilon", "0.05"]).output().unwrap();
    assert!(output.status.success(), "{}", common::stderr(&output));
    let doc: Document<ShBody> = parse(&output.stdout);
    let body = &doc.body;
    let selection = &body.selection;
    assert_eq!((selection.method.as_str(), selection.epsilon), ("epsilon", Some(0.05)));
    let captured = |order: usize| body.band_energy[..=order].iter().sum::<f64>() / body.total_energy;
    let order = body.order;
    assert!((1.0 - captured(order) - selection.epsilon_achieved).abs() < 1e-12);

    // ε is measured on the map with its compact sun clipped at `clipped_at` (docs/sh-project.md):
    // clip it here, sum its energy texel by texel, and check the order is the smallest that
    // captures 1 − ε of it (§5.1).
    let threshold = selection.clipped_at.expect("the sun is a compact bright source");
    let mut clipped = common::sky(128, 64);
    let luminance = |p: &[f32; 3]| (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0;
    let mut clipped_count = 0;
    for p in clipped.images_mut()[0].pixels.iter_mut() {
        let y = luminance(p);
        if y > threshold {
            *p = p.map(|c| (c as f64 * threshold / y) as f32);
            clipped_count += 1;
        }
    }
    assert!(clipped_count > 0 && clipped_count < 128 * 64 / 100, "{clipped_count} texels clipped");
    let grid = prtkit::sphere::LatLong::new(128, 64);
    let energy: f64 = (clipped.image().pixels.iter().enumerate())
        .map(|(i, p)| grid.row_solid_angle(i / 128) * p.iter().map(|&c| c as f64 * c as f64).sum::<f64>())
        .sum();
    let residual = |order: usize| {
        let coeffs = prtkit::sh::project::project(&clipped, order, &prtkit::progress::NoProgress).unwrap();
        1.0 - coeffs.band_energy().iter().sum::<f64>() / energy
    };
    let achieved = selection.epsilon_achieved_clipped.unwrap();
    assert!((residual(order) - achieved).abs() < 1e-6, "{} vs {achieved}", residual(order));
    assert!(achieved <= 0.05 && order > 0 && residual(order - 1) > 0.05, "order {order}: {selection:?}");
}

#[test]
fn reconstruction_and_irradiance_images_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_pfm(dir.path(), "sky.pfm", &sky_image(64, 32));
    let (recon, irr, png) = (dir.path().join("r.exr"), dir.path().join("e.exr"), dir.path().join("e.png"));
    cmd("sh-project")
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
    // The sky is brighter than the ground: more irradiance facing up than facing down.
    assert!(e.get(10, 0)[0] > e.get(10, 31)[0]);
    assert!(recon.exists());
}

#[test]
fn bad_inputs_exit_2_and_leave_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.json");
    let good = write_pfm(dir.path(), "good.pfm", &sky_image(32, 16));
    let mut neg = sky_image(32, 16);
    neg.set(5, 6, [-1.0, 0.0, 0.0]);
    let neg = write_pfm(dir.path(), "neg.pfm", &neg);
    // Malformed files are in testdata/bad/cli (tests/conventions.rs); these are the options.
    let cases: Vec<(Vec<std::ffi::OsString>, &str)> = vec![
        (vec![neg.clone().into_os_string()], "negative"),
        (vec![good.clone().into_os_string(), "--order".into(), "100000".into()], "absurd"),
        (vec![good.clone().into_os_string(), "--order".into(), "40".into()], "resolves"),
        (vec![good.clone().into_os_string(), "--epsilon".into(), "1.5".into()], "epsilon"),
        (vec!["missing.exr".into()], "missing.exr"),
    ];
    for (args, needle) in cases {
        let output = cmd("sh-project").args(&args).arg("-o").arg(&out).output().unwrap();
        let stderr = common::stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(needle), "{args:?}: stderr lacks {needle:?}: {stderr}");
        assert!(!out.exists(), "{args:?} left an output file");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: one line, no repeated cause: {stderr}");
    }
    // Negative pixels are accepted when asked to clamp.
    cmd("sh-project").arg(&neg).args(["--negative", "clamp", "-o"]).arg(&out).assert().success();
}

#[test]
fn umbrella_binary_runs_the_same_stage() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_pfm(dir.path(), "sky.pfm", &sky_image(64, 32));
    let a: Document<ShBody> = parse(&cmd("sh-project").arg(&input).output().unwrap().stdout);
    let b: Document<ShBody> = parse(&cmd("prtkit").arg("sh-project").arg(&input).output().unwrap().stdout);
    assert_eq!(a.body, b.body);
    // The command lines differ only in the program and the subcommand.
    assert_eq!(b.provenance.args[1], "sh-project");
    assert_eq!(a.provenance.args[1..], b.provenance.args[2..]);
}

#[test]
fn the_reconstruction_keeps_a_sun_apart_without_rings_and_keeps_the_energy() {
    // A sky with a sun 10⁴ times the ground (half the energy): the order-F expansion of the whole map rings (and
    // goes negative); the reconstruction is the clipped map's expansion plus the sun's texels.
    let sun = glam::DVec3::new(0.3, -0.4, 0.6).normalize();
    let image = common::latlong(128, 64, |d| {
        let v = if d.z > 0.0 { 1.0 } else { 0.1 } + if d.dot(sun) > 0.999 { 1e3 } else { 0.0 };
        [v as f32; 3]
    });
    let map = prtkit::envmap::EnvMap::latlong(image.clone()).unwrap();
    let config = prtkit::sh::stage::Config {
        order: prtkit::sh::project::OrderChoice::Order(12),
        reconstruction: true,
        ..Default::default()
    };
    let out = prtkit::sh::stage::run(&config, &map, &prtkit::progress::NoProgress).unwrap();
    let recon = out.reconstruction.unwrap();
    assert!(recon.pixels.iter().flatten().all(|&v| v >= 0.0), "negative texels");
    // ∫ dω: band 0 of the clipped map is reproduced exactly and the sun's excess is put back.
    let grid = prtkit::sphere::LatLong::new(128, 64);
    let integral = |img: &prtkit::io::RgbImage| -> f64 {
        img.pixels.iter().enumerate().map(|(i, p)| grid.row_solid_angle(i / 128) * p[0] as f64).sum()
    };
    let (got, want) = (integral(&recon), integral(&image));
    assert!((got - want).abs() < 1e-4 * want, "{got} vs {want}");
    // In the lower half, far from the sun, the reconstruction stays within a tenth of the rings
    // the raw order-12 expansion of the whole map carries, measured against the sky without the
    // sun (the horizon's own Gibbs ripples are in both). What is left comes from the clipped
    // sun, which still stands at the threshold, 4× the sky.
    let no_sun =
        prtkit::envmap::EnvMap::latlong(common::latlong(128, 64, |d| [if d.z > 0.0 { 1.0 } else { 0.1 }; 3])).unwrap();
    let plain =
        prtkit::sh::stage::run(&config, &no_sun, &prtkit::progress::NoProgress).unwrap().reconstruction.unwrap();
    let raw = prtkit::sh::synth::synthesize_latlong(
        &prtkit::sh::project::project(&map, 12, &prtkit::progress::NoProgress).unwrap(),
        128,
        64,
    )
    .unwrap();
    let worst = |img: &prtkit::io::RgbImage| {
        (44..64)
            .flat_map(|y| (0..128).map(move |x| (x, y)))
            .map(|(x, y)| (img.get(x, y)[0] - plain.get(x, y)[0]).abs())
            .fold(0.0f32, f32::max)
    };
    assert!(worst(&recon) < worst(&raw) / 10.0, "sun apart: {} vs raw {}", worst(&recon), worst(&raw));
    assert!(worst(&raw) > 0.05, "the raw expansion should ring: {}", worst(&raw));
}

#[test]
fn the_default_window_keeps_a_horizon_from_banding_the_ground() {
    // A sky of 1 over a ground of 0.1: at order 30 the step rings through the whole ground (Gibbs).
    // `nonneg` only removes what goes negative, so the ground's rows keep ripples of tens of per
    // cent; the default (Lanczos's σ-factors, then the guard) keeps every ground row, below the
    // horizon's own transition, within a few per cent of 0.1.
    let (w, h) = (256, 128);
    let map =
        prtkit::envmap::EnvMap::latlong(common::latlong(w, h, |d| [if d.z > 0.0 { 1.0 } else { 0.1 }; 3])).unwrap();
    let ground = |window: Option<prtkit::sh::window::Window>| -> (f64, f64) {
        let defaults = prtkit::sh::stage::Config::default();
        let config = prtkit::sh::stage::Config {
            order: prtkit::sh::project::OrderChoice::Order(30),
            reconstruction: true,
            window: window.unwrap_or(defaults.window),
            ..defaults
        };
        let out = prtkit::sh::stage::run(&config, &map, &prtkit::progress::NoProgress).unwrap();
        let recon = out.reconstruction.unwrap();
        (9 * h / 16..h)
            .map(|y| (0..w).map(|x| recon.get(x, y)[0] as f64).sum::<f64>() / (w as f64 * 0.1))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| (lo.min(r), hi.max(r)))
    };
    let (lo, hi) = ground(None);
    let (nlo, nhi) = ground(Some(prtkit::sh::window::Window::Nonneg));
    assert!(lo > 0.95 && hi < 1.05, "default: ground rows {lo:.3}–{hi:.3} × 0.1");
    assert!(nlo < 0.85 || nhi > 1.15, "nonneg leaves the ripples: {nlo:.3}–{nhi:.3}");
}
