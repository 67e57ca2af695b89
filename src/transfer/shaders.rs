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
//! [`ShRotation`]: crate::sh::rotate::ShRotation

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
