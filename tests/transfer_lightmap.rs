//! `transfer --lightmap WxH FILE.exr` (issue 32, item 2): diffuse transfer per texel of a UV set.
//!
//! - Unshadowed: every covered texel's T equals (ρ/π) Â_l Y_lm(n) at the texel's interpolated,
//!   renormalized normal, Â_l typed in from Ramamoorthi & Hanrahan 2001 (eq. 8–9).
//! - Shadowed, relit by a uniform sky: on a floor under a ball the exact answer is known in
//!   closed form, B(x) = ρ (1 − r² h / d³) (the projected solid angle of a sphere of radius r at
//!   distance d and height h above x is π (r/d)² (h/d)); the lightmap must find the shadow that a
//!   two-triangle floor's vertices cannot, and on a dense floor the two bakes must agree.
//! - `render --shading transfer --lightmap` of the fixture `floor-ball.obj` (a two-triangle
//!   floor) approaches `--shading reference` where the per-vertex bake cannot.
//! - Thread counts give the same bytes; bad requests exit 2 naming the file and write nothing.

mod common;

use common::{cmd, render_rel_error, stderr};
use glam::DVec3;
use prtkit::mesh::{uv_sphere, Mesh};
use prtkit::progress::NoProgress;
use prtkit::sh::basis::eval_basis_dir;
use prtkit::sh::legendre::LegendreTable;
use prtkit::transfer::albedo::{Albedo, Reflectance};
use prtkit::transfer::lightmap::{rasterize, LightmapConfig, LightmapInfo, LightmapUvs};
use prtkit::transfer::stage::{self, Config, Mode};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Â_l of the clamped cosine, l = 0..7 (Ramamoorthi & Hanrahan 2001, eq. 8–9).
const A_HAT: [f64; 8] = [PI, 2.0 * PI / 3.0, PI / 4.0, 0.0, -PI / 24.0, 0.0, PI / 64.0, 0.0];

/// The ball: radius and centre height above the floor.
const RADIUS: f64 = 0.3;
const HEIGHT: f64 = 0.45;

fn band(i: usize) -> usize {
    (i as f64).sqrt().floor() as usize
}

