//! Order-2 SH irradiance for shaders (what cmgen's `--sh-shader` gives): nine RGB coefficients,
//! already convolved with the clamped cosine and divided by π, in the output frame, so a shader
//! evaluates the diffuse radiance of a white Lambertian surface as a polynomial in the normal:
//!
//!   E(n)/π = Σ_i c_i b_i(n),  b = (1, y, z, x, xy, yz, 3z² − 1, xz, x² − y²),
//!
//! with n = (x, y, z) in the output frame (glTF's, +Y up, unless `--up z`). The c_i are
//! c_i = (Â_l/π) K_lm L_lm (Ramamoorthi & Hanrahan 2001, eqs. 8–9, 12: Â_0 = π, Â_1 = 2π/3,
//! Â_2 = π/4), where L_lm are the radiance coefficients in prtkit's real orthonormal basis
//! (`docs/conventions.md`: Y_1,−1 ∝ y, Y_1,0 ∝ z, Y_1,1 ∝ x, no Condon–Shortley phase) and K_lm
//! the constant of Y_lm = K_lm b_i. Multiply by the albedo; multiply by π for the irradiance E.
//!
//! The L_lm are prtkit's projection of the input (`sh::project`: the midpoint rule with exact
//! solid angles, separable on a lat-long map, as `sh-project`) carried to the output frame by
//! M, the output frame's matrix from prtkit's (rotation, `--rotate`, `--mirror` included):
//! L'_lm = Σ_t L_t Ω_t Y_lm(M d_t) are the coefficients of L∘M⁻¹, which `ShRotation` gives for
//! any orthogonal M, a mirror too (band l of a degree-l harmonic polynomial).

use crate::envmap::EnvMap;
use crate::progress::NoProgress;
use crate::sh::project::{project, ProjectError};
use crate::sh::rotate::ShRotation;
use crate::sh::{convolve::clamped_cosine, lm, ShCoeffs};
use glam::{DMat3, DVec3};
use std::f64::consts::PI;

/// The polynomial constants K_lm of prtkit's order-2 basis, Y_lm = K_lm b_i, in index order.
pub fn basis_constants() -> [f64; 9] {
    let c0 = 0.5 / PI.sqrt();
    let c1 = (3.0 / (4.0 * PI)).sqrt();
    let c2 = (15.0 / (4.0 * PI)).sqrt();
    let c20 = (5.0 / (16.0 * PI)).sqrt();
    let c22 = (15.0 / (16.0 * PI)).sqrt();
    [c0, c1, c1, c1, c2, c2, c20, c2, c22]
}

/// The polynomials b_i(n) of the shader form, in index order.
pub fn basis_polynomials(n: DVec3) -> [f64; 9] {
    let (x, y, z) = (n.x, n.y, n.z);
    [1.0, y, z, x, x * y, y * z, 3.0 * z * z - 1.0, x * z, x * x - y * y]
}

/// The polynomials as shader source (GLSL/HLSL/WGSL share the syntax of these products).
const POLYNOMIALS: [&str; 9] = [
    "1.0",
    "n.y",
    "n.z",
    "n.x",
    "n.x * n.y",
    "n.y * n.z",
    "3.0 * n.z * n.z - 1.0",
    "n.x * n.z",
    "n.x * n.x - n.y * n.y",
];

/// The irradiance of one environment in the output frame.
#[derive(Clone, Debug, PartialEq)]
pub struct IrradianceSh {
    /// Radiance coefficients L_lm in the output frame (orthonormal basis, order 2).
    pub radiance: ShCoeffs,
    /// Shader coefficients c_i: E(n)/π = Σ c_i b_i(n).
    pub shader: [[f64; 3]; 9],
}

impl IrradianceSh {
    /// Projects `env` (any layout; prtkit's frame) with its directions taken to the output frame
    /// by `world_from_env`. A map too coarse for order 2 (a lat-long map narrower than 4 texels)
    /// is an error.
    pub fn project(env: &EnvMap, world_from_env: DMat3) -> Result<Self, ProjectError> {
        let radiance = ShRotation::new(world_from_env, 2).apply(&project(env, 2, &NoProgress)?);
        let k = basis_constants();
        let mut shader = [[0.0; 3]; 9];
        for i in 0..9 {
            let (l, _) = lm(i);
            let factor = clamped_cosine(l) / PI * k[i];
            shader[i] = radiance.rgb[i].map(|v| v * factor);
        }
        Ok(IrradianceSh { radiance, shader })
    }

    /// E(n)/π at an output-frame normal.
    pub fn eval(&self, n: DVec3) -> [f64; 3] {
        let b = basis_polynomials(n.normalize());
        let mut out = [0.0; 3];
        for i in 0..9 {
            for ch in 0..3 {
                out[ch] += self.shader[i][ch] * b[i];
            }
        }
        out
    }

    /// The comment block the three languages share (all take `//`).
    fn header(&self, frame: &str) -> String {
        format!(
            "// prtkit ibl: order-2 SH irradiance, pre-convolved (Ramamoorthi & Hanrahan 2001).\n\
             // Frame: {frame}; n must be a unit normal in that frame.\n\
             // Scale: returns E(n)/pi, the radiance a white Lambertian surface reflects;\n\
             // multiply by the albedo (by pi for the irradiance E itself).\n"
        )
    }

    fn sum_expression(&self, name: &str) -> String {
        POLYNOMIALS
            .iter()
            .enumerate()
            .map(|(i, p)| if i == 0 { format!("{name}[0]") } else { format!("{name}[{i}] * ({p})") })
            .collect::<Vec<_>>()
            .join("\n        + ")
    }

