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
//! normals, whose rings are turns of one another about +Z (the lighting is gathered once per
//! ring and shifted, [`RingLighting`]); for meshes it is computed per vertex with visibility by ray casting (the
//! visibility bits are kept, so relighting under a new environment only redoes the sums) and
//! interpolated across triangles. ω_i, ω_o are expressed in the normal's frame: the table's
//! R_z(φ)·R_y(θ) ([`sphere::frame_of`], whose rings are the turns above) for the sphere; for
//! meshes the shortest-arc turn of +Z onto the normal ([`sphere::shortest_arc_frame`]), whose
//! twist about the normal varies smoothly wherever the normal is not −Z, because c_k of
//! neighbouring vertices are blended before the sum over k (`transfer::glossy`, "The frame").

use super::{Hit, Scene, Shade};
use crate::envmap::EnvMap;
use crate::factor::{CellSamples, Factorization, Grid};
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
        let frames: Vec<DMat3> = mesh.normals.iter().map(|n| sphere::shortest_arc_frame(*n)).collect();
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
    fn len(&self) -> usize {
        self.frames.len()
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

    /// The shader of a mesh whose c_k per vertex (`coeffs[vertex * K + k]`, σ_k folded in) were
    /// computed elsewhere: relit from a glossy `transfer` bake, c_k = Σ_j T_kj L_j.
    pub fn from_vertex_coefficients(
        grid: Grid,
        h: &[Vec<f64>],
        triangles: Vec<[u32; 3]>,
        coeffs: Vec<[f64; 3]>,
    ) -> Self {
        Factored {
            sigma: vec![1.0; h.len()],
            h: h.iter().map(|h| with_pole_values(h, grid.n)).collect(),
            grid,
            transport: Transport {
                support: Support::Vertices,
                frames: Vec::new(),
                visible: Vec::new(),
                words: 0,
                triangles,
            },
            cosine: false,
            coeffs,
        }
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
    let (n, span) = (grid.n, grid.span());
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

/// The environment as a lat-long map whose width is a multiple of the normal table's, for the
/// sphere's rings. The table's frames are R_z(φ_x)·R_y(θ_y) ([`texel_frame`]), and
/// φ_x − φ_0 = 2πx/W is a whole number of the map's columns: every lighting sample of normal
/// (x, y) is the sample of normal (0, y) turned about +Z by x·(map width / W) columns, at the
/// same row and with the same bilinear weights. So the directions, their (θ, φ) and their
/// bilinear taps are computed once per ring (cells·sub² of them) instead of once per normal,
/// and each normal's samples are gathers at shifted columns: the same sum as looking every
/// sample up, without the trigonometry and without the layout's own lookup.
///
/// A lat-long map of such a width is used as it is, so the result equals the direct gather to
/// rounding. Any other map is first resampled (point samples at the texel centres, which is the
/// bilinear lookup of the source there) to a lat-long map at least twice as fine as the source
/// (2·√(2N) columns for N texels, at most [`MAX_RING_MAP_WIDTH`] rounded up to a multiple of W):
/// the extra blur is a tent of half a source texel, far below a cell
/// (`tests::rings_match_the_direct_gather`).
struct RingLighting<'a> {
    map: std::borrow::Cow<'a, crate::io::RgbImage>,
    /// Columns of the map per column of the normal table.
    step: usize,
}

/// Widest lat-long map the rings resample a map into (4096 × 2048 texels, 100 MB): finer than
/// the lighting samples of the finest grid and most samples per cell (256 bins, 8 × 8 samples
/// per cell: 2048 samples around the hemisphere). A cap on a working resolution, not a ceiling on
/// input: a wider map is accepted and resampled to this width.
const MAX_RING_MAP_WIDTH: f64 = 4096.0;

/// One lighting sample of a ring: the bilinear taps of its direction in the ring's first normal,
/// each tap's weight the bilinear weight times the sample's.
#[derive(Clone, Copy)]
struct RingTap {
    /// Offsets of the two rows (y·width) and the first column at shift 0.
    row0: u32,
    row1: u32,
    column: u32,
    /// Weights of (row0, column), (row0, column + 1), (row1, column), (row1, column + 1).
    weights: [f32; 4],
}

impl<'a> RingLighting<'a> {
    fn new(env: &'a EnvMap, table_width: usize) -> Self {
        let img = env.image();
        if env.layout() == crate::envmap::Layout::LatLong && img.width % table_width == 0 {
            return RingLighting { map: std::borrow::Cow::Borrowed(img), step: img.width / table_width };
        }
        let fine = (2.0 * (2.0 * env.texel_count() as f64).sqrt()).min(MAX_RING_MAP_WIDTH);
        let step = (fine / table_width as f64).ceil().max(1.0) as usize;
        let width = step * table_width;
        let height = width.div_ceil(2);
        let map = crate::envmap::resample(env, crate::envmap::Layout::LatLong, width, height, 1)
            .expect("a lat-long map of at least 1 × 1 texels")
            .image()
            .clone();
        RingLighting { map: std::borrow::Cow::Owned(map), step }
    }

    /// The taps of every sample of every cell for the normals of row `y` of a `table` grid.
    fn ring(&self, samples: &CellSamples, table: LatLong, y: usize) -> Vec<RingTap> {
        let (w, h) = (self.map.width, self.map.height);
        let grid = LatLong::new(w, h);
        let frame = texel_frame(table.width, table.height, 0, y);
        samples
            .dirs
            .iter()
            .zip(&samples.weights)
            .map(|(d, &weight)| {
                // The taps of `EnvMap::lookup` on a lat-long map (`bilinear_taps`, x wrapping).
                let (px, py) = grid.position(frame * *d);
                let fy = (py - 0.5).clamp(0.0, (h - 1) as f64);
                let y0 = fy.floor() as usize;
                let y1 = (y0 + 1).min(h - 1);
                let fx = px - 0.5;
                let fl = fx.floor();
                let column = (fl as i64).rem_euclid(w as i64) as u32;
                let (tx, ty) = (fx - fl, fy - y0 as f64);
                let weights = [(1.0 - tx) * (1.0 - ty), tx * (1.0 - ty), (1.0 - tx) * ty, tx * ty];
                RingTap {
                    row0: (y0 * w) as u32,
                    row1: (y1 * w) as u32,
                    column,
                    weights: weights.map(|b| (b * weight) as f32),
                }
            })
            .collect()
    }

    /// Σ weight · L over the taps of one cell, for the normal `x` columns of the table along.
    /// The sum runs in single precision, as the lookups do (a cell has sub² ≤ 64 samples).
    #[inline]
    fn gather(&self, taps: &[RingTap], x: usize) -> [f64; 3] {
        let w = self.map.width;
        let px = &self.map.pixels;
        let shift = x * self.step;
        let mut l = [0.0f32; 3];
        for t in taps {
            let mut xa = t.column as usize + shift;
            if xa >= w {
                xa -= w;
            }
            let xb = if xa + 1 == w { 0 } else { xa + 1 };
            let (r0, r1) = (t.row0 as usize, t.row1 as usize);
            let [a, b, c, d] = [px[r0 + xa], px[r0 + xb], px[r1 + xa], px[r1 + xb]];
            let [wa, wb, wc, wd] = t.weights;
            for ch in 0..3 {
                l[ch] += wa * a[ch] + wb * b[ch] + wc * c[ch] + wd * d[ch];
            }
        }
        l.map(f64::from)
    }
}

/// c_k = Σ_cells V g_k [max(cos θ, 0)] L ΔΩ at every point (eq. 4). For a block of points the
/// lighting of every cell is gathered once into a cells × (3·points) matrix Λ (zero where the
/// cell is occluded), then C = G Λ with G the K × cells matrix of g_k: one dense product per
/// block instead of K·3 dot products per point. Blocks are fixed and each product runs
/// sequentially, so the result does not depend on the number of threads. The sphere's table
/// gathers ring by ring ([`RingLighting`]); meshes look every sample up in their own frames.
fn project(
    g: &[Vec<f64>],
    grid: &Grid,
    transport: &Transport,
    cosine: bool,
    env: &EnvMap,
    sub: usize,
) -> Vec<[f64; 3]> {
    let samples = CellSamples::new(grid, sub, cosine);
    let g_mat = Mat::<f64>::from_fn(g.len(), grid.len(), |k, c| g[k][c]);
    match transport.support {
        Support::NormalTable { width, height } if transport.visible.is_empty() => {
            let rings = RingLighting::new(env, width);
            let table = LatLong::new(width, height);
            let per_ring: Vec<Vec<[f64; 3]>> = (0..height)
                .into_par_iter()
                .map(|y| {
                    let taps = rings.ring(&samples, table, y);
                    let per_cell = samples.per_cell;
                    (0..width.div_ceil(BLOCK))
                        .flat_map(|b| {
                            let xs = b * BLOCK..((b + 1) * BLOCK).min(width);
                            project_block(&g_mat, xs, |x, c| rings.gather(&taps[c * per_cell..(c + 1) * per_cell], x))
                        })
                        .collect()
                })
                .collect();
            per_ring.into_iter().flatten().collect()
        }
        _ => project_direct(&g_mat, &samples, transport, env),
    }
}

/// The projection with every sample looked up in its point's frame: meshes, and the reference
/// for the sphere's ring path.
fn project_direct(g_mat: &Mat<f64>, samples: &CellSamples, transport: &Transport, env: &EnvMap) -> Vec<[f64; 3]> {
    let points = transport.len();
    let blocks: Vec<Vec<[f64; 3]>> = (0..points.div_ceil(BLOCK))
        .into_par_iter()
        .map(|b| {
            project_block(g_mat, b * BLOCK..((b + 1) * BLOCK).min(points), |pt, c| {
                let visible = transport.visible.is_empty()
                    || transport.visible[pt * transport.words + c / 64] & (1 << (c % 64)) != 0;
                let mut l = [0.0f64; 3];
                if visible {
                    let frame = transport.frames[pt];
                    for (d, &w) in samples.of_cell(c) {
                        let v = env.lookup(frame * *d);
                        for ch in 0..3 {
                            l[ch] += w * v[ch] as f64;
                        }
                    }
                }
                l
            })
        })
        .collect();
    blocks.into_iter().flatten().collect()
}

/// C = G Λ for the points of `range`, Λ's entry for (point, cell) from `light`; c_k per point,
/// point-major.
fn project_block(
    g_mat: &Mat<f64>,
    range: std::ops::Range<usize>,
    light: impl Fn(usize, usize) -> [f64; 3],
) -> Vec<[f64; 3]> {
    let (kk, cells) = (g_mat.nrows(), g_mat.ncols());
    let width = range.len();
    // Column 3·i + ch holds channel ch of point range.start + i.
    let mut lambda = Mat::<f64>::zeros(cells, 3 * width);
    for (i, pt) in range.enumerate() {
        for c in 0..cells {
            let l = light(pt, c);
            for ch in 0..3 {
                lambda[(c, 3 * i + ch)] = l[ch];
            }
        }
    }
    let mut out = Mat::<f64>::zeros(kk, 3 * width);
    matmul(out.as_mut(), Accum::Replace, g_mat.as_ref(), lambda.as_ref(), 1.0, Par::Seq);
    (0..width)
        .flat_map(|i| (0..kk).map(move |k| (i, k)))
        .map(|(i, k)| [out[(k, 3 * i)], out[(k, 3 * i + 1)], out[(k, 3 * i + 2)]])
        .collect()
}

impl Shade for Factored {
    fn shade(&self, hit: &Hit, wo: DVec3) -> [f64; 3] {
        let kk = self.terms();
        // Interpolation weights over points.
        let (taps, frame): (Vec<(usize, f64)>, DMat3) = match (&self.transport.support, hit.triangle) {
            (Support::Vertices, Some((t, u, v))) => {
                let [a, b, c] = self.transport.triangles[t].map(|i| i as usize);
                (vec![(a, 1.0 - u - v), (b, u), (c, v)], sphere::shortest_arc_frame(hit.n))
            }
            (Support::NormalTable { width, height }, _) => {
                (LatLong::new(*width, *height).taps(hit.n).to_vec(), sphere::frame_of(hit.n))
            }
            _ => return [0.0; 3],
        };
        let wo_l = frame.transpose() * wo;
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

    /// A lat-long map of radiance `f(ω)` at its texel centres.
    fn latlong_of(width: usize, height: usize, f: impl Fn(DVec3) -> [f32; 3]) -> EnvMap {
        let grid = LatLong::new(width, height);
        EnvMap::latlong(crate::io::RgbImage::from_fn(width, height, |x, y| f(grid.texel_direction(x, y)))).unwrap()
    }

    /// A lit sky with a bright patch off every axis: neither symmetric about +Z nor in φ.
    fn patchy(d: DVec3) -> [f32; 3] {
        let patch = (40.0 * (d.dot(DVec3::new(0.5, -0.6, 0.62).normalize()) - 1.0)).exp();
        let d = d.as_vec3();
        [1.0 + d.x + 8.0 * patch as f32, 0.5 + 0.4 * d.y * d.z, 0.3 + 0.2 * d.z + (3.0 * d.x).sin().abs()]
    }

    /// Three factors with structure in φ (g = 1, cos φ, a cell-wise pattern).
    fn factors(grid: &Grid) -> Vec<Vec<f64>> {
        let c = |f: &dyn Fn(usize) -> f64| (0..grid.len()).map(f).collect::<Vec<f64>>();
        vec![c(&|_| 1.0), c(&|i| grid.direction(i).x), c(&|i| ((i * 7919) % 13) as f64 / 13.0 - 0.5)]
    }

    fn max_relative_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
        let scale = a.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        a.iter().flatten().zip(b.iter().flatten()).map(|(x, y)| (x - y).abs() / scale).fold(0.0, f64::max)
    }

    #[test]
    fn rings_match_the_direct_gather() {
        // The sphere's ring path against every sample looked up in its normal's own frame,
        // the projection meshes use. A lat-long map whose width is a multiple of the table's
        // is gathered as it is: equal to rounding (single-precision sums). Turning a ring the
        // wrong way, or by the wrong number of columns, moves the patch and fails this.
        let grid = Grid { n: 12, domain: crate::factor::Domain::Hemisphere };
        let g = factors(&grid);
        for (table, map) in [((16, 8), (64, 32)), ((12, 6), (96, 48)), ((10, 5), (40, 20))] {
            let env = latlong_of(map.0, map.1, patchy);
            let transport = Transport::sphere(table.0, table.1);
            for (sub, cosine) in [(1, true), (3, true), (2, false)] {
                let samples = CellSamples::new(&grid, sub, cosine);
                let g_mat = Mat::<f64>::from_fn(g.len(), grid.len(), |k, c| g[k][c]);
                let direct = project_direct(&g_mat, &samples, &transport, &env);
                let rings = project(&g, &grid, &transport, cosine, &env, sub);
                let d = max_relative_difference(&direct, &rings);
                eprintln!("table {table:?}, map {map:?}, sub {sub}: rings vs direct {d:.1e}");
                assert!(d < 1e-6, "table {table:?}, map {map:?}, sub {sub}: {d:e}");
            }
        }
        // Any other map (here an angular probe, and a lat-long map of another width) is
        // resampled to a finer lat-long map first: close, not equal.
        let fine = latlong_of(256, 128, patchy);
        let probe = crate::envmap::resample(&fine, crate::envmap::Layout::Angular, 128, 128, 2).unwrap();
        let odd = latlong_of(100, 50, patchy);
        let transport = Transport::sphere(16, 8);
        let samples = CellSamples::new(&grid, 3, true);
        let g_mat = Mat::<f64>::from_fn(g.len(), grid.len(), |k, c| g[k][c]);
        for env in [probe, odd] {
            let direct = project_direct(&g_mat, &samples, &transport, &env);
            let rings = project(&g, &grid, &transport, true, &env, 3);
            let d = max_relative_difference(&direct, &rings);
            eprintln!("{:?} {}x{}: rings vs direct {d:.1e}", env.layout(), env.image().width, env.image().height);
            assert!(d < 2e-3 && d > 0.0, "{:?}: {d:e}", env.layout());
        }
    }

    #[test]
    fn a_linear_environment_projects_to_its_closed_form() {
        // With g = 1 and the cosine in the transport, c = ∫_{n·ω>0} (n·ω) L(ω) dω. For
        // L(ω) = a + b·(v·ω), ∫ (n·ω) dω = π and ∫ (n·ω) ω dω = (2π/3) n over the hemisphere
        // about n, so c(n) = aπ + (2π/3) b (v·n): an oracle independent of the gather, for
        // the sphere's rings and for the direct lookups meshes use alike.
        let (a, b, v) = (1.0, 0.5, DVec3::new(0.6, -0.3, 0.7).normalize());
        let grid = Grid { n: 48, domain: crate::factor::Domain::Hemisphere };
        let g = vec![vec![1.0; grid.len()]];
        let samples = CellSamples::new(&grid, 2, true);
        let g_mat = Mat::<f64>::from_fn(1, grid.len(), |_, _| 1.0);
        let env = latlong_of(512, 256, |d| [(a + b * v.dot(d)) as f32, a as f32, (a - b * v.dot(d)) as f32]);
        let (w, h) = (16, 8);
        let transport = Transport::sphere(w, h);
        let rings = project(&g, &grid, &transport, true, &env, 2);
        let direct = project_direct(&g_mat, &samples, &transport, &env);
        for (pt, (r, d)) in rings.iter().zip(&direct).enumerate() {
            let n = LatLong::new(w, h).texel_direction(pt % w, pt / w);
            let want = [a * PI + 2.0 * PI / 3.0 * b * v.dot(n), a * PI, a * PI - 2.0 * PI / 3.0 * b * v.dot(n)];
            for ch in 0..3 {
                // The midpoint rule over 48 bins in cos θ and the map's bilinear
                // interpolation each miss by well under 10⁻³ π.
                assert!((r[ch] - want[ch]).abs() < 2e-3, "normal {pt} ch {ch}: rings {} vs {}", r[ch], want[ch]);
                assert!((d[ch] - want[ch]).abs() < 2e-3, "normal {pt} ch {ch}: direct {} vs {}", d[ch], want[ch]);
            }
        }
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
