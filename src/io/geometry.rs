//! The plain triangle geometry every mesh reader returns (`io::obj`, `io::gltf`): what the file
//! holds, before `mesh::Mesh` normalizes normals, computes missing ones and builds its BVH. One
//! type, so that every format hands the mesh the same thing.

use glam::DVec3;

/// A file's triangles, in the file's own axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Geometry {
    /// Vertex positions, in the order the reader numbers them (see each reader).
    pub positions: Vec<DVec3>,
    /// Vertex normals as the file gives them, when every vertex has one (the mesh normalizes
    /// them and computes a zero one).
    pub normals: Option<Vec<DVec3>>,
    /// Triangles as vertex indices, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// The lightmap UV set (u, v), when every vertex has one (see each reader for which set).
    pub uvs: Option<Vec<[f64; 2]>>,
}
