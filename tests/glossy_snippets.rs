//! The run-time snippets of glossy bakes (`transfer --factors … --glsl/--hlsl/--wgsl`, issue 32
//! item 6): beside the diffuse snippet's per-term dot product and SH rotation they hold the view
//! direction in the normal's frame and the h_k lookup (Mahajan, Tseng & Ramamoorthi 2008,
//! eq. 4). GLSL and WGSL go through naga's front ends and validator, called from a fragment
//! shader as a client would; naga has no HLSL front end, so the HLSL is checked for its
//! declarations. What the lookup computes is checked in the browser against `render`
//! (`viewer/test/run.mjs`, `mode=prt` with a glossy bake, which runs the emitted GLSL).

mod common;

use common::{check_glsl_fragment, check_wgsl, cmd, stderr};
use prtkit::factor::{Domain, Grid};
use prtkit::transfer::shaders::{glossy_snippet, snippet, Language};

/// The GLSL snippet in a fragment shader that relights a pixel: the lighting block, the h
/// texture, c_t as inputs, B from `prtkitGlossyRadiance` plus a rotated coefficient (so both
/// halves are used).
fn glsl_client(glsl: &str, order: usize, terms: usize) -> String {
    let c = order * order;
    format!(
        "#version 450\n#define PRTKIT_LIGHT_SH_DECLARED\n\
         layout(std140, binding = 0) uniform Light {{ vec3 prtkitLightSH[{c}]; }};\n\
         layout(set = 0, binding = 1) uniform texture2D glossyH;\n\
         layout(set = 0, binding = 2) uniform sampler glossyHSampler;\n\
         #define PRTKIT_GLOSSY_H_FETCH(x, y) texelFetch(sampler2D(glossyH, glossyHSampler), ivec2(x, y), 0).r\n{glsl}\
         layout(location = 0) in vec3 normal;\nlayout(location = 1) in vec3 toEye;\nlayout(location = 2) in vec3 c0;\n\
         layout(location = 0) out vec4 o;\n\
         void main() {{ vec3 c[{terms}]; for (int k = 0; k < {terms}; ++k) c[k] = c0 * float(k + 1);\n\
         vec3 turned[{c}]; prtkitRotateSH(mat3(normal, normal.yzx, normal.zxy), prtkitLightSH, turned);\n\
         o = vec4(prtkitGlossyRadiance(normalize(normal), normalize(toEye), c) + turned[{last}], 1.0); }}\n",
        last = c - 1
    )
}

fn wgsl_client(wgsl: &str, order: usize, terms: usize) -> String {
    let c = order * order;
    format!(
        "{wgsl}@group(0) @binding(0) var<uniform> light: array<vec4<f32>, {c}>;\n\
         @group(0) @binding(1) var glossy_h: texture_2d<f32>;\n\
         @fragment fn main(@location(0) normal: vec3<f32>, @location(1) to_eye: vec3<f32>, @location(2) c0: vec3<f32>) -> @location(0) vec4<f32> {{\n\
         var sh: array<vec3<f32>, {c}>;\n for (var i = 0; i < {c}; i++) {{ sh[i] = light[i].xyz; }}\n\
         let turned = prtkit_rotate_sh(mat3x3<f32>(normal, normal.yzx, normal.zxy), sh);\n\
         var c: array<vec3<f32>, {terms}>;\n for (var k = 0; k < {terms}; k++) {{ c[k] = c0 * f32(k + 1); }}\n\
         return vec4<f32>(prtkit_glossy_radiance(glossy_h, normalize(normal), normalize(to_eye), c) + turned[{last}], 1.0);\n}}\n",
        last = c - 1
    )
}

