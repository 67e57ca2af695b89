//! The lat-long (equirectangular) grid: W columns over φ ∈ [0, 2π), H rows over θ ∈ [0, π],
//! row 0 at θ = 0 (+Z), column 0 at φ = 0 (+X), texel centres at half-integers.

use super::{direction, phi, theta};
use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// A W×H lat-long grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LatLong {
    /// Columns (φ).
    pub width: usize,
    /// Rows (θ).
    pub height: usize,
}

impl LatLong {
    /// A W×H grid.
    pub fn new(width: usize, height: usize) -> Self {
        LatLong { width, height }
    }

    /// θ of the centre of row `y`.
    #[inline]
    pub fn row_theta(&self, y: usize) -> f64 {
        PI * (y as f64 + 0.5) / self.height as f64
    }

    /// φ of the centre of column `x`.
    #[inline]
    pub fn column_phi(&self, x: usize) -> f64 {
        TAU * (x as f64 + 0.5) / self.width as f64
    }

    /// Direction at continuous grid position (px, py): pixel x spans [x, x + 1].
    #[inline]
    pub fn direction_at(&self, px: f64, py: f64) -> DVec3 {
        direction(PI * py / self.height as f64, TAU * px / self.width as f64)
    }

    /// Unit direction of the centre of texel (x, y).
    #[inline]
    pub fn texel_direction(&self, x: usize, y: usize) -> DVec3 {
        direction(self.row_theta(y), self.column_phi(x))
    }

    /// The rows in mirrored pairs (y, H − 1 − y) over the top half, and an odd middle row alone.
    /// A pair's rows have opposite z = cos θ, and P̄_l^m(−z) = (−1)^{l+m} P̄_l^m(z), so one
    /// Legendre evaluation serves both rows of a pair (the separable projection and synthesis).
    pub fn mirrored_row_pairs(&self) -> impl Iterator<Item = (usize, Option<usize>)> {
        let h = self.height;
        (0..h / 2).map(move |y| (y, Some(h - 1 - y))).chain((h % 2 == 1).then_some((h / 2, None)))
    }

    /// Exact solid angle of every texel of row `y`: (2π/W)(cos θ_top − cos θ_bottom).
    #[inline]
    pub fn row_solid_angle(&self, y: usize) -> f64 {
        let t0 = PI * y as f64 / self.height as f64;
        let t1 = PI * (y + 1) as f64 / self.height as f64;
        TAU / self.width as f64 * (t0.cos() - t1.cos())
    }

    /// Continuous grid position of a direction (texel centres at half-integers), so that
    /// `position(texel_direction(x, y)) = (x + 0.5, y + 0.5)`.
    #[inline]
    pub fn position(&self, d: DVec3) -> (f64, f64) {
        let d = d.normalize();
        (phi(d) / TAU * self.width as f64, theta(d) / PI * self.height as f64)
    }

    /// The texel (x, y) a direction falls in: `position` floored, clamped to the grid.
    #[inline]
    pub fn texel_of(&self, d: DVec3) -> (usize, usize) {
        let (fx, fy) = self.position(d);
        ((fx.floor().max(0.0) as usize).min(self.width - 1), (fy.floor().max(0.0) as usize).min(self.height - 1))
    }

    /// Bilinear taps of direction `d` between texel centres: φ wraps, θ clamps to the first and
    /// last rows. Four (pixel index, weight) pairs; the weights sum to 1.
    #[inline]
    pub fn taps(&self, d: DVec3) -> [(usize, f64); 4] {
        let (px, py) = self.position(d);
        bilinear_taps(self.width, self.height, px - 0.5, py - 0.5, true)
    }
}

/// Bilinear taps at continuous pixel-centre coordinates (fx, fy) of a W×H grid (pixel (x, y)'s
/// centre is at (x, y)): x wraps when `wrap_x`, else clamps; y clamps. Four (index, weight) pairs.
#[inline]
pub fn bilinear_taps(width: usize, height: usize, fx: f64, fy: f64, wrap_x: bool) -> [(usize, f64); 4] {
    let fy = fy.clamp(0.0, (height - 1) as f64);
    let y0 = fy.floor() as usize;
    let y1 = (y0 + 1).min(height - 1);
    let ty = fy - y0 as f64;
    let (x0, x1, tx) = if wrap_x {
        let fl = fx.floor();
        let x0 = (fl as i64).rem_euclid(width as i64) as usize;
        (x0, (x0 + 1) % width, fx - fl)
    } else {
        let fx = fx.clamp(0.0, (width - 1) as f64);
        let x0 = fx.floor() as usize;
        (x0, (x0 + 1).min(width - 1), fx - x0 as f64)
    };
    [
        (y0 * width + x0, (1.0 - tx) * (1.0 - ty)),
        (y0 * width + x1, tx * (1.0 - ty)),
        (y1 * width + x0, (1.0 - tx) * ty),
        (y1 * width + x1, tx * ty),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texel_solid_angles_sum_to_the_sphere() {
        let g = LatLong::new(64, 32);
        let total: f64 = (0..g.height).map(|y| g.row_solid_angle(y) * g.width as f64).sum();
        assert!((total - 4.0 * PI).abs() < 1e-12);
    }

    #[test]
    fn a_texel_centre_taps_only_itself() {
        let g = LatLong::new(16, 8);
        for y in 0..g.height {
            for x in 0..g.width {
                let taps = g.taps(g.texel_direction(x, y));
                let own: f64 = taps.iter().filter(|(i, _)| *i == y * g.width + x).map(|t| t.1).sum();
                assert!((own - 1.0).abs() < 1e-9, "({x}, {y}): {taps:?}");
            }
        }
    }

    #[test]
    fn taps_wrap_across_phi_zero_and_clamp_at_the_poles() {
        let g = LatLong::new(8, 4);
        // On the φ = 0 meridian, halfway between the last and the first column.
        let taps = g.taps(direction(g.row_theta(1), 0.0));
        let cols: Vec<usize> = taps.iter().filter(|t| t.1 > 0.0).map(|t| t.0 % 8).collect();
        assert!(cols.contains(&0) && cols.contains(&7), "{taps:?}");
        assert!(taps.iter().all(|t| t.1 == 0.0 || (t.1 - 0.5).abs() < 1e-9));
        // At the pole every tap is in row 0.
        assert!(g.taps(DVec3::Z).iter().all(|t| t.0 < 8 || t.1 == 0.0));
        let sum: f64 = g.taps(DVec3::new(0.3, -0.2, 0.9)).iter().map(|t| t.1).sum();
        assert!((sum - 1.0).abs() < 1e-12);
    }
}
