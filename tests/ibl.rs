//! The `ibl` stage: where the faces land, seams, accuracy against an independent brute-force
//! integral, SH irradiance against the addition theorem, the files read back by independent
//! readers (`ktx2`, `ddsfile`, naga), and bad input refused with nothing half-written.

mod common;

use common::{cmd, latlong, sky, sky_pfm};
use glam::{DMat3, DVec3};
use prtkit::brdf::ggx::SplitSumLobe;
use prtkit::envmap::{EnvMap, Face, FACES};
use prtkit::ibl::cube::{face_direction, texel_coordinate, texel_direction, CubeMap};
use prtkit::ibl::manifest::{IblBody, ShBody};
use prtkit::ibl::stage::{self, Config, MethodChoice, Up};
use prtkit::io::document::parse_document;
use prtkit::progress::NoProgress;
use prtkit::sphere::LatLong;
use std::f64::consts::PI;

fn small(size: usize, min_size: usize) -> Config {
    Config { size, min_size, irradiance_size: 8, samples: 0, dfg_size: 8, ..Config::default() }
}

/// Face, row, column of the brightest texel (red channel).
fn brightest(cube: &CubeMap) -> (Face, usize, usize) {
    let n = cube.size();
    let mut best = (0.0f32, Face::PosX, 0, 0);
    for face in FACES {
        for r in 0..n {
            for c in 0..n {
                let v = cube.get(face, r, c)[0];
                if v > best.0 {
                    best = (v, face, r, c);
                }
            }
        }
    }
    (best.1, best.2, best.3)
}

#[test]
fn a_bright_spot_lands_on_the_face_engines_expect_at_every_level() {
    // Black but for a spot around a prtkit direction; every level's brightest texel must be on
    // the face that direction selects in the output frame.
    let cases: [(DVec3, Config, Face); 6] = [
        (DVec3::X, small(16, 4), Face::PosX),
        (DVec3::Z, small(16, 4), Face::PosY),
        (DVec3::Y, small(16, 4), Face::NegZ),
        (DVec3::Z, Config { up: Up::Z, ..small(16, 4) }, Face::PosZ),
        (DVec3::Y, Config { mirror: true, ..small(16, 4) }, Face::PosZ),
        (DVec3::X, Config { rotate_degrees: 90.0, ..small(16, 4) }, Face::NegZ),
    ];
    for (target, config, face) in cases {
        let env =
            EnvMap::latlong(latlong(64, 32, |d| if d.dot(target) > 0.99 { [100.0; 3] } else { [0.0; 3] })).unwrap();
        let out = stage::run(&config, &env, &NoProgress).unwrap();
        for level in out.specular.levels().iter().chain(std::iter::once(&out.irradiance)) {
            let (f, r, c) = brightest(level);
            let n = level.size();
            assert_eq!(f, face, "{target} {:?}: level {n}² brightest at {f:?} ({r},{c})", config.up);
            // …at the face's centre.
            assert!(r.abs_diff(n / 2) <= 1 && c.abs_diff(n / 2) <= 1, "{target}: ({r},{c}) of {n}");
        }
    }
}

#[test]
fn adjacent_faces_agree_at_every_level() {
    let out = stage::run(&small(32, 4), &sky(128, 64), &NoProgress).unwrap();
    for level in out.specular.levels() {
        let n = level.size();
        let (mut seam, mut inside) = (0.0f32, 0.0f32);
        for face in FACES {
            for k in 0..n {
                for (row, col, inner, beyond) in [
                    (0, k, (1.min(n - 1), k), (texel_coordinate(n, k), -1.0 - 1.0 / n as f64)),
                    (n - 1, k, (n.saturating_sub(2), k), (texel_coordinate(n, k), 1.0 + 1.0 / n as f64)),
                    (k, 0, (k, 1.min(n - 1)), (-1.0 - 1.0 / n as f64, texel_coordinate(n, k))),
                    (k, n - 1, (k, n.saturating_sub(2)), (1.0 + 1.0 / n as f64, texel_coordinate(n, k))),
                ] {
                    let v = level.get(face, row, col);
                    let across = level.lookup_nearest(face_direction(face, beyond.0, beyond.1));
                    let next = level.get(face, inner.0, inner.1);
                    seam = seam.max((v[0] - across[0]).abs() / v[0].max(1e-3));
                    inside = inside.max((v[0] - next[0]).abs() / v[0].max(1e-3));
                }
            }
        }
        // Across an edge the texel centres are no farther apart than within a face.
        assert!(seam <= 1.5 * inside + 1e-6, "{n}²: seam {seam} vs inside {inside}");
    }
}

