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
//!
//! [`read_coloured`] also reads each vertex's base colour (albedo), the core metallic-roughness
//! material's `baseColorFactor × baseColorTexture × COLOR_0` (§3.9.2) evaluated at the vertex,
//! the texture sampled bilinearly in linear values ([`BaseColourTexture`];
//! `docs/formats/mesh-colours.md`). [`read`] decodes no texture.

use super::read::{display_path, read_bytes};
use super::IoError;
use crate::limits::{human_bytes, LimitError};
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use ::gltf::texture::WrappingMode;
use ::gltf::Semantic;
use base64::Engine as _;
use glam::{DMat3, DMat4, DQuat, DVec3, DVec4};
use std::collections::HashMap;
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
    /// A primitive's base-colour texture cannot be had ([`read_coloured`] alone): its image is
    /// missing, unreadable, neither PNG nor JPEG, or in an extension; its `texCoord` set is not on
    /// the primitive or cannot be read.
    #[error("{path}: {at}: {reason}")]
    Texture {
        /// The glTF file.
        path: PathBuf,
        /// Which primitive, texture and image, e.g. "mesh 0, primitive 1, baseColorTexture
        /// (texture 0, image 2)".
        at: String,
        /// What is wrong.
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
    read_with(path, false).map(|(geometry, _)| geometry)
}

/// As [`read`], and each vertex's linear RGB base colour, one per position in the same order:
/// per primitive, `baseColorFactor.rgb × baseColorTexture.rgb × COLOR_0.rgb` (glTF 2.0 §3.9.2;
/// each factor white when absent, a primitive without material white), alpha ignored. The
/// texture is sampled as [`BaseColourTexture::sample`] says; COLOR_0 is float or normalized
/// unsigned byte/short VEC3 or VEC4 (§3.7.2.1), linear. A texture that cannot be had, a
/// `texCoord` set the primitive lacks, KHR_texture_transform on the base-colour texture, or a
/// colour that is negative or not finite is an error naming the file and the object.
pub fn read_coloured(path: &Path) -> Result<(Geometry, Vec<[f64; 3]>), GltfError> {
    read_with(path, true).map(|(geometry, colours)| (geometry, colours.unwrap_or_default()))
}

/// Linear RGB base colours, one per vertex.
type BaseColours = Vec<[f64; 3]>;

/// [`read`], and with `colours` [`read_coloured`]'s colours.
fn read_with(path: &Path, colours: bool) -> Result<(Geometry, Option<BaseColours>), GltfError> {
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
        source: path.to_path_buf(),
        buffers,
        geometry: Geometry {
            positions: Vec::new(),
            normals: Some(Vec::new()),
            triangles: Vec::new(),
            uvs: Some(Vec::new()),
        },
        colours: colours.then(Vec::new),
        images: HashMap::new(),
        image_bytes: 0,
    };
    for (mesh, world, at) in placements(&document).map_err(|(at, reason)| scene.invalid(at, reason))? {
        scene.place(&document, &mesh, world, at)?;
    }
    Ok((scene.geometry, scene.colours))
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
            ::gltf::buffer::Source::Uri(uri) => buffer_uri(path, uri, "glTF buffer").map_err(error)?,
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
/// schemes are refused: an asset names the files beside it. `what` names the file's role in
/// messages ("glTF buffer", "glTF image").
fn buffer_uri(gltf: &Path, uri: &str, what: &'static str) -> Result<Vec<u8>, String> {
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
    read_bytes(&file, what, crate::limits::max_file_bytes(), |_| Ok(())).map_err(|e| e.to_string())
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
    /// The file, as messages name it.
    path: PathBuf,
    /// The file as given, against which relative image URIs resolve.
    source: PathBuf,
    buffers: Vec<Vec<u8>>,
    /// What is placed so far; `normals` is `None` from the first primitive without NORMAL.
    geometry: Geometry,
    /// The base colours placed so far, when they are read ([`read_coloured`]).
    colours: Option<Vec<[f64; 3]>>,
    /// The images decoded so far, by image index: each once, however many textures name it.
    images: HashMap<usize, BaseColourTexture>,
    /// Bytes the decoded images take together, kept within the memory budget.
    image_bytes: u128,
}

