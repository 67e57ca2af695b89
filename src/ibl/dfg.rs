//! The split-sum DFG table (Karis 2013, "Real Shading in Unreal Engine 4", §"Image Based
//! Lighting"): the second factor of the split sum, the specular BRDF integrated against a white
//! environment, tabulated over (n·v, perceptual roughness).
//!
//! With Schlick's Fresnel F = F0 + (1 − F0)(1 − v·h)⁵ = F0 (1 − F_c) + F_c, F_c = (1 − v·h)⁵, the
//! GGX D and the height-correlated Smith visibility V (see [`crate::brdf::ggx`]), the directional albedo
//! of f_spec = D F V splits into a scale and a bias on F0:
//!
//!   ∫ f_spec(l, v) (n·l) dω_l = F0·A + B,
//!   A = ∫ D V (1 − F_c) (n·l) dω_l,   B = ∫ D V F_c (n·l) dω_l.
//!
//! The integrals are taken over the half vector, dω_l = 4 (v·h) dω_h (Walter et al. 2007, eq. 14),
//! with h = (θ_h, φ) about n = +Z and v = (sin θ_v, 0, cos θ_v). There is **no Monte Carlo**:
//! Gauss–Legendre in θ_h on pieces that grow geometrically from the lobe width α (so every
//! roughness is resolved), and Gauss–Legendre in φ over exactly the part of the circle where
//! n·l = 2(v·h) cos θ_h − cos θ_v > 0, solved in closed form per θ_h:
//!
//!   sin θ_v sin θ_h cos φ > −cos θ_v cos 2θ_h / (2 cos θ_h).
//!
//! That set is the whole circle for θ_h < (π/2 − θ_v)/2 and empty beyond (π/2 + θ_v)/2; at those
//! two angles the φ-integral behaves like a power of √(θ_h − t), so they are piece boundaries and
//! the adjacent pieces use θ = t ± (b − a)u², which makes the integrand smooth in u.
//!
//! ## What the table holds (`DfgTable`)
//!
//! Texel (row j, column i) of an N×N table is at n·v = (i + ½)/N and perceptual roughness
//! r = (j + ½)/N (texel centres; α = r²). Row 0 is the smoothest; a shader samples it with
//! uv = (n·v, r) and a clamp-to-edge, linear sampler (the glTF Sample Viewer's layout; Filament
//! stores the same values upside down).
//!
//! - [`DfgVariant::ScaleBias`] — (A, B): the shader forms the specular environment term as
//!   `prefiltered(R, r) * (F0 * dfg.x + dfg.y)` (Karis 2013).
//! - [`DfgVariant::MultiScatter`] — Filament's `DFV_Multiscatter` layout (B, A + B): x is the
//!   F_c-weighted albedo and y the single-scattering albedo E(n·v) for F0 = 1. The shader forms
//!   `mix(dfg.xxx, dfg.yyy, F0) = F0 A + B`, the same single-scattering term, and multiplies the
//!   specular lobe by the energy compensation `1 + F0 (1/dfg.y − 1)` (Fdez-Agüera 2019; Kulla &
//!   Conty 2017), which makes a white furnace with F0 = 1 reflect exactly 1.

use crate::brdf::ggx::{lobe_rule, Ggx, GgxError};
use crate::io::gpu_format::{Texture, TextureShape};
use crate::limits::MAX_DFG_SIZE;
use crate::quadrature::gauss_legendre_cached as gauss_legendre;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// Default table side (Filament's and the glTF Sample Viewer's 128²).
pub const DEFAULT_SIZE: usize = 128;

/// Gauss–Legendre nodes per θ_h piece ([`phi_nodes`] in φ). On the 128² table, 16 and 48 nodes
/// agree to 1.2e-7 in every texel (`benches/ibl_blocks.rs`), below the table's f32 rounding.
pub const DEFAULT_ORDER: usize = 16;

