//! Shader decoders matching a codec's bit layout (`--emit-decoder glsl|hlsl|wgsl`).
//!
//! Codes of up to 32 bits arrive as one `uint`; wider codes as two (`lo` = bits 0–31, `hi` =
//! bits 32–63, the little-endian word split in half). Shaders decode in f32, so above ~48 bits
//! the decoded direction carries f32 rounding (~6e-8 rad) on top of the code's own error.

use super::fixed::snorm_max;
use super::{Codec, Field, FieldKind, Scheme};

/// Target shading language.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Language {
    /// OpenGL / Vulkan GLSL (4.00+).
    Glsl,
    /// Direct3D HLSL (SM 5+).
    Hlsl,
    /// WebGPU WGSL.
    Wgsl,
}

impl std::str::FromStr for Language {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "glsl" => Ok(Language::Glsl),
            "hlsl" => Ok(Language::Hlsl),
            "wgsl" => Ok(Language::Wgsl),
            _ => Err(format!("unknown shader language {s:?} (expected glsl, hlsl or wgsl)")),
        }
    }
}

struct Syntax {
    uint: &'static str,
    float: &'static str,
    vec2: &'static str,
    vec3: &'static str,
}

fn syntax(lang: Language) -> Syntax {
    match lang {
        Language::Glsl => Syntax { uint: "uint", float: "float", vec2: "vec2", vec3: "vec3" },
        Language::Hlsl => Syntax { uint: "uint", float: "float", vec2: "float2", vec3: "float3" },
        Language::Wgsl => Syntax { uint: "u32", float: "f32", vec2: "vec2<f32>", vec3: "vec3<f32>" },
    }
}

/// A float literal that every language accepts.
fn lit(x: f64) -> String {
    let s = format!("{x:?}");
    if s.contains('.') || s.contains('e') {
        s
    } else {
        format!("{s}.0")
    }
}

/// Expression extracting `f` as an unsigned integer from `lo`/`hi` (or `code`).
fn extract(f: &Field, wide: bool) -> String {
    let mask = if f.width >= 32 { "0xffffffffu".to_string() } else { format!("0x{:x}u", (1u64 << f.width) - 1) };
    let (word, off) = if !wide {
        ("code", f.offset)
    } else if f.offset >= 32 {
        ("hi", f.offset - 32)
    } else {
        ("lo", f.offset)
    };
    if wide && f.offset < 32 && f.offset + f.width > 32 {
        return format!("(((lo >> {}u) | (hi << {}u)) & {mask})", f.offset, 32 - f.offset);
    }
    if off == 0 {
        format!("({word} & {mask})")
    } else {
        format!("(({word} >> {off}u) & {mask})")
    }
}

/// Expression for the value of field `f`: SNORM → float in [-1, 1]; unsigned → the integer.
fn value(lang: Language, f: &Field, wide: bool) -> String {
    let e = extract(f, wide);
    match f.kind {
        FieldKind::Snorm => format!("prtkit_snorm({e}, {}u, {})", f.width, lit(snorm_max(f.width) as f64)),
        FieldKind::Unsigned => match lang {
            Language::Wgsl => format!("f32({e})"),
            _ => format!("float({e})"),
        },
    }
}