/// A problem of one primitive, before the caller says where it is.
enum Problem {
    Invalid(String),
    Unsupported(String),
}

impl Problem {
    fn reason(self) -> String {
        match self {
            Problem::Invalid(reason) | Problem::Unsupported(reason) => reason,
        }
    }
}

/// The component-wise product of two colours.
fn times(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}

/// Bytes of memory a texel of a base-colour image may take while it is decoded: the decoder's
/// RGBA at 16 bits (8 bytes) and the RGB codes kept (up to 6).
const IMAGE_TEXEL_BYTES: u64 = 14;

/// A decoded base-colour image (glTF 2.0 §3.9.2): its sRGB-encoded codes, RGB from the top row
/// down, and the linear value of each code, so that texels are decoded to linear exactly (in f64)
/// when they are sampled, and the image takes 3 or 6 bytes a texel.
struct BaseColourTexture {
    width: usize,
    height: usize,
    codes: Codes,
    /// The linear value of each code: `srgb_decode(code / max)`.
    linear: Vec<f64>,
}

/// An image's codes: 8-bit (PNG, JPEG), or 16-bit (PNG).
enum Codes {
    Eight(Vec<u8>),
    Sixteen(Vec<u16>),
}

/// Why an image cannot be decoded.
enum ImageProblem {
    Limit(crate::limits::LimitError),
    Bad(String),
}

impl BaseColourTexture {
    /// Decodes a PNG or JPEG (glTF 2.0 §3.8.3, the two image formats of core glTF). Its size is
    /// read from the header and checked (`check_size`: the texel ceiling of an image read) before
    /// any texel is decoded; a grey image is read as RGB, alpha is dropped.
    fn decode(
        bytes: &[u8],
        check_size: impl Fn(u64, u64) -> Result<(), crate::limits::LimitError>,
    ) -> Result<Self, ImageProblem> {
        use ::image::{DynamicImage, ImageFormat, ImageReader};
        let reader = || -> Result<ImageReader<std::io::Cursor<&[u8]>>, ImageProblem> {
            let reader = ImageReader::new(std::io::Cursor::new(bytes))
                .with_guessed_format()
                .map_err(|e| ImageProblem::Bad(e.to_string()))?;
            match reader.format() {
                Some(ImageFormat::Png | ImageFormat::Jpeg) => Ok(reader),
                Some(format) => Err(ImageProblem::Bad(format!("the image is {format:?}, not PNG or JPEG"))),
                None => Err(ImageProblem::Bad("the image is neither PNG nor JPEG (by its first bytes)".into())),
            }
        };
        let (width, height) = reader()?.into_dimensions().map_err(|e| ImageProblem::Bad(e.to_string()))?;
        if width == 0 || height == 0 {
            return Err(ImageProblem::Bad(format!("the image is {width}x{height}")));
        }
        check_size(width as u64, height as u64).map_err(ImageProblem::Limit)?;
        let mut reader = reader()?;
        // The ceiling above is prtkit's; the decoder's own allocation limit (512 MiB by default)
        // is raised to the memory budget so that it is not a second, different ceiling.
        let mut limits = ::image::Limits::default();
        limits.max_alloc = Some(crate::limits::memory_budget());
        reader.limits(limits);
        let image = reader.decode().map_err(|e| ImageProblem::Bad(e.to_string()))?;
        let sixteen = matches!(
            image,
            DynamicImage::ImageLuma16(_)
                | DynamicImage::ImageLumaA16(_)
                | DynamicImage::ImageRgb16(_)
                | DynamicImage::ImageRgba16(_)
        );
        let (codes, max) = match sixteen {
            true => (Codes::Sixteen(image.to_rgb16().into_raw()), u16::MAX as u32),
            false => (Codes::Eight(image.to_rgb8().into_raw()), u8::MAX as u32),
        };
        let linear = (0..=max).map(|c| super::png::srgb_decode(c as f64 / max as f64)).collect();
        Ok(BaseColourTexture { width: width as usize, height: height as usize, codes, linear })
    }

