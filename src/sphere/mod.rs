//! The sphere's vocabulary, which knows nothing of rendering (pbrt's `util/` is the model):
//! directions and their spherical angles in the prtkit frame, the lat-long grid with its texels,
//! solid angles and bilinear taps.
//!
//! Frame (DESIGN.md, `docs/conventions.md`): right-handed, +Z up, θ measured from +Z, φ from +X
//! towards +Y, φ ∈ [0, 2π). Every module that turns a direction into angles or back, or a
//! lat-long texel into a direction, calls these functions: the φ wrap and the half-texel offset
//! are written once.

pub mod latlong;

pub use latlong::LatLong;

use glam::{DMat3, DVec3};
use std::f64::consts::TAU;

/// Unit direction of spherical angles (θ from +Z, φ from +X towards +Y).
#[inline]
pub fn direction(theta: f64, phi: f64) -> DVec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    DVec3::new(st * cp, st * sp, ct)
}

/// θ ∈ [0, π] of a unit direction.
#[inline]
pub fn theta(d: DVec3) -> f64 {
    d.z.clamp(-1.0, 1.0).acos()
}

/// φ ∈ [0, 2π) of a direction (any length; 0 on the poles).
#[inline]
pub fn phi(d: DVec3) -> f64 {
    let p = d.y.atan2(d.x);
    if p < 0.0 {
        // atan2 is in (−π, π]; p + 2π can round up to exactly 2π for tiny negative p.
        let wrapped = p + TAU;
        if wrapped >= TAU {
            0.0
        } else {
            wrapped
        }
    } else {
        p
    }
}

/// (θ, φ) of a unit direction.
#[inline]
pub fn angles(d: DVec3) -> (f64, f64) {
    (theta(d), phi(d))
}

/// The frame R_z(φ)·R_y(θ) of a unit direction's spherical angles: its third column is `d`,
/// its first the direction of increasing θ. Smooth away from the poles. Ramamoorthi & Hanrahan
/// 2002 (§3) use this frame R_{α,β} for reflection vectors; normals use it as their shading frame.
#[inline]
pub fn frame_of(d: DVec3) -> DMat3 {
    let (theta, phi) = angles(d);
    frame(theta, phi)
}

/// R_z(φ)·R_y(θ).
#[inline]
pub fn frame(theta: f64, phi: f64) -> DMat3 {
    DMat3::from_rotation_z(phi) * DMat3::from_rotation_y(theta)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn angles_invert_direction_everywhere_and_phi_wraps_into_its_range() {
        for i in 0..=20 {
            for j in 0..40 {
                let (t, p) = (PI * i as f64 / 20.0, TAU * (j as f64 + 0.25) / 40.0);
                let d = direction(t, p);
                assert!((d.length() - 1.0).abs() < 1e-14);
                assert!((theta(d) - t).abs() < 1e-7);
                if i != 0 && i != 20 {
                    assert!((phi(d) - p).abs() < 1e-12, "{t} {p}: {}", phi(d));
                }
                assert!((0.0..TAU).contains(&phi(d)));
            }
        }
        // Just below the +X axis on the −Y side: φ is just under 2π, never 2π itself.
        assert!(phi(DVec3::new(1.0, -1e-300, 0.0)) < TAU);
        assert_eq!(phi(DVec3::Z), 0.0);
    }

    #[test]
    fn frame_carries_z_to_the_direction() {
        let d = direction(1.1, 4.0);
        let r = frame_of(d);
        assert!((r * DVec3::Z - d).length() < 1e-14);
        assert!((r.determinant() - 1.0).abs() < 1e-14);
        // The first column is ∂d/∂θ.
        let dt = (direction(1.1 + 1e-6, 4.0) - direction(1.1 - 1e-6, 4.0)) / 2e-6;
        assert!((r * DVec3::X - dt).length() < 1e-8);
    }
}
