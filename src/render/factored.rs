//! View-dependent relighting with the in-out factorization (Mahajan, Tseng & Ramamoorthi 2008,
//! eq. 3–4). `factor` gives ρ(ω_i, ω_o) ≈ Σ_k σ_k h_k(ω_o) g_k(ω_i) on its equal-solid-angle
//! grid (g_k, h_k L²-orthonormal), or ρ·max(cos θ_i, 0) when the cosine was folded into the
//! matrix (`factor-brdf --cosine`). With the transport of eq. 3,
//! T_k(x, ω_i) = V(x, ω_i) g_k(ω_i) max(cos θ_i, 0) — without the cosine when g_k holds it —
//! the radiance is
//!
//!   B(x, ω_o) = Σ_k σ_k h_k(ω_o) c_k(x),   c_k(x) = Σ_cells T_k(x, ω_c) L(ω_c) ΔΩ      (eq. 4)
//!
//! — the lighting projected onto the factors, K numbers per point and colour. For the sphere
//! (no visibility) c_k depends on the normal only and is tabulated on a lat-long grid of
//! normals; for meshes it is computed per vertex with visibility by ray casting (the
//! visibility bits are kept, so relighting under a new environment only redoes the sums) and
//! interpolated across triangles. ω_i, ω_o are expressed in the frame of [`sphere::frame_of`].

use super::{Hit, Scene, Shade};
use crate::envmap::EnvMap;
use crate::factor::{Factorization, Grid};
use crate::prefilter::shrm::texel_frame;
use crate::progress::Progress;
use crate::sphere::{self, LatLong};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Where the coefficient vectors c_k live.
#[derive(Clone, Debug)]
enum Support {
    /// A W×H lat-long table of normals (sphere).
    NormalTable { width: usize, height: usize },
    /// One per mesh vertex.
    Vertices,
}

/// Per-point transport: the frames, and visibility bits per grid cell for meshes.
#[derive(Clone, Debug)]
pub struct Transport {
    support: Support,
    frames: Vec<DMat3>,
    /// `cells` bits per point (1 = visible), empty for the sphere.
    visible: Vec<u64>,
    words: usize,
    triangles: Vec<[u32; 3]>,
}

impl Transport {
    /// The sphere: a `width`×`height` lat-long table of normals, no visibility.
    pub fn sphere(width: usize, height: usize) -> Self {
        let frames = (0..height).flat_map(|y| (0..width).map(move |x| texel_frame(width, height, x, y))).collect();
        Transport {
            support: Support::NormalTable { width, height },
            frames,
            visible: Vec::new(),
            words: 0,
            triangles: Vec::new(),
        }
    }

    /// A mesh: per-vertex frames and visibility of every grid cell by ray casting.
    pub fn mesh(scene: &Scene, grid: &Grid, progress: &dyn Progress) -> Self {
        let Scene::Mesh(mesh) = scene else {
            return Transport::sphere(64, 32);
        };
        let cells = grid.len();
        let words = cells.div_ceil(64);
        let frames: Vec<DMat3> = mesh.normals.iter().map(|n| sphere::frame_of(*n)).collect();
        progress.start("visibility", mesh.positions.len() as u64);
        let visible: Vec<u64> = (0..mesh.positions.len())
            .into_par_iter()
            .flat_map_iter(|v| {
                let mut bits = vec![0u64; words];
                let (p, n) = (mesh.positions[v], mesh.normals[v]);
                for c in 0..cells {
                    let d = frames[v] * grid.direction(c);
                    if !scene.occluded(p, n, d) {
                        bits[c / 64] |= 1 << (c % 64);
                    }
                }
                progress.advance(1);
                bits
            })
            .collect();
        progress.finish();
        Transport { support: Support::Vertices, frames, visible, words, triangles: mesh.triangles.clone() }
    }