/// The split-sum integral of a lat-long map by brute force: every texel split into 12 × 12
/// cells of equal Δz × Δφ (equal solid angle), the kernel at each cell's centre. Nothing shared
/// with the bake or with the reference integrator but the kernel itself.
fn brute_force(img: &prtkit::io::RgbImage, lobe: &SplitSumLobe, axis: DVec3) -> [f64; 3] {
    let (w, h) = (img.width, img.height);
    let s = 12;
    let mut acc = [0.0; 3];
    for y in 0..h {
        let (z0, z1) = ((PI * y as f64 / h as f64).cos(), (PI * (y + 1) as f64 / h as f64).cos());
        for x in 0..w {
            let mut k = 0.0;
            for j in 0..s {
                let z = z0 + (z1 - z0) * (j as f64 + 0.5) / s as f64;
                for i in 0..s {
                    let phi = 2.0 * PI * (x as f64 + (i as f64 + 0.5) / s as f64) / w as f64;
                    let d = prtkit::sphere::direction(z.clamp(-1.0, 1.0).acos(), phi);
                    k += lobe.kernel(axis.dot(d));
                }
            }
            let omega = 2.0 * PI / w as f64 * (z0 - z1) / (s * s) as f64;
            let l = img.get(x, y);
            for c in 0..3 {
                acc[c] += k * omega * l[c] as f64;
            }
        }
    }
    acc
}

#[test]
fn levels_match_a_brute_force_integral_within_the_targets() {
    // The sky of the tests (a sun 40× the sky, a bright horizon) at 64 × 32; a 32² chain with
    // levels r = 0, 1/3, 2/3, 1. Every texel of a fixed sample against the brute-force integral:
    // RMS within 1 %, none beyond 5 %, no negative texel.
    let env = sky(64, 32);
    let img = env.image().clone();
    for method in [MethodChoice::Auto, MethodChoice::Zonal, MethodChoice::Angular] {
        let config = Config { method, ..small(32, 4) };
        let out = stage::run(&config, &env, &NoProgress).unwrap();
        let env_from_cube = config.world_from_prtkit().transpose();
        for (k, level) in out.specular.levels().iter().enumerate().skip(1) {
            let r = k as f64 / 3.0;
            let lobe = SplitSumLobe::new(r).unwrap();
            let n = level.size();
            let (mut sum2, mut count, mut worst) = (0.0, 0, 0.0f64);
            for i in (0..6 * n * n).step_by(13) {
                let (face, row, col) = (FACES[i / (n * n)], (i / n) % n, i % n);
                let want = brute_force(&img, &lobe, env_from_cube * texel_direction(face, n, row, col));
                let got = level.get(face, row, col);
                let diff = (0..3).map(|c| (got[c] as f64 - want[c]).powi(2)).sum::<f64>().sqrt();
                let rel = diff / want.iter().map(|v| v * v).sum::<f64>().sqrt();
                sum2 += rel * rel;
                count += 1;
                worst = worst.max(rel);
            }
            let rms = (sum2 / count as f64).sqrt();
            assert!(rms < 0.01 && worst < 0.05, "{method:?} level {k} (r={r:.3}): RMS {rms}, max {worst}");
            assert!(level.texels().iter().all(|&v| v >= 0.0));
        }
    }
}

