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
                // Shade the side the viewer sees (open meshes, back faces).
                if n.dot(d) > 0.0 {
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
