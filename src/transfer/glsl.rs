//! The run-time half of diffuse PRT as GLSL: B(x) = Σ_i T_i(x) L_i (Sloan, Kautz & Snyder 2002,
//! eq. 9), the transfer read from the `_PRT_k` vertex attributes (`docs/formats/transfer.md`),
//! the lighting's SH from a uniform array.

/// The snippet for `order` n bands (n² coefficients in ⌈n²/4⌉ vec4 attributes).
pub fn snippet(order: usize) -> String {
    let coeffs = order * order;
    let vec4s = coeffs.div_ceil(4);
    format!(
        "// prtkit transfer: diffuse precomputed radiance transfer (Sloan, Kautz & Snyder 2002, eq. 9).
// Outgoing radiance B(x) = sum_i T_i(x) L_i, i = l(l+1)+m over n = {order} bands ({coeffs} coefficients).
// T_i: the glTF vertex attributes _PRT_0.._PRT_{last}, four coefficients per vec4 in index order
// (zeros pad the last); L_i: the lighting's RGB SH coefficients in prtkit's basis (real,
// orthonormal, no Condon-Shortley phase), expressed in the mesh's own axes; albedo is baked in.
// Declare prtkitLightSH yourself (e.g. in a uniform block) and define
// PRTKIT_LIGHT_SH_DECLARED to replace the plain uniform below.
#define PRTKIT_TRANSFER_COEFFS {coeffs}
#define PRTKIT_TRANSFER_VEC4S {vec4s}
#ifndef PRTKIT_LIGHT_SH_DECLARED
uniform vec3 prtkitLightSH[PRTKIT_TRANSFER_COEFFS];
#endif

vec3 prtkitTransferRadiance(vec4 transfer[PRTKIT_TRANSFER_VEC4S]) {{
    vec3 radiance = vec3(0.0);
    for (int k = 0; k < PRTKIT_TRANSFER_VEC4S; ++k) {{
        for (int j = 0; j < 4; ++j) {{
            int i = 4 * k + j;
            if (i < PRTKIT_TRANSFER_COEFFS) {{
                radiance += transfer[k][j] * prtkitLightSH[i];
            }}
        }}
    }}
    return radiance;
}}
",
        last = vec4s - 1
    )
}
