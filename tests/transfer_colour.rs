//! Diffuse transfer with a coloured albedo (`transfer --albedo R,G,B` and `--albedo mesh`; issue
//! 32, item 2): three transfer vectors per vertex, one per colour channel.
//!
//! - A constant colour (r, g, b) is three grey bakes: channel c of the coloured bake equals the
//!   grey bake of albedo ρ_c, in every mode, per vertex and per lightmap texel, and so do the
//!   relit pictures (`render --shading transfer`, with and without the lightmap).
//! - Colour bleeding against a closed form: inside a sphere the form factor is uniform, so each
//!   bounce of channel c is ρ_c(x) times the area mean of the previous bounce, and with a
//!   per-vertex albedo the bounces form ρ_c(x) T^0 m_c^b, m_c the area mean of ρ_c.
//! - The mesh's own colours (a PLY's sRGB vertex colours; a glTF base-colour texture at its
//!   vertices, times its factor): channel c is ρ_c(v) times the grey bake of albedo 1.
//! - The snippets compile (naga: GLSL and WGSL), and what cannot be baked is refused.

mod common;

use common::{check_glsl_fragment, check_wgsl, cmd, run_in, stderr, test_mesh};
use glam::DVec3;
use prtkit::mesh::{uv_sphere, Mesh};
use prtkit::progress::NoProgress;
use prtkit::render::transfer::TransferBake;
use std::f64::consts::PI;
use std::path::Path;

const COLOUR: [f64; 3] = [0.9, 0.5, 0.2];
const COLOUR_ARG: &str = "0.9,0.5,0.2";

/// The bake `name` in `dir`, read back as `render` reads it.
fn bake(dir: &Path, name: &str) -> TransferBake {
    let path = dir.join(name);
    TransferBake::from_glb(name, &std::fs::read(&path).unwrap()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The largest |a − b| over the largest |b|, `a` and `b` of one length.
fn relative_max(a: &[f32], b: &[f32]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs() as f64));
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs() as f64)) / scale
}

/// Channel `c` of a coloured transfer (3·n² values per vertex or texel, channel-major).
fn channel(values: &[f32], coeffs: usize, c: usize) -> Vec<f32> {
    values.chunks_exact(3 * coeffs).flat_map(|t| t[c * coeffs..(c + 1) * coeffs].to_vec()).collect()
}

