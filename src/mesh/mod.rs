//! Triangle meshes from OBJ, PLY or glTF files (read by [`crate::io::obj`], [`crate::io::ply`] and
//! [`crate::io::gltf`]) with per-vertex normals, and a bounding-volume hierarchy for primary rays and
//! visibility (shadow) rays.

use crate::io::obj::ObjError;
use glam::DVec3;
use std::path::Path;

/// Errors of loading a mesh.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// tobj could not read or parse the file.
    #[error("{path}: cannot read OBJ: {reason}")]
    Load {
        /// The file.
        path: String,
        /// tobj's message.
        reason: String,
    },
    /// Parsed, but holds no triangles.
    #[error("{0}: the OBJ holds no triangles")]
    Empty(String),
    /// Bad numbers (NaN, infinite) or indices.
    #[error("{path}: {reason}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// The file cannot be read, or is not text, or is too large.
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// A glTF asset cannot be read, or is wrong (the error names the file and the object).
    #[error(transparent)]
    Gltf(#[from] crate::io::gltf::GltfError),
    /// [`Mesh::load_coloured`]: the file holds no base colours prtkit reads (an OBJ, a PLY
    /// without `red green blue`), or they are wrong (negative, not finite, of a type without an
    /// agreed meaning).
    #[error("{path}: {reason}")]
    Colours {
        /// The file.
        path: String,
        /// What is missing or wrong.
        reason: String,
    },
    /// A line of the file is wrong.
    #[error("{path}:{line}:{column}: {reason}")]
    At {
        /// The file.
        path: String,
        /// Line, from 1.
        line: usize,
        /// Column (in characters), from 1.
        column: usize,
        /// What is wrong.
        reason: String,
    },
}

/// An indexed triangle mesh with unit vertex normals.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Unit vertex normals (same length as `positions`).
    pub normals: Vec<DVec3>,
    /// Triangles as vertex indices.
    pub triangles: Vec<[u32; 3]>,
    /// True when the file had no normals and they were computed (area-weighted face normals).
    pub normals_computed: bool,
    /// The lightmap UV set, one (u, v) per vertex, when the file has one (OBJ `vt` on every
    /// vertex; glTF `TEXCOORD_1`, else `TEXCOORD_0`, on every primitive; a PLY's vertex pair
    /// `s t`, `u v`, `texture_u texture_v` or `texture_s texture_t`): `transfer --lightmap` bakes
    /// per texel of it.
    pub uvs: Option<Vec<[f64; 2]>>,
    /// Linear RGB base colour per vertex (same length as `positions`) when loaded with
    /// [`Mesh::load_coloured`]; `None` otherwise.
    pub base_colors: Option<Vec<[f64; 3]>>,
    /// Length of the bounding box diagonal, computed once: shadow rays offset by a fraction of it.
    extent: f64,
    bvh: Bvh,
}

/// A ray hit on a mesh: distance, triangle and barycentrics (u, v) of vertices 1 and 2.
#[derive(Clone, Copy, Debug)]
pub struct MeshHit {
    /// Ray parameter.
    pub t: f64,
    /// Triangle index.
    pub triangle: usize,
    /// Barycentric weight of vertex 1.
    pub u: f64,
    /// Barycentric weight of vertex 2.
    pub v: f64,
}

