//! Interreflected diffuse transfer (Sloan, Kautz & Snyder 2002, eq. 9 and §5's interreflection
//! passes).
//!
//! Light that reaches x after bounding off the object itself: the radiance arriving from ω is
//! the outgoing radiance of the point y the ray x → ω hits, which is itself a dot product with
//! the lighting, T(y) · L. So the b-th bounce's transfer is
//!
//!   T^b(x) = (ρ/π) ∫ (1 − V(x, ω)) max(n·ω, 0) T^{b−1}(y(x, ω)) dω       (Sloan et al. 2002, eq. 9)
//!
//! with T^0 the shadowed transfer (eq. 8), and the interreflected transfer is T^0 + Σ_{b=1..B} T^b.
//! With the cosine-weighted stratified rays of [`super::directions::Stratified`] (density
//! cos θ/π) the estimator is T^b(x) ≈ (ρ/N) Σ_{rays that hit} T^{b−1}(y), T^{b−1}(y)
//! interpolated from the hit triangle's vertices by its barycentrics, as §5 does.
//!
//! **Back faces.** A ray that reaches the *back* of a surface still blocks the lighting, but
//! contributes nothing to the bounce: T^{b−1}(y) is the radiance leaving the front, and a
//! diffuse sheet's back is not lit by its front. Open meshes seen from behind, and rays that
//! slip through cracks into a closed mesh's inside, are the cases. The front is told by the hit
//! triangle's *geometric* normal, turned to the side of its vertex normals (n_f · ω ≥ 0: back):
//! the interpolated normal would call a grazing ray's hit on a neighbouring facet of a concave,
//! tessellated surface a back hit, since near the ray's origin it is nearly the origin's normal,
//! which the ray leaves along.
//!
//! **The hits are traced once.** Every bounce gathers over the same rays, so the closest hit
//! of each ray (triangle, barycentrics) is recorded in the first pass and reused by every
//! bounce, which then costs a few multiply-adds per hit instead of a ray cast. Only front hits
//! are kept, in 8 bytes each (the triangle as u32, u and v quantized to 16 bits: an
//! interpolation weight off by at most 2⁻¹⁷, far below the rays' Monte Carlo error). When the
//! worst case (every ray of every vertex a hit) would pass [`HIT_BUDGET`], the hits are traced
//! again in every bounce instead: the same rays through the same tree give the same hits, so
//! both ways give the same bits.

use super::albedo::Reflectance;
use super::diffuse::{LocalBasis, PointTransfer};
use super::directions::Stratified;
use super::visibility::{barycentrics, Occluders};
use crate::mesh::Mesh;
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;

/// Most bytes of recorded hits; past it every bounce traces its rays again.
pub const HIT_BUDGET: usize = 1 << 30;
/// Vertices per parallel work item (and per unit of progress).
const CHUNK: usize = 64;
/// The quantization of the barycentric weights: u = q / 65535.
const QUANT: f64 = 65535.0;

/// One ray's hit on the front of a surface: the mesh's triangle and the barycentric weights of
/// its vertices 1 and 2, quantized (u + v ≤ 1 exactly, so the three weights sum to one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrontHit {
    triangle: u32,
    u: u16,
    v: u16,
}

impl FrontHit {
    fn new(triangle: u32, u: f64, v: f64) -> FrontHit {
        let qu = (u * QUANT).round().clamp(0.0, QUANT) as u16;
        let qv = ((v * QUANT).round() as u16).min(u16::MAX - qu);
        FrontHit { triangle, u: qu, v: qv }
    }

    /// The weights (w0, w1, w2) of the triangle's vertices, summing to one.
    fn weights(&self) -> [f64; 3] {
        let (u, v) = (self.u as f64 / QUANT, self.v as f64 / QUANT);
        [(u16::MAX - self.u - self.v) as f64 / QUANT, u, v]
    }

    /// Adds the per-vertex `values` (`out.len()` per vertex) interpolated at the hit to `out`:
    /// Σ_j w_j values(v_j), vertices in the triangle's order.
    pub fn gather(&self, triangles: &[[u32; 3]], values: &[f64], out: &mut [f64]) {
        let n = out.len();
        let w = self.weights();
        for (j, &i) in triangles[self.triangle as usize].iter().enumerate() {
            for (a, p) in out.iter_mut().zip(&values[i as usize * n..(i as usize + 1) * n]) {
                *a += w[j] * p;
            }
        }
    }
}

