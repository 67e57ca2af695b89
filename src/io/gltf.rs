//! glTF 2.0 (Khronos, "glTF 2.0 Specification", 2021), the one reader of it: `.gltf` (JSON, its
//! buffers in files beside it or in `data:` URIs) and `.glb` (§4.4, one file). The `gltf` crate
//! parses the container and the JSON and validates the document; the bytes it is given, and every
//! buffer file, are read here within [`crate::limits::max_file_bytes`] (the crate's `import`
//! reads files without a bound), and the accessors are decoded here with every range checked, so
//! that a garbled file ends in an error naming it, never a panic.
//!
//! What a mesh is made of: the default scene (or the first, or every mesh once when the asset has
//! no scene) flattened into one triangle list, so that its meshes shadow each other. Every node's
//! mesh is placed by the node's world transform (§3.5.3: the product of the local transforms from
//! the root, a local transform being `matrix` or T·R·S), positions by the matrix, normals by the
//! inverse transpose of its upper 3 × 3 (renormalized). Positions stay in the file's axes: glTF is
//! +Y up (§3.4) where prtkit's frame is +Z up, and nothing is turned. Skins and morph targets are
//! not applied (the rest pose is read).

use super::read::{display_path, read_bytes};
use super::IoError;
use crate::limits::{human_bytes, LimitError};
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use ::gltf::Semantic;
use base64::Engine as _;
use glam::{DMat3, DMat4, DQuat, DVec3, DVec4};
use std::path::{Path, PathBuf};

/// The format's name in messages.
const FORMAT: &str = "glTF";

/// What is wrong with a glTF asset. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    /// The file cannot be read, is too large, or does not start like glTF.
    #[error(transparent)]
    Read(#[from] IoError),
    /// The bytes are not a glTF 2.0 asset: a broken GLB container, JSON that does not parse, or a
    /// document the `gltf` crate's validation refuses (a dangling index, a missing property…).
    #[error("{path}: not a valid glTF 2.0 asset: {reason}")]
    NotGltf {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A buffer's bytes cannot be had: a missing or unreadable file, a bad `data:` URI, fewer
    /// bytes than its `byteLength`.
    #[error("{path}: buffer {index}: {reason}")]
    Buffer {
        /// The glTF file.
        path: PathBuf,
        /// The buffer's index.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// A node or primitive is wrong: no POSITION, a non-finite position, an index out of range,
    /// an accessor past the end of its buffer view, a singular transform, a cycle of nodes.
    #[error("{path}: {at}: {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Which object, e.g. "mesh 0, primitive 1" or "node 3".
        at: String,
        /// What is wrong.
        reason: String,
    },
    /// A valid asset using what prtkit does not read: points or lines, sparse accessors,
    /// quantized attributes.
    #[error("{path}: {at}: {reason}, which prtkit does not read")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// Which object.
        at: String,
        /// What is used.
        reason: String,
    },
    /// The buffers or the flattened scene exceed a ceiling.
    #[error("{path}: {error}")]
    Limit {
        /// The file.
        path: PathBuf,
        /// The ceiling.
        error: LimitError,
    },
}

/// The flattened triangles of a glTF scene, in world space (the file's axes): every primitive's
/// vertices placed by its node, depth first in the order the scene and the `children` lists name
/// the nodes, primitives in their mesh's order; unit normals placed likewise when every primitive
/// has `NORMAL` (a zero normal stays zero: the mesh computes that vertex's); triangles
/// counter-clockwise seen from the front (§3.7.2.1; a node whose transform mirrors has its
/// triangles turned, §3.7.4); UVs when every primitive has a set: `TEXCOORD_1` (the second set,
/// which engines keep for lightmaps), else `TEXCOORD_0`, float or normalized unsigned
/// byte/short VEC2 (§3.7.2.1). A set that cannot be read leaves the scene without UVs rather
/// than failing: the geometry reads as it did before UVs were read.
pub use super::geometry::Geometry;

