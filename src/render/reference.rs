//! Ground truth by direct integration over every environment texel (exact solid angles):
//!
//!   B(x, ω_o) = Σ_texels L(ω) ρ(ω, ω_o) max(n·ω, 0) V(x, ω) ΔΩ          (`Integrand::BrdfCosine`)
//!
//! the rendering equation for distant lighting, no approximation but the texel quadrature, or
//! the quantity the prefilter represents, Σ L ρ̂ ΔΩ (`Integrand::Prefilter`): for radially
//! symmetric BRDFs R&H 2002 use ρ̂ = the lobe about its centre over the whole sphere (Phong
//! without n·ω, §6.3), which the SHRM must then be compared against.

use super::{Hit, Scene, Shade};
use crate::brdf::Brdf;
use crate::envmap::EnvMap;
use crate::prefilter::model::{Centre, Model, ModelError};
use glam::DVec3;

/// What is integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Integrand {
    /// ρ(ω_i, ω_o) max(n·ω_i, 0) with visibility: the rendering equation.
    BrdfCosine,
    /// ρ̂ as `prefilter` defines it (its reparameterized lobe; no visibility).
    Prefilter,
}

/// The reference shader.
pub struct Reference<'a> {
    texels: Vec<(DVec3, f64, [f64; 3])>,
    brdf: Brdf,
    model: Option<Model>,
    integrand: Integrand,
    scene: &'a Scene,
}

impl<'a> Reference<'a> {
    /// Gathers the environment's texels (direction, solid angle, radiance); zero texels are
    /// skipped, they add nothing.
    pub fn new(env: &EnvMap, brdf: Brdf, integrand: Integrand, scene: &'a Scene) -> Result<Self, ModelError> {
        let mut texels = Vec::with_capacity(env.texel_count());
        env.for_each_texel(|t| {
            if t.rgb.iter().any(|&v| v != 0.0) {
                texels.push((t.dir, t.solid_angle, t.rgb.map(|v| v as f64)));
            }
        });
        Self::from_texels(texels, brdf, integrand, scene)
    }

    /// The same sum over given texels (direction, solid angle, radiance): the bright sources a
    /// factored render shades exactly.
    pub fn from_texels(
        texels: Vec<(DVec3, f64, [f64; 3])>,
        brdf: Brdf,
        integrand: Integrand,
        scene: &'a Scene,
    ) -> Result<Self, ModelError> {
        let model = match integrand {
            Integrand::Prefilter => Some(Model::new(brdf.clone(), true)?),
            Integrand::BrdfCosine => None,
        };
        Ok(Reference { texels, brdf, model, integrand, scene })
    }

    /// The environment turned by `rotation`: L'(ω) = L(R⁻¹ω), each texel moved to R ω.
    pub fn turned(mut self, rotation: glam::DMat3) -> Self {
        for t in &mut self.texels {
            t.0 = rotation * t.0;
        }
        self
    }
}

impl Shade for Reference<'_> {
    fn shade(&self, hit: &Hit, wo: DVec3) -> [f64; 3] {
        let n = hit.n;
        let mut acc = [0.0f64; 3];
        match (self.integrand, &self.model) {
            (Integrand::Prefilter, Some(model)) => {
                let r = super::reflect(wo, n);
                let prepared = model.prepare_view(r, wo);
                for &(dir, sa, rgb) in &self.texels {
                    let w = match model.centre() {
                        Some(Centre::Reflection) => model.lobe(r.dot(dir)),
                        Some(Centre::Normal) => model.lobe(n.dot(dir)),
                        None => match &prepared {
                            Some(p) => model.rho_hat_prepared(p, dir),
                            None => [0.0; 3],
                        },
                    };
                    for c in 0..3 {
                        acc[c] += rgb[c] * w[c] * sa;
                    }
                }
            }
            _ => {
                let (t, b) = n.any_orthonormal_pair();
                let wo_l = DVec3::new(wo.dot(t), wo.dot(b), wo.dot(n));
                for &(dir, sa, rgb) in &self.texels {
                    let cos = n.dot(dir);
                    if cos <= 0.0 {
                        continue;
                    }
                    let f = self.brdf.eval(DVec3::new(dir.dot(t), dir.dot(b), cos), wo_l);
                    if f.iter().all(|&v| v == 0.0) || self.scene.occluded(hit.p, n, dir) {
                        continue;
                    }
                    for c in 0..3 {
                        acc[c] += rgb[c] * f[c] * cos * sa;
                    }
                }
            }
        }
        acc
    }
}
