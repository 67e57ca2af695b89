//! Visibility V(x, ω) by ray casting through a compressed wide BVH (`obvhs`: an 8-wide BVH
//! after Ylitie, Karras & Laine 2017, built by PLOC), in single precision as real-time ray
//! tracers cast them. Triangles of zero area are left out: they occlude nothing.
//!
//! **Instruction set.** The traversal (its node tests, four children at a time, its hit masks'
//! bit scans, the triangle tests) is compiled twice: for the baseline x86-64 prtkit is built
//! for, and for the AVX2 generation (x86-64-v3: AVX2, BMI1/2, LZCNT, POPCNT, FMA), chosen at
//! run time where the CPU has it, as Embree picks its kernels. Both builds run the same source,
//! the same operations in the same order (Rust fuses no multiply-add it is not told to), so
//! they answer every ray with the same bits; only the encoding and scheduling differ.

use glam::DVec3;
use glam_obvhs::UVec2;
use glam_obvhs::Vec3A;
use obvhs::cwbvh::{builder::build_cwbvh_from_tris, CwBvh};
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

/// The occluders of a scene: every triangle of every object, in one BVH.
pub struct Occluders {
    bvh: CwBvh,
    /// The AVX2 generation's instructions (x86-64-v3), where this CPU has them.
    #[cfg(target_arch = "x86_64")]
    avx2: Option<pulp::x86::V3>,
    /// The triangles in the order of the tree's primitive slots (a triangle split by the build
    /// appears in each of its slots): the traversal reads them in sequence, not through an index.
    triangles: Vec<Packed>,
    /// The mesh's index of the triangle in each slot.
    ids: Vec<u32>,
}

impl Occluders {
    /// A BVH over the triangles of `positions` with non-zero area (the PLOC build is
    /// sequential here: the crate's `parallel` feature is off, so the tree does not depend on
    /// the thread count; visibility would not either, as any hit is a hit).
    pub fn new(positions: &[DVec3], triangles: &[[u32; 3]]) -> Occluders {
        let vertex = |i: u32| Vec3A::from_array(positions[i as usize].as_vec3().to_array());
        let (ids, triangles): (Vec<u32>, Vec<Triangle>) = triangles
            .iter()
            .enumerate()
            .filter(|(_, t)| triangle_area(positions, t) > 0.0)
            .map(|(i, t)| (i as u32, Triangle { v0: vertex(t[0]), v1: vertex(t[1]), v2: vertex(t[2]) }))
            .unzip();
        // PLOC with pre-splitting and more reinsertion than the crate's medium preset: a better
        // tree for the 10⁸ rays of a bake, for a build that stays a small part of it.
        let bvh = build_cwbvh_from_tris(&triangles, BvhBuildParams::slow_build(), &mut Default::default());
        let slots = &bvh.primitive_indices;
        let (triangles, ids) = (
            slots.iter().map(|&i| Packed::new(&triangles[i as usize])).collect(),
            slots.iter().map(|&i| ids[i as usize]).collect(),
        );
        Occluders {
            bvh,
            triangles,
            ids,
            #[cfg(target_arch = "x86_64")]
            avx2: pulp::x86::V3::try_new(),
        }
    }

    /// Whether anything blocks the ray from `origin` along the unit `direction`.
    #[inline]
    pub fn occluded(&self, origin: DVec3, direction: DVec3) -> bool {
        self.dispatch(Trace { occluders: self, ray: single_precision(origin, direction), any: true }).is_some()
    }

    /// The closest triangle the ray from `origin` along the unit `direction` hits: its index in
    /// the mesh and the ray parameter t (single precision, as the traversal). The traversal
    /// order is fixed by the tree, so ties between equally close triangles resolve the same way
    /// on every run and thread.
    #[inline]
    pub fn closest(&self, origin: DVec3, direction: DVec3) -> Option<(u32, f32)> {
        let (slot, t) =
            self.dispatch(Trace { occluders: self, ray: single_precision(origin, direction), any: false })?;
        Some((self.ids[slot], t))
    }

    /// Runs a traversal, in the AVX2 build where this CPU has it.
    #[inline(always)]
    fn dispatch(&self, trace: Trace) -> Option<(usize, f32)> {
        if self.triangles.is_empty() {
            return None;
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = self.avx2 {
            return v3.vectorize(trace);
        }
        pulp::NullaryFnOnce::call(trace)
    }
}

/// A traversal of the occluders: its ray, and whether it stops at the first hit found (any
/// hit, for occlusion) or finds the closest.
struct Trace<'a> {
    occluders: &'a Occluders,
    ray: Ray,
    any: bool,
}

/// `pulp` runs a traversal inside a function compiled for the instructions it picked;
/// everything below `call` is `inline(always)`, so the whole loop is built for them.
impl pulp::NullaryFnOnce for Trace<'_> {
    /// The hit's tree slot and t.
    type Output = Option<(usize, f32)>;

    /// obvhs' own traversal loop (its exported `traverse!`, as its `ray_traverse` runs it),
    /// written out here rather than called so that it is inlined whole.
    #[inline(always)]
    fn call(self) -> Self::Output {
        let Trace { occluders, mut ray, any } = self;
        let mut state = occluders.bvh.new_traversal(ray.direction);
        let mut node;
        let mut hit = None;
        'found: {
            obvhs::traverse!(occluders.bvh, node, state, node.intersect_ray(&ray, state.oct_inv4), {
                let slot = state.primitive_id as usize;
                let t = occluders.triangles[slot].intersect(&ray);
                if t < ray.tmax {
                    hit = Some((slot, t));
                    ray.tmax = t;
                    if any {
                        break 'found;
                    }
                }
            });
        }
        hit
    }
}

