//! `transfer` (issue 32, first slice): diffuse per-vertex PRT against independent derivations.
//!
//! - Unshadowed transfer on a sphere equals the clamped cosine's SH convolution,
//!   T_lm = (ρ/π) Â_l Y_lm(n), with Â_l typed in from Ramamoorthi & Hanrahan 2001 (eq. 8–9).
//! - Shadowed transfer in a bowl holding a ball matches a brute-force integral by another code
//!   path: a naive loop over every triangle (f64 Möller–Trumbore, no BVH) over a dense
//!   Gauss–Legendre × azimuth product rule in world axes (not the stage's stratified rays).
//! - Thread counts give the same bytes; bad meshes exit 2 naming the file and write nothing.

mod common;

use common::{check_glsl_fragment, check_wgsl, cmd, stderr};
use glam::DVec3;
use prtkit::mesh::{uv_sphere, Mesh};
use prtkit::progress::NoProgress;
use prtkit::sh::basis::eval_basis_dir;
use prtkit::sh::legendre::LegendreTable;
use prtkit::transfer::albedo::{Albedo, Reflectance};
use prtkit::transfer::stage::{self, Config, Mode};
use std::f64::consts::PI;
use std::path::Path;

/// Â_l of the clamped cosine, l = 0..7 (Ramamoorthi & Hanrahan 2001, eq. 8–9): π, 2π/3, π/4,
/// 0, −π/24, 0, π/64, 0.
const A_HAT: [f64; 8] = [PI, 2.0 * PI / 3.0, PI / 4.0, 0.0, -PI / 24.0, 0.0, PI / 64.0, 0.0];

// The bowl-and-ball scene and the brute-force integral of the accuracy example, compiled into
// this test (its `main` unused here), so the test and the published figures use one copy.
#[allow(dead_code)]
#[path = "../examples/transfer_accuracy.rs"]
mod accuracy;
use accuracy::{bowl_and_ball, brute_force};

fn band(i: usize) -> usize {
    (i as f64).sqrt().floor() as usize
}