impl Mesh {
    /// Reads a mesh file by its extension (in any case): PLY ([`Mesh::load_ply`]), glTF
    /// (`.gltf`, `.glb`: [`Mesh::load_gltf`]), else OBJ (all its objects, triangulated) through
    /// [`crate::io::obj`], which reads the file whole (at most [`crate::limits::max_file_bytes`])
    /// and checks its geometry lines first, so that an error names the line and column.
    pub fn load(path: &Path) -> Result<Mesh, MeshError> {
        let name = path.display().to_string();
        let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("ply") => return Self::load_ply(path),
            Some("gltf" | "glb") => return Self::load_gltf(path),
            _ => {}
        }
        let text = crate::io::obj::read(path)?;
        let geometry = crate::io::obj::geometry(&text).map_err(|e| match e {
            ObjError::At { line, column, reason } => MeshError::At { path: name.clone(), line, column, reason },
            ObjError::Load(reason) => MeshError::Load { path: name.clone(), reason },
            ObjError::FaceIndex => MeshError::Invalid { path: name.clone(), reason: e.to_string() },
        })?;
        let crate::io::obj::Geometry { positions, normals, triangles, uvs } = geometry;
        if triangles.is_empty() {
            return Err(MeshError::Empty(name));
        }
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(MeshError::Invalid { path: name, reason: "a vertex position is not finite".into() });
        }
        if uvs.as_ref().is_some_and(|uvs| uvs.iter().flatten().any(|c| !c.is_finite())) {
            return Err(MeshError::Invalid { path: name, reason: "a texture coordinate is not finite".into() });
        }
        let mut mesh =
            Mesh::new(positions, normals, triangles).map_err(|reason| MeshError::Invalid { path: name, reason })?;
        mesh.uvs = uvs;
        Ok(mesh)
    }

    /// As [`Mesh::load`], and reads each vertex's linear RGB base colour (albedo) into
    /// [`Mesh::base_colors`], the vertices in the order [`Mesh::load`] gives them
    /// (`docs/formats/mesh-colours.md`):
    ///
    /// - glTF: per primitive, `baseColorFactor.rgb × baseColorTexture.rgb × COLOR_0.rgb` (glTF 2.0
    ///   §3.9.2), the texture sampled bilinearly in linear values ([`crate::io::gltf::read_coloured`]);
    /// - PLY: the vertex element's `red green blue`, `uchar` sRGB-decoded, `float`/`double` linear
    ///   ([`crate::io::ply::PlyColours`]); a PLY without them is an error;
    /// - OBJ: an error ([`crate::io::obj::NO_BASE_COLOURS`]).
    ///
    /// A colour that is negative or not finite, or a texture that cannot be read, is an error
    /// naming the file.
    ///
    /// ```
    /// use prtkit::mesh::Mesh;
    /// let dir = tempfile::tempdir()?;
    /// let ply = dir.path().join("triangle.ply");
    /// let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
    ///               property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
    ///               element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    /// std::fs::write(&ply, format!("{header}0 0 0 255 128 0\n1 0 0 255 128 0\n0 1 0 255 128 0\n3 0 1 2\n"))?;
    /// let mesh = Mesh::load_coloured(&ply)?;
    /// // 8-bit PLY colours are sRGB-encoded: code 128 is 0.2159 linear.
    /// let [r, g, b] = mesh.base_colors.as_ref().unwrap()[0];
    /// assert!(r == 1.0 && (g - 0.2159).abs() < 1e-4 && b == 0.0);
    /// // `load` reads no colour; an OBJ has none to read.
    /// assert!(Mesh::load(&ply)?.base_colors.is_none());
    /// let obj = dir.path().join("triangle.obj");
    /// std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")?;
    /// assert!(Mesh::load_coloured(&obj).unwrap_err().to_string().contains("OBJ vertex colours are not read"));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn load_coloured(path: &Path) -> Result<Mesh, MeshError> {
        let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("ply") => Self::ply(path, true),
            Some("gltf" | "glb") => Self::gltf(path, true),
            _ => Err(MeshError::Colours {
                path: path.display().to_string(),
                reason: crate::io::obj::NO_BASE_COLOURS.into(),
            }),
        }
    }

    /// Reads a PLY file (ASCII or binary; [`crate::io::ply`]): its vertices, their normals when
    /// every vertex has `nx ny nz` (else computed), their texture coordinates when the vertex
    /// element has a pair ([`crate::io::ply::UV_NAMES`]), its faces split into triangles.
    pub fn load_ply(path: &Path) -> Result<Mesh, MeshError> {
        Self::ply(path, false)
    }

    /// [`Mesh::load_ply`], and with `colours` the vertex colours.
    fn ply(path: &Path, colours: bool) -> Result<Mesh, MeshError> {
        let name = path.display().to_string();
        let invalid = |reason: String| MeshError::Invalid { path: name.clone(), reason };
        let bytes = crate::io::ply::read(path)?;
        let crate::io::ply::PlyMesh { positions, normals, uvs, triangles, colours: stored } =
            crate::io::ply::parse(&bytes).map_err(|reason| invalid(format!("cannot read PLY: {reason}")))?;
        if triangles.is_empty() {
            return Err(invalid("the PLY holds no triangles".into()));
        }
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(invalid("a vertex position is not finite".into()));
        }
        if uvs.as_ref().is_some_and(|uvs| uvs.iter().flatten().any(|c| !c.is_finite())) {
            return Err(invalid("a texture coordinate is not finite".into()));
        }
        let base_colors = match (colours, stored) {
            (false, _) => None,
            (true, None) => {
                let reason = "the PLY has no vertex colours (red, green, blue)".into();
                return Err(MeshError::Colours { path: name, reason });
            }
            (true, Some(stored)) => {
                Some(stored.linear().map_err(|reason| MeshError::Colours { path: name.clone(), reason })?)
            }
        };
        let mut mesh = Mesh::new(positions, normals, triangles).map_err(invalid)?;
        mesh.uvs = uvs;
        mesh.base_colors = base_colors;
        Ok(mesh)
    }

    /// Reads a glTF 2.0 asset (`.gltf` with its buffers, or `.glb`; [`crate::io::gltf`]): the
    /// triangles of every mesh of its scene placed by their nodes, in the file's axes; normals
    /// from the file when every primitive has NORMAL, else computed.
    pub fn load_gltf(path: &Path) -> Result<Mesh, MeshError> {
        Self::gltf(path, false)
    }

    /// [`Mesh::load_gltf`], and with `colours` the base colours.
    fn gltf(path: &Path, colours: bool) -> Result<Mesh, MeshError> {
        let name = path.display().to_string();
        let (geometry, base_colors) = match colours {
            true => crate::io::gltf::read_coloured(path).map(|(g, c)| (g, Some(c)))?,
            false => (crate::io::gltf::read(path)?, None),
        };
        let crate::io::gltf::Geometry { positions, normals, triangles, uvs } = geometry;
        if triangles.is_empty() {
            return Err(MeshError::Invalid { path: name, reason: "the glTF scene holds no triangles".into() });
        }
        let mut mesh =
            Mesh::new(positions, normals, triangles).map_err(|reason| MeshError::Invalid { path: name, reason })?;
        mesh.uvs = uvs.filter(|uvs| !uvs.is_empty());
        mesh.base_colors = base_colors;
        Ok(mesh)
    }

    /// Builds a mesh; computes normals when `normals` is `None` (or when a given normal is zero).
    pub fn new(positions: Vec<DVec3>, normals: Option<Vec<DVec3>>, triangles: Vec<[u32; 3]>) -> Result<Mesh, String> {
        if triangles.iter().flatten().any(|&i| i as usize >= positions.len()) {
            return Err("a face index is out of range".into());
        }
        let computed = area_weighted_normals(&positions, &triangles);
        let (normals, normals_computed) = match normals {
            Some(n) => {
                let n: Vec<DVec3> = n.iter().zip(&computed).map(|(g, c)| g.try_normalize().unwrap_or(*c)).collect();
                (n, false)
            }
            None => (computed, true),
        };
        let bvh = Bvh::build(&positions, &triangles);
        let (lo, hi) =
            positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| (l.min(*p), h.max(*p)));
        let extent = if positions.is_empty() { 0.0 } else { (hi - lo).length() };
        Ok(Mesh { positions, normals, triangles, normals_computed, uvs: None, base_colors: None, extent, bvh })
    }

    /// The closest hit of the ray o + t d with t in (t_min, t_max).
    pub fn intersect(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64) -> Option<MeshHit> {
        self.bvh.walk(&self.positions, &self.triangles, o, d, t_min, t_max, false)
    }

    /// Whether anything blocks the ray o + t d for t in (t_min, ∞).
    pub fn occluded(&self, o: DVec3, d: DVec3, t_min: f64) -> bool {
        self.bvh.walk(&self.positions, &self.triangles, o, d, t_min, f64::INFINITY, true).is_some()
    }

    /// Position and interpolated unit normal of a hit.
    pub fn surface(&self, hit: &MeshHit) -> (DVec3, DVec3) {
        let [a, b, c] = self.triangles[hit.triangle].map(|i| i as usize);
        let w = 1.0 - hit.u - hit.v;
        let p = w * self.positions[a] + hit.u * self.positions[b] + hit.v * self.positions[c];
        let n = w * self.normals[a] + hit.u * self.normals[b] + hit.v * self.normals[c];
        (p, n.try_normalize().unwrap_or(self.normals[a]))
    }

    /// Length of the bounding box diagonal (scale for ray offsets).
    pub fn extent(&self) -> f64 {
        self.extent
    }
}

