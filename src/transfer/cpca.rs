//! Clustered principal component analysis of per-vertex transfer (Sloan, Hall, Hart & Snyder
//! 2003, "Clustered Principal Components for Precomputed Radiance Transfer", §3).
//!
//! The transfer vectors (n² values, or K·n² for a glossy bake) of all vertices are split into C
//! clusters; each cluster keeps its mean m_c and its P leading principal directions b_c1 … b_cP,
//! each vertex its cluster and P weights, so that
//!
//!   T(x) ≈ m_c + Σ_p w_p(x) b_cp,   w_p(x) = b_cp · (T(x) − m_c)                (eq. 2)
//!
//! and relighting by a lighting vector L costs, per frame, the C·(P + 1) dot products
//! m_c · L and b_cp · L, then P multiply-adds per vertex instead of n² (or K·n²) (eq. 3):
//! B(x) = (m_c · L) + Σ_p w_p(x) (b_cp · L).
//!
//! **The iteration** is §3.2's: starting from clusters cut along the data's first principal
//! direction (equal counts, so the start is deterministic), repeat — fit each cluster's mean and
//! P directions (an SVD), then move every vertex to the cluster that reconstructs it best
//! (least ‖x − m_c‖² − ‖B_cᵀ(x − m_c)‖²) — until no vertex moves, a round gains less than
//! [`CONVERGED`] of the error, or [`MAX_ITERATIONS`]. A
//! cluster left empty takes the vertex reconstructed worst. Each step depends only on the data,
//! never on the thread count (the SVDs are sequential; the assignment is per vertex).

use crate::factor::svd::{run_svd, FactorError};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use rayon::prelude::*;

/// Most fit-and-assign rounds: a cap of the iteration that no input sets (the ceilings on what
/// input may ask for are in `crate::limits`).
pub const MAX_ITERATIONS: usize = 30;
/// A round that lowers the total squared error by less than this fraction of it ends the
/// iteration.
pub const CONVERGED: f64 = 1e-3;

/// The compressed transfer.
#[derive(Clone, Debug, PartialEq)]
pub struct Cpca {
    /// Values per vertex D.
    pub dim: usize,
    /// Clusters C.
    pub clusters: usize,
    /// Principal directions per cluster P.
    pub components: usize,
    /// m_c, cluster after cluster (C × D).
    pub means: Vec<f64>,
    /// b_cp, cluster after cluster, direction after direction (C × P × D); zero beyond a
    /// cluster's rank.
    pub bases: Vec<f64>,
    /// Each vertex's cluster.
    pub cluster_of: Vec<u32>,
    /// Each vertex's P weights (V × P).
    pub weights: Vec<f64>,
    /// Rounds run.
    pub iterations: usize,
}

/// How well the compressed transfer reproduces the original.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reconstruction {
    /// ‖T − T̃‖ / ‖T‖ over every vertex and value.
    pub relative_rms: f64,
    /// The largest per-vertex ‖T(x) − T̃(x)‖, over the RMS of ‖T(x)‖ (not over each vertex's
    /// own ‖T(x)‖, which is near 0 where a vertex sees almost nothing).
    pub max_vertex: f64,
}

impl Cpca {
    /// Compresses `data` (vertices × `dim`, vertex-major) into `clusters` clusters of
    /// `components` directions each. `clusters` is capped at the vertex count.
    pub fn new(data: &[f64], dim: usize, clusters: usize, components: usize) -> Result<Cpca, FactorError> {
        let vertices = data.len() / dim.max(1);
        let clusters = clusters.clamp(1, vertices.max(1));
        let mut cluster_of = initial_clusters(data, dim, clusters)?;
        let mut iterations = 0;
        let mut last_total = f64::INFINITY;
        while iterations < MAX_ITERATIONS {
            iterations += 1;
            let fits = (0..clusters)
                .map(|c| Fit::of(data, dim, components, &cluster_of, c as u32))
                .collect::<Result<Vec<_>, FactorError>>()?;
            let (best, errors) = assign(data, dim, &fits);
            let moved = best != cluster_of;
            cluster_of = best;
            refill_empty(&mut cluster_of, &errors, clusters);
            // Done when no vertex moves, or when a round gains less than CONVERGED of the error
            // (vertices trading places between clusters of nearly equal fit).
            let total: f64 = errors.iter().sum();
            if !moved || last_total - total <= CONVERGED * total {
                break;
            }
            last_total = total;
        }
        // The weights against the last fit of each vertex's cluster: fit once more if the last
        // round moved vertices (the fits must be of the final clusters).
        let fits = (0..clusters)
            .map(|c| Fit::of(data, dim, components, &cluster_of, c as u32))
            .collect::<Result<Vec<_>, FactorError>>()?;
        let weights = data.chunks_exact(dim).zip(&cluster_of).flat_map(|(x, &c)| fits[c as usize].weights(x)).collect();
        let means = fits.iter().flat_map(|f| f.mean.iter().copied()).collect();
        let bases = fits.iter().flat_map(|f| f.basis.iter().copied()).collect();
        Ok(Cpca { dim, clusters, components, means, bases, cluster_of, weights, iterations })
    }

