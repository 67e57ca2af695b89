//! Every HLSL text prtkit writes compiles in a real HLSL front end: glslang's (Khronos
//! `glslangValidator -D`, Debian's `glslang-tools`), as a pixel shader that calls it the way a
//! client would, compiled to SPIR-V. naga, which checks the GLSL and WGSL twins elsewhere, has no
//! HLSL front end. The texts: `transfer`'s diffuse snippet at every order, its glossy snippet on
//! both factor domains, its coloured-albedo snippet, the dequantization of a quantized bake (as the CLI writes it), every
//! `encode-normals` decoder, and `ibl`'s SH irradiance.
//!
//! CI installs glslang-tools (`.ci/run`) and fails here without it; elsewhere the test says it
//! is skipping.

mod common;

use common::{run_in, test_mesh};
use glam::DMat3;
use prtkit::factor::{Domain, Grid};
use prtkit::ibl::sh_irradiance::IrradianceSh;
use prtkit::normals::shader::{decoder, Language as NormalsLanguage};
use prtkit::normals::{Codec, Scheme};
use prtkit::transfer::shaders::{glossy_snippet, snippet, Language};
use std::path::Path;
use std::process::Command;

const VALIDATOR: &str = "glslangValidator";

/// Whether glslang is here; without it, a skip outside CI and a failure in CI.
fn have_validator() -> bool {
    if Command::new(VALIDATOR).arg("--version").output().is_ok_and(|o| o.status.success()) {
        return true;
    }
    assert!(std::env::var_os("CI").is_none(), "{VALIDATOR} is missing; .ci/run installs Debian's glslang-tools");
    eprintln!("skipping: {VALIDATOR} not found (Debian: apt-get install glslang-tools)");
    false
}