    fn vectors(&self, ctor: &str) -> Vec<String> {
        self.shader
            .iter()
            .map(|c| format!("{ctor}({:.9e}, {:.9e}, {:.9e})", c[0] as f32, c[1] as f32, c[2] as f32))
            .collect()
    }

    /// GLSL (ES 3.0 / 4.x): a constant array and `vec3 prtkitIrradiance(vec3 n)`.
    pub fn glsl(&self, frame: &str) -> String {
        format!(
            "{}const vec3 PRTKIT_SH[9] = vec3[9](\n    {}\n);\n\nvec3 prtkitIrradiance(vec3 n) {{\n    return {};\n}}\n",
            self.header(frame),
            self.vectors("vec3").join(",\n    "),
            self.sum_expression("PRTKIT_SH")
        )
    }

    /// HLSL: a static constant array and `float3 prtkitIrradiance(float3 n)`.
    pub fn hlsl(&self, frame: &str) -> String {
        format!(
            "{}static const float3 PRTKIT_SH[9] = {{\n    {}\n}};\n\nfloat3 prtkitIrradiance(float3 n) {{\n    return {};\n}}\n",
            self.header(frame),
            self.vectors("float3").join(",\n    "),
            self.sum_expression("PRTKIT_SH")
        )
    }

    /// WGSL: a module-scope constant array and `fn prtkit_irradiance(n: vec3<f32>) -> vec3<f32>`.
    pub fn wgsl(&self, frame: &str) -> String {
        format!(
            "{}const PRTKIT_SH = array<vec3<f32>, 9>(\n    {}\n);\n\nfn prtkit_irradiance(n: vec3<f32>) -> vec3<f32> {{\n    return {};\n}}\n",
            self.header(frame),
            self.vectors("vec3<f32>").join(",\n    "),
            self.sum_expression("PRTKIT_SH")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::eval_basis_dir;
    use crate::sh::legendre::LegendreTable;
    use crate::sphere::latlong::LatLong;

    /// Σ_t L_t Ω_t Y_lm(M d_t) texel by texel with the library's basis, M applied to each
    /// direction: what `project` must give.
    fn projected_texel_by_texel(env: &EnvMap, m: DMat3) -> Vec<[f64; 3]> {
        let (table, mut y) = (LegendreTable::new(2), vec![0.0; 9]);
        let mut sums = vec![[0.0; 3]; 9];
        env.for_each_texel(|t| {
            eval_basis_dir(&table, m * t.dir, &mut y);
            for (sum, yi) in sums.iter_mut().zip(&y) {
                (0..3).for_each(|c| sum[c] += t.rgb[c] as f64 * t.solid_angle * yi);
            }
        });
        sums
    }

    /// An uneven map (a sun, a horizon, a tilt in φ), lat-long or as six faces.
    fn uneven(d: DVec3) -> [f32; 3] {
        let sun = (-(1.0 - d.dot(DVec3::new(0.3, -0.5, 0.8).normalize())) * 40.0).exp() * 20.0;
        let sky = if d.z > 0.0 { 0.5 + 0.4 * d.x + 0.2 * d.y * d.y } else { 0.1 };
        [(sky + sun) as f32, (0.7 * sky + sun) as f32, (0.4 * sky + 0.5 * sun) as f32]
    }

    #[test]
    fn projects_as_the_basis_does_texel_by_texel_in_the_output_frame() {
        let grid = LatLong::new(96, 48);
        let latlong =
            EnvMap::latlong(crate::io::RgbImage::from_fn(96, 48, |x, y| uneven(grid.texel_direction(x, y)))).unwrap();
        let faces = EnvMap::from_faces(
            crate::envmap::FACES
                .iter()
                .map(|&f| {
                    crate::io::RgbImage::from_fn(16, 16, |x, y| {
                        uneven(crate::ibl::cube::texel_direction(f, 16, y, x).normalize())
                    })
                })
                .collect(),
        )
        .unwrap();
        let turned = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7);
        let mirrored = DMat3::from_diagonal(DVec3::new(1.0, -1.0, 1.0)) * turned;
        for env in [&latlong, &faces] {
            for m in [DMat3::IDENTITY, turned, mirrored] {
                let got = IrradianceSh::project(env, m).unwrap().radiance.rgb;
                let want = projected_texel_by_texel(env, m);
                for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                    for c in 0..3 {
                        assert!(
                            (g[c] - w[c]).abs() < 1e-12 * (1.0 + w[c].abs()),
                            "{:?} {i}/{c}: {} vs {}",
                            env.layout(),
                            g[c],
                            w[c]
                        );
                    }
                }
                // Not vacuous: the map has every band.
                assert!(want.iter().all(|w| w.iter().all(|v| v.abs() > 1e-4)), "{want:?}");
            }
        }
    }

    #[test]
    fn polynomial_form_is_prtkits_basis() {
        // Independent of the constants' derivation: K_lm b_i(n) must equal the library's Y_lm(n).
        let table = LegendreTable::new(2);
        let mut y = vec![0.0; 9];
        let k = basis_constants();
        for n in [DVec3::new(0.3, -0.5, 0.8), DVec3::new(-0.9, 0.1, 0.2), DVec3::Z, DVec3::new(1.0, 1.0, -1.0)] {
            let n = n.normalize();
            eval_basis_dir(&table, n, &mut y);
            let b = basis_polynomials(n);
            for i in 0..9 {
                assert!((k[i] * b[i] - y[i]).abs() < 1e-12, "{i}: {} vs {}", k[i] * b[i], y[i]);
            }
        }
    }
}