/// Reads a `.gltf` or `.glb` file and its buffers, and flattens its scene.
pub fn read(path: &Path) -> Result<Geometry, GltfError> {
    let name = display_path(path);
    let ceiling = crate::limits::max_file_bytes();
    let bytes = read_bytes(path, FORMAT, ceiling, |start| {
        let json = start.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{');
        if start.starts_with(b"glTF") || json {
            Ok(())
        } else {
            Err("does not start like glTF (a .glb's 'glTF' magic or a .gltf's '{')".into())
        }
    })?;
    let not_gltf = |reason: String| GltfError::NotGltf { path: name.clone(), reason };
    let asset = glb_container(&bytes).map_err(not_gltf)?;
    let ::gltf::Gltf { document, blob } =
        ::gltf::Gltf::from_slice_without_validation(asset).map_err(|e| not_gltf(e.to_string()))?;
    // Validated in two steps: the crate's validation indexes the accessors with POSITION before
    // it checks that index, so that is checked here first.
    let mut root = document.into_json();
    precheck(&mut root).map_err(|(at, reason)| GltfError::Invalid { path: name.clone(), at, reason })?;
    let document = ::gltf::Document::from_json(root).map_err(|e| not_gltf(e.to_string()))?;
    let buffers = buffers(path, &name, &document, blob, ceiling)?;
    let mut scene = Flattened {
        path: name,
        buffers,
        geometry: Geometry {
            positions: Vec::new(),
            normals: Some(Vec::new()),
            triangles: Vec::new(),
            uvs: Some(Vec::new()),
        },
    };
    for (mesh, world, at) in placements(&document).map_err(|(at, reason)| scene.invalid(at, reason))? {
        scene.place(&mesh, world, at)?;
    }
    Ok(scene.geometry)
}

/// The asset a file holds: a `.glb`'s first `length` bytes once its 12-byte header is checked
/// (§4.4.2: magic, version 2, the total length), or the JSON text as it is.
fn glb_container(bytes: &[u8]) -> Result<&[u8], String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(bytes);
    }
    let word = |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(format!("the GLB header is cut short ({} bytes of 12)", bytes.len()));
    };
    if version != 2 {
        return Err(format!("GLB version {version} (glTF 2.0 is version 2)"));
    }
    // The header, then at least the JSON chunk's 8-byte header (§4.4.3).
    if (length as usize) < 20 {
        return Err(format!("the GLB header gives a length of {length} bytes, less than its headers take"));
    }
    if length as usize > bytes.len() {
        return Err(format!("truncated: the GLB header gives {length} bytes, the file holds {}", bytes.len()));
    }
    Ok(&bytes[..length as usize])
}

/// Extensions that change only materials, textures or lights: an asset that requires them is read
/// all the same, as its geometry is core glTF. Any other in `extensionsRequired` (Draco or
/// meshopt compression, quantized attributes…) is refused by the crate's validation.
const GEOMETRY_FREE_EXTENSIONS: [&str; 5] =
    ["KHR_materials_", "KHR_texture_", "EXT_texture_", "MSFT_texture_", "KHR_lights_"];

/// What the `gltf` crate's validation assumes before it checks it: every primitive has a POSITION
/// naming an accessor that exists (its hook indexes the accessors with it). Returns the object and
/// the problem. Drops the [`GEOMETRY_FREE_EXTENSIONS`] from `extensionsRequired`.
fn precheck(root: &mut ::gltf::json::Root) -> Result<(), (String, String)> {
    use ::gltf::json::validation::Checked;
    root.extensions_required.retain(|e| !GEOMETRY_FREE_EXTENSIONS.iter().any(|prefix| e.starts_with(prefix)));
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let at = format!("mesh {m}, primitive {p}");
            let Some(index) = primitive.attributes.get(&Checked::Valid(Semantic::Positions)) else {
                return Err((at, "no POSITION attribute".into()));
            };
            if index.value() >= root.accessors.len() {
                let reason = format!("POSITION names accessor {}, of {}", index.value(), root.accessors.len());
                return Err((at, reason));
            }
        }
    }
    Ok(())
}

