//! `transfer --quantize i16|i8` (issue 32 item 5): the per-vertex values stored as normalized
//! SHORT or BYTE with a scale per value index (or per CPCA cluster), checked against the float
//! bake of the same mesh by reading both `.glb` files here, with this file's own accessor
//! reader (not `render`'s, not the writer's figures):
//!
//! - every dequantized value, code / q × scale, is the float bake's within half a code step
//!   × scale (plus the float file's own f32 rounding), and each group's largest value takes the
//!   code ±q (the scale is that group's largest |value|);
//! - the manifest's relative RMS error is that of the values read back, and lies within its
//!   closed-form bound, recomputed here from the stored scales;
//! - `render --shading transfer` relights a quantized bake within the bound's effect on the
//!   picture: per pixel |ΔB| ≤ Σ_i (s_i / 2q) |L_i| (B = Σ_i T_i L_i interpolated over each
//!   triangle, a convex combination of the vertices');
//! - an unknown `--quantize` exits 2 naming the flag; `render` refuses an attribute of a component
//!   type the bake does not declare, naming the file.

mod common;

use common::{check_glsl_fragment, check_wgsl, cmd, run_in, stderr, test_mesh};
use serde_json::Value;
use std::path::Path;

/// A `.glb` read here: its JSON and BIN chunks (glTF 2.0 §4.4).
struct Glb {
    json: Value,
    bin: Vec<u8>,
}

impl Glb {
    fn read(path: &Path) -> Glb {
        let bytes = std::fs::read(path).unwrap();
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        assert_eq!(&bytes[0..4], b"glTF");
        let json_len = word(12);
        let json = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
        let at = 20 + json_len;
        assert_eq!(&bytes[at + 4..at + 8], b"BIN\0");
        Glb { json, bin: bytes[at + 8..at + 8 + word(at)].to_vec() }
    }

    /// Attribute `name`: its component type, whether normalized, and its raw values (codes for
    /// integers), component after component.
    fn attribute(&self, name: &str) -> (u64, bool, Vec<f64>) {
        let index = self.json["meshes"][0]["primitives"][0]["attributes"][name].as_u64().unwrap();
        let a = &self.json["accessors"][index as usize];
        let view = &self.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let components = match a["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC4" => 4,
            other => panic!("{other}"),
        };
        let n = a["count"].as_u64().unwrap() as usize * components;
        let ty = a["componentType"].as_u64().unwrap();
        let b = &self.bin[start..];
        let values = match ty {
            5126 => (0..n).map(|k| f32::from_le_bytes(b[4 * k..4 * k + 4].try_into().unwrap()) as f64).collect(),
            5122 => (0..n).map(|k| i16::from_le_bytes([b[2 * k], b[2 * k + 1]]) as f64).collect(),
            5120 => (0..n).map(|k| b[k] as i8 as f64).collect(),
            other => panic!("component type {other}"),
        };
        (ty, a["normalized"].as_bool().unwrap_or(false), values)
    }

    /// `per_vertex` values a vertex from VEC4 attributes PREFIX0, PREFIX1, …: the component type
    /// and the raw values.
    fn vec4s(&self, prefix: &str, per_vertex: usize) -> (u64, Vec<f64>) {
        let columns: Vec<(u64, bool, Vec<f64>)> =
            (0..per_vertex.div_ceil(4)).map(|k| self.attribute(&format!("{prefix}{k}"))).collect();
        let vertices = columns[0].2.len() / 4;
        let mut out = Vec::with_capacity(vertices * per_vertex);
        for v in 0..vertices {
            for i in 0..per_vertex {
                out.push(columns[i / 4].2[4 * v + i % 4]);
            }
        }
        let ty = columns[0].0;
        assert!(columns.iter().all(|c| c.0 == ty && c.1 == (ty != 5126)), "mixed or unnormalized attributes");
        (ty, out)
    }

    /// The f32 blob `name` (`extras."prtkit.blobs"`).
    fn blob(&self, name: &str) -> Vec<f64> {
        let entry = &self.json["meshes"][0]["extras"]["prtkit.blobs"][name];
        let view = &self.json["bufferViews"][entry["bufferView"].as_u64().unwrap() as usize];
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let count = entry["count"].as_u64().unwrap() as usize;
        (0..count)
            .map(|k| f32::from_le_bytes(self.bin[start + 4 * k..start + 4 * k + 4].try_into().unwrap()) as f64)
            .collect()
    }
}

/// The largest code q of a component type.
fn code_max(component_type: u64) -> f64 {
    match component_type {
        5122 => 32767.0,
        5120 => 127.0,
        other => panic!("not a quantized component type: {other}"),
    }
}

