//! `render --shading ibl`: the split sum read back from an `ibl` bake's KTX2 files against the
//! split sum of the exact integrals (the bake's own error) and against the glTF material
//! integrated over the environment (`render --shading reference`), and the `gltf` BRDF itself.

mod common;

use common::{cmd, latlong, sky_pfm};
use glam::DVec3;
use prtkit::brdf::models::GltfMaterial;
use prtkit::brdf::Brdf;
use prtkit::envmap::EnvMap;
use prtkit::ibl::dfg::split_sum_terms;
use prtkit::ibl::reference::Reference as SplitSumReference;
use prtkit::ibl::stage::{self, Config};
use prtkit::progress::NoProgress;
use prtkit::render::ibl::{ExactLobe, ExactSplitSum, IblBake, SplitSum, SplitSumLighting};
use prtkit::render::reference::{Integrand, Reference};
use prtkit::render::{Hit, Scene, Shade};
use std::f64::consts::PI;

/// Bakes `env` with `config` into a temporary directory; the manifest's path.
fn bake(env: &EnvMap, config: Config) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let out = stage::run(&config, env, &NoProgress).unwrap();
    // What `render --shading ibl` reads: the textures and the manifest.
    for (name, texture, format) in out.textures() {
        std::fs::write(dir.path().join(name), out.container.encode(&texture, format).unwrap()).unwrap();
    }
    let manifest = dir.path().join(prtkit::ibl::manifest::FILE);
    std::fs::write(&manifest, out.document.to_json()).unwrap();
    (dir, manifest)
}

fn gltf(spec: &str) -> (Brdf, GltfMaterial) {
    let brdf = Brdf::parse(spec).unwrap();
    let Brdf::Gltf(m) = brdf else { panic!("{spec} is not gltf") };
    (brdf, m)
}

fn hit(n: DVec3) -> Hit {
    Hit { p: n, n, triangle: None }
}