/// Every buffer's bytes (§3.6.1): the GLB's BIN chunk for a buffer without `uri`, a `data:` URI's
/// base64, or a file at a relative path from the glTF file's directory, read within the file
/// ceiling. The declared lengths together must fit that ceiling; a buffer holding more bytes than
/// its `byteLength` is cut to it.
fn buffers(
    path: &Path,
    name: &Path,
    document: &::gltf::Document,
    mut blob: Option<Vec<u8>>,
    ceiling: u64,
) -> Result<Vec<Vec<u8>>, GltfError> {
    let declared: u128 = document.buffers().map(|b| b.length() as u128).sum();
    if declared > ceiling as u128 {
        let error = LimitError {
            what: "the buffers' byteLength together".into(),
            value: human_bytes(declared),
            ceiling: human_bytes(ceiling as u128),
            reason: "buffers are read whole into memory",
        };
        return Err(GltfError::Limit { path: name.to_path_buf(), error });
    }
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let index = buffer.index();
        let error = |reason: String| GltfError::Buffer { path: name.to_path_buf(), index, reason };
        let mut data = match buffer.source() {
            ::gltf::buffer::Source::Bin => {
                blob.take().ok_or_else(|| error("it has no uri, and the file has no GLB BIN chunk".into()))?
            }
            ::gltf::buffer::Source::Uri(uri) => buffer_uri(path, uri).map_err(error)?,
        };
        let length = buffer.length();
        if data.len() < length {
            return Err(error(format!("it holds {} bytes, fewer than its byteLength {length}", data.len())));
        }
        data.truncate(length);
        out.push(data);
    }
    Ok(out)
}

/// A buffer's bytes from its URI (RFC 3986, §3.6.1): `data:…;base64,…`, or a relative reference
/// resolved against the directory of `gltf` (percent-escapes decoded). Absolute paths and other
/// schemes are refused: an asset names the files beside it.
fn buffer_uri(gltf: &Path, uri: &str) -> Result<Vec<u8>, String> {
    if let Some(data) = uri.strip_prefix("data:") {
        let (_, payload) = data.split_once(";base64,").ok_or("a data: URI that is not base64")?;
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("the data: URI's base64 is wrong: {e}"));
    }
    // RFC 3986 §3.1: scheme = ALPHA *( ALPHA / DIGIT / "+" / "-" / "." ), then ':'.
    let scheme = uri.split_once(':').is_some_and(|(scheme, _)| {
        scheme.starts_with(|c: char| c.is_ascii_alphabetic())
            && scheme.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    if scheme || uri.starts_with('/') || uri.starts_with('\\') {
        return Err(format!("{uri:?} is not a relative path or a data: URI"));
    }
    let relative = percent_decode(uri).ok_or_else(|| format!("{uri:?} has a bad percent-escape"))?;
    let file = gltf.parent().unwrap_or(Path::new("")).join(relative);
    read_bytes(&file, "glTF buffer", crate::limits::max_file_bytes(), |_| Ok(())).map_err(|e| e.to_string())
}

/// `%XX` escapes of a URI decoded (RFC 3986 §2.1); `None` for a bad escape or bytes that are not
/// UTF-8 once decoded.
fn percent_decode(uri: &str) -> Option<String> {
    let mut out = Vec::with_capacity(uri.len());
    let mut bytes = uri.bytes();
    while let Some(b) = bytes.next() {
        if b == b'%' {
            let hex = [bytes.next()?, bytes.next()?];
            out.push(u8::from_str_radix(std::str::from_utf8(&hex).ok()?, 16).ok()?);
        } else {
            out.push(b);
        }
    }
    String::from_utf8(out).ok()
}

/// Every mesh of the scene with its world transform and the node that places it, depth first:
/// the default scene's nodes (§3.5.1: `scene`, else the first scene), or, when the asset has no
/// scene, every mesh once, untransformed. Returns the first problem met: a node reached twice, a
/// transform that is not finite.
#[allow(clippy::type_complexity)]
fn placements(document: &::gltf::Document) -> Result<Vec<(::gltf::Mesh<'_>, DMat4, String)>, (String, String)> {
    let Some(scene) = document.default_scene().or_else(|| document.scenes().next()) else {
        return Ok(document.meshes().map(|m| (m.clone(), DMat4::IDENTITY, format!("mesh {}", m.index()))).collect());
    };
    let mut placed = Vec::new();
    // A node is in at most one tree and has at most one parent (§3.5.3): a node reached twice (a
    // cycle, a shared child) is refused, which also bounds the walk by the node count.
    let mut seen = vec![false; document.nodes().len()];
    let mut stack: Vec<(::gltf::Node, DMat4)> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let at = format!("node {}", node.index());
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err((at, "is reached twice: a scene's nodes must form disjoint trees (glTF 2.0 §3.5.3)".into()));
        }
        let world = parent * local_transform(&node.transform()).map_err(|reason| (at.clone(), reason))?;
        if !world.is_finite() {
            return Err((at, "the world transform is not finite".into()));
        }
        stack.extend(node.children().collect::<Vec<_>>().into_iter().rev().map(|c| (c, world)));
        if let Some(mesh) = node.mesh() {
            placed.push((mesh, world, at));
        }
    }
    Ok(placed)
}