#[test]
fn sh_irradiance_equals_the_brute_force_order_two_irradiance() {
    // E₂(n) = Σ_t L_t Ω_t Σ_{l≤2} (2l+1)/(4π) Â_l P_l(n·ω_t): the order-2 irradiance by the
    // addition theorem, in prtkit's frame, with no SH basis, no rotation and no frame matrix of
    // the stage's. The shader form evaluated at M n must give E₂(n)/π.
    let env = sky(64, 32);
    let img = env.image();
    let grid = LatLong::new(64, 32);
    let a_hat = [PI, 2.0 * PI / 3.0, PI / 4.0];
    let e2 = |n: DVec3| -> [f64; 3] {
        let mut e = [0.0; 3];
        for y in 0..32 {
            for x in 0..64 {
                let c = n.dot(grid.texel_direction(x, y));
                let p = [1.0, c, 0.5 * (3.0 * c * c - 1.0)];
                let k: f64 = (0..3).map(|l| (2 * l + 1) as f64 / (4.0 * PI) * a_hat[l] * p[l]).sum();
                let l = img.get(x, y);
                for ch in 0..3 {
                    e[ch] += l[ch] as f64 * grid.row_solid_angle(y) * k;
                }
            }
        }
        e
    };
    for config in
        [small(8, 8), Config { rotate_degrees: 37.0, mirror: true, ..small(8, 8) }, Config { up: Up::Z, ..small(8, 8) }]
    {
        let out = stage::run(&config, &env, &NoProgress).unwrap();
        let m: DMat3 = config.world_from_prtkit();
        for n in [DVec3::X, DVec3::Z, DVec3::new(0.3, -0.7, 0.2), DVec3::new(-0.5, 0.1, -0.8)] {
            let n = n.normalize();
            let want = e2(n).map(|v| v / PI);
            let got = out.sh.eval(m * n);
            for ch in 0..3 {
                assert!(
                    (got[ch] - want[ch]).abs() <= 1e-4 * want[ch].abs(),
                    "{n} ch {ch}: {} vs {}",
                    got[ch],
                    want[ch]
                );
            }
        }
    }
}

#[test]
fn outputs_are_deterministic_across_thread_counts() {
    let env = sky(64, 32);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| stage::run(&small(16, 4), &env, &NoProgress).unwrap())
    };
    let (one, two) = (run(1), run(2));
    for (a, b) in one.specular.levels().iter().zip(two.specular.levels()) {
        assert!(a.texels() == b.texels(), "a {}² specular level differs between 1 and 2 threads", a.size());
    }
    assert!(one.irradiance.texels() == two.irradiance.texels(), "the irradiance cube differs");
    assert!(one.dfg == two.dfg, "the DFG table differs");
    assert!(one.shaders() == two.shaders(), "the SH snippets differ");
}

fn ibl_dir(args: &[&str]) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let env = sky_pfm(dir.path(), 64, 32);
    let out = dir.path().join("out");
    cmd("ibl").arg(&env).arg("-o").arg(&out).args(args).assert().success();
    (dir, out)
}