/// Errors of the DFG integrals.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum DfgError {
    /// A table side of 0 or above [`MAX_DFG_SIZE`].
    #[error("the DFG table side must be between 1 and {MAX_DFG_SIZE}, got {0}")]
    Size(usize),
    /// n·v outside (0, 1].
    #[error("n·v must be in (0, 1], got {0}")]
    NDotV(f64),
    /// A bad roughness.
    #[error(transparent)]
    Roughness(#[from] GgxError),
}

/// Which pair of integrals a table stores (see the module docs for the shader side).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DfgVariant {
    /// (A, B): the split-sum scale and bias on F0 (Karis 2013).
    ScaleBias,
    /// (B, A + B): Filament's multiple-scattering layout.
    MultiScatter,
}

/// The two split-sum integrals at one (n·v, r): ∫ f_spec (n·l) dω = F0·scale + bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplitSumTerms {
    /// A = ∫ D V (1 − F_c) (n·l) dω_l.
    pub scale: f64,
    /// B = ∫ D V F_c (n·l) dω_l.
    pub bias: f64,
}

impl SplitSumTerms {
    /// A + B: the single-scattering directional albedo E(n·v) for F0 = 1.
    pub fn albedo(&self) -> f64 {
        self.scale + self.bias
    }

    /// The two values a table of `variant` stores.
    pub fn channels(&self, variant: DfgVariant) -> [f64; 2] {
        match variant {
            DfgVariant::ScaleBias => [self.scale, self.bias],
            DfgVariant::MultiScatter => [self.bias, self.albedo()],
        }
    }
}

/// A and B at n·v ∈ (0, 1] and perceptual roughness r ∈ [0, 1], by the default quadrature.
pub fn split_sum_terms(n_dot_v: f64, perceptual_roughness: f64) -> Result<SplitSumTerms, DfgError> {
    if !(n_dot_v > 0.0 && n_dot_v <= 1.0) {
        return Err(DfgError::NDotV(n_dot_v));
    }
    Ok(integrate(n_dot_v, Ggx::new(perceptual_roughness)?, DEFAULT_ORDER))
}

/// Gauss–Legendre nodes in φ for `order` in θ_h: order + 2. The φ-integrand is smooth on
/// [0, φ_max] (it vanishes linearly at the horizon cut), and the θ_h rule sets the error: on the
/// 128² table against 48 and 96 nodes, order 6 is 9.94e-5 off with 12 φ nodes and with 8, and
/// 9.87e-5 with 6 (but 6e-5 instead of 1e-5 at r ≈ 0.13).
pub fn phi_nodes(order: usize) -> usize {
    order.max(1) + 2
}

/// A and B by the half-vector quadrature with `order` nodes per θ_h piece and
/// [`phi_nodes`]`(order)` in φ.
fn integrate(n_dot_v: f64, ggx: Ggx, order: usize) -> SplitSumTerms {
    let mu = n_dot_v;
    let sin_v = (1.0 - mu * mu).max(0.0).sqrt();
    let theta_v = mu.acos();
    // Whole circle below t_full, nothing beyond t_end (see the module docs).
    let t_full = 0.5 * (FRAC_PI_2 - theta_v);
    let t_end = 0.5 * (FRAC_PI_2 + theta_v);
    let phi_rule = gauss_legendre(phi_nodes(order));
    let (mut a, mut b) = (0.0, 0.0);
    for (theta_h, w_theta) in lobe_rule(ggx.alpha(), 0.0, t_end, PI / 16.0, order, &[t_full, t_end]) {
        let (s_h, c_h) = theta_h.sin_cos();
        let d = ggx.d_half_angle(c_h * c_h, s_h * s_h);
        // n·l > 0 ⇔ sin θ_v sin θ_h cos φ > −cos θ_v cos 2θ_h / (2 cos θ_h) =: rhs.
        let rhs = -mu * (2.0 * c_h * c_h - 1.0) / (2.0 * c_h);
        let k = sin_v * s_h;
        let phi_max = if k <= 1e-300 {
            if rhs < 0.0 {
                PI
            } else {
                0.0
            }
        } else {
            let c = rhs / k;
            if c <= -1.0 {
                PI
            } else if c >= 1.0 {
                0.0
            } else {
                c.acos()
            }
        };
        if phi_max <= 0.0 {
            continue;
        }
        let (mut sa, mut sb) = (0.0, 0.0);
        for &(x, w) in phi_rule.iter() {
            let phi = 0.5 * phi_max * (x + 1.0);
            let v_dot_h = k * phi.cos() + mu * c_h;
            let n_dot_l = 2.0 * v_dot_h * c_h - mu;
            if n_dot_l <= 0.0 || v_dot_h <= 0.0 {
                continue;
            }
            let fc = (1.0 - v_dot_h).powi(5);
            let term = w * ggx.visibility(mu, n_dot_l) * n_dot_l * 4.0 * v_dot_h;
            sa += term * (1.0 - fc);
            sb += term * fc;
        }
        // φ ∈ [−φ_max, φ_max] by symmetry: 2 × (φ_max/2) × Σ.
        let scale = w_theta * s_h * d * phi_max;
        a += scale * sa;
        b += scale * sb;
    }
    SplitSumTerms { scale: a, bias: b }
}

