//! Stanford PLY (Turk 1994; the format as Paul Bourke documents it), the one reader of it: a text
//! header of `element` and `property` lines ([`Header`], parsed once for every view), then the
//! elements in ASCII or binary (little- or big-endian), read value by value by one walker that
//! knows where each value sits ([`walk`]). Two views are taken of a file through it:
//!
//! - [`parse`], the geometry of a mesh: the `vertex` element's `x`, `y`, `z` (and `nx`, `ny`, `nz`
//!   when all three are there, a texture coordinate pair, [`UV_NAMES`], and `red`, `green`,
//!   `blue`, [`PlyColours`]) and the `face` element's index list (`vertex_indices` or
//!   `vertex_index`), polygons split into fans; every other element and property is skipped.
//! - [`vertex_normals`], the `vertex` element's `nx ny nz` alone with where each sits, so that
//!   decoded normals can be written back with only their bytes changed ([`PlyNormals`]).
//!
//! Values are read as their declared type (an ASCII `float` as an f32), so the ASCII and binary
//! encodings of one mesh read the same. Counts are checked against the file's size before
//! anything is allocated.

use super::IoError;
use crate::limits::MAX_PLY_LIST_LEN;
use glam::DVec3;
use std::ops::Range;
use std::path::Path;

/// Reads a PLY file (`-`: standard input) whole, within [`crate::limits::max_file_bytes`]
/// (`docs/limits.md`), refusing at once an input that does not start with the `ply` magic.
pub fn read(path: &Path) -> Result<Vec<u8>, IoError> {
    super::read_bytes(path, "PLY", crate::limits::max_file_bytes(), |start| {
        if start.starts_with(b"ply") {
            Ok(())
        } else {
            Err("no 'ply' magic".into())
        }
    })
}

/// What a PLY file holds for a mesh.
#[derive(Debug, PartialEq)]
pub struct PlyMesh {
    /// The vertex element's x y z.
    pub positions: Vec<DVec3>,
    /// One per vertex when the vertex element has `nx ny nz`.
    pub normals: Option<Vec<DVec3>>,
    /// One (u, v) per vertex when the vertex element has a pair of [`UV_NAMES`], as stored (the
    /// convention of an OBJ's `vt`, which prtkit reads the same way).
    pub uvs: Option<Vec<[f64; 2]>>,
    /// The faces, polygons split into fans about their first vertex.
    pub triangles: Vec<[u32; 3]>,
    /// One colour per vertex when the vertex element has `red green blue` scalars.
    pub colours: Option<PlyColours>,
}

