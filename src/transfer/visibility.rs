//! Visibility V(x, ω) by ray casting through a compressed wide BVH (`obvhs`: an 8-wide BVH
//! after Ylitie, Karras & Laine 2017, built by PLOC), in single precision as real-time ray
//! tracers cast them. Triangles of zero area are left out: they occlude nothing.

use glam::DVec3;
use glam_obvhs::Vec3A;
use obvhs::cwbvh::{builder::build_cwbvh_from_tris, CwBvh};
use obvhs::ray::Ray;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

/// The occluders of a scene: every triangle of every object, in one BVH.
pub struct Occluders {
    bvh: CwBvh,
    triangles: Vec<Triangle>,
}

impl Occluders {
    /// A BVH over the triangles of `positions` with non-zero area (the PLOC build is
    /// sequential here: the crate's `parallel` feature is off, so the tree does not depend on
    /// the thread count; visibility would not either, as any hit is a hit).
    pub fn new(positions: &[DVec3], triangles: &[[u32; 3]]) -> Occluders {
        let vertex = |i: u32| Vec3A::from_array(positions[i as usize].as_vec3().to_array());
        let triangles: Vec<Triangle> = triangles
            .iter()
            .filter(|t| triangle_area(positions, t) > 0.0)
            .map(|t| Triangle { v0: vertex(t[0]), v1: vertex(t[1]), v2: vertex(t[2]) })
            .collect();
        let bvh = build_cwbvh_from_tris(&triangles, BvhBuildParams::medium_build(), &mut Default::default());
        Occluders { bvh, triangles }
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
        !self
            .bvh
            .ray_traverse_miss(ray, |ray, id| self.triangles[self.bvh.primitive_indices[id] as usize].intersect(ray))
    }
}

/// Area of triangle `t`: half the length of its edges' cross product.
pub fn triangle_area(positions: &[DVec3], t: &[u32; 3]) -> f64 {
    let [a, b, c] = t.map(|i| positions[i as usize]);
    0.5 * (b - a).cross(c - a).length()
}