/// An N×N split-sum table (see the module docs for the texel layout and the channels).
#[derive(Clone, Debug, PartialEq)]
pub struct DfgTable {
    size: usize,
    variant: DfgVariant,
    /// Row-major, row j = roughness (j + ½)/N, column i = n·v (i + ½)/N.
    values: Vec<[f32; 2]>,
}

/// The side of the table prtkit ships as data ([`DEFAULT_SIZE`]).
pub const SHIPPED_SIZE: usize = DEFAULT_SIZE;

/// A and B of every texel of the [`SHIPPED_SIZE`]² table by the default quadrature, as f64
/// little-endian pairs, row-major: the same for every bake, so computed once
/// (`cargo run --release --example dfg_table -- data/dfg-128.bin`) and checked bit for bit
/// against the quadrature by `the_shipped_table_is_the_quadratures`.
static SHIPPED: &[u8] = include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/dfg-128.bin"));

/// A and B at every texel of an N×N table, row-major, by the quadrature with `order` nodes
/// per θ_h piece (rows in parallel; every texel is computed independently, so the result does
/// not depend on the thread count).
pub fn integrate_table(size: usize, order: usize) -> Result<Vec<SplitSumTerms>, DfgError> {
    check_size(size)?;
    Ok((0..size)
        .into_par_iter()
        .flat_map_iter(|row| {
            let ggx = Ggx::new(DfgTable::texel_coordinate(size, row)).expect("texel centres lie in (0, 1)");
            (0..size).map(move |col| integrate(DfgTable::texel_coordinate(size, col), ggx, order))
        })
        .collect())
}

/// Refuses a table side of 0 or above [`MAX_DFG_SIZE`].
pub fn check_size(size: usize) -> Result<(), DfgError> {
    if size == 0 || size > MAX_DFG_SIZE {
        return Err(DfgError::Size(size));
    }
    Ok(())
}

/// The shipped table's terms, decoded.
fn shipped_terms() -> Vec<SplitSumTerms> {
    let value = |k: usize| f64::from_le_bytes(SHIPPED[8 * k..8 * k + 8].try_into().expect("8 bytes"));
    (0..SHIPPED_SIZE * SHIPPED_SIZE).map(|t| SplitSumTerms { scale: value(2 * t), bias: value(2 * t + 1) }).collect()
}

impl DfgTable {
    /// The table by the default quadrature: the [`SHIPPED_SIZE`]² one from the data it was
    /// computed into, any other size integrated.
    pub fn new(size: usize, variant: DfgVariant) -> Result<Self, DfgError> {
        if size == SHIPPED_SIZE {
            return Ok(Self::from_terms(size, variant, &shipped_terms()));
        }
        Self::with_quadrature_order(size, variant, DEFAULT_ORDER)
    }