    /// T̃ of vertex `v` (eq. 2).
    pub fn reconstruct(&self, v: usize) -> Vec<f64> {
        let (d, p) = (self.dim, self.components);
        let c = self.cluster_of[v] as usize;
        let mut out = self.means[c * d..(c + 1) * d].to_vec();
        for (k, w) in self.weights[v * p..(v + 1) * p].iter().enumerate() {
            let b = &self.bases[(c * p + k) * d..(c * p + k + 1) * d];
            for (o, bj) in out.iter_mut().zip(b) {
                *o += w * bj;
            }
        }
        out
    }

    /// The reconstruction error against the `data` it was made from.
    pub fn reconstruction(&self, data: &[f64]) -> Reconstruction {
        let (mut diff2, mut ref2, mut max_d2) = (0.0, 0.0, 0.0f64);
        let vertices = data.len() / self.dim;
        for (v, x) in data.chunks_exact(self.dim).enumerate() {
            let t = self.reconstruct(v);
            let d2: f64 = x.iter().zip(&t).map(|(a, b)| (a - b) * (a - b)).sum();
            diff2 += d2;
            ref2 += x.iter().map(|a| a * a).sum::<f64>();
            max_d2 = max_d2.max(d2);
        }
        let rms_norm2 = ref2 / vertices.max(1) as f64;
        let relative = |d2: f64| if ref2 > 0.0 { d2.sqrt() / rms_norm2.sqrt() } else { 0.0 };
        Reconstruction {
            relative_rms: if ref2 > 0.0 { (diff2 / ref2).sqrt() } else { 0.0 },
            max_vertex: relative(max_d2),
        }
    }
}

/// One cluster's mean and P leading directions (orthonormal rows, zero beyond its rank).
struct Fit {
    mean: Vec<f64>,
    basis: Vec<f64>,
    components: usize,
}

impl Fit {
    fn of(data: &[f64], dim: usize, components: usize, cluster_of: &[u32], c: u32) -> Result<Fit, FactorError> {
        let members: Vec<&[f64]> =
            data.chunks_exact(dim).zip(cluster_of).filter(|(_, &k)| k == c).map(|(x, _)| x).collect();
        let mut mean = vec![0.0; dim];
        for x in &members {
            for (m, v) in mean.iter_mut().zip(*x) {
                *m += v;
            }
        }
        let count = members.len().max(1) as f64;
        mean.iter_mut().for_each(|m| *m /= count);
        let mut basis = vec![0.0; components * dim];
        if components > 0 && members.len() > 1 {
            // The right singular vectors of the centred members, from the members themselves
            // when they are fewer than the dimension, else from their D × D Gram matrix (whose
            // singular vectors are the same directions): the smaller SVD either way.
            let centred = Mat::<f64>::from_fn(members.len(), dim, |i, j| members[i][j] - mean[j]);
            let v = if members.len() < dim {
                run_svd(centred.as_ref(), true)?.2
            } else {
                let gram = centred.transpose() * &centred;
                run_svd(gram.as_ref(), true)?.2
            };
            if let Some(v) = v {
                for p in 0..components.min(v.ncols()) {
                    for j in 0..dim {
                        basis[p * dim + j] = v[(j, p)];
                    }
                }
            }
        }
        Ok(Fit { mean, basis, components })
    }