/// A floor [−1, 1]² at z = 0 of k × k quads (2k² triangles), UV chart v ∈ [0, ½], under a ball
/// (a 32 × 64 UV sphere, UV chart v ∈ [0.55, 0.95]), written as OBJ with `v`, `vt`, `vn`.
fn write_floor_and_ball(dir: &Path, k: usize) -> PathBuf {
    let mut p = Vec::new();
    let mut n = Vec::new();
    let mut uv = Vec::new();
    let mut t: Vec<[usize; 3]> = Vec::new();
    for j in 0..=k {
        for i in 0..=k {
            let (x, y) = (-1.0 + 2.0 * i as f64 / k as f64, -1.0 + 2.0 * j as f64 / k as f64);
            p.push(DVec3::new(x, y, 0.0));
            n.push(DVec3::Z);
            uv.push([(x + 1.0) / 2.0, (y + 1.0) / 4.0]);
        }
    }
    for j in 0..k {
        for i in 0..k {
            let a = j * (k + 1) + i;
            t.push([a, a + 1, a + k + 2]);
            t.push([a, a + k + 2, a + k + 1]);
        }
    }
    let base = p.len();
    let (sp, st) = uv_sphere(32, 64);
    for d in &sp {
        p.push(DVec3::new(0.0, 0.0, HEIGHT) + RADIUS * *d);
        n.push(*d);
        let u = 0.5 + d.y.atan2(d.x) / (2.0 * PI);
        uv.push([0.05 + 0.9 * u, 0.75 + 0.2 * d.z]);
    }
    t.extend(st.iter().map(|f| f.map(|i| base + i as usize)));
    let mut s = String::from("o floor_and_ball\n");
    for v in &p {
        s += &format!("v {} {} {}\n", v.x, v.y, v.z);
    }
    for v in &uv {
        s += &format!("vt {} {}\n", v[0], v[1]);
    }
    for v in &n {
        s += &format!("vn {} {} {}\n", v.x, v.y, v.z);
    }
    for f in &t {
        s += &format!("f {0}/{0}/{0} {1}/{1}/{1} {2}/{2}/{2}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    let path = dir.join(format!("floor{k}.obj"));
    std::fs::write(&path, s).unwrap();
    path
}

fn lightmap_config(mode: Mode, order: usize, side: usize, source: &Path) -> Config {
    Config {
        order,
        mode,
        rays: 1024,
        albedo: Albedo::Grey(0.8),
        source: source.display().to_string(),
        lightmap: Some(LightmapConfig {
            width: side,
            height: side,
            file: "lightmap.exr".into(),
            uvs: LightmapUvs::Mesh,
        }),
        ..Config::default()
    }
}

#[test]
fn unshadowed_texels_are_the_clamped_cosine_convolution() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write_floor_and_ball(dir.path(), 4);
    let mesh = Mesh::load(&obj).unwrap();
    let uvs = mesh.uvs.clone().expect("the OBJ's vt are read");
    let (order, side) = (8, 64);
    let config = lightmap_config(Mode::Unshadowed, order, side, &obj);
    let out = stage::run(&config, &mesh, &NoProgress).unwrap();
    let lightmap = out.lightmap.unwrap();
    let coverage = rasterize(&uvs, &mesh.triangles, side, side);
    let table = LegendreTable::new(order - 1);
    let mut y = vec![0.0; 64];
    let (mut worst, mut covered) = (0.0f64, 0);
    for (texel, sample) in coverage.samples.iter().enumerate() {
        let Some(s) = sample else { continue };
        covered += 1;
        // The normal at the texel centre: the vertex normals mixed by its barycentrics.
        let tri = mesh.triangles[s.triangle as usize].map(|i| mesh.normals[i as usize]);
        let normal = (s.weights[0] * tri[0] + s.weights[1] * tri[1] + s.weights[2] * tri[2]).normalize();
        eval_basis_dir(&table, normal, &mut y);
        for i in 0..64 {
            let expected = 0.8 / PI * A_HAT[band(i)] * y[i];
            worst = worst.max((lightmap.transfer[texel * 64 + i] - expected).abs());
        }
    }
    eprintln!(
        "unshadowed lightmap {side}x{side}, order 8, {covered} covered texels: largest |T - closed form| = {worst:.2e}"
    );
    assert_eq!(covered, lightmap.info.texels_covered);
    assert!(covered > 1000 && worst < 1e-12, "{covered} {worst}");
    // The EXR holds the same values as f32, one grey layer per coefficient, and the coverage.
    let layers = prtkit::io::exr::decode_layers(Path::new("lightmap.exr"), &lightmap.exr).unwrap();
    let layer = |name: &str| &layers.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no {name}")).1;
    for i in [0, 5, 63] {
        let image = layer(&format!("T{i}"));
        for (texel, px) in image.pixels.iter().enumerate() {
            assert_eq!(px[0], lightmap.transfer[texel * 64 + i] as f32);
        }
    }
    let cov = layer("coverage");
    let count = |v: f32| cov.pixels.iter().filter(|p| p[0] == v).count();
    assert_eq!(count(1.0), lightmap.info.texels_covered);
    assert_eq!(count(0.5), lightmap.info.texels_dilated);
    assert!(lightmap.info.texels_dilated > 0);
}

/// The relit floor (uniform sky of radiance 1) by the lightmap, by the per-vertex bake
/// interpolated at the same points, and in closed form, over the floor's covered texels.
struct Floor {
    lightmap: Vec<f64>,
    vertex: Vec<f64>,
    exact: Vec<f64>,
    /// Row-major positions of the floor texels in the W × W/2 picture.
    picture: Vec<Option<usize>>,
}

fn relit_floor(dir: &Path, k: usize, side: usize, mode: Mode) -> Floor {
    let obj = write_floor_and_ball(dir, k);
    let mesh = Mesh::load(&obj).unwrap();
    let config = lightmap_config(mode, 3, side, &obj);
    let out = stage::run(&config, &mesh, &NoProgress).unwrap();
    let lightmap = out.lightmap.unwrap();
    let coverage = rasterize(mesh.uvs.as_ref().unwrap(), &mesh.triangles, side, side);
    // A uniform sky of radiance 1 has L_00 = √(4π) and nothing else: B = √(4π) T_0.
    let sky = (4.0 * PI).sqrt();
    let floor_triangles = 2 * k * k;
    let mut f = Floor { lightmap: vec![], vertex: vec![], exact: vec![], picture: vec![None; side * side / 2] };
    for (texel, sample) in coverage.samples.iter().enumerate() {
        let Some(s) = sample else { continue };
        if s.triangle as usize >= floor_triangles {
            continue;
        }
        let tri = mesh.triangles[s.triangle as usize].map(|i| i as usize);
        let x: DVec3 = (0..3).map(|c| s.weights[c] * mesh.positions[tri[c]]).sum();
        let d = (DVec3::new(0.0, 0.0, HEIGHT) - x).length();
        f.picture[texel] = Some(f.exact.len());
        f.exact.push(0.8 * (1.0 - RADIUS * RADIUS * HEIGHT / d.powi(3)));
        f.lightmap.push(sky * lightmap.transfer[texel * 9]);
        f.vertex.push(sky * (0..3).map(|c| s.weights[c] * out.transfer[tri[c] * 9]).sum::<f64>());
    }
    f
}

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>() / a.len() as f64).sqrt()
}

