//! The lat-long (equirectangular) grid: W columns over φ ∈ [0, 2π), H rows over θ ∈ [0, π],
//! row 0 at θ = 0 (+Z), column 0 at φ = 0 (+X), texel centres at half-integers.

use super::{atan2_f32, direction, phi, theta};
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

/// Directions per block of [`LatLong::taps_lanes`].
pub const LANES: usize = 16;

/// The bilinear taps of [`LANES`] directions, structure of arrays: lane i reads columns `x0[i]`,
/// `x1[i]` of rows `y0[i]`, `y1[i]` with weights (1 − tx, tx) × (1 − ty, ty), as
/// [`bilinear_taps`] with φ wrapping. The indices are whole numbers held as f32 (exact below
/// 2²⁴), so that the lanes never leave float registers.
#[derive(Clone, Copy, Debug, Default)]
pub struct TapLanes {
    /// Left column.
    pub x0: [f32; LANES],
    /// Right column (wraps to 0 after the last).
    pub x1: [f32; LANES],
    /// Upper row.
    pub y0: [f32; LANES],
    /// Lower row (the last row clamps).
    pub y1: [f32; LANES],
    /// Weight of the right column.
    pub tx: [f32; LANES],
    /// Weight of the lower row.
    pub ty: [f32; LANES],
}

impl LatLong {
    /// [`LatLong::taps`] of [`LANES`] directions (any length, not zero) in f32, without a branch
    /// on the data so that the loop compiles to SIMD: φ and θ = atan2(√(x² + y²), z) by
    /// [`atan2_f32`], positions within 0.002 of a texel of the f64 ones on grids up to 16384
    /// columns (f32 holds 16384 to 0.001).
    #[inline(always)]
    pub fn taps_lanes(&self, x: &[f32; LANES], y: &[f32; LANES], z: &[f32; LANES], taps: &mut TapLanes) {
        let (w, h) = (self.width as f32, self.height as f32);
        let (x_scale, y_scale) = (w / std::f32::consts::TAU, h / std::f32::consts::PI);
        for i in 0..LANES {
            let phi = atan2_f32(y[i], x[i]);
            let phi = if phi < 0.0 { phi + std::f32::consts::TAU } else { phi };
            let theta = atan2_f32((x[i] * x[i] + y[i] * y[i]).sqrt(), z[i]);
            // Pixel-centre coordinates: fx ∈ [−½, W − ½], fy clamped to the first and last rows.
            let fx = phi * x_scale - 0.5;
            let fy = theta * y_scale - 0.5;
            let fy = if fy < 0.0 {
                0.0
            } else if fy > h - 1.0 {
                h - 1.0
            } else {
                fy
            };
            let (col, row) = (fx.floor(), fy.floor());
            taps.tx[i] = fx - col;
            taps.ty[i] = fy - row;
            let x0 = if col < 0.0 {
                col + w
            } else if col > w - 1.0 {
                w - 1.0
            } else {
                col
            };
            let x1 = if x0 + 1.0 < w { x0 + 1.0 } else { 0.0 };
            let y1 = if row + 1.0 < h { row + 1.0 } else { h - 1.0 };
            taps.x0[i] = x0;
            taps.x1[i] = x1;
            taps.y0[i] = row;
            taps.y1[i] = y1;
        }
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

    #[test]
    fn lane_taps_are_the_f64_taps_within_two_thousandths_of_a_texel() {
        // On the largest grid prtkit reads, directions all round (any length) and the awkward
        // ones: the poles, the φ = 0 seam from both sides (signed zeros), the axes.
        let g = LatLong::new(16384, 8192);
        // A Fibonacci spiral, with lengths from 0.5 to 1.5.
        let n = 20_000;
        let mut dirs: Vec<DVec3> = (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let length = 0.5 + (i as f64 * 0.618_034).fract();
                direction(z.acos(), 2.399_963 * i as f64) * length
            })
            .collect();
        for d in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::new(1.0, -0.0, 0.0),
            DVec3::new(1.0, 1e-9, 0.3),
            DVec3::new(1.0, -1e-9, -0.3),
            DVec3::new(1e-9, 0.0, 1.0),
        ] {
            dirs.push(d);
        }
        let mut worst = 0.0f64;
        for block in dirs.chunks(LANES) {
            let (mut x, mut y, mut z) = ([1.0f32; LANES], [0.0f32; LANES], [0.0f32; LANES]);
            for (i, d) in block.iter().enumerate() {
                (x[i], y[i], z[i]) = (d.x as f32, d.y as f32, d.z as f32);
            }
            let mut lanes = TapLanes::default();
            g.taps_lanes(&x, &y, &z, &mut lanes);
            for (i, d) in block.iter().enumerate() {
                // The f64 taps of the same f32 direction.
                let want = g.taps(DVec3::new(x[i] as f64, y[i] as f64, z[i] as f64));
                let (want_x0, want_y0) = (want[0].0 % g.width, want[0].0 / g.width);
                let want_tx = want[1].1 + want[3].1;
                let want_ty = want[2].1 + want[3].1;
                // Position along each axis, measured from the f64 taps' left column or upper row
                // (a lane may pick the neighbouring texel with a weight near 0 or 1).
                let w = g.width as f64;
                let dx = (lanes.x0[i] as f64 + lanes.tx[i] as f64) - (want_x0 as f64 + want_tx);
                let dx = dx - w * (dx / w).round();
                let dy = (lanes.y0[i] as f64 + lanes.ty[i] as f64) - (want_y0 as f64 + want_ty);
                worst = worst.max(dx.abs()).max(dy.abs());
                assert!(dx.abs() < 2e-3 && dy.abs() < 2e-3, "{d:?}: off by ({dx}, {dy}) texels");
                // The neighbours are the next column (wrapping) and row (clamped), as in f64.
                assert_eq!(lanes.x1[i] as usize, (lanes.x0[i] as usize + 1) % g.width, "{d:?}");
                let y1 = (lanes.y0[i] as usize + 1).min(g.height - 1);
                assert_eq!(lanes.y1[i] as usize, y1, "{d:?}");
            }
        }
        assert!(worst > 0.0, "the lanes are f32: some difference must show");
    }
}
