//! Integration tests of `render`: furnace, irradiance and SHRM against the reference, factored
//! convergence in K, and bad input.

mod common;

use common::{cmd as bin, latlong, write_exr, Chain};
use glam::DVec3;
use predicates::prelude::PredicateBooleanExt;
use predicates::str::contains;
use prtkit::io::image::{read_image, write_image};
use prtkit::io::RgbImage;
use prtkit::render::stage::Summary;
use std::path::{Path, PathBuf};

/// Writes a lat-long environment of `f(direction)` (white light, tinted 1 : 0.9 : 0.8) as EXR.
fn write_env(dir: &Path, name: &str, w: usize, h: usize, f: impl Fn(DVec3) -> f32) -> PathBuf {
    write_exr(
        dir,
        name,
        &latlong(w, h, |d| {
            let v = f(d);
            [v, 0.9 * v, 0.8 * v]
        }),
    )
}

/// A smooth sky: bands ≤ 2 plus a wide warm blob (smooth enough for order-2 irradiance to be
/// nearly exact and for a Phong s = 16 SHRM at ε = 1e-3).
fn smooth(d: DVec3) -> f32 {
    let blob = (4.0 * (d.dot(DVec3::new(0.6, -0.5, 0.6).normalize()) - 1.0)).exp();
    (1.0 + 0.5 * d.z + 0.3 * d.x + 0.2 * (3.0 * d.z * d.z - 1.0) + blob) as f32
}

/// Mean of the central `r`×`r` pixels (inside the sphere's silhouette at the default camera).
fn centre(img: &RgbImage, r: usize) -> [f64; 3] {
    let (cx, cy) = (img.width / 2, img.height / 2);
    let mut s = [0.0; 3];
    for y in cy - r / 2..cy + r / 2 {
        for x in cx - r / 2..cx + r / 2 {
            for c in 0..3 {
                s[c] += img.get(x, y)[c] as f64;
            }
        }
    }
    s.map(|v| v / (r * r) as f64)
}

/// The ground truth (`render`'s default shading) of `env` at `res`, as `dir/ref.exr`.
fn render_reference(dir: &Path, env: &Path, args: &[&str], res: &str) -> PathBuf {
    let reference = dir.join("ref.exr");
    bin("render").arg(env).args(args).args(["--res", res, "-q", "-o"]).arg(&reference).assert().success();
    reference
}

/// The `render --json` summary.
fn summary(out: &[u8]) -> Summary {
    common::parse(out)
}

/// Relative error of a `render --compare --json` run.
fn rel_error(out: &[u8]) -> f64 {
    summary(out).metrics.expect("--compare gives metrics").rel_error
}

#[test]
fn render_white_furnace_gives_the_albedo_in_every_mode() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "white.exr", 64, 32, |_| 1.0);
    // A white furnace looks the same from every normal: a coarse factorization and table suffice.
    let factored = ["--shading", "factored", "--brdf", "lambert:albedo=0.5", "-K", "1", "--factor-resolution", "16"];
    let factored = [&factored[..], &["--normal-table", "16x8"]].concat();
    let cases: [(&[&str], f64, f64); 4] = [
        (&["--shading", "irradiance", "--brdf", "lambert:albedo=0.5"], 0.5, 1e-3),
        (&["--shading", "reference", "--brdf", "lambert:albedo=0.5"], 0.5, 5e-3),
        (&factored, 0.5, 5e-3),
        // Normalized Phong's lobe integrates to 1 over the sphere (the prefilter's ρ̂, §6.3).
        (&["--shading", "reference", "--brdf", "phong:s=16", "--integrand", "prefilter"], 1.0, 5e-3),
    ];
    for (args, want, tol) in cases {
        let out = dir.path().join("f.exr");
        bin("render").arg(&env).args(args).args(["--res", "24x24", "-q", "-o"]).arg(&out).assert().success();
        // The white channel: green and blue of the env are 0.9 and 0.8.
        let c = centre(&read_image(&out).unwrap(), 6);
        for (ch, scale) in [(0, 1.0), (1, 0.9), (2, 0.8)] {
            assert!((c[ch] / scale - want).abs() < tol, "{args:?}: channel {ch} = {} want {want}", c[ch] / scale);
        }
    }
    // SHRM furnace: prefilter's Phong SHRM of the white map gives 1.
    let chain = Chain::prefilter(dir.path(), &env, "phong:s=16", "w.shrm", &["-e", "0.001"]);
    let out = dir.path().join("s.exr");
    chain.render().args(["--res", "24x24", "-o"]).arg(&out).assert().success();
    let c = centre(&read_image(&out).unwrap(), 6);
    assert!((c[0] - 1.0).abs() < 2e-3, "shrm furnace {c:?}");
}