#[test]
fn files_read_back_with_independent_readers() {
    let (_tmp, out) = ibl_dir(&["--size", "32", "--min-size", "4", "--samples", "16", "-q"]);
    let bytes = std::fs::read(out.join("specular.ktx2")).unwrap();
    let reader = ktx2::Reader::new(&bytes[..]).unwrap();
    let h = reader.header();
    assert_eq!((h.pixel_width, h.pixel_height, h.face_count, h.level_count), (32, 32, 6, 4));
    assert_eq!(h.format, Some(ktx2::Format::R16G16B16A16_SFLOAT));
    for (p, level) in reader.levels().enumerate() {
        let n = 32 >> p;
        assert_eq!(level.data.len(), 6 * n * n * 8, "level {p}");
    }
    let bytes = std::fs::read(out.join("irradiance.ktx2")).unwrap();
    let h = ktx2::Reader::new(&bytes[..]).unwrap().header();
    assert_eq!((h.pixel_width, h.face_count, h.level_count), (32, 6, 1));
    let bytes = std::fs::read(out.join("dfg.ktx2")).unwrap();
    let h = ktx2::Reader::new(&bytes[..]).unwrap().header();
    assert_eq!((h.pixel_width, h.pixel_height, h.face_count), (128, 128, 1));
    assert_eq!(h.format, Some(ktx2::Format::R16G16_SFLOAT));

    // The manifest and the SH document read back into the library's types.
    let text = std::fs::read_to_string(out.join("ibl.json")).unwrap();
    let doc = parse_document::<IblBody>(&text, "prtkit.ibl", 1).unwrap();
    let b = &doc.body;
    // The conventions block names the frame the files are in, as frame.up does.
    assert_eq!(b.frame.up, "y");
    assert!(doc.conventions.frame.starts_with("glTF world, +Y up"), "{}", doc.conventions.frame);
    assert_eq!(doc.conventions.input_orientation.as_deref(), Some("as stored"));
    assert!(!b.frame.flip_vertical);
    assert_eq!(b.frame.faces, ["+X", "-X", "+Y", "-Y", "+Z", "-Z"]);
    assert_eq!(b.frame.world_from_prtkit, [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]);
    let levels = &b.specular.levels;
    assert_eq!(levels.iter().map(|l| l.size).collect::<Vec<_>>(), [32, 16, 8, 4]);
    assert_eq!(levels.iter().map(|l| l.level).collect::<Vec<_>>(), [0, 1, 2, 3]);
    assert_eq!(levels[0].method, "resample");
    for (k, l) in levels.iter().enumerate().skip(1) {
        assert!((l.roughness - k as f64 / 3.0).abs() < 1e-12);
        assert!(l.method == "zonal" || l.method == "angular", "{}", l.method);
        let (rms, max) = (l.rms_rel_error.unwrap(), l.max_rel_error.unwrap());
        assert!(rms < 0.01 && max < 0.05 && l.samples >= 16, "{l:?}");
        assert!(l.min_value >= 0.0);
    }
    let sh = std::fs::read_to_string(out.join("sh.json")).unwrap();
    let sh = parse_document::<ShBody>(&sh, "prtkit.ibl-sh", 1).unwrap();
    assert_eq!((sh.body.coefficients.len(), sh.body.radiance.len()), (9, 9));

    // The shader snippets compile (naga's GLSL and WGSL front ends, then its validator).
    let glsl = std::fs::read_to_string(out.join("sh.glsl")).unwrap();
    let src = format!(
        "#version 450\n{glsl}layout(location = 0) in vec3 n;\nlayout(location = 0) out vec4 o;\nvoid main() {{ o = vec4(prtkitIrradiance(normalize(n)), 1.0); }}\n"
    );
    let module = naga::front::glsl::Frontend::default()
        .parse(&naga::front::glsl::Options::from(naga::ShaderStage::Fragment), &src)
        .unwrap_or_else(|e| panic!("{e:?}\n{src}"));
    let mut validator =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    validator.validate(&module).unwrap();
    let wgsl = std::fs::read_to_string(out.join("sh.wgsl")).unwrap();
    let src = format!(
        "{wgsl}@fragment fn main(@location(0) n: vec3<f32>) -> @location(0) vec4<f32> {{ return vec4<f32>(prtkit_irradiance(normalize(n)), 1.0); }}\n"
    );
    let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
    validator.validate(&module).unwrap();
    let hlsl = std::fs::read_to_string(out.join("sh.hlsl")).unwrap();
    assert!(hlsl.contains("float3 prtkitIrradiance(float3 n)") && hlsl.contains("E(n)/pi"));
}