#[test]
fn a_constant_colour_is_three_grey_bakes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = test_mesh("floor-ball.obj");
    let env = common::sky_pfm(d, 64, 32);
    let env = env.to_str().unwrap();
    let coeffs = 9;
    for mode in ["unshadowed", "shadowed", "interreflected"] {
        let bake_with = |tag: &str, albedo: &str| {
            let mut args =
                vec![mesh.as_str(), "-n", "3", "--mode", mode, "--rays", "64", "--albedo", albedo, "--threads", "2"];
            let (glb, json, exr) = (format!("{tag}.glb"), format!("{tag}.json"), format!("{tag}.exr"));
            args.extend(["--glb", &glb, "-o", &json, "--lightmap", "24x24", &exr]);
            run_in(d, "transfer", &args);
        };
        bake_with("rgb", COLOUR_ARG);
        let rgb = bake(d, "rgb.glb");
        assert_eq!((rgb.channels, rgb.albedo), (3, None), "{mode}");
        assert_eq!(rgb.transfer.len(), 3 * coeffs * rgb.positions.len());
        let manifest: serde_json::Value = common::read(&d.join("rgb.json"));
        assert_eq!(manifest["channels"], 3);
        assert_eq!(manifest["coefficients"], 27);
        assert_eq!(manifest["albedo"], serde_json::json!(COLOUR));
        let rgb_layers = prtkit::io::exr::read_layers(&d.join("rgb.exr")).unwrap();
        let mut worst = (0.0f64, 0.0f64, 0.0f64);
        for (c, rho) in COLOUR.iter().enumerate() {
            let tag = format!("grey{c}");
            bake_with(&tag, &rho.to_string());
            let grey = bake(d, &format!("{tag}.glb"));
            assert_eq!((grey.channels, grey.albedo), (1, Some(*rho)));
            // Per vertex: the grey bake folds ρ_c into its rays' sum, the coloured one scales
            // the sum at ρ = 1 afterwards: equal up to rounding.
            worst.0 = worst.0.max(relative_max(&channel(&rgb.transfer, coeffs, c), &grey.transfer));
            // Per texel: layer T_i's channel c against the grey lightmap's layer T_i.
            let grey_layers = prtkit::io::exr::read_layers(&d.join(format!("{tag}.exr"))).unwrap();
            for i in 0..coeffs {
                let layer = |layers: &[(String, prtkit::io::RgbImage)], k: usize| -> Vec<f32> {
                    let (_, image) = layers.iter().find(|(n, _)| *n == format!("T{i}")).expect("layer T_i");
                    image.pixels.iter().map(|p| p[k]).collect()
                };
                worst.1 = worst.1.max(relative_max(&layer(&rgb_layers, c), &layer(&grey_layers, 0)));
            }
            // Relit: channel c of the coloured picture is channel c of the grey one.
            let render = |glb: &str, brdf: &str, out: &str, lightmap: Option<&str>| {
                let mut args = vec![env, "--scene", mesh.as_str(), "--shading", "transfer", "--transfer", glb];
                args.extend(["--brdf", brdf, "--eye", "2,-2.5,2", "--target", "0,0,0.2", "--res", "64x64", "-o", out]);
                if let Some(l) = lightmap {
                    args.extend(["--lightmap", l]);
                }
                run_in(d, "render", &args);
                prtkit::io::image::read_image(&d.join(out)).unwrap()
            };
            for lightmap in [None, Some(("rgb.exr", format!("{tag}.exr")))] {
                let a = render("rgb.glb", "lambert", "rgb-render.exr", lightmap.as_ref().map(|l| l.0));
                let brdf = format!("lambert:albedo={rho}");
                let b =
                    render(&format!("{tag}.glb"), &brdf, "grey-render.exr", lightmap.as_ref().map(|l| l.1.as_str()));
                let pa: Vec<f32> = a.pixels.iter().map(|p| p[c]).collect();
                let pb: Vec<f32> = b.pixels.iter().map(|p| p[c]).collect();
                worst.2 = worst.2.max(relative_max(&pa, &pb));
            }
        }
        eprintln!(
            "{mode}, albedo {COLOUR:?}: channel c against the grey bake of albedo rho_c, largest difference over the \
             largest value: per vertex {:.1e}, per texel {:.1e}, relit {:.1e}",
            worst.0, worst.1, worst.2
        );
        assert!(worst.0 < 1e-6 && worst.1 < 1e-6 && worst.2 < 1e-5, "{mode}: {worst:?}");
    }
}