/// A node's local transform (§3.5.2): its `matrix` (column-major), or T·R·S with the rotation
/// quaternion normalized (it is stored as f32, so it is unit only to that precision).
fn local_transform(transform: &::gltf::scene::Transform) -> Result<DMat4, String> {
    let to64 = |v: [f32; 3]| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
    Ok(match *transform {
        ::gltf::scene::Transform::Matrix { matrix } => DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from))),
        ::gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            let [x, y, z, w] = rotation.map(f64::from);
            let q = DVec4::new(x, y, z, w)
                .try_normalize()
                .ok_or_else(|| format!("the rotation {rotation:?} is not a unit quaternion"))?;
            let rotation = DQuat::from_vec4(q);
            DMat4::from_scale_rotation_translation(to64(scale), rotation, to64(translation))
        }
    })
}

/// The scene as it is flattened.
struct Flattened {
    path: PathBuf,
    buffers: Vec<Vec<u8>>,
    /// What is placed so far; `normals` is `None` from the first primitive without NORMAL.
    geometry: Geometry,
}

/// A problem of one primitive, before the caller says where it is.
enum Problem {
    Invalid(String),
    Unsupported(String),
}

/// Bytes of memory a vertex of the scene takes while it is flattened: the decoded primitive's and
/// the placed copy's position and normal (DVec3 each).
const VERTEX_BYTES: u128 = 96;
/// Bytes of a triangle corner: its index as decoded and in the placed triangle (u32 each).
const CORNER_BYTES: u128 = 8;

impl Flattened {
    fn invalid(&self, at: String, reason: String) -> GltfError {
        GltfError::Invalid { path: self.path.clone(), at, reason }
    }

    /// Appends the primitives of `mesh`, placed by `world` (`at`: the node that places it).
    fn place(&mut self, mesh: &::gltf::Mesh, world: DMat4, at: String) -> Result<(), GltfError> {
        let linear = DMat3::from_mat4(world);
        let det = linear.determinant();
        if det == 0.0 || !det.is_finite() {
            return Err(self.invalid(at, "the world transform is singular".into()));
        }
        // Normals go by the inverse transpose, so that they stay perpendicular to the placed
        // surface; a mirroring transform (det < 0) turns the winding, which is turned back (§3.7.4).
        let normal_matrix = linear.inverse().transpose();
        let identity = world == DMat4::IDENTITY;
        for primitive in mesh.primitives() {
            let at = format!("mesh {}, primitive {}", mesh.index(), primitive.index());
            let wrap = |p: Problem| match p {
                Problem::Invalid(reason) => GltfError::Invalid { path: self.path.clone(), at: at.clone(), reason },
                Problem::Unsupported(reason) => {
                    GltfError::Unsupported { path: self.path.clone(), at: at.clone(), reason }
                }
            };
            let (positions, normals, triangles) = self.primitive(&primitive).map_err(wrap)?;
            let uvs = self.uvs(&primitive, positions.len());
            let base = u32::try_from(self.geometry.positions.len())
                .ok()
                .filter(|b| b.checked_add(positions.len() as u32).is_some() && positions.len() <= u32::MAX as usize)
                .ok_or_else(|| wrap(Problem::Invalid("the scene has more than 2³² vertices".into())))?;
            for p in &positions {
                let placed = if identity { *p } else { world.transform_point3(*p) };
                if !placed.is_finite() {
                    return Err(wrap(Problem::Invalid("a position is not finite once placed by its node".into())));
                }
                self.geometry.positions.push(placed);
            }
            self.geometry.normals = match (normals, self.geometry.normals.take()) {
                (Some(n), Some(mut all)) => {
                    all.extend(n.iter().map(|v| if identity { *v } else { (normal_matrix * *v).normalize_or_zero() }));
                    Some(all)
                }
                _ => None,
            };
            self.geometry.uvs = match (uvs, self.geometry.uvs.take()) {
                (Some(uv), Some(mut all)) => {
                    all.extend(uv);
                    Some(all)
                }
                _ => None,
            };
            let turn = |[a, b, c]: [u32; 3]| if det < 0.0 { [a, c, b] } else { [a, b, c] };
            self.geometry.triangles.extend(triangles.into_iter().map(|t| turn(t).map(|i| base + i)));
        }
        Ok(())
    }

