//! Stratified directions over the sphere: N cells of equal solid angle 4π/N, one jittered
//! direction in each, from a fixed seed. Every vertex uses the same set, so the directions do
//! not depend on the vertex, the thread or the thread count.
//!
//! **The cells.** z = cos θ is cut into R ≈ √(N/2) bands and band r is cut in φ into c_r
//! cells, Σ c_r = N; band r spans a height 2 c_r/N of z. By Archimedes' hat-box theorem the solid
//! angle of a z-band is 2π times its height, so every cell has solid angle
//! 2π · (2 c_r/N) / c_r = 4π/N exactly, and the estimator Σ_k f(ω_k) · 4π/N is unbiased
//! for any jitter. With R ≈ √(N/2) the cells are about as tall (in θ near the equator) as wide.

use crate::rng::SplitMix64;
use glam::DVec3;
use std::f64::consts::TAU;

/// The stratified set: unit directions, each standing for a solid angle of 4π/N.
#[derive(Clone, Debug)]
pub struct Stratified {
    /// The directions, band after band from +Z to −Z, φ increasing within a band.
    pub directions: Vec<DVec3>,
}

impl Stratified {
    /// `count` directions (≥ 1), jittered within their cells by a generator seeded with `seed`.
    pub fn new(count: usize, seed: u64) -> Stratified {
        let count = count.max(1);
        let bands = ((count as f64 / 2.0).sqrt().round() as usize).clamp(1, count);
        let mut rng = SplitMix64::keyed(&[seed, count as u64]);
        let mut directions = Vec::with_capacity(count);
        let mut done = 0usize; // cells in the bands above
        for r in 0..bands {
            // Cells per band differ by at most one: ⌊(r+1)N/R⌋ − ⌊rN/R⌋.
            let end = (r + 1) * count / bands;
            let cells = end - done;
            let (z_top, z_bottom) = (1.0 - 2.0 * done as f64 / count as f64, 1.0 - 2.0 * end as f64 / count as f64);
            for c in 0..cells {
                let z = z_top + (z_bottom - z_top) * rng.next_f64();
                let phi = TAU * (c as f64 + rng.next_f64()) / cells as f64;
                let s = (1.0 - z * z).max(0.0).sqrt();
                let (sin_phi, cos_phi) = phi.sin_cos();
                directions.push(DVec3::new(s * cos_phi, s * sin_phi, z));
            }
            done = end;
        }
        Stratified { directions }
    }

    /// The solid angle each direction stands for: 4π/N.
    pub fn weight(&self) -> f64 {
        2.0 * TAU / self.directions.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_have_equal_solid_angle_and_integrate_low_degree_polynomials() {
        for n in [1usize, 7, 64, 1000, 1024] {
            let s = Stratified::new(n, 3);
            assert_eq!(s.directions.len(), n);
            assert!(s.directions.iter().all(|d| (d.length() - 1.0).abs() < 1e-12));
        }
        // ∫ z² dω = 4π/3: stratification makes the error far below plain Monte Carlo's.
        let s = Stratified::new(4096, 1);
        let z2: f64 = s.directions.iter().map(|d| d.z * d.z).sum::<f64>() * s.weight();
        assert!((z2 - 4.0 * std::f64::consts::PI / 3.0).abs() < 1e-3, "{z2}");
        // Same seed, same set; another seed, another jitter.
        assert_eq!(Stratified::new(100, 5).directions, Stratified::new(100, 5).directions);
        assert_ne!(Stratified::new(100, 5).directions, Stratified::new(100, 6).directions);
    }
}