/// Inside a sphere every ray of a vertex meets the inside, at points spread uniformly over its
/// area (the form factor is cos θ_x cos θ_y / (π |x − y|²) = 1/(4πR²)). So bounce b of channel
/// c at x is ρ_c(x) times the area mean of bounce b − 1: from T^0(x) = ρ_c(x) t_0,
/// T^b(x) = ρ_c(x) t_0 m_c^b, m_c the area mean of ρ_c (of its linear interpolation over the
/// triangles, which the bounces gather). A different albedo per channel and per vertex, each
/// channel gathering only its own, is what colour bleeding is.
#[test]
fn colour_bleeds_inside_a_sphere_as_the_closed_form_says() {
    use prtkit::transfer::albedo::{colourize, Reflectance};
    use prtkit::transfer::diffuse::unshadowed_exact;
    use prtkit::transfer::directions::Stratified;
    use prtkit::transfer::interreflect::{Storage, Tracer};
    use prtkit::transfer::visibility::Occluders;
    let (p, t) = uv_sphere(24, 48);
    let inward: Vec<DVec3> = p.iter().map(|v| -*v).collect();
    let mesh = Mesh::new(p.clone(), Some(inward.clone()), t.clone()).unwrap();
    // Red brighter at the top, green constant, blue brighter towards −x: smooth, so that 1024
    // rays sample the mean well.
    let rho: Vec<[f64; 3]> = p.iter().map(|v| [0.3 + 0.25 * v.z, 0.6, 0.85 - 0.1 * v.x]).collect();
    let (order, bounces) = (3, 3);
    let coeffs = order * order;
    let occluders = Occluders::new(&mesh.positions, &mesh.triangles);
    let directions = Stratified::new(1024, 0);
    let tracer = Tracer::new(&mesh, &occluders, &directions, order, 1e-4 * mesh.extent());
    let first = tracer.first_pass(1.0, Storage::Record, &NoProgress);
    assert!(1.0 - first.front_fraction < 1e-5);
    // The source: the unshadowed transfer at ρ = 1, t_0 = 1/√(4π) in band 0 at every vertex.
    let mut grey = vec![0.0; p.len() * coeffs];
    for (v, n) in inward.iter().enumerate() {
        unshadowed_exact(*n, order, 1.0, &mut grey[v * coeffs..(v + 1) * coeffs]);
    }
    let t0 = 1.0 / (4.0 * PI).sqrt();
    let source = colourize(&grey, coeffs, &rho);
    let passes = tracer.bounces(&source, bounces, Reflectance::Rgb(&rho), &first.hits, &NoProgress);
    // m_c: each vertex weighs a third of the area of its triangles.
    let mut area = vec![0.0; p.len()];
    for tri in &t {
        let [a, b, c] = tri.map(|i| p[i as usize]);
        let third = (b - a).cross(c - a).length() / 6.0;
        tri.iter().for_each(|&i| area[i as usize] += third);
    }
    let total: f64 = area.iter().sum();
    let m: Vec<f64> = (0..3).map(|c| rho.iter().zip(&area).map(|(r, a)| r[c] * a).sum::<f64>() / total).collect();
    let mut worst = [0.0f64; 3];
    for (b, pass) in passes.iter().enumerate() {
        for (v, values) in pass.chunks_exact(3 * coeffs).enumerate() {
            for c in 0..3 {
                let expected = rho[v][c] * t0 * m[c].powi(b as i32 + 1);
                worst[b] = worst[b].max((values[c * coeffs] - expected).abs() / expected);
            }
        }
    }
    eprintln!(
        "sphere inside, per-vertex albedo, area means m = {m:.4?}: bounces 1..3 of band 0 against rho_c(x) t0 m_c^b, \
         largest relative difference {worst:?}"
    );
    assert!(worst.iter().all(|&w| w < 0.02), "{worst:?}");
    // The channels' means differ by far more than that bound, so a bounce that gathered another
    // channel's light would fail it.
    assert!((0..3).all(|c| (m[c] / m[(c + 1) % 3] - 1.0).abs() > 0.2), "{m:?}");
}

#[test]
fn the_mesh_colours_scale_each_channel_of_the_shadowed_transfer() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = test_mesh("corner-ball.ply");
    let base = [mesh.as_str(), "-n", "3", "--rays", "64"];
    run_in(d, "transfer", &[&base[..], &["--albedo", "mesh", "--glb", "mesh.glb", "-o", "mesh.json"]].concat());
    run_in(d, "transfer", &[&base[..], &["--glb", "grey.glb", "-o", "grey.json"]].concat());
    let (coloured, grey) = (bake(d, "mesh.glb"), bake(d, "grey.glb"));
    assert_eq!(coloured.channels, 3);
    let colours = Mesh::load_coloured(Path::new(&mesh)).unwrap().base_colors.expect("the PLY's vertex colours");
    let coeffs = 9;
    let expected: Vec<f32> = grey
        .transfer
        .chunks_exact(coeffs)
        .zip(&colours)
        .flat_map(|(t, rho)| rho.iter().flat_map(move |r| t.iter().map(move |x| (r * *x as f64) as f32)))
        .collect();
    let difference = relative_max(&coloured.transfer, &expected);
    eprintln!("--albedo mesh on {mesh}: against rho_c(v) times the grey bake, {difference:.1e} of the largest value");
    assert!(difference < 1e-6, "{difference}");
    let manifest: serde_json::Value = common::read(&d.join("mesh.json"));
    assert_eq!(manifest["albedo"]["source"], "mesh");
    // The ball's and the red wall's sRGB 235 and the walls' 45 decoded (the sRGB transfer function, IEC 61966-2-1):
    // the largest and the smallest of every channel.
    let decode = |code: f64| ((code / 255.0 + 0.055) / 1.055f64).powf(2.4);
    for c in 0..3 {
        let (lo, hi) = (manifest["albedo"]["min"][c].as_f64().unwrap(), manifest["albedo"]["max"][c].as_f64().unwrap());
        assert!((lo - decode(45.0)).abs() < 1e-9 && (hi - decode(235.0)).abs() < 1e-9, "{}", manifest["albedo"]);
    }
}