    /// The linear RGB of texel (i, j), column i from the left, row j from the top.
    fn texel(&self, i: usize, j: usize) -> [f64; 3] {
        let at = 3 * (j * self.width + i);
        match &self.codes {
            Codes::Eight(c) => [0, 1, 2].map(|k| self.linear[c[at + k] as usize]),
            Codes::Sixteen(c) => [0, 1, 2].map(|k| self.linear[c[at + k] as usize]),
        }
    }

    /// The linear RGB at `uv`, filtered bilinearly between the four nearest texels *after* each
    /// is decoded to linear (glTF 2.0 §3.9.2: "the transfer function SHOULD be decoded before
    /// performing linear interpolation"). UV (0, 0) is the image's top-left corner (§3.8.4) and
    /// texel (i, j)'s centre is at ((i + ½)/W, (j + ½)/H) (OpenGL 4.6 §8.14.2, which glTF's
    /// samplers follow), so the texel coordinate of u is uW − ½. The neighbours' indices are
    /// wrapped by the sampler's modes, s for u and t for v ([`wrap`]). The sampler's filters
    /// are not used: a vertex reads the full-resolution image, bilinearly, whatever they say.
    fn sample(&self, [u, v]: [f64; 2], [wrap_s, wrap_t]: [WrappingMode; 2]) -> [f64; 3] {
        let (x, y) = (u * self.width as f64 - 0.5, v * self.height as f64 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        // `as` saturates: a UV far outside [0, 1] still lands on a texel.
        let (x0, y0) = (x0 as i64, y0 as i64);
        let [i0, i1] = [x0, x0.saturating_add(1)].map(|i| wrap(i, self.width, wrap_s));
        let [j0, j1] = [y0, y0.saturating_add(1)].map(|j| wrap(j, self.height, wrap_t));
        let (a, b, c, d) = (self.texel(i0, j0), self.texel(i1, j0), self.texel(i0, j1), self.texel(i1, j1));
        [0, 1, 2].map(|k| (1.0 - fy) * ((1.0 - fx) * a[k] + fx * b[k]) + fy * ((1.0 - fx) * c[k] + fx * d[k]))
    }
}

/// A texel index wrapped into 0..size by a sampler's mode (OpenGL 4.6 §8.14.2, Table 8.20, which
/// glTF 2.0 §3.8.4 names): REPEAT takes it modulo the size; CLAMP_TO_EDGE clamps it to the edge
/// texels; MIRRORED_REPEAT repeats the image and its mirror image, period 2·size, so index −1 is
/// texel 0 and index size is texel size − 1.
fn wrap(i: i64, size: usize, mode: WrappingMode) -> usize {
    let n = size as i64;
    (match mode {
        WrappingMode::Repeat => i.rem_euclid(n),
        WrappingMode::ClampToEdge => i.clamp(0, n - 1),
        WrappingMode::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n {
                m
            } else {
                2 * n - 1 - m
            }
        }
    }) as usize
}

/// Bytes of memory a vertex of the scene takes while it is flattened: the decoded primitive's and
/// the placed copy's position and normal (DVec3 each).
const VERTEX_BYTES: u128 = 96;
/// Bytes of a triangle corner: its index as decoded and in the placed triangle (u32 each).
const CORNER_BYTES: u128 = 8;
/// Bytes a vertex's base colour takes on top ([`read_coloured`]): the primitive's and the
/// scene's copy ([f64; 3] each).
const COLOUR_BYTES: u128 = 48;

impl Flattened {
    fn invalid(&self, at: String, reason: String) -> GltfError {
        GltfError::Invalid { path: self.path.clone(), at, reason }
    }