/// A PLY's vertex colours, `red green blue` as stored, and how they are stored. PLY itself says
/// nothing of colour (Turk 1994 names the properties only); the writers that store them agree on
/// two conventions, which [`PlyColours::linear`] follows:
///
/// - `uchar` (MeshLab, Blender, Open3D, the Stanford scans' scanners): 8-bit codes 0..255 of
///   sRGB-encoded colour, as a picture stores them: decoded to linear by the sRGB transfer
///   function (IEC 61966-2-1) of code / 255.
/// - `float` or `double` (Open3D's float colours, most point-cloud tools): values in [0, 1], taken
///   as linear, as stored.
///
/// Any other type (`ushort`, a signed integer, a mix of types) has no agreed meaning and is an
/// error, as is a negative or non-finite value. `alpha` is not read.
#[derive(Clone, Debug, PartialEq)]
pub struct PlyColours {
    /// Each vertex's `red green blue`, as stored (0..255 for `uchar`).
    pub stored: Vec<[f64; 3]>,
    /// The three properties' types as declared, e.g. `["uchar", "uchar", "uchar"]`.
    pub types: [&'static str; 3],
}

impl PlyColours {
    /// The linear colours, by the rule of the properties' type (see [`PlyColours`]). The error
    /// says what is wrong (the caller names the file).
    pub fn linear(&self) -> Result<Vec<[f64; 3]>, String> {
        let srgb8 = match self.types {
            ["uchar", "uchar", "uchar"] => true,
            [a, b, c] if [a, b, c].iter().all(|t| matches!(*t, "float" | "double")) => false,
            types => {
                return Err(format!(
                    "the vertex colours (red, green, blue) are {types:?}; prtkit reads uchar (sRGB-encoded 0..255) \
                     or float/double (linear) colours"
                ))
            }
        };
        if let Some((i, c)) = self.stored.iter().enumerate().find(|(_, c)| c.iter().any(|x| !x.is_finite() || *x < 0.0))
        {
            return Err(format!("vertex {i}'s colour (red, green, blue) {c:?} is negative or not finite"));
        }
        if !srgb8 {
            return Ok(self.stored.clone());
        }
        // A binary uchar is 0..=255 by its type; an ASCII token is read as a number, so it is
        // checked to be one of the 256 codes.
        if let Some((i, c)) =
            self.stored.iter().enumerate().find(|(_, c)| c.iter().any(|x| *x > 255.0 || x.fract() != 0.0))
        {
            return Err(format!("vertex {i}'s colour (red, green, blue) {c:?} is not three uchar codes 0..255"));
        }
        let table: Vec<f64> = (0..=255).map(|c| super::png::srgb_decode(c as f64 / 255.0)).collect();
        Ok(self.stored.iter().map(|c| c.map(|x| table[x as usize])).collect())
    }
}

/// The names PLY writers give a vertex's texture coordinates, in the order they are looked for:
/// `s t` (Blender, the Stanford scans' convention), `u v`, `texture_u texture_v` and
/// `texture_s texture_t` (MeshLab, Open3D).
pub const UV_NAMES: [[&str; 2]; 4] = [["s", "t"], ["u", "v"], ["texture_u", "texture_v"], ["texture_s", "texture_t"]];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

/// A scalar type: its size in bytes, and whether it is a float, a signed integer.
#[derive(Clone, Copy, Debug)]
struct Scalar {
    size: usize,
    float: bool,
    signed: bool,
}

/// The canonical name of a scalar type (`uint8` is `uchar`…), for messages and [`PlyColours`].
fn type_name(t: Scalar) -> &'static str {
    match (t.size, t.float, t.signed) {
        (4, true, _) => "float",
        (8, true, _) => "double",
        (1, false, true) => "char",
        (1, false, false) => "uchar",
        (2, false, true) => "short",
        (2, false, false) => "ushort",
        (4, false, true) => "int",
        _ => "uint",
    }
}

fn scalar(name: &str) -> Option<Scalar> {
    let (size, float, signed) = match name {
        "char" | "int8" => (1, false, true),
        "uchar" | "uint8" => (1, false, false),
        "short" | "int16" => (2, false, true),
        "ushort" | "uint16" => (2, false, false),
        "int" | "int32" => (4, false, true),
        "uint" | "uint32" => (4, false, false),
        "float" | "float32" => (4, true, true),
        "double" | "float64" => (8, true, true),
        _ => return None,
    };
    Some(Scalar { size, float, signed })
}

#[derive(Clone, Debug)]
enum Property {
    Scalar(String, Scalar),
    /// Name, count type, item type.
    List(String, Scalar, Scalar),
}

impl Property {
    fn name(&self) -> &str {
        match self {
            Property::Scalar(name, _) | Property::List(name, ..) => name,
        }
    }
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

/// Where a value sits in the file: its bytes, and (ASCII) the line it is on.
#[derive(Clone, Debug, Default)]
struct Place {
    bytes: Range<usize>,
    line: usize,
}

/// Reads the body's values one after another, each with its [`Place`].
struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    encoding: Encoding,
    /// ASCII: the line `at` is on, and the offset where that line starts.
    line: usize,
    line_start: usize,
}

impl<'a> Body<'a> {
    fn new(bytes: &'a [u8], header: &Header) -> Self {
        Body { bytes, at: header.body, encoding: header.encoding, line: header.body_line, line_start: header.body }
    }