/// Where one ray went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Nothing hit: the lighting is visible.
    Escaped,
    /// The back of a surface: blocked, and nothing reflected.
    Back,
    /// The front of a surface.
    Front(FrontHit),
}

/// Casts the ray from `origin` along the unit `d` through `occluders` (built from `mesh`) and
/// tells where it went: the closest hit's side by the hit triangle's [`front_normal`].
pub fn cast(mesh: &Mesh, occluders: &Occluders, origin: DVec3, d: DVec3) -> Outcome {
    match occluders.closest(origin, d) {
        None => Outcome::Escaped,
        Some((triangle, t)) => {
            let tri = &mesh.triangles[triangle as usize];
            if front_normal(&mesh.positions, &mesh.normals, tri).dot(d) >= 0.0 {
                Outcome::Back
            } else {
                let (u, w) = barycentrics(&mesh.positions, tri, origin + t as f64 * d);
                Outcome::Front(FrontHit::new(triangle, u, w))
            }
        }
    }
}

/// Traces the rays of a vertex with closest hits: its shadowed transfer, as
/// [`super::diffuse::Shadowed`] computes it, and its front hits.
pub struct Tracer<'a> {
    mesh: &'a Mesh,
    occluders: &'a Occluders,
    directions: &'a Stratified,
    basis: LocalBasis,
    order: usize,
    offset: f64,
}

/// What the first pass saw, over every vertex.
#[derive(Clone, Debug)]
pub struct FirstPass {
    /// Each vertex's shadowed transfer and ray counts.
    pub points: Vec<PointTransfer>,
    /// The front hits, recorded when they fit [`HIT_BUDGET`].
    pub hits: Hits,
    /// Share of all rays that hit the back of a surface.
    pub back_fraction: f64,
    /// Share of all rays that hit the front of a surface.
    pub front_fraction: f64,
}

/// The hits the bounces gather over.
#[derive(Clone, Debug)]
pub enum Hits {
    /// Recorded per chunk of [`CHUNK`] vertices: each chunk's hits and its vertices' ends in them.
    Recorded(Vec<(Vec<FrontHit>, Vec<u32>)>),
    /// Traced again in every bounce.
    Retraced,
}

/// Ray counts of a chunk of vertices.
#[derive(Clone, Copy, Default)]
struct Counts {
    back: u64,
    front: u64,
}

/// A chunk's first pass: its vertices' transfer, its front hits and each vertex's end in them,
/// its ray counts.
type ChunkPass = (Vec<PointTransfer>, Vec<FrontHit>, Vec<u32>, Counts);

/// Whether the first pass records the hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// When the worst case fits [`HIT_BUDGET`].
    Auto,
    /// Always (tests).
    Record,
    /// Never (tests).
    Retrace,
}

