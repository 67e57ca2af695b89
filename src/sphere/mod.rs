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

/// atan2(y, x) in f32 without a branch on the data, so that a loop over lanes of it compiles to
/// SIMD (the batched lat-long lookups, [`LatLong::taps_lanes`]): octant reduction to a ∈ [0, 1],
/// then Cephes' `atanf` (a second reduction above tan(π/8), a degree-9 odd polynomial). Within
/// 3·10⁻⁷ rad (1.25 f32 ulps of π) of the f64 atan2 (`atan2_f32_is_within_its_bound`), under
/// a thousandth of a texel on a 16384-column map.
#[inline(always)]
pub fn atan2_f32(y: f32, x: f32) -> f32 {
    use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
    // Comparisons rather than `f32::min`/`max` (whose NaN rules cost instructions per lane).
    let (ax, ay) = (x.abs(), y.abs());
    let steep = ay > ax;
    let (lo, hi) = if steep { (ax, ay) } else { (ay, ax) };
    let a = if hi > 0.0 { lo / hi } else { 0.0 };
    // atan a = π/4 + atan((a − 1)/(a + 1)) keeps the polynomial's argument within tan(π/8).
    let reduce = a > 0.414_213_57;
    let t = if reduce { (a - 1.0) / (a + 1.0) } else { a };
    let z = t * t;
    let p = (((8.053_744_5e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1) * z * t + t;
    let r = if reduce { p + FRAC_PI_4 } else { p };
    let r = if steep { FRAC_PI_2 - r } else { r };
    // The sign bits, not comparisons, as IEEE atan2: atan2(±0, −0) = ±π.
    let r = if x.is_sign_negative() { PI - r } else { r };
    r.copysign(y)
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

/// The frame of the shortest-arc rotation carrying +Z to the unit direction `d`: the turn by θ
/// about +Z × d, R_z(φ)·R_y(θ)·R_z(−φ). Its third column is `d`. Unlike [`frame_of`], whose
/// twist φ about `d` jumps at both poles, it varies smoothly with `d` everywhere but at −Z (at
/// +Z it is the identity from every side; at −Z it takes φ = 0, R_y(π)): by the hairy-ball
/// theorem a tangent frame over the whole sphere of directions has a singular point, and this
/// one has exactly one. Shading frames of meshes use it (glossy transfer, the factored render),
/// so that frames of neighbouring normals differ by small turns wherever the normal is not −Z.
///
/// Written without angles: with v = +Z × d, the rotation is I + \[v\]× + \[v\]×²/(1 + d_z)
/// (Rodrigues), and x²/(1 + d_z) = cos²φ (1 − d_z) for unit `d`, which stays accurate where
/// 1 + d_z cancels.
#[inline]
pub fn shortest_arc_frame(d: DVec3) -> DMat3 {
    let s = (d.x * d.x + d.y * d.y).sqrt();
    let (c, t) = if s > 0.0 { (d.x / s, d.y / s) } else { (1.0, 0.0) };
    let a = 1.0 - d.z;
    DMat3::from_cols(DVec3::new(1.0 - a * c * c, -a * c * t, -d.x), DVec3::new(-a * c * t, 1.0 - a * t * t, -d.y), d)
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

    #[test]
    fn shortest_arc_frame_is_the_turn_about_z_cross_d_and_smooth_at_the_north_pole() {
        // R_z(φ)·R_y(θ)·R_z(−φ) by its angles, everywhere including both poles (φ = 0 there).
        for i in 0..=24 {
            for j in 0..16 {
                let (t, p) = (PI * i as f64 / 24.0, TAU * (j as f64 + 0.3) / 16.0);
                let d = direction(t, p);
                let (theta, phi) = angles(d);
                let want = frame(theta, phi) * DMat3::from_rotation_z(-phi);
                let got = shortest_arc_frame(d);
                assert!((got - want).abs().to_cols_array().iter().all(|e| *e < 1e-12), "θ {t} φ {p}: {got} vs {want}");
                assert!((got * DVec3::Z - d).length() < 1e-15);
                assert!((got.transpose() * got - DMat3::IDENTITY).abs().to_cols_array().iter().all(|e| *e < 1e-14));
                // It fixes the axis of the turn, +Z × d.
                let axis = DVec3::Z.cross(d);
                assert!((got * axis - axis).length() < 1e-14);
            }
        }
        // Near +Z the frame is near the identity from every side: the twist has no jump there,
        // where frame_of's first column turns with φ. Near −Z it depends on the side.
        for p in [0.1, 1.7, 3.0, 5.9] {
            let near = direction(1e-9, p);
            let off = (shortest_arc_frame(near) - DMat3::IDENTITY).abs().to_cols_array();
            assert!(off.iter().all(|e| *e < 2e-9), "φ {p}: {off:?}");
        }
        let (a, b) =
            (shortest_arc_frame(direction(PI - 1e-6, 0.0)), shortest_arc_frame(direction(PI - 1e-6, PI / 2.0)));
        assert!((a * DVec3::X - b * DVec3::X).length() > 1.0);
    }

    #[test]
    fn atan2_f32_is_within_its_bound() {
        // Every angle on a fine circle at several radii, the axes, signed zeros and both octant
        // boundaries of the reductions, against the f64 atan2 of the same f32 inputs.
        let mut worst = 0.0f64;
        let mut check = |y: f32, x: f32| {
            let want = (y as f64).atan2(x as f64);
            worst = worst.max((atan2_f32(y, x) as f64 - want).abs());
        };
        for k in 0..200_000 {
            let a = TAU * k as f64 / 200_000.0 - PI;
            for r in [1e-30, 1e-3, 1.0, 7.5, 1e30] {
                check((r * a.sin()) as f32, (r * a.cos()) as f32);
            }
        }
        let t8 = (PI / 8.0).tan() as f32;
        for (y, x) in [(0.0, 1.0), (-0.0, 1.0), (1.0, 0.0), (-1.0, 0.0), (0.0, -1.0), (1.0, 1.0), (t8, 1.0), (1.0, t8)]
        {
            check(y, x);
        }
        assert!(worst < 3e-7, "worst {worst:e} rad");
        assert_eq!(atan2_f32(0.0, 0.0), 0.0);
        assert_eq!(atan2_f32(-0.0, -1.0), -std::f32::consts::PI);
        assert_eq!(atan2_f32(-0.0, -0.0), -std::f32::consts::PI);
        assert_eq!(atan2_f32(0.0, -0.0), std::f32::consts::PI);
    }
}