#[test]
fn the_lightmap_finds_the_shadow_that_vertices_miss() {
    let dir = tempfile::tempdir().unwrap();
    let side = 128;
    let coarse = relit_floor(dir.path(), 1, side, Mode::Shadowed);
    let dense = relit_floor(dir.path(), 32, side, Mode::Shadowed);
    let darkest = coarse.exact.iter().copied().fold(f64::INFINITY, f64::min);
    let figures = [
        ("2-triangle floor, lightmap vs exact", rms(&coarse.lightmap, &coarse.exact)),
        ("2-triangle floor, per-vertex vs exact", rms(&coarse.vertex, &coarse.exact)),
        ("2048-triangle floor, lightmap vs exact", rms(&dense.lightmap, &dense.exact)),
        ("2048-triangle floor, per-vertex vs exact", rms(&dense.vertex, &dense.exact)),
        ("2048-triangle floor, lightmap vs per-vertex", rms(&dense.lightmap, &dense.vertex)),
    ];
    eprintln!(
        "floor of albedo 0.8 under a uniform sky, darkest exact value {darkest:.3}; RMS over {} texels:",
        coarse.exact.len()
    );
    for (what, e) in figures {
        eprintln!("  {what}: {e:.4}");
    }
    // The coarse floor's vertices sit far from the ball: per-vertex sees no shadow at all.
    assert!(figures[1].1 > 0.02, "{figures:?}");
    assert!(figures[0].1 < 0.2 * figures[1].1, "{figures:?}");
    assert!(figures[2].1 < 0.01 && figures[3].1 < 0.01 && figures[4].1 < 0.01, "{figures:?}");
    assert!(coarse.lightmap.iter().copied().fold(f64::INFINITY, f64::min) < darkest + 0.05);

    // The picture: lightmap | per-vertex | exact, the floor seen from above.
    if let Some(out) = std::env::var_os("PRTKIT_LIGHTMAP_PNG") {
        let (w, h) = (side, side / 2);
        let mut image = prtkit::io::RgbImage { width: 3 * w, height: h, pixels: vec![[0.0; 3]; 3 * w * h] };
        for (p, slot) in coarse.picture.iter().enumerate() {
            let Some(k) = slot else { continue };
            let (x, y) = (p % w, p / w);
            for (panel, v) in [coarse.lightmap[*k], coarse.vertex[*k], coarse.exact[*k]].into_iter().enumerate() {
                image.pixels[(h - 1 - y) * 3 * w + panel * w + x] = [v as f32; 3];
            }
        }
        prtkit::io::png::write_tonemapped(Path::new(&out), &image, 0.0).unwrap();
    }
}