/// Vertex normals as the normalized sum of the adjacent faces' cross products (area-weighted).
fn area_weighted_normals(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        let f = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        n[a] += f;
        n[b] += f;
        n[c] += f;
    }
    n.into_iter().map(|v| v.try_normalize().unwrap_or(DVec3::Z)).collect()
}

/// Möller–Trumbore ray/triangle intersection: (t, u, v).
#[inline]
fn ray_triangle(o: DVec3, d: DVec3, p0: DVec3, p1: DVec3, p2: DVec3) -> Option<(f64, f64, f64)> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() < 1e-14 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = o - p0;
    let u = tv.dot(pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = tv.cross(e1);
    let v = d.dot(qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((e2.dot(qv) * inv, u, v))
}

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first triangle in `order`; inner: index of the left child (right = left + 1).
    start: u32,
    /// Leaf: triangle count (> 0); inner: 0.
    count: u32,
}

/// A binary BVH split at the median centroid along the widest axis, leaves of ≤ 4 triangles.
#[derive(Clone, Debug)]
struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

impl Bvh {
    fn build(positions: &[DVec3], triangles: &[[u32; 3]]) -> Bvh {
        let centroid: Vec<DVec3> =
            triangles.iter().map(|t| t.iter().map(|&i| positions[i as usize]).sum::<DVec3>() / 3.0).collect();
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let mut nodes = vec![Node { lo: DVec3::ZERO, hi: DVec3::ZERO, start: 0, count: 0 }];
        let mut stack = vec![(0usize, 0usize, triangles.len())];
        while let Some((node, start, end)) = stack.pop() {
            let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            let (mut clo, mut chi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            for &t in &order[start..end] {
                for &i in &triangles[t as usize] {
                    lo = lo.min(positions[i as usize]);
                    hi = hi.max(positions[i as usize]);
                }
                clo = clo.min(centroid[t as usize]);
                chi = chi.max(centroid[t as usize]);
            }
            nodes[node].lo = lo;
            nodes[node].hi = hi;
            let span = chi - clo;
            if end - start <= 4 || span.max_element() <= 0.0 {
                nodes[node].start = start as u32;
                nodes[node].count = (end - start) as u32;
                continue;
            }
            let axis = if span.x >= span.y && span.x >= span.z {
                0
            } else if span.y >= span.z {
                1
            } else {
                2
            };
            let mid = (start + end) / 2;
            order[start..end].select_nth_unstable_by(mid - start, |a, b| {
                centroid[*a as usize][axis].total_cmp(&centroid[*b as usize][axis])
            });
            let left = nodes.len();
            nodes.push(Node { lo, hi, start: 0, count: 0 });
            nodes.push(Node { lo, hi, start: 0, count: 0 });
            nodes[node].start = left as u32;
            nodes[node].count = 0;
            stack.push((left, start, mid));
            stack.push((left + 1, mid, end));
        }
        Bvh { nodes, order }
    }

    #[inline]
    fn slab(node: &Node, o: DVec3, inv: DVec3, t_min: f64, t_max: f64) -> bool {
        let t0 = (node.lo - o) * inv;
        let t1 = (node.hi - o) * inv;
        let near = t0.min(t1).max_element().max(t_min);
        let far = t0.max(t1).min_element().min(t_max);
        near <= far
    }

    /// One traversal for both queries: the closest hit in (t_min, t_max), shrinking t_max at
    /// every hit, or — with `first` — any hit, returned as soon as it is found (shadow rays).
    #[allow(clippy::too_many_arguments)]
    fn walk(
        &self,
        p: &[DVec3],
        tris: &[[u32; 3]],
        o: DVec3,
        d: DVec3,
        t_min: f64,
        mut t_max: f64,
        first: bool,
    ) -> Option<MeshHit> {
        let inv = d.recip();
        let mut best = None;
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if !Self::slab(node, o, inv, t_min, t_max) {
                continue;
            }
            if node.count == 0 {
                stack.push(node.start);
                stack.push(node.start + 1);
                continue;
            }
            for &t in &self.order[node.start as usize..(node.start + node.count) as usize] {
                let [a, b, c] = tris[t as usize].map(|i| p[i as usize]);
                if let Some((tt, u, v)) = ray_triangle(o, d, a, b, c) {
                    if tt > t_min && tt < t_max {
                        t_max = tt;
                        best = Some(MeshHit { t: tt, triangle: t as usize, u, v });
                        if first {
                            return best;
                        }
                    }
                }
            }
        }
        best
    }
}