    /// One primitive's positions, normals (if it has them) and triangles, in its own numbering.
    /// Its size is checked against the memory budget, with what is placed so far, before a byte
    /// of it is decoded: an asset that places one large mesh many times could exceed it.
    #[allow(clippy::type_complexity)]
    fn primitive(
        &self,
        primitive: &::gltf::Primitive,
    ) -> Result<(Vec<DVec3>, Option<Vec<DVec3>>, Vec<[u32; 3]>), Problem> {
        let mode = primitive.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            return Err(Problem::Unsupported(format!("mode {mode:?} draws points or lines, which have no surface")));
        }
        let position = primitive.get(&Semantic::Positions).ok_or(Problem::Invalid("no POSITION attribute".into()))?;
        let vertices = self.geometry.positions.len() as u128 + position.count() as u128;
        let corners = 3 * self.geometry.triangles.len() as u128
            + primitive.indices().map_or(position.count(), |i| i.count()) as u128;
        crate::limits::check_memory("the flattened glTF scene", vertices * VERTEX_BYTES + corners * CORNER_BYTES)
            .map_err(|e| Problem::Invalid(e.to_string()))?;
        let positions = self.vec3(&position, "POSITION")?;
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(Problem::Invalid("a POSITION is not finite".into()));
        }
        let normals = match primitive.get(&Semantic::Normals) {
            Some(accessor) => {
                let normals = self.vec3(&accessor, "NORMAL")?;
                if normals.len() != positions.len() {
                    let (n, p) = (normals.len(), positions.len());
                    return Err(Problem::Invalid(format!("NORMAL has {n} elements for {p} positions")));
                }
                // A normal that is not finite is no direction: left zero, for the mesh to compute.
                Some(normals.into_iter().map(|n| if n.is_finite() { n } else { DVec3::ZERO }).collect())
            }
            None => None,
        };
        let indices = match primitive.indices() {
            Some(accessor) => {
                let indices = self.indices(&accessor)?;
                if let Some(&i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                    return Err(Problem::Invalid(format!("index {i} is out of range ({} vertices)", positions.len())));
                }
                indices
            }
            None => (0..positions.len() as u32).collect(),
        };
        let triangles = triangles(mode, &indices)?;
        Ok((positions, normals, triangles))
    }

    /// The bytes of every element of `accessor`, `element` bytes each, in order: the accessor's
    /// range within its buffer view, and the view's within its buffer, checked first (§3.6.2).
    fn elements<'b>(
        &'b self,
        accessor: &::gltf::Accessor,
        element: usize,
    ) -> Result<impl Iterator<Item = &'b [u8]> + 'b, Problem> {
        let index = accessor.index();
        if accessor.sparse().is_some() {
            return Err(Problem::Unsupported(format!("accessor {index} is sparse")));
        }
        let (count, offset) = (accessor.count(), accessor.offset());
        let view = accessor.view().ok_or_else(|| Problem::Invalid(format!("accessor {index} has no bufferView")))?;
        let buffer = &self.buffers[view.buffer().index()];
        let Some(bytes) = view.offset().checked_add(view.length()).and_then(|end| buffer.get(view.offset()..end))
        else {
            return Err(Problem::Invalid(format!(
                "buffer view {} (bytes {}..{}+{}) runs past the end of buffer {} ({} bytes)",
                view.index(),
                view.offset(),
                view.offset(),
                view.length(),
                view.buffer().index(),
                buffer.len()
            )));
        };
        let stride = view.stride().unwrap_or(element);
        if stride < element {
            return Err(Problem::Invalid(format!(
                "buffer view {} has a byteStride of {stride}, less than accessor {index}'s {element}-byte elements",
                view.index()
            )));
        }
        let end = match count {
            0 => Some(offset),
            _ => {
                (count - 1).checked_mul(stride).and_then(|x| x.checked_add(element)).and_then(|x| x.checked_add(offset))
            }
        };
        if end.is_none_or(|end| end > bytes.len()) {
            return Err(Problem::Invalid(format!(
                "accessor {index} ({count} elements of {element} bytes, {stride} apart, from byte {offset}) runs past \
                 the end of buffer view {} ({} bytes)",
                view.index(),
                bytes.len()
            )));
        }
        Ok((0..count).map(move |i| &bytes[offset + i * stride..][..element]))
    }

    /// A float VEC3 attribute (§3.7.2.1: POSITION and NORMAL are float VEC3 in glTF 2.0 itself).
    fn vec3(&self, accessor: &::gltf::Accessor, semantic: &str) -> Result<Vec<DVec3>, Problem> {
        if (accessor.data_type(), accessor.dimensions()) != (DataType::F32, Dimensions::Vec3) {
            return Err(Problem::Unsupported(format!(
                "{semantic} is {:?} of {:?} (KHR_mesh_quantization); glTF 2.0 itself has float VEC3",
                accessor.dimensions(),
                accessor.data_type()
            )));
        }
        let f = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64;
        Ok(self.elements(accessor, 12)?.map(|e| DVec3::new(f(&e[0..4]), f(&e[4..8]), f(&e[8..12]))).collect())
    }

    /// The primitive's lightmap UVs ([`Geometry::uvs`]), one per vertex, or `None`.
    fn uvs(&self, primitive: &::gltf::Primitive, vertices: usize) -> Option<Vec<[f64; 2]>> {
        let accessor = primitive.get(&Semantic::TexCoords(1)).or_else(|| primitive.get(&Semantic::TexCoords(0)))?;
        if accessor.dimensions() != Dimensions::Vec2 || accessor.count() != vertices {
            return None;
        }
        let (size, normalized) = (accessor.data_type(), accessor.normalized());
        let element = match (size, normalized) {
            (DataType::F32, _) => 8,
            (DataType::U16, true) => 4,
            (DataType::U8, true) => 2,
            _ => return None,
        };
        let elements = self.elements(&accessor, element).ok()?;
        let uvs: Vec<[f64; 2]> = elements
            .map(|e| match size {
                DataType::F32 => [0, 4].map(|k| f32::from_le_bytes([e[k], e[k + 1], e[k + 2], e[k + 3]]) as f64),
                DataType::U16 => [0, 2].map(|k| u16::from_le_bytes([e[k], e[k + 1]]) as f64 / 65535.0),
                _ => [0, 1].map(|k| e[k] as f64 / 255.0),
            })
            .collect();
        uvs.iter().flatten().all(|c| c.is_finite()).then_some(uvs)
    }

    /// Vertex indices (§3.7.2.1: unsigned byte, short or int SCALAR).
    fn indices(&self, accessor: &::gltf::Accessor) -> Result<Vec<u32>, Problem> {
        let size = match (accessor.data_type(), accessor.dimensions()) {
            (DataType::U8, Dimensions::Scalar) => 1,
            (DataType::U16, Dimensions::Scalar) => 2,
            (DataType::U32, Dimensions::Scalar) => 4,
            (t, d) => {
                return Err(Problem::Invalid(format!(
                    "the indices are {d:?} of {t:?}, not unsigned byte, short or int scalars"
                )))
            }
        };
        Ok(self
            .elements(accessor, size)?
            .map(|e| match size {
                1 => e[0] as u32,
                2 => u16::from_le_bytes([e[0], e[1]]) as u32,
                _ => u32::from_le_bytes([e[0], e[1], e[2], e[3]]),
            })
            .collect())
    }
}