#[test]
fn render_irradiance_matches_the_reference_for_lambert_within_one_percent() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "sky.exr", 128, 64, smooth);
    let reference = render_reference(dir.path(), &env, &["--brdf", "lambert"], "32x32");
    let out = bin("render")
        .arg(&env)
        .args(["--shading", "irradiance", "--brdf", "lambert", "--res", "32x32", "-q", "--json", "--compare"])
        .arg(&reference)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let e = rel_error(&out);
    assert!(e < 0.01 && e > 0.0, "irradiance vs reference: {e}");
}

#[test]
fn render_shrm_matches_the_reference_within_the_prefilter_epsilon() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "sky.exr", 128, 64, smooth);
    let reference = render_reference(dir.path(), &env, &["--brdf", "phong:s=16", "--integrand", "prefilter"], "32x32");
    let out = Chain::prefilter(dir.path(), &env, "phong:s=16", "p.shrm", &["-e", "0.01"])
        .render()
        .args(["--res", "32x32", "--json", "--compare"])
        .arg(&reference)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let (e, eps) = (rel_error(&out), summary(&out).epsilon_achieved.unwrap());
    assert!(eps > 0.0 && eps <= 0.01, "ε {eps}");
    assert!(e <= eps, "shrm vs reference: rel error {e} > ε {eps}");
}

#[test]
fn render_factored_error_falls_monotonically_with_k() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "sky.exr", 128, 64, smooth);
    let reference = render_reference(dir.path(), &env, &["--brdf", "phong:s=8"], "24x24");
    let mut errors = Vec::new();
    for k in [1, 3, 8, 20, 40] {
        let out = bin("render")
            .arg(&env)
            .args(["--shading", "factored", "--brdf", "phong:s=8", "--factor-resolution", "32", "--res", "24x24"])
            .args(["--normal-table", "32x16", "-q", "--json", "-K", &k.to_string(), "--compare"])
            .arg(&reference)
            .assert()
            .success()
            .get_output()
            .stdout
            .clone();
        errors.push(rel_error(&out));
    }
    for w in errors.windows(2) {
        assert!(w[1] < w[0], "errors not decreasing: {errors:?}");
    }
    assert!(errors[4] < 0.05, "K = 40 error {errors:?}");
}

