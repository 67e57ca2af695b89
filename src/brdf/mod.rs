//! BRDF models, the MERL measured-BRDF reader and the one spec parser every stage uses.
//!
//! Frame: the local shading frame of DESIGN.md (+Z is the normal, θ from +Z, φ from +X towards
//! +Y); ω_i points towards the light, ω_o towards the viewer, both unit vectors. The spec grammar
//! is documented in `docs/brdf-specs.md`.
//!
//! ```
//! use prtkit::brdf::Brdf;
//! let phong = Brdf::parse("phong:s=30").unwrap();
//! let up = glam::DVec3::Z;
//! // Normal incidence, mirror direction: the peak of the normalized lobe, (s+1)/(2π).
//! assert!((phong.eval(up, up)[0] - 31.0 / (2.0 * std::f64::consts::PI)).abs() < 1e-12);
//! assert!(phong.is_isotropic() && phong.is_radially_symmetric());
//! ```

pub mod ggx;
pub mod halfdiff;
pub mod merl;
pub mod models;
pub mod spec;

pub use merl::MerlBrdf;
pub use spec::{SpecError, ACCEPTED};

use glam::DVec3;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Errors from building a BRDF.
#[derive(Debug, thiserror::Error)]
pub enum BrdfError {
    /// The spec string does not parse.
    #[error(transparent)]
    Spec(#[from] SpecError),
    /// A MERL file is missing, unreadable or not in MERL's format.
    #[error("{path}: invalid MERL BRDF file: {reason}", path = path.display())]
    Merl {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// A BRDF in the local frame: the one vocabulary of models every stage takes (`--brdf`, the
/// `count-terms` manifest, the documents' `brdf` field). A model is one variant here, one
/// branch of the parser ([`spec`]) and one arm in each method below. Cheap to clone (MERL
/// tables are shared).
#[derive(Clone, Debug)]
pub enum Brdf {
    /// Lambertian.
    Lambert(models::Lambert),
    /// Normalized Phong about the mirror direction.
    Phong(models::Phong),
    /// Normalized Blinn-Phong (half-angle).
    BlinnPhong(models::BlinnPhong),
    /// Simplified Torrance-Sparrow (Mahajan et al. 2008, eq. 14).
    TorranceSparrow(models::TorranceSparrow),
    /// Multi-lobe Lafortune.
    Lafortune(models::Lafortune),
    /// Kajiya-Kay (anisotropic, tangent +X).
    KajiyaKay(models::KajiyaKay),
    /// GGX microfacet reflection (Walter et al. 2007; Heitz 2014), no Fresnel.
    Ggx(models::GgxMicrofacet),
    /// The glTF 2.0 metallic-roughness material (GGX with Schlick Fresnel over Lambert).
    Gltf(models::GltfMaterial),
    /// Measured MERL table.
    Merl(Arc<MerlBrdf>),
}

impl Brdf {
    /// Parses a spec (`docs/brdf-specs.md`) and builds the BRDF, reading MERL data.
    pub fn parse(spec: &str) -> Result<Brdf, BrdfError> {
        Self::parse_relative_to(spec, Path::new(""))
    }

    /// [`Brdf::parse`] with a relative MERL path taken relative to `base` (a manifest's
    /// directory).
    pub fn parse_relative_to(spec: &str, base: &Path) -> Result<Brdf, BrdfError> {
        spec::parse(spec, base)
    }

    /// ρ(ω_i, ω_o) per RGB channel; analytic models are grey. Both directions are unit vectors
    /// anywhere on the sphere: analytic models evaluate their formula, MERL its table lookup.
    pub fn eval(&self, wi: DVec3, wo: DVec3) -> [f64; 3] {
        let grey = |v: f64| [v, v, v];
        match self {
            Brdf::Lambert(m) => grey(m.eval()),
            Brdf::Phong(m) => grey(m.eval(wi, wo)),
            Brdf::BlinnPhong(m) => grey(m.eval(wi, wo)),
            Brdf::TorranceSparrow(m) => grey(m.eval(wi, wo)),
            Brdf::Lafortune(m) => grey(m.eval(wi, wo)),
            Brdf::KajiyaKay(m) => grey(m.eval(wi, wo)),
            Brdf::Ggx(m) => grey(m.eval(wi, wo)),
            Brdf::Gltf(m) => m.eval(wi, wo),
            Brdf::Merl(m) => m.eval(wi, wo),
        }
    }

    /// True if ρ is unchanged when both directions rotate about the normal (it depends on
    /// φ_o − φ_i only). Then the sampled BRDF matrix is block-circulant in φ.
    pub fn is_isotropic(&self) -> bool {
        match self {
            Brdf::Lafortune(m) => m.is_isotropic(),
            Brdf::KajiyaKay(_) => false,
            _ => true,
        }
    }

    /// True if ρ is a function of R·ω_i alone, R the mirror of ω_o (Phong, Lambert, mirror
    /// Lafortune lobes): then its in-out SVD on the sphere is its SH expansion (Mahajan et al.
    /// 2008, eq. 9) and [`Brdf::reflection_lobe`] is defined.
    pub fn is_radially_symmetric(&self) -> bool {
        match self {
            Brdf::Lambert(_) | Brdf::Phong(_) => true,
            Brdf::Lafortune(m) => m.is_radially_symmetric(),
            _ => false,
        }
    }

    /// For radially symmetric BRDFs, the lobe f(cos γ) with cos γ = R·ω_i (eq. 7); else `None`.
    pub fn reflection_lobe(&self, cos_gamma: f64) -> Option<f64> {
        match self {
            Brdf::Lambert(m) => Some(m.eval()),
            Brdf::Phong(m) => Some(m.lobe(cos_gamma)),
            Brdf::Lafortune(m) if m.is_radially_symmetric() => Some(m.lobe(cos_gamma)),
            _ => None,
        }
    }

    /// For analytic half-angle models (ρ a function of θ_h alone), the curve ρ(θ_h); else `None`.
    pub fn half_angle_curve(&self, theta_h: f64) -> Option<f64> {
        match self {
            Brdf::BlinnPhong(m) => Some(m.half_angle_curve(theta_h)),
            Brdf::TorranceSparrow(m) => Some(m.half_angle_curve(theta_h)),
            _ => None,
        }
    }

    /// True if the channels can differ (measured data, coloured materials).
    pub fn is_rgb(&self) -> bool {
        matches!(self, Brdf::Merl(_) | Brdf::Gltf(_))
    }

    /// The model name, e.g. `phong`.
    pub fn name(&self) -> &'static str {
        match self {
            Brdf::Lambert(_) => "lambert",
            Brdf::Phong(_) => "phong",
            Brdf::BlinnPhong(_) => "blinn-phong",
            Brdf::TorranceSparrow(_) => "torrance-sparrow",
            Brdf::Lafortune(_) => "lafortune",
            Brdf::KajiyaKay(_) => "kajiya-kay",
            Brdf::Ggx(_) => "ggx",
            Brdf::Gltf(_) => "gltf",
            Brdf::Merl(_) => "merl",
        }
    }

    /// The canonical spec string (parses back to an equal BRDF; see `Display` in [`spec`]).
    pub fn spec(&self) -> String {
        self.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sphere::direction;

    #[test]
    fn isotropic_models_depend_on_the_azimuth_difference_only() {
        for spec in ["phong:s=12", "blinn-phong:s=20", "torrance-sparrow:sigma=0.3", "lafortune:kd=0.2,lobe=-1/1/8"] {
            let b = Brdf::parse(spec).unwrap();
            assert!(b.is_isotropic());
            let a = b.eval(direction(0.4, 0.3), direction(0.9, 2.0))[0];
            let r = b.eval(direction(0.4, 1.3), direction(0.9, 3.0))[0];
            assert!((a - r).abs() < 1e-12 * a.abs().max(1.0), "{spec}");
        }
        let kk = Brdf::parse("kajiya-kay:s=8").unwrap();
        assert!(!kk.is_isotropic());
        let a = kk.eval(direction(0.7, 0.3), direction(0.9, 2.0))[0];
        let r = kk.eval(direction(0.7, 1.3), direction(0.9, 3.0))[0];
        assert!((a - r).abs() > 1e-3);
    }

    #[test]
    fn reflection_lobe_reproduces_eval() {
        let b = Brdf::parse("phong:s=9").unwrap();
        let (wi, wo) = (direction(0.3, 0.1), direction(0.5, 3.0));
        let r = models::reflect_about_normal(wo);
        assert_eq!(b.reflection_lobe(r.dot(wi)), Some(b.eval(wi, wo)[0]));
        assert_eq!(Brdf::parse("torrance-sparrow:sigma=0.2").unwrap().reflection_lobe(0.5), None);
        assert_eq!(b.spec(), "phong:s=9");
        assert_eq!(b.name(), "phong");
    }
}