impl<'a> Tracer<'a> {
    /// Rays of `directions` about each vertex normal of `mesh`, from x + `offset` n, through
    /// `occluders` (built from the same mesh), for `order` n bands.
    pub fn new(
        mesh: &'a Mesh,
        occluders: &'a Occluders,
        directions: &'a Stratified,
        order: usize,
        offset: f64,
    ) -> Tracer<'a> {
        Tracer { mesh, occluders, directions, basis: LocalBasis::new(directions, order), order, offset }
    }

    /// Vertex `v`'s shadowed transfer with albedo ρ (T_i = (ρ/N) Σ_k V_k Y_i(ω_k), Sloan et al.
    /// 2002 eq. 8 with the cosine in the density), appending its front hits to `hits` in the
    /// rays' order; returns the transfer and the number of back hits.
    pub fn trace(&self, v: usize, albedo: f64, hits: &mut Vec<FrontHit>) -> (PointTransfer, u32) {
        let mut local = vec![0.0; self.order * self.order];
        let (mut visible, mut back) = (0u32, 0u32);
        self.each_ray(v, |k, outcome| match outcome {
            Outcome::Escaped => {
                visible += 1;
                self.basis.add_row(k, &mut local);
            }
            Outcome::Back => back += 1,
            Outcome::Front(hit) => hits.push(hit),
        });
        let scale = albedo / self.directions.len() as f64;
        let (shadowed, unshadowed) = self.basis.to_world(self.mesh.normals[v], &local, scale);
        (PointTransfer { shadowed, unshadowed, visible }, back)
    }

    /// Vertex `v`'s front hits alone, appended to `hits` in the rays' order (the bounces'
    /// re-tracing: the same rays as [`Tracer::trace`], so the same hits).
    fn trace_hits(&self, v: usize, hits: &mut Vec<FrontHit>) {
        self.each_ray(v, |_, outcome| {
            if let Outcome::Front(hit) = outcome {
                hits.push(hit);
            }
        });
    }

    /// The interreflected transfer at a point of the surface that is not a vertex (a lightmap
    /// texel's): its shadowed transfer plus, over its rays' front hits, `gathered` — every
    /// vertex's T^0 + … + T^{B−1} — interpolated at the hit, so that
    /// T = T^0 + Σ_{b=1..B} (ρ/N) Σ_hits T^{b−1}(y), eq. 9 summed over the bounces. `albedo`
    /// holds the point's ρ per channel (one for a grey bake, three for a coloured one), and
    /// `gathered` as many blocks of n² values per vertex; so does the result.
    pub fn gather_at(&self, position: DVec3, normal: DVec3, albedo: &[f64], gathered: &[f64]) -> Vec<f64> {
        let coeffs = self.order * self.order;
        let mut local = vec![0.0; coeffs];
        let mut bounced = vec![0.0; albedo.len() * coeffs];
        self.each_ray_from(position, normal, |k, outcome| match outcome {
            Outcome::Escaped => self.basis.add_row(k, &mut local),
            Outcome::Back => {}
            Outcome::Front(hit) => hit.gather(&self.mesh.triangles, gathered, &mut bounced),
        });
        let mut transfer = Vec::with_capacity(bounced.len());
        for (rho, bounced) in albedo.iter().zip(bounced.chunks_exact(coeffs)) {
            let scale = rho / self.directions.len() as f64;
            let (direct, _) = self.basis.to_world(normal, &local, scale);
            transfer.extend(direct.iter().zip(bounced).map(|(t, b)| t + scale * b));
        }
        transfer
    }

    /// Casts vertex `v`'s rays in order ([`Tracer::each_ray_from`]).
    fn each_ray(&self, v: usize, f: impl FnMut(usize, Outcome)) {
        self.each_ray_from(self.mesh.positions[v], self.mesh.normals[v], f)
    }

    /// Casts the rays about `normal` in order, from `position` + offset · n, and tells `f` each
    /// one's index and where it went.
    fn each_ray_from(&self, position: DVec3, normal: DVec3, mut f: impl FnMut(usize, Outcome)) {
        let origin = position + self.offset * normal;
        for (k, d) in self.directions.about(normal).enumerate() {
            f(k, cast(self.mesh, self.occluders, origin, d));
        }
    }

    /// The first pass over every vertex: shadowed transfer, and the hits recorded or not
    /// according to `storage`. Work items are chunks of vertices whose results are kept in
    /// vertex order, so nothing depends on the thread count.
    pub fn first_pass(&self, albedo: f64, storage: Storage, progress: &dyn Progress) -> FirstPass {
        let vertices = self.mesh.positions.len();
        let worst = vertices * self.directions.len() * std::mem::size_of::<FrontHit>();
        let record = match storage {
            Storage::Auto => worst <= HIT_BUDGET,
            Storage::Record => true,
            Storage::Retrace => false,
        };
        progress.start("visibility and hits", vertices as u64);
        let chunks: Vec<ChunkPass> = (0..vertices.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let range = c * CHUNK..((c + 1) * CHUNK).min(vertices);
                let (mut points, mut hits, mut ends, mut counts) =
                    (Vec::new(), Vec::new(), Vec::new(), Counts::default());
                for v in range {
                    let (point, back) = self.trace(v, albedo, &mut hits);
                    points.push(point);
                    counts.back += back as u64;
                    counts.front += hits.len() as u64;
                    if record {
                        ends.push(hits.len() as u32);
                    } else {
                        hits.clear();
                    }
                }
                if record {
                    counts.front = hits.len() as u64;
                }
                progress.advance(points.len() as u64);
                (points, hits, ends, counts)
            })
            .collect();
        progress.finish();
        let rays = (vertices * self.directions.len()).max(1) as f64;
        let mut total = Counts::default();
        let mut points = Vec::with_capacity(vertices);
        let mut recorded = Vec::with_capacity(chunks.len());
        for (p, hits, ends, counts) in chunks {
            points.extend(p);
            total.back += counts.back;
            total.front += counts.front;
            if record {
                recorded.push((hits, ends));
            }
        }
        let (back, front) = (total.back, total.front);
        FirstPass {
            points,
            hits: if record { Hits::Recorded(recorded) } else { Hits::Retraced },
            back_fraction: back as f64 / rays,
            front_fraction: front as f64 / rays,
        }
    }

    /// The bounces b = 1..=`bounces` from `source` = T^0: each
    /// T^b(x) = (ρ(x)/N) Σ_{front hits} Σ_j w_j T^{b−1}(v_j), summed in the rays' order (eq. 9;
    /// [`FrontHit`]'s weights w_j), ρ(x) the `reflectance` of the gathering vertex. `source`
    /// holds its channels' blocks of n² values per vertex (one grey, or R, G, B: each block
    /// gathers the same block of its neighbours, so colour bleeds). Returns every bounce's
    /// transfer, in order.
    pub fn bounces(
        &self,
        source: &[f64],
        bounces: usize,
        reflectance: Reflectance,
        hits: &Hits,
        progress: &dyn Progress,
    ) -> Vec<Vec<f64>> {
        let coeffs = self.order * self.order;
        let width = reflectance.channels() * coeffs;
        let vertices = self.mesh.positions.len();
        let rays = self.directions.len() as f64;
        let mut out: Vec<Vec<f64>> = Vec::with_capacity(bounces);
        for b in 1..=bounces {
            let previous = out.last().map_or(source, Vec::as_slice);
            let mut next = vec![0.0; vertices * width];
            progress.start(&format!("bounce {b} of {bounces}"), vertices as u64);
            next.par_chunks_mut(CHUNK * width).enumerate().for_each(|(c, block)| {
                let mut traced = Vec::new();
                for (k, t) in block.chunks_exact_mut(width).enumerate() {
                    let v = c * CHUNK + k;
                    let list: &[FrontHit] = match hits {
                        Hits::Recorded(chunks) => {
                            let (hits, ends) = &chunks[c];
                            let start = if k == 0 { 0 } else { ends[k - 1] as usize };
                            &hits[start..ends[k] as usize]
                        }
                        Hits::Retraced => {
                            traced.clear();
                            self.trace_hits(v, &mut traced);
                            &traced
                        }
                    };
                    for hit in list {
                        hit.gather(&self.mesh.triangles, previous, t);
                    }
                    for (channel, t) in t.chunks_exact_mut(coeffs).enumerate() {
                        let scale = reflectance.at(v, channel) / rays;
                        t.iter_mut().for_each(|a| *a *= scale);
                    }
                }
                progress.advance((block.len() / width) as u64);
            });
            progress.finish();
            out.push(next);
        }
        out
    }
}

/// The hit triangle's geometric normal, turned to the side its vertex normals are on (the side
/// its vertices' transfer was computed for), whatever the winding.
fn front_normal(positions: &[DVec3], normals: &[DVec3], t: &[u32; 3]) -> DVec3 {
    let [a, b, c] = t.map(|i| positions[i as usize]);
    let geometric = (b - a).cross(c - a);
    let shading: DVec3 = t.iter().map(|&i| normals[i as usize]).sum();
    if geometric.dot(shading) < 0.0 {
        -geometric
    } else {
        geometric
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantized_weights_sum_to_one_and_round_trip() {
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.3, 0.7), (0.5, 0.5000001), (0.123, 0.456)] {
            let w = FrontHit::new(7, u, v).weights();
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15, "{u} {v}");
            assert!((w[1] - u).abs() <= 1.0 / QUANT && (w[2] - v).abs() <= 1.0 / QUANT, "{u} {v}: {w:?}");
            assert!(w.iter().all(|&x| x >= 0.0));
        }
    }
}
