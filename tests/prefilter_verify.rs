//! `prefilter --verify N` (docs/prefilter.md, "Verifying a bake"): the figures it writes are the
//! full comparison against `--method angular` restricted to the texels it checked, they tell a
//! ringing bake from a clean one, and they do not depend on the thread count.

mod common;

use glam::DVec3;
use predicates::prelude::*;
use prtkit::brdf::Brdf;
use prtkit::envmap::bright::BrightRule;
use prtkit::envmap::EnvMap;
use prtkit::io::RgbImage;
use prtkit::metrics;
use prtkit::prefilter::model::Model;
use prtkit::prefilter::orders::OrderRule;
use prtkit::prefilter::pipeline::Lighting;
use prtkit::prefilter::stage::{self, Config, MapRequest, Method};
use prtkit::prefilter::tuning::ANGULAR_EPSILON as EPSILON;
use prtkit::prefilter::verify::{MapVerification, Verifier};
use prtkit::progress::NoProgress;
use prtkit::sh::window::Window;

/// A sky with a sun 10⁴ times the ground (the ring-free test's scene): truncated expansions
/// ring around it.
fn sun_scene() -> RgbImage {
    let sun = DVec3::new(0.4, -0.3, 0.7).normalize();
    common::latlong(128, 64, |d| {
        let ground = if d.z > 0.0 { 1.0 } else { 0.2 };
        let v = ground + if d.dot(sun) > 0.9985 { 1e4 } else { 0.0 };
        [v as f32, (0.9 * v) as f32, (0.8 * v) as f32]
    })
}

fn bake(
    env: &EnvMap,
    spec: &str,
    view: DVec3,
    size: (usize, usize),
    setup: impl Fn(Config) -> Config,
) -> stage::Output {
    let config = setup(Config {
        size: Some(size),
        maps: vec![MapRequest { file: "m.exr".into(), view }],
        ..Config::new(Brdf::parse(spec).unwrap())
    });
    stage::run(&config, Lighting::Map(env), &NoProgress).unwrap()
}

fn paper(c: Config) -> Config {
    Config { order_rule: OrderRule::Energy, bright: BrightRule::Off, window: Window::None, ..c }
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * b.abs().max(1e-300)
}

#[test]
fn the_figures_are_the_full_comparison_on_the_checked_texels() {
    let env = EnvMap::latlong(sun_scene()).unwrap();
    let n = 300;
    // Phong on a grid as wide as the map (the reference's zonal FFT path), Torrance–Sparrow at
    // a grazing view on a narrower one (its cone sum); each bake the default and the paper's.
    for (spec, view, size) in [
        ("phong:s=32", DVec3::Z, (128, 64)),
        ("torrance-sparrow:sigma=0.2", DVec3::new(1.0, 0.0, 0.2).normalize(), (64, 32)),
    ] {
        let reference =
            bake(&env, spec, view, size, |c| Config { method: Method::Angular, epsilon: EPSILON, ..c }).maps.remove(0);
        for (setup, name) in [(&(|c| c) as &dyn Fn(Config) -> Config, "default"), (&paper, "paper")] {
            let out = bake(&env, spec, view, size, |c| setup(Config { verify: Some(n), ..c }));
            let v = out.document.body.verification.clone().expect("the document has the verification");
            assert_eq!(out.summary.verification.as_ref(), Some(&v), "--json says the same");
            assert_eq!(v.epsilon, EPSILON);
            let got: &MapVerification = &v.maps[0];
            // The same texels, chosen from the same bake, compared with the full reference.
            let model = Model::new(Brdf::parse(spec).unwrap(), true).unwrap();
            let (texels, selection) = Verifier::new(&model, &env, size.1, n).unwrap().choose(&out.maps[0]);
            assert_eq!((texels.len(), selection), (n, got.selection), "{spec} {name}");
            let mut mask = vec![false; size.0 * size.1];
            texels.iter().for_each(|&i| mask[i] = true);
            let (want, _) = metrics::compare(&out.maps[0], &reference, &mask).unwrap();
            eprintln!("{spec} {name}: verify {got:?}\n  full comparison on the same texels: {want}");
            assert!(close(got.rel_error, want.rel_error), "{spec} {name}: {} vs {}", got.rel_error, want.rel_error);
            assert!(close(got.p99_texel_error, want.p99_texel_error), "{spec} {name}");
            assert!(close(got.max_texel_error, want.max_texel_error), "{spec} {name}");
            assert_eq!(got.negative as f64 / n as f64, want.negative_fraction, "{spec} {name}");
            assert_eq!([got.worst.x, got.worst.y], want.worst_texel, "{spec} {name}");
            let r = reference.get(got.worst.x, got.worst.y);
            assert!((0..3).all(|c| (got.worst.exact[c] - r[c] as f64).abs() <= 1e-6 * (r[c] as f64).abs()));
        }
    }
}

#[test]
fn a_ringing_bake_says_so_and_a_clean_one_does_not() {
    let env = EnvMap::latlong(sun_scene()).unwrap();
    let figures = |setup: &dyn Fn(Config) -> Config| {
        let out = bake(&env, "phong:s=32", DVec3::Z, (64, 32), |c| setup(Config { verify: Some(200), ..c }));
        out.document.body.verification.unwrap().maps.remove(0)
    };
    let clean = figures(&|c| c);
    let ringing = figures(&paper);
    eprintln!("default: {clean:?}\npaper: {ringing:?}");
    assert_eq!(clean.negative, 0, "{clean:?}");
    assert!(clean.p99_texel_error <= 0.05 && clean.rel_error <= 0.02, "{clean:?}");
    assert!(ringing.negative > 0 && ringing.max_texel_error > 1.0, "{ringing:?}");
}

#[test]
fn the_document_is_the_same_for_any_thread_count_and_sh_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let env = common::write_pfm(dir.path(), "sun.pfm", &sun_scene());
    let run = |threads: &str| {
        let doc = dir.path().join(format!("t{threads}.json"));
        let map = dir.path().join(format!("t{threads}.exr"));
        common::cmd("prefilter")
            .arg(&env)
            .args(["--brdf", "torrance-sparrow:sigma=0.2", "--view", "1,0,0.2", "--size", "64x32"])
            .args(["--verify", "150", "--threads", threads, "-o"])
            .arg(&doc)
            .arg("--reflection-map")
            .arg(&map)
            .assert()
            .success()
            .stderr(predicates::str::contains("verify: ").and(predicates::str::contains("150 texels")));
        let mut json: serde_json::Value = common::read(&doc);
        // The provenance records the command line, which names the thread count and the files.
        json.as_object_mut().unwrap().remove("provenance");
        json["maps"][0]["file"] = "m.exr".into();
        json["verification"]["maps"][0]["map"] = "m.exr".into();
        (json, std::fs::read(&map).unwrap())
    };
    let (one, two) = (run("1"), run("2"));
    assert_eq!(one.0["verification"]["maps"][0]["texels"], 150);
    assert_eq!(one, two);

    let sh = dir.path().join("sun.sh.json");
    common::cmd("sh-project").arg(&env).args(["--order", "8", "-o"]).arg(&sh).assert().success();
    let out = common::cmd("prefilter")
        .args(["--brdf", "phong:s=8", "--verify", "10", "--sh"])
        .arg(&sh)
        .assert()
        .code(2)
        .get_output()
        .clone();
    assert!(common::stderr(&out).contains("--verify needs the environment map"), "{}", common::stderr(&out));
}