/// Checks the dequantized `codes` (scale of value k: `scales[group(k)]`) against `floats`: within
/// half a code step of their scale (plus the f32 rounding of the float file), and each group's
/// largest |value| coded as ±q. Returns ‖dequantized − floats‖².
fn check_codes(codes: &[f64], q: f64, scales: &[f64], group: impl Fn(usize) -> usize, floats: &[f64]) -> f64 {
    assert_eq!(codes.len(), floats.len());
    let mut largest_code = vec![0.0f64; scales.len()];
    let mut diff2 = 0.0;
    for (k, (&c, &f)) in codes.iter().zip(floats).enumerate() {
        let s = scales[group(k)];
        assert!(c.abs() <= q, "code {c}");
        let value = (c / q).max(-1.0) * s;
        let half_step = s / (2.0 * q);
        assert!(
            (value - f).abs() <= half_step + s * 2f64.powi(-23),
            "value {k}: {value} vs {f}, half a step {half_step}"
        );
        largest_code[group(k)] = largest_code[group(k)].max(c.abs());
        diff2 += (value - f).powi(2);
    }
    for (g, (&c, &s)) in largest_code.iter().zip(scales).enumerate() {
        assert!(s == 0.0 || c == q, "group {g}: scale {s}, largest code {c}");
    }
    diff2
}

fn manifest(dir: &Path, name: &str) -> Value {
    common::read(&dir.join(name))
}

/// Bakes `bowl-ball.obj` at order 4 with `extra` arguments and `--quantize` none, i16 and i8
/// into `{stem}-{kind}.glb/.json`.
fn bakes(d: &Path, stem: &str, extra: &[&str]) {
    let mesh = test_mesh("bowl-ball.obj");
    for kind in ["none", "i16", "i8"] {
        let (glb, json) = (format!("{stem}-{kind}.glb"), format!("{stem}-{kind}.json"));
        let base = [mesh.as_str(), "-n", "4", "--rays", "256", "--quantize", kind, "--glb", &glb, "-o", &json];
        run_in(d, "transfer", &[&base[..], extra].concat());
    }
}

#[test]
fn quantized_values_are_the_float_bake_within_half_a_code_step_and_the_error_is_as_stated() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    bakes(d, "t", &[]);
    let float = Glb::read(&d.join("t-none.glb"));
    let (ty, floats) = float.vec4s("_PRT_", 16);
    assert_eq!(ty, 5126);
    let reference2: f64 = floats.iter().map(|t| t * t).sum();
    let vertices = floats.len() / 16;
    assert!(manifest(d, "t-none.json").get("quantization").is_none());
    for (kind, expected_type) in [("i16", 5122), ("i8", 5120)] {
        let glb = Glb::read(&d.join(format!("t-{kind}.glb")));
        let (ty, codes) = glb.vec4s("_PRT_", 16);
        assert_eq!(ty, expected_type);
        let q = code_max(ty);
        let scales = glb.blob("transfer.scales");
        assert_eq!(scales.len(), 16);
        let diff2 = check_codes(&codes, q, &scales, |k| k % 16, &floats);
        let m = manifest(d, &format!("t-{kind}.json"));
        let stated = &m["quantization"];
        assert_eq!(
            stated["scales"].as_array().unwrap().iter().map(|s| s.as_f64().unwrap() as f32 as f64).collect::<Vec<_>>(),
            scales
        );
        let measured = (diff2 / reference2).sqrt();
        let bound = (vertices as f64 * scales.iter().map(|s| (s / (2.0 * q)).powi(2)).sum::<f64>() / reference2).sqrt();
        let (rms, rms_bound) =
            (stated["relative_rms"].as_f64().unwrap(), stated["relative_rms_bound"].as_f64().unwrap());
        eprintln!(
            "{kind}: relative RMS read back {measured:.4e}, manifest {rms:.4e}, bound {bound:.4e} ({rms_bound:.4e})"
        );
        assert!((measured - rms).abs() <= 1e-3 * rms, "{measured} vs {rms}");
        assert!((bound - rms_bound).abs() <= 1e-6 * bound, "{bound} vs {rms_bound}");
        assert!(rms <= rms_bound && stated["max_error_over_half_step"].as_f64().unwrap() <= 1.0);
    }
}