#[test]
fn render_factored_shades_a_sun_exactly_and_the_rest_through_the_factors() {
    // A sky with a sun 10⁴ times brighter over a few texels: through a truncated factorization
    // the sun spreads into blotches and negative pixels (the paper's method, `--bright off`);
    // shaded exactly, apart from the smooth remainder, the render comes close to the reference.
    let dir = tempfile::tempdir().unwrap();
    let sun = DVec3::new(0.5, -0.6, 0.6).normalize();
    let env = write_env(dir.path(), "sun.exr", 128, 64, |d| smooth(d) + if d.dot(sun) > 0.9995 { 1e4 } else { 0.0 });
    let reference = render_reference(dir.path(), &env, &["--brdf", "phong:s=30"], "32x32");
    let run = |bright: &str| {
        let out = bin("render")
            .arg(&env)
            .args(["--shading", "factored", "--brdf", "phong:s=30", "--factor-resolution", "24", "--res", "32x32"])
            .args(["-K", "30", "--bright", bright, "-q", "--json", "--compare"])
            .arg(&reference)
            .assert()
            .success()
            .get_output()
            .stdout
            .clone();
        summary(&out)
    };
    let (apart, paper) = (run("auto"), run("off"));
    let (a, p) = (apart.metrics.unwrap(), paper.metrics.unwrap());
    let share = apart.bright.expect("the sun is split off");
    assert!(share.texels > 0 && share.energy_fraction > 0.5, "{share:?}");
    assert!(paper.bright.is_none());
    assert!(a.rel_error < p.rel_error / 5.0, "apart {} vs paper {}", a.rel_error, p.rel_error);
    assert_eq!(a.negative_fraction, 0.0);
}

#[test]
fn render_obj_without_normals_is_shaded_with_computed_normals_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "white.exr", 32, 16, |_| 1.0);
    let obj = dir.path().join("tet.obj");
    std::fs::write(
        &obj,
        "v 0 0 1\nv 1 0 -0.5\nv -0.5 0.8 -0.5\nv -0.5 -0.8 -0.5\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n",
    )
    .unwrap();
    let out = dir.path().join("t.exr");
    bin("render")
        .arg(&env)
        .args(["--scene"])
        .arg(&obj)
        .args(["--shading", "irradiance", "--res", "16x16", "-o"])
        .arg(&out)
        .assert()
        .success()
        .stderr(contains("no vertex normals").and(contains("computed")));
    // Lambert albedo 1 in a white furnace: every object pixel is 1 whatever its normal.
    let c = centre(&read_image(&out).unwrap(), 2);
    assert!((c[0] - 1.0).abs() < 1e-3, "{c:?}");
}

#[test]
fn render_bad_input_exits_2_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "white.exr", 32, 16, |_| 1.0);
    let out = dir.path().join("never.exr");
    // Malformed files (OBJ, documents) are in testdata/bad/cli (tests/conventions.rs).
    bin("render")
        .arg(&env)
        .args(["--scene", "/nonexistent/x.obj", "-o"])
        .arg(&out)
        .assert()
        .code(2)
        .stderr(contains("x.obj"));
    // An SHRM document for another BRDF, and one whose EXR has the wrong size.
    let chain = Chain::prefilter(dir.path(), &env, "phong:s=8", "p.shrm", &["--order", "8,0"]);
    let doc = &chain.document;
    bin("render")
        .arg(&env)
        .args(["--shading", "shrm", "--brdf", "phong:s=30", "--shrm"])
        .arg(doc)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(contains("phong:s=8"));
    let text = std::fs::read_to_string(doc).unwrap().replace("\"width\": ", "\"width\": 1");
    let bad_doc = dir.path().join("bad.shrm.json");
    std::fs::write(&bad_doc, text).unwrap();
    bin("render")
        .arg(&env)
        .args(["--shading", "shrm", "--brdf", "phong:s=8", "--shrm"])
        .arg(&bad_doc)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(contains("does not match"));
    // An SHRM of another layout (a horizontal cross): render reads lat-long SHRMs.
    let args = ["--order", "8,0", "--output-layout", "cross-horizontal"];
    Chain::prefilter(dir.path(), &env, "phong:s=8", "cross.shrm", &args)
        .render()
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(contains("cross.shrm.json").and(contains("layout")));
    // A reference of another size.
    let small = dir.path().join("small.exr");
    write_image(&small, &RgbImage::new(8, 8), 0.0).unwrap();
    bin("render").arg(&env).args(["--res", "16x16", "--compare"]).arg(&small).arg("-o").arg(&out).assert().code(2);
    assert!(!out.exists(), "a failed run left {}", out.display());
}