    /// B_cᵀ (x − m_c).
    fn weights(&self, x: &[f64]) -> Vec<f64> {
        let dim = self.mean.len();
        (0..self.components)
            .map(|p| {
                let b = &self.basis[p * dim..(p + 1) * dim];
                b.iter().zip(x).zip(&self.mean).map(|((b, x), m)| b * (x - m)).sum()
            })
            .collect()
    }
}

/// Vertices per block of the assignment: a block's products with every cluster's mean and
/// directions stay a few MB.
const ASSIGN_BLOCK: usize = 256;

/// Each vertex's best cluster and its squared error there. Per block of vertices, one product
/// X_block [m_c b_c1 … b_cP]_c gives every x·m_c and x·b_cp at matrix-product speed; then
/// ‖x − m‖² = ‖x‖² − 2 x·m + ‖m‖² and (x − m)·b = x·b − m·b. The blocks are fixed and each
/// product runs sequentially, so the result does not depend on the thread count.
fn assign(data: &[f64], dim: usize, fits: &[Fit]) -> (Vec<u32>, Vec<f64>) {
    let vertices = data.len() / dim;
    let p = fits.first().map_or(0, |f| f.components);
    let columns = fits.len() * (p + 1);
    let targets = Mat::<f64>::from_fn(dim, columns, |j, col| {
        let (fit, k) = (&fits[col / (p + 1)], col % (p + 1));
        if k == 0 {
            fit.mean[j]
        } else {
            fit.basis[(k - 1) * dim + j]
        }
    });
    // ‖m_c‖² and m_c·b_cp.
    let constants: Vec<(f64, Vec<f64>)> = fits
        .iter()
        .map(|f| {
            let mm = f.mean.iter().map(|m| m * m).sum();
            let mb = f.basis.chunks_exact(dim).map(|b| b.iter().zip(&f.mean).map(|(b, m)| b * m).sum()).collect();
            (mm, mb)
        })
        .collect();
    let blocks: Vec<(Vec<u32>, Vec<f64>)> = (0..vertices.div_ceil(ASSIGN_BLOCK))
        .into_par_iter()
        .map(|b| {
            let range = b * ASSIGN_BLOCK..((b + 1) * ASSIGN_BLOCK).min(vertices);
            let x = Mat::<f64>::from_fn(range.len(), dim, |i, j| data[(range.start + i) * dim + j]);
            let mut g = Mat::<f64>::zeros(range.len(), columns);
            matmul(g.as_mut(), Accum::Replace, x.as_ref(), targets.as_ref(), 1.0, Par::Seq);
            range
                .clone()
                .enumerate()
                .map(|(i, v)| {
                    let xx: f64 = data[v * dim..(v + 1) * dim].iter().map(|a| a * a).sum();
                    let (mut best, mut least) = (0u32, f64::INFINITY);
                    for (c, (mm, mb)) in constants.iter().enumerate() {
                        let base = c * (p + 1);
                        let r2 = xx - 2.0 * g[(i, base)] + mm;
                        let kept: f64 = mb.iter().enumerate().map(|(k, m)| (g[(i, base + 1 + k)] - m).powi(2)).sum();
                        let e = (r2 - kept).max(0.0);
                        if e < least {
                            (best, least) = (c as u32, e);
                        }
                    }
                    (best, least)
                })
                .unzip()
        })
        .collect();
    let (mut best, mut errors) = (Vec::with_capacity(vertices), Vec::with_capacity(vertices));
    for (b, e) in blocks {
        best.extend(b);
        errors.extend(e);
    }
    (best, errors)
}

/// Clusters of equal counts along the data's first principal direction.
fn initial_clusters(data: &[f64], dim: usize, clusters: usize) -> Result<Vec<u32>, FactorError> {
    let vertices = data.len() / dim;
    let all = vec![0u32; vertices];
    let fit = Fit::of(data, dim, 1, &all, 0)?;
    let mut order: Vec<(f64, usize)> =
        data.chunks_exact(dim).enumerate().map(|(v, x)| (fit.weights(x)[0], v)).collect();
    order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut cluster_of = vec![0u32; vertices];
    for (rank, &(_, v)) in order.iter().enumerate() {
        cluster_of[v] = (rank * clusters / vertices.max(1)) as u32;
    }
    Ok(cluster_of)
}

