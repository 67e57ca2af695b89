//! The emitted shader decoders parse and validate (naga's WGSL and GLSL front ends + validator)
//! for every scheme at budgets that exercise one-word, straddling and two-word field layouts.
//! (The GLSL and HLSL output was also checked with glslangValidator; see docs/encode-normals.md.)

use prtkit::normals::shader::{decoder, Language};
use prtkit::normals::{Codec, Scheme};

const BUDGETS: [u32; 8] = [8, 16, 19, 31, 32, 33, 48, 64];

fn validate(module: &naga::Module, what: &str) {
    let mut v = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all());
    if let Err(e) = v.validate(module) {
        panic!("{what}: invalid module: {e:?}");
    }
}

#[test]
fn wgsl_decoders_validate() {
    for scheme in Scheme::ALL {
        for bits in BUDGETS {
            let codec = Codec::new(scheme, bits).unwrap();
            let mut src = decoder(&codec, Language::Wgsl);
            // An entry point that uses the function, so nothing is dead code.
            src += if bits <= 32 {
                "@fragment fn main(@location(0) @interpolate(flat) c: u32) -> @location(0) vec4<f32> { return vec4<f32>(prtkit_decode_normal(c), 1.0); }\n"
            } else {
                "@fragment fn main(@location(0) @interpolate(flat) c: vec2<u32>) -> @location(0) vec4<f32> { return vec4<f32>(prtkit_decode_normal(c.x, c.y), 1.0); }\n"
            };
            let module = naga::front::wgsl::parse_str(&src)
                .unwrap_or_else(|e| panic!("{scheme} {bits}: {}\n{src}", e.emit_to_string(&src)));
            validate(&module, &format!("wgsl {scheme} {bits}"));
        }
    }
}

#[test]
fn glsl_decoders_validate() {
    for scheme in Scheme::ALL {
        for bits in BUDGETS {
            let codec = Codec::new(scheme, bits).unwrap();
            let mut src = String::from("#version 450\n");
            src += &decoder(&codec, Language::Glsl);
            src += if bits <= 32 {
                "layout(location = 0) flat in uint c;\nlayout(location = 0) out vec4 o;\nvoid main() { o = vec4(prtkit_decode_normal(c), 1.0); }\n"
            } else {
                "layout(location = 0) flat in uvec2 c;\nlayout(location = 0) out vec4 o;\nvoid main() { o = vec4(prtkit_decode_normal(c.x, c.y), 1.0); }\n"
            };
            let mut frontend = naga::front::glsl::Frontend::default();
            let options = naga::front::glsl::Options::from(naga::ShaderStage::Fragment);
            let module = frontend.parse(&options, &src).unwrap_or_else(|e| panic!("{scheme} {bits}: {e:?}\n{src}"));
            validate(&module, &format!("glsl {scheme} {bits}"));
        }
    }
}