#[test]
fn quantized_cpca_weights_have_a_scale_per_cluster_within_half_a_code_step() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    bakes(d, "c", &["--clusters", "16", "--pca", "4"]);
    let float = Glb::read(&d.join("c-none.glb"));
    let (_, _, clusters) = float.attribute("_PRT_CLUSTER");
    let (_, weights) = float.vec4s("_PRT_W_", 4);
    let (means, bases) = (float.blob("cpca.means"), float.blob("cpca.bases"));
    // ‖T‖² of the float file's reconstruction (the manifest's denominator is the f64 bake's ‖T‖,
    // which the reconstruction approximates to its own error, a few per cent here).
    let transfer = |w: &[f64]| -> Vec<f64> {
        let mut t = Vec::new();
        for (v, &c) in clusters.iter().enumerate() {
            let c = c as usize;
            for i in 0..16 {
                t.push(means[c * 16 + i] + (0..4).map(|p| w[v * 4 + p] * bases[(c * 4 + p) * 16 + i]).sum::<f64>());
            }
        }
        t
    };
    let float_t = transfer(&weights);
    for kind in ["i16", "i8"] {
        let glb = Glb::read(&d.join(format!("c-{kind}.glb")));
        assert_eq!(glb.attribute("_PRT_CLUSTER").2, clusters, "quantization moved a vertex to another cluster");
        let (ty, codes) = glb.vec4s("_PRT_W_", 4);
        let q = code_max(ty);
        let scales = glb.blob("cpca.scales");
        assert_eq!(scales.len(), 16);
        check_codes(&codes, q, &scales, |k| clusters[k / 4] as usize, &weights);
        let dequantized: Vec<f64> =
            codes.iter().enumerate().map(|(k, c)| (c / q).max(-1.0) * scales[clusters[k / 4] as usize]).collect();
        let diff2: f64 = transfer(&dequantized).iter().zip(&float_t).map(|(a, b)| (a - b).powi(2)).sum();
        let ref2: f64 = float_t.iter().map(|t| t * t).sum();
        let stated = &manifest(d, &format!("c-{kind}.json"))["quantization"];
        let rms = stated["relative_rms"].as_f64().unwrap();
        let measured = (diff2 / ref2).sqrt();
        eprintln!("CPCA {kind}: relative RMS read back {measured:.4e}, manifest {rms:.4e}");
        assert!((measured - rms).abs() <= 0.05 * rms, "{measured} vs {rms}");
        assert!(rms <= stated["relative_rms_bound"].as_f64().unwrap());
        assert_eq!(stated["scale_per"], "cluster");
    }
}

#[test]
fn render_relights_a_quantized_bake_within_the_bound_on_every_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    common::sky_pfm(d, 64, 32);
    bakes(d, "r", &[]);
    let mesh = test_mesh("bowl-ball.obj");
    let view = ["--scene", mesh.as_str(), "--res", "48x48", "--eye", "0,-1.6,3.2", "--target", "0,0,-0.45"];
    for kind in ["none", "i16", "i8"] {
        let args = ["--shading", "transfer", "--transfer", &format!("r-{kind}.glb"), "-o", &format!("r-{kind}.exr")];
        run_in(d, "render", &[&["sky.pfm"][..], &view, &args].concat());
    }
    // The lighting's SH as render projects it (bands 0..3 of the same sky).
    let light = prtkit::sh::project::project(&common::sky(64, 32), 3, &prtkit::progress::NoProgress).unwrap();
    let image = |kind: &str| {
        let path = d.join(format!("r-{kind}.exr"));
        prtkit::io::exr::decode(&path, &std::fs::read(&path).unwrap()).unwrap()
    };
    let float = image("none");
    for kind in ["i16", "i8"] {
        let glb = Glb::read(&d.join(format!("r-{kind}.glb")));
        let q = code_max(glb.attribute("_PRT_0").0);
        let scales = glb.blob("transfer.scales");
        let bound: Vec<f64> = (0..3)
            .map(|ch| scales.iter().zip(&light.rgb).map(|(s, l)| s / (2.0 * q) * l[ch].abs()).sum::<f64>())
            .collect();
        let quantized = image(kind);
        let (mut worst, mut moved) = (0.0f64, 0usize);
        for (a, b) in quantized.pixels.iter().zip(&float.pixels) {
            for ch in 0..3 {
                let delta = (a[ch] as f64 - b[ch] as f64).abs();
                // The f32 sums of the two renders round differently: 10⁻⁶ of the pixel.
                assert!(delta <= bound[ch] + 1e-6 * (b[ch] as f64).abs(), "{kind}: |ΔB| {delta} > {}", bound[ch]);
                worst = worst.max(delta / bound[ch]);
                moved += (delta > 0.0) as usize;
            }
        }
        eprintln!("{kind}: largest pixel change {worst:.3} of the bound; {moved} channel values moved");
        assert!(moved > 0, "{kind}: the quantized picture is the float one");
    }
}

