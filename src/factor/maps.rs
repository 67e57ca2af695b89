//! Factor maps: g_k(ω_i) and h_k(ω_o) drawn as lat-long images so a person can see that they
//! are spherical harmonics (Mahajan et al. 2008, Fig. 2 and 4): red where the factor is
//! positive, blue where it is negative (the paper's colouring), magnitude as intensity.
//!
//! Image frame (DESIGN.md): row 0 is θ = 0, column 0 is φ = 0, pixel centres at half-integers;
//! the hemisphere maps cover θ ∈ [0, π/2] only. Each pixel shows the grid cell containing its
//! centre (nearest cell, no interpolation: the picture is the sampled factor).

use super::grid::{Domain, Grid};
use super::svd::Factorization;
use crate::io::RgbImage;
use std::f64::consts::PI;

/// Pixels per grid bin along θ in the maps.
const PIXELS_PER_BIN: usize = 4;

/// The grid cell containing direction (θ, φ).
fn cell(grid: &Grid, theta: f64, phi: f64) -> usize {
    let span = match grid.domain {
        Domain::Sphere => 2.0,
        Domain::Hemisphere => 1.0,
    };
    let n = grid.n;
    let j = (((1.0 - theta.cos()) / span * n as f64).floor().max(0.0) as usize).min(n - 1);
    let k = ((phi / (2.0 * PI) * n as f64).floor().max(0.0) as usize).min(n - 1);
    j * n + k
}

/// Size (width, height) of one factor map for `grid`.
pub fn map_size(grid: &Grid) -> (usize, usize) {
    let height = grid.n * PIXELS_PER_BIN;
    let sphere_height = match grid.domain {
        Domain::Sphere => height,
        Domain::Hemisphere => 2 * height,
    };
    (2 * sphere_height, height)
}

/// A signed factor on the grid as a lat-long image: R = max(v, 0), B = max(−v, 0), G = 0,
/// with v scaled by `scale`.
pub fn latlong(grid: &Grid, values: &[f64], scale: f64) -> RgbImage {
    let (w, h) = map_size(grid);
    let theta_span = match grid.domain {
        Domain::Sphere => PI,
        Domain::Hemisphere => PI / 2.0,
    };
    RgbImage::from_fn(w, h, |x, y| {
        let theta = (y as f64 + 0.5) / h as f64 * theta_span;
        let phi = (x as f64 + 0.5) / w as f64 * 2.0 * PI;
        let v = values[cell(grid, theta, phi)] * scale;
        [v.max(0.0) as f32, 0.0, (-v).max(0.0) as f32]
    })
}

/// Named EXR layers `g_000`, `h_000`, `g_001`, … holding the factors in their L² normalization.
pub fn layers(f: &Factorization) -> Vec<(String, RgbImage)> {
    let mut out = Vec::new();
    for (k, (g, h)) in f.g.iter().zip(&f.h).enumerate() {
        out.push((format!("g_{k:03}"), latlong(&f.grid, g, 1.0)));
        out.push((format!("h_{k:03}"), latlong(&f.grid, h, 1.0)));
    }
    out
}

/// A contact sheet for a quick look (PNG): one row per term, g_k left and h_k right, each map
/// scaled so its largest magnitude is 1, separated by 2-pixel grey gutters.
pub fn contact_sheet(f: &Factorization) -> RgbImage {
    let (w, h) = map_size(&f.grid);
    let gap = 2;
    let terms = f.g.len().min(f.h.len());
    let width = 2 * w + 3 * gap;
    let height = terms * (h + gap) + gap;
    let mut sheet = RgbImage::from_fn(width, height, |_, _| [0.25, 0.25, 0.25]);
    for k in 0..terms {
        for (col, values) in [&f.g[k], &f.h[k]].into_iter().enumerate() {
            let peak = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let img = latlong(&f.grid, values, if peak > 0.0 { 1.0 / peak } else { 0.0 });
            let (x0, y0) = (gap + col * (w + gap), gap + k * (h + gap));
            for y in 0..h {
                for x in 0..w {
                    sheet.set(x0 + x, y0 + y, img.get(x, y));
                }
            }
        }
    }
    sheet
}