    /// Number of points (normals or vertices).
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Fraction of (point, cell) pairs that are visible (1 for the sphere).
    pub fn visible_fraction(&self, cells: usize) -> f64 {
        if self.visible.is_empty() {
            return 1.0;
        }
        let ones: u64 = self.visible.iter().map(|w| w.count_ones() as u64).sum();
        ones as f64 / (self.len() * cells) as f64
    }
}

/// The factored shader: σ_k, h_k and the projected lighting c_k per point.
pub struct Factored {
    sigma: Vec<f64>,
    /// h_k on the grid's n² cells, then two entries: the mean of the first ring of cells (the
    /// value at the pole θ = 0) and of the last ring (θ = π on the sphere).
    h: Vec<Vec<f64>>,
    grid: Grid,
    transport: Transport,
    /// Whether the transport applies max(cos θ_i, 0) (false when the factors already hold it).
    cosine: bool,
    /// c_k per point: `coeffs[(point * K + k)]` RGB.
    coeffs: Vec<[f64; 3]>,
}

impl Factored {
    /// Keeps the first `terms` terms of `f` and projects `env` onto them at every point.
    /// `cosine_in_factors`: the factorization was of ρ·max(cos θ_i, 0) (else the transport
    /// applies the cosine). `sub`×`sub` lighting samples per grid cell.
    pub fn new(
        f: &Factorization,
        terms: usize,
        cosine_in_factors: bool,
        transport: Transport,
        env: &EnvMap,
        sub: usize,
    ) -> Self {
        let k = terms.min(f.g.len());
        let mut s = Factored {
            sigma: f.singular_values[..k].to_vec(),
            h: f.h[..k].iter().map(|h| with_pole_values(h, f.grid.n)).collect(),
            grid: f.grid,
            transport,
            cosine: !cosine_in_factors,
            coeffs: Vec::new(),
        };
        s.relight(&f.g, env, sub);
        s
    }

    /// Number of terms K.
    pub fn terms(&self) -> usize {
        self.sigma.len()
    }

    /// Re-projects a new environment onto the factors (the per-frame relighting step).
    pub fn relight(&mut self, g: &[Vec<f64>], env: &EnvMap, sub: usize) {
        self.coeffs = project(&g[..self.terms()], &self.grid, &self.transport, self.cosine, env, sub.max(1));
    }
}

/// Taps (index into `h`, weight) of ω on the factor grid, the same for every k: bilinear
/// between cell centres in (cos θ, φ), φ wrapping. Between the pole and the first ring of
/// centres the ring's value blends into the pole value, the ring's mean: φ means nothing at
/// the pole, and a bilinear lookup there would take h along whatever φ rounding gives (a
/// dark dot where the view meets the normal). The hemisphere's horizon side clamps.
fn h_taps(grid: &Grid, wo: DVec3) -> [(usize, f64); 5] {
    let n = grid.n;
    let span = match grid.domain {
        crate::factor::Domain::Sphere => 2.0,
        crate::factor::Domain::Hemisphere => 1.0,
    };
    let z = wo.z.clamp(-1.0, 1.0).max(1.0 - span);
    let raw = (1.0 - z) / span * n as f64 - 0.5;
    let fj = raw.clamp(0.0, (n - 1) as f64);
    // Weight of the pole value: 1 at the pole, 0 at the ring of centres half a bin away.
    let pole = match grid.domain {
        _ if raw < 0.0 => (n * n, -2.0 * raw),
        crate::factor::Domain::Sphere if raw > (n - 1) as f64 => (n * n + 1, 2.0 * (raw - (n - 1) as f64)),
        _ => (n * n, 0.0),
    };
    let ring = 1.0 - pole.1;
    let fk = sphere::phi(wo) / (2.0 * PI) * n as f64 - 0.5;
    let k0f = fk.floor();
    let (tk, tj) = (fk - k0f, fj - fj.floor());
    let k0 = (k0f as isize).rem_euclid(n as isize) as usize;
    let k1 = (k0 + 1) % n;
    let j0 = fj.floor() as usize;
    let j1 = (j0 + 1).min(n - 1);
    [
        (j0 * n + k0, ring * (1.0 - tj) * (1.0 - tk)),
        (j0 * n + k1, ring * (1.0 - tj) * tk),
        (j1 * n + k0, ring * tj * (1.0 - tk)),
        (j1 * n + k1, ring * tj * tk),
        pole,
    ]
}

