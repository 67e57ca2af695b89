//! Triangle meshes from Stanford PLY files (Turk 1994; the format as Paul Bourke documents it):
//! a text header of `element` and `property` lines, then the elements in ASCII or binary
//! (little- or big-endian). What is read: the `vertex` element's `x`, `y`, `z` (and `nx`, `ny`,
//! `nz` when all three are there) and the `face` element's index list (`vertex_indices` or
//! `vertex_index`), polygons split into fans; every other element and property is skipped.
//! Counts are checked against the file's size before anything is allocated.

use glam::DVec3;

/// What a PLY file holds for [`super::Mesh`]: positions, normals if every vertex has one,
/// triangles.
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

/// Parses a PLY file's bytes. The error says what is wrong (the caller names the file).
pub fn parse(bytes: &[u8]) -> Result<PlyMesh, String> {
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