    /// The table integrated with `order` Gauss–Legendre nodes per θ_h piece ([`phi_nodes`] in
    /// φ): for convergence studies.
    pub fn with_quadrature_order(size: usize, variant: DfgVariant, order: usize) -> Result<Self, DfgError> {
        Ok(Self::from_terms(size, variant, &integrate_table(size, order)?))
    }

    fn from_terms(size: usize, variant: DfgVariant, terms: &[SplitSumTerms]) -> Self {
        let values = terms.iter().map(|t| t.channels(variant).map(|c| c as f32)).collect();
        DfgTable { size, variant, values }
    }

    /// (k + ½)/N: the n·v of column k and the roughness of row k.
    pub fn texel_coordinate(size: usize, k: usize) -> f64 {
        (k as f64 + 0.5) / size as f64
    }

    /// The side N.
    pub fn size(&self) -> usize {
        self.size
    }

    /// What the two channels hold.
    pub fn variant(&self) -> DfgVariant {
        self.variant
    }

    /// The two channels at (row = roughness index, column = n·v index).
    pub fn get(&self, row: usize, col: usize) -> [f32; 2] {
        self.values[row * self.size + col]
    }

    /// All texels, row-major.
    pub fn values(&self) -> &[[f32; 2]] {
        &self.values
    }