    /// The next value, read as its declared type (an ASCII `float` as the f32 a binary file
    /// would hold, so that both encodings of one mesh read the same), and where it sits.
    fn value(&mut self, t: Scalar) -> Result<(f64, Place), String> {
        if self.encoding == Encoding::Ascii {
            return self.token(t);
        }
        let start = self.at;
        let b = self.bytes.get(start..start + t.size).ok_or("the file ends early")?;
        self.at += t.size;
        let mut word = [0u8; 8];
        word[..t.size].copy_from_slice(b);
        if self.encoding == Encoding::Big {
            word[..t.size].reverse();
        }
        let value = match (t.size, t.float, t.signed) {
            (4, true, _) => f32::from_le_bytes(word[..4].try_into().unwrap()) as f64,
            (8, true, _) => f64::from_le_bytes(word),
            (1, false, true) => word[0] as i8 as f64,
            (1, false, false) => word[0] as f64,
            (2, false, true) => i16::from_le_bytes([word[0], word[1]]) as f64,
            (2, false, false) => u16::from_le_bytes([word[0], word[1]]) as f64,
            (4, false, true) => i32::from_le_bytes(word[..4].try_into().unwrap()) as f64,
            _ => u32::from_le_bytes(word[..4].try_into().unwrap()) as f64,
        };
        Ok((value, Place { bytes: start..self.at, line: 0 }))
    }

    fn token(&mut self, t: Scalar) -> Result<(f64, Place), String> {
        while let Some(&b) = self.bytes.get(self.at).filter(|b| b.is_ascii_whitespace()) {
            self.at += 1;
            if b == b'\n' {
                self.line += 1;
                self.line_start = self.at;
            }
        }
        let start = self.at;
        while self.bytes.get(self.at).is_some_and(|b| !b.is_ascii_whitespace()) {
            self.at += 1;
        }
        let token = std::str::from_utf8(&self.bytes[start..self.at]).map_err(|_| self.placed(start, "not text"))?;
        if token.is_empty() {
            return Err("the file ends early".into());
        }
        let value = if t.float && t.size == 4 { token.parse::<f32>().map(f64::from).ok() } else { token.parse().ok() };
        let value = value.ok_or_else(|| self.placed(start, &format!("{token:?} is not a number")))?;
        Ok((value, Place { bytes: start..self.at, line: self.line }))
    }

    /// `what`, placed at byte `offset` of the current line.
    fn placed(&self, offset: usize, what: &str) -> String {
        let column = String::from_utf8_lossy(&self.bytes[self.line_start..offset]).chars().count() + 1;
        format!("line {}, column {column}: {what}", self.line)
    }
}

/// One item of an element as read: each scalar property's value and place (a list property
/// holds NaN there), and each list property's items.
#[derive(Default)]
struct Item {
    scalars: Vec<(f64, Place)>,
    lists: Vec<Vec<f64>>,
}

/// Reads the items of the elements before and at `last`, in file order, handing each to `visit`
/// with its element's index and its number. The element counts are checked against the body's
/// size first: every item takes at least one byte (binary) or two characters (ASCII), so a
/// larger count is garbage, refused before anything is allocated.
fn walk(
    bytes: &[u8],
    header: &Header,
    last: usize,
    mut visit: impl FnMut(usize, usize, &Item) -> Result<(), String>,
) -> Result<(), String> {
    let elements = &header.elements[..=last];
    let room = bytes.len() - header.body;
    if let Some(e) = elements.iter().find(|e| e.count > room) {
        return Err(format!("element {} claims {} items, more than the file holds", e.name, e.count));
    }
    let mut body = Body::new(bytes, header);
    let mut item = Item::default();
    for (index, e) in elements.iter().enumerate() {
        item.scalars.resize(e.properties.len(), Default::default());
        item.lists.resize(e.properties.len(), Vec::new());
        for number in 0..e.count {
            let within = |reason: String| format!("{reason} ({} {number} of {})", e.name, e.count);
            for (k, p) in e.properties.iter().enumerate() {
                item.lists[k].clear();
                match p {
                    Property::Scalar(_, t) => item.scalars[k] = body.value(*t).map_err(within)?,
                    Property::List(_, count, t) => {
                        let (n, place) = body.value(*count).map_err(within)?;
                        if !(0.0..=MAX_PLY_LIST_LEN as f64).contains(&n) || n.fract() != 0.0 {
                            return Err(within(format!("a list of {n} items")));
                        }
                        item.scalars[k] = (f64::NAN, place);
                        for _ in 0..n as usize {
                            let (v, _) = body.value(*t).map_err(within)?;
                            item.lists[k].push(v);
                        }
                    }
                }
            }
            visit(index, number, &item)?;
        }
    }
    Ok(())
}

