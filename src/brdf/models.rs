//! Analytic BRDF models in the local shading frame (+Z is the normal, ω_i points towards the
//! light, ω_o towards the viewer). Every model is grey (the same value in R, G and B) and is
//! evaluated as its formula on the whole sphere of directions: restricting to the visible
//! hemispheres is the caller's choice (`factor --domain hemisphere`), because the paper's
//! analysis (Mahajan et al. 2008, §3.1–3.2) deliberately extends Phong to the full sphere.

use crate::brdf::ggx::{self, Ggx, GgxError};
use glam::DVec3;
use std::f64::consts::PI;

/// Mirror of ω about the normal +Z: R = (−x, −y, z). With ω = ω_o this is the paper's reflected
/// view direction R, whose spherical angles are (θ_o, φ_o ± π) (Mahajan et al. 2008, eq. 8).
#[inline]
pub fn reflect_about_normal(w: DVec3) -> DVec3 {
    DVec3::new(-w.x, -w.y, w.z)
}

/// Lambertian: ρ = albedo / π.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    /// Diffuse albedo in [0, 1].
    pub albedo: f64,
}

impl Lambert {
    /// ρ (constant).
    pub fn eval(&self) -> f64 {
        self.albedo / PI
    }
}

/// Normalized Phong: ρ = (s+1)/(2π) · max(0, R·ω_i)^s, R the mirror of ω_o (Mahajan et al.
/// 2008, eq. 5). Radially symmetric about R, so it is a function of cos γ = R·L alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    /// Exponent s > 0.
    pub exponent: f64,
}

impl Phong {
    /// The lobe as a function of cos γ = R·L (eq. 5, clamped at 0).
    #[inline]
    pub fn lobe(&self, cos_gamma: f64) -> f64 {
        if cos_gamma <= 0.0 {
            0.0
        } else {
            (self.exponent + 1.0) / (2.0 * PI) * power(cos_gamma.min(1.0), self.exponent)
        }
    }

    /// ρ(ω_i, ω_o).
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.lobe(reflect_about_normal(wo).dot(wi))
    }
}

/// x^s for x in [0, 1]: by repeated multiplication when s is an integer (an exact product
/// rounded at most 2·log₂ s times; 1.5–2 times faster than `powf` for s = 8–512, measured over
/// 10⁵ values), else `powf`.
#[inline]
pub fn power(x: f64, s: f64) -> f64 {
    if s.fract() == 0.0 && s.abs() <= i32::MAX as f64 {
        x.powi(s as i32)
    } else {
        x.powf(s)
    }
}

/// Blinn-Phong: ρ = (s+2)/(8π) · max(0, N·H)^s with H = normalize(ω_i + ω_o). The factor
/// (s+2)/(2π) normalizes the distribution cos^s θ_h over the hemisphere of half vectors
/// (∫ D(h) (n·h) dω_h = 1), and 1/4 is the half-vector Jacobian at normal incidence; Fresnel
/// and shadowing are omitted, as in the simplified half-angle models of Mahajan et al. §4.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlinnPhong {
    /// Exponent s > 0.
    pub exponent: f64,
}

impl BlinnPhong {
    /// The half-angle curve as a function of θ_h.
    pub fn half_angle_curve(&self, theta_h: f64) -> f64 {
        let c = theta_h.cos();
        if c <= 0.0 {
            0.0
        } else {
            (self.exponent + 2.0) / (8.0 * PI) * c.powf(self.exponent)
        }
    }

    /// ρ(ω_i, ω_o).
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.half_angle_curve(theta_h(wi, wo))
    }
}

/// The simplified Torrance-Sparrow model of Mahajan et al. 2008, eq. 14:
/// ρ = exp(−(acos(N·H)/σ)²) / (4πσ²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TorranceSparrow {
    /// Roughness σ > 0 (radians of θ_h).
    pub sigma: f64,
}

impl TorranceSparrow {
    /// The half-angle curve as a function of θ_h (eq. 14).
    pub fn half_angle_curve(&self, theta_h: f64) -> f64 {
        let x = theta_h / self.sigma;
        (-x * x).exp() / (4.0 * PI * self.sigma * self.sigma)
    }

    /// ρ(ω_i, ω_o).
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.half_angle_curve(theta_h(wi, wo))
    }
}

/// θ_h = acos(N·H) with H = normalize(ω_i + ω_o) (+Z when the directions are opposite).
#[inline]
pub fn theta_h(wi: DVec3, wo: DVec3) -> f64 {
    let s = wi + wo;
    let len = s.length();
    if len > 0.0 {
        (s.z / len).clamp(-1.0, 1.0).acos()
    } else {
        0.0
    }
}