/// Runs factor-brdf for `brdf` at resolution 32, storing `terms` factors; returns the document.
fn factor_file(dir: &Path, name: &str, brdf: &str, cosine: bool, terms: usize) -> PathBuf {
    let doc = dir.join(format!("{name}.json"));
    let mut cmd = bin("factor-brdf");
    cmd.arg(brdf).args(["--resolution", "32", "--terms", &terms.to_string(), "-q", "--factors"]);
    cmd.arg(dir.join(format!("{name}.exr"))).arg("-o").arg(&doc);
    if cosine {
        cmd.arg("--cosine");
    }
    cmd.assert().success();
    doc
}

#[test]
fn render_factored_reads_factor_brdf_files_with_or_without_the_cosine_folded_in() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "sky.exr", 128, 64, smooth);
    let reference = render_reference(dir.path(), &env, &["--brdf", "phong:s=8"], "24x24");
    let factored = |extra: &[&str]| -> f64 {
        let out = bin("render")
            .arg(&env)
            .args(["--shading", "factored", "--brdf", "phong:s=8", "--res", "24x24", "--normal-table", "32x16"])
            .args(["-q", "--json", "--compare"])
            .arg(&reference)
            .args(extra)
            .assert()
            .success()
            .get_output()
            .stdout
            .clone();
        rel_error(&out)
    };
    // The stored factors (f32) give the render of the in-process factorization (f64).
    let folded = factor_file(dir.path(), "folded", "phong:s=8", true, 20);
    let from_file = factored(&["-K", "20", "--factors", folded.to_str().unwrap()]);
    let in_process = factored(&["-K", "20", "--factor-resolution", "32"]);
    assert!((from_file - in_process).abs() < 1e-6, "file {from_file} vs in-process {in_process}");
    // The paper's factorization of ρ alone, with the cosine in the transport (eq. 3), converges
    // to the reference too.
    let plain = factor_file(dir.path(), "plain", "phong:s=8", false, 40);
    let errors: Vec<f64> =
        [3, 10, 40].iter().map(|k| factored(&["-K", &k.to_string(), "--factors", plain.to_str().unwrap()])).collect();
    assert!(errors.windows(2).all(|w| w[1] < w[0]), "{errors:?}");
    assert!(errors[2] < 0.05, "K = 40 without the folded cosine: {errors:?}");
    // Lambert is rank one: ρ = albedo/π, so one term in a white furnace gives the albedo.
    let white = write_env(dir.path(), "white.exr", 64, 32, |_| 1.0);
    let lambert = factor_file(dir.path(), "lambert", "lambert:albedo=0.5", false, 1);
    let out = dir.path().join("l.exr");
    bin("render")
        .arg(&white)
        .args(["--shading", "factored", "--brdf", "lambert:albedo=0.5", "-K", "1", "--res", "24x24", "-q"])
        .args(["--normal-table", "16x8"])
        .arg("--factors")
        .arg(&lambert)
        .arg("-o")
        .arg(&out)
        .assert()
        .success();
    let c = centre(&read_image(&out).unwrap(), 6);
    assert!((c[0] - 0.5).abs() < 5e-3, "lambert furnace from a factor file: {c:?}");
}