/// A quad (normal +Z) whose four vertices sit on the four texel centres of a 2×2 base-colour
/// texture, `baseColorFactor` (0.5, 1, 1): `transfer --albedo mesh` (unshadowed) gives each
/// vertex channel c = factor_c × decode(code_c) × the grey transfer at albedo 1, the texture's
/// sRGB codes decoded here (IEC 61966-2-1), independently of the reader.
#[test]
fn a_base_colour_texture_is_the_albedo_at_each_vertex() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let codes: [[u8; 3]; 4] = [[255, 0, 0], [0, 128, 0], [40, 40, 200], [255, 255, 255]];
    image::RgbImage::from_fn(2, 2, |x, y| image::Rgb(codes[(2 * y + x) as usize])).save(d.join("albedo.png")).unwrap();
    // Vertex k on texel k's centre (texel (x, y) at UV ((x + ½)/2, (y + ½)/2), row 0 the top).
    let uvs = [[0.25f32, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]];
    let positions = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let mut bin: Vec<u8> = Vec::new();
    positions.iter().flatten().for_each(|v| bin.extend(v.to_le_bytes()));
    positions.iter().for_each(|_| [0.0f32, 0.0, 1.0].iter().for_each(|v| bin.extend(v.to_le_bytes())));
    uvs.iter().flatten().for_each(|v| bin.extend(v.to_le_bytes()));
    [0u32, 1, 3, 0, 3, 2].iter().for_each(|i| bin.extend(i.to_le_bytes()));
    std::fs::write(d.join("quad.bin"), &bin).unwrap();
    let gltf = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3,
                                    "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 1.0, 1.0, 1.0],
                                                "baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0}], "images": [{"uri": "albedo.png"}],
        "buffers": [{"uri": "quad.bin", "byteLength": bin.len()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 96, "byteLength": 32}, {"buffer": 0, "byteOffset": 128, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5125, "count": 6, "type": "SCALAR"}],
    });
    std::fs::write(d.join("quad.gltf"), gltf.to_string()).unwrap();
    let base = ["quad.gltf", "-n", "2", "--mode", "unshadowed"];
    run_in(d, "transfer", &[&base[..], &["--albedo", "mesh", "--glb", "c.glb", "-o", "c.json"]].concat());
    run_in(d, "transfer", &[&base[..], &["--glb", "g.glb", "-o", "g.json"]].concat());
    let (coloured, grey) = (bake(d, "c.glb"), bake(d, "g.glb"));
    let decode = |code: u8| {
        let c = code as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055f64).powf(2.4)
        }
    };
    let factor = [0.5, 1.0, 1.0];
    let coeffs = 4;
    let mut worst = 0.0f64;
    for v in 0..4 {
        for c in 0..3 {
            let rho = factor[c] * decode(codes[v][c]);
            for i in 0..coeffs {
                let expected = rho * grey.transfer[v * coeffs + i] as f64;
                let got = coloured.transfer[v * 3 * coeffs + c * coeffs + i] as f64;
                worst = worst.max((got - expected).abs());
            }
        }
    }
    // The grey transfer's band 0 at albedo 1 is Â_0 Y_00 / π = 1/√(4π) ≈ 0.28: f32 rounding.
    assert!(worst < 1e-7, "{worst}");
}