/// One generalized cosine lobe of the Lafortune model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LafortuneLobe {
    /// C_x.
    pub cx: f64,
    /// C_y.
    pub cy: f64,
    /// C_z.
    pub cz: f64,
    /// Exponent n > 0.
    pub exponent: f64,
}

/// Multi-lobe Lafortune (Lafortune, Foo, Torrance & Greenberg 1997):
/// ρ = kd/π + Σ_j max(0, C_x,j ω_i,x ω_o,x + C_y,j ω_i,y ω_o,y + C_z,j ω_i,z ω_o,z)^n_j.
/// C_x = C_y = −C_z = −c (c > 0) gives (c R·ω_i)^n, a Phong lobe about the mirror direction R.
#[derive(Clone, Debug, PartialEq)]
pub struct Lafortune {
    /// Diffuse albedo.
    pub kd: f64,
    /// Specular lobes (at least one).
    pub lobes: Vec<LafortuneLobe>,
}

impl Lafortune {
    /// ρ(ω_i, ω_o).
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> f64 {
        let mut sum = self.kd / PI;
        for lobe in &self.lobes {
            let d = lobe.cx * wi.x * wo.x + lobe.cy * wi.y * wo.y + lobe.cz * wi.z * wo.z;
            if d > 0.0 {
                sum += d.powf(lobe.exponent);
            }
        }
        sum
    }

    /// Isotropic (invariant under rotation about the normal) iff C_x = C_y in every lobe.
    pub fn is_isotropic(&self) -> bool {
        self.lobes.iter().all(|l| l.cx == l.cy)
    }

    /// Radially symmetric about the mirror direction R iff every lobe has C_x = C_y = −C_z < 0:
    /// then ρ = kd/π + Σ_j max(0, C_z,j R·ω_i)^n_j (the diffuse term is a constant).
    pub fn is_radially_symmetric(&self) -> bool {
        self.lobes.iter().all(|l| l.cx == l.cy && l.cx == -l.cz && l.cz > 0.0)
    }

    /// The lobe as a function of cos γ = R·L when [`Self::is_radially_symmetric`].
    pub fn lobe(&self, cos_gamma: f64) -> f64 {
        let mut sum = self.kd / PI;
        for lobe in &self.lobes {
            let d = lobe.cz * cos_gamma;
            if d > 0.0 {
                sum += d.powf(lobe.exponent);
            }
        }
        sum
    }
}

/// Kajiya-Kay hair/fibre specular (Kajiya & Kay 1989) with the fibre tangent T = +X (the model
/// is anisotropic): light arriving along −ω_i is reflected into the cone of directions that make
/// the same angle with T, and the lobe is a power of the cosine of the angle between ω_o and the
/// nearest cone direction:
/// cos = sin(T,ω_i) sin(T,ω_o) − (T·ω_i)(T·ω_o),  ρ = (s+1)/(2π) · max(0, cos)^s.
/// The factor (s+1)/(2π) mirrors normalized Phong; it is a scale, not an energy normalization.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KajiyaKay {
    /// Exponent s > 0.
    pub exponent: f64,
}

impl KajiyaKay {
    /// ρ(ω_i, ω_o).
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> f64 {
        let (ti, to) = (wi.x, wo.x);
        let si = (1.0 - ti * ti).max(0.0).sqrt();
        let so = (1.0 - to * to).max(0.0).sqrt();
        let c = si * so - ti * to;
        if c <= 0.0 {
            0.0
        } else {
            (self.exponent + 1.0) / (2.0 * PI) * c.min(1.0).powf(self.exponent)
        }
    }
}

/// The GGX microfacet reflection model (Walter, Marschner, Li & Torrance 2007) with the
/// height-correlated Smith masking-shadowing (Heitz 2014, eq. 99) and no Fresnel term (F = 1):
///
///   ρ = D(h) G₂(ω_i, ω_o) / (4 (n·ω_i)(n·ω_o)),  h = normalize(ω_i + ω_o),
///
/// D the Trowbridge–Reitz distribution of width α = r² for the perceptual roughness r (Karis
/// 2013). D, Λ and the visibility V = G₂/(4 (n·ω_i)(n·ω_o)) are those of [`super::ggx::Ggx`],
/// the one GGX the crate has. Unlike the other models, ρ is zero unless both directions are in
/// the upper hemisphere: G₂ carries the Heaviside factors χ⁺(n·ω) of Heitz's eq. 99, so the
/// formula has no meaning below the surface. With F = 1 the model is the specular layer a glTF
/// engine scales by its Fresnel term; its directional albedo is at most 1 and falls below 1 at
/// grazing view as single scattering loses energy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GgxMicrofacet {
    distribution: Ggx,
}

