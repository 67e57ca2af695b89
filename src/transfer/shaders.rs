//! The run-time half of diffuse PRT in GLSL, HLSL and WGSL (`transfer --glsl/--hlsl/--wgsl`):
//!
//! - the dot product B(x) = Σ_i T_i(x) L_i (Sloan, Kautz & Snyder 2002, eq. 9), the transfer read
//!   from the `_PRT_k` vertex attributes (`docs/formats/transfer.md`);
//! - SH rotation of the lighting, band by band (Sloan et al. 2002, §7: a rotating environment is
//!   relit by rotating its coefficients, one (2l+1)² block per band, not by re-projecting it):
//!   the blocks of a 3×3 rotation built by Ivanic & Ruedenberg's recurrence, written out term by
//!   term from [`crate::sh::rotate::band_terms`], the recurrence [`ShRotation`] runs, so the
//!   snippet's basis and signs are prtkit's by construction (`docs/conventions.md`).
//!
//! As `ibl`'s `sh.glsl/sh.hlsl/sh.wgsl`, the three languages share one comment header and one
//! body, written out (no loops, no tables) with each language's type names, so what is checked
//! in one holds in the others.
//!
//! A glossy bake ([`glossy_snippet`]) adds what its per-pixel half needs (Mahajan, Tseng &
//! Ramamoorthi 2008, eq. 4: B(x, ω_o) = Σ_k h_k(Fᵀ ω_o) c_k(x)): the view direction in the
//! normal's frame F, and the lookup of h_k with the rule `render` uses
//! (`render::factored::h_taps`): bilinear between cell centres in (cos θ, φ), φ wrapping, the
//! grid's edge rows clamped, and within half a bin of a pole a blend into the pole ring's mean.
//!
//! [`ShRotation`]: crate::sh::rotate::ShRotation

use super::quantize::Quantized;
use crate::factor::{Domain, Grid};
pub use crate::normals::shader::Language;
use crate::sh::index;
use crate::sh::rotate::band_terms;

struct Syntax {
    vec3: &'static str,
    vec4: &'static str,
    mat3: &'static str,
}

fn syntax(lang: Language) -> Syntax {
    match lang {
        Language::Glsl => Syntax { vec3: "vec3", vec4: "vec4", mat3: "mat3" },
        Language::Hlsl => Syntax { vec3: "float3", vec4: "float4", mat3: "float3x3" },
        Language::Wgsl => Syntax { vec3: "vec3<f32>", vec4: "vec4<f32>", mat3: "mat3x3<f32>" },
    }
}

/// Element (row i, column j) of the rotation argument: GLSL and WGSL index a matrix by column,
/// HLSL by row.
fn r(lang: Language, i: usize, j: usize) -> String {
    match lang {
        Language::Hlsl => format!("R[{i}][{j}]"),
        Language::Glsl => format!("R[{j}][{i}]"),
        Language::Wgsl => format!("r[{j}][{i}]"),
    }
}

/// Name of element (m, n) of band l's block.
fn element(l: usize, m: isize, n: isize) -> String {
    let li = l as isize;
    format!("b{l}_{}_{}", m + li, n + li)
}

/// Band 1's rows and columns are ordered (y, z, x): Y_1,−1 ∝ y, Y_1,0 ∝ z, Y_1,1 ∝ x.
fn axis(m: isize) -> usize {
    match m {
        -1 => 1,
        0 => 2,
        _ => 0,
    }
}

/// `c * a * b` summed, as source, with the signs folded in.
fn sum(terms: impl Iterator<Item = (f64, String)>) -> String {
    let mut out = String::new();
    for (k, (c, e)) in terms.enumerate() {
        let (sign, c) = if c < 0.0 { ("-", -c) } else { ("+", c) };
        let factor = if c == 1.0 { e } else { format!("{c:.8e} * {e}") };
        out += &match (k, sign) {
            (0, "+") => factor,
            (0, _) => format!("-{factor}"),
            _ => format!(" {sign} {factor}"),
        };
    }
    if out.is_empty() {
        "0.0".into()
    } else {
        out
    }
}

