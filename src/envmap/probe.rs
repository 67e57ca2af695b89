//! Debevec's angular light-probe map.
//!
//! Image coordinates u ∈ [−1, 1] (right), v ∈ [−1, 1] (up); r = √(u² + v²) ≤ 1 is the angle from
//! the probe's centre direction divided by π. In the probe's own frame (x right, y up, z towards
//! the viewer of the image) a pixel looks along (sin(πr) u/r, sin(πr) v/r, cos(πr)).
//! `WORLD_FROM_PROBE` takes that frame to prtkit's +Z-up frame (`docs/envmap-layouts.md`).

use glam::{DMat3, DVec3};
use std::f64::consts::PI;

/// Probe frame → world: probe up (y) is world +Z, the image centre (probe +z) looks along
/// world −X, probe right (x) is world −Y… chosen so Debevec's probes agree with pbrt's lat-long
/// conversion of the same probe (checked against `grace_latlong.exr` in the tests).
pub const WORLD_FROM_PROBE: DMat3 = DMat3::from_cols(
    DVec3::new(0.0, -1.0, 0.0), // probe x
    DVec3::new(0.0, 0.0, 1.0),  // probe y
    DVec3::new(-1.0, 0.0, 0.0), // probe z
);

/// Direction at continuous image position (px, py) ∈ [0, n]², or `None` outside the disc.
pub(crate) fn direction_at(n: usize, px: f64, py: f64) -> Option<DVec3> {
    let u = 2.0 * px / n as f64 - 1.0;
    let v = 1.0 - 2.0 * py / n as f64;
    let r = (u * u + v * v).sqrt();
    if r > 1.0 {
        return None;
    }
    let local = if r < 1e-12 {
        DVec3::Z
    } else {
        let (s, c) = (PI * r).sin_cos();
        DVec3::new(s * u / r, s * v / r, c)
    };
    Some(WORLD_FROM_PROBE * local)
}

/// Centre direction and solid angle of pixel (x, y) of an n×n probe, `None` if the centre lies
/// outside the disc. dΩ = π sin(πr)/r du dv, integrated over the pixel (clipped to the disc).
pub(crate) fn texel(n: usize, x: usize, y: usize) -> Option<(DVec3, f64)> {
    let dir = direction_at(n, x as f64 + 0.5, y as f64 + 0.5)?;
    Some((dir, solid_angle(n, x, y)))
}

fn density(u: f64, v: f64) -> f64 {
    let r = (u * u + v * v).sqrt();
    if r > 1.0 {
        0.0
    } else if r < 1e-9 {
        PI * PI
    } else {
        PI * (PI * r).sin() / r
    }
}

fn solid_angle(n: usize, x: usize, y: usize) -> f64 {
    let h = 2.0 / n as f64; // pixel edge in (u, v)
    let u0 = x as f64 * h - 1.0;
    let v0 = 1.0 - (y + 1) as f64 * h;
    let far = ((u0.abs().max((u0 + h).abs())).powi(2) + (v0.abs().max((v0 + h).abs())).powi(2)).sqrt();
    // Interior pixels: 2×2 Gauss–Legendre (the density is smooth); pixels the rim crosses:
    // a 16×16 midpoint grid that clips at r = 1, where the density falls to zero.
    if far <= 1.0 {
        let g = 0.5 / 3f64.sqrt();
        let mut s = 0.0;
        for a in [0.5 - g, 0.5 + g] {
            for b in [0.5 - g, 0.5 + g] {
                s += density(u0 + a * h, v0 + b * h);
            }
        }
        s * 0.25 * h * h
    } else {
        let k = 16;
        let mut s = 0.0;
        for i in 0..k {
            for j in 0..k {
                s += density(u0 + (i as f64 + 0.5) / k as f64 * h, v0 + (j as f64 + 0.5) / k as f64 * h);
            }
        }
        s * h * h / (k * k) as f64
    }
}

/// Continuous pixel position (texel centres at half-integers minus 0.5, i.e. `x` for pixel x)
/// of a world direction in an n×n probe.
pub(crate) fn pixel_of(n: usize, dir: DVec3) -> (f64, f64) {
    let local = WORLD_FROM_PROBE.transpose() * dir;
    let alpha = local.z.clamp(-1.0, 1.0).acos();
    let rho = (local.x * local.x + local.y * local.y).sqrt();
    let (u, v) = if rho < 1e-12 {
        (0.0, 0.0)
    } else {
        let r = alpha / PI;
        (r * local.x / rho, r * local.y / rho)
    };
    ((u + 1.0) * 0.5 * n as f64 - 0.5, (1.0 - v) * 0.5 * n as f64 - 0.5)
}
