//! Binary glTF 2.0 (`.glb`): one mesh of one indexed triangle primitive with float or
//! normalized-integer vertex attributes, written by hand (Khronos glTF 2.0 specification, §4.4 "GLB File Format
//! Specification": a 12-byte header, a JSON chunk padded with spaces and a BIN chunk padded
//! with zeros, each to 4 bytes). Application-specific attributes are named with a leading
//! underscore (§3.7.2.1), e.g. `_PRT_0`.

use serde_json::{json, Value};

/// One vertex attribute: its semantic, components per vertex (1–4) and values, vertex after
/// vertex.
#[derive(Clone, Debug)]
pub struct Attribute {
    /// Semantic, e.g. `NORMAL` or `_PRT_0`.
    pub name: String,
    /// Components per vertex: 1 (SCALAR) to 4 (VEC4).
    pub components: usize,
    /// `components` × vertex count values.
    pub values: Values,
}

/// An attribute's values in the accessor component type they are stored as. A normalized
/// integer accessor (glTF 2.0 §3.6.2.2, `normalized: true`) is read by a client as
/// max(c / 32767, −1) (SHORT) or max(c / 127, −1) (BYTE) (§3.11's table of normalized integers).
#[derive(Clone, Debug)]
pub enum Values {
    /// FLOAT (5126).
    Float(Vec<f32>),
    /// SHORT (5122), normalized.
    NormalizedShort(Vec<i16>),
    /// BYTE (5120), normalized.
    NormalizedByte(Vec<i8>),
}

impl Values {
    fn len(&self) -> usize {
        match self {
            Values::Float(v) => v.len(),
            Values::NormalizedShort(v) => v.len(),
            Values::NormalizedByte(v) => v.len(),
        }
    }

    /// The little-endian bytes, the accessor's `componentType` and whether it is normalized.
    fn encoded(&self) -> (Vec<u8>, u32, bool) {
        match self {
            Values::Float(v) => (v.iter().flat_map(|x| x.to_le_bytes()).collect(), FLOAT, false),
            Values::NormalizedShort(v) => (v.iter().flat_map(|x| x.to_le_bytes()).collect(), SHORT, true),
            Values::NormalizedByte(v) => (v.iter().flat_map(|x| x.to_le_bytes()).collect(), BYTE, true),
        }
    }
}

/// Bytes per component of an accessor `componentType` [`Values`] writes (FLOAT, SHORT, BYTE).
pub fn component_bytes(component_type: u32) -> Option<usize> {
    match component_type {
        FLOAT => Some(4),
        SHORT => Some(2),
        BYTE => Some(1),
        _ => None,
    }
}

/// Accessor data of `component_type` as a glTF client reads it, the inverse of [`Values`]'
/// encoding: floats as they are, normalized SHORT and BYTE as max(c / q, −1) (glTF 2.0 §3.11).
pub fn decode_values(component_type: u32, data: &[u8]) -> Option<Vec<f32>> {
    Some(match component_type {
        FLOAT => data.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect(),
        SHORT => data
            .chunks_exact(2)
            .map(|b| (i16::from_le_bytes([b[0], b[1]]) as f32 / i16::MAX as f32).max(-1.0))
            .collect(),
        BYTE => data.iter().map(|&b| (b as i8 as f32 / i8::MAX as f32).max(-1.0)).collect(),
        _ => return None,
    })
}

/// A triangle mesh to write.
#[derive(Clone, Debug)]
pub struct GlbMesh {
    /// Positions, the `POSITION` attribute.
    pub positions: Vec<[f32; 3]>,
    /// Further attributes (`NORMAL`, custom ones).
    pub attributes: Vec<Attribute>,
    /// Triangles, as indices into the vertices.
    pub triangles: Vec<[u32; 3]>,
    /// The asset's `generator` string.
    pub generator: String,
    /// Application data stored in the mesh's `extras`.
    pub extras: Value,
    /// Float arrays that are not vertex attributes (e.g. a lookup table the run time needs),
    /// each stored as a buffer view; the mesh's `extras."prtkit.blobs"` maps each name to
    /// `{"bufferView", "count"}` (little-endian f32).
    pub blobs: Vec<Blob>,
}

/// A named float array stored beside the mesh.
#[derive(Clone, Debug)]
pub struct Blob {
    /// Its name in `extras."prtkit.blobs"`.
    pub name: String,
    /// The values.
    pub values: Vec<f32>,
}