/// The snippet for `order` n bands (n² coefficients in ⌈n²/4⌉ four-vectors) in `lang`.
pub fn snippet(order: usize, lang: Language) -> String {
    let coeffs = order * order;
    let vec4s = coeffs.div_ceil(4);
    let s = syntax(lang);
    let (radiance, rotate) = match lang {
        Language::Wgsl => ("prtkit_transfer_radiance", "prtkit_rotate_sh"),
        _ => ("prtkitTransferRadiance", "prtkitRotateSH"),
    };
    let mut out = format!(
        "// prtkit transfer: diffuse precomputed radiance transfer (Sloan, Kautz & Snyder 2002).
// {radiance}: outgoing radiance B(x) = sum_i T_i(x) L_i (eq. 9), i = l(l+1)+m over n = {order}
// bands ({coeffs} coefficients). T_i: the glTF vertex attributes _PRT_0.._PRT_{last}, four
// coefficients per four-vector in index order (zeros pad the last); L_i: the lighting's RGB SH
// coefficients in prtkit's basis (real, orthonormal, no Condon-Shortley phase), in the mesh's own
// axes; the albedo is baked in.
// {rotate}: the coefficients of the lighting turned by the rotation R, L'(w) = L(R^-1 w)
// (a direction d of the lighting goes to R d), band by band (Ivanic & Ruedenberg 1996, with
// the 1998 errata): call it once per frame when the environment turns, then relight with the
// result. R is row i, column j = R_ij acting on column vectors (GLSL/WGSL matrices are indexed
// [column][row], HLSL ones [row][column]); `render --env-rotation DEG` is R = rotation about +Z
// by DEG.
",
        last = vec4s - 1
    );
    // The dot product.
    let terms = (0..coeffs).map(|i| (1.0, format!("transfer[{}].{} * light[{i}]", i / 4, ["x", "y", "z", "w"][i % 4])));
    let dot = sum(terms);
    match lang {
        Language::Wgsl => {
            out += &format!(
                "\nfn {radiance}(transfer: array<{}, {vec4s}>, light: array<{}, {coeffs}>) -> {} {{\n    return {dot};\n}}\n",
                s.vec4, s.vec3, s.vec3
            );
        }
        _ => {
            out += &format!(
                "// Declare prtkitLightSH yourself (e.g. in a uniform block / cbuffer) and define
// PRTKIT_LIGHT_SH_DECLARED to replace the plain declaration below.
#define PRTKIT_TRANSFER_COEFFS {coeffs}
#define PRTKIT_TRANSFER_VEC4S {vec4s}
#ifndef PRTKIT_LIGHT_SH_DECLARED
uniform {vec3} prtkitLightSH[PRTKIT_TRANSFER_COEFFS];
#endif

{vec3} {radiance}({vec4} transfer[PRTKIT_TRANSFER_VEC4S]) {{
    return {body};
}}
",
                vec3 = s.vec3,
                vec4 = s.vec4,
                body = dot.replace("light[", "prtkitLightSH[")
            );
        }
    }
    // The rotation: band 1 from R, band l from band 1 and band l − 1, then each band's block
    // times its coefficients.
    let mut body = String::new();
    let decl = |name: &str, e: &str| match lang {
        Language::Wgsl => format!("    let {name} = {e};\n"),
        _ => format!("    float {name} = {e};\n"),
    };
    if order >= 2 {
        for m in -1..=1isize {
            for n in -1..=1isize {
                body += &decl(&element(1, m, n), &r(lang, axis(m), axis(n)));
            }
        }
    }
    for l in 2..order {
        let li = l as isize;
        for (k, terms) in band_terms(l).into_iter().enumerate() {
            let (m, n) = (k as isize / (2 * li + 1) - li, k as isize % (2 * li + 1) - li);
            let e = sum(terms
                .into_iter()
                .map(|(c, (i, j), (a, b))| (c, format!("{} * {}", element(1, i, j), element(l - 1, a, b)))));
            body += &decl(&element(l, m, n), &e);
        }
    }
    body += "    rotated[0] = sh[0];\n";
    for l in 1..order {
        let li = l as isize;
        for m in -li..=li {
            let e = sum((-li..=li).map(|n| (1.0, format!("{} * sh[{}]", element(l, m, n), index(l, n)))));
            body += &format!("    rotated[{}] = {e};\n", index(l, m));
        }
    }
    out += &match lang {
        Language::Wgsl => format!(
            "\nfn {rotate}(r: {mat3}, sh: array<{vec3}, {coeffs}>) -> array<{vec3}, {coeffs}> {{\n    var rotated: array<{vec3}, {coeffs}>;\n{body}    return rotated;\n}}\n",
            mat3 = s.mat3,
            vec3 = s.vec3
        ),
        _ => format!(
            "\nvoid {rotate}({mat3} R, {vec3} sh[{coeffs}], out {vec3} rotated[{coeffs}]) {{\n{body}}}\n",
            mat3 = s.mat3,
            vec3 = s.vec3
        ),
    };
    out
}

