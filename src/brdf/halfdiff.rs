//! Rusinkiewicz's half/difference-angle parameterization (Rusinkiewicz 1998), in the exact form
//! MERL's reader uses (see `docs/brdf-specs.md` and `../shared/testdata/merl/SOURCES.md`).
//!
//! h = normalize(ω_i + ω_o), θ_h = acos h_z, φ_h = atan2(h_y, h_x);
//! d = R_binormal(−θ_h) · R_normal(−φ_h) · ω_i, θ_d = acos d_z, φ_d = atan2(d_y, d_x),
//! with normal = +Z, binormal = +Y and right-handed Rodrigues rotations.

use glam::DVec3;

/// Half and difference angles of a pair of directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfDiff {
    /// Angle between the half vector and the normal, in [0, π].
    pub theta_h: f64,
    /// Azimuth of the half vector (ignored by isotropic BRDFs).
    pub phi_h: f64,
    /// Angle between ω_i and the half vector, in [0, π/2] for non-opposite directions.
    pub theta_d: f64,
    /// Azimuth of ω_i about the half vector, in (−π, π].
    pub phi_d: f64,
}

/// Rotates `v` by `angle` about the unit `axis` (right-handed Rodrigues formula):
/// v cos a + k (k·v)(1 − cos a) + (k × v) sin a.
#[inline]
pub fn rotate_about(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    v * c + axis * (axis.dot(v) * (1.0 - c)) + axis.cross(v) * s
}

/// Half/difference angles of (ω_i, ω_o), both unit vectors in the local frame (+Z normal).
/// For exactly opposite directions the half vector is undefined; +Z is used.
pub fn from_directions(wi: DVec3, wo: DVec3) -> HalfDiff {
    let sum = wi + wo;
    let h = if sum.length_squared() > 0.0 { sum.normalize() } else { DVec3::Z };
    let theta_h = h.z.clamp(-1.0, 1.0).acos();
    let phi_h = h.y.atan2(h.x);
    let tmp = rotate_about(wi, DVec3::Z, -phi_h);
    let diff = rotate_about(tmp, DVec3::Y, -theta_h);
    let theta_d = diff.z.clamp(-1.0, 1.0).acos();
    let phi_d = diff.y.atan2(diff.x);
    HalfDiff { theta_h, phi_h, theta_d, phi_d }
}

/// The inverse map: (ω_i, ω_o) from half/difference angles. ω_o is the mirror of ω_i about h.
pub fn to_directions(hd: &HalfDiff) -> (DVec3, DVec3) {
    let d = crate::sphere::direction(hd.theta_d, hd.phi_d);
    let wi = rotate_about(rotate_about(d, DVec3::Y, hd.theta_h), DVec3::Z, hd.phi_h);
    let h = crate::sphere::direction(hd.theta_h, hd.phi_h);
    let wo = h * (2.0 * h.dot(wi)) - wi;
    (wi, wo)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_through_half_diff() {
        for &(th, ph, td, pd) in
            &[(0.3, 0.2, 0.5, 1.0), (1.1, -2.0, 0.2, -2.5), (0.05, 1.0, 1.3, 0.3), (0.7, 3.0, 0.9, -0.1)]
        {
            let hd = HalfDiff { theta_h: th, phi_h: ph, theta_d: td, phi_d: pd };
            let (wi, wo) = to_directions(&hd);
            assert!((wi.length() - 1.0).abs() < 1e-12 && (wo.length() - 1.0).abs() < 1e-12);
            let back = from_directions(wi, wo);
            assert!((back.theta_h - th).abs() < 1e-12, "{back:?}");
            assert!((back.phi_h - ph).abs() < 1e-12, "{back:?}");
            assert!((back.theta_d - td).abs() < 1e-12, "{back:?}");
            assert!((back.phi_d - pd).abs() < 1e-12, "{back:?}");
        }
    }

    #[test]
    fn theta_d_is_half_the_angle_between_directions() {
        let wi = DVec3::new(0.3, -0.2, 0.9).normalize();
        let wo = DVec3::new(-0.5, 0.4, 0.6).normalize();
        let hd = from_directions(wi, wo);
        assert!((2.0 * hd.theta_d - wi.dot(wo).acos()).abs() < 1e-12);
        assert!(((wi + wo).normalize().z.acos() - hd.theta_h).abs() < 1e-12);
    }
}