#[test]
fn an_interreflected_texel_at_a_vertex_is_that_vertex_transfer() {
    // A texel's gather (its shadowed transfer plus, at its rays' front hits, the vertices'
    // T^0 + … + T^{B−1}) is eq. 9 summed over the bounces: at a vertex's own position and normal
    // it casts that vertex's rays and must give the per-vertex interreflected transfer, T^0 plus
    // the bounces added one by one, to rounding.
    use prtkit::transfer::directions::Stratified;
    use prtkit::transfer::interreflect::{Storage, Tracer};
    use prtkit::transfer::visibility::Occluders;
    let dir = tempfile::tempdir().unwrap();
    let mesh = Mesh::load(&write_floor_and_ball(dir.path(), 4)).unwrap();
    let (order, albedo, bounces) = (3, 0.8, 2);
    let coeffs = order * order;
    let occluders = Occluders::new(&mesh.positions, &mesh.triangles);
    let directions = Stratified::new(256, 0);
    let tracer = Tracer::new(&mesh, &occluders, &directions, order, 1e-4 * mesh.extent());
    let first = tracer.first_pass(albedo, Storage::Record, &NoProgress);
    let direct: Vec<f64> = first.points.iter().flat_map(|p| p.shadowed.clone()).collect();
    let passes = tracer.bounces(&direct, bounces, Reflectance::Grey(albedo), &first.hits, &NoProgress);
    let sum = |passes: &[Vec<f64>]| -> Vec<f64> {
        passes.iter().fold(direct.clone(), |acc, p| acc.iter().zip(p).map(|(a, b)| a + b).collect())
    };
    let (total, gathered) = (sum(&passes), sum(&passes[..bounces - 1]));
    let (mut worst, mut bounced) = (0.0f64, 0.0f64);
    for v in 0..mesh.positions.len() {
        let t = tracer.gather_at(mesh.positions[v], mesh.normals[v], &[albedo], &gathered);
        for i in 0..coeffs {
            worst = worst.max((t[i] - total[v * coeffs + i]).abs());
            bounced = bounced.max((total[v * coeffs + i] - direct[v * coeffs + i]).abs());
        }
    }
    eprintln!("texel gather at the vertices vs the per-vertex bounces: largest difference {worst:.1e}, bounces add up to {bounced:.3}");
    assert!(bounced > 0.01 && worst < 1e-12, "{worst} {bounced}");
}

#[test]
fn an_interreflected_lightmap_holds_the_bounce_off_the_ball() {
    // The ball lights the floor around its foot; a dense floor's vertices see that bounce, and
    // the lightmap must agree with them as the shadowed bakes do, while differing from its own
    // shadowed bake by the bounce.
    let dir = tempfile::tempdir().unwrap();
    let side = 128;
    let shadowed = relit_floor(dir.path(), 32, side, Mode::Shadowed);
    let bounced = relit_floor(dir.path(), 32, side, Mode::Interreflected);
    let gained: Vec<f64> = bounced.lightmap.iter().zip(&shadowed.lightmap).map(|(b, s)| b - s).collect();
    let most = gained.iter().copied().fold(0.0f64, f64::max);
    let least = gained.iter().copied().fold(f64::INFINITY, f64::min);
    let figures = [rms(&bounced.lightmap, &bounced.vertex), rms(&bounced.lightmap, &shadowed.lightmap)];
    eprintln!(
        "interreflected floor (2 bounces): lightmap vs per-vertex RMS {:.4}; the bounces add {least:.4} to {most:.4} \
         (RMS {:.4}) over the shadowed lightmap",
        figures[0], figures[1]
    );
    assert!(least >= 0.0 && most > 0.05 && figures[1] > 0.01, "{least} {most} {figures:?}");
    assert!(figures[0] < 0.01, "{figures:?}");
}

fn bake_cli(dir: &Path, obj: &Path, extra: &[&str], tag: &str) -> (std::process::Output, PathBuf, PathBuf, PathBuf) {
    let (glb, json, exr) =
        (dir.join(format!("{tag}.glb")), dir.join(format!("{tag}.json")), dir.join(format!("{tag}.exr")));
    let output = cmd("transfer")
        .arg(obj)
        .args(["--rays", "64", "-q", "--glb"])
        .arg(&glb)
        .arg("-o")
        .arg(&json)
        .args(extra)
        .output()
        .unwrap();
    (output, glb, json, exr)
}