/// Gives every empty cluster the vertex reconstructed worst (each vertex at most once).
fn refill_empty(cluster_of: &mut [u32], errors: &[f64], clusters: usize) {
    let mut counts = vec![0usize; clusters];
    for &c in cluster_of.iter() {
        counts[c as usize] += 1;
    }
    let mut worst: Vec<usize> = (0..errors.len()).collect();
    worst.sort_by(|&a, &b| errors[b].total_cmp(&errors[a]).then(a.cmp(&b)));
    let mut donors = worst.into_iter();
    for c in 0..clusters {
        if counts[c] == 0 {
            // Take a vertex from a cluster that keeps at least one member.
            for v in donors.by_ref() {
                let from = cluster_of[v] as usize;
                if counts[from] > 1 {
                    counts[from] -= 1;
                    counts[c] += 1;
                    cluster_of[v] = c as u32;
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on C affine subspaces of dimension P in D dimensions, far apart: CPCA with C
    /// clusters and P directions reconstructs them exactly, with fewer it cannot.
    fn subspaces(dim: usize, clusters: usize, components: usize, per: usize) -> Vec<f64> {
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut data = Vec::new();
        for c in 0..clusters {
            let origin: Vec<f64> = (0..dim).map(|_| 20.0 * c as f64 + rng.next_f64()).collect();
            let dirs: Vec<Vec<f64>> =
                (0..components).map(|_| (0..dim).map(|_| rng.next_f64() - 0.5).collect()).collect();
            for _ in 0..per {
                let w: Vec<f64> = (0..components).map(|_| 2.0 * rng.next_f64() - 1.0).collect();
                data.extend((0..dim).map(|j| origin[j] + (0..components).map(|p| w[p] * dirs[p][j]).sum::<f64>()));
            }
        }
        data
    }

    #[test]
    fn points_on_c_subspaces_of_dimension_p_are_reconstructed_exactly() {
        let (dim, clusters, components) = (12, 4, 3);
        let data = subspaces(dim, clusters, components, 50);
        let exact = Cpca::new(&data, dim, clusters, components).unwrap();
        let r = exact.reconstruction(&data);
        assert!(r.relative_rms < 1e-10 && r.max_vertex < 1e-9, "{r:?}");
        // One direction fewer, or one cluster fewer, leaves an error.
        for (c, p) in [(clusters, components - 1), (clusters - 1, components)] {
            let r = Cpca::new(&data, dim, c, p).unwrap().reconstruction(&data);
            assert!(r.relative_rms > 1e-3, "C {c} P {p}: {r:?}");
        }
    }

    #[test]
    fn the_weights_are_the_projections_and_more_clusters_never_hurt_here() {
        let dim = 9;
        let mut rng = crate::rng::SplitMix64::new(3);
        let data: Vec<f64> = (0..400 * dim).map(|i| ((i % dim) as f64).sin() + 0.3 * rng.next_f64()).collect();
        let mut last = f64::INFINITY;
        for clusters in [1, 2, 4, 8] {
            let cpca = Cpca::new(&data, dim, clusters, 2).unwrap();
            let r = cpca.reconstruction(&data);
            assert!(r.relative_rms <= last + 1e-12, "C {clusters}: {} after {last}", r.relative_rms);
            last = r.relative_rms;
            // w = Bᵀ(x − m) with orthonormal B: the reconstruction is the orthogonal projection,
            // so its residual is orthogonal to every direction of the vertex's cluster.
            for v in [0, 17, 399] {
                let c = cpca.cluster_of[v] as usize;
                let t = cpca.reconstruct(v);
                for p in 0..2 {
                    let b = &cpca.bases[(c * 2 + p) * dim..(c * 2 + p + 1) * dim];
                    let dot: f64 =
                        b.iter().zip(&data[v * dim..(v + 1) * dim]).zip(&t).map(|((b, x), t)| b * (x - t)).sum();
                    assert!(dot.abs() < 1e-12, "C {clusters} vertex {v} direction {p}: {dot:e}");
                }
            }
        }
    }
}