/// A triangle as the traversal reads it: its first vertex and the two edges obvhs' Möller–Trumbore
/// test forms from its vertices (e1 = v0 − v1, e2 = v2 − v0), formed once, unpadded (36 bytes, where
/// three 16-byte vectors take 48): the test mostly waits for these bytes.
#[derive(Clone, Copy)]
struct Packed {
    v0: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
}

impl Packed {
    fn new(t: &Triangle) -> Packed {
        Packed { v0: t.v0.to_array(), e1: (t.v0 - t.v1).to_array(), e2: (t.v2 - t.v0).to_array() }
    }

    /// The ray parameter of the hit, or infinity: obvhs' `Triangle::intersect`, operation for
    /// operation (so the same bits), from the stored edges.
    #[inline(always)]
    fn intersect(&self, ray: &Ray) -> f32 {
        let (v0, e1, e2) = (Vec3A::from_array(self.v0), Vec3A::from_array(self.e1), Vec3A::from_array(self.e2));
        let n = e1.cross(e2);
        let c = v0 - ray.origin;
        let r = ray.direction.cross(c);
        let inv_det = 1.0 / n.dot(ray.direction);
        let u = r.dot(e2) * inv_det;
        let v = r.dot(e1) * inv_det;
        let w = 1.0 - u - v;
        // Hit when u, v and w are all ≥ +0 (a sign bit set is outside).
        let outside = (u.to_bits() | v.to_bits() | w.to_bits()) & 0x8000_0000 != 0;
        if inv_det != 0.0 && !outside {
            let t = n.dot(c) * inv_det;
            if t >= ray.tmin && t <= ray.tmax {
                return t;
            }
        }
        f32::INFINITY
    }
}

/// The ray from `origin` along `direction`, unbounded, in single precision.
fn single_precision(origin: DVec3, direction: DVec3) -> Ray {
    Ray::new_inf(Vec3A::from_array(origin.as_vec3().to_array()), Vec3A::from_array(direction.as_vec3().to_array()))
}

/// Barycentric weights (u, v) of vertices 1 and 2 of the triangle `t` at the point `p` (assumed
/// in its plane), clamped into the triangle: w0 = 1 − u − v ≥ 0.
pub fn barycentrics(positions: &[DVec3], t: &[u32; 3], p: DVec3) -> (f64, f64) {
    let [a, b, c] = t.map(|i| positions[i as usize]);
    let (e1, e2, q) = (b - a, c - a, p - a);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (q1, q2) = (q.dot(e1), q.dot(e2));
    let det = d11 * d22 - d12 * d12;
    if det <= 0.0 {
        return (0.0, 0.0);
    }
    let u = ((d22 * q1 - d12 * q2) / det).clamp(0.0, 1.0);
    let v = ((d11 * q2 - d12 * q1) / det).clamp(0.0, 1.0);
    let s = u + v;
    if s > 1.0 {
        (u / s, v / s)
    } else {
        (u, v)
    }
}

/// Area of triangle `t`: half the length of its edges' cross product.
pub fn triangle_area(positions: &[DVec3], t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|i| positions[i as usize]);
    0.5 * (b - a).cross(c - a).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::transfer::directions::Stratified;

    /// The AVX2 build and the baseline build of the traversal answer every ray with the same
    /// bits: occluded or not, and the closest hit's triangle and t.
    #[test]
    fn both_builds_answer_alike() {
        // A bowl of 24 × 48 quads around a ball, rays from points on the bowl.
        let (rings, segments) = (24, 48);
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for (centre, radius, top) in [(DVec3::ZERO, 1.0, 0.55), (DVec3::new(0.1, -0.4, 0.0), 0.35, 1.0)] {
            let base = positions.len() as u32;
            for i in 0..=rings {
                let theta = std::f64::consts::PI * (1.0 - top * i as f64 / rings as f64);
                for j in 0..segments {
                    let phi = std::f64::consts::TAU * j as f64 / segments as f64;
                    let d = DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
                    positions.push(centre + radius * d);
                }
            }
            for i in 0..rings as u32 {
                for j in 0..segments as u32 {
                    let at = |i: u32, j: u32| base + i * segments as u32 + j % segments as u32;
                    triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                    triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
            }
        }
        let mut occluders = Occluders::new(&positions, &triangles);
        let directions = Stratified::new(256, 7);
        let trace = |occluders: &Occluders| -> Vec<(bool, Option<(u32, u32)>)> {
            positions[..rings * segments]
                .iter()
                .step_by(5)
                .flat_map(|&p| {
                    let origin = p * 0.999;
                    directions.about(-p.normalize()).map(move |d| {
                        (occluders.occluded(origin, d), occluders.closest(origin, d).map(|(t, s)| (t, s.to_bits())))
                    })
                })
                .collect()
        };
        let fast = trace(&occluders);
        #[cfg(target_arch = "x86_64")]
        {
            assert!(occluders.avx2.is_some(), "this CPU has no AVX2: the test compares nothing");
            occluders.avx2 = None;
        }
        let baseline = trace(&occluders);
        let blocked = baseline.iter().filter(|a| a.0).count();
        assert!(blocked > baseline.len() / 4 && blocked < baseline.len(), "{blocked} of {} blocked", baseline.len());
        assert!(
            fast == baseline,
            "the two builds differ on {} rays",
            fast.iter().zip(&baseline).filter(|(a, b)| a != b).count()
        );
    }
}