fn write_obj(path: &Path, p: &[DVec3], n: &[DVec3], t: &[[u32; 3]]) {
    let mut s = String::from("o scene\n");
    for v in p {
        s += &format!("v {} {} {}\n", v.x, v.y, v.z);
    }
    for v in n {
        s += &format!("vn {} {} {}\n", v.x, v.y, v.z);
    }
    for f in t {
        s += &format!("f {0}//{0} {1}//{1} {2}//{2}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn unshadowed_sphere_is_the_clamped_cosine_convolution() {
    let (p, t) = uv_sphere(16, 32);
    let mesh = Mesh::new(p.clone(), Some(p.clone()), t).unwrap();
    let (order, albedo) = (8, 0.8);
    let config = Config { order, mode: Mode::Unshadowed, albedo: Albedo::Grey(albedo), ..Config::default() };
    let out = stage::run(&config, &mesh, &NoProgress).unwrap();
    let table = LegendreTable::new(order - 1);
    let mut y = vec![0.0; 64];
    let mut worst = 0.0f64;
    for (v, n) in mesh.normals.iter().enumerate() {
        eval_basis_dir(&table, *n, &mut y);
        for i in 0..64 {
            let expected = albedo / PI * A_HAT[band(i)] * y[i];
            worst = worst.max((out.transfer[v * 64 + i] - expected).abs());
        }
    }
    eprintln!("unshadowed sphere, order 8, {} vertices: largest |T - (albedo/pi) A_l Y_lm(n)| = {worst:.2e}", p.len());
    assert!(worst < 1e-6, "{worst}");

    // Shadowed on a convex mesh: nothing occludes, so the rays' error is the quadrature's alone.
    let config = Config { order, mode: Mode::Shadowed, albedo: Albedo::Grey(albedo), rays: 4096, ..Config::default() };
    let shadowed = stage::run(&config, &mesh, &NoProgress).unwrap();
    let error = shadowed.document.body.error.clone().unwrap();
    let (mut d2, mut r2) = (0.0, 0.0);
    for (a, b) in shadowed.transfer.iter().zip(&out.transfer) {
        d2 += (a - b) * (a - b);
        r2 += b * b;
    }
    let rms = (d2 / r2).sqrt();
    eprintln!(
        "shadowed sphere, 4096 rays: relative RMS {rms:.2e} against the closed form, visible fraction {:.6}",
        error.visible_fraction
    );
    assert_eq!(error.visible_fraction, 1.0);
    assert!((rms - error.relative_rms).abs() < 1e-12 && rms < 0.01, "{rms}");
}

#[test]
fn shadowed_bowl_matches_a_brute_force_integral() {
    let (p, n, t) = bowl_and_ball();
    let mesh = Mesh::new(p.clone(), Some(n.clone()), t.clone()).unwrap();
    let order = 8;
    let rule = prtkit::quadrature::gauss_legendre(96);
    let azimuths = 192;
    let directions: Vec<(DVec3, f64)> = rule
        .iter()
        .flat_map(|&(z, w)| {
            let s = (1.0 - z * z).sqrt();
            (0..azimuths).map(move |k| {
                let phi = 2.0 * PI * (k as f64 + 0.5) / azimuths as f64;
                (DVec3::new(s * phi.cos(), s * phi.sin(), z), w * 2.0 * PI / azimuths as f64)
            })
        })
        .collect();
    // Every third vertex of the bowl and the ball (the brute force costs vertices × directions
    // × triangles).
    let sample: Vec<usize> = (0..p.len()).step_by(3).collect();
    let offset = 1e-4 * mesh.extent();
    let reference: Vec<Vec<f64>> =
        sample.iter().map(|&v| brute_force(&p, &t, p[v] + offset * n[v], n[v], order, &directions)).collect();
    for rays in [1024, 4096, 16384] {
        let config = Config { order, mode: Mode::Shadowed, rays, ..Config::default() };
        let out = stage::run(&config, &mesh, &NoProgress).unwrap();
        let (mut d2, mut r2) = (0.0, 0.0);
        for (&v, r) in sample.iter().zip(&reference) {
            for i in 0..64 {
                let d = out.transfer[v * 64 + i] - r[i];
                d2 += d * d;
                r2 += r[i] * r[i];
            }
        }
        let rms = (d2 / r2).sqrt();
        let error = out.document.body.error.unwrap();
        eprintln!(
            "bowl + ball, order 8, {rays} rays, {} of {} vertices vs brute force over {} directions: relative RMS \
             {rms:.4}; visible fraction {:.3}; unshadowed integration error of the rays {:.4}",
            sample.len(),
            p.len(),
            directions.len(),
            error.visible_fraction,
            error.relative_rms
        );
        if rays == 16384 {
            assert!(rms < 0.01, "{rms}");
        }
        assert!(error.visible_fraction < 0.9, "the bowl should shadow itself");
    }
}

/// `transfer OBJ ARGS` with `--threads 1` and `--threads 2`, each into its own folder under the
/// same names (the manifest names its .glb): per run the .glb, the manifest without its
/// provenance (which records the thread count) and the GLSL snippet.
fn bakes_per_thread_count(dir: &Path, obj: &Path, args: &[&str]) -> Vec<(Vec<u8>, serde_json::Value, Vec<u8>)> {
    ["1", "2"]
        .iter()
        .map(|threads| {
            let out = dir.join(threads);
            std::fs::create_dir(&out).unwrap();
            let (glb, json, glsl) = (out.join("t.glb"), out.join("t.json"), out.join("t.glsl"));
            cmd("transfer")
                .arg(obj)
                .args(args)
                .args(["-q", "--threads", threads, "--glb"])
                .arg(&glb)
                .arg("-o")
                .arg(&json)
                .arg("--glsl")
                .arg(&glsl)
                .assert()
                .success();
            let mut doc: serde_json::Value = common::read(&json);
            doc.as_object_mut().unwrap().remove("provenance");
            (std::fs::read(&glb).unwrap(), doc, std::fs::read(&glsl).unwrap())
        })
        .collect()
}

#[test]
fn thread_counts_give_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let (p, n, t) = bowl_and_ball();
    let obj = dir.path().join("scene.obj");
    write_obj(&obj, &p, &n, &t);
    let outputs = bakes_per_thread_count(dir.path(), &obj, &["-n", "5", "--rays", "512"]);
    assert!(outputs[0] == outputs[1], "outputs differ between --threads 1 and 2");

    // The .glb holds the transfer as documented: _PRT_k = coefficients 4k..4k+3, zero padded.
    let bytes = &outputs[0].0;
    let gltf = prtkit::io::glb::json_chunk(bytes).unwrap();
    let bin = prtkit::io::glb::bin_chunk(bytes).unwrap();
    let attributes = &gltf["meshes"][0]["primitives"][0]["attributes"];
    let config = Config { order: 5, mode: Mode::Shadowed, rays: 512, ..Config::default() };
    let mesh = Mesh::load(&obj).unwrap();
    let out = stage::run(&config, &mesh, &NoProgress).unwrap();
    for k in 0..7 {
        let accessor = &gltf["accessors"][attributes[format!("_PRT_{k}")].as_u64().unwrap() as usize];
        assert_eq!((accessor["type"].as_str(), accessor["count"].as_u64()), (Some("VEC4"), Some(p.len() as u64)));
        let view = &gltf["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
        let start = view["byteOffset"].as_u64().unwrap() as usize;
        for v in [0, p.len() / 2, p.len() - 1] {
            for j in 0..4 {
                let at = start + 16 * v + 4 * j;
                let value = f32::from_le_bytes(bin[at..at + 4].try_into().unwrap());
                let i = 4 * k + j;
                let expected = if i < 25 { out.transfer[v * 25 + i] as f32 } else { 0.0 };
                assert_eq!(value, expected, "_PRT_{k}[{j}] of vertex {v}");
            }
        }
    }
    assert!(attributes.get("_PRT_7").is_none());

    // The GLSL snippet compiles (naga's GLSL front end, then its validator).
    let glsl = String::from_utf8(outputs[0].2.clone()).unwrap();
    let src = format!(
        "#version 450\n#define PRTKIT_LIGHT_SH_DECLARED\nlayout(std140, binding = 0) uniform Light {{ vec3 prtkitLightSH[25]; }};\n{glsl}\
         layout(location = 0) in vec4 t0;\nlayout(location = 0) out vec4 o;\n\
         void main() {{ vec4 t[7] = vec4[7](t0, t0, t0, t0, t0, t0, t0); o = vec4(prtkitTransferRadiance(t), 1.0); }}\n"
    );
    check_glsl_fragment(&src, "the order-5 GLSL snippet");
}

#[test]
fn hlsl_and_wgsl_snippets_beside_the_glsl_one_and_their_rotation_compiles() {
    // `--glsl/--hlsl/--wgsl` write the dot product and the SH rotation; GLSL and WGSL go through
    // naga's front ends and validator at every order (the rotation's band blocks are written out,
    // so each order is different code). naga has no HLSL front end: here the HLSL is checked for its
    // declarations; glslang compiles it (`tests/hlsl_snippets.rs`).
    let dir = tempfile::tempdir().unwrap();
    for order in 1..=8usize {
        let files = ["t.glsl", "t.hlsl", "t.wgsl"].map(|f| dir.path().join(format!("{order}-{f}")));
        cmd("transfer")
            .args(["testdata/meshes/bowl.obj", "-q", "--mode", "unshadowed", "-n", &order.to_string(), "--glb"])
            .arg(dir.path().join("t.glb"))
            .arg("-o")
            .arg(dir.path().join("t.json"))
            .arg("--glsl")
            .arg(&files[0])
            .arg("--hlsl")
            .arg(&files[1])
            .arg("--wgsl")
            .arg(&files[2])
            .assert()
            .success();
        let [glsl, hlsl, wgsl] = files.map(|f| std::fs::read_to_string(f).unwrap());
        let (c, v) = (order * order, (order * order).div_ceil(4));
        let src = format!(
            "#version 450\n#define PRTKIT_LIGHT_SH_DECLARED\n\
             layout(std140, binding = 0) uniform Light {{ vec3 prtkitLightSH[{c}]; }};\n{glsl}layout(location = 0) in vec4 t0;\nlayout(location = 1) in vec3 axis;\n\
             layout(location = 0) out vec4 o;\nvoid main() {{ vec4 t[{v}]; for (int k = 0; k < {v}; ++k) t[k] = t0; \
             vec3 turned[{c}]; prtkitRotateSH(mat3(axis, axis.yzx, axis.zxy), prtkitLightSH, turned); \
             o = vec4(prtkitTransferRadiance(t) + turned[{last}], 1.0); }}\n",
            last = c - 1
        );
        check_glsl_fragment(&src, &format!("glsl order {order}"));
        let src = format!(
            "{wgsl}@group(0) @binding(0) var<uniform> light: array<vec4<f32>, {c}>;\n\
             @fragment fn main(@location(0) t0: vec4<f32>, @location(1) axis: vec3<f32>) -> @location(0) vec4<f32> {{\n\
             var sh: array<vec3<f32>, {c}>;\n for (var i = 0; i < {c}; i++) {{ sh[i] = light[i].xyz; }}\n\
             let turned = prtkit_rotate_sh(mat3x3<f32>(axis, axis.yzx, axis.zxy), sh);\n\
             var t: array<vec4<f32>, {v}>;\n for (var k = 0; k < {v}; k++) {{ t[k] = t0; }}\n\
             return vec4<f32>(prtkit_transfer_radiance(t, turned), 1.0);\n}}\n"
        );
        check_wgsl(&src, &format!("wgsl order {order}"));
        assert!(
            hlsl.contains("float3 prtkitTransferRadiance(float4 transfer[PRTKIT_TRANSFER_VEC4S])")
                && hlsl.contains(&format!("void prtkitRotateSH(float3x3 R, float3 sh[{c}], out float3 rotated[{c}])")),
            "{hlsl}"
        );
        assert!(!hlsl.contains("vec3") && !hlsl.contains("mat3"), "GLSL type names in the HLSL");
    }
}

/// Runs the body of a snippet's SH rotation as text: its `let`/`float` lines and `rotated[i] = …`
/// lines are sums of products of literals, names, `R[a][b]` and `sh[k]`, evaluated here in
/// f64 with `sh` one scalar channel; `matrix(a, b)` reads the language's `R[a][b]`.
fn run_rotation_text(text: &str, sh: &[f64], matrix: impl Fn(usize, usize) -> f64) -> Vec<f64> {
    let mut names = std::collections::HashMap::new();
    let mut rotated = vec![f64::NAN; sh.len()];
    let index = |f: &str, open: &str| -> Vec<usize> {
        f[open.len()..].trim_end_matches(']').split("][").map(|d| d.parse().unwrap()).collect()
    };
    for line in text.lines().map(str::trim) {
        let Some((lhs, rhs)) = line.strip_suffix(';').and_then(|l| l.split_once(" = ")) else { continue };
        // Tokens: a sign, then factors joined by `*`, then the next sign, …
        let expr = match rhs.strip_prefix('-') {
            Some(rest) => format!("- {rest}"),
            None => format!("+ {rhs}"),
        };
        let mut terms: Vec<f64> = Vec::new();
        for token in expr.split_whitespace() {
            match token {
                "+" => terms.push(1.0),
                "-" => terms.push(-1.0),
                "*" => {}
                f => {
                    let factor = if let Ok(x) = f.parse::<f64>() {
                        x
                    } else if f.starts_with("sh[") {
                        sh[index(f, "sh[")[0]]
                    } else if f.starts_with("R[") || f.starts_with("r[") {
                        let ab = index(f, "R[");
                        matrix(ab[0], ab[1])
                    } else {
                        *names.get(f).unwrap_or_else(|| panic!("{f} used before it is defined"))
                    };
                    *terms.last_mut().expect("a sign first") *= factor;
                }
            }
        }
        let value: f64 = terms.iter().sum();
        if let Some(i) = lhs.strip_prefix("rotated[") {
            rotated[i.trim_end_matches(']').parse::<usize>().unwrap()] = value;
        } else if let Some(name) = lhs.strip_prefix("let ").or_else(|| lhs.strip_prefix("float ")) {
            names.insert(name.to_string(), value);
        }
    }
    rotated
}

#[test]
fn the_snippets_rotation_text_turns_coefficients_as_shrotation_does() {
    // The emitted text itself (each language's matrix indexing included), evaluated line by
    // line, against the Rust rotation prtkit relights with: a wrong sign, transposed R or
    // misplaced band would show at order 8 for a generic rotation.
    use glam::DMat3;
    use prtkit::sh::rotate::ShRotation;
    use prtkit::transfer::shaders::{snippet, Language};
    let rotation = DMat3::from_axis_angle(DVec3::new(-0.4, 0.7, 0.2).normalize(), 2.3);
    let rows = rotation.transpose().to_cols_array_2d(); // rows[i][j] = R_ij
    for order in [1usize, 2, 3, 8] {
        let sh: Vec<f64> = (0..order * order).map(|i| ((i * 7919) % 13) as f64 / 13.0 - 0.4).collect();
        let want = ShRotation::new(rotation, order - 1).apply_scalar(&sh);
        for lang in [Language::Glsl, Language::Hlsl, Language::Wgsl] {
            let text = snippet(order, lang);
            let got = run_rotation_text(&text, &sh, |a, b| match lang {
                Language::Hlsl => rows[a][b],
                _ => rows[b][a],
            });
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                assert!((g - w).abs() < 1e-7, "{lang:?} order {order}, coefficient {i}: {g} vs {w}");
            }
        }
    }
}

#[test]
fn bad_meshes_exit_2_naming_the_file_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "not a finite"),
        ("huge.obj", "v 1e39 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "not a finite"),
        ("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n", "zero area"),
        ("empty.obj", "v 0 0 0\n", "no triangles"),
        ("mesh.ply", "ply\nformat ascii 1.0\nend_header\n", "no vertex element"),
        ("nan.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\nnan 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "not finite"),
        ("mesh.stl", "solid x\n", "reads OBJ, PLY and glTF"),
    ];
    let flags: &[&str] = &[];
    let cases = cases.iter().map(|c| (c, flags)).chain([
        (
            &("b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "--bounces 17 is outside 1..=16"),
            &["--mode", "interreflected", "--bounces", "17"][..],
        ),
        (
            &("c.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "--bounces is for --mode interreflected"),
            &["--bounces", "2"][..],
        ),
    ]);
    for (&(name, text, reason), flags) in cases {
        let mesh = dir.path().join(name);
        std::fs::write(&mesh, text).unwrap();
        let glb = dir.path().join("out.glb");
        let json = dir.path().join("out.json");
        let output =
            cmd("transfer").arg(&mesh).args(flags).arg("--glb").arg(&glb).arg("-o").arg(&json).output().unwrap();
        let message = stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{name}: {message}");
        // A bad option is named instead of the file when it is the option that is wrong.
        let names_file = message.contains(&mesh.display().to_string()) || name == "c.obj";
        assert!(names_file && message.contains(reason), "{name}: {message}");
        assert!(!glb.exists() && !json.exists(), "{name}: an output was written");
    }
    assert!(prtkit::limits::check_transfer_mesh("m.obj", prtkit::limits::MAX_TRANSFER_VERTICES + 1, 1).is_err());
    assert!(prtkit::limits::check_transfer_mesh("m.obj", 8, prtkit::limits::MAX_TRANSFER_TRIANGLES + 1).is_err());
}

/// The inside of a closed sphere of radius R (normals facing inward), a white furnace for the
/// interreflection passes. Two facts independent of the code under test:
///
/// - Every ray from the inside hits the inside (the front), so with a constant T^{b−1}_0 each
///   bounce's constant-lighting response is ρ times the previous one, exactly:
///   T^b_0 = (ρ/N) Σ_k T^{b−1}_0 = ρ T^{b−1}_0, and the total is T^0_0 (1 + ρ + … + ρ^B).
/// - Inside a sphere the form factor is uniform, cos θ_x cos θ_y / (π |x − y|²) = 1/(4πR²)
///   (the two cosines are |x − y|/(2R) each), so bounce 1 is ρ times the *mean* of T^0 over the
///   sphere: the mean of Y_lm(n) over a sphere is 0 for l ≥ 1, so T^1 has band 0 only, up to
///   the rays' noise and the polygonal sphere.
#[test]
fn furnace_inside_a_sphere_converges_to_the_geometric_series() {
    use prtkit::transfer::diffuse::unshadowed_exact;
    use prtkit::transfer::directions::Stratified;
    use prtkit::transfer::interreflect::{Storage, Tracer};
    use prtkit::transfer::visibility::Occluders;
    let (p, t) = uv_sphere(24, 48);
    let inward: Vec<DVec3> = p.iter().map(|v| -*v).collect();
    let mesh = Mesh::new(p.clone(), Some(inward.clone()), t.clone()).unwrap();
    let (order, albedo, bounces) = (3, 0.6, 4);
    let coeffs = order * order;
    let occluders = Occluders::new(&mesh.positions, &mesh.triangles);
    let directions = Stratified::new(1024, 0);
    let tracer = Tracer::new(&mesh, &occluders, &directions, order, 1e-4 * mesh.extent());
    let first = tracer.first_pass(albedo, Storage::Record, &NoProgress);
    // Every ray from the inside hits the inside's front, but for the odd one that slips through
    // a crack between two triangles of the single-precision traversal (it escapes, or meets a
    // back face), which loses 1/N of that vertex's bounce.
    let lost = 1.0 - first.front_fraction;
    assert!(lost < 1e-5, "{lost}");
    // The source term: the unshadowed transfer (what every vertex would get with V ≡ 1).
    let mut source = vec![0.0; p.len() * coeffs];
    for (v, n) in inward.iter().enumerate() {
        unshadowed_exact(*n, order, albedo, &mut source[v * coeffs..(v + 1) * coeffs]);
    }
    let t0 = albedo / (4.0 * PI).sqrt(); // (ρ/π) Â_0 Y_00 = ρ/√(4π)
    assert!(source.iter().step_by(coeffs).all(|&s| (s - t0).abs() < 1e-15));
    let passes = tracer.bounces(&source, bounces, Reflectance::Grey(albedo), &first.hits, &NoProgress);
    let mut total: Vec<f64> = source.iter().step_by(coeffs).copied().collect();
    let (mut worst_series, mut mean_series, mut exact) = (0.0f64, 0.0f64, 0usize);
    for (b, pass) in passes.iter().enumerate() {
        let expected = t0 * albedo.powi(b as i32 + 1);
        for (v, x) in pass.iter().step_by(coeffs).enumerate() {
            exact += (b == 0 && (x - expected).abs() < 1e-14 * t0) as usize;
            total[v] += x;
        }
    }
    let series: f64 = (0..=bounces).map(|k| albedo.powi(k as i32)).sum();
    for s in &total {
        let e = (s / (t0 * series) - 1.0).abs();
        worst_series = worst_series.max(e);
        mean_series += e / total.len() as f64;
    }
    let exact = exact as f64 / p.len() as f64;
    // Bounce 1 outside band 0 against its largest coefficient ρ T^0_0: the rays' noise.
    let worst_higher =
        passes[0].chunks_exact(coeffs).flat_map(|c| c[1..].iter().map(|x| x.abs())).fold(0.0f64, f64::max)
            / (albedo * t0);
    eprintln!(
        "furnace, albedo {albedo}, {bounces} bounces, {} vertices, rays lost {lost:.1e}: |total / (T0 (1 + r + ... + \
         r^B)) - 1| at most {worst_series:.1e}, mean {mean_series:.1e}; bounce 1 equal to r T0 to 1e-14 at \
         {:.2}% of the vertices; bounce 1 outside band 0 at most {worst_higher:.2e} of its band 0",
        p.len(),
        100.0 * exact
    );
    // A lost ray costs its vertex 1/N of a bounce, and its neighbours a share of that in later
    // bounces: a few rays of 1024 at worst, none at most vertices.
    assert!(worst_series < 4.0 / 1024.0 && mean_series < 1e-5, "{worst_series} {mean_series}");
    assert!(exact > 0.98, "{exact}");
    assert!(worst_higher < 0.02, "{worst_higher}");

    // Hits recorded or traced again in every bounce: the same bits.
    let retraced = tracer.first_pass(albedo, Storage::Retrace, &NoProgress);
    assert!(matches!(retraced.hits, prtkit::transfer::interreflect::Hits::Retraced));
    assert_eq!(tracer.bounces(&source, bounces, Reflectance::Grey(albedo), &retraced.hits, &NoProgress), passes);
}

#[test]
fn interreflected_equals_shadowed_on_a_convex_mesh() {
    // Nothing on a convex mesh is hit by its own rays: no bounce, the same bits as shadowed.
    let (p, t) = uv_sphere(12, 24);
    let mesh = Mesh::new(p.clone(), Some(p.clone()), t).unwrap();
    let base = Config { order: 4, rays: 256, ..Config::default() };
    let shadowed = stage::run(&Config { mode: Mode::Shadowed, ..base.clone() }, &mesh, &NoProgress).unwrap();
    let config = Config { mode: Mode::Interreflected, bounces: 3, ..base };
    let inter = stage::run(&config, &mesh, &NoProgress).unwrap();
    assert!(shadowed.transfer == inter.transfer, "interreflected differs from shadowed on a sphere");
    let info = inter.document.body.interreflection.unwrap();
    assert_eq!((info.front_hit_fraction, info.back_hit_fraction), (0.0, 0.0));
    assert_eq!(&info.white_sky_response[1..], &[0.0; 3]);
}

#[test]
fn interreflected_bowl_is_shadowed_plus_bounces_and_thread_independent() {
    let (p, n, t) = bowl_and_ball();
    let mesh = Mesh::new(p.clone(), Some(n.clone()), t.clone()).unwrap();
    let base = Config { order: 3, rays: 512, albedo: Albedo::Grey(0.8), ..Config::default() };
    let shadowed = stage::run(&Config { mode: Mode::Shadowed, ..base.clone() }, &mesh, &NoProgress).unwrap();
    let inter = stage::run(&Config { mode: Mode::Interreflected, ..base }, &mesh, &NoProgress).unwrap();
    let info = inter.document.body.interreflection.clone().unwrap();
    // The direct part is the shadowed transfer (the same rays, the closest-hit traversal finds
    // an occluder exactly when the any-hit one does); the bounces only add light to band 0 in
    // a concave bowl lit by a white sky (every T^{b−1}_0 ≥ 0).
    let w = info.white_sky_response.clone();
    assert!(w[1] > 0.0 && w[2] > 0.0 && w[2] < w[1] && w[1] < w[0], "{w:?}");
    for (v, (a, b)) in inter.transfer.chunks_exact(9).zip(shadowed.transfer.chunks_exact(9)).enumerate() {
        assert!(a[0] >= b[0], "vertex {v}: interreflected {} < shadowed {}", a[0], b[0]);
    }
    let mean = |t: &[f64]| (4.0 * PI).sqrt() * t.iter().step_by(9).sum::<f64>() / p.len() as f64;
    assert!((mean(&shadowed.transfer) - w[0]).abs() < 1e-12);
    assert!((mean(&inter.transfer) - w.iter().sum::<f64>()).abs() < 1e-12);
    eprintln!("bowl + ball, albedo 0.8: white-sky response direct, bounce 1, bounce 2 = {w:?}; hits {info:?}");

    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("scene.obj");
    write_obj(&obj, &p, &n, &t);
    let outputs = bakes_per_thread_count(
        dir.path(),
        &obj,
        &["-n", "4", "--rays", "256", "--mode", "interreflected", "--bounces", "3"],
    );
    assert_eq!(outputs[0].1["interreflection"]["bounces"], 3);
    assert!(outputs[0] == outputs[1], "interreflected outputs differ between --threads 1 and 2");
}

/// `render --json`'s metrics against `--compare`.
/// (PSNR is `null` when the images are equal, so the summary is read as JSON values.)
/// Runs `transfer ARGS` in `dir` and expects success.
fn transfer_in(dir: &Path, args: &[&str]) {
    cmd("transfer").args(args).current_dir(dir).assert().success();
}

fn render_metrics(args: &[&str], dir: &Path) -> Metrics {
    let out = cmd("render").args(args).args(["-q", "--json"]).current_dir(dir).output().unwrap();
    assert!(out.status.success(), "render {args:?}: {}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let at = |k: &str| v["metrics"][k].as_f64().unwrap_or(f64::NAN);
    Metrics { rel_error: at("rel_error"), max_rel_error: at("max_rel_error"), transfer: v["transfer"].clone() }
}

fn read_image(path: &Path) -> prtkit::io::RgbImage {
    prtkit::io::image::read_image(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// What the tests read of `render --json`.
#[derive(Debug)]
struct Metrics {
    rel_error: f64,
    max_rel_error: f64,
    transfer: serde_json::Value,
}

/// Writes `mesh` (positions and normals) as OBJ.
fn write_sphere(dir: &Path, rings: usize, segments: usize) -> std::path::PathBuf {
    let (p, t) = uv_sphere(rings, segments);
    let obj = dir.join("sphere.obj");
    write_obj(&obj, &p, &p, &t);
    obj
}

#[test]
fn relit_unshadowed_sphere_is_the_irradiance_shading() {
    // An unshadowed transfer relit under L is (ρ/π) Σ Â_l L_lm Y_lm(n) at every vertex
    // (R&H 2001, eq. 8–9), which `--shading irradiance` evaluates per pixel from the normal by
    // another code path; the two differ by the vertex interpolation of a function of the normal
    // (the transfer's Gouraud shading against irradiance at the interpolated normal) alone, of
    // order (edge length)²: small on a sphere of 96 × 192 quads.
    let dir = tempfile::tempdir().unwrap();
    common::sky_pfm(dir.path(), 64, 32);
    write_sphere(dir.path(), 96, 192);
    transfer_in(
        dir.path(),
        &["sphere.obj", "-n", "3", "--mode", "unshadowed", "--albedo", "0.7", "-q", "--glb", "s.glb", "-o", "s.json"],
    );
    let view = ["--scene", "sphere.obj", "--res", "96x96", "--brdf", "lambert:albedo=0.7"];
    let irradiance =
        [&["sky.pfm"][..], &view, &["--shading", "irradiance", "-F", "2", "--window", "none", "-o", "i.exr"]].concat();
    render_metrics(&irradiance, dir.path());
    let transfer =
        [&["sky.pfm"][..], &view, &["--shading", "transfer", "--transfer", "s.glb", "--compare", "i.exr"]].concat();
    let m = render_metrics(&transfer, dir.path());
    eprintln!(
        "unshadowed sphere (96 x 192), n = 3, relit vs irradiance F = 2: relative RMS {:.2e}, max {:.2e}",
        m.rel_error, m.max_rel_error
    );
    assert!(m.rel_error < 2e-4 && m.max_rel_error < 1e-3, "{m:?}");
    let relight = &m.transfer;
    assert_eq!((relight["order"].as_u64(), relight["mode"].as_str()), (Some(3), Some("unshadowed")));
    assert_eq!(relight["vertices"].as_u64(), Some(2 + 95 * 192));
    assert!(relight["frames_per_second"].as_f64().unwrap() > 0.0);
}

#[test]
fn relit_shadowed_bowl_approaches_the_reference_with_visibility() {
    // The bowl seen from above (its inside only), relit from its shadowed transfer, against
    // `--shading reference`: every texel of the map × BRDF × cosine × visibility by the mesh's
    // own ray casts, per pixel. The transfer's error is the lighting's SH truncation at n bands
    // (the test sky has a sun, cos²⁰⁰ wide, which no low order holds), the rays' noise and the
    // vertex interpolation: it must fall as n grows.
    let dir = tempfile::tempdir().unwrap();
    common::sky_pfm(dir.path(), 64, 32);
    let bowl = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/bowl.obj");
    let view = ["--scene", bowl.to_str().unwrap(), "--res", "64x64", "--eye", "0,0.01,3.5", "--target", "0,0,-0.3"];
    render_metrics(&[&["sky.pfm"][..], &view, &["--shading", "reference", "-o", "r.exr"]].concat(), dir.path());
    let mut errors = Vec::new();
    for n in ["2", "4", "8"] {
        transfer_in(
            dir.path(),
            &[bowl.to_str().unwrap(), "-n", n, "--rays", "4096", "-q", "--glb", "b.glb", "-o", "b.json"],
        );
        let args =
            [&["sky.pfm"][..], &view, &["--shading", "transfer", "--transfer", "b.glb", "--compare", "r.exr"]].concat();
        let m = render_metrics(&args, dir.path());
        eprintln!(
            "shadowed bowl, n = {n}, 4096 rays, relit vs reference with visibility: relative RMS {:.4}",
            m.rel_error
        );
        errors.push(m.rel_error);
    }
    assert!(errors[0] > errors[1] && errors[1] > errors[2] && errors[2] < 0.05, "{errors:?}");
}

#[test]
fn a_turned_environment_is_one_sh_rotation() {
    // Turning the environment by 90° about +Z is rolling a lat-long map by a quarter of its
    // width (φ = 2π(x + ½)/W, docs/conventions.md; the turned map at φ is the map at φ − 90°),
    // a symmetry of the projection's texel grid: the relit image with --env-rotation 90 must be
    // the relit image of the rolled map, to rounding; and the reference turns the same way.
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64, 32);
    let sky = common::sky_image(w, h);
    common::write_pfm(dir.path(), "sky.pfm", &sky);
    let mut rolled = sky.clone();
    for y in 0..h {
        for x in 0..w {
            rolled.pixels[y * w + x] = sky.pixels[y * w + (x + w - w / 4) % w];
        }
    }
    common::write_pfm(dir.path(), "rolled.pfm", &rolled);
    let bowl = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/bowl.obj");
    transfer_in(
        dir.path(),
        &[bowl.to_str().unwrap(), "-n", "5", "--rays", "512", "-q", "--glb", "b.glb", "-o", "b.json"],
    );
    let view = ["--scene", bowl.to_str().unwrap(), "--res", "48x48", "--eye", "0,0.01,3.5", "--target", "0,0,-0.3"];
    let relit = ["--shading", "transfer", "--transfer", "b.glb"];
    render_metrics(&[&["rolled.pfm"][..], &view, &relit, &["-o", "rolled.exr"]].concat(), dir.path());
    let turned =
        [&["sky.pfm"][..], &view, &relit, &["--env-rotation", "90", "--compare", "rolled.exr", "-o", "turned.exr"]]
            .concat();
    let m = render_metrics(&turned, dir.path());
    // The comparison covers the object; the background turns with the lighting too.
    let (a, b) = (read_image(&dir.path().join("turned.exr")), read_image(&dir.path().join("rolled.exr")));
    let worst =
        a.pixels.iter().flatten().zip(b.pixels.iter().flatten()).map(|(x, y)| (x - y).abs() / y.abs().max(1e-2));
    let worst = worst.fold(0.0f32, f32::max);
    assert!(worst < 1e-3, "--env-rotation 90 vs the rolled map, whole image: largest relative difference {worst:e}");
    let unturned = [&["sky.pfm"][..], &view, &relit, &["--compare", "rolled.exr"]].concat();
    let other = render_metrics(&unturned, dir.path());
    eprintln!(
        "--env-rotation 90 vs the rolled map: relative RMS {:.2e} (unturned: {:.2e})",
        m.rel_error, other.rel_error
    );
    assert!(m.rel_error < 1e-5 && other.rel_error > 1e-2, "{m:?} {other:?}");

    let reference = ["--shading", "reference"];
    render_metrics(&[&["rolled.pfm"][..], &view, &reference, &["-o", "ref-rolled.exr"]].concat(), dir.path());
    let turned =
        [&["sky.pfm"][..], &view, &reference, &["--env-rotation", "90", "--compare", "ref-rolled.exr"]].concat();
    let m = render_metrics(&turned, dir.path());
    eprintln!("reference --env-rotation 90 vs the rolled map: relative RMS {:.2e}", m.rel_error);
    assert!(m.rel_error < 1e-5, "{m:?}");
}

#[test]
fn a_bake_of_another_mesh_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    common::sky_pfm(dir.path(), 16, 8);
    let bowl = Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/bowl.obj");
    write_sphere(dir.path(), 8, 16);
    transfer_in(dir.path(), &["sphere.obj", "-q", "--rays", "16", "--glb", "s.glb", "-o", "s.json"]);
    std::fs::write(dir.path().join("junk.glb"), b"glTF not really").unwrap();
    let cases: [(&[&str], &str); 5] = [
        (&["--scene", bowl.to_str().unwrap(), "--transfer", "s.glb"], "s.glb: the transfer is of a mesh of"),
        (&["--scene", "sphere.obj", "--transfer", "junk.glb"], "junk.glb: not a prtkit transfer .glb"),
        (
            &["--scene", "sphere.obj", "--transfer", "s.glb", "--brdf", "lambert:albedo=0.5"],
            "s.glb: the transfer was baked with albedo 1",
        ),
        (&["--scene", "sphere", "--transfer", "s.glb"], "relights a mesh"),
        (&["--scene", "sphere.obj", "--transfer", "s.glb", "--env-rotation", "400"], "--env-rotation 400 is outside"),
    ];
    for (args, says) in cases {
        let out = cmd("render")
            .arg("sky.pfm")
            .args(["--shading", "transfer", "-o", "o.exr"])
            .args(args)
            .current_dir(dir.path())
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(says), "{args:?}: {}", stderr(&out));
        assert!(!dir.path().join("o.exr").exists());
    }
}

/// `p`, `n`, `t` as a binary little-endian PLY with normals and an extra property, quads left
/// as they are: the same mesh as [`write_obj`] writes.
fn write_ply(path: &Path, p: &[DVec3], n: &[DVec3], t: &[[u32; 3]]) {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nelement face {}\n\
         property list uchar uint vertex_indices\nend_header\n",
        p.len(),
        t.len()
    )
    .into_bytes();
    for (v, m) in p.iter().zip(n) {
        for c in [v.x, v.y, v.z, m.x, m.y, m.z] {
            b.extend((c as f32).to_le_bytes());
        }
        b.push(9);
    }
    for f in t {
        b.push(3);
        for i in f {
            b.extend(i.to_le_bytes());
        }
    }
    std::fs::write(path, b).unwrap();
}

#[test]
fn ply_and_obj_of_one_mesh_bake_the_same_transfer() {
    // The same vertices (to single precision, as both files hold them), normals and triangles:
    // the same transfer at every vertex. (tobj numbers an OBJ's vertices in the order the faces
    // first use them, a PLY keeps its own order: vertices are matched by position.)
    let dir = tempfile::tempdir().unwrap();
    let (p, n, t) = bowl_and_ball();
    let (obj, ply) = (dir.path().join("scene.obj"), dir.path().join("scene.ply"));
    write_obj(&obj, &p, &n, &t);
    write_ply(&ply, &p, &n, &t);
    let config = Config { order: 3, rays: 128, mode: Mode::Interreflected, ..Config::default() };
    let key = |v: DVec3| v.as_vec3().to_array().map(f32::to_bits);
    let mut baked = Vec::new();
    for path in [&obj, &ply] {
        let mesh = Mesh::load(path).unwrap();
        assert!(!mesh.normals_computed && mesh.triangles.len() == t.len(), "{}", path.display());
        let out = stage::run(&config, &mesh, &NoProgress).unwrap();
        let by_position: std::collections::BTreeMap<[u32; 3], Vec<f64>> =
            mesh.positions.iter().zip(out.transfer.chunks_exact(9)).map(|(v, x)| (key(*v), x.to_vec())).collect();
        assert_eq!(by_position.len(), p.len());
        baked.push(by_position);
    }
    assert!(baked[0] == baked[1], "the PLY's transfer differs from the OBJ's");
    // And through the binary: a PLY is baked like an OBJ.
    transfer_in(
        dir.path(),
        &[ply.to_str().unwrap(), "-n", "3", "--rays", "64", "-q", "--glb", "t.glb", "-o", "t.json"],
    );
    let doc: serde_json::Value = common::read(&dir.path().join("t.json"));
    assert_eq!(
        (doc["mesh"]["vertices"].as_u64(), doc["mesh"]["normals"].as_str()),
        (Some(p.len() as u64), Some("file"))
    );
}
