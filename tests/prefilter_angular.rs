//! `prefilter --method angular`, the reference every accuracy figure is measured against: it
//! needs no spherical harmonics, says what it used, and is exact on the cases that have an
//! independent answer.

use assert_cmd::Command;
use glam::DVec3;
use prtkit::io::{pfm, RgbImage};
use std::path::{Path, PathBuf};

fn prefilter() -> Command {
    Command::cargo_bin("prefilter").unwrap()
}

fn write(dir: &Path, name: &str, img: &RgbImage) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, pfm::encode(img)).unwrap();
    path
}

fn document(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn the_angular_method_runs_where_no_sh_order_reaches_epsilon() {
    // The command: at ε = 0.001 no orders up to F = 128, P = 6 keep 1 − ε of eq. 11's
    // energy, which used to stop the angular method before it started.
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (48, 24);
    let sky = RgbImage::from_fn(w, h, |x, y| {
        let d = prtkit::sphere::LatLong::new(w, h).texel_direction(x, y);
        let v = (0.2 + d.z.max(0.0) + 20.0 * d.dot(DVec3::new(0.6, 0.0, 0.8)).max(0.0).powi(40)) as f32;
        [v, 0.9 * v, 0.8 * v]
    });
    let env = write(dir.path(), "sky.pfm", &sky);
    let (doc, map) = (dir.path().join("ts.json"), dir.path().join("ts.pfm"));
    prefilter()
        .arg(&env)
        .args(["--brdf", "torrance-sparrow:sigma=0.2", "--no-cosine", "--method", "angular", "--epsilon", "0.001"])
        .args(["--view", "0,0,1", "--reflection-map"])
        .arg(&map)
        .arg("-o")
        .arg(&doc)
        .assert()
        .success();
    let d = document(&doc);
    assert_eq!(d["method"], "angular");
    // No orders: F_B = P_B = 0, and the grid is the input's own.
    assert_eq!((d["f_b"].as_u64(), d["p_b"].as_u64()), (Some(0), Some(0)));
    assert_eq!((d["width"].as_u64(), d["height"].as_u64()), (Some(w as u64), Some(h as u64)));
    let left_out = d["epsilon_achieved"].as_f64().unwrap();
    assert!(left_out > 0.0 && left_out <= 0.001, "{left_out}");
    let out = prtkit::io::image::read_image(&map).unwrap();
    assert_eq!((out.width, out.height), (w, h));
    assert!(out.pixels.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    assert!(out.pixels.iter().any(|p| p[0] > 0.0));
}

#[test]
fn a_white_environment_gives_the_kept_share_of_the_lobe_everywhere() {
    // White furnace through the whole stage: ∫ (s+1)/2π max(R·ω, 0)^s dω = 1, the truncation
    // keeps 1 − ε_achieved of it up to the texels the cone's rim cuts, and the texel integrals
    // are good to ε/10.
    let dir = tempfile::tempdir().unwrap();
    let env = write(dir.path(), "white.pfm", &RgbImage::from_fn(64, 32, |_, _| [1.0; 3]));
    let (doc, map) = (dir.path().join("w.json"), dir.path().join("w.pfm"));
    prefilter()
        .arg(&env)
        .args(["--brdf", "phong:s=8", "--method", "angular", "--epsilon", "1e-6", "--reflection-map"])
        .arg(&map)
        .arg("-o")
        .arg(&doc)
        .assert()
        .success();
    let out = prtkit::io::image::read_image(&map).unwrap();
    for v in out.pixels.iter().flatten() {
        assert!((*v as f64 - 1.0).abs() < 1e-5, "{v}");
    }
}

#[test]
fn an_output_of_another_width_takes_the_cone_sum_and_agrees_with_the_zonal_filter() {
    // 48 × 24 from a 48 × 24 input takes the zonal FFT; 16 × 24 the cone sum. Column x of the
    // second is centred at (x + ½)·2π/16 = (3x + 1 + ½)·2π/48, the centre of column 3x + 1 of
    // the first: the same integral, computed two ways.
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (48, 24);
    let sky = RgbImage::from_fn(w, h, |x, y| {
        let d = prtkit::sphere::LatLong::new(w, h).texel_direction(x, y);
        let v = (1.0 + 0.5 * d.x + 0.25 * d.z + (x % 5) as f64 * 0.5 + 30.0 * (x == 7 && y == 5) as u8 as f64) as f32;
        [v, 0.5 * v, 1.0]
    });
    let env = write(dir.path(), "sky.pfm", &sky);
    let run = |size: &str, name: &str| {
        let map = dir.path().join(name);
        prefilter()
            .arg(&env)
            .args(["--brdf", "phong:s=16", "--method", "angular", "--epsilon", "1e-3", "--size", size])
            .arg("--reflection-map")
            .arg(&map)
            .arg("-o")
            .arg(dir.path().join(format!("{name}.json")))
            .assert()
            .success();
        prtkit::io::image::read_image(&map).unwrap()
    };
    let (zonal, cone) = (run("48x24", "z.pfm"), run("16x24", "c.pfm"));
    for y in 0..h {
        for x in 0..16 {
            let (a, b) = (cone.get(x, y), zonal.get(3 * x + 1, y));
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() <= 1e-6 * b[c].abs(), "({x}, {y}): {a:?} vs {b:?}");
            }
        }
    }
}

#[test]
fn orders_mean_nothing_to_the_angular_method() {
    let dir = tempfile::tempdir().unwrap();
    let env = write(dir.path(), "white.pfm", &RgbImage::from_fn(16, 8, |_, _| [1.0; 3]));
    prefilter()
        .arg(&env)
        .args(["--brdf", "phong:s=8", "--method", "angular", "--order", "8", "--reflection-map"])
        .arg(dir.path().join("x.pfm"))
        .assert()
        .code(2)
        .stderr(predicates::str::contains("takes no --order"));
}