#[test]
fn glossy_snippets_parse_and_validate_in_naga_for_both_domains() {
    // Both grids (the sphere's adds the south pole's blend), odd and even orders (term
    // boundaries inside and on four-vectors), one term and many.
    for (order, terms, grid) in [
        (4, 10, Grid { n: 16, domain: Domain::Hemisphere }),
        (3, 1, Grid { n: 8, domain: Domain::Sphere }),
        (8, 18, Grid { n: 32, domain: Domain::Hemisphere }),
        (1, 5, Grid { n: 7, domain: Domain::Sphere }),
    ] {
        let what = format!("order {order}, K = {terms}, {} x {} {}", grid.n, grid.n, grid.domain);
        let glsl = glossy_snippet(order, terms, grid, Language::Glsl);
        let src = glsl_client(&glsl, order, terms);
        check_glsl_fragment(&src, &format!("glsl {what}"));
        let wgsl = glossy_snippet(order, terms, grid, Language::Wgsl);
        let src = wgsl_client(&wgsl, order, terms);
        check_wgsl(&src, &format!("wgsl {what}"));
        let hlsl = glossy_snippet(order, terms, grid, Language::Hlsl);
        for decl in [
            "float3 prtkitGlossyLocalView(float3 n, float3 wo)",
            "float2 prtkitGlossyCosThetaPhi(float3 w)",
            "PrtkitGlossyTaps prtkitGlossyTaps(float2 ctPhi)",
            "float prtkitGlossyH(int term, PrtkitGlossyTaps t)",
            "float3 prtkitGlossyRadiance(float3 n, float3 wo, float3 c[PRTKIT_GLOSSY_TERMS])",
            "Texture2D<float> prtkitGlossyHTexture;",
            &format!("#define PRTKIT_GLOSSY_TERMS {terms}"),
        ] {
            assert!(hlsl.contains(decl), "{what}: {decl}\n{hlsl}");
        }
        assert!(!hlsl.contains("vec3") && !hlsl.contains("texelFetch"), "GLSL in the HLSL");
        // The diffuse half is the diffuse snippet, unchanged.
        for lang in [Language::Glsl, Language::Hlsl, Language::Wgsl] {
            assert!(glossy_snippet(order, terms, grid, lang).starts_with(&snippet(order, lang)), "{what}");
        }
        // The sphere's grid blends into both poles' rings, the hemisphere's into the top only.
        assert_eq!(glsl.contains(&format!("t.poleRow = {};", grid.n - 1)), grid.domain == Domain::Sphere, "{what}");
    }
}

#[test]
fn transfer_writes_the_glossy_snippet_for_a_glossy_bake_and_the_diffuse_one_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mesh = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/meshes/bowl.obj");
    let run = |stage: &str, args: &[&str]| {
        let out = cmd(stage).args(args).arg("-q").current_dir(d).output().unwrap();
        assert!(out.status.success(), "{stage} {args:?}: {}", stderr(&out));
    };
    run(
        "factor-brdf",
        &[
            "phong:s=8",
            "--domain",
            "hemisphere",
            "--resolution",
            "8",
            "--cosine",
            "--factors",
            "p.exr",
            "--terms",
            "6",
            "-o",
            "p.json",
        ],
    );
    let mesh = mesh.to_str().unwrap();
    for (args, glossy) in [
        (vec![mesh, "-n", "3", "--mode", "unshadowed", "--factors", "p.json", "-K", "4"], true),
        (vec![mesh, "-n", "3", "--mode", "unshadowed"], false),
    ] {
        let mut args = args;
        args.extend(["--glb", "t.glb", "-o", "t.json", "--glsl", "t.glsl", "--hlsl", "t.hlsl", "--wgsl", "t.wgsl"]);
        run("transfer", &args);
        let grid = Grid { n: 8, domain: Domain::Hemisphere };
        for (file, lang) in [("t.glsl", Language::Glsl), ("t.hlsl", Language::Hlsl), ("t.wgsl", Language::Wgsl)] {
            let text = std::fs::read_to_string(d.join(file)).unwrap();
            let want = if glossy { glossy_snippet(3, 4, grid, lang) } else { snippet(3, lang) };
            assert_eq!(text, want, "{file}, glossy {glossy}");
        }
    }
}