fn rel(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d: f64 = (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt();
    d / b.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// A smooth environment, different in every channel and direction: L = 1 + d (per axis).
fn smooth_env() -> EnvMap {
    EnvMap::latlong(latlong(256, 128, |d| [(1.0 + d.x) as f32, (1.0 + d.y) as f32, (1.0 + d.z) as f32])).unwrap()
}

#[test]
fn gltf_is_the_spec_mix_of_its_layers() {
    let (brdf, m) = gltf("gltf:base=0.9/0.5/0.2,metalness=0.3,roughness=0.45");
    assert_eq!(Brdf::parse(&brdf.spec()).unwrap().spec(), brdf.spec(), "canonical spec round trip");
    let ggx = Brdf::parse("ggx:roughness=0.45").unwrap();
    let (wi, wo) = (DVec3::new(0.3, -0.2, 0.93).normalize(), DVec3::new(-0.5, 0.1, 0.86).normalize());
    // glTF 2.0 Appendix B written out: mix(fresnel_mix(ior 1.5, diffuse, specular), conductor_fresnel(c, specular), m).
    let spec = ggx.eval(wi, wo)[0];
    let x = (1.0 - wo.dot((wi + wo).normalize())).powi(5);
    let fr = 0.04 + 0.96 * x;
    let got = brdf.eval(wi, wo);
    for (c, &base) in m.base.iter().enumerate() {
        let dielectric = (1.0 - fr) * base / PI + fr * spec;
        let metal = spec * (base + (1.0 - base) * x);
        let want = (1.0 - m.metalness) * dielectric + m.metalness * metal;
        assert!((got[c] - want).abs() < 1e-12 * want, "channel {c}: {} vs {want}", got[c]);
    }
    assert_eq!(brdf.eval(DVec3::new(0.0, 0.6, -0.8), wo), [0.0; 3], "below the surface");
    assert!(Brdf::parse("gltf:metalness=1.5").is_err());
    assert!(Brdf::parse("gltf:base=1/2").is_err());
    assert!(Brdf::parse("gltf:roughness=0").is_err());
    // glTF's defaults: white, metal, roughness 1.
    assert_eq!(Brdf::parse("gltf").unwrap().spec(), "gltf:base=1/1/1,metalness=1,roughness=1");
}

#[test]
fn the_split_sum_is_exact_under_uniform_light_and_matches_the_brdf_integral() {
    // Under L = 1 the prefiltered lobe and E/π are 1, so the split sum is F0·A + B plus the
    // diffuse: the BRDF's directional albedo up to the diffuse weighting (1 − F at each h
    // against 1 − (0.04 A + B)), which stays within 1 %.
    let env = EnvMap::latlong(latlong(256, 128, |_| [1.0; 3])).unwrap();
    let (_dir, manifest) = bake(&env, Config { size: 32, min_size: 4, samples: 0, ..Config::default() });
    let ibl = IblBake::load(&manifest).unwrap();
    let scene = Scene::unit_sphere();
    for spec in ["gltf:metalness=1,roughness=0.4", "gltf:base=0.8/0.6/0.3,metalness=0,roughness=0.6"] {
        let (brdf, m) = gltf(spec);
        let reference = Reference::new(&env, brdf, Integrand::BrdfCosine, &scene).unwrap();
        for n_dot_v in [1.0f64, 0.7, 0.4] {
            let wo = DVec3::new((1.0 - n_dot_v * n_dot_v).sqrt(), 0.0, n_dot_v);
            let got = SplitSum::new(&ibl, m).shade(&hit(DVec3::Z), wo);
            let t = split_sum_terms(n_dot_v, m.specular.roughness()).unwrap();
            let transmitted = 1.0 - (0.04 * t.scale + t.bias);
            let want: [f64; 3] = [0, 1, 2].map(|c| m.f0()[c] * t.scale + t.bias + m.diffuse_colour()[c] * transmitted);
            assert!(rel(got, want) < 0.01, "{spec} n.v={n_dot_v}: files {got:?} vs split sum {want:?}");
            let truth = reference.shade(&hit(DVec3::Z), wo);
            assert!(rel(got, truth) < 0.01, "{spec} n.v={n_dot_v}: split sum {got:?} vs BRDF integral {truth:?}");
        }
    }
}

#[test]
fn the_files_equal_the_exact_split_sum_in_every_direction() {
    // The bake's error alone: files (KTX2 read back, frame matrix, bilinear lookups, DFG table)
    // against the exact integrals, on the levels' roughness (0, 0.5, 1 for a 64² to 16² chain).
    let env = smooth_env();
    let (_dir, manifest) = bake(&env, Config { size: 64, min_size: 16, samples: 0, ..Config::default() });
    let ibl = IblBake::load(&manifest).unwrap();
    let reference = SplitSumReference::new(&env).unwrap();
    let irradiance = ExactLobe::new(&reference, 1.0).unwrap();
    let directions = [
        DVec3::X,
        -DVec3::Y,
        DVec3::Z,
        -DVec3::Z,
        DVec3::new(0.3, -0.5, 0.8).normalize(),
        DVec3::new(-0.7, 0.2, -0.1).normalize(),
    ];
    for roughness in [0.5, 1.0] {
        let lobe = ExactLobe::new(&reference, roughness).unwrap();
        let exact = ExactSplitSum { specular: &lobe, irradiance: &irradiance };
        for d in directions {
            let (got, want) = (ibl.prefiltered(d, roughness), exact.prefiltered(d, roughness));
            assert!(rel(got, want) < 0.005, "r={roughness} at {d}: {got:?} vs {want:?}");
            let (got, want) = (ibl.irradiance(d), exact.irradiance(d));
            assert!(rel(got, want) < 0.005, "E/π at {d}: {got:?} vs {want:?}");
        }
        let [a, b] = ibl.scale_bias(0.55, roughness);
        let [ea, eb] = exact.scale_bias(0.55, roughness);
        // At r = 1 the clamped lookup reads the last row, r = 1 − 1/(2N): 3e-3 away in A.
        assert!((a - ea).abs() < 5e-3 && (b - eb).abs() < 5e-3, "DFG at r={roughness}: ({a}, {b}) vs ({ea}, {eb})");
    }
}

#[test]
fn a_bright_direction_is_read_where_prtkit_put_it() {
    // A bright cap at prtkit's +Y (glTF's −Z after the frame change): the mirror level must
    // show it looking along prtkit's +Y, not along glTF's +Y or any other axis.
    let env = EnvMap::latlong(latlong(128, 64, |d| [if d.y > 0.95 { 50.0 } else { 1.0 }; 3])).unwrap();
    let (_dir, manifest) = bake(&env, Config { size: 32, min_size: 4, samples: 0, ..Config::default() });
    let ibl = IblBake::load(&manifest).unwrap();
    let at = |d: DVec3| ibl.prefiltered(d, 0.0)[0];
    assert!(at(DVec3::Y) > 40.0, "{}", at(DVec3::Y));
    for other in [DVec3::X, -DVec3::X, -DVec3::Y, DVec3::Z, -DVec3::Z] {
        assert!(at(other) < 1.5, "{other}: {}", at(other));
    }
}

#[test]
fn the_grid_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let env = sky_pfm(dir.path(), 128, 64);
    let out = dir.path().join("ibl");
    // Levels of roughness 0, 0.5 and 1: the grid's columns lie on levels.
    cmd("ibl").arg(&env).arg("-o").arg(&out).args(["--size", "32", "--min-size", "8", "-q"]).assert().success();
    let manifest = out.join("ibl.json");
    let panel = dir.path().join("grid.png");
    let run = cmd("render")
        .arg(&env)
        .args(["--shading", "ibl", "--ibl"])
        .arg(&manifest)
        .args(["--grid", "--grid-roughness", "0.5,1", "--grid-metalness", "0,1", "--brdf", "gltf:base=0.9/0.7/0.4"])
        .args(["--res", "24x24", "--json", "-q", "--panel"])
        .arg(&panel)
        .assert()
        .success();
    let summary: serde_json::Value = serde_json::from_slice(&run.get_output().stdout).unwrap();
    let cells = summary["grid"].as_array().unwrap();
    assert_eq!(cells.len(), 4);
    for c in cells {
        let bake = c["bake"]["rel_error"].as_f64().unwrap();
        let reference = c["reference"]["rel_error"].as_f64().unwrap();
        assert!(bake < 0.02, "{c}: the files against the exact split sum");
        assert!(bake < reference, "{c}: the split sum's own error is the larger");
        assert_eq!(c["bake"]["negative_fraction"].as_f64(), Some(0.0));
    }
    assert!(panel.exists());

    // Refused with exit 2 and nothing written: no bake, a material that is not gltf, a DDS bake.
    let bad = |args: &[&str]| {
        let png = dir.path().join("bad.png");
        cmd("render").arg(&env).args(args).arg("--png").arg(&png).assert().code(2);
        assert!(!png.exists(), "{args:?}");
    };
    let m = manifest.to_str().unwrap();
    bad(&["--shading", "ibl", "--brdf", "gltf"]);
    bad(&["--shading", "ibl", "--ibl", m, "--brdf", "ggx:roughness=0.5"]);
    bad(&["--shading", "ibl", "--ibl", m, "--brdf", "gltf", "--grid", "--grid-roughness", "0"]);
    bad(&["--grid"]);
    let dds = dir.path().join("dds");
    cmd("ibl")
        .arg(&env)
        .arg("-o")
        .arg(&dds)
        .args(["--size", "16", "--min-size", "4", "--container", "dds", "-q"])
        .assert()
        .success();
    bad(&["--shading", "ibl", "--ibl", dds.join("ibl.json").to_str().unwrap(), "--brdf", "gltf"]);
}

/// The manifest names its source map and that map's fingerprint: `--ibl DIR` finds the manifest,
/// and a bake given with another map (or the same map read the other way up) is refused with
/// exit 2, naming the manifest and the map it was baked from, before any pixel is shaded.
#[test]
fn a_bake_is_rendered_only_with_the_map_it_was_baked_from() {
    let dir = tempfile::tempdir().unwrap();
    let env = sky_pfm(dir.path(), 64, 32);
    let out = dir.path().join("ibl");
    cmd("ibl").arg(&env).arg("-o").arg(&out).args(["--size", "16", "--min-size", "4", "-q"]).assert().success();
    let manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("ibl.json")).unwrap()).unwrap();
    let hash = manifest["source_hash"].as_str().unwrap();
    assert_eq!(hash, common::sky(64, 32).content_hash(), "the fingerprint of the map as read");

    let render = |env: &std::path::Path, extra: &[&str]| {
        let png = dir.path().join("r.png");
        let _ = std::fs::remove_file(&png);
        let run = cmd("render")
            .arg(env)
            .args(["--shading", "ibl", "--ibl"])
            .arg(&out) // the directory stands for DIR/ibl.json
            .args(["--brdf", "gltf:roughness=0.5", "--res", "8x8", "-q", "--png"])
            .arg(&png)
            .args(extra)
            .output()
            .unwrap();
        (run.status.code(), common::stderr(&run), png.exists())
    };
    assert_eq!(render(&env, &[]).0, Some(0));

    let other = common::write_pfm(dir.path(), "other.pfm", &latlong(64, 32, |d| [1.0 + d.z as f32; 3]));
    for (map, extra) in [(&other, &[][..]), (&env, &["--flip-vertical"][..])] {
        let (code, stderr, wrote) = render(map, extra);
        assert_eq!(code, Some(2), "{stderr}");
        assert!(stderr.contains("ibl.json") && stderr.contains("baked from") && stderr.contains("sky"), "{stderr}");
        assert!(!wrote, "nothing written");
    }
}