#[test]
fn bad_values_exit_2_naming_the_flag_and_render_names_the_file_of_an_unexpected_type() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = test_mesh("bowl-ball.obj");
    let out = cmd("transfer")
        .args([mesh.as_str(), "--rays", "16", "--quantize", "f16", "--glb", "x.glb", "-o", "x.json"])
        .current_dir(d)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--quantize"), "{}", stderr(&out));
    assert!(!d.join("x.glb").exists() && !d.join("x.json").exists());
    // An i16 bake whose extras say i8: its attributes are of a type the bake does not declare.
    run_in(
        d,
        "transfer",
        &[mesh.as_str(), "-n", "3", "--rays", "16", "--quantize", "i16", "--glb", "q.glb", "-o", "q.json"],
    );
    let mut bytes = std::fs::read(d.join("q.glb")).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json = String::from_utf8(bytes[20..20 + json_len].to_vec()).unwrap();
    assert!(json.contains("\"type\":\"i16\"") && json.contains("\"code_max\":32767"), "no quantization record");
    // The same length, so that the chunk lengths and the BIN chunk stay as they were.
    let altered = json.replacen("\"type\":\"i16\"", "\"type\":\"i8\" ", 1).replacen(
        "\"code_max\":32767",
        "\"code_max\":127  ",
        1,
    );
    assert_eq!(altered.len(), json_len);
    bytes[20..20 + json_len].copy_from_slice(altered.as_bytes());
    let altered = bytes;
    std::fs::write(d.join("bad.glb"), altered).unwrap();
    common::sky_pfm(d, 16, 8);
    let out = cmd("render")
        .args(["sky.pfm", "--scene", mesh.as_str(), "--shading", "transfer", "--transfer", "bad.glb", "--res", "8x8"])
        .args(["-o", "bad.exr"])
        .current_dir(d)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let says = stderr(&out);
    assert!(says.contains("bad.glb") && says.contains("_PRT_0") && says.contains("normalized BYTE"), "{says}");
    assert!(!d.join("bad.exr").exists());
}

#[test]
fn the_snippets_of_a_quantized_bake_dequantize_with_the_stored_scales_and_compile() {
    // The float bake's snippets are those of a bake without --quantize; a quantized bake's are
    // the same text followed by the dequantization, whose literals are the .glb's scales, and it
    // parses and validates in naga (GLSL and WGSL front ends) called before the dot product.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = test_mesh("bowl-ball.obj");
    for kind in ["none", "i8"] {
        let args = [mesh.as_str(), "-n", "3", "--rays", "16", "--quantize", kind, "--glb", "s.glb", "-o", "s.json"];
        let outputs = ["--glsl", &format!("{kind}.glsl"), "--wgsl", &format!("{kind}.wgsl")];
        run_in(d, "transfer", &[&args[..], &outputs].concat());
    }
    let text = |name: &str| std::fs::read_to_string(d.join(name)).unwrap();
    let (glsl, wgsl) = (text("i8.glsl"), text("i8.wgsl"));
    assert!(glsl.starts_with(&text("none.glsl")) && wgsl.starts_with(&text("none.wgsl")));
    let literals: Vec<f64> = glsl[text("none.glsl").len()..]
        .split("vec4(")
        .skip(1)
        .flat_map(|s| {
            s[..s.find(')').unwrap()].split(", ").map(|x| x.parse::<f32>().unwrap() as f64).collect::<Vec<_>>()
        })
        .collect();
    let scales = Glb::read(&d.join("s.glb")).blob("transfer.scales");
    assert_eq!(&literals[..9], &scales[..]);
    assert!(literals[9..].iter().all(|&x| x == 0.0));
    let src = format!(
        "#version 450\n#define PRTKIT_LIGHT_SH_DECLARED\nlayout(std140, binding = 0) uniform Light {{ vec3 prtkitLightSH[9]; }};\n\
         {glsl}layout(location = 0) in vec4 t0;\nlayout(location = 0) out vec4 o;\n\
         void main() {{ vec4 t[3] = vec4[3](t0, t0, t0); prtkitDequantizeTransfer(t); o = vec4(prtkitTransferRadiance(t), 1.0); }}\n"
    );
    check_glsl_fragment(&src, "the quantized bake's GLSL");
    let src = format!(
        "{wgsl}@group(0) @binding(0) var<uniform> light: array<vec4<f32>, 9>;\n\
         @fragment fn main(@location(0) t0: vec4<f32>) -> @location(0) vec4<f32> {{\n\
         var l: array<vec3<f32>, 9>;\n    for (var i = 0; i < 9; i++) {{ l[i] = light[i].xyz; }}\n\
         let t = prtkit_dequantize_transfer(array<vec4<f32>, 3>(t0, t0, t0));\n\
         return vec4<f32>(prtkit_transfer_radiance(t, l), 1.0);\n}}\n"
    );
    check_wgsl(&src, "the quantized bake's WGSL");
}
