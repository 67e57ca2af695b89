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
//! The L_lm are projected directly in the output frame, L_lm = Σ_t L_t Ω_t Y_lm(M d_t) over the
//! input lat-long texels (midpoint rule with exact solid angles, as `sh-project`), with M the
//! output frame's matrix from prtkit's (rotation, `--rotate`, `--mirror` included).
//!
//! Every b_i is a polynomial of degree at most 2, so these sums need only the map's moments
//! Σ L Ω, Σ L Ω d and Σ L Ω d dᵀ ([`Moments`]), which M carries to the output frame as M m and
//! M S Mᵀ. On a lat-long map a row's moments factor into five sums over its columns,
//! Σ L · (1, cos φ, sin φ, cos² φ, cos φ sin φ), since d = (sin θ cos φ, sin θ sin φ, cos θ) has
//! one θ per row: five products per texel and channel where the basis took twenty-seven.

use crate::envmap::{EnvMap, Layout};
use crate::sh::{convolve::clamped_cosine, lm, ShCoeffs};
use crate::sphere::latlong::LatLong;
use glam::{DMat3, DVec3};
use rayon::prelude::*;
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
    /// Projects `latlong` (any layout works; prtkit's frame) with its directions taken to the
    /// output frame by `world_from_env`.
    pub fn project(env: &EnvMap, world_from_env: DMat3) -> Self {
        let sums = Moments::of(env).rotated(world_from_env).polynomial_sums();
        let k = basis_constants();
        let mut radiance = ShCoeffs::zeros(2);
        for ((c, sum), ki) in radiance.rgb.iter_mut().zip(&sums).zip(&k) {
            *c = sum.map(|v| v * ki);
        }
        let mut shader = [[0.0; 3]; 9];
        for i in 0..9 {
            let (l, _) = lm(i);
            let factor = clamped_cosine(l) / PI * k[i];
            shader[i] = radiance.rgb[i].map(|v| v * factor);
        }
        IrradianceSh { radiance, shader }
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

/// The zeroth, first and second moments of a map's radiance over the sphere, per channel:
/// Σ_t L_t Ω_t, Σ_t L_t Ω_t d_t and Σ_t L_t Ω_t d_t d_tᵀ (midpoint rule, exact solid angles).
struct Moments {
    zero: [f64; 3],
    first: [DVec3; 3],
    second: [DMat3; 3],
}

impl Moments {
    fn zeros() -> Moments {
        Moments { zero: [0.0; 3], first: [DVec3::ZERO; 3], second: [DMat3::ZERO; 3] }
    }

    /// The moments of `env`: row by row on a lat-long map (rows summed in parallel, then added in
    /// order, so the same sums on any number of threads), texel by texel otherwise.
    fn of(env: &EnvMap) -> Moments {
        let mut moments = Moments::zeros();
        if env.layout() != Layout::LatLong {
            env.for_each_texel(|t| moments.add(t.rgb.map(|v| v as f64 * t.solid_angle), t.dir));
            return moments;
        }
        let image = env.image();
        let grid = LatLong::new(image.width, image.height);
        let columns: Vec<[f64; 4]> = (0..grid.width)
            .map(|x| {
                let (sin, cos) = grid.column_phi(x).sin_cos();
                [cos, sin, cos * cos, cos * sin]
            })
            .collect();
        let rows: Vec<[[f64; 5]; 3]> = (0..grid.height)
            .into_par_iter()
            .map(|y| {
                let mut sums = [[0.0; 5]; 3];
                for (l, [cos, sin, cos2, cos_sin]) in
                    image.pixels[y * grid.width..(y + 1) * grid.width].iter().zip(&columns)
                {
                    for (s, &l) in sums.iter_mut().zip(l) {
                        let l = l as f64;
                        s[0] += l;
                        s[1] += l * cos;
                        s[2] += l * sin;
                        s[3] += l * cos2;
                        s[4] += l * cos_sin;
                    }
                }
                sums
            })
            .collect();
        for (y, sums) in rows.iter().enumerate() {
            let (sin_t, cos_t) = grid.row_theta(y).sin_cos();
            let solid_angle = grid.row_solid_angle(y);
            for (c, [l, l_cos, l_sin, l_cos2, l_cos_sin]) in sums.iter().enumerate() {
                let (xx, yy, xy) = (sin_t * sin_t * l_cos2, sin_t * sin_t * (l - l_cos2), sin_t * sin_t * l_cos_sin);
                let (xz, yz, zz) = (sin_t * cos_t * l_cos, sin_t * cos_t * l_sin, cos_t * cos_t * l);
                moments.zero[c] += solid_angle * l;
                moments.first[c] += solid_angle * DVec3::new(sin_t * l_cos, sin_t * l_sin, cos_t * l);
                moments.second[c] += solid_angle
                    * DMat3::from_cols(DVec3::new(xx, xy, xz), DVec3::new(xy, yy, yz), DVec3::new(xz, yz, zz));
            }
        }
        moments
    }

    /// Adds one texel: its radiance times its solid angle, `weighted`, in direction `d`.
    fn add(&mut self, weighted: [f64; 3], d: DVec3) {
        let outer = DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        for (c, w) in weighted.into_iter().enumerate() {
            self.zero[c] += w;
            self.first[c] += w * d;
            self.second[c] += w * outer;
        }
    }

    /// The moments of the directions taken by `m`: M m and M S Mᵀ.
    fn rotated(&self, m: DMat3) -> Moments {
        Moments {
            zero: self.zero,
            first: self.first.map(|v| m * v),
            second: self.second.map(|s| m * s * m.transpose()),
        }
    }

    /// Σ L Ω b_i(d) for the shader form's polynomials b = (1, y, z, x, xy, yz, 3z² − 1, xz,
    /// x² − y²), per channel.
    fn polynomial_sums(&self) -> [[f64; 3]; 9] {
        let mut sums = [[0.0; 3]; 9];
        for c in 0..3 {
            let (zero, m, s) = (self.zero[c], self.first[c], self.second[c]);
            let b = [
                zero,
                m.y,
                m.z,
                m.x,
                s.x_axis.y,
                s.y_axis.z,
                3.0 * s.z_axis.z - zero,
                s.x_axis.z,
                s.x_axis.x - s.y_axis.y,
            ];
            for (sum, b) in sums.iter_mut().zip(b) {
                sum[c] = b;
            }
        }
        sums
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::eval_basis_dir;
    use crate::sh::legendre::LegendreTable;
    use crate::sphere::latlong::LatLong;

    /// Σ_t L_t Ω_t Y_lm(M d_t) texel by texel with the library's basis: what `project`'s
    /// moments must sum to.
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
    fn moments_project_as_the_basis_does_texel_by_texel() {
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
                let got = IrradianceSh::project(env, m).radiance.rgb;
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
    fn moments_are_the_same_on_any_number_of_threads() {
        let grid = LatLong::new(512, 256);
        let env =
            EnvMap::latlong(crate::io::RgbImage::from_fn(512, 256, |x, y| uneven(grid.texel_direction(x, y)))).unwrap();
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| IrradianceSh::project(&env, DMat3::IDENTITY))
        };
        assert_eq!(on(1), on(3));
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