/// A PLY header: the body's encoding, the elements in file order, where the body starts.
#[derive(Clone, Debug)]
struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the body (just past the `end_header` line).
    body: usize,
    /// Line number of the body's first line (ASCII): the header's lines, then `end_header`.
    body_line: usize,
}

/// Parses the header. The error says what is wrong (the caller names the file).
fn header(bytes: &[u8]) -> Result<Header, String> {
    let end = bytes.windows(10).position(|w| w == b"end_header").ok_or("no end_header line")?;
    let body = bytes[end..].iter().position(|&b| b == b'\n').map(|p| end + p + 1).ok_or("the header does not end")?;
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| "the header is not text")?;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    for (i, line) in header.lines().enumerate() {
        let t: Vec<&str> = line.split_whitespace().collect();
        let at = |what: &str| format!("header line {}: {what}", i + 1);
        match t.first().copied() {
            Some("ply") if i == 0 => {}
            _ if i == 0 => return Err(at("no 'ply' magic")),
            Some("format") => {
                encoding = Some(match t.get(1).copied() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::Little,
                    Some("binary_big_endian") => Encoding::Big,
                    other => return Err(at(&format!("unknown format {other:?}"))),
                })
            }
            Some("element") => {
                let count =
                    t.get(2).and_then(|c| c.parse().ok()).ok_or_else(|| at("an element needs a name and a count"))?;
                elements.push(Element { name: t.get(1).unwrap_or(&"").to_string(), count, properties: Vec::new() });
            }
            Some("property") => {
                let element = elements.last_mut().ok_or_else(|| at("a property before any element"))?;
                let property = if t.get(1) == Some(&"list") {
                    let count = t
                        .get(2)
                        .and_then(|x| scalar(x))
                        .filter(|s| !s.float)
                        .ok_or_else(|| at("bad list count type"))?;
                    let item = t.get(3).and_then(|x| scalar(x)).ok_or_else(|| at("bad list item type"))?;
                    Property::List(t.get(4).ok_or_else(|| at("a list needs a name"))?.to_string(), count, item)
                } else {
                    let ty = t.get(1).and_then(|x| scalar(x)).ok_or_else(|| at("unknown property type"))?;
                    Property::Scalar(t.get(2).ok_or_else(|| at("a property needs a name"))?.to_string(), ty)
                };
                element.properties.push(property);
            }
            _ => {}
        }
    }
    let encoding = encoding.ok_or("no format line")?;
    Ok(Header { encoding, elements, body, body_line: header.lines().count() + 2 })
}