#[test]
fn render_factored_rejects_a_factorization_that_does_not_fit() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "white.exr", 32, 16, |_| 1.0);
    let doc = factor_file(dir.path(), "p", "phong:s=8", true, 4);
    let out = dir.path().join("never.exr");
    let run = |brdf: &str, extra: &[&str], doc: &Path, needle: &str| {
        bin("render")
            .arg(&env)
            .args([
                "--shading",
                "factored",
                "--brdf",
                brdf,
                "--res",
                "8x8",
                "--normal-table",
                "16x8",
                "-q",
                "--factors",
            ])
            .arg(doc)
            .args(extra)
            .arg("-o")
            .arg(&out)
            .assert()
            .code(2)
            .stderr(contains(needle));
        assert!(!out.exists(), "no output after {needle}");
    };
    run("phong:s=30", &["-K", "4"], &doc, "phong:s=8");
    run("phong:s=8", &["-K", "5"], &doc, "holds 4 terms");
    run("phong:s=8", &["-K", "4", "--factor-resolution", "64"], &doc, "another resolution");
    // The document's EXR replaced by a factorization of another resolution.
    let coarse = dir.path().join("coarse.json");
    bin("factor-brdf")
        .args(["phong:s=8", "--resolution", "16", "--terms", "4", "-q", "--cosine", "--factors"])
        .arg(dir.path().join("p.exr"))
        .arg("-o")
        .arg(&coarse)
        .assert()
        .success();
    run("phong:s=8", &["-K", "4"], &doc, "another resolution");
    // A document without a factor file.
    let bare = dir.path().join("bare.json");
    bin("factor-brdf").args(["phong:s=8", "--resolution", "8", "-q", "-o"]).arg(&bare).assert().success();
    run("phong:s=8", &["-K", "1"], &bare, "--factors FILE.exr");
}

#[test]
fn render_panel_places_this_render_where_an_item_says_dash() {
    let dir = tempfile::tempdir().unwrap();
    let env = write_env(dir.path(), "white.exr", 32, 16, |_| 1.0);
    let black = dir.path().join("black.exr");
    write_image(&black, &RgbImage::new(16, 16), 0.0).unwrap();
    // Brightness at the centre of cell `i` of two: cells of equal width (the widest of image
    // and label) between 8-pixel gutters, images centred in them, 8 pixels from the top.
    let cell_centre = |png: &Path, i: u32| -> u8 {
        let img = image::open(png).unwrap().to_rgb8();
        let cell_w = (img.width() - 8) / 2 - 8;
        img.get_pixel(8 + i * (cell_w + 8) + cell_w / 2, 8 + 8)[0]
    };
    let panel = |items: &[&str]| -> PathBuf {
        let png = dir.path().join("panel.png");
        let mut cmd = bin("render");
        cmd.arg(&env).args(["--brdf", "lambert", "--shading", "irradiance", "--res", "16x16", "-q", "--panel"]);
        cmd.arg(&png);
        for item in items {
            cmd.arg("--panel-item").arg(item);
        }
        cmd.assert().success();
        png
    };
    // Default: the items, then this render (a white furnace sphere: 1.0).
    let png = panel(&[&format!("black={}", black.display())]);
    assert!(cell_centre(&png, 0) < 10 && cell_centre(&png, 1) > 200);
    let width = image::open(&png).unwrap().width();
    // `LABEL=-` puts this render first (under its default label here); it is not repeated at the
    // end: the panel has the same two cells.
    let png = panel(&["irradiance F=2=-", &format!("black={}", black.display())]);
    assert!(cell_centre(&png, 0) > 200 && cell_centre(&png, 1) < 10);
    assert_eq!(image::open(&png).unwrap().width(), width, "two cells, not three");
    bin("render")
        .arg(&env)
        .args(["--res", "16x16", "-q", "--panel"])
        .arg(dir.path().join("p.png"))
        .args(["--panel-item", "a=-", "--panel-item", "b=-"])
        .assert()
        .code(2)
        .stderr(contains("once"));
}