    /// Appends the primitives of `mesh`, placed by `world` (`at`: the node that places it).
    fn place(
        &mut self,
        document: &::gltf::Document,
        mesh: &::gltf::Mesh,
        world: DMat4,
        at: String,
    ) -> Result<(), GltfError> {
        let linear = DMat3::from_mat4(world);
        let det = linear.determinant();
        if det == 0.0 || !det.is_finite() {
            return Err(self.invalid(at, "the world transform is singular".into()));
        }
        // Normals go by the inverse transpose, so that they stay perpendicular to the placed
        // surface; a mirroring transform (det < 0) turns the winding, which is turned back (§3.7.4).
        let normal_matrix = linear.inverse().transpose();
        let identity = world == DMat4::IDENTITY;
        let path = self.path.clone();
        for primitive in mesh.primitives() {
            let at = format!("mesh {}, primitive {}", mesh.index(), primitive.index());
            let wrap = |p: Problem| match p {
                Problem::Invalid(reason) => GltfError::Invalid { path: path.clone(), at: at.clone(), reason },
                Problem::Unsupported(reason) => GltfError::Unsupported { path: path.clone(), at: at.clone(), reason },
            };
            let (positions, normals, triangles) = self.primitive(&primitive).map_err(wrap)?;
            let uvs = self.uvs(&primitive, positions.len());
            let colours = match self.colours {
                Some(_) => Some(self.base_colours(document, &primitive, positions.len(), &at)?),
                None => None,
            };
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
            if let (Some(colours), Some(all)) = (colours, self.colours.as_mut()) {
                all.extend(colours);
            }
            let turn = |[a, b, c]: [u32; 3]| if det < 0.0 { [a, c, b] } else { [a, b, c] };
            self.geometry.triangles.extend(triangles.into_iter().map(|t| turn(t).map(|i| base + i)));
        }
        Ok(())
    }

    /// One primitive's base colours, one per vertex ([`read_coloured`]). `at` names the
    /// primitive.
    fn base_colours(
        &mut self,
        document: &::gltf::Document,
        primitive: &::gltf::Primitive,
        vertices: usize,
        at: &str,
    ) -> Result<Vec<[f64; 3]>, GltfError> {
        let path = self.path.clone();
        let invalid = |at: String, reason: String| GltfError::Invalid { path: path.clone(), at, reason };
        let texture_error = |at: &str, reason: String| GltfError::Texture { path: path.clone(), at: at.into(), reason };
        // §3.9.1: a primitive without material is drawn with the default material, whose
        // baseColorFactor is (1, 1, 1, 1) and which has no texture; so is `material()`'s.
        let material = primitive.material();
        let material_at = match material.index() {
            Some(m) => format!("{at}, material {m}"),
            None => at.to_string(),
        };
        let pbr = material.pbr_metallic_roughness();
        let [r, g, b, _] = pbr.base_color_factor();
        let factor = [r, g, b].map(f64::from);
        if factor.iter().any(|c| !c.is_finite() || *c < 0.0) {
            let reason = format!("baseColorFactor {factor:?} is not a colour (a negative or infinite component)");
            return Err(invalid(material_at, reason));
        }
        let mut colours = vec![factor; vertices];
        if let Some(accessor) = primitive.get(&Semantic::Colors(0)) {
            let colour_0 = self.colour_0(&accessor, vertices).map_err(|p| invalid(at.into(), p.reason()))?;
            colours.iter_mut().zip(colour_0).for_each(|(c, k)| *c = times(*c, k));
        }
        let Some(info) = pbr.base_color_texture() else {
            return Ok(colours);
        };
        let texture = info.texture();
        let texture_at = format!("{material_at}, baseColorTexture (texture {})", texture.index());
        if info.extension_value("KHR_texture_transform").is_some() {
            // It moves, turns and scales the UVs the texture is read at: ignoring it would read the
            // wrong texels, silently.
            let reason = "KHR_texture_transform (an offset, rotation or scale of its UVs)".into();
            return Err(GltfError::Unsupported { path: path.clone(), at: texture_at, reason });
        }
        let set = info.tex_coord();
        let Some(accessor) = primitive.get(&Semantic::TexCoords(set)) else {
            return Err(texture_error(&texture_at, format!("it is read at TEXCOORD_{set}, which the primitive lacks")));
        };
        let uvs = self
            .texcoords(&accessor, vertices)
            .map_err(|p| texture_error(&texture_at, format!("its TEXCOORD_{set}: {}", p.reason())))?;
        let Some(image) = texture.source() else {
            let extensions: Vec<&str> =
                texture.extensions().into_iter().flat_map(|e| e.keys()).map(|k| k.as_str()).collect();
            let reason = format!("its image is in an extension ({}), not a PNG or JPEG", extensions.join(", "));
            return Err(GltfError::Unsupported { path: path.clone(), at: texture_at, reason });
        };
        let image_at =
            format!("{material_at}, baseColorTexture (texture {}, image {})", texture.index(), image.index());
        self.decode_image(document, image.index(), &image_at)?;
        let texels = &self.images[&image.index()];
        let sampler = texture.sampler();
        let wrap = [sampler.wrap_s(), sampler.wrap_t()];
        colours.iter_mut().zip(uvs).for_each(|(c, uv)| *c = times(*c, texels.sample(uv, wrap)));
        Ok(colours)
    }

