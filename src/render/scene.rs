//! What the camera sees: an analytic sphere or a triangle mesh, in front of the environment.

use crate::mesh::Mesh;
use glam::DVec3;

/// The object in the scene.
#[derive(Clone, Debug)]
pub enum Scene {
    /// An analytic sphere (exact normals, no self-occlusion).
    Sphere {
        /// Centre.
        centre: DVec3,
        /// Radius (> 0).
        radius: f64,
    },
    /// A triangle mesh with vertex normals.
    Mesh(Box<Mesh>),
}

/// A visible surface point.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Position.
    pub p: DVec3,
    /// Unit shading normal.
    pub n: DVec3,
    /// For meshes: the triangle and barycentrics (u, v) of its vertices 1 and 2, for
    /// interpolating per-vertex data.
    pub triangle: Option<(usize, f64, f64)>,
}

impl Scene {
    /// The unit sphere at the origin.
    pub fn unit_sphere() -> Scene {
        Scene::Sphere { centre: DVec3::ZERO, radius: 1.0 }
    }

    /// The first surface point along the ray o + t d (d unit), t > 0.
    pub fn intersect(&self, o: DVec3, d: DVec3) -> Option<Hit> {
        match self {
            Scene::Sphere { centre, radius } => {
                let oc = o - *centre;
                let b = oc.dot(d);
                let c = oc.length_squared() - radius * radius;
                let disc = b * b - c;
                if disc < 0.0 {
                    return None;
                }
                let s = disc.sqrt();
                let t = if -b - s > 1e-9 { -b - s } else { -b + s };
                if t <= 1e-9 {
                    return None;
                }
                let p = o + t * d;
                Some(Hit { p, n: (p - *centre) / *radius, triangle: None })
            }
            Scene::Mesh(mesh) => {
                let h = mesh.intersect(o, d, 1e-9, f64::INFINITY)?;
                let (p, mut n) = mesh.surface(&h);
                // Shade the side the viewer sees (open meshes, back faces). Which side that is,
                // the triangle says, not the interpolated normal: near a silhouette a front face's
                // interpolated normal can lean away from the viewer, and flipping it would turn
                // it into the mesh, where every shadow ray is blocked (a black pixel).
                if facing_normal(mesh, h.triangle, n).dot(d) > 0.0 {
                    n = -n;
                }
                Some(Hit { p, n, triangle: Some((h.triangle, h.u, h.v)) })
            }
        }
    }

    /// Whether the ray from `p` (offset along `n`) towards `d` is blocked (meshes only: a
    /// sphere does not shadow itself over its visible hemisphere).
    pub fn occluded(&self, p: DVec3, n: DVec3, d: DVec3) -> bool {
        match self {
            Scene::Sphere { .. } => false,
            Scene::Mesh(mesh) => {
                let eps = 1e-4 * mesh.extent().max(1e-9);
                mesh.occluded(p + eps * n, d, 0.0)
            }
        }
    }
}

/// The geometric normal of `triangle`, on the side of the interpolated normal `n` (so that a
/// file's winding does not matter); `n` itself for a degenerate triangle.
fn facing_normal(mesh: &Mesh, triangle: usize, n: DVec3) -> DVec3 {
    let [a, b, c] = mesh.triangles[triangle].map(|i| mesh.positions[i as usize]);
    let g = (b - a).cross(c - a);
    if g == DVec3::ZERO {
        return n;
    }
    if g.dot(n) < 0.0 {
        -g
    } else {
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_front_face_keeps_its_normal_where_the_interpolated_normal_leans_away() {
        // A triangle facing +Z whose vertex normals lean far towards +X, seen from above at a
        // slant towards +X: the face is in front (its normal meets the ray), the interpolated
        // normal leans away from the viewer. The viewer sees the front: the normal stays on the
        // front side (n·z > 0); flipping it by its own facing would put it below the face.
        let lean = DVec3::new(0.999, 0.0, 0.045).normalize();
        let positions = vec![DVec3::new(-1.0, -1.0, 0.0), DVec3::new(1.0, -1.0, 0.0), DVec3::new(0.0, 1.0, 0.0)];
        let mesh = Mesh::new(positions, Some(vec![lean; 3]), vec![[0, 1, 2]]).unwrap();
        let scene = Scene::Mesh(Box::new(mesh));
        let d = DVec3::new(0.3, 0.0, -0.1).normalize();
        assert!(lean.dot(d) > 0.0 && DVec3::Z.dot(d) < 0.0);
        let hit = scene.intersect(DVec3::new(0.0, 0.0, 0.0) - d, d).expect("the triangle");
        assert!(hit.n.dot(DVec3::Z) > 0.0 && (hit.n - lean).length() < 1e-12, "{}", hit.n);
        // From below, the back face: flipped.
        let up = DVec3::new(0.3, 0.0, 0.1).normalize();
        let hit = scene.intersect(-up, up).expect("the triangle");
        assert!((hit.n + lean).length() < 1e-12, "{}", hit.n);
    }
}