#[test]
fn shipped_meshes_load_and_only_the_concave_ones_shadow_themselves() {
    use prtkit::factor::{Domain, Grid};
    use prtkit::mesh::Mesh;
    use prtkit::progress::NoProgress;
    use prtkit::render::factored::Transport;
    use prtkit::render::Scene;
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes");
    let grid = Grid { n: 12, domain: Domain::Hemisphere };
    let mut fractions = Vec::new();
    for name in ["sphere.obj", "bowl.obj", "torus-knot.obj"] {
        let mesh = Mesh::load(&dir.join(name)).unwrap();
        // Stored normals point the way the faces wind: within 10° of the area-weighted normals.
        let computed = Mesh::new(mesh.positions.clone(), None, mesh.triangles.clone()).unwrap();
        let worst = mesh.normals.iter().zip(&computed.normals).map(|(a, b)| a.dot(*b)).fold(1.0, f64::min);
        assert!(worst > 10f64.to_radians().cos(), "{name}: normals disagree with the winding ({worst})");
        let transport = Transport::mesh(&Scene::Mesh(Box::new(mesh)), &grid, &NoProgress);
        fractions.push(transport.visible_fraction(grid.len()));
    }
    // A convex polytope lies below every vertex's tangent plane: nothing in the upper hemisphere
    // is blocked. The bowl's inner wall and the knot's loops block part of it.
    assert_eq!(fractions[0], 1.0, "{fractions:?}");
    assert!(fractions[1] < 0.9 && fractions[2] < 0.95, "{fractions:?}");
}

#[test]
fn render_irradiance_window_nonneg_removes_the_negative_lobes_of_a_point_light() {
    // One bright texel on black: its order-4 irradiance rings negative over the dark half
    // (the clamped cosine truncated at l = 4). The default `nonneg` window finds the gentlest
    // heat window that leaves no object pixel negative, and says so; `none` keeps the rings.
    let dir = tempfile::tempdir().unwrap();
    let spot = DVec3::new(0.4, -0.5, 0.3).normalize();
    let env = write_env(dir.path(), "spot.exr", 128, 64, |d| if d.dot(spot) > 0.998 { 5000.0 } else { 0.0 });
    let object_negatives = |path: &Path| {
        let img = read_image(path).unwrap();
        img.pixels.iter().filter(|p| p.iter().any(|&v| v < 0.0)).count()
    };
    let mut negatives = Vec::new();
    for window in ["none", "nonneg", "hann"] {
        let out = dir.path().join(format!("{window}.exr"));
        let base = ["--shading", "irradiance", "--brdf", "lambert", "-F", "4", "--res", "48x48", "--json", "-q"];
        let stdout = bin("render").arg(&env).args(base).args(["--window", window, "-o"]).arg(&out).output().unwrap();
        assert!(stdout.status.success());
        let report = summary(&stdout.stdout).window.expect("irradiance reports its window");
        assert_eq!(report.kind.name(), window);
        if window == "nonneg" {
            let t = report.t.unwrap();
            assert!(t > 0.0 && t < 1.0, "t = {t}");
        }
        negatives.push(object_negatives(&out));
    }
    assert!(negatives[0] > 20, "the raw order-4 irradiance is negative over the dark half: {negatives:?}");
    assert_eq!(negatives[1], 0, "nonneg leaves no negative pixel: {negatives:?}");
    // Hann keeps a kernel with negative lobes; its guard leaves no negative pixel either.
    assert_eq!(negatives[2], 0, "hann is guarded: {negatives:?}");
    // A smooth sky needs no window: nonneg keeps the raw render (t = 0), bit for bit.
    let sky = write_env(dir.path(), "sky.exr", 64, 32, smooth);
    let run = |window: &str, name: &str| {
        let out = dir.path().join(name);
        let args = ["--shading", "irradiance", "--brdf", "lambert", "--res", "32x32", "--json", "-q", "--window"];
        let stdout = bin("render").arg(&sky).args(args).arg(window).arg("-o").arg(&out).output().unwrap();
        (summary(&stdout.stdout).window.unwrap(), read_image(&out).unwrap())
    };
    let ((raw_report, raw), (kept_report, kept)) = (run("none", "a.exr"), run("nonneg", "b.exr"));
    assert_eq!((raw_report.t, kept_report.t), (None, Some(0.0)));
    assert_eq!(raw.pixels, kept.pixels);
    // Only the SH modes window.
    bin("render")
        .arg(&sky)
        .args(["--shading", "reference", "--window", "hann", "--res", "8x8", "-o"])
        .arg(dir.path().join("no.exr"))
        .assert()
        .code(2)
        .stderr(contains("--window is for --shading irradiance and shrm"));
    assert!(!dir.path().join("no.exr").exists());
}

