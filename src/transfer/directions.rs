//! Stratified, cosine-weighted ray directions over the hemisphere about a normal: N cells of
//! equal *projected* solid angle π/N, one jittered direction in each, from a fixed seed. The
//! set is made once in a local frame (+Z the normal) and turned onto each vertex's normal, so
//! it does not depend on the vertex, the thread or the thread count.
//!
//! **Why cosine-weighted and about the normal.** With p(ω) = cos θ/π (Malley's method: uniform
//! on the unit disk, lifted to the hemisphere) the estimator of T_i = (ρ/π) ∫ V cos θ Y_i dω is
//! (ρ/N) Σ_k V(ω_k) Y_i(ω_k): the cosine is integrated exactly and the horizon, where
//! max(n·ω, 0) has its kink, is a cell boundary rather than a cut through cells. A fixed set over
//! the whole sphere shared by every vertex was tried first: its horizon cuts cost a relative
//! RMS of 1.3 % at order 8 with 4096 directions on a sphere, where nothing is occluded.
//!
//! **The cells.** The disk radius² s = sin²θ is cut into R = round(√(N/2)) bands
//! and band r into c_r cells in φ, Σ c_r = N, band r spanning a height c_r/N of s. A cell's
//! area on the disk, hence its projected solid angle, is π · (c_r/N) / c_r = π/N exactly, so
//! the weights are equal for any jitter.

use crate::rng::SplitMix64;
use glam::{DMat3, DVec3};
use std::f64::consts::TAU;

/// The stratified set in the local frame (+Z the normal): each direction stands for a projected
/// solid angle of π/N.
#[derive(Clone, Debug)]
pub struct Stratified {
    /// Unit directions with z > 0, band after band from the pole down, φ increasing in a band.
    pub local: Vec<DVec3>,
}

impl Stratified {
    /// `count` directions (≥ 1), jittered within their cells by a generator seeded with `seed`.
    pub fn new(count: usize, seed: u64) -> Stratified {
        let count = count.max(1);
        let bands = ((count as f64 / 2.0).sqrt().round() as usize).clamp(1, count);
        let mut rng = SplitMix64::keyed(&[seed, count as u64]);
        let mut local = Vec::with_capacity(count);
        let mut done = 0usize; // cells in the bands above
        for r in 0..bands {
            // Cells per band differ by at most one: ⌊(r+1)N/R⌋ − ⌊rN/R⌋.
            let end = (r + 1) * count / bands;
            let cells = end - done;
            let (s_top, s_bottom) = (done as f64 / count as f64, end as f64 / count as f64);
            for c in 0..cells {
                let s = s_top + (s_bottom - s_top) * rng.next_f64();
                let phi = TAU * (c as f64 + rng.next_f64()) / cells as f64;
                let sin_theta = s.sqrt();
                let (sin_phi, cos_phi) = phi.sin_cos();
                // z > 0 strictly: a jitter of exactly s = 1 would lie on the horizon.
                let z = (1.0 - s).max(1e-12).sqrt();
                local.push(DVec3::new(sin_theta * cos_phi, sin_theta * sin_phi, z).normalize());
            }
            done = end;
        }
        Stratified { local }
    }

    /// The directions about `normal` (unit), in world axes: the local set turned by
    /// [`Stratified::frame`].
    pub fn about(&self, normal: DVec3) -> impl Iterator<Item = DVec3> + '_ {
        let world_from_local = Self::frame(normal);
        self.local.iter().map(move |d| world_from_local * *d)
    }

    /// The rotation taking the local set onto `normal` (unit): the columns are the deterministic
    /// frame (tangent, bitangent, normal) of glam's `any_orthonormal_pair` (Duff et al. 2017),
    /// right-handed, so a proper rotation whose SH rotation exists.
    pub fn frame(normal: DVec3) -> DMat3 {
        let (tangent, bitangent) = normal.any_orthonormal_pair();
        DMat3::from_cols(tangent, bitangent, normal)
    }

    /// How many directions.
    pub fn len(&self) -> usize {
        self.local.len()
    }

    /// Whether the set is empty (never: [`Stratified::new`] makes at least one).
    pub fn is_empty(&self) -> bool {
        self.local.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn cells_have_equal_projected_solid_angle() {
        for n in [1usize, 7, 64, 1000, 1024] {
            let s = Stratified::new(n, 3);
            assert_eq!(s.len(), n);
            assert!(s.local.iter().all(|d| (d.length() - 1.0).abs() < 1e-12 && d.z > 0.0));
        }
        // With p = cos θ/π: ∫ cos θ · cos θ dω = 2π/3 ≈ (π/N) Σ cos θ_k. One jittered direction
        // per cell leaves an error of a few 1e-5 at N = 4096 (6.5e-5 at seed 1); directions not
        // distributed as cos θ/π miss by more than 1e-2 (uniform ones give π/2).
        let s = Stratified::new(4096, 1);
        let estimate: f64 = s.local.iter().map(|d| d.z).sum::<f64>() * PI / 4096.0;
        assert!((estimate - 2.0 * PI / 3.0).abs() < 2e-4, "{estimate}");
        // Same seed, same set; another seed, another jitter; turned onto a normal, above it.
        assert_eq!(Stratified::new(100, 5).local, Stratified::new(100, 5).local);
        assert_ne!(Stratified::new(100, 5).local, Stratified::new(100, 6).local);
        let n = DVec3::new(0.3, -0.4, 0.5).normalize();
        assert!(s.about(n).all(|d| d.dot(n) > 0.0 && (d.length() - 1.0).abs() < 1e-12));
        for n in [n, DVec3::Z, -DVec3::Z, DVec3::X, DVec3::new(-0.2, 0.9, -0.1).normalize()] {
            let f = Stratified::frame(n);
            assert!((f.determinant() - 1.0).abs() < 1e-12 && (f * DVec3::Z - n).length() < 1e-15, "{n}");
        }
    }
}