    /// A primitive's COLOR_0 (§3.7.2.1): float, or normalized unsigned byte or short, VEC3 or VEC4
    /// (alpha dropped), linear; every colour finite and not negative.
    fn colour_0(&self, accessor: &::gltf::Accessor, vertices: usize) -> Result<Vec<[f64; 3]>, Problem> {
        let channels = match accessor.dimensions() {
            Dimensions::Vec3 => 3,
            Dimensions::Vec4 => 4,
            d => return Err(Problem::Invalid(format!("COLOR_0 is {d:?}, not VEC3 or VEC4"))),
        };
        if accessor.count() != vertices {
            return Err(Problem::Invalid(format!(
                "COLOR_0 has {} elements for {vertices} positions",
                accessor.count()
            )));
        }
        let (data_type, normalized) = (accessor.data_type(), accessor.normalized());
        let size = match (data_type, normalized) {
            (DataType::F32, _) => 4,
            (DataType::U16, true) => 2,
            (DataType::U8, true) => 1,
            _ => {
                return Err(Problem::Invalid(format!(
                "COLOR_0 is {data_type:?} (normalized: {normalized}), not float or normalized unsigned byte or short"
            )))
            }
        };
        // §3.11 (accessor data types): a normalized unsigned integer c stands for c / (2ⁿ − 1).
        let value = |e: &[u8], k: usize| match data_type {
            DataType::F32 => f32::from_le_bytes([e[4 * k], e[4 * k + 1], e[4 * k + 2], e[4 * k + 3]]) as f64,
            DataType::U16 => u16::from_le_bytes([e[2 * k], e[2 * k + 1]]) as f64 / 65535.0,
            _ => e[k] as f64 / 255.0,
        };
        let colours: Vec<[f64; 3]> =
            self.elements(accessor, channels * size)?.map(|e| [0, 1, 2].map(|k| value(e, k))).collect();
        if let Some((i, c)) = colours.iter().enumerate().find(|(_, c)| c.iter().any(|x| !x.is_finite() || *x < 0.0)) {
            return Err(Problem::Invalid(format!(
                "COLOR_0 of vertex {i} is {c:?}, not a colour (a negative component, or one not finite)"
            )));
        }
        Ok(colours)
    }