    /// The table as texture data for the KTX2 and DDS writers (`crate::io::texture`): one
    /// N × N level, two interleaved channels (x0, y0, x1, y1, …), row 0 first.
    pub fn as_texture(&self) -> Texture<'_> {
        Texture {
            shape: TextureShape::Texture2d { width: self.size, height: self.size },
            channels: 2,
            levels: vec![self.values.as_flattened()],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn the_microfacet_brdf_white_furnace_is_the_albedo() {
        // E(ω_o) = ∫ ρ cos θ_i dω_i of brdf::models' GGX, by brute force over ω_i (midpoint rule
        // in cos θ_i and φ_i), against the split-sum A + B at F0 = 1 (integrated over the half
        // vector): the same albedo two ways.
        use crate::brdf::models::GgxMicrofacet;
        let n = 800;
        for r in [0.3, 0.6, 1.0] {
            let m = GgxMicrofacet::new(r).unwrap();
            for mu in [1.0, 0.5, 0.2] {
                let wo = DVec3::new((1.0f64 - mu * mu).sqrt(), 0.0, mu);
                let mut e = 0.0;
                for j in 0..n {
                    let theta = ((j as f64 + 0.5) / n as f64).acos();
                    for k in 0..2 * n {
                        let wi = crate::sphere::direction(theta, (k as f64 + 0.5) * PI / n as f64);
                        e += m.eval(wi, wo) * wi.z;
                    }
                }
                e *= 2.0 * PI / (2 * n * n) as f64;
                let want = split_sum_terms(mu, r).unwrap().albedo();
                assert!(e <= 1.0 && (e - want).abs() < 2e-3, "r={r}, μ={mu}: {e} vs {want}");
            }
        }
    }

    /// ∫ f_spec (n·l) dω_l by brute force over a θ_l × φ_l grid of light directions (midpoint
    /// rule, exact cell solid angles): no half vectors, no lobe-adapted pieces.
    fn brute_force(mu: f64, r: f64, n_theta: usize) -> SplitSumTerms {
        let ggx = Ggx::new(r).unwrap();
        let v = DVec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
        let n_phi = 2 * n_theta;
        let (mut a, mut b) = (0.0, 0.0);
        for i in 0..n_theta {
            let (t0, t1) = (FRAC_PI_2 * i as f64 / n_theta as f64, FRAC_PI_2 * (i + 1) as f64 / n_theta as f64);
            let omega = 2.0 * PI / n_phi as f64 * (t0.cos() - t1.cos());
            for j in 0..n_phi {
                let l = crate::sphere::direction(0.5 * (t0 + t1), 2.0 * PI * (j as f64 + 0.5) / n_phi as f64);
                let h = (v + l).normalize();
                let fc = (1.0 - v.dot(h)).powi(5);
                let f = ggx.d(h.z) * ggx.visibility(mu, l.z) * l.z * omega;
                a += f * (1.0 - fc);
                b += f * fc;
            }
        }
        SplitSumTerms { scale: a, bias: b }
    }

    #[test]
    fn normal_incidence_at_roughness_one_is_one_minus_ln_two() {
        // α = 1, v = n: D = 1/π, V = 1/(2(1 + n·l)), v·h = cos(θ_l/2), so
        // A + B = ∫_0^1 x/(1 + x) dx = 1 − ln 2 and A = ∫_0^1 (1 − F_c) x/(1 + x) dx with
        // F_c = (1 − √((1 + x)/2))⁵, here by a 10⁶-point midpoint rule in x.
        let t = split_sum_terms(1.0, 1.0).unwrap();
        assert!((t.albedo() - (1.0 - 2f64.ln())).abs() < 1e-12, "{}", t.albedo());
        let n = 1_000_000;
        let a: f64 = (0..n)
            .map(|i| {
                let x = (i as f64 + 0.5) / n as f64;
                (1.0 - (1.0 - ((1.0 + x) / 2.0).sqrt()).powi(5)) * x / (1.0 + x)
            })
            .sum::<f64>()
            / n as f64;
        assert!((t.scale - a).abs() < 1e-10, "{} vs {a}", t.scale);
    }

    #[test]
    fn matches_brute_force_sphere_integral() {
        for (mu, r) in [(1.0, 1.0), (0.5, 0.5), (0.2, 0.7), (0.9, 0.35), (0.05, 1.0)] {
            let got = split_sum_terms(mu, r).unwrap();
            let want = brute_force(mu, r, 1500);
            assert!(
                (got.scale - want.scale).abs() < 2e-5 && (got.bias - want.bias).abs() < 2e-5,
                "μ={mu} r={r}: {got:?} vs {want:?}"
            );
        }
    }

    #[test]
    fn smooth_limit_is_schlick_at_the_view_angle() {
        // As α → 0 the lobe collapses onto the mirror direction: v·h → n·v, G2 → 1, so
        // A → 1 − (1 − n·v)⁵ and B → (1 − n·v)⁵.
        for mu in [0.3, 0.7, 1.0] {
            let t = split_sum_terms(mu, 0.02).unwrap();
            let fc = (1.0 - mu).powi(5);
            assert!((t.scale - (1.0 - fc)).abs() < 2e-3 && (t.bias - fc).abs() < 2e-3, "μ={mu}: {t:?}");
        }
    }

    #[test]
    fn quadrature_has_converged() {
        // Two resolutions on a 32² grid of texel centres, including the grazing and the
        // smoothest corners, agree far below the 1e-5 the table needs.
        let coarse = DfgTable::with_quadrature_order(32, DfgVariant::ScaleBias, 16).unwrap();
        let fine = DfgTable::with_quadrature_order(32, DfgVariant::ScaleBias, 32).unwrap();
        let mut worst = 0.0f64;
        for (c, f) in coarse.values().iter().zip(fine.values()) {
            worst = worst.max((c[0] - f[0]).abs().max((c[1] - f[1]).abs()) as f64);
        }
        assert!(worst < 1e-5, "{worst}");
        // Extreme texel centres of a 256² table (α ≈ 4e-6, n·v ≈ 0.002) too.
        for (mu, r) in [(0.5 / 256.0, 0.5 / 256.0), (1.0 - 0.5 / 256.0, 0.5 / 256.0), (0.5 / 256.0, 1.0)] {
            let ggx = Ggx::new(r).unwrap();
            let (c, f) = (integrate(mu, ggx, 16), integrate(mu, ggx, 32));
            assert!((c.scale - f.scale).abs() < 1e-5 && (c.bias - f.bias).abs() < 1e-5, "μ={mu} r={r}: {c:?} {f:?}");
        }
    }

    #[test]
    fn energy_is_conserved_everywhere() {
        let table = DfgTable::new(64, DfgVariant::ScaleBias).unwrap();
        for row in 0..64 {
            for col in 0..64 {
                let [a, b] = table.get(row, col);
                assert!(a >= 0.0 && b >= 0.0 && a + b <= 1.0, "({row},{col}): {a} + {b}");
            }
        }
        // Rough grazing lobes lose the most to shadowing: the albedo falls with roughness.
        assert!(table.get(63, 32)[0] + table.get(63, 32)[1] < table.get(0, 32)[0] + table.get(0, 32)[1]);
    }

    #[test]
    fn multiscatter_variant_restores_the_white_furnace() {
        // Filament's channels are (B, A + B); with the energy compensation 1 + F0 (1/y − 1) at
        // F0 = 1, the BRDF's albedo measured by the independent sphere integral becomes 1.
        let table = DfgTable::new(64, DfgVariant::MultiScatter).unwrap();
        for (row, col) in [(40, 20), (63, 5), (20, 60), (63, 63)] {
            let [x, y] = table.get(row, col);
            let (mu, r) = (DfgTable::texel_coordinate(64, col), DfgTable::texel_coordinate(64, row));
            let single = split_sum_terms(mu, r).unwrap();
            assert!((x as f64 - single.bias).abs() < 1e-7 && (y as f64 - single.albedo()).abs() < 1e-7);
            let brute = brute_force(mu, r, 1500).albedo();
            let compensated = brute * (1.0 + (1.0 / y as f64 - 1.0));
            assert!((compensated - 1.0).abs() < 5e-5, "({row},{col}): {compensated}");
            // The shader's mix(x, y, F0) is the single-scattering split sum F0 A + B.
            let f0 = 0.04;
            let mixed = (1.0 - f0) * x as f64 + f0 * y as f64;
            assert!((mixed - (f0 * single.scale + single.bias)).abs() < 1e-7);
        }
    }

    #[test]
    fn layout_and_errors() {
        let t = DfgTable::new(4, DfgVariant::ScaleBias).unwrap();
        assert_eq!(t.values().len(), 16);
        assert_eq!(t.as_texture().levels[0].len(), 32);
        let direct = split_sum_terms(DfgTable::texel_coordinate(4, 1), DfgTable::texel_coordinate(4, 2)).unwrap();
        assert_eq!(t.get(2, 1), [direct.scale as f32, direct.bias as f32]);
        assert_eq!(DfgTable::new(0, DfgVariant::ScaleBias), Err(DfgError::Size(0)));
        assert_eq!(DfgTable::new(MAX_DFG_SIZE + 1, DfgVariant::ScaleBias), Err(DfgError::Size(MAX_DFG_SIZE + 1)));
        assert_eq!(split_sum_terms(0.0, 0.5), Err(DfgError::NDotV(0.0)));
        assert!(split_sum_terms(f64::NAN, 0.5).is_err());
        assert!(matches!(split_sum_terms(0.5, 2.0), Err(DfgError::Roughness(_))));
    }

    /// The shipped data is what the quadrature computes today, bit for bit (regenerate it with
    /// the `dfg_table` example when the quadrature changes).
    #[test]
    fn the_shipped_table_is_the_quadratures() {
        assert_eq!(SHIPPED.len(), SHIPPED_SIZE * SHIPPED_SIZE * 16);
        let computed = integrate_table(SHIPPED_SIZE, DEFAULT_ORDER).unwrap();
        for (k, (a, b)) in shipped_terms().iter().zip(&computed).enumerate() {
            assert!(
                a.scale.to_bits() == b.scale.to_bits() && a.bias.to_bits() == b.bias.to_bits(),
                "texel {k}: shipped {a:?}, quadrature {b:?}"
            );
        }
        for variant in [DfgVariant::ScaleBias, DfgVariant::MultiScatter] {
            let shipped = DfgTable::new(SHIPPED_SIZE, variant).unwrap();
            assert_eq!(shipped, DfgTable::with_quadrature_order(SHIPPED_SIZE, variant, DEFAULT_ORDER).unwrap());
        }
    }
}
