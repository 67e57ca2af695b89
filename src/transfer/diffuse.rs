//! Diffuse transfer vectors T_i(x) = (ρ/π) ∫ V(x, ω) max(n·ω, 0) Y_i(ω) dω
//! (Sloan, Kautz & Snyder 2002, eq. 7–8) at one surface point, by two integrators:
//!
//! - [`unshadowed_exact`], V ≡ 1, by a product quadrature over the hemisphere about n that is
//!   exact for this integrand: it equals (ρ/π) Â_l Y_lm(n) (Ramamoorthi & Hanrahan 2001, eq. 8–9,
//!   the Funk–Hecke theorem) to rounding, which the tests check against the paper's Â_l.
//! - [`Shadowed::integrate`], with visibility, by the stratified cosine-weighted rays of
//!   [`super::directions::Stratified`], each cast through [`super::visibility::Occluders`].

use super::directions::Stratified;
use super::visibility::Occluders;
use crate::sh::basis::eval_basis_dir;
use crate::sh::legendre::LegendreTable;
use crate::sh::rotate::ShRotation;
use glam::DVec3;
use std::f64::consts::{PI, TAU};

/// Gauss–Legendre nodes in μ = n·ω over [0, 1] of [`unshadowed_exact`].
const EXACT_MU_NODES: usize = 8;
/// Equally spaced nodes in φ about n of [`unshadowed_exact`].
const EXACT_PHI_NODES: usize = 18;

/// The unshadowed transfer (V ≡ 1) of a point with unit normal `normal`, `order` n bands
/// (n² coefficients), albedo ρ, into `out`.
///
/// **Why the quadrature is exact.** In a frame with n as its pole, Y_lm(ω) (l < n ≤ 8) is a
/// polynomial of degree l in the Cartesian components sin θ cos φ, sin θ sin φ, μ, and the
/// integrand μ Y_lm(ω) one of degree ≤ n. The trapezoidal rule in φ with M = 18 > n points is
/// exact for trigonometric polynomials of degree < M, so it keeps exactly the φ-mean, in which
/// only even powers of cos φ and sin φ survive: sin θ then comes in even powers, (1 − μ²)^k, and
/// what is left is a polynomial of degree ≤ n ≤ 8 in μ, integrated exactly by 8 Gauss–Legendre
/// nodes (exact to degree 15).
pub fn unshadowed_exact(normal: DVec3, order: usize, albedo: f64, out: &mut [f64]) {
    let coeffs = order * order;
    let table = LegendreTable::new(order - 1);
    let (tangent, bitangent) = normal.any_orthonormal_pair();
    let mut y = vec![0.0; coeffs];
    out[..coeffs].fill(0.0);
    let rule = crate::quadrature::gauss_legendre_cached(EXACT_MU_NODES);
    for &(node, weight) in rule.iter() {
        // μ ∈ [0, 1] from the node on [−1, 1]; dμ = dx/2.
        let mu = 0.5 * (node + 1.0);
        let sin_theta = (1.0 - mu * mu).max(0.0).sqrt();
        let w = 0.5 * weight * TAU / EXACT_PHI_NODES as f64 * mu;
        for k in 0..EXACT_PHI_NODES {
            let (s, c) = (TAU * k as f64 / EXACT_PHI_NODES as f64).sin_cos();
            let omega = sin_theta * (c * tangent + s * bitangent) + mu * normal;
            eval_basis_dir(&table, omega, &mut y);
            for i in 0..coeffs {
                out[i] += w * y[i];
            }
        }
    }
    for t in &mut out[..coeffs] {
        *t *= albedo / PI;
    }
}

/// The SH basis at the stratified set's local directions, evaluated once: per vertex the rays
/// only add rows of it, and one SH rotation turns the local sums onto the vertex's frame.
///
/// **Why this is exact.** Each vertex's directions are ω_k = F l_k, F = [`Stratified::frame`]. A
/// band of real SH is closed under rotation, Y_i(F l) = Σ_j M_ij(F) Y_j(l) with M(F) the
/// block-diagonal matrix taking the coefficients of f to those of f∘F⁻¹ (Ivanic & Ruedenberg
/// 1996, [`ShRotation`]), so Σ_k V_k Y_i(ω_k) = Σ_j M_ij(F) Σ_k V_k Y_j(l_k): the same sum, to
/// rounding, for one (2l+1)² matrix per band and vertex instead of n² basis values per ray.
pub struct LocalBasis {
    coeffs: usize,
    order: usize,
    /// Y_j(l_k), row k.
    y: Vec<f64>,
    /// Σ_k Y_j(l_k): the unshadowed sums, the same in every frame.
    all: Vec<f64>,
}

impl LocalBasis {
    /// The basis of `order` n bands at `directions`' local set.
    pub fn new(directions: &Stratified, order: usize) -> LocalBasis {
        let coeffs = order * order;
        let table = LegendreTable::new(order - 1);
        let mut y = vec![0.0; directions.len() * coeffs];
        for (row, d) in y.chunks_exact_mut(coeffs).zip(&directions.local) {
            eval_basis_dir(&table, *d, row);
        }
        let mut all = vec![0.0; coeffs];
        for row in y.chunks_exact(coeffs) {
            for (a, v) in all.iter_mut().zip(row) {
                *a += v;
            }
        }
        LocalBasis { coeffs, order, y, all }
    }