/// The snippet of a bake with a coloured albedo (`transfer --albedo R,G,B` or `mesh`):
/// [`snippet`]'s rotation, and the dot product of each colour channel's transfer with that
/// channel of the lighting, B_c(x) = Σ_i T_ci(x) L_ci, over the 3·n² values channel-major.
pub fn colour_snippet(order: usize, lang: Language) -> String {
    let coeffs = order * order;
    let vec4s = (3 * coeffs).div_ceil(4);
    let s = syntax(lang);
    let radiance = match lang {
        Language::Wgsl => "prtkit_transfer_radiance_rgb",
        _ => "prtkitTransferRadianceRGB",
    };
    let light = match lang {
        Language::Wgsl => "light",
        _ => "prtkitLightSH",
    };
    // Channel c's coefficient i is value c·n² + i: four-vector (c·n² + i)/4, its lane mod 4.
    let channel = |c: usize| {
        sum((0..coeffs).map(|i| {
            let value = c * coeffs + i;
            let lane = ["x", "y", "z", "w"];
            (1.0, format!("transfer[{}].{} * {light}[{i}].{}", value / 4, lane[value % 4], lane[c]))
        }))
    };
    let body = format!("{}(\n        {},\n        {},\n        {})", s.vec3, channel(0), channel(1), channel(2));
    let mut out = snippet(order, lang);
    out += &format!(
        "
// prtkit transfer, coloured albedo (transfer --albedo R,G,B or --albedo mesh): one transfer
// vector per colour channel, so colour bleeds between surfaces. _PRT_0.._PRT_{last} hold
// 3 x {coeffs} values channel-major (value c*{coeffs} + i is channel c's coefficient i, c = R, G, B;
// zeros pad the last four-vector). {radiance}: B_c(x) = sum_i T_ci(x) L_ci, each
// channel's transfer dotted with that channel of the lighting; use it for this bake in place of
// the grey dot product above, with the lighting turned by the same rotation.
",
        last = vec4s - 1
    );
    out += &match lang {
        Language::Wgsl => format!(
            "\nfn {radiance}(transfer: array<{vec4}, {vec4s}>, light: array<{vec3}, {coeffs}>) -> {vec3} {{\n    return {body};\n}}\n",
            vec4 = s.vec4,
            vec3 = s.vec3
        ),
        _ => format!(
            "\n#define PRTKIT_TRANSFER_RGB_VEC4S {vec4s}\n\n{vec3} {radiance}({vec4} transfer[PRTKIT_TRANSFER_RGB_VEC4S]) {{\n    return {body};\n}}\n",
            vec4 = s.vec4,
            vec3 = s.vec3
        ),
    };
    out
}

