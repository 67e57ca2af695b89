//! `transfer --texels WxH FILE.exr`: the lightmap of a generated atlas (`src/transfer/atlas.rs`)
//! against the closed-form shadow of a ball on a floor, against `--lightmap`'s bake of the
//! mesh's own UVs, relit by `render`, and its refusals.

mod common;

use common::{cmd, render_rel_error, stderr};
use glam::DVec3;
use prtkit::mesh::Mesh;
use prtkit::progress::NoProgress;
use prtkit::transfer::albedo::Albedo;
use prtkit::transfer::lightmap::{self, rasterize, LightmapConfig, LightmapUvs};
use prtkit::transfer::stage::{self, Config, Mode};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// The fixture's ball: radius and centre height above its two-triangle floor.
const RADIUS: f64 = 0.3;
const HEIGHT: f64 = 0.45;

fn floor_ball() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/floor-ball.obj")
}

fn config(uvs: LightmapUvs, side: usize, source: &Path) -> Config {
    Config {
        order: 3,
        mode: Mode::Shadowed,
        rays: 1024,
        albedo: Albedo::Grey(0.8),
        source: source.display().to_string(),
        lightmap: Some(LightmapConfig { width: side, height: side, file: "lightmap.exr".into(), uvs }),
        ..Config::default()
    }
}

/// The floor's texels relit by a uniform sky of radiance 1 (B = √(4π) T_0), and the closed form
/// B(x) = ρ (1 − r² h / d³) at the same points.
fn relit_floor(uvs: LightmapUvs, side: usize) -> (Vec<f64>, Vec<f64>) {
    let obj = floor_ball();
    let mesh = Mesh::load(&obj).unwrap();
    let config = config(uvs, side, &obj);
    let out = stage::run(&config, &mesh, &NoProgress).unwrap();
    let baked = out.lightmap.unwrap();
    // The mesh the bake ran on: the atlas's split one (triangles keep their order), or the mesh.
    let split = lightmap::atlas_mesh(config.lightmap.as_ref().unwrap(), &config, &mesh).unwrap();
    let mesh = split.map(|(m, _)| m).unwrap_or(mesh);
    let coverage = rasterize(mesh.uvs.as_ref().unwrap(), &mesh.triangles, side, side);
    let (mut relit, mut exact) = (Vec::new(), Vec::new());
    for (texel, sample) in coverage.samples.iter().enumerate() {
        // The floor is the file's first two triangles.
        let Some(s) = sample.filter(|s| s.triangle < 2) else { continue };
        let tri = mesh.triangles[s.triangle as usize].map(|i| i as usize);
        let x: DVec3 = (0..3).map(|c| s.weights[c] * mesh.positions[tri[c]]).sum();
        // The split mesh's floor is the file's, [−1, 1]² at z = 0.
        assert!(x.z == 0.0 && x.x.abs() <= 1.0 && x.y.abs() <= 1.0, "{x}");
        let d = (DVec3::new(0.0, 0.0, HEIGHT) - x).length();
        exact.push(0.8 * (1.0 - RADIUS * RADIUS * HEIGHT / d.powi(3)));
        relit.push((4.0 * PI).sqrt() * baked.transfer[texel * 9]);
    }
    (relit, exact)
}

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>() / a.len() as f64).sqrt()
}

#[test]
fn the_atlas_lightmap_finds_the_floor_shadow_as_the_hand_made_uvs_do() {
    let (atlas, atlas_exact) = relit_floor(LightmapUvs::Atlas, 128);
    let (own, own_exact) = relit_floor(LightmapUvs::Mesh, 128);
    let (e_atlas, e_own) = (rms(&atlas, &atlas_exact), rms(&own, &own_exact));
    eprintln!(
        "floor under a ball, uniform sky, 1024 rays, 128x128: RMS vs closed form, atlas {e_atlas:.4} over {} floor \
         texels, own UVs {e_own:.4} over {}",
        atlas.len(),
        own.len()
    );
    // The floor's shadow is there: its darkest texel is near the closed form's 0.445.
    assert!(atlas.iter().copied().fold(f64::INFINITY, f64::min) < 0.5);
    assert!(atlas.len() > 1000);
    assert!(e_atlas < 0.01 && e_own < 0.01, "atlas {e_atlas}, own {e_own}");
}