/// A UV sphere of radius 1 with `rings` latitude bands and `segments` longitude bands, exact
/// normals; also used by `testdata/meshes` generation and the tests.
pub fn uv_sphere(rings: usize, segments: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut p = vec![DVec3::Z];
    for r in 1..rings {
        let theta = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..segments {
            let phi = 2.0 * std::f64::consts::PI * s as f64 / segments as f64;
            p.push(crate::sphere::direction(theta, phi));
        }
    }
    p.push(-DVec3::Z);
    let last = (p.len() - 1) as u32;
    let ring = |r: usize, s: usize| (1 + (r - 1) * segments + s % segments) as u32;
    let mut t = Vec::new();
    for s in 0..segments {
        t.push([0, ring(1, s), ring(1, s + 1)]);
        t.push([last, ring(rings - 1, s + 1), ring(rings - 1, s)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            t.push([ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)]);
            t.push([ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)]);
        }
    }
    (p, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_errors_name_the_file_line_and_column() {
        // Through the loader: the message is path:line:column.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.obj");
        std::fs::write(&p, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap();
        let msg = Mesh::load(&p).unwrap_err().to_string();
        assert!(msg.starts_with(&format!("{}:4:7: vertex index 9", p.display())), "{msg}");
        for name in ["bowl", "sphere", "torus-knot"] {
            let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("testdata/meshes/{name}.obj"));
            assert!(Mesh::load(&p).is_ok_and(|m| !m.triangles.is_empty()), "{name}");
        }
    }

    #[test]
    fn bvh_hits_agree_with_brute_force_and_normals_point_out() {
        let (p, t) = uv_sphere(12, 24);
        let mesh = Mesh::new(p.clone(), None, t.clone()).unwrap();
        assert!(mesh.normals_computed);
        for (v, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!(v.dot(*n) > 0.95, "normal {n:?} at {v:?}");
        }
        for k in 0..200 {
            let o = DVec3::new((k as f64 * 0.37).sin() * 3.0, -3.0, (k as f64 * 0.11).cos() * 2.0);
            let d = (DVec3::new((k as f64).sin() * 0.5, 0.0, (k as f64 * 1.3).cos() * 0.5) - o).normalize();
            let mut brute = f64::INFINITY;
            for tri in &t {
                let [a, b, c] = tri.map(|i| p[i as usize]);
                if let Some((tt, _, _)) = ray_triangle(o, d, a, b, c) {
                    if tt > 1e-9 {
                        brute = brute.min(tt);
                    }
                }
            }
            let hit = mesh.intersect(o, d, 1e-9, f64::INFINITY).map(|h| h.t).unwrap_or(f64::INFINITY);
            assert!(hit == brute, "ray {k}: bvh {hit} brute {brute}");
            assert_eq!(mesh.occluded(o, d, 1e-9), brute.is_finite());
        }
    }
}