/// Parses a PLY file's bytes into a mesh's geometry. The error says what is wrong (the caller
/// names the file).
pub fn parse(bytes: &[u8]) -> Result<PlyMesh, String> {
    let header = header(bytes)?;
    let element = |name: &str| header.elements.iter().position(|e| e.name == name);
    let vertex = element("vertex").ok_or("no vertex element")?;
    let face = element("face").ok_or("no face element")?;
    let property = |e: usize, name: &str| header.elements[e].properties.iter().position(|p| p.name() == name);
    let [Some(x), Some(y), Some(z)] = ["x", "y", "z"].map(|n| property(vertex, n)) else {
        return Err("the vertex element has no x, y and z".into());
    };
    let normal = match ["nx", "ny", "nz"].map(|n| property(vertex, n)) {
        [Some(a), Some(b), Some(c)] => Some([a, b, c]),
        _ => None,
    };
    let uv = UV_NAMES.iter().find_map(|names| match names.map(|n| property(vertex, n)) {
        [Some(u), Some(v)] => Some([u, v]),
        _ => None,
    });
    // Scalars only: a list named `red` is no colour.
    let scalar_type = |k: usize| match header.elements[vertex].properties[k] {
        Property::Scalar(_, t) => Some(t),
        Property::List(..) => None,
    };
    let colour = match ["red", "green", "blue"].map(|n| property(vertex, n).and_then(|k| Some((k, scalar_type(k)?)))) {
        [Some(r), Some(g), Some(b)] => Some(([r.0, g.0, b.0], [r.1, g.1, b.1].map(type_name))),
        _ => None,
    };
    let list = property(face, "vertex_indices")
        .or_else(|| property(face, "vertex_index"))
        .filter(|&k| matches!(header.elements[face].properties[k], Property::List(..)))
        .ok_or("the face element has no vertex_indices list")?;

    let (mut positions, mut normals, mut uvs, mut triangles) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut colours = Vec::new();
    let last = header.elements.len() - 1;
    walk(bytes, &header, last, |e, number, item| {
        let at = |k: usize| item.scalars[k].0;
        if e == vertex {
            positions.push(DVec3::new(at(x), at(y), at(z)));
            if let Some([a, b, c]) = normal {
                normals.push(DVec3::new(at(a), at(b), at(c)));
            }
            if let Some([u, v]) = uv {
                uvs.push([at(u), at(v)]);
            }
            if let Some(([r, g, b], _)) = colour {
                colours.push([at(r), at(g), at(b)]);
            }
        } else if e == face {
            let indices = &item.lists[list];
            let n = positions.len() as f64;
            if let Some(bad) = indices.iter().find(|&&i| !(0.0..n).contains(&i) || i.fract() != 0.0) {
                return Err(format!(
                    "face {number}: vertex index {bad} is out of range (vertices come first, {n} of them)"
                ));
            }
            // A polygon as a fan about its first vertex.
            for k in 2..indices.len() {
                triangles.push([indices[0] as u32, indices[k - 1] as u32, indices[k] as u32]);
            }
        }
        Ok(())
    })?;
    let colours = colour.map(|(_, types)| PlyColours { stored: colours, types });
    Ok(PlyMesh { positions, normals: normal.map(|_| normals), uvs: uv.map(|_| uvs), triangles, colours })
}

/// The `vertex` element's `nx ny nz` of a PLY file, with where each sits.
#[derive(Clone, Debug)]
pub struct PlyNormals {
    /// The normals as stored (read as f32, not normalized).
    pub normals: Vec<[f32; 3]>,
    /// Where they sit.
    pub layout: NormalLayout,
}

/// The file a PLY's normals were read from and where each sits, so that decoded normals can be
/// written back with only those values changed, every other byte kept.
#[derive(Clone, Debug)]
pub struct NormalLayout {
    bytes: Vec<u8>,
    encoding: Encoding,
    /// Each vertex's nx, ny, nz.
    places: Vec<[Place; 3]>,
    /// Whether nx, ny, nz are doubles.
    double: [bool; 3],
}

/// Reads the vertex normals of a PLY file's bytes (as [`read`] returns them); the elements after
/// the vertices are not read. Errors name `path`, and the line and column in an ASCII file.
pub fn vertex_normals(path: &Path, bytes: Vec<u8>) -> Result<PlyNormals, IoError> {
    let bad = |msg: String| IoError::invalid(path, "PLY", msg);
    let header = header(&bytes).map_err(bad)?;
    let vertex =
        header.elements.iter().position(|e| e.name == "vertex").ok_or_else(|| bad("no vertex element".into()))?;
    let properties = &header.elements[vertex].properties;
    let mut index = [0; 3];
    let mut double = [false; 3];
    for (k, name) in ["nx", "ny", "nz"].iter().enumerate() {
        index[k] = properties
            .iter()
            .position(|p| p.name() == *name)
            .ok_or_else(|| bad(format!("vertex element has no {name} property")))?;
        match properties[index[k]] {
            Property::Scalar(_, s) if s.float => double[k] = s.size == 8,
            _ => return Err(IoError::unsupported(path, "PLY", format!("{name} is not float or double"))),
        }
    }
    let (mut normals, mut places) = (Vec::new(), Vec::new());
    walk(&bytes, &header, vertex, |e, _, item| {
        if e == vertex {
            normals.push(index.map(|k| item.scalars[k].0 as f32));
            places.push(index.map(|k| item.scalars[k].1.clone()));
        }
        Ok(())
    })
    .map_err(bad)?;
    if normals.is_empty() {
        return Err(bad("no vertices".into()));
    }
    Ok(PlyNormals { normals, layout: NormalLayout { encoding: header.encoding, bytes, places, double } })
}