    /// Decodes image `index` into [`Flattened::images`] unless it is there: its bytes from its
    /// bufferView (§3.6.2, a GLB's images), or from its `uri` by [`buffer_uri`]'s rules (a
    /// relative path read within the file ceiling, or a `data:` URI of a file read within it);
    /// its size checked against the image ceiling before it is decoded, and the images'
    /// decoded bytes together against the memory budget.
    fn decode_image(&mut self, document: &::gltf::Document, index: usize, at: &str) -> Result<(), GltfError> {
        if self.images.contains_key(&index) {
            return Ok(());
        }
        let error = |reason: String| GltfError::Texture { path: self.path.clone(), at: at.into(), reason };
        let limit = |error| GltfError::Limit { path: self.path.clone(), error };
        let json = &document.as_json().images[index];
        let from_uri;
        let bytes: &[u8] = match (&json.buffer_view, &json.uri) {
            (Some(view), _) => {
                let view = document
                    .views()
                    .nth(view.value())
                    .ok_or_else(|| error(format!("its bufferView {} does not exist", view.value())))?;
                let buffer = &self.buffers[view.buffer().index()];
                view.offset().checked_add(view.length()).and_then(|end| buffer.get(view.offset()..end)).ok_or_else(
                    || {
                        error(format!(
                            "its buffer view {} runs past the end of buffer {} ({} bytes)",
                            view.index(),
                            view.buffer().index(),
                            buffer.len()
                        ))
                    },
                )?
            }
            (None, Some(uri)) => {
                let named = if uri.starts_with("data:") { "its data: URI".to_string() } else { format!("{uri:?}") };
                from_uri = buffer_uri(&self.source, uri, "glTF image")
                    .map_err(|e| error(format!("cannot read {named}: {e}")))?;
                &from_uri
            }
            (None, None) => return Err(error("the image has neither a uri nor a bufferView".into())),
        };
        let check = |w, h| crate::limits::check_image(at, w, h, IMAGE_TEXEL_BYTES);
        let texture = BaseColourTexture::decode(bytes, check).map_err(|p| match p {
            ImageProblem::Limit(e) => limit(e),
            ImageProblem::Bad(reason) => error(format!("cannot decode the image: {reason}")),
        })?;
        let kept = match &texture.codes {
            Codes::Eight(c) => c.len() as u128,
            Codes::Sixteen(c) => 2 * c.len() as u128,
        };
        self.image_bytes += kept;
        crate::limits::check_memory("the glTF's base-colour images together", self.image_bytes).map_err(limit)?;
        self.images.insert(index, texture);
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
        let vertex_bytes = VERTEX_BYTES + if self.colours.is_some() { COLOUR_BYTES } else { 0 };
        crate::limits::check_memory("the flattened glTF scene", vertices * vertex_bytes + corners * CORNER_BYTES)
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
        self.texcoords(&accessor, vertices).ok()
    }

    /// A TEXCOORD_n accessor, one (u, v) per vertex: float, or normalized unsigned byte or
    /// short, VEC2 (§3.7.2.1), every coordinate finite.
    fn texcoords(&self, accessor: &::gltf::Accessor, vertices: usize) -> Result<Vec<[f64; 2]>, Problem> {
        let index = accessor.index();
        if accessor.dimensions() != Dimensions::Vec2 {
            return Err(Problem::Invalid(format!("accessor {index} is {:?}, not VEC2", accessor.dimensions())));
        }
        if accessor.count() != vertices {
            let count = accessor.count();
            return Err(Problem::Invalid(format!("accessor {index} has {count} elements for {vertices} positions")));
        }
        let (size, normalized) = (accessor.data_type(), accessor.normalized());
        let element = match (size, normalized) {
            (DataType::F32, _) => 8,
            (DataType::U16, true) => 4,
            (DataType::U8, true) => 2,
            _ => {
                return Err(Problem::Invalid(format!(
                    "accessor {index} is {size:?} (normalized: {normalized}), not float or normalized unsigned byte or short"
                )))
            }
        };
        let elements = self.elements(accessor, element)?;
        let uvs: Vec<[f64; 2]> = elements
            .map(|e| match size {
                DataType::F32 => [0, 4].map(|k| f32::from_le_bytes([e[k], e[k + 1], e[k + 2], e[k + 3]]) as f64),
                DataType::U16 => [0, 2].map(|k| u16::from_le_bytes([e[k], e[k + 1]]) as f64 / 65535.0),
                _ => [0, 1].map(|k| e[k] as f64 / 255.0),
            })
            .collect();
        match uvs.iter().flatten().all(|c| c.is_finite()) {
            true => Ok(uvs),
            false => Err(Problem::Invalid(format!("accessor {index} has a coordinate that is not finite"))),
        }
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
        assert_eq!(
            buffer_uri(here, "data:application/octet-stream;base64,AAEC", "glTF buffer").unwrap(),
            vec![0, 1, 2]
        );
        assert!(buffer_uri(here, "data:application/octet-stream,abc", "glTF buffer")
            .unwrap_err()
            .contains("not base64"));
        assert!(buffer_uri(here, "data:;base64,!!", "glTF buffer").unwrap_err().contains("base64"));
        for uri in ["/etc/passwd", "file:///etc/passwd", "https://example.com/a.bin", "C:x.bin"] {
            assert!(buffer_uri(here, uri, "glTF buffer").unwrap_err().contains("not a relative path"), "{uri}");
        }
        let e = buffer_uri(here, "missing%20file.bin", "glTF buffer").unwrap_err();
        assert!(e.contains("dir/missing file.bin"), "{e}");
    }