/// The decoder source for `codec` in `lang`: a helper `prtkit_snorm` and a function
/// `prtkit_decode_normal` returning a unit vector in the prtkit frame.
pub fn decoder(codec: &Codec, lang: Language) -> String {
    let s = syntax(lang);
    let wide = codec.bits() > 32;
    let fields = codec.fields();
    let fv = |i: usize| value(lang, &fields[i], wide);
    let layout: Vec<String> = fields
        .iter()
        .map(|f| {
            let kind = if f.kind == FieldKind::Snorm { "snorm" } else { "uint" };
            format!("{}: bits {}..{} {kind}", f.name, f.offset, f.offset + f.width)
        })
        .collect();
    let mut out = format!(
        "// prtkit encode-normals decoder: scheme {}, {} bits ({}).\n// Fields, lowest bit first: {}.\n// SNORM: two's complement s, value max(s / (2^(k-1) - 1), -1).\n",
        codec.scheme().name(),
        codec.bits(),
        if wide { "lo = bits 0-31, hi = bits 32-63" } else { "one 32-bit word" },
        layout.join("; ")
    );
    let (u, f) = (s.uint, s.float);
    // Helper: sign-extend a k-bit field and scale.
    out += &match lang {
        Language::Glsl | Language::Hlsl => format!(
            "{f} prtkit_snorm({u} field, {u} bits, {f} q) {{\n    int s = int(field << (32u - bits)) >> int(32u - bits);\n    return max({f}(s) / q, -1.0);\n}}\n\n"
        ),
        Language::Wgsl => "fn prtkit_snorm(field: u32, bits: u32, q: f32) -> f32 {\n    let s = bitcast<i32>(field << (32u - bits)) >> (32u - bits);\n    return max(f32(s) / q, -1.0);\n}\n\n".to_string(),
    };
    let params = match (lang, wide) {
        (Language::Wgsl, false) => "code: u32".to_string(),
        (Language::Wgsl, true) => "lo: u32, hi: u32".to_string(),
        (_, false) => format!("{u} code"),
        (_, true) => format!("{u} lo, {u} hi"),
    };
    let head = match lang {
        Language::Wgsl => format!("fn prtkit_decode_normal({params}) -> vec3<f32> {{\n"),
        _ => format!("{} prtkit_decode_normal({params}) {{\n", s.vec3),
    };
    out += &head;
    let (let_, var_) = match lang {
        Language::Wgsl => ("let", "var"),
        _ => ("", ""),
    };
    // Declarations: `let x = e;` in WGSL, `float x = e;` elsewhere.
    let decl = |ty: &str, name: &str, e: &str, mutable: bool| -> String {
        match lang {
            Language::Wgsl => format!("    {} {name} = {e};\n", if mutable { var_ } else { let_ }),
            _ => format!("    {ty} {name} = {e};\n"),
        }
    };
    let sel = |cond: &str, t: &str, e: &str| -> String {
        match lang {
            Language::Wgsl => format!("select({e}, {t}, {cond})"),
            _ => format!("(({cond}) ? {t} : {e})"),
        }
    };
    let low = if wide { "lo" } else { "code" };
    let body = match codec.scheme() {
        Scheme::OnvRange | Scheme::OnvDomain => {
            let mut b =
                String::from("    // Meyer et al. 2010, eq. 9, continuous fold: x = σ(u)(1-|v|), y = σ(v)(1-|u|).\n");
            b += &decl(s.vec2, "p0", &format!("{}({}, {})", s.vec2, fv(0), fv(1)), false);
            b += &decl(f, "z", "1.0 - abs(p0.x) - abs(p0.y)", false);
            let sx = sel("p0.x >= 0.0", "1.0", "-1.0");
            let sy = sel("p0.y >= 0.0", "1.0", "-1.0");
            let folded = format!("(1.0 - abs(p0.yx)) * {}({sx}, {sy})", s.vec2);
            b += &decl(s.vec2, "p", &sel("z < 0.0", &folded, "p0"), false);
            b += &format!("    return normalize({}(p, z));\n", s.vec3);
            b
        }
        Scheme::Sc => {
            let turns_scale = lit(1.0 / (1u64 << fields[1].width) as f64);
            let mut b = String::new();
            b += &decl(f, "theta", &format!("({} + 1.0) * 1.5707963267948966", fv(0)), false);
            b += &decl(f, "phi", &format!("{} * {turns_scale} * 6.283185307179586", fv(1)), false);
            b += &format!("    return {}(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));\n", s.vec3);
            b
        }
        Scheme::Pp => {
            let mut b = String::new();
            b += &decl(f, "x", &fv(1), false);
            b += &decl(f, "y", &fv(2), false);
            b += &decl(f, "r", "sqrt(max(0.0, 1.0 - x * x - y * y))", false);
            b += &decl(f, "z", &sel(&format!("({low} & 1u) != 0u"), "-r", "r"), false);
            b += &format!("    return normalize({}(x, y, z));\n", s.vec3);
            b
        }
        Scheme::Spp | Scheme::Cm => {
            let scale = if codec.scheme() == Scheme::Spp { " * 0.7071067811865476" } else { "" };
            let mut b =
                String::from("    // face = 2*axis + negative; minor axes in cyclic order (y,z), (z,x), (x,y).\n");
            b += &decl(u, "face", &format!("{low} & 7u"), false);
            b += &decl(u, "axis", "min(face >> 1u, 2u)", false);
            b += &decl(f, "sgn", &sel("(face & 1u) != 0u", "-1.0", "1.0"), false);
            b += &decl(f, "a", &format!("{}{scale}", fv(1)), false);
            b += &decl(f, "b", &format!("{}{scale}", fv(2)), false);
            let m = if codec.scheme() == Scheme::Spp { "sgn * sqrt(max(0.0, 1.0 - a * a - b * b))" } else { "sgn" };
            b += &decl(f, "m", m, false);
            let v = s.vec3;
            let inner = sel("axis == 1u", &format!("{v}(b, m, a)"), &format!("{v}(a, b, m)"));
            b += &decl(v, "n", &sel("axis == 0u", &format!("{v}(m, a, b)"), &inner), false);
            b += "    return normalize(n);\n";
            b
        }
    };
    out += &body;
    out += "}\n";
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_extraction_matches_layout() {
        let c = Codec::new(Scheme::OnvRange, 48).unwrap();
        let src = decoder(&c, Language::Glsl);
        assert!(src.contains("prtkit_snorm((lo & 0xffffffu), 24u, 8388607.0)"), "{src}");
        assert!(src.contains("(((lo >> 24u) | (hi << 8u)) & 0xffffffu)"), "{src}");
        let c = Codec::new(Scheme::OnvDomain, 32).unwrap();
        let src = decoder(&c, Language::Wgsl);
        assert!(src.contains("fn prtkit_decode_normal(code: u32) -> vec3<f32>"));
        assert!(src.contains("((code >> 16u) & 0xffffu), 16u, 32767.0"), "{src}");
        for scheme in Scheme::ALL {
            for lang in [Language::Glsl, Language::Hlsl, Language::Wgsl] {
                for bits in [8, 16, 31, 48, 64] {
                    let src = decoder(&Codec::new(scheme, bits).unwrap(), lang);
                    assert_eq!(src.matches('{').count(), src.matches('}').count());
                }
            }
        }
    }
}