#[test]
fn colour_snippets_compile_and_dot_each_channel_with_its_own_lighting() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for order in [1usize, 3, 5] {
        let mesh = test_mesh("bowl.obj");
        let n = order.to_string();
        let args = [mesh.as_str(), "--mode", "unshadowed", "-n", &n, "--albedo", COLOUR_ARG, "--glb", "t.glb"];
        run_in(d, "transfer", &[&args[..], &["-o", "t.json", "--glsl", "t.glsl", "--wgsl", "t.wgsl"]].concat());
        let glsl = std::fs::read_to_string(d.join("t.glsl")).unwrap();
        let wgsl = std::fs::read_to_string(d.join("t.wgsl")).unwrap();
        let (c, v) = (order * order, (3 * order * order).div_ceil(4));
        // Every value of the layout meets its own channel of its own coefficient, once.
        for value in 0..3 * c {
            let lane = ["x", "y", "z", "w"];
            let term = format!(
                "transfer[{}].{} * prtkitLightSH[{}].{}",
                value / 4,
                lane[value % 4],
                value % c,
                lane[value / c]
            );
            assert_eq!(
                glsl.matches(&format!("{term} ")).count()
                    + glsl.matches(&format!("{term},")).count()
                    + glsl.matches(&format!("{term})")).count(),
                1,
                "order {order}: {term}"
            );
        }
        let src = format!(
            "#version 450\n#define PRTKIT_LIGHT_SH_DECLARED\n\
             layout(std140, binding = 0) uniform Light {{ vec3 prtkitLightSH[{c}]; }};\n{glsl}\
             layout(location = 0) in vec4 t0;\nlayout(location = 0) out vec4 o;\n\
             void main() {{ vec4 t[{v}]; for (int k = 0; k < {v}; ++k) t[k] = t0; \
             o = vec4(prtkitTransferRadianceRGB(t), 1.0); }}\n"
        );
        check_glsl_fragment(&src, &format!("glsl order {order}"));
        let src = format!(
            "{wgsl}@group(0) @binding(0) var<uniform> light: array<vec4<f32>, {c}>;\n\
             @fragment fn main(@location(0) t0: vec4<f32>) -> @location(0) vec4<f32> {{\n\
             var sh: array<vec3<f32>, {c}>;\n for (var i = 0; i < {c}; i++) {{ sh[i] = light[i].xyz; }}\n\
             var t: array<vec4<f32>, {v}>;\n for (var k = 0; k < {v}; k++) {{ t[k] = t0; }}\n\
             return vec4<f32>(prtkit_transfer_radiance_rgb(t, sh), 1.0);\n}}\n"
        );
        check_wgsl(&src, &format!("wgsl order {order}"));
    }
}

/// Runs `transfer` in `dir`, expecting exit 2 with `message` on stderr and nothing written.
fn refused(dir: &Path, args: &[&str], message: &str) {
    let out = cmd("transfer").args(args).args(["--glb", "x.glb", "-o", "x.json"]).current_dir(dir).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
    assert!(stderr(&out).contains(message), "{args:?}: {}", stderr(&out));
    assert!(!dir.join("x.glb").exists() && !dir.join("x.json").exists(), "{args:?}: an output was written");
}

#[test]
fn what_a_coloured_albedo_cannot_bake_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let bowl = test_mesh("bowl.obj");
    let bowl = bowl.as_str();
    refused(d, &[bowl, "--albedo", "0.5,0.5"], "an albedo is a number");
    refused(d, &[bowl, "--albedo", "0.5,-0.1,0.2"], "--albedo -0.1 must be a finite number ≥ 0");
    refused(d, &[bowl, "--albedo", "mesh"], "bowl.obj");
    let factors = ["phong:s=8", "--domain", "hemisphere", "--resolution", "8", "--cosine", "--factors", "p.exr"];
    run_in(d, "factor-brdf", &[&factors[..], &["--terms", "2", "-o", "p.json"]].concat());
    refused(d, &[bowl, "--factors", "p.json", "-K", "2", "--albedo", COLOUR_ARG], "for diffuse transfer");
    // render refuses a coloured bake with a Lambert of another albedo: its colour is in the bake.
    run_in(d, "transfer", &[bowl, "--mode", "unshadowed", "--albedo", COLOUR_ARG, "--glb", "c.glb", "-o", "c.json"]);
    let env = common::sky_pfm(d, 32, 16);
    let out = cmd("render")
        .arg(&env)
        .args(["--scene", bowl, "--shading", "transfer", "--transfer", "c.glb", "--brdf", "lambert:albedo=0.5"])
        .args(["--res", "16x16", "-o", "r.exr"])
        .current_dir(d)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("coloured albedo"), "{}", stderr(&out));
    assert!(!d.join("r.exr").exists());
}