/// The triangles of a vertex sequence (§3.7.2.1, "Topology types"): in TRIANGLES each three
/// vertices; in a strip triangle i is (v_i, v_{i+1+i%2}, v_{i+2−i%2}); in a fan (v_{i+1}, v_{i+2}, v_0).
fn triangles(mode: Mode, v: &[u32]) -> Result<Vec<[u32; 3]>, Problem> {
    Ok(match mode {
        Mode::Triangles => {
            if v.len() % 3 != 0 {
                return Err(Problem::Invalid(format!("{} vertices do not make whole triangles", v.len())));
            }
            v.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
        }
        Mode::TriangleStrip => {
            (0..v.len().saturating_sub(2)).map(|i| [v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]]).collect()
        }
        Mode::TriangleFan => (0..v.len().saturating_sub(2)).map(|i| [v[i + 1], v[i + 2], v[0]]).collect(),
        _ => unreachable!("points and lines are refused before"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_follow_the_specification() {
        let strip = triangles(Mode::TriangleStrip, &[0, 1, 2, 3, 4]).ok().unwrap();
        // Every triangle of a strip keeps the first one's winding.
        assert_eq!(strip, vec![[0, 1, 2], [1, 3, 2], [2, 3, 4]]);
        let fan = triangles(Mode::TriangleFan, &[0, 1, 2, 3]).ok().unwrap();
        assert_eq!(fan, vec![[1, 2, 0], [2, 3, 0]]);
        assert!(triangles(Mode::Triangles, &[0, 1]).is_err());
        assert!(triangles(Mode::TriangleStrip, &[0, 1]).ok().unwrap().is_empty());
    }

    #[test]
    fn uris_are_data_or_relative_paths() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("a%2"), None);
        assert_eq!(percent_decode("a%zz"), None);
        let here = Path::new("dir/scene.gltf");
        assert_eq!(buffer_uri(here, "data:application/octet-stream;base64,AAEC").unwrap(), vec![0, 1, 2]);
        assert!(buffer_uri(here, "data:application/octet-stream,abc").unwrap_err().contains("not base64"));
        assert!(buffer_uri(here, "data:;base64,!!").unwrap_err().contains("base64"));
        for uri in ["/etc/passwd", "file:///etc/passwd", "https://example.com/a.bin", "C:x.bin"] {
            assert!(buffer_uri(here, uri).unwrap_err().contains("not a relative path"), "{uri}");
        }
        let e = buffer_uri(here, "missing%20file.bin").unwrap_err();
        assert!(e.contains("dir/missing file.bin"), "{e}");
    }

    #[test]
    fn glb_headers_are_checked_before_the_crate_reads_them() {
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(4u32.to_le_bytes());
        assert!(glb_container(&glb).unwrap_err().contains("less than its headers"));
        glb[8..12].copy_from_slice(&100u32.to_le_bytes());
        assert!(glb_container(&glb).unwrap_err().contains("truncated"));
        glb[4..8].copy_from_slice(&1u32.to_le_bytes());
        assert!(glb_container(&glb).unwrap_err().contains("version 1"));
        assert!(glb_container(b"glTF\x02").unwrap_err().contains("cut short"));
        assert_eq!(glb_container(b"{}").unwrap(), b"{}");
    }

    #[test]
    fn transforms_are_t_r_s_with_the_quaternion_normalized() {
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let m = local_transform(&::gltf::scene::Transform::Decomposed {
            translation: [1.0, 2.0, 3.0],
            rotation: [0.0, 0.0, h * 2.0, h * 2.0], // 90° about +Z, twice unit length
            scale: [2.0, 1.0, 1.0],
        })
        .unwrap();
        // x scaled by 2, turned onto +y, then moved.
        let p = m.transform_point3(DVec3::X);
        assert!((p - DVec3::new(1.0, 4.0, 3.0)).length() < 1e-7, "{p}");
        let zero = ::gltf::scene::Transform::Decomposed { translation: [0.0; 3], rotation: [0.0; 4], scale: [1.0; 3] };
        assert!(local_transform(&zero).is_err());
    }
}