/// Compiles `source` as an HLSL pixel shader with entry point `main` to SPIR-V in `dir`,
/// failing with glslang's messages and the source.
fn compile(dir: &Path, name: &str, source: &str) {
    let file = dir.join(format!("{name}.hlsl"));
    std::fs::write(&file, source).unwrap();
    let out = Command::new(VALIDATOR)
        .args(["-D", "-V", "-S", "frag", "-e", "main", "-o"])
        .arg(dir.join(format!("{name}.spv")))
        .arg(&file)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{name}: glslang rejects the HLSL:\n{}{}\n{source}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A pixel shader around a transfer snippet: T from an interpolated four-vector, the lighting
/// turned by a rotation, the dot product; with `glossy`, K interpolated c_t and the per-pixel
/// sum; with `dequantize`, the codes scaled first.
fn transfer_client(snippet: &str, glossy: bool, dequantize: bool) -> String {
    let mut body = String::from(
        "    float4 t[PRTKIT_TRANSFER_VEC4S];\n\
         for (int k = 0; k < PRTKIT_TRANSFER_VEC4S; ++k) t[k] = i.t0 * float(k + 1);\n\
         float3 turned[PRTKIT_TRANSFER_COEFFS];\n\
         prtkitRotateSH(float3x3(i.n, i.n.yzx, i.n.zxy), prtkitLightSH, turned);\n",
    );
    if dequantize {
        body += "    prtkitDequantizeTransfer(t);\n";
    }
    body += "    float3 b = prtkitTransferRadiance(t) + turned[PRTKIT_TRANSFER_COEFFS - 1];\n";
    if glossy {
        body += "    float3 c[PRTKIT_GLOSSY_TERMS];\n\
                 for (int j = 0; j < PRTKIT_GLOSSY_TERMS; ++j) c[j] = i.c0 * float(j + 1);\n\
                 b += prtkitGlossyRadiance(normalize(i.n), normalize(i.toEye), c);\n";
    }
    format!(
        "{snippet}\nstruct PixelIn {{ float4 t0 : T0; float3 n : NORMAL; float3 toEye : EYE; float3 c0 : C0; }};\n\
         float4 main(PixelIn i) : SV_Target {{\n{body}    return float4(b, 1.0);\n}}\n"
    )
}

#[test]
fn transfer_snippets_compile_as_hlsl_at_every_order_and_on_both_glossy_domains() {
    if !have_validator() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for order in 1..=8 {
        compile(
            dir.path(),
            &format!("diffuse-{order}"),
            &transfer_client(&snippet(order, Language::Hlsl), false, false),
        );
    }
    // Odd and even orders (term boundaries inside and on four-vectors), one term and many; the
    // sphere's grid adds the south pole's blend.
    for (order, terms, grid) in [
        (4, 10, Grid { n: 16, domain: Domain::Hemisphere }),
        (3, 1, Grid { n: 8, domain: Domain::Sphere }),
        (8, 18, Grid { n: 32, domain: Domain::Sphere }),
    ] {
        let text = glossy_snippet(order, terms, grid, Language::Hlsl);
        compile(dir.path(), &format!("glossy-{order}-{terms}-{}", grid.n), &transfer_client(&text, true, false));
    }
}

#[test]
fn the_hlsl_a_quantized_bake_writes_compiles_with_its_dequantization() {
    if !have_validator() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = test_mesh("bowl-ball.obj");
    for kind in ["i16", "i8"] {
        let hlsl = format!("{kind}.hlsl");
        let args = [mesh.as_str(), "-n", "3", "--rays", "16", "--quantize", kind, "--glb", "q.glb", "-o", "q.json"];
        run_in(d, "transfer", &[&args[..], &["--hlsl", &hlsl]].concat());
        let text = std::fs::read_to_string(d.join(&hlsl)).unwrap();
        assert!(text.contains("prtkitDequantizeTransfer"), "{hlsl}: no dequantization");
        compile(d, &format!("quantized-{kind}"), &transfer_client(&text, false, true));
    }
}

#[test]
fn the_hlsl_of_a_coloured_albedo_compiles_quantized_or_not() {
    if !have_validator() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = test_mesh("bowl.obj");
    for (order, quantize) in [("1", "none"), ("3", "none"), ("4", "i8"), ("8", "i16")] {
        let hlsl = format!("rgb-{order}-{quantize}.hlsl");
        let args =
            [mesh.as_str(), "--mode", "unshadowed", "-n", order, "--albedo", "0.9,0.5,0.2", "--quantize", quantize];
        run_in(d, "transfer", &[&args[..], &["--glb", "c.glb", "-o", "c.json", "--hlsl", &hlsl]].concat());
        let text = std::fs::read_to_string(d.join(&hlsl)).unwrap();
        let dequantize = if quantize == "none" { "" } else { "    prtkitDequantizeTransfer(t);\n" };
        let source = format!(
            "{text}\nfloat4 main(float4 t0 : T0) : SV_Target {{\n\
             float4 t[PRTKIT_TRANSFER_RGB_VEC4S];\n\
             for (int k = 0; k < PRTKIT_TRANSFER_RGB_VEC4S; ++k) t[k] = t0 * float(k + 1);\n{dequantize}\
             return float4(prtkitTransferRadianceRGB(t), 1.0);\n}}\n"
        );
        compile(d, &format!("rgb-{order}-{quantize}"), &source);
    }
}

#[test]
fn every_normal_decoder_compiles_as_hlsl() {
    if !have_validator() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // One-word, straddling and two-word code layouts.
    for scheme in Scheme::ALL {
        for bits in [8, 16, 19, 31, 32, 33, 48, 64] {
            let codec = Codec::new(scheme, bits).unwrap();
            let call = if codec.bits() <= 32 {
                "float4 main(nointerpolation uint c : CODE) : SV_Target { return float4(prtkit_decode_normal(c), 1.0); }\n"
            } else {
                "float4 main(nointerpolation uint2 c : CODE) : SV_Target { return float4(prtkit_decode_normal(c.x, c.y), 1.0); }\n"
            };
            compile(dir.path(), &format!("{scheme:?}-{bits}"), &(decoder(&codec, NormalsLanguage::Hlsl) + call));
        }
    }
}

#[test]
fn the_ibl_sh_irradiance_compiles_as_hlsl() {
    if !have_validator() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let sh = IrradianceSh::project(&common::sky(64, 32), DMat3::IDENTITY).unwrap();
    let call = "float4 main(float3 n : NORMAL) : SV_Target { return float4(prtkitIrradiance(normalize(n)), 1.0); }\n";
    compile(dir.path(), "irradiance", &(sh.hlsl("prtkit's own (+Z up)") + call));
}