#[test]
fn render_shrm_window_nonneg_removes_negative_pixels_of_a_view_dependent_shrm() {
    // A Torrance-Sparrow σ = 0.3 SHRM of Grace (P_B = 6): its raw view bands make some pixels
    // of the sphere negative (measured 1.8 %); the default window on the view bands leaves none.
    let probe = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/testdata/envmaps/grace_probe_250.pfm");
    if !probe.exists() {
        eprintln!("skipping: {} is absent", probe.display());
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let doc = dir.path().join("ts.json");
    let brdf = ["--brdf", "torrance-sparrow:sigma=0.3"];
    bin("prefilter")
        .arg(&probe)
        .args(brdf)
        .args(["--size", "128x64", "-q", "--shrm"])
        .arg(dir.path().join("ts.exr"))
        .arg("-o")
        .arg(&doc)
        .assert()
        .success();
    let mut found = Vec::new();
    for window in ["none", "nonneg"] {
        let out = dir.path().join(format!("{window}.exr"));
        let stdout = bin("render")
            .arg(&probe)
            .args(brdf)
            .args(["--shading", "shrm", "--res", "64x64", "--json", "-q", "--window", window, "--shrm"])
            .arg(&doc)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        assert!(stdout.status.success());
        let t = summary(&stdout.stdout).window.unwrap().t;
        let negatives = read_image(&out).unwrap().pixels.iter().filter(|p| p.iter().any(|&v| v < 0.0)).count();
        found.push((t, negatives));
    }
    assert!(found[0].0.is_none() && found[0].1 > 0, "raw view bands: {found:?}");
    assert!(found[1].0.unwrap() > 0.0 && found[1].1 == 0, "nonneg: {found:?}");
}

#[test]
fn render_env_rotation_turns_the_background_with_the_lighting() {
    // `--env-rotation` turns the environment, L'(ω) = L(R⁻¹ω): a background pixel along the
    // camera ray d must show the stored map along R⁻¹d, as the object is lit, not along d.
    use prtkit::envmap::EnvMap;
    use prtkit::progress::NoProgress;
    use prtkit::render::stage::{run, Config, Shading};
    use prtkit::render::{Camera, Scene};
    let env = EnvMap::latlong(common::sky_image(64, 32)).unwrap();
    let camera = Camera::look_at(DVec3::new(0.0, -4.0, 1.0), DVec3::ZERO, 60.0, 32, 32).unwrap();
    let degrees = 37.0;
    let config = Config {
        brdf: prtkit::brdf::Brdf::parse("lambert").unwrap(),
        shading: Shading::Reference { integrand: prtkit::render::reference::Integrand::BrdfCosine },
        camera,
        env_rotation: degrees,
        compare: None,
        panel: None,
        label: None,
        exposure: 0.0,
        output_name: None,
        args: Vec::new(),
    };
    let frame = run(&config, &env, &Scene::unit_sphere(), &NoProgress).unwrap().frame;
    let from_turned = glam::DMat3::from_rotation_z(-f64::to_radians(degrees));
    let (mut background, mut moved) = (0, 0);
    for y in 0..32 {
        for x in 0..32 {
            if frame.mask[y * 32 + x] {
                continue;
            }
            let d = camera.ray(x, y);
            let (got, want, stored) = (frame.image.get(x, y), env.lookup(from_turned * d), env.lookup(d));
            for c in 0..3 {
                assert!((got[c] - want[c]).abs() <= 1e-5 * want[c].abs().max(1.0), "({x}, {y}): {got:?} vs {want:?}");
            }
            background += 1;
            moved += usize::from((stored[0] - want[0]).abs() > 1e-2);
        }
    }
    // The check has teeth: most of the background differs from the unturned map.
    assert!(background > 300 && moved > background / 2, "{background} background pixels, {moved} moved");
}