impl GgxMicrofacet {
    /// GGX of perceptual roughness r ∈ [0, 1] (α = r²).
    pub fn new(roughness: f64) -> Result<Self, GgxError> {
        Ok(GgxMicrofacet { distribution: Ggx::new(roughness)? })
    }

    /// The perceptual roughness r.
    pub fn roughness(&self) -> f64 {
        self.distribution.perceptual_roughness()
    }

    /// The microfacet distribution and its Smith terms.
    pub fn distribution(&self) -> Ggx {
        self.distribution
    }

    /// The peak at normal incidence, ρ(n, n) = D(1) V(1, 1) = 1/(4πα²): the value the spec
    /// parser holds against [`crate::limits::MAX_BRDF_PEAK`] (the lobe's height where it is
    /// narrowest; towards grazing ρ grows like 1/(n·ω) but ρ (n·ω_i) stays bounded).
    pub fn normal_peak(roughness: f64) -> f64 {
        let a = ggx::alpha(roughness);
        1.0 / (4.0 * PI * a * a)
    }

    /// ρ(ω_i, ω_o).
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> f64 {
        let (cos_i, cos_o) = (wi.z, wo.z);
        if cos_i <= 0.0 || cos_o <= 0.0 {
            return 0.0;
        }
        // D from cos² θ_h and sin² θ_h of the unnormalized half vector: no cancellation in
        // 1 − cos² θ_h at the peak, which a narrow lobe (α² below the rounding of n·h) needs.
        let h = wi + wo;
        let len2 = h.length_squared();
        let d = self.distribution.d_half_angle(h.z * h.z / len2, (h.x * h.x + h.y * h.y) / len2);
        d * self.distribution.visibility(cos_o, cos_i)
    }
}

/// The glTF 2.0 metallic-roughness material (glTF 2.0 specification, Appendix B "BRDF
/// Implementation"): a GGX specular layer over a Lambertian base for dielectrics (F0 = 0.04, IOR
/// 1.5), the same layer tinted by the base colour for metals, mixed by the metalness:
///
///   f = f_spec · F(v·h) + (1 − m)(1 − F_d(v·h)) · c/π,
///   F = F0 + (1 − F0)(1 − v·h)⁵ with F0 = mix(0.04, c, m),   F_d = 0.04 + 0.96 (1 − v·h)⁵,
///
/// f_spec the [`GgxMicrofacet`] D·V of roughness r (α = r²). Expanding the spec's
/// mix(fresnel_mix(diffuse, specular), conductor_fresnel(specular), m) gives exactly this. It is
/// what `ibl`'s split sum approximates, and `render --shading reference` integrates it as the
/// ground truth of `render --shading ibl`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfMaterial {
    /// Base colour c (linear RGB, each in [0, 1]).
    pub base: [f64; 3],
    /// Metalness m in [0, 1].
    pub metalness: f64,
    /// The specular layer.
    pub specular: GgxMicrofacet,
}

impl GltfMaterial {
    /// F0 of the dielectric (IOR 1.5): ((1 − 1.5)/(1 + 1.5))².
    pub const DIELECTRIC_F0: f64 = 0.04;

    /// F0 per channel: mix(0.04, c, m).
    pub fn f0(&self) -> [f64; 3] {
        self.base.map(|c| Self::DIELECTRIC_F0 + self.metalness * (c - Self::DIELECTRIC_F0))
    }

    /// The diffuse colour (1 − m) c.
    pub fn diffuse_colour(&self) -> [f64; 3] {
        self.base.map(|c| (1.0 - self.metalness) * c)
    }

    /// ρ(ω_i, ω_o) per channel; zero unless both directions are above the surface.
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> [f64; 3] {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return [0.0; 3];
        }
        let spec = self.specular.eval(wi, wo);
        let v_dot_h = wo.dot((wi + wo).normalize()).clamp(0.0, 1.0);
        let schlick = (1.0 - v_dot_h).powi(5);
        let diffuse_weight = (1.0 - (Self::DIELECTRIC_F0 + (1.0 - Self::DIELECTRIC_F0) * schlick)) / PI;
        let (f0, kd) = (self.f0(), self.diffuse_colour());
        [0, 1, 2].map(|c| spec * (f0[c] + (1.0 - f0[c]) * schlick) + kd[c] * diffuse_weight)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sphere::direction;