/// h on the n² cells followed by the means of its first and last rings of n cells.
fn with_pole_values(h: &[f64], n: usize) -> Vec<f64> {
    let mean = |ring: &[f64]| ring.iter().sum::<f64>() / n as f64;
    let mut out = h.to_vec();
    out.push(mean(&h[..n]));
    out.push(mean(&h[h.len() - n..]));
    out
}

/// Points per block of the projection: the block's lighting matrix (cells × 3·BLOCK) stays
/// small (1024 cells: 1.5 MB) while the product with G is large enough to run at GEMM speed.
const BLOCK: usize = 64;

/// c_k = Σ_cells V g_k [max(cos θ, 0)] L ΔΩ at every point (eq. 4). For a block of points the
/// lighting of every cell is gathered once into a cells × (3·points) matrix Λ (zero where the
/// cell is occluded), then C = G Λ with G the K × cells matrix of g_k: one dense product per
/// block instead of K·3 dot products per point. Blocks are fixed and each product runs
/// sequentially, so the result does not depend on the number of threads.
fn project(
    g: &[Vec<f64>],
    grid: &Grid,
    transport: &Transport,
    cosine: bool,
    env: &EnvMap,
    sub: usize,
) -> Vec<[f64; 3]> {
    let cells = grid.len();
    // Each cell's lighting is the mean of sub×sub samples uniform in (cos θ, φ) inside it (equal
    // solid angles), a box prefilter of the environment: point samples alias bright sources.
    let n = grid.n;
    let span = match grid.domain {
        crate::factor::Domain::Sphere => 2.0,
        crate::factor::Domain::Hemisphere => 1.0,
    };
    let dirs: Vec<DVec3> = (0..cells)
        .flat_map(|c| {
            let (j, k) = (c / n, c % n);
            (0..sub * sub).map(move |s| {
                let z = 1.0 - (j as f64 + ((s / sub) as f64 + 0.5) / sub as f64) * span / n as f64;
                let phi = (k as f64 + ((s % sub) as f64 + 0.5) / sub as f64) * 2.0 * PI / n as f64;
                let r = (1.0 - z * z).max(0.0).sqrt();
                DVec3::new(r * phi.cos(), r * phi.sin(), z)
            })
        })
        .collect();
    let weight = grid.cell_solid_angle() / (sub * sub) as f64;
    let kk = g.len();
    let g_mat = Mat::<f64>::from_fn(kk, cells, |k, c| g[k][c]);
    let points = transport.len();
    let blocks: Vec<Vec<[f64; 3]>> = (0..points.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            let range = b * BLOCK..((b + 1) * BLOCK).min(points);
            let width = range.len();
            // Column 3·i + ch holds channel ch of point range.start + i.
            let mut light = Mat::<f64>::zeros(cells, 3 * width);
            for (i, pt) in range.clone().enumerate() {
                let frame = transport.frames[pt];
                for c in 0..cells {
                    if !transport.visible.is_empty()
                        && transport.visible[pt * transport.words + c / 64] & (1 << (c % 64)) == 0
                    {
                        continue;
                    }
                    let mut l = [0.0f64; 3];
                    for d in &dirs[c * sub * sub..(c + 1) * sub * sub] {
                        let v = env.lookup(frame * *d);
                        let w = if cosine { d.z.max(0.0) } else { 1.0 };
                        for ch in 0..3 {
                            l[ch] += w * v[ch] as f64;
                        }
                    }
                    for ch in 0..3 {
                        light[(c, 3 * i + ch)] = l[ch] * weight;
                    }
                }
            }
            let mut out = Mat::<f64>::zeros(kk, 3 * width);
            matmul(out.as_mut(), Accum::Replace, g_mat.as_ref(), light.as_ref(), 1.0, Par::Seq);
            (0..width)
                .flat_map(|i| (0..kk).map(move |k| (i, k)))
                .map(|(i, k)| [out[(k, 3 * i)], out[(k, 3 * i + 1)], out[(k, 3 * i + 2)]])
                .collect()
        })
        .collect();
    blocks.into_iter().flatten().collect()
}