/// `transfer MESH ARGS -o DIR/t.json --glb DIR/t.glb` in `dir`.
fn bake(dir: &Path, mesh: &Path, args: &[&str]) -> std::process::Output {
    cmd("transfer")
        .arg(mesh)
        .args(["-n", "3", "--rays", "64", "-q", "--glb", "t.glb", "-o", "t.json"])
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

#[test]
fn bad_texel_requests_exit_2_naming_the_mesh_and_write_nothing() {
    let knot = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/torus-knot.obj");
    let cases: [(&[&str], &str); 6] = [
        (&["--texels", "0x64", "t.exr"], "has no texels"),
        (&["--texels", "64x0", "t.exr"], "has no texels"),
        (&["--texels", "20000x64", "t.exr"], "ceiling"),
        // 84 charts of at least 5x5 texels do not fit 16x16.
        (&["--texels", "16x16", "t.exr"], "no atlas"),
        (&["--texels", "64x64", "t.exr", "--lightmap", "64x64", "u.exr"], "cannot be used with"),
        (&["--texels", "64x64", "t.exr", "--join", "a.part"], "cannot be used with"),
    ];
    for (args, expected) in cases {
        let dir = tempfile::tempdir().unwrap();
        let out = bake(dir.path(), &knot, args);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {message}");
        assert!(message.contains(expected), "{args:?}: {message}");
        if !message.contains("cannot be used with") {
            assert!(message.contains("torus-knot.obj"), "{args:?}: {message}");
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "{args:?} wrote something");
    }
}

#[test]
fn the_glb_carries_the_atlas_uvs_and_the_manifest_its_account() {
    let dir = tempfile::tempdir().unwrap();
    let knot = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/torus-knot.obj");
    let out = bake(dir.path(), &knot, &["--texels", "256x256", "t.exr"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let manifest: serde_json::Value = common::read(&dir.path().join("t.json"));
    let atlas = &manifest["lightmap"]["atlas"];
    assert_eq!(manifest["lightmap"]["texels_overlapping"], 0);
    assert_eq!(atlas["vertices_before"], 1920);
    let after = atlas["vertices_after"].as_u64().unwrap() as usize;
    // The .glb read back: the split mesh, with the atlas's UVs as TEXCOORD_0, in [0, 1].
    let glb = Mesh::load(&dir.path().join("t.glb")).unwrap();
    assert_eq!(glb.positions.len(), after);
    let uvs = glb.uvs.expect("the .glb has UVs");
    assert!(uvs.iter().flatten().all(|c| (0.0..=1.0).contains(c)));
    let coverage = rasterize(&uvs, &glb.triangles, 256, 256);
    assert_eq!(coverage.overlapping, 0);
    let covered = coverage.samples.iter().flatten().count();
    // The .glb stores the UVs as f32: a texel centre within rounding of a chart's border may
    // change sides, no more than a handful.
    let baked = manifest["lightmap"]["texels_covered"].as_u64().unwrap() as usize;
    assert!(covered.abs_diff(baked) <= covered / 1000, "{covered} vs {baked}");
    eprintln!("torus knot, 256x256: {atlas}, {covered} texels covered");
}

#[test]
fn the_atlas_lightmap_relights_from_its_glb_alone() {
    // As tests/transfer_lightmap.rs relights the hand-made UVs: the floor and ball under the
    // test sky, against `--shading reference` (shadow rays per pixel). The --texels bake is
    // rendered with its own .glb as the scene (the split mesh and its TEXCOORD_0).
    let dir = tempfile::tempdir().unwrap();
    common::sky_pfm(dir.path(), 64, 32);
    let mesh = floor_ball();
    let mesh = mesh.to_str().unwrap();
    let camera = ["--res", "96x96", "--eye", "0,-2.2,2.6", "--target", "0,0,0.1", "--brdf", "lambert:albedo=0.8"];
    let run = |scene: &str, args: &[&str]| {
        render_rel_error(dir.path(), &[&["sky.pfm", "--scene", scene][..], &camera, args].concat())
    };
    run(mesh, &["--shading", "reference", "-o", "r.exr"]);
    let bake_args = ["-n", "6", "--rays", "1024", "--albedo", "0.8", "-q"];
    for (flag, name) in [("--texels", "a"), ("--lightmap", "m")] {
        let out = cmd("transfer")
            .arg(mesh)
            .args(bake_args)
            .args([
                "--glb",
                &format!("{name}.glb"),
                "-o",
                &format!("{name}.json"),
                flag,
                "128x128",
                &format!("{name}.exr"),
            ])
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let compare = ["--shading", "transfer", "--compare", "r.exr"];
    let atlas = run("a.glb", &[&compare[..], &["--transfer", "a.glb", "--lightmap", "a.exr"]].concat());
    let own = run(mesh, &[&compare[..], &["--transfer", "m.glb", "--lightmap", "m.exr"]].concat());
    let vertex = run(mesh, &[&compare[..], &["--transfer", "m.glb"]].concat());
    eprintln!(
        "floor and ball under the test sky, n = 6, 1024 rays, relit vs reference (relative RMS): atlas 128x128 \
         {atlas:.4}, own UVs 128x128 {own:.4}, per-vertex {vertex:.4}"
    );
    assert!(atlas < 0.7 * vertex && atlas < 1.5 * own, "atlas {atlas}, own UVs {own}, per-vertex {vertex}");
}