impl NormalLayout {
    /// Where normal `index` sits, for messages: `line 12` (ASCII) or `vertex 12` (binary).
    pub fn locate(&self, index: usize) -> String {
        match (self.encoding, self.places.get(index)) {
            (Encoding::Ascii, Some(place)) => format!("line {}", place[0].line),
            _ => format!("vertex {index}"),
        }
    }

    /// The file with its normals replaced by `decoded` (one per normal read), every other byte
    /// kept. ASCII numbers are written with the shortest text that reads back to the same f32.
    pub fn write_back(&self, decoded: &[[f32; 3]]) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.bytes.len());
        let mut pos = 0;
        for (places, n) in self.places.iter().zip(decoded) {
            // In file order, whatever order the header declares nx, ny, nz in.
            let mut values: Vec<(&Place, Vec<u8>)> = (0..3).map(|k| (&places[k], self.encode(k, n[k]))).collect();
            values.sort_by_key(|(place, _)| place.bytes.start);
            for (place, bytes) in values {
                out.extend_from_slice(&self.bytes[pos..place.bytes.start]);
                out.extend_from_slice(&bytes);
                pos = place.bytes.end;
            }
        }
        out.extend_from_slice(&self.bytes[pos..]);
        out
    }

    /// Component `k` of a normal as the file stores it.
    fn encode(&self, k: usize, v: f32) -> Vec<u8> {
        match (self.encoding, self.double[k]) {
            (Encoding::Ascii, _) => format!("{v}").into_bytes(),
            (Encoding::Little, true) => (v as f64).to_le_bytes().to_vec(),
            (Encoding::Little, false) => v.to_le_bytes().to_vec(),
            (Encoding::Big, true) => (v as f64).to_be_bytes().to_vec(),
            (Encoding::Big, false) => v.to_be_bytes().to_vec(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binary(big: bool) -> Vec<u8> {
        let order = if big { "binary_big_endian" } else { "binary_little_endian" };
        let mut b = format!(
            "ply\nformat {order} 1.0\ncomment x\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
             property uchar red\nelement face 1\nproperty uchar intensity\nproperty list uchar int vertex_indices\nend_header\n"
        )
        .into_bytes();
        let f = |v: f32| if big { v.to_be_bytes() } else { v.to_le_bytes() };
        let i = |v: i32| if big { v.to_be_bytes() } else { v.to_le_bytes() };
        for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.5]] {
            for c in p {
                b.extend(f(c));
            }
            b.push(200);
        }
        b.push(7);
        b.push(4);
        for k in 0..4 {
            b.extend(i(k));
        }
        b
    }

    #[test]
    fn ascii_and_binary_read_the_same_quad_as_two_triangles() {
        let ascii = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
                     property uchar red\nelement face 1\nproperty uchar intensity\nproperty list uchar int vertex_indices\n\
                     end_header\n0 0 0 200\n1 0 0 200\n1 1 0 200\n0 1 0.5 200\n7 4 0 1 2 3\n";
        let expected = PlyMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::new(0.0, 1.0, 0.5)],
            normals: None,
            uvs: None,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            colours: None,
        };
        assert_eq!(parse(ascii.as_bytes()).unwrap(), expected);
        assert_eq!(parse(&binary(false)).unwrap(), expected);
        assert_eq!(parse(&binary(true)).unwrap(), expected);
        let mut cut = binary(false);
        cut.truncate(cut.len() - 3);
        assert!(parse(&cut).unwrap_err().contains("ends early"));
        let bad = ascii.replace("7 4 0 1 2 3", "7 3 0 1 9");
        assert!(parse(bad.as_bytes()).unwrap_err().contains("out of range"));
        let huge = ascii.replace("element vertex 4", "element vertex 4000000000");
        assert!(parse(huge.as_bytes()).unwrap_err().contains("more than the file holds"));
    }

    #[test]
    fn ascii_floats_read_as_the_f32_a_binary_file_holds() {
        // 0.1 is not an f32: read as the declared float, ASCII and binary agree to the bit.
        let ascii = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                     property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
                     0.1 0 0\n0 0.1 0\n0 0 0.1\n3 0 1 2\n";
        let positions = parse(ascii.as_bytes()).unwrap().positions;
        assert_eq!(positions[0].x, 0.1f32 as f64);
    }

    #[test]
    fn texture_coordinates_are_read_under_each_writers_names() {
        let file = |u: &str, v: &str| {
            format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float {u}\nproperty float y\n\
                 property float z\nproperty double {v}\nelement face 1\nproperty list uchar int vertex_indices\n\
                 end_header\n0 0.25 0 0 0.5\n1 1 0 0 0.75\n0 0 1 0 1\n3 0 1 2\n"
            )
        };
        for [u, v] in UV_NAMES {
            let mesh = parse(file(u, v).as_bytes()).unwrap();
            assert_eq!(mesh.uvs, Some(vec![[0.25, 0.5], [1.0, 0.75], [0.0, 1.0]]), "{u} {v}");
            assert_eq!(mesh.positions[1], DVec3::X, "{u} {v}");
        }
        // One coordinate of a pair is not a pair.
        assert_eq!(parse(file("s", "w").as_bytes()).unwrap().uvs, None);
    }

    #[test]
    fn colours_are_read_by_their_type() {
        let file = |ty: &str, row: &str| {
            format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                 property {ty} red\nproperty {ty} green\nproperty {ty} blue\nelement face 1\n\
                 property list uchar int vertex_indices\nend_header\n0 0 0 {row}\n1 0 0 {row}\n0 1 0 {row}\n3 0 1 2\n"
            )
        };
        let colours = |ty: &str, row: &str| parse(file(ty, row).as_bytes()).unwrap().colours.unwrap();
        let uchar = colours("uint8", "0 255 51");
        assert_eq!(uchar.types, ["uchar"; 3]);
        let c = uchar.linear().unwrap()[0];
        // 51/255 = 0.2 encoded: ((0.2 + 0.055) / 1.055)^2.4.
        assert_eq!(c[..2], [0.0, 1.0]);
        assert!((c[2] - ((0.2f64 + 0.055) / 1.055).powf(2.4)).abs() < 1e-15);
        assert_eq!(colours("float32", "0.25 0.5 1").linear().unwrap()[2], [0.25, 0.5, 1.0]);
        assert!(colours("int", "1 2 3").linear().unwrap_err().contains("[\"int\", \"int\", \"int\"]"));
        // Two of three, or a list named red, are no colours.
        let two = file("uchar", "1 2 3").replace("property uchar blue\n", "").replace(" 1 2 3", " 1 2");
        assert_eq!(parse(two.as_bytes()).unwrap().colours, None);
    }

    #[test]
    fn normals_write_back_changes_only_their_bytes() {
        // Tabs, runs of spaces and a list in the vertex element are kept; nz is declared first.
        let text = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float nz\nproperty list uchar int ids\n\
                    property float x\nproperty float nx\nproperty float ny\nend_header\n\
                    1  2 7 8\t5 0 0\n0 0\t6   1 0\n";
        let read = vertex_normals(Path::new("n.ply"), text.as_bytes().to_vec()).unwrap();
        assert_eq!(read.normals, vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
        assert_eq!(read.layout.locate(1), "line 11");
        let out = read.layout.write_back(&[[0.5, -1.0, 0.25], [0.0, 1.0, -0.5]]);
        let body = &String::from_utf8(out).unwrap()[text.find("1  2").unwrap()..];
        assert_eq!(body, "0.25  2 7 8\t5 0.5 -1\n-0.5 0\t6   0 1\n");
        let bad = text.replace("6   1", "6   q");
        let e = vertex_normals(Path::new("n.ply"), bad.into_bytes()).unwrap_err().to_string();
        assert!(e.contains("n.ply") && e.contains("line 11, column 9") && e.contains("vertex 1 of 2"), "{e}");
    }
}