/// A change to a copy of a bake: to its directory and to its manifest.
type Edit = dyn Fn(&std::path::Path, &mut serde_json::Value);

/// A bake whose files contradict its manifest is refused with exit 2, naming the file and the
/// manifest, before anything is rendered (issue 34): every field that describes a file (format,
/// face size, levels, face order) is checked, and a level offset into the KTX2 header is refused.
#[test]
fn a_bake_whose_files_contradict_the_manifest_is_refused_naming_both() {
    let dir = tempfile::tempdir().unwrap();
    let env = sky_pfm(dir.path(), 64, 32);
    let good = dir.path().join("good");
    cmd("ibl").arg(&env).arg("-o").arg(&good).args(["--size", "16", "--min-size", "4", "-q"]).assert().success();
    let manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(good.join("ibl.json")).unwrap()).unwrap();
    let render = |bake: &std::path::Path| {
        let png = dir.path().join("r.png");
        let _ = std::fs::remove_file(&png);
        let out = cmd("render")
            .arg(&env)
            .args(["--shading", "ibl", "--ibl"])
            .arg(bake)
            .args(["--brdf", "gltf:roughness=0.5", "--res", "8x8", "-q", "--png"])
            .arg(&png)
            .output()
            .unwrap();
        (out.status.code(), common::stderr(&out), png.exists())
    };
    assert_eq!(render(&good).0, Some(0), "the good bake renders");

    // A copy of the good bake, broken by `edit` (on the directory and the manifest).
    let broken = |name: &str, edit: &Edit| {
        let bake = dir.path().join(name);
        std::fs::create_dir(&bake).unwrap();
        for entry in std::fs::read_dir(&good).unwrap() {
            let entry = entry.unwrap();
            std::fs::copy(entry.path(), bake.join(entry.file_name())).unwrap();
        }
        let mut m = manifest.clone();
        edit(&bake, &mut m);
        std::fs::write(bake.join("ibl.json"), serde_json::to_vec_pretty(&m).unwrap()).unwrap();
        bake
    };
    let level_offset_into_header = |bake: &std::path::Path, _: &mut serde_json::Value| {
        let path = bake.join("specular.ktx2");
        let mut bytes = std::fs::read(&path).unwrap();
        bytes[80..88].copy_from_slice(&16u64.to_le_bytes()); // level 0's byteOffset
        std::fs::write(&path, bytes).unwrap();
    };
    let cases: [(&str, &Edit, &str, &str); 7] = [
        (
            "specular-as-irradiance",
            &|bake, _| {
                std::fs::copy(bake.join("specular.ktx2"), bake.join("irradiance.ktx2")).unwrap();
            },
            "irradiance.ktx2",
            "levels are [16, 8, 4] texels wide, the manifest says [32]",
        ),
        (
            "offset-into-header",
            &level_offset_into_header,
            "specular.ktx2",
            "level 0 starts at byte 16, inside the header",
        ),
        (
            "size",
            &|_, m| m["specular"]["levels"][0]["size"] = 32.into(),
            "specular.ktx2",
            "the manifest says [32, 8, 4]",
        ),
        ("format", &|_, m| m["specular"]["format"] = "rgba32f".into(), "specular.ktx2", "the manifest says rgba32f"),
        ("dfg-size", &|_, m| m["dfg"]["size"] = 64.into(), "dfg.ktx2", "the manifest says [64]"),
        ("irradiance-format", &|_, m| m["irradiance"]["format"] = "e5b9g9r9".into(), "irradiance.ktx2", "e5b9g9r9"),
        (
            "faces",
            &|_, m| m["frame"]["faces"] = serde_json::json!(["+X", "+Y", "+Z", "-X", "-Y", "-Z"]),
            "ibl.json",
            "frame.faces",
        ),
    ];
    for (name, edit, file, says) in cases {
        let bake = broken(name, edit);
        let (code, stderr, wrote) = render(&bake);
        assert_eq!(code, Some(2), "{name}: {stderr}");
        assert!(stderr.contains(file) && stderr.contains("ibl.json") && stderr.contains(says), "{name}: {stderr}");
        assert!(!wrote, "{name}: an image was written");
    }
}