#[test]
fn dds_container_and_other_formats() {
    let (_tmp, out) = ibl_dir(&[
        "--size",
        "16",
        "--min-size",
        "4",
        "--samples",
        "0",
        "--container",
        "dds",
        "--format",
        "e5b9g9r9",
        "-q",
    ]);
    let dds = ddsfile::Dds::read(&mut std::fs::File::open(out.join("specular.dds")).unwrap()).unwrap();
    assert_eq!((dds.get_width(), dds.get_num_mipmap_levels()), (16, 3));
    assert_eq!(dds.get_dxgi_format(), Some(ddsfile::DxgiFormat::R9G9B9E5_SharedExp));
    assert!(out.join("dfg.dds").exists() && out.join("irradiance.dds").exists());
    assert!(!out.join("specular.ktx2").exists());
}

#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let env = sky_pfm(dir.path(), 64, 32);
    let out = dir.path().join("out");
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, b"x").unwrap();
    let cases: [(&[&str], &str); 5] = [
        (&["--size", "100"], "power of two"),
        (&["--size", "64", "--min-size", "128"], "--min-size 128 is larger than --size 64"),
        (&["--format", "rgb8"], "rgb8"),
        (&["--min-size", "0"], "power of two"),
        (&["--clamp", "0"], "--clamp 0 must be positive"),
    ];
    for (args, message) in cases {
        cmd("ibl").arg(&env).arg("-o").arg(&out).args(args).assert().code(2).stderr(predicates::str::contains(message));
        assert!(!out.exists(), "{args:?} left {}", out.display());
    }
    // An output directory that cannot be made: under a regular file.
    let under_file = blocker.join("out");
    cmd("ibl").arg(&env).arg("-o").arg(&under_file).assert().code(2).stderr(predicates::str::contains("error"));
    // An existing non-empty directory is refused, and left as it was.
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("keep"), b"mine").unwrap();
    cmd("ibl")
        .arg(&env)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(2)
        .stderr(predicates::str::contains("not an empty directory"));
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1);
    // A map too coarse for order-2 SH (2 × 1: φ holds no cos 2φ) is refused, naming it.
    let coarse = common::write_pfm(dir.path(), "coarse.pfm", &common::sky_image(2, 1));
    cmd("ibl").arg(&coarse).arg("-o").arg(dir.path().join("coarse")).assert().code(2).stderr(
        predicates::str::contains("coarse.pfm: too coarse for the SH irradiance: order 2 is beyond what this 2x1"),
    );
    assert!(!dir.path().join("coarse").exists());
    // `-o -`: a bake is a directory, never a directory named `-` (issue 34).
    cmd("ibl")
        .arg(&env)
        .args(["-o", "-"])
        .current_dir(dir.path())
        .assert()
        .code(2)
        .stderr(predicates::str::contains("a bake is a directory"));
    assert!(!dir.path().join("-").exists(), "made a directory named -");
}

/// Radiance above 65504 saturates in rgba16f: said on stderr with the count, the maximum and the
/// remedies; not said when the format holds it or --clamp brings it under (issue 34).
#[test]
fn values_a_format_cannot_hold_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let sun = DVec3::new(0.3, 0.2, 0.9).normalize();
    let image = latlong(64, 32, |d| if d.dot(sun) > 0.99 { [1e6; 3] } else { [1.0; 3] });
    let env = common::write_pfm(dir.path(), "sun.pfm", &image);
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut run = cmd("ibl");
        run.arg(&env).arg("-o").arg(&out).args(["--size", "16", "--min-size", "4", "--samples", "0"]).args(extra);
        common::stderr(run.assert().success().get_output())
    };
    let stderr = run("half", &[]);
    let note = stderr.lines().find(|l| l.contains("were saturated")).unwrap_or_else(|| panic!("no note: {stderr}"));
    let count: usize = note.split_whitespace().nth(1).and_then(|n| n.parse().ok()).unwrap_or(0);
    assert!(count > 0 && note.contains("above 65504, the largest rgba16f holds"), "{note}");
    assert!(note.contains("--clamp") && note.contains("--format rgba32f"), "{note}");
    for (name, extra) in [("full", &["--format", "rgba32f"][..]), ("clamped", &["--clamp", "60000"][..])] {
        let stderr = run(name, extra);
        assert!(!stderr.contains("saturated"), "{extra:?}: {stderr}");
    }
}
