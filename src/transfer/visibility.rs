//! Visibility V(x, ω) by ray casting through a compressed wide BVH (`obvhs`: an 8-wide BVH
//! after Ylitie, Karras & Laine 2017, built by PLOC), in single precision as real-time ray
//! tracers cast them. Triangles of zero area are left out: they occlude nothing.

use glam::DVec3;
use glam_obvhs::Vec3A;
use obvhs::cwbvh::{builder::build_cwbvh_from_tris, CwBvh};
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

/// The occluders of a scene: every triangle of every object, in one BVH.
pub struct Occluders {
    bvh: CwBvh,
    /// The triangles in the order of the tree's primitive slots (a triangle split by the build
    /// appears in each of its slots): the traversal reads them in sequence, not through an index.
    triangles: Vec<Triangle>,
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
        let (triangles, ids) =
            (slots.iter().map(|&i| triangles[i as usize]).collect(), slots.iter().map(|&i| ids[i as usize]).collect());
        Occluders { bvh, triangles, ids }
    }

    /// Whether anything blocks the ray from `origin` along the unit `direction`.
    #[inline]
    pub fn occluded(&self, origin: DVec3, direction: DVec3) -> bool {
        if self.triangles.is_empty() {
            return false;
        }
        let ray = Ray::new_inf(
            Vec3A::from_array(origin.as_vec3().to_array()),
            Vec3A::from_array(direction.as_vec3().to_array()),
        );
        !self.bvh.ray_traverse_miss(ray, |ray, slot| self.triangles[slot].intersect(ray))
    }

    /// The closest triangle the ray from `origin` along the unit `direction` hits: its index in
    /// the mesh and the ray parameter t (single precision, as the traversal). The traversal
    /// order is fixed by the tree, so ties between equally close triangles resolve the same way
    /// on every run and thread.
    #[inline]
    pub fn closest(&self, origin: DVec3, direction: DVec3) -> Option<(u32, f32)> {
        if self.triangles.is_empty() {
            return None;
        }
        let ray = Ray::new_inf(
            Vec3A::from_array(origin.as_vec3().to_array()),
            Vec3A::from_array(direction.as_vec3().to_array()),
        );
        let mut hit = RayHit::none();
        let found = self.bvh.ray_traverse(ray, &mut hit, |ray, slot| self.triangles[slot].intersect(ray));
        found.then(|| (self.ids[hit.primitive_id as usize], hit.t))
    }
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