impl Shade for Factored {
    fn shade(&self, hit: &Hit, wo: DVec3) -> [f64; 3] {
        let kk = self.terms();
        // Interpolation weights over points.
        let taps: Vec<(usize, f64)> = match (&self.transport.support, hit.triangle) {
            (Support::Vertices, Some((t, u, v))) => {
                let [a, b, c] = self.transport.triangles[t].map(|i| i as usize);
                vec![(a, 1.0 - u - v), (b, u), (c, v)]
            }
            (Support::NormalTable { width, height }, _) => LatLong::new(*width, *height).taps(hit.n).to_vec(),
            _ => return [0.0; 3],
        };
        let wo_l = sphere::frame_of(hit.n).transpose() * wo;
        let wo_taps = h_taps(&self.grid, wo_l);
        let mut out = [0.0; 3];
        for k in 0..kk {
            let h = &self.h[k];
            let hk = self.sigma[k] * wo_taps.iter().map(|&(i, w)| w * h[i]).sum::<f64>();
            for &(p, w) in &taps {
                let c = self.coeffs[p * kk + k];
                for ch in 0..3 {
                    out[ch] += hk * w * c[ch];
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::factor::Domain;

    /// h_k through the taps, as `shade` evaluates it.
    fn eval(grid: &Grid, h: &[f64], wo: DVec3) -> f64 {
        let h = with_pole_values(h, grid.n);
        h_taps(grid, wo.normalize()).iter().map(|&(i, w)| w * h[i]).sum()
    }

    #[test]
    fn h_is_continuous_at_the_poles_and_exact_at_cell_centres() {
        for domain in [Domain::Hemisphere, Domain::Sphere] {
            let grid = Grid { n: 16, domain };
            // An m = 1 factor, cos φ · sin θ, sampled at the cell centres, and an m = 0 one.
            let m1: Vec<f64> = (0..grid.len()).map(|c| grid.direction(c).x).collect();
            let m0: Vec<f64> = (0..grid.len()).map(|c| grid.direction(c).z).collect();
            // At a cell centre the taps return the sample.
            for c in [0, 17, 100, grid.len() - 1] {
                assert!((eval(&grid, &m1, grid.direction(c)) - m1[c]).abs() < 1e-12, "{domain:?} cell {c}");
            }
            // Approaching the pole from any φ, the m = 1 factor goes to 0 (its mean over the
            // ring) and the m = 0 factor to its ring value: no dependence on φ at the pole.
            for phi in [0.1, 1.7, 3.0, 5.9] {
                let near = DVec3::new(1e-9 * f64::cos(phi), 1e-9 * f64::sin(phi), 1.0);
                assert!(eval(&grid, &m1, near).abs() < 1e-6, "{domain:?} φ {phi}");
                assert!((eval(&grid, &m0, near) - m0[0]).abs() < 1e-12);
            }
            // Half-way between the pole and the first ring of centres: half of each.
            let theta0 = grid.cos_theta(0).acos();
            let z = 0.5 * (1.0 + grid.cos_theta(0));
            let wo = DVec3::new((1.0 - z * z).sqrt(), 0.0, z);
            let ring = eval(&grid, &m1, DVec3::new(theta0.sin(), 0.0, theta0.cos()));
            assert!((eval(&grid, &m1, wo) - 0.5 * ring).abs() < 1e-9, "{domain:?}");
        }
        // On the sphere the south pole works the same way.
        let grid = Grid { n: 16, domain: Domain::Sphere };
        let m1: Vec<f64> = (0..grid.len()).map(|c| grid.direction(c).y).collect();
        assert!(eval(&grid, &m1, DVec3::new(1e-9, 2e-9, -1.0)).abs() < 1e-6);
    }
}