/// The snippet of a glossy bake: [`snippet`]'s dot product (applied per term) and rotation, then
/// the per-pixel half of Mahajan, Tseng & Ramamoorthi 2008's eq. 4 for `terms` K factors on
/// `grid` (the bake's `glossy.h`): the view direction in the normal's frame, the h_k lookup and
/// the sum over the terms (`docs/transfer.md`, "The run-time snippets").
pub fn glossy_snippet(order: usize, terms: usize, grid: Grid, lang: Language) -> String {
    let coeffs = order * order;
    let n = grid.n;
    let span = grid.span();
    let (domain, sphere) = match grid.domain {
        Domain::Sphere => ("sphere", true),
        Domain::Hemisphere => ("hemisphere", false),
    };
    let names = match lang {
        Language::Wgsl => [
            "prtkit_glossy_local_view",
            "prtkit_glossy_cos_theta_phi",
            "prtkit_glossy_taps",
            "prtkit_glossy_h",
            "prtkit_glossy_radiance",
            "prtkit_transfer_radiance",
        ],
        _ => [
            "prtkitGlossyLocalView",
            "prtkitGlossyCosThetaPhi",
            "prtkitGlossyTaps",
            "prtkitGlossyH",
            "prtkitGlossyRadiance",
            "prtkitTransferRadiance",
        ],
    };
    let [local_view, angles, taps, lookup, radiance, dot] = names;
    let (texture, h) = match lang {
        Language::Glsl => ("prtkitGlossyHTexture, a sampler2D (R32F; only texelFetch reads it, no filtering),", ""),
        Language::Hlsl => ("prtkitGlossyHTexture, a Texture2D<float> (only Load reads it, no filtering),", ""),
        Language::Wgsl => ("the argument h, a texture_2d<f32> (r32float; only textureLoad reads it),", "h, "),
    };
    let mut out = snippet(order, lang);
    out += &format!(
        "
// prtkit transfer, glossy: view-dependent transfer through the in-out BRDF factorization
// (Mahajan, Tseng & Ramamoorthi 2008, eq. 4), K = {terms} terms on a {n} x {n} {domain} grid:
//   B(x, w_o) = sum_t h_t(F^T w_o) c_t(x),   c_t(x) = sum_i T_ti(x) L_i.
// c_t: per vertex, {dot} applied to term t's {coeffs} values (the _PRT_k stream holds
// K x {coeffs} values term-major: value t*{coeffs} + i is T_ti, sigma_t folded in{repack}), then
// interpolated over the triangle.
// F = R_z(phi_n) R_y(theta_n) R_z(-phi_n): the shortest-arc rotation carrying +Z to the unit
// shading normal n, in the mesh's axes (the turn by theta_n about +Z x n; its third column is n;
// the identity at n = +Z, R_y(pi) at n = -Z). It matters: the factors have structure in phi, and
// c_t blends vertices, so F's twist about n must vary smoothly (it does but at n = -Z). w_o:
// unit, from the surface towards the eye, in the mesh's axes.
// {local_view}(n, w_o): F^T w_o.
// {angles}(w): (cos theta, phi) of it, phi in [0, 2 pi).
// {taps}(ct_phi): where h is read, the same for every term: bilinear between the cell
// centres cos theta_j = 1 - (j + 1/2) {span:.1}/{n}, phi_k = (k + 1/2) 2 pi/{n}, phi wrapping, cos theta
// clamped to the grid's first and last rows{horizon}; within half a bin of a pole the value
// blends linearly into the mean of the pole's ring of cells (phi means nothing at the pole: a
// plain bilinear lookup there shows a dot where the view meets the normal).
// {lookup}({h}t, taps): h_t there. h: {texture}
// {n} texels wide and K*{n} = {rows} tall, texel (k, t*{n} + j) = h_t of cell (j, k): the .glb's
// glossy.h blob (extras.prtkit.blobs, K*{cells} little-endian floats) uploaded as it is.
// {radiance}({h}n, w_o, c): the sum over the K terms, c[t] = c_t interpolated.
// This is the lookup prtkit render uses (render::factored::h_taps).
",
        rows = terms * n,
        cells = n * n,
        horizon = if sphere { "" } else { " (views below the horizon read\n// the horizon row)" },
        repack = if coeffs % 4 == 0 { "" } else { ";\n// repack term t's values into four-vectors" },
    );
    let two_pi = "6.283185307179586";
    let pole_south = if sphere {
        format!(
            " else if (raw > {last:.1}) {{\n        t.poleRow = {lasti};\n        t.pole = 2.0 * (raw - {last:.1});\n    }}\n    ",
            last = (n - 1) as f64,
            lasti = n - 1
        )
    } else {
        "\n    ".to_string()
    };
    match lang {
        Language::Glsl | Language::Hlsl => {
            let glsl = lang == Language::Glsl;
            let (v2, v3, v4, i4) =
                if glsl { ("vec2", "vec3", "vec4", "ivec4") } else { ("float2", "float3", "float4", "int4") };
            let atan = if glsl { "atan" } else { "atan2" };
            let fetch = |x: &str, y: &str| format!("PRTKIT_GLOSSY_H_FETCH({x}, {y})");
            // The texture is named through a macro, as the lighting is, so that a client can bind
            // it its own way (a Vulkan GLSL client: a texture2D and a sampler).
            let (declare, default_fetch) = if glsl {
                ("uniform sampler2D prtkitGlossyHTexture;", "texelFetch(prtkitGlossyHTexture, ivec2(x, y), 0).r")
            } else {
                ("Texture2D<float> prtkitGlossyHTexture;", "prtkitGlossyHTexture.Load(int3(x, y, 0))")
            };
            out += &format!(
                "
// h: the plain declaration below, or define PRTKIT_GLOSSY_H_FETCH(x, y) (texel (x, y) of h, a
// float) yourself to read your own binding.
#define PRTKIT_GLOSSY_TERMS {terms}
#define PRTKIT_GLOSSY_RESOLUTION {n}
#ifndef PRTKIT_GLOSSY_H_FETCH
{declare}
#define PRTKIT_GLOSSY_H_FETCH(x, y) {default_fetch}
#endif

{v3} {local_view}({v3} n, {v3} wo) {{
    float s = length(n.xy); // sin theta_n
    float cp = 1.0;
    float sp = 0.0;
    if (s > 0.0) {{
        cp = n.x / s;
        sp = n.y / s;
    }}
    float a = 1.0 - n.z; // F = I + [z x n]x + [z x n]x^2 / (1 + n.z): columns u, v, n
    {v3} u = {v3}(1.0 - a * cp * cp, -a * cp * sp, -n.x);
    {v3} v = {v3}(-a * cp * sp, 1.0 - a * sp * sp, -n.y);
    return {v3}(dot(u, wo), dot(v, wo), dot(n, wo));
}}

{v2} {angles}({v3} w) {{
    float phi = 0.0;
    if (w.x != 0.0 || w.y != 0.0) {{
        phi = {atan}(w.y, w.x);
    }}
    if (phi < 0.0) {{
        phi += {two_pi};
    }}
    return {v2}(clamp(w.z, -1.0, 1.0), phi);
}}

struct PrtkitGlossyTaps {{
    {i4} texel; // phi columns k0, k1; cos theta rows j0, j1
    {v4} weight; // of (k0, j0), (k1, j0), (k0, j1), (k1, j1), the ring's share folded in
    int poleRow; // the ring whose mean is the pole's value
    float pole; // its weight
}};

PrtkitGlossyTaps {taps}({v2} ctPhi) {{
    PrtkitGlossyTaps t;
    float z = max(ctPhi.x, {zmin:.1});
    float raw = (1.0 - z) * {bins_per_cos:.1} - 0.5;
    float fj = clamp(raw, 0.0, {last:.1});
    t.poleRow = 0;
    t.pole = 0.0;
    if (raw < 0.0) {{
        t.pole = -2.0 * raw;
    }}{pole_south}float ring = 1.0 - t.pole;
    float fk = ctPhi.y * {bins_per_radian:.17} - 0.5;
    float k0f = floor(fk);
    float tk = fk - k0f;
    float tj = fj - floor(fj);
    int k0 = (int(k0f) + {n}) % {n}; // fk >= -1/2
    int j0 = int(floor(fj));
    t.texel = {i4}(k0, (k0 + 1) % {n}, j0, min(j0 + 1, {lasti}));
    t.weight = ring * {v4}((1.0 - tj) * (1.0 - tk), (1.0 - tj) * tk, tj * (1.0 - tk), tj * tk);
    return t;
}}

float {lookup}(int term, PrtkitGlossyTaps t) {{
    int row = term * {n};
    float value = t.weight.x * {f00} + t.weight.y * {f10}
        + t.weight.z * {f01} + t.weight.w * {f11};
    if (t.pole > 0.0) {{
        float mean = 0.0;
        for (int k = 0; k < {n}; k++) {{
            mean += {fpole};
        }}
        value += t.pole * mean / {bins:.1};
    }}
    return value;
}}

{v3} {radiance}({v3} n, {v3} wo, {v3} c[PRTKIT_GLOSSY_TERMS]) {{
    PrtkitGlossyTaps t = {taps}({angles}({local_view}(n, wo)));
    {v3} b = {v3}(0.0, 0.0, 0.0);
    for (int k = 0; k < PRTKIT_GLOSSY_TERMS; k++) {{
        b += {lookup}(k, t) * c[k];
    }}
    return b;
}}
",
                zmin = 1.0 - span,
                bins_per_cos = n as f64 / span,
                last = (n - 1) as f64,
                lasti = n - 1,
                bins_per_radian = n as f64 / std::f64::consts::TAU,
                bins = n as f64,
                f00 = fetch("t.texel.x", "row + t.texel.z"),
                f10 = fetch("t.texel.y", "row + t.texel.z"),
                f01 = fetch("t.texel.x", "row + t.texel.w"),
                f11 = fetch("t.texel.y", "row + t.texel.w"),
                fpole = fetch("k", "row + t.poleRow"),
            );
        }
        Language::Wgsl => {
            let pole_south = pole_south.replace("poleRow", "pole_row");
            let fetch = |x: &str, y: &str| format!("textureLoad(h, vec2<i32>({x}, {y}), 0).x");
            out += &format!(
                "
fn {local_view}(n: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {{
    let s = length(n.xy); // sin theta_n
    var cp = 1.0;
    var sp = 0.0;
    if (s > 0.0) {{
        cp = n.x / s;
        sp = n.y / s;
    }}
    let a = 1.0 - n.z; // F = I + [z x n]x + [z x n]x^2 / (1 + n.z): columns u, v, n
    let u = vec3<f32>(1.0 - a * cp * cp, -a * cp * sp, -n.x);
    let v = vec3<f32>(-a * cp * sp, 1.0 - a * sp * sp, -n.y);
    return vec3<f32>(dot(u, wo), dot(v, wo), dot(n, wo));
}}

fn {angles}(w: vec3<f32>) -> vec2<f32> {{
    var phi = 0.0;
    if (w.x != 0.0 || w.y != 0.0) {{
        phi = atan2(w.y, w.x);
    }}
    if (phi < 0.0) {{
        phi += {two_pi};
    }}
    return vec2<f32>(clamp(w.z, -1.0, 1.0), phi);
}}

struct PrtkitGlossyTaps {{
    texel: vec4<i32>,  // phi columns k0, k1; cos theta rows j0, j1
    weight: vec4<f32>, // of (k0, j0), (k1, j0), (k0, j1), (k1, j1), the ring's share folded in
    pole_row: i32,     // the ring whose mean is the pole's value
    pole: f32,         // its weight
}}

fn {taps}(ct_phi: vec2<f32>) -> PrtkitGlossyTaps {{
    var t: PrtkitGlossyTaps;
    let z = max(ct_phi.x, {zmin:.1});
    let raw = (1.0 - z) * {bins_per_cos:.1} - 0.5;
    let fj = clamp(raw, 0.0, {last:.1});
    t.pole_row = 0;
    t.pole = 0.0;
    if (raw < 0.0) {{
        t.pole = -2.0 * raw;
    }}{pole_south}let ring = 1.0 - t.pole;
    let fk = ct_phi.y * {bins_per_radian:.17} - 0.5;
    let k0f = floor(fk);
    let tk = fk - k0f;
    let tj = fj - floor(fj);
    let k0 = (i32(k0f) + {n}) % {n}; // fk >= -1/2
    let j0 = i32(floor(fj));
    t.texel = vec4<i32>(k0, (k0 + 1) % {n}, j0, min(j0 + 1, {lasti}));
    t.weight = ring * vec4<f32>((1.0 - tj) * (1.0 - tk), (1.0 - tj) * tk, tj * (1.0 - tk), tj * tk);
    return t;
}}

fn {lookup}(h: texture_2d<f32>, term: i32, t: PrtkitGlossyTaps) -> f32 {{
    let row = term * {n};
    var value = t.weight.x * {f00} + t.weight.y * {f10}
        + t.weight.z * {f01} + t.weight.w * {f11};
    if (t.pole > 0.0) {{
        var mean = 0.0;
        for (var k = 0; k < {n}; k++) {{
            mean += {fpole};
        }}
        value += t.pole * mean / {bins:.1};
    }}
    return value;
}}

fn {radiance}(h: texture_2d<f32>, n: vec3<f32>, wo: vec3<f32>, c: array<vec3<f32>, {terms}>) -> vec3<f32> {{
    let t = {taps}({angles}({local_view}(n, wo)));
    var terms = c; // indexed by a variable: held in a var
    var b = vec3<f32>(0.0, 0.0, 0.0);
    for (var k = 0; k < {terms}; k++) {{
        b += {lookup}(h, k, t) * terms[k];
    }}
    return b;
}}
",
                zmin = 1.0 - span,
                bins_per_cos = n as f64 / span,
                last = (n - 1) as f64,
                lasti = n - 1,
                bins_per_radian = n as f64 / std::f64::consts::TAU,
                bins = n as f64,
                f00 = fetch("t.texel.x", "row + t.texel.z"),
                f10 = fetch("t.texel.y", "row + t.texel.z"),
                f01 = fetch("t.texel.x", "row + t.texel.w"),
                f11 = fetch("t.texel.y", "row + t.texel.w"),
                fpole = fetch("k", "row + t.pole_row"),
            );
        }
    }
    out
}

/// The dequantization of a quantized, uncompressed bake's `_PRT_k` four-vectors (`transfer
/// --quantize`): a client reads a normalized component as max(code / q, −1) (glTF 2.0 §3.11),
/// and the transfer value is that times its index's scale, `scales` being the `.glb`'s
/// `transfer.scales` blob written out as literals. Call it on a vertex's four-vectors before
/// the dot product (or, for a glossy bake, before splitting the stream into terms).
pub fn dequantize_snippet(quantized: &Quantized, lang: Language) -> String {
    let (scales, code_max, kind) = (&quantized.scales, quantized.code_max, quantized.component());
    let vec4s = scales.len().div_ceil(4);
    let s = syntax(lang);
    let name = match lang {
        Language::Wgsl => "prtkit_dequantize_transfer",
        _ => "prtkitDequantizeTransfer",
    };
    let mut body = String::new();
    for k in 0..vec4s {
        let four: Vec<String> =
            (4 * k..4 * k + 4).map(|i| format!("{:.8e}", scales.get(i).copied().unwrap_or(0.0))).collect();
        let scale = format!("{}({})", s.vec4, four.join(", "));
        body += &match lang {
            Language::Wgsl => format!("    t[{k}] = t[{k}] * {scale};\n"),
            _ => format!("    transfer[{k}] *= {scale};\n"),
        };
    }
    let header = format!(
        "
// prtkit transfer, quantized (transfer --quantize): the _PRT_k attributes are normalized {kind}
// VEC4s; a glTF client reads each component as max(code / {code_max}, -1), and the transfer value
// is that times its index's scale, scale_i = the .glb's transfer.scales blob (written out below).
// {name}: call it on the vertex's {vec4s} four-vectors before the dot product.
"
    );
    header
        + &match lang {
            Language::Wgsl => format!(
                "\nfn {name}(transfer: array<{vec4}, {vec4s}>) -> array<{vec4}, {vec4s}> {{\n    var t = transfer;\n{body}    return t;\n}}\n",
                vec4 = s.vec4
            ),
            _ => format!("\nvoid {name}(inout {vec4} transfer[{vec4s}]) {{\n{body}}}\n", vec4 = s.vec4),
        }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::rotate::ShRotation;
    use glam::{DMat3, DVec3};

    #[test]
    fn written_out_bands_are_the_recurrences() {
        // The terms the snippet prints, evaluated in f64 from band 1 of a rotation up, must give
        // ShRotation's blocks: the same recurrence, not a second derivation of it.
        let rotation = DMat3::from_axis_angle(DVec3::new(0.3, -0.5, 0.8).normalize(), 1.1);
        let order = 7;
        let reference = ShRotation::new(rotation, order);
        let mut prev: Vec<f64> = (0..9).map(|k| reference.element(1, k / 3 - 1, k % 3 - 1)).collect();
        let b1 = prev.clone();
        for l in 2..=order {
            let li = l as isize;
            let wp = 2 * li - 1;
            let block: Vec<f64> = band_terms(l)
                .iter()
                .map(|terms| {
                    terms
                        .iter()
                        .map(|&(c, (i, j), (a, b))| {
                            c * b1[((i + 1) * 3 + j + 1) as usize] * prev[((a + li - 1) * wp + b + li - 1) as usize]
                        })
                        .sum()
                })
                .collect();
            for (k, v) in block.iter().enumerate() {
                let (m, n) = (k as isize / (2 * li + 1) - li, k as isize % (2 * li + 1) - li);
                assert!((v - reference.element(l, m, n)).abs() < 1e-13, "band {l} ({m}, {n})");
            }
            prev = block;
        }
        // Band 1 read from R as the snippet reads it: element (m, n) = R[axis(m)][axis(n)].
        let cols = rotation.to_cols_array_2d();
        for m in -1..=1isize {
            for n in -1..=1isize {
                assert_eq!(cols[axis(n)][axis(m)], reference.element(1, m, n));
            }
        }
    }
}