    /// ∫ over the upper hemisphere of f(ω) dω by a midpoint rule in (cos θ, φ).
    fn hemisphere_integral(f: impl Fn(DVec3) -> f64, n: usize) -> f64 {
        let mut sum = 0.0;
        for j in 0..n {
            let c = (j as f64 + 0.5) / n as f64;
            let theta = c.acos();
            for k in 0..2 * n {
                let phi = (k as f64 + 0.5) * PI / n as f64;
                sum += f(direction(theta, phi));
            }
        }
        sum * (2.0 * PI) / (2 * n * n) as f64
    }

    #[test]
    fn normalized_phong_lobe_integrates_to_one_at_normal_incidence() {
        // ∫ (s+1)/(2π) (R·L)^s dL over the hemisphere around R = +Z is exactly 1.
        for s in [1.0, 10.0, 30.0] {
            let p = Phong { exponent: s };
            let got = hemisphere_integral(|l| p.eval(l, DVec3::Z), 400);
            assert!((got - 1.0).abs() < 2e-3, "s={s}: {got}");
        }
    }

    #[test]
    fn phong_is_a_function_of_the_mirror_direction() {
        let p = Phong { exponent: 7.0 };
        let wo = direction(0.6, 1.3);
        let r = direction(0.6, 1.3 + PI);
        let wi = direction(0.9, 4.0);
        assert!((p.eval(wi, wo) - 8.0 / (2.0 * PI) * r.dot(wi).powf(7.0)).abs() < 1e-14);
    }

    #[test]
    fn blinn_phong_distribution_is_normalized() {
        // (s+2)/(2π) ∫ cos^s θ_h cos θ_h dω_h = 1: the 4·ρ curve times cos θ_h integrates to 1.
        let b = BlinnPhong { exponent: 20.0 };
        let got = hemisphere_integral(|h| 4.0 * b.half_angle_curve(h.z.acos()) * h.z, 400);
        assert!((got - 1.0).abs() < 2e-3, "{got}");
    }

    #[test]
    fn torrance_sparrow_matches_eq_14() {
        let t = TorranceSparrow { sigma: 0.2 };
        let wi = direction(0.7, 0.0);
        let wo = direction(0.6, 2.5);
        let th = (wi + wo).normalize().z.acos();
        let want = (-(th / 0.2f64).powi(2)).exp() / (4.0 * PI * 0.04);
        assert!((t.eval(wi, wo) - want).abs() < 1e-14);
    }

    const R_DOT_L: f64 = 0.8;

    #[test]
    fn lafortune_with_mirror_lobe_is_phong() {
        // C = diag(1, 1, −1) is the anti-mirror: (C ω_o)·ω_i = −R·ω_i, zero on the specular peak.
        let l = Lafortune { kd: 0.0, lobes: vec![LafortuneLobe { cx: 1.0, cy: 1.0, cz: -1.0, exponent: 12.0 }] };
        // C = diag(−1, −1, 1) is the classic mirror lobe: (C ω_o)·ω_i = R·ω_i.
        let l2 = Lafortune { kd: 0.0, lobes: vec![LafortuneLobe { cx: -1.0, cy: -1.0, cz: 1.0, exponent: 12.0 }] };
        let p = Phong { exponent: 12.0 };
        let (wi, wo) = (direction(0.4, 0.3), direction(0.5, 3.3));
        let phong_unnormalized = p.eval(wi, wo) * 2.0 * PI / 13.0;
        assert!((l2.eval(wi, wo) - phong_unnormalized).abs() < 1e-14);
        assert_eq!(l.eval(wi, wo), 0.0);
        assert!(l2.is_isotropic() && l2.is_radially_symmetric() && !l.is_radially_symmetric());
        assert!((l2.lobe(R_DOT_L) - R_DOT_L.powf(12.0)).abs() < 1e-15);
    }

    #[test]
    fn kajiya_kay_peaks_on_the_reflection_cone() {
        let k = KajiyaKay { exponent: 32.0 };
        // ω_i at 40° from T = +X; the cone contains ω_o with T·ω_o = −T·ω_i.
        let a = 40f64.to_radians();
        let wi = DVec3::new(a.cos(), a.sin(), 0.0);
        let on_cone = DVec3::new(-a.cos(), 0.0, a.sin());
        let off_cone = DVec3::new(a.cos(), 0.0, a.sin());
        assert!((k.eval(wi, on_cone) - 33.0 / (2.0 * PI)).abs() < 1e-12);
        assert!(k.eval(wi, off_cone) < 1e-6);
    }