/// Accessor component types (glTF 2.0 §3.6.2.2).
pub const FLOAT: u32 = 5126;
/// Signed 16-bit.
pub const SHORT: u32 = 5122;
/// Signed 8-bit.
pub const BYTE: u32 = 5120;
const UNSIGNED_INT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// The whole `.glb` file. Fails when it would exceed the format's 4 GiB length.
pub fn encode(mesh: &GlbMesh) -> Result<Vec<u8>, String> {
    let count = mesh.positions.len();
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut attributes = serde_json::Map::new();
    let mut push_view = |bin: &mut Vec<u8>, bytes: &[u8], target: Option<u32>| {
        let offset = bin.len();
        bin.extend_from_slice(bytes);
        let mut view = json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()});
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        views.push(view);
        views.len() - 1
    };
    let floats = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();

    let flat: Vec<f32> = mesh.positions.iter().flatten().copied().collect();
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in &mesh.positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let view = push_view(&mut bin, &floats(&flat), Some(ARRAY_BUFFER));
    accessors.push(
        json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": "VEC3", "min": lo, "max": hi}),
    );
    attributes.insert("POSITION".into(), json!(accessors.len() - 1));
    for a in &mesh.attributes {
        if a.values.len() != a.components * count {
            return Err(format!("attribute {} holds {} values for {count} vertices", a.name, a.values.len()));
        }
        let kind = ["SCALAR", "VEC2", "VEC3", "VEC4"][a.components - 1];
        let (bytes, component_type, normalized) = a.values.encoded();
        // Each vertex's element must start on a 4-byte boundary (§3.6.2.4): refuse what would not.
        if bytes.len() % (4 * count.max(1)) != 0 {
            return Err(format!(
                "attribute {}: {} bytes per vertex is not a multiple of 4",
                a.name,
                bytes.len() / count
            ));
        }
        let view = push_view(&mut bin, &bytes, Some(ARRAY_BUFFER));
        let mut accessor = json!({"bufferView": view, "componentType": component_type, "count": count, "type": kind});
        if normalized {
            accessor["normalized"] = json!(true);
        }
        accessors.push(accessor);
        attributes.insert(a.name.clone(), json!(accessors.len() - 1));
    }
    let indices: Vec<u8> = mesh.triangles.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
    let view = push_view(&mut bin, &indices, Some(ELEMENT_ARRAY_BUFFER));
    accessors.push(
        json!({"bufferView": view, "componentType": UNSIGNED_INT, "count": 3 * mesh.triangles.len(), "type": "SCALAR"}),
    );
    let indices_accessor = accessors.len() - 1;
    let mut extras = mesh.extras.clone();
    if !mesh.blobs.is_empty() {
        let mut blobs = serde_json::Map::new();
        for b in &mesh.blobs {
            let view = push_view(&mut bin, &floats(&b.values), None);
            blobs.insert(b.name.clone(), json!({"bufferView": view, "count": b.values.len()}));
        }
        extras["prtkit.blobs"] = Value::Object(blobs);
    }

    let document = json!({
        "asset": {"version": "2.0", "generator": mesh.generator},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{
            "primitives": [{"attributes": attributes, "indices": indices_accessor, "mode": 4}],
            "extras": extras,
        }],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": views,
        "accessors": accessors,
    });
    let mut json_chunk = serde_json::to_vec(&document).map_err(|e| e.to_string())?;
    json_chunk.resize(json_chunk.len().next_multiple_of(4), b' ');
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json_chunk.len() + 8 + bin.len();
    let length = u32::try_from(total).map_err(|_| format!("{total} bytes exceed the 4 GiB a .glb can hold"))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&length.to_le_bytes());
    out.extend_from_slice(&(json_chunk.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json_chunk);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    Ok(out)
}

/// The f32 values of the blob `name` of the first mesh (see [`GlbMesh::blobs`]): `None` when
/// there is no such blob, an error when it does not fit the BIN chunk.
pub fn blob(json: &Value, bin: &[u8], name: &str) -> Option<Result<Vec<f32>, String>> {
    let entry = json["meshes"][0]["extras"]["prtkit.blobs"].get(name)?;
    let read = || -> Result<Vec<f32>, String> {
        let view = entry["bufferView"].as_u64().ok_or("no bufferView")? as usize;
        let count = entry["count"].as_u64().ok_or("no count")? as usize;
        let view = &json["bufferViews"][view];
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        let length = view["byteLength"].as_u64().ok_or("a buffer view without byteLength")? as usize;
        if count.checked_mul(4) != Some(length) {
            return Err(format!("{count} values in a buffer view of {length} bytes"));
        }
        let bytes = start.checked_add(length).and_then(|end| bin.get(start..end)).ok_or("past the BIN chunk")?;
        Ok(decode_values(FLOAT, bytes).expect("FLOAT is a component type"))
    };
    Some(read().map_err(|e| format!("blob {name}: {e}")))
}

/// The JSON chunk of a `.glb` (for readers and tests): `None` when the header is not glTF 2.
pub fn json_chunk(bytes: &[u8]) -> Option<Value> {
    let word = |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    if bytes.get(0..4)? != b"glTF" || word(4)? != 2 || bytes.get(16..20)? != b"JSON" {
        return None;
    }
    let len = word(12)? as usize;
    serde_json::from_slice(bytes.get(20..20 + len)?).ok()
}

/// The BIN chunk of a `.glb`.
pub fn bin_chunk(bytes: &[u8]) -> Option<&[u8]> {
    let word = |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    let at = 20 + word(12)? as usize;
    let len = word(at)? as usize;
    if bytes.get(at + 4..at + 8)? != b"BIN\0" {
        return None;
    }
    bytes.get(at + 8..at + 8 + len)
}