    /// Adds the row of direction `k` to `sums`.
    #[inline]
    pub fn add_row(&self, k: usize, sums: &mut [f64]) {
        for (a, v) in sums.iter_mut().zip(&self.y[k * self.coeffs..(k + 1) * self.coeffs]) {
            *a += v;
        }
    }

    /// The local sums `shadowed` (and the unshadowed ones) turned onto `normal`'s frame and
    /// scaled by `scale`: (shadowed, unshadowed) in world axes.
    pub fn to_world(&self, normal: DVec3, shadowed: &[f64], scale: f64) -> (Vec<f64>, Vec<f64>) {
        let rotation = ShRotation::new(Stratified::frame(normal), self.order - 1);
        let turn = |local: &[f64]| rotation.apply_scalar(local).into_iter().map(|t| t * scale).collect::<Vec<f64>>();
        (turn(shadowed), turn(&self.all))
    }
}

/// What the shadowed integrator needs for every point: the directions and the occluders.
pub struct Shadowed<'a> {
    directions: &'a Stratified,
    basis: LocalBasis,
    occluders: &'a Occluders,
}

/// One point's shadowed transfer, with what its rays saw.
#[derive(Clone, Debug, Default)]
pub struct PointTransfer {
    /// T_i, n² values.
    pub shadowed: Vec<f64>,
    /// The same rays with V ≡ 1: compared with [`unshadowed_exact`], the integration error of
    /// the direction set alone.
    pub unshadowed: Vec<f64>,
    /// Of the rays cast, those that escaped.
    pub visible: u32,
}

impl<'a> Shadowed<'a> {
    /// The integrator for `order` n bands over `directions`, casting through `occluders`.
    pub fn new(directions: &'a Stratified, order: usize, occluders: &'a Occluders) -> Shadowed<'a> {
        Shadowed { directions, basis: LocalBasis::new(directions, order), occluders }
    }

    /// T_i at `position` with unit normal `normal`, albedo ρ. The rays leave from
    /// `position + offset · normal` (so that they do not hit the surface they leave) along the
    /// cosine-weighted set turned onto the normal, whose density cos θ/π cancels the cosine:
    /// T_i ≈ (ρ/π) (π/N) Σ_k V(ω_k) Y_i(ω_k), summed in the fixed order of the directions in
    /// the local frame and turned onto the normal's by [`LocalBasis`] (the same bits for any
    /// thread count).
    ///
    /// (A control variate, T_exact − (ρ/N) Σ (1 − V_k) Y_i, was tried: exact where nothing is
    /// occluded, but 1.2–1.3× the error of this plain estimate in the bowl test, where most
    /// directions are occluded.)
    pub fn integrate(&self, position: DVec3, normal: DVec3, offset: f64, albedo: f64) -> PointTransfer {
        let origin = position + offset * normal;
        let mut local = vec![0.0; self.basis.coeffs];
        let mut visible = 0u32;
        for (k, d) in self.directions.about(normal).enumerate() {
            if self.occluders.occluded(origin, d) {
                continue;
            }
            visible += 1;
            self.basis.add_row(k, &mut local);
        }
        let (shadowed, unshadowed) = self.basis.to_world(normal, &local, albedo / self.directions.len() as f64);
        PointTransfer { shadowed, unshadowed, visible }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::convolve::clamped_cosine;

    #[test]
    fn local_sums_turned_onto_the_normal_are_the_world_sums() {
        // The slow, obvious way: the basis at every world direction, against LocalBasis.
        let order = 8;
        let directions = Stratified::new(200, 4);
        let basis = LocalBasis::new(&directions, order);
        let table = LegendreTable::new(order - 1);
        let mut y = vec![0.0; 64];
        for n in [DVec3::Z, -DVec3::Z, DVec3::new(0.3, -0.8, 0.2).normalize(), DVec3::new(-0.9, 0.1, -0.3).normalize()]
        {
            // Every third ray "visible".
            let mut world = vec![0.0; 64];
            let mut local = vec![0.0; 64];
            for (k, d) in directions.about(n).enumerate().filter(|(k, _)| k % 3 == 0) {
                eval_basis_dir(&table, d, &mut y);
                for i in 0..64 {
                    world[i] += y[i];
                }
                basis.add_row(k, &mut local);
            }
            let (turned, _) = basis.to_world(n, &local, 1.0);
            for i in 0..64 {
                assert!((turned[i] - world[i]).abs() < 1e-11, "{n}: {i}: {} vs {}", turned[i], world[i]);
            }
        }
    }

    #[test]
    fn exact_quadrature_is_the_clamped_cosine_convolution() {
        // T_lm = (ρ/π) Â_l Y_lm(n) for any normal (R&H 2001, eq. 8–9).
        let order = 8;
        let table = LegendreTable::new(order - 1);
        let mut y = vec![0.0; 64];
        let mut t = vec![0.0; 64];
        for n in [DVec3::Z, DVec3::new(0.3, -0.8, 0.2).normalize(), -DVec3::X] {
            unshadowed_exact(n, order, 0.7, &mut t);
            eval_basis_dir(&table, n, &mut y);
            for i in 0..64 {
                let (l, _) = crate::sh::lm(i);
                let expected = 0.7 / PI * clamped_cosine(l) * y[i];
                assert!((t[i] - expected).abs() < 1e-13, "{i}: {} vs {expected}", t[i]);
            }
        }
    }
}