/// `mesh` as an ASCII PLY with `double` x y z, nx ny nz and the UV pair `s t` (written in
/// shortest round-trip form, so every value reads back to the bit).
fn write_ply(path: &Path, mesh: &Mesh) {
    let uvs = mesh.uvs.as_ref().expect("the mesh has UVs");
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\n\
         property double nx\nproperty double ny\nproperty double nz\nproperty double s\nproperty double t\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.positions.len(),
        mesh.triangles.len()
    );
    for ((p, n), uv) in mesh.positions.iter().zip(&mesh.normals).zip(uvs) {
        s += &format!("{:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}\n", p.x, p.y, p.z, n.x, n.y, n.z, uv[0], uv[1]);
    }
    for t in &mesh.triangles {
        s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn a_ply_with_texture_coordinates_bakes_the_lightmap_of_the_same_obj() {
    // The OBJ as prtkit reads it, written out as a PLY with `s t`: the same vertices, normals,
    // UVs and triangles, so the same lightmap, byte for byte.
    let dir = tempfile::tempdir().unwrap();
    let obj = write_floor_and_ball(dir.path(), 2);
    let ply = dir.path().join("floor2.ply");
    write_ply(&ply, &Mesh::load(&obj).unwrap());
    let mut bytes = Vec::new();
    for (mesh, tag) in [(&obj, "obj"), (&ply, "ply")] {
        let exr = dir.path().join(format!("{tag}.exr"));
        let (output, ..) = bake_cli(dir.path(), mesh, &["--lightmap", "48x32", exr.to_str().unwrap()], tag);
        assert!(output.status.success(), "{tag}: {}", stderr(&output));
        bytes.push(std::fs::read(&exr).unwrap());
    }
    assert!(bytes[0] == bytes[1], "the PLY's lightmap differs from the OBJ's");
}

#[test]
fn thread_counts_give_the_same_lightmap_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write_floor_and_ball(dir.path(), 2);
    let mut bytes = Vec::new();
    for threads in ["1", "2"] {
        let exr = dir.path().join(format!("t{threads}.exr"));
        let (output, _, json, _) = bake_cli(
            dir.path(),
            &obj,
            &["--threads", threads, "--lightmap", "48x32", exr.to_str().unwrap()],
            &format!("t{threads}"),
        );
        assert!(output.status.success(), "{}", stderr(&output));
        let manifest: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        let info: LightmapInfo = serde_json::from_value(manifest["lightmap"].clone()).unwrap();
        assert_eq!((info.width, info.height, info.dilation), (48, 32, 2));
        assert_eq!(info.file, format!("t{threads}.exr"));
        assert_eq!(info.layers.len(), 10);
        assert!(info.texels_covered > 500, "{info:?}");
        bytes.push(std::fs::read(&exr).unwrap());
    }
    assert!(bytes[0] == bytes[1], "--threads 1 and 2 wrote different lightmaps");
}

#[test]
fn bad_lightmap_requests_exit_2_naming_the_file_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let with_uvs = write_floor_and_ball(dir.path(), 1);
    let without = dir.path().join("plain.obj");
    std::fs::write(&without, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let cases: [(&Path, &[&str], &str); 6] = [
        (&without, &["64x64"], "no lightmap UVs (TEXCOORD_1/TEXCOORD_0, vt, or a PLY's s t / u v)"),
        (&with_uvs, &["0x64"], "has no texels"),
        (&with_uvs, &["100000x100000"], "16384"),
        (&with_uvs, &["16384x16384", "--order", "8"], "268435456"),
        (&with_uvs, &["64x64", "--clusters", "2", "--pca", "2"], "compressed"),
        (&with_uvs, &["64"], "the size must be WxH"),
    ];
    for (mesh, args, reason) in cases {
        let exr = dir.path().join("lm.exr");
        let mut extra = vec!["--lightmap", args[0], exr.to_str().unwrap()];
        extra.extend(&args[1..]);
        let (output, glb, json, _) = bake_cli(dir.path(), mesh, &extra, "bad");
        let message = stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {message}");
        let names_file = message.contains(&mesh.display().to_string()) || args[0] == "64";
        assert!(names_file && message.contains(reason), "{args:?}: {message}");
        assert!(!glb.exists() && !json.exists() && !exr.exists(), "{args:?}: an output was written");
    }
}

