//! Stanford PLY (Turk 1994; the format as Paul Bourke documents it), the one reader of it: a text
//! header of `element` and `property` lines ([`Header`], parsed once for every view), then the
//! elements in ASCII or binary (little- or big-endian). Two views are taken of a file:
//!
//! - [`parse`], the geometry of a mesh: the `vertex` element's `x`, `y`, `z` (and `nx`, `ny`, `nz`
//!   when all three are there) and the `face` element's index list (`vertex_indices` or
//!   `vertex_index`), polygons split into fans; every other element and property is skipped.
//! - [`vertex_normals`], the `vertex` element's `nx ny nz` alone with where each sits, so that
//!   decoded normals can be written back with only those properties changed ([`PlyNormals`]).
//!
//! Counts are checked against the file's size before anything is allocated.

use super::IoError;
use glam::DVec3;
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

/// What a PLY file holds for a mesh: positions, normals if every vertex has one, triangles.
pub type PlyMesh = (Vec<DVec3>, Option<Vec<DVec3>>, Vec<[u32; 3]>);

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

/// Reads values one after another from the body.
struct Body<'a> {
    bytes: &'a [u8],
    at: usize,
    encoding: Encoding,
}

impl Body<'_> {
    fn value(&mut self, t: Scalar) -> Result<f64, String> {
        if self.encoding == Encoding::Ascii {
            while self.at < self.bytes.len() && self.bytes[self.at].is_ascii_whitespace() {
                self.at += 1;
            }
            let start = self.at;
            while self.at < self.bytes.len() && !self.bytes[self.at].is_ascii_whitespace() {
                self.at += 1;
            }
            let token = std::str::from_utf8(&self.bytes[start..self.at]).map_err(|_| "the body is not text")?;
            if token.is_empty() {
                return Err("the file ends inside an element".into());
            }
            return token.parse::<f64>().map_err(|_| format!("{token:?} is not a number"));
        }
        let b = self.bytes.get(self.at..self.at + t.size).ok_or("the file ends inside an element")?;
        self.at += t.size;
        let mut word = [0u8; 8];
        word[..t.size].copy_from_slice(b);
        if self.encoding == Encoding::Big {
            word[..t.size].reverse();
        }
        Ok(match (t.size, t.float, t.signed) {
            (4, true, _) => f32::from_le_bytes(word[..4].try_into().unwrap()) as f64,
            (8, true, _) => f64::from_le_bytes(word),
            (1, false, true) => word[0] as i8 as f64,
            (1, false, false) => word[0] as f64,
            (2, false, true) => i16::from_le_bytes([word[0], word[1]]) as f64,
            (2, false, false) => u16::from_le_bytes([word[0], word[1]]) as f64,
            (4, false, true) => i32::from_le_bytes(word[..4].try_into().unwrap()) as f64,
            _ => u32::from_le_bytes(word[..4].try_into().unwrap()) as f64,
        })
    }
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
    let Header { encoding, elements, body, .. } = header(bytes)?;
    // Every element takes at least one byte (binary) or two characters (ASCII) per item: a count
    // beyond the body's size is garbage, refused before allocating.
    let room = bytes.len() - body;
    if let Some(e) = elements.iter().find(|e| e.count > room) {
        return Err(format!("element {} claims {} items, more than the file holds", e.name, e.count));
    }
    let vertex = elements.iter().find(|e| e.name == "vertex").ok_or("no vertex element")?;
    let named =
        |e: &Element, name: &str| e.properties.iter().position(|p| matches!(p, Property::Scalar(n, _) if n == name));
    let xyz = ["x", "y", "z"].map(|n| named(vertex, n));
    let [Some(x), Some(y), Some(z)] = xyz else {
        return Err("the vertex element has no x, y and z".into());
    };
    let normal = match ["nx", "ny", "nz"].map(|n| named(vertex, n)) {
        [Some(a), Some(b), Some(c)] => Some([a, b, c]),
        _ => None,
    };
    let face = elements.iter().find(|e| e.name == "face").ok_or("no face element")?;
    let list = face
        .properties
        .iter()
        .position(|p| matches!(p, Property::List(n, _, _) if n == "vertex_indices" || n == "vertex_index"))
        .ok_or("the face element has no vertex_indices list")?;

    let mut reader = Body { bytes, at: body, encoding };
    let (mut positions, mut normals, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
    for e in &elements {
        for item in 0..e.count {
            let mut values: Vec<f64> = Vec::with_capacity(e.properties.len());
            let mut indices: Vec<f64> = Vec::new();
            for (k, p) in e.properties.iter().enumerate() {
                match p {
                    Property::Scalar(_, t) => values.push(reader.value(*t)?),
                    Property::List(_, count, t) => {
                        let n = reader.value(*count)?;
                        if !(0.0..=1024.0).contains(&n) || n.fract() != 0.0 {
                            return Err(format!("{} {item}: a list of {n} items", e.name));
                        }
                        values.push(f64::NAN);
                        for _ in 0..n as usize {
                            let v = reader.value(*t)?;
                            if e.name == "face" && k == list {
                                indices.push(v);
                            }
                        }
                    }
                }
            }
            if e.name == "vertex" {
                positions.push(DVec3::new(values[x], values[y], values[z]));
                if let Some([a, b, c]) = normal {
                    normals.push(DVec3::new(values[a], values[b], values[c]));
                }
            } else if e.name == "face" {
                let n = positions.len() as f64;
                if let Some(bad) = indices.iter().find(|&&i| !(0.0..n).contains(&i) || i.fract() != 0.0) {
                    return Err(format!(
                        "face {item}: vertex index {bad} is out of range (vertices come first, {n} of them)"
                    ));
                }
                // A polygon as a fan about its first vertex.
                for k in 2..indices.len() {
                    triangles.push([indices[0] as u32, indices[k - 1] as u32, indices[k] as u32]);
                }
            }
        }
    }
    let normals = normal.map(|_| normals);
    Ok((positions, normals, triangles))
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
/// written back with only those properties changed (binary: patched in place; ASCII: the three
/// tokens replaced).
#[derive(Clone, Debug)]
pub struct NormalLayout {
    bytes: Vec<u8>,
    encoding: Encoding,
    /// Binary: byte offset of each vertex's nx, ny, nz.
    offsets: Vec<[usize; 3]>,
    /// Binary: whether nx, ny, nz are f64.
    double: [bool; 3],
    /// ASCII: (line start, line end, token indices of nx ny nz) per vertex.
    ascii: Vec<(usize, usize, [usize; 3])>,
    /// ASCII: each vertex's line number.
    lines: Option<Vec<usize>>,
}

/// Reads the vertex normals of a PLY file's bytes (as [`read`] returns them). Each element is
/// one line in ASCII (the layout every PLY writer uses), so that a normal has a line number; the
/// elements after the vertices are not read. Errors name `path`.
pub fn vertex_normals(path: &Path, bytes: Vec<u8>) -> Result<PlyNormals, IoError> {
    let bad = |msg: String| IoError::invalid(path, "PLY", msg);
    let Header { encoding, elements, body: body_start, body_line } = header(&bytes).map_err(bad)?;
    let vi = elements.iter().position(|e| e.name == "vertex").ok_or_else(|| bad("no vertex element".into()))?;
    let vertex = &elements[vi];
    let mut idx = [0usize; 3];
    let mut double = [false; 3];
    for (k, name) in ["nx", "ny", "nz"].iter().enumerate() {
        idx[k] = vertex
            .properties
            .iter()
            .position(|p| p.name() == *name)
            .ok_or_else(|| bad(format!("vertex element has no {name} property")))?;
        match vertex.properties[idx[k]] {
            Property::Scalar(_, s) if s.float => double[k] = s.size == 8,
            _ => return Err(IoError::unsupported(path, "PLY", format!("{name} is not float or double"))),
        }
    }
    let n = vertex.count;
    // A vertex count larger than the bytes can hold is garbage; refuse before allocating.
    if n > bytes.len() {
        return Err(bad(format!("vertex count {n} exceeds the file size")));
    }
    let mut normals = Vec::with_capacity(n);
    let (mut offsets, mut ascii, mut lines_at) = (Vec::new(), Vec::new(), None);
    match encoding {
        Encoding::Ascii => {
            let text = std::str::from_utf8(&bytes[body_start..]).map_err(|_| bad("ascii body is not text".into()))?;
            let mut line_no = body_line;
            let mut pos = body_start;
            let mut lines = text.split_inclusive('\n');
            let mut line_numbers = Vec::with_capacity(n);
            // Skip elements before the vertices, one line each.
            let before = elements[..vi].iter().fold(0usize, |acc, e| acc.saturating_add(e.count));
            for _ in 0..before {
                let l = lines.next().ok_or_else(|| bad("file ends before the vertex element".into()))?;
                pos += l.len();
                line_no += 1;
            }
            for v in 0..n {
                let l = lines.next().ok_or_else(|| bad(format!("file ends at vertex {v} of {n}")))?;
                let body = l.trim_end_matches(['\n', '\r']);
                let tokens: Vec<&str> = body.split_whitespace().collect();
                let mut value = [0f32; 3];
                for k in 0..3 {
                    let tok = tokens
                        .get(idx[k])
                        .ok_or_else(|| bad(format!("line {line_no}: vertex {v} has only {} values", tokens.len())))?;
                    // The token is a slice of `body`: its column (in characters) from its offset.
                    let col = body[..tok.as_ptr() as usize - body.as_ptr() as usize].chars().count() + 1;
                    value[k] = tok
                        .parse()
                        .map_err(|_| bad(format!("line {line_no}, column {col}: {tok:?} is not a number")))?;
                }
                if vertex.properties.iter().any(|p| matches!(p, Property::List(..))) {
                    return Err(IoError::unsupported(path, "PLY", "list properties in the vertex element"));
                }
                normals.push(value);
                ascii.push((pos, pos + body.len(), idx));
                line_numbers.push(line_no);
                pos += l.len();
                line_no += 1;
            }
            lines_at = Some(line_numbers);
        }
        Encoding::Little | Encoding::Big => {
            let mut pos = body_start;
            let read_uint = |pos: usize, size: usize| -> Option<usize> {
                let b = bytes.get(pos..pos + size)?;
                let mut v = 0usize;
                for k in 0..size {
                    let byte = if encoding == Encoding::Little { b[size - 1 - k] } else { b[k] };
                    v = (v << 8) | byte as usize;
                }
                Some(v)
            };
            for (ei, el) in elements.iter().enumerate() {
                if ei > vi {
                    break;
                }
                // Every element with properties takes at least one byte: a larger count is
                // garbage (and would loop for ever).
                if el.properties.is_empty() {
                    continue;
                }
                if el.count > bytes.len() {
                    return Err(bad(format!("element {} count {} exceeds the file size", el.name, el.count)));
                }
                for v in 0..el.count {
                    let mut offs = [0usize; 3];
                    for (pi, p) in el.properties.iter().enumerate() {
                        match p {
                            Property::Scalar(_, s) => {
                                if ei == vi {
                                    for k in 0..3 {
                                        if idx[k] == pi {
                                            offs[k] = pos;
                                        }
                                    }
                                }
                                pos += s.size;
                            }
                            Property::List(_, count_type, item) => {
                                let count = read_uint(pos, count_type.size)
                                    .ok_or_else(|| bad(format!("truncated in element {} #{v}", el.name)))?;
                                // A garbled count must not wrap the offset back into the file.
                                pos = count
                                    .checked_mul(item.size)
                                    .and_then(|n| n.checked_add(pos + count_type.size))
                                    .ok_or_else(|| {
                                    bad(format!("list length {count} in element {} #{v} overflows", el.name))
                                })?;
                            }
                        }
                        if pos > bytes.len() {
                            return Err(bad(format!("truncated in element {} #{v} of {}", el.name, el.count)));
                        }
                    }
                    if ei == vi {
                        let mut value = [0f32; 3];
                        for k in 0..3 {
                            value[k] = read_float(&bytes, offs[k], double[k], encoding == Encoding::Little);
                        }
                        normals.push(value);
                        offsets.push(offs);
                    }
                }
            }
        }
    }
    if normals.is_empty() {
        return Err(bad("no vertices".into()));
    }
    Ok(PlyNormals { normals, layout: NormalLayout { bytes, encoding, offsets, double, ascii, lines: lines_at } })
}

fn read_float(bytes: &[u8], pos: usize, double: bool, little: bool) -> f32 {
    if double {
        let mut b = [0u8; 8];
        b.copy_from_slice(&bytes[pos..pos + 8]);
        (if little { f64::from_le_bytes(b) } else { f64::from_be_bytes(b) }) as f32
    } else {
        let mut b = [0u8; 4];
        b.copy_from_slice(&bytes[pos..pos + 4]);
        if little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    }
}

impl NormalLayout {
    /// Where normal `index` sits, for messages: `line 12` (ASCII) or `vertex 12` (binary).
    pub fn locate(&self, index: usize) -> String {
        match &self.lines {
            Some(lines) => lines.get(index).map_or(String::new(), |n| format!("line {n}")),
            None => format!("vertex {index}"),
        }
    }

    /// The file with its normals replaced by `decoded` (one per normal read), every other
    /// property kept. ASCII numbers are written with the shortest text that reads back to the
    /// same f32.
    pub fn write_back(&self, decoded: &[[f32; 3]]) -> Vec<u8> {
        match self.encoding {
            Encoding::Ascii => {
                let mut out = Vec::with_capacity(self.bytes.len());
                let mut pos = 0;
                for (&(a, b, idx), n) in self.ascii.iter().zip(decoded) {
                    out.extend_from_slice(&self.bytes[pos..a]);
                    let line = String::from_utf8_lossy(&self.bytes[a..b]);
                    let mut tokens: Vec<String> = line.split_whitespace().map(str::to_string).collect();
                    for k in 0..3 {
                        tokens[idx[k]] = format!("{}", n[k]);
                    }
                    out.extend_from_slice(tokens.join(" ").as_bytes());
                    pos = b;
                }
                out.extend_from_slice(&self.bytes[pos..]);
                out
            }
            Encoding::Little | Encoding::Big => {
                let little = self.encoding == Encoding::Little;
                let mut out = self.bytes.clone();
                for (offs, n) in self.offsets.iter().zip(decoded) {
                    for k in 0..3 {
                        let p = offs[k];
                        if self.double[k] {
                            let v = n[k] as f64;
                            out[p..p + 8].copy_from_slice(&if little { v.to_le_bytes() } else { v.to_be_bytes() });
                        } else {
                            out[p..p + 4].copy_from_slice(&if little {
                                n[k].to_le_bytes()
                            } else {
                                n[k].to_be_bytes()
                            });
                        }
                    }
                }
                out
            }
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
        let expected = (
            vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::new(0.0, 1.0, 0.5)],
            None,
            vec![[0, 1, 2], [0, 2, 3]],
        );
        assert_eq!(parse(ascii.as_bytes()).unwrap(), expected);
        assert_eq!(parse(&binary(false)).unwrap(), expected);
        assert_eq!(parse(&binary(true)).unwrap(), expected);
        let mut cut = binary(false);
        cut.truncate(cut.len() - 3);
        assert!(parse(&cut).unwrap_err().contains("ends inside"));
        let bad = ascii.replace("7 4 0 1 2 3", "7 3 0 1 9");
        assert!(parse(bad.as_bytes()).unwrap_err().contains("out of range"));
        let huge = ascii.replace("element vertex 4", "element vertex 4000000000");
        assert!(parse(huge.as_bytes()).unwrap_err().contains("more than the file holds"));
    }
}
