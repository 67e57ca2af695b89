//! Shader decoders matching a codec's layout (`--emit-decoder glsl|hlsl|wgsl`).
//!
//! Codes of up to 32 bits arrive as one `uint`; wider codes as two (`lo` = bits 0–31, `hi` =
//! bits 32–63, the little-endian word split in half). ONV fields are extracted with shifts and
//! masks. Mixed-radix codes (`radix.rs`) are split with `%` and `/`; above 32 bits that is a
//! 64-by-32-bit division, which shading languages lack (WGSL has no 64-bit integers at all), so
//! the decoder carries `prtkit_divmod`, a restoring division of one quotient bit per step
//! (32 steps, exact). Shaders decode in f32, so above ~48 bits the decoded direction carries f32
//! rounding (~6e-8 rad, up to ~4e-7 rad for SC's `φ` at 64 bits) on top of the code's own error.

use super::fixed::snorm_max;
use super::radix::GridLayout;
use super::{Codec, Layout, Scheme};
use std::f64::consts::{PI, TAU};

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
    uvec3: &'static str,
}

fn syntax(lang: Language) -> Syntax {
    match lang {
        Language::Glsl => Syntax { uint: "uint", float: "float", vec2: "vec2", vec3: "vec3", uvec3: "uvec3" },
        Language::Hlsl => Syntax { uint: "uint", float: "float", vec2: "float2", vec3: "float3", uvec3: "uint3" },
        Language::Wgsl => {
            Syntax { uint: "u32", float: "f32", vec2: "vec2<f32>", vec3: "vec3<f32>", uvec3: "vec3<u32>" }
        }
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

/// Statement writer for one language: declarations, conditional selects, conversions.
struct Writer {
    lang: Language,
    s: Syntax,
    out: String,
}

impl Writer {
    /// `let name = e;` in WGSL, `type name = e;` elsewhere.
    fn decl(&mut self, ty: &str, name: &str, e: &str) {
        self.out += &match self.lang {
            Language::Wgsl => format!("    let {name} = {e};\n"),
            _ => format!("    {ty} {name} = {e};\n"),
        };
    }

    fn comment(&mut self, text: &str) {
        self.out += &format!("    // {text}\n");
    }

    /// `cond ? t : e`.
    fn sel(&self, cond: &str, t: &str, e: &str) -> String {
        match self.lang {
            Language::Wgsl => format!("select({e}, {t}, {cond})"),
            _ => format!("(({cond}) ? {t} : {e})"),
        }
    }

    /// An unsigned integer converted to float.
    fn float(&self, e: &str) -> String {
        format!("{}({e})", self.s.float)
    }
}

/// Expression extracting the `width`-bit field at `offset` from `lo`/`hi` (or `code`).
fn extract(offset: u32, width: u32, wide: bool) -> String {
    let mask = if width >= 32 { "0xffffffffu".to_string() } else { format!("0x{:x}u", (1u64 << width) - 1) };
    if wide && offset < 32 && offset + width > 32 {
        return format!("(((lo >> {offset}u) | (hi << {}u)) & {mask})", 32 - offset);
    }
    let (word, off) = if !wide {
        ("code", offset)
    } else if offset >= 32 {
        ("hi", offset - 32)
    } else {
        ("lo", offset)
    };
    if off == 0 {
        format!("({word} & {mask})")
    } else {
        format!("(({word} >> {off}u) & {mask})")
    }
}

fn helpers(lang: Language, divmod: bool, symmetric: bool, snorm: bool) -> String {
    let mut out = String::new();
    if snorm {
        out += match lang {
            Language::Wgsl => "fn prtkit_snorm(field: u32, bits: u32, q: f32) -> f32 {\n    let s = bitcast<i32>(field << (32u - bits)) >> (32u - bits);\n    return max(f32(s) / q, -1.0);\n}\n\n",
            _ => "float prtkit_snorm(uint field, uint bits, float q) {\n    int s = int(field << (32u - bits)) >> int(32u - bits);\n    return max(float(s) / q, -1.0);\n}\n\n",
        };
    }
    if symmetric {
        out += "// Digit d of an odd symmetric lattice of 2h+1 points: (d - h) / h in [-1, 1].\n";
        out += match lang {
            Language::Wgsl => {
                "fn prtkit_symmetric(d: u32, h: u32) -> f32 {\n    return f32(bitcast<i32>(d - h)) / f32(h);\n}\n\n"
            }
            _ => "float prtkit_symmetric(uint d, uint h) {\n    return float(int(d - h)) / float(h);\n}\n\n",
        };
    }
    if divmod {
        out += "// (hi * 2^32 + lo) = q * n + r for 2 <= n < 2^32, returned as (q_hi, q_lo, r): restoring\n// division, one quotient bit per step, without 64-bit integers.\n";
        out += match lang {
            Language::Wgsl => "fn prtkit_divmod(hi: u32, lo: u32, n: u32) -> vec3<u32> {\n    var r = hi % n;\n    var q = 0u;\n    for (var i = 0u; i < 32u; i = i + 1u) {\n        let carry = r >> 31u;\n        r = (r << 1u) | ((lo >> (31u - i)) & 1u);\n        let take = carry != 0u || r >= n;\n        r = select(r, r - n, take);\n        q = (q << 1u) | select(0u, 1u, take);\n    }\n    return vec3<u32>(hi / n, q, r);\n}\n\n",
            Language::Glsl => "uvec3 prtkit_divmod(uint hi, uint lo, uint n) {\n    uint r = hi % n;\n    uint q = 0u;\n    for (uint i = 0u; i < 32u; i++) {\n        uint carry = r >> 31u;\n        r = (r << 1u) | ((lo >> (31u - i)) & 1u);\n        bool take = carry != 0u || r >= n;\n        r = take ? r - n : r;\n        q = (q << 1u) | (take ? 1u : 0u);\n    }\n    return uvec3(hi / n, q, r);\n}\n\n",
            Language::Hlsl => "uint3 prtkit_divmod(uint hi, uint lo, uint n) {\n    uint r = hi % n;\n    uint q = 0u;\n    for (uint i = 0u; i < 32u; i++) {\n        uint carry = r >> 31u;\n        r = (r << 1u) | ((lo >> (31u - i)) & 1u);\n        bool take = carry != 0u || r >= n;\n        r = take ? r - n : r;\n        q = (q << 1u) | (take ? 1u : 0u);\n    }\n    return uint3(hi / n, q, r);\n}\n\n",
        };
    }
    out
}

/// The decoder source for `codec` in `lang`: helpers and a function `prtkit_decode_normal`
/// returning a unit vector in the prtkit frame.
pub fn decoder(codec: &Codec, lang: Language) -> String {
    let wide = codec.bits() > 32;
    let digits = codec.digits();
    let layout: Vec<String> = digits.iter().map(|d| format!("{} < {} ({})", d.name, d.radix, d.kind.name())).collect();
    let grid = match codec.layout() {
        Layout::Grid(l) => Some(l),
        Layout::Onv(_) => None,
    };
    let mut out = format!(
        "// prtkit encode-normals decoder: scheme {}, {} bits ({}).\n// Digits, lowest first (code = d0 + N0 * (d1 + N1 * d2)): {}.\n",
        codec.scheme().name(),
        codec.bits(),
        if wide { "lo = bits 0-31, hi = bits 32-63" } else { "one 32-bit word" },
        layout.join("; ")
    );
    out += if grid.is_some() {
        "// Symmetric: odd lattice of 2h+1 points, value (d - h) / h. Turns: value d / N of a full turn.\n"
    } else {
        "// SNORM: k-bit two's complement s, value max(s / (2^(k-1) - 1), -1).\n"
    };
    let symmetric = grid.is_some() && codec.scheme() != Scheme::Sc;
    out += &helpers(lang, wide && grid.is_some(), symmetric, grid.is_none());
    let s = syntax(lang);
    let params = match (lang, wide) {
        (Language::Wgsl, false) => "code: u32".to_string(),
        (Language::Wgsl, true) => "lo: u32, hi: u32".to_string(),
        (_, false) => format!("{} code", s.uint),
        (_, true) => format!("{0} lo, {0} hi", s.uint),
    };
    out += &match lang {
        Language::Wgsl => format!("fn prtkit_decode_normal({params}) -> vec3<f32> {{\n"),
        _ => format!("{} prtkit_decode_normal({params}) {{\n", s.vec3),
    };
    let mut w = Writer { lang, s, out };
    match grid {
        None => onv_body(&mut w, codec, wide),
        Some(l) => grid_body(&mut w, codec, l, wide),
    }
    w.out += "}\n";
    w.out
}

fn onv_body(w: &mut Writer, codec: &Codec, wide: bool) {
    let (f, v2) = (w.s.float, w.s.vec2);
    let snorm = |offset: u32, width: u32| {
        format!("prtkit_snorm({}, {width}u, {})", extract(offset, width, wide), lit(snorm_max(width) as f64))
    };
    let digits = codec.digits();
    let (ku, kv) = (digits[0].radix.trailing_zeros(), digits[1].radix.trailing_zeros());
    w.comment("Meyer et al. 2010, eq. 9, continuous fold: x = σ(u)(1-|v|), y = σ(v)(1-|u|).");
    w.decl(v2, "p0", &format!("{v2}({}, {})", snorm(0, ku), snorm(ku, kv)));
    w.decl(f, "z", "1.0 - abs(p0.x) - abs(p0.y)");
    let sx = w.sel("p0.x >= 0.0", "1.0", "-1.0");
    let sy = w.sel("p0.y >= 0.0", "1.0", "-1.0");
    let folded = format!("(1.0 - abs(p0.yx)) * {v2}({sx}, {sy})");
    let p = w.sel("z < 0.0", &folded, "p0");
    w.decl(v2, "p", &p);
    w.out += &format!("    return normalize({}(p, z));\n", w.s.vec3);
}

/// Splits the code into `face`, `a` (for SC with one face: the float `a_value`) and `b`, then
/// applies the scheme's formula.
fn grid_body(w: &mut Writer, codec: &Codec, l: GridLayout, wide: bool) {
    let (u, f, v3) = (w.s.uint, w.s.float, w.s.vec3);
    let (na, nb) = (format!("{}u", l.a), format!("{}u", l.b));
    let max_code = if codec.bits() >= 64 { u64::MAX } else { (1u64 << codec.bits()) - 1 };
    // The quotient code / N_b fits one word unless the a digit and the faces need more than 32 bits.
    let rest_fits = max_code / l.b <= u32::MAX as u64;
    // The a digit as a float (SC with one face may need both words of the quotient).
    let a_float;
    if !wide {
        w.decl(u, "b", &format!("code % {nb}"));
        w.decl(u, "rest", &format!("code / {nb}"));
    } else {
        w.decl(w.s.uvec3, "qb", &format!("prtkit_divmod(hi, lo, {nb})"));
        w.decl(u, "b", "qb.z");
        if rest_fits {
            w.comment("qb.x, the high word of code / N_b, is 0 for every code of this budget.");
            w.decl(u, "rest", "qb.y");
        }
    }
    if rest_fits || !wide {
        w.decl(u, "a", &format!("rest % {na}"));
        a_float = w.float("a");
        if l.faces > 1 {
            w.decl(u, "face", &format!("min(rest / {na}, {}u)", l.faces - 1));
        }
    } else if l.faces > 1 {
        w.decl(w.s.uvec3, "qa", &format!("prtkit_divmod(qb.x, qb.y, {na})"));
        w.comment("qa.x is 0: the face quotient is below 2^32 for every code.");
        w.decl(u, "a", "qa.z");
        w.decl(u, "face", &format!("min(qa.y, {}u)", l.faces - 1));
        a_float = w.float("a");
    } else {
        // One face (SC): a is the whole quotient, up to two words; only its float is needed.
        a_float = format!("({} * 4294967296.0 + {})", w.float("qb.x"), w.float("qb.y"));
    }
    let sym = |d: &str, radix: u64| format!("prtkit_symmetric({d}, {}u)", (radix - 1) / 2);
    match codec.scheme() {
        Scheme::Sc => {
            w.comment("θ = π·b/(N_θ-1) from +Z, φ = 2π·a/N_φ from +X towards +Y.");
            w.decl(f, "theta", &format!("{} * {}", w.float("b"), lit(PI / (l.b - 1) as f64)));
            w.decl(f, "phi", &format!("{a_float} * {}", lit(TAU / l.a as f64)));
            w.out += &format!("    return {v3}(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));\n");
        }
        Scheme::Pp => {
            w.decl(f, "x", &sym("a", l.a));
            w.decl(f, "y", &sym("b", l.b));
            w.decl(f, "r", "sqrt(max(0.0, 1.0 - x * x - y * y))");
            let z = w.sel("face != 0u", "-r", "r");
            w.decl(f, "z", &z);
            w.out += &format!("    return normalize({v3}(x, y, z));\n");
        }
        _ => {
            let spp = codec.scheme() == Scheme::Spp;
            let scale = if spp { " * 0.7071067811865476" } else { "" };
            w.comment("face = 2*axis + negative; minor axes in cyclic order (y,z), (z,x), (x,y).");
            w.decl(u, "axis", "face >> 1u");
            let sgn = w.sel("(face & 1u) != 0u", "-1.0", "1.0");
            w.decl(f, "sgn", &sgn);
            w.decl(f, "a_value", &format!("{}{scale}", sym("a", l.a)));
            w.decl(f, "b_value", &format!("{}{scale}", sym("b", l.b)));
            let m = if spp { "sgn * sqrt(max(0.0, 1.0 - a_value * a_value - b_value * b_value))" } else { "sgn" };
            w.decl(f, "m", m);
            let inner =
                w.sel("axis == 1u", &format!("{v3}(b_value, m, a_value)"), &format!("{v3}(a_value, b_value, m)"));
            let n = w.sel("axis == 0u", &format!("{v3}(m, a_value, b_value)"), &inner);
            w.decl(v3, "n", &n);
            w.out += "    return normalize(n);\n";
        }
    }
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