    /// GGX written out independently of `brdf::ggx` (Walter et al. 2007, eq. 33; Heitz 2014,
    /// eqs. 72 and 99): D(h) G₂ / (4 cos θ_i cos θ_o).
    fn ggx_by_hand(alpha: f64, wi: DVec3, wo: DVec3) -> f64 {
        let a2 = alpha * alpha;
        let h = (wi + wo).normalize();
        let d = a2 / (PI * (h.z * h.z * (a2 - 1.0) + 1.0).powi(2));
        let lambda = |c: f64| 0.5 * (-1.0 + (1.0 + a2 * (1.0 - c * c) / (c * c)).sqrt());
        let g2 = 1.0 / (1.0 + lambda(wi.z) + lambda(wo.z));
        d * g2 / (4.0 * wi.z * wo.z)
    }

    #[test]
    fn ggx_is_the_microfacet_formula_and_reciprocal() {
        for r in [0.1, 0.5, 1.0] {
            let m = GgxMicrofacet::new(r).unwrap();
            for (wi, wo) in [
                (direction(0.3, 0.2), direction(0.5, 2.9)),
                (direction(1.2, 1.0), direction(0.1, 4.0)),
                (direction(1.5, 0.0), direction(1.4, 3.0)),
            ] {
                let want = ggx_by_hand(r * r, wi, wo);
                assert!((m.eval(wi, wo) - want).abs() < 1e-12 * want, "r={r}: {} vs {want}", m.eval(wi, wo));
                assert!((m.eval(wi, wo) - m.eval(wo, wi)).abs() < 1e-14 * want, "reciprocity at r={r}");
            }
            // Below the surface the Heaviside factors of G₂ make ρ zero.
            assert_eq!(m.eval(direction(1.7, 0.0), direction(0.3, 3.0)), 0.0);
            assert_eq!(m.eval(direction(0.3, 0.0), direction(2.0, 3.0)), 0.0);
            // The normal-incidence peak the parser checks: D(1)/4 = 1/(4πα²).
            assert!((m.eval(DVec3::Z, DVec3::Z) - GgxMicrofacet::normal_peak(r)).abs() < 1e-12 / (r * r * r * r));
        }
    }

    #[test]
    fn ggx_distribution_is_normalized_and_masking_is_at_most_one() {
        // ∫ D(h) (n·h) dω_h = 2π ∫ D(θ_h) cos θ_h sin θ_h dθ_h = 1 by the midpoint rule in θ_h
        // (independent of the lobe-adapted Gauss–Legendre rule brdf::ggx tests it with).
        for r in [0.1, 0.3, 0.6, 1.0] {
            let g = GgxMicrofacet::new(r).unwrap().distribution();
            let n = 200_000;
            let dt = PI / 2.0 / n as f64;
            let got: f64 = (0..n)
                .map(|k| {
                    let t = (k as f64 + 0.5) * dt;
                    2.0 * PI * g.d(t.cos()) * t.cos() * t.sin() * dt
                })
                .sum();
            assert!((got - 1.0).abs() < 1e-6, "r={r}: {got}");
            // G₂ ∈ (0, 1], 1 exactly at normal incidence and falling towards grazing.
            assert_eq!(g.smith_g2(1.0, 1.0), 1.0);
            let mut last = 1.0;
            for k in 1..=50 {
                let mu = 1.0 - k as f64 / 51.0;
                let g2 = g.smith_g2(mu, 0.8);
                assert!(g2 > 0.0 && g2 <= 1.0 && g2 <= last, "r={r}, μ={mu}: {g2}");
                last = g2;
            }
        }
    }

    #[test]
    fn ggx_single_scattering_loses_energy_on_rough_surfaces() {
        // (That this BRDF's white furnace equals the split-sum albedo of ibl::dfg is tested
        // there, above this module in the layers.)
        // Single scattering loses energy on rough surfaces, little on smooth ones at normal view.
        // At r = 1, D = 1/π and Λ(θ) = (1/cos θ − 1)/2, so E(n) = ∫₀¹ μ/(1 + μ) dμ = 1 − ln 2.
        let e = |r: f64| hemisphere_integral(|wi| GgxMicrofacet::new(r).unwrap().eval(wi, DVec3::Z) * wi.z, 800);
        assert!(e(0.3) > 0.98, "{}", e(0.3));
        assert!((e(1.0) - (1.0 - 2f64.ln())).abs() < 1e-5, "{}", e(1.0));
    }
}