#[test]
fn a_relit_lightmap_approaches_the_reference_where_vertices_cannot() {
    // The fixture's two-triangle floor under its ball, seen from above and to the side, under
    // the test sky: `--shading reference` casts the mesh's own shadow rays per pixel; the
    // per-vertex bake has four floor vertices far from the ball, the lightmap 128×128 texels.
    let dir = tempfile::tempdir().unwrap();
    common::sky_pfm(dir.path(), 64, 32);
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/floor-ball.obj");
    let mesh = mesh.to_str().unwrap();
    let camera = ["--res", "96x96", "--eye", "0,-2.2,2.6", "--target", "0,0,0.1"];
    let view = [&["--scene", mesh, "--brdf", "lambert:albedo=0.8"][..], &camera].concat();
    let run = |args: &[&str]| render_rel_error(dir.path(), &[&["sky.pfm"][..], &view, args].concat());
    run(&["--shading", "reference", "-o", "r.exr"]);
    let bake = ["-n", "6", "--rays", "1024", "--albedo", "0.8", "-q", "--glb", "f.glb", "-o", "f.json"];
    let out = cmd("transfer")
        .arg(mesh)
        .args(bake)
        .args(["--lightmap", "128x128", "f.exr"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let compare = ["--shading", "transfer", "--transfer", "f.glb", "--compare", "r.exr"];
    let png = std::env::var("PRTKIT_LIGHTMAP_RENDER_PNG").ok();
    let with_png = |extra: &[&str], name: &str| {
        let mut args: Vec<String> = compare.iter().chain(extra).map(|s| s.to_string()).collect();
        if let Some(dir) = &png {
            args.extend(["--png".into(), format!("{dir}/{name}.png")]);
        }
        run(&args.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let vertex = with_png(&[], "vertex");
    let lightmap = with_png(&["--lightmap", "f.exr"], "lightmap");
    if let Some(out) = &png {
        let file = format!("{out}/reference.png");
        run(&["--shading", "reference", "--png", &file]);
    }
    eprintln!("floor and ball under the test sky, n = 6, 1024 rays, relit vs reference (relative RMS): per-vertex {vertex:.4}, lightmap 128x128 {lightmap:.4}");
    assert!(lightmap < 0.7 * vertex, "lightmap {lightmap} vs per-vertex {vertex}");
}

#[test]
fn a_gltf_with_texcoord_0_bakes_the_lightmap_of_the_same_obj() {
    // The fixture's OBJ written again as a .glb with its UVs as TEXCOORD_0: the same texels are
    // covered, and the transfer agrees to the f32 rounding of the normals.
    let dir = tempfile::tempdir().unwrap();
    let obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/floor-ball.obj");
    let mesh = Mesh::load(&obj).unwrap();
    let uvs = mesh.uvs.clone().unwrap();
    let glb = prtkit::io::glb::encode(&prtkit::io::glb::GlbMesh {
        positions: mesh.positions.iter().map(|p| p.as_vec3().to_array()).collect(),
        attributes: vec![
            prtkit::io::glb::Attribute {
                name: "NORMAL".into(),
                components: 3,
                values: prtkit::io::glb::Values::Float(
                    mesh.normals.iter().flat_map(|n| n.as_vec3().to_array()).collect(),
                ),
            },
            prtkit::io::glb::Attribute {
                name: "TEXCOORD_0".into(),
                components: 2,
                values: prtkit::io::glb::Values::Float(uvs.iter().flat_map(|uv| uv.map(|c| c as f32)).collect()),
            },
        ],
        triangles: mesh.triangles.clone(),
        generator: "test".into(),
        extras: serde_json::json!({}),
        blobs: Vec::new(),
    })
    .unwrap();
    let path = dir.path().join("floor-ball.glb");
    std::fs::write(&path, glb).unwrap();
    let from_glb = Mesh::load(&path).unwrap();
    assert_eq!(from_glb.uvs.as_ref().map(Vec::len), Some(uvs.len()));
    let bake = |m: &Mesh, source: &Path| {
        stage::run(&lightmap_config(Mode::Shadowed, 3, 64, source), m, &NoProgress).unwrap().lightmap.unwrap()
    };
    let (a, b) = (bake(&mesh, &obj), bake(&from_glb, &path));
    assert_eq!(a.info.texels_covered, b.info.texels_covered);
    assert_eq!(a.coverage, b.coverage);
    let worst = a.transfer.iter().zip(&b.transfer).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
    eprintln!("floor-ball as OBJ and as glTF TEXCOORD_0: {} texels, largest |dT| = {worst:.2e}", a.info.texels_covered);
    assert!(worst < 1e-3, "{worst}");
}