    #[test]
    fn wrap_modes_follow_the_opengl_table() {
        // OpenGL 4.6 Table 8.20 with size 3, indices −7..=7, written out (mirrored: period 6,
        // 0 1 2 2 1 0 from index 0, and index −1 is 0).
        let repeat = [2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1];
        let clamp = [0, 0, 0, 0, 0, 0, 0, 0, 1, 2, 2, 2, 2, 2, 2];
        let mirror = [0, 0, 1, 2, 2, 1, 0, 0, 1, 2, 2, 1, 0, 0, 1];
        for (k, i) in (-7i64..=7).enumerate() {
            assert_eq!(wrap(i, 3, WrappingMode::Repeat), repeat[k], "repeat {i}");
            assert_eq!(wrap(i, 3, WrappingMode::ClampToEdge), clamp[k], "clamp {i}");
            assert_eq!(wrap(i, 3, WrappingMode::MirroredRepeat), mirror[k], "mirror {i}");
        }
        // The far ends of i64 (a UV of ±1e300 saturates there) stay in range.
        for mode in [WrappingMode::Repeat, WrappingMode::ClampToEdge, WrappingMode::MirroredRepeat] {
            assert!(wrap(i64::MAX, 3, mode) < 3 && wrap(i64::MIN, 3, mode) < 3);
        }
    }

    #[test]
    fn a_texture_is_sampled_anywhere_without_panicking() {
        let mut png = std::io::Cursor::new(Vec::new());
        ::image::RgbImage::from_fn(3, 2, |x, y| ::image::Rgb([(x * 100) as u8, (y * 200) as u8, 7]))
            .write_to(&mut png, ::image::ImageFormat::Png)
            .unwrap();
        let texture = BaseColourTexture::decode(png.get_ref(), |_, _| Ok(())).ok().unwrap();
        assert_eq!((texture.width, texture.height), (3, 2));
        let modes = [WrappingMode::Repeat, WrappingMode::ClampToEdge, WrappingMode::MirroredRepeat];
        for u in [-1e300, -1e19, -2.5, 0.0, 0.5, 1.0, 7.25, 1e19, 1e300] {
            for mode in modes {
                let c = texture.sample([u, -u], [mode, mode]);
                assert!(c.iter().all(|x| x.is_finite() && (0.0..=1.0).contains(x)), "{u}: {c:?}");
            }
        }
        // Texel (2, 1) at its centre: codes 200, 200, 7.
        let c = texture.sample([2.5 / 3.0, 0.75], [WrappingMode::Repeat; 2]);
        let want = [200.0, 200.0, 7.0].map(|x: f64| super::super::png::srgb_decode(x / 255.0));
        assert!((0..3).all(|k| (c[k] - want[k]).abs() < 1e-12), "{c:?}");
        let refuse = |_, _| Err(crate::limits::check_image("x", u64::MAX, 1, 1).unwrap_err());
        assert!(matches!(BaseColourTexture::decode(png.get_ref(), refuse), Err(ImageProblem::Limit(_))));
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
