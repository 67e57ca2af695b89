//! Where normals come from and go back to: EXR normal maps, OBJ `vn` lines, PLY vertex
//! `nx ny nz` properties (ascii, binary little- and big-endian), and raw little-endian f32 xyz.
//!
//! Each reader keeps what it needs to write decoded normals back *in the same format*: the EXR
//! size and value encoding, the OBJ text with the `vn` lines replaced, the PLY file with only the
//! normal properties rewritten (binary: patched in place; ascii: the three tokens replaced).

use crate::io::{obj, IoError, RgbImage};
use std::path::Path;

/// Input format, chosen by extension (`.exr`, `.obj`, `.ply`; anything else is raw f32 xyz).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceFormat {
    /// OpenEXR normal map.
    Exr,
    /// Wavefront OBJ vertex normals.
    Obj,
    /// Stanford PLY vertex normals.
    Ply,
    /// Raw little-endian f32 triples.
    Raw,
}

impl SourceFormat {
    /// The format of `path` by extension.
    pub fn from_path(path: &Path) -> SourceFormat {
        match path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).as_deref() {
            Some("exr") => SourceFormat::Exr,
            Some("obj") => SourceFormat::Obj,
            Some("ply") => SourceFormat::Ply,
            _ => SourceFormat::Raw,
        }
    }
}

#[derive(Clone, Debug)]
enum Kind {
    Exr { width: usize, height: usize, unorm: bool },
    Obj { text: String, lines: Vec<obj::VnLine> },
    Ply(PlyLayout),
    Raw,
}

/// Normals read from a file, with what is needed to write them back.
#[derive(Clone, Debug)]
pub struct NormalSource {
    /// Normals as stored (f32, not normalized).
    pub normals: Vec<[f32; 3]>,
    kind: Kind,
}

impl NormalSource {
    /// Reads the normals of `path`; `unorm` maps EXR values from `[0,1]` to `[-1,1]`.
    pub fn read(path: &Path, unorm: bool) -> Result<NormalSource, IoError> {
        match SourceFormat::from_path(path) {
            SourceFormat::Exr => {
                let image = crate::io::image::read_image(path)?;
                let normals = image.pixels.iter().map(|p| if unorm { p.map(|c| 2.0 * c - 1.0) } else { *p }).collect();
                Ok(NormalSource { normals, kind: Kind::Exr { width: image.width, height: image.height, unorm } })
            }
            SourceFormat::Obj => {
                let text = obj::read(path)?;
                let vn = obj::vertex_normals(&text).map_err(|e| IoError::invalid(path, "OBJ", e.to_string()))?;
                if vn.normals.is_empty() {
                    return Err(IoError::invalid(path, "OBJ", "no vertex normals (vn lines)"));
                }
                Ok(NormalSource { normals: vn.normals, kind: Kind::Obj { text, lines: vn.lines } })
            }
            SourceFormat::Ply => read_ply(path, read_whole(path, "PLY")?),
            SourceFormat::Raw => {
                let bytes = read_whole(path, "raw f32 xyz")?;
                Ok(NormalSource { normals: raw_from_bytes(path, &bytes)?, kind: Kind::Raw })
            }
        }
    }

    /// Where normal `index` sits in the input, for messages (`line 12`, `pixel (3, 4)`, …).
    pub fn locate(&self, index: usize) -> String {
        match &self.kind {
            Kind::Exr { width, .. } if *width > 0 => format!("pixel ({}, {})", index % width, index / width),
            Kind::Obj { lines, .. } => lines.get(index).map_or(String::new(), |l| format!("line {}", l.line)),
            Kind::Ply(l) => match &l.lines {
                Some(lines) => lines.get(index).map_or(String::new(), |n| format!("line {n}")),
                None => format!("vertex {index}"),
            },
            _ => format!("normal {index}"),
        }
    }

    /// Serializes `decoded` (one per input normal) in the input's format.
    pub fn write_back(&self, path: &Path, decoded: &[[f32; 3]]) -> Result<Vec<u8>, IoError> {
        if decoded.len() != self.normals.len() {
            return Err(IoError::invalid(path, "normals", "decoded count differs from the input"));
        }
        match &self.kind {
            Kind::Exr { width, height, unorm } => {
                let pixels = decoded.iter().map(|n| if *unorm { n.map(|c| 0.5 * c + 0.5) } else { *n }).collect();
                let image = RgbImage { width: *width, height: *height, pixels };
                crate::io::exr::encode_layers(&[("", &image)]).map_err(|e| IoError::invalid(path, "OpenEXR", e))
            }
            Kind::Obj { text, lines } => Ok(obj::replace_vertex_normals(text, lines, decoded).into_bytes()),
            Kind::Ply(layout) => Ok(layout.write_back(decoded)),
            Kind::Raw => Ok(raw_to_bytes(decoded)),
        }
    }
}

/// Reads a file whole, up to [`crate::limits::max_file_bytes`] (`docs/limits.md`).
fn read_whole(path: &Path, format: &'static str) -> Result<Vec<u8>, IoError> {
    crate::io::read_bytes(path, format, crate::limits::max_file_bytes(), |_| Ok(()))
}

/// Raw little-endian f32 xyz triples.
pub fn raw_from_bytes(path: &Path, bytes: &[u8]) -> Result<Vec<[f32; 3]>, IoError> {
    if bytes.len() % 12 != 0 {
        return Err(IoError::invalid(
            path,
            "raw f32 xyz",
            format!("length {} is not a multiple of 12 bytes (3 little-endian f32 per normal)", bytes.len()),
        ));
    }
    Ok(bytes
        .chunks_exact(12)
        .map(|c| {
            let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
            [f(0), f(4), f(8)]
        })
        .collect())
}

/// Raw little-endian f32 xyz triples.
pub fn raw_to_bytes(normals: &[[f32; 3]]) -> Vec<u8> {
    normals.iter().flat_map(|n| n.iter().flat_map(|c| c.to_le_bytes())).collect()
}

/// A shortest round-trip float for text formats.
fn fmt_f32(x: f32) -> String {
    format!("{x}")
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PlyEncoding {
    Ascii,
    Little,
    Big,
}

#[derive(Clone, Debug)]
struct PlyProperty {
    name: String,
    scalar: Option<usize>,
    list: Option<(usize, usize)>,
    float_kind: Option<bool>,
}

#[derive(Clone, Debug)]
struct PlyElement {
    name: String,
    count: usize,
    props: Vec<PlyProperty>,
}

/// Everything needed to patch normals back into a PLY file.
#[derive(Clone, Debug)]
struct PlyLayout {
    bytes: Vec<u8>,
    encoding: PlyEncoding,
    /// Binary: byte offset of each vertex's nx, ny, nz and whether they are f64.
    offsets: Vec<[usize; 3]>,
    double: [bool; 3],
    /// Ascii: (line start, line end, token indices of nx ny nz) per vertex, and line numbers.
    ascii: Vec<(usize, usize, [usize; 3])>,
    lines: Option<Vec<usize>>,
}

fn ply_type_size(t: &str) -> Option<(usize, bool)> {
    Some(match t {
        "char" | "int8" | "uchar" | "uint8" => (1, false),
        "short" | "int16" | "ushort" | "uint16" => (2, false),
        "int" | "int32" | "uint" | "uint32" => (4, false),
        "float" | "float32" => (4, true),
        "double" | "float64" => (8, true),
        _ => return None,
    })
}

fn read_ply(path: &Path, bytes: Vec<u8>) -> Result<NormalSource, IoError> {
    let bad = |msg: String| IoError::invalid(path, "PLY", msg);
    let end = find(&bytes, b"end_header").ok_or_else(|| bad("no end_header line".into()))?;
    let body_start = bytes[end..]
        .iter()
        .position(|&b| b == b'\n')
        .map(|p| end + p + 1)
        .ok_or_else(|| bad("header not terminated".into()))?;
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| bad("header is not text".into()))?;
    let mut encoding = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    // Body line numbers: the header's lines, then `end_header`, then the first data line.
    let header_lines = header.lines().count() + 2;
    for (i, line) in header.lines().enumerate() {
        let t: Vec<&str> = line.split_whitespace().collect();
        let at = |msg: &str| bad(format!("line {}: {msg}", i + 1));
        match t.first().copied() {
            Some("ply") if i == 0 => {}
            _ if i == 0 => return Err(at("missing 'ply' magic")),
            Some("format") => {
                encoding = Some(match t.get(1).copied() {
                    Some("ascii") => PlyEncoding::Ascii,
                    Some("binary_little_endian") => PlyEncoding::Little,
                    Some("binary_big_endian") => PlyEncoding::Big,
                    other => return Err(at(&format!("unknown format {other:?}"))),
                })
            }
            Some("element") => {
                let count =
                    t.get(2).and_then(|c| c.parse().ok()).ok_or_else(|| at("element needs a name and a count"))?;
                elements.push(PlyElement { name: t.get(1).unwrap_or(&"").to_string(), count, props: Vec::new() });
            }
            Some("property") => {
                let el = elements.last_mut().ok_or_else(|| at("property before any element"))?;
                if t.get(1) == Some(&"list") {
                    let c = t.get(2).and_then(|x| ply_type_size(x)).ok_or_else(|| at("bad list count type"))?;
                    let v = t.get(3).and_then(|x| ply_type_size(x)).ok_or_else(|| at("bad list item type"))?;
                    let name = t.get(4).ok_or_else(|| at("list property needs a name"))?;
                    el.props.push(PlyProperty {
                        name: name.to_string(),
                        scalar: None,
                        list: Some((c.0, v.0)),
                        float_kind: None,
                    });
                } else {
                    let ty = t.get(1).and_then(|x| ply_type_size(x)).ok_or_else(|| at("unknown property type"))?;
                    let name = t.get(2).ok_or_else(|| at("property needs a name"))?;
                    let double = if ty.1 { Some(ty.0 == 8) } else { None };
                    el.props.push(PlyProperty {
                        name: name.to_string(),
                        scalar: Some(ty.0),
                        list: None,
                        float_kind: double,
                    });
                }
            }
            _ => {}
        }
    }
    let encoding = encoding.ok_or_else(|| bad("no format line".into()))?;
    let vi = elements.iter().position(|e| e.name == "vertex").ok_or_else(|| bad("no vertex element".into()))?;
    let vertex = &elements[vi];
    let mut idx = [0usize; 3];
    for (k, name) in ["nx", "ny", "nz"].iter().enumerate() {
        idx[k] = vertex
            .props
            .iter()
            .position(|p| p.name == *name)
            .ok_or_else(|| bad(format!("vertex element has no {name} property")))?;
        if vertex.props[idx[k]].float_kind.is_none() {
            return Err(IoError::unsupported(path, "PLY", format!("{name} is not float or double")));
        }
    }
    let double = idx.map(|i| vertex.props[i].float_kind == Some(true));
    let n = vertex.count;
    // A vertex count larger than the bytes can hold is garbage; refuse before allocating.
    if n > bytes.len() {
        return Err(bad(format!("vertex count {n} exceeds the file size")));
    }
    let mut normals = Vec::with_capacity(n);
    let mut layout =
        PlyLayout { bytes: Vec::new(), encoding, offsets: Vec::new(), double, ascii: Vec::new(), lines: None };
    match encoding {
        PlyEncoding::Ascii => {
            let text = std::str::from_utf8(&bytes[body_start..]).map_err(|_| bad("ascii body is not text".into()))?;
            let mut line_no = header_lines;
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
                    let col = body.find(tok).map_or(1, |c| c + 1);
                    value[k] = tok
                        .parse()
                        .map_err(|_| bad(format!("line {line_no}, column {col}: {tok:?} is not a number")))?;
                }
                if vertex.props.iter().any(|p| p.list.is_some()) {
                    return Err(IoError::unsupported(path, "PLY", "list properties in the vertex element"));
                }
                normals.push(value);
                layout.ascii.push((pos, pos + body.len(), idx));
                line_numbers.push(line_no);
                pos += l.len();
                line_no += 1;
            }
            layout.lines = Some(line_numbers);
        }
        PlyEncoding::Little | PlyEncoding::Big => {
            let mut pos = body_start;
            let read_uint = |pos: usize, size: usize| -> Option<usize> {
                let b = bytes.get(pos..pos + size)?;
                let mut v = 0usize;
                for k in 0..size {
                    let byte = if encoding == PlyEncoding::Little { b[size - 1 - k] } else { b[k] };
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
                if el.props.is_empty() {
                    continue;
                }
                if el.count > bytes.len() {
                    return Err(bad(format!("element {} count {} exceeds the file size", el.name, el.count)));
                }
                for v in 0..el.count {
                    let mut offs = [0usize; 3];
                    for (pi, p) in el.props.iter().enumerate() {
                        if let Some(size) = p.scalar {
                            if ei == vi {
                                for k in 0..3 {
                                    if idx[k] == pi {
                                        offs[k] = pos;
                                    }
                                }
                            }
                            pos += size;
                        } else if let Some((cs, vs)) = p.list {
                            let count = read_uint(pos, cs)
                                .ok_or_else(|| bad(format!("truncated in element {} #{v}", el.name)))?;
                            // A garbled count must not wrap the offset back into the file.
                            pos = count.checked_mul(vs).and_then(|n| n.checked_add(pos + cs)).ok_or_else(|| {
                                bad(format!("list length {count} in element {} #{v} overflows", el.name))
                            })?;
                        }
                        if pos > bytes.len() {
                            return Err(bad(format!("truncated in element {} #{v} of {}", el.name, el.count)));
                        }
                    }
                    if ei == vi {
                        let mut value = [0f32; 3];
                        for k in 0..3 {
                            value[k] = read_float(&bytes, offs[k], double[k], encoding == PlyEncoding::Little);
                        }
                        normals.push(value);
                        layout.offsets.push(offs);
                    }
                }
            }
        }
    }
    layout.bytes = bytes;
    if normals.is_empty() {
        return Err(bad("no vertices".into()));
    }
    Ok(NormalSource { normals, kind: Kind::Ply(layout) })
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

impl PlyLayout {
    fn write_back(&self, decoded: &[[f32; 3]]) -> Vec<u8> {
        match self.encoding {
            PlyEncoding::Ascii => {
                let mut out = Vec::with_capacity(self.bytes.len());
                let mut pos = 0;
                for (&(a, b, idx), n) in self.ascii.iter().zip(decoded) {
                    out.extend_from_slice(&self.bytes[pos..a]);
                    let line = String::from_utf8_lossy(&self.bytes[a..b]);
                    let mut tokens: Vec<String> = line.split_whitespace().map(str::to_string).collect();
                    for k in 0..3 {
                        tokens[idx[k]] = fmt_f32(n[k]);
                    }
                    out.extend_from_slice(tokens.join(" ").as_bytes());
                    pos = b;
                }
                out.extend_from_slice(&self.bytes[pos..]);
                out
            }
            PlyEncoding::Little | PlyEncoding::Big => {
                let little = self.encoding == PlyEncoding::Little;
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

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// Writes normals alone in the format of `path`'s extension (used by `--decode`): `.obj` as
/// `vn` lines, `.ply` as an ascii PLY with `nx ny nz`, `.exr` (needs `size`) as an RGB image,
/// anything else raw f32.
pub fn write_normals(
    path: &Path,
    normals: &[[f32; 3]],
    size: Option<(usize, usize)>,
    unorm: bool,
) -> Result<Vec<u8>, IoError> {
    Ok(match SourceFormat::from_path(path) {
        SourceFormat::Raw => raw_to_bytes(normals),
        SourceFormat::Obj => {
            let mut s = String::from("# prtkit encode-normals --decode\n");
            for n in normals {
                s += &format!("vn {} {} {}\n", fmt_f32(n[0]), fmt_f32(n[1]), fmt_f32(n[2]));
            }
            s.into_bytes()
        }
        SourceFormat::Ply => {
            let mut s = format!(
                "ply\nformat ascii 1.0\ncomment prtkit encode-normals --decode\nelement vertex {}\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n",
                normals.len()
            );
            for n in normals {
                s += &format!("{} {} {}\n", fmt_f32(n[0]), fmt_f32(n[1]), fmt_f32(n[2]));
            }
            s.into_bytes()
        }
        SourceFormat::Exr => {
            let (w, h) = size.ok_or_else(|| IoError::invalid(path, "OpenEXR", "writing an EXR needs --size WxH"))?;
            if w * h != normals.len() {
                return Err(IoError::invalid(
                    path,
                    "OpenEXR",
                    format!("--size {w}x{h} holds {} normals, the codes hold {}", w * h, normals.len()),
                ));
            }
            let pixels = normals.iter().map(|n| if unorm { n.map(|c| 0.5 * c + 0.5) } else { *n }).collect();
            let image = RgbImage { width: w, height: h, pixels };
            crate::io::exr::encode_layers(&[("", &image)]).map_err(|e| IoError::invalid(path, "OpenEXR", e))?
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn obj_round_trip_keeps_other_lines() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.obj");
        std::fs::write(&p, "# c\nv 1 2 3\nvn 0 0 1\nvn 1 0 0\r\nf 1//1 1//2 1//1\n").unwrap();
        let s = NormalSource::read(&p, false).unwrap();
        assert_eq!(s.normals, vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
        assert_eq!(s.locate(1), "line 4");
        let out = String::from_utf8(s.write_back(&p, &[[0.0, 1.0, 0.0], [0.5, 0.25, -1.0]]).unwrap()).unwrap();
        assert_eq!(out, "# c\nv 1 2 3\nvn 0 1 0\nvn 0.5 0.25 -1\r\nf 1//1 1//2 1//1\n");
        std::fs::write(&p, "vn 0 x 1\n").unwrap();
        let e = NormalSource::read(&p, false).unwrap_err().to_string();
        assert!(e.contains("line 1, column 6") && e.contains("a.obj"), "{e}");
    }

    #[test]
    fn garbled_files_give_errors_not_panics() {
        let dir = tempfile::tempdir().unwrap();
        let mut state = crate::rng::SplitMix64::new(99);
        let headers = [
            "ply\nformat binary_little_endian 1.0\nelement face 3\nproperty list uchar int vertex_indices\nelement vertex 4\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n",
            "ply\nformat binary_big_endian 1.0\nelement vertex 99999999999\nproperty double nx\nproperty double ny\nproperty double nz\nend_header\n",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n",
            "ply\nformat ascii 1.0\nelement empty 18446744073709551615\nelement vertex 1\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n",
            "",
        ];
        for (h, header) in headers.iter().enumerate() {
            for trial in 0..100 {
                let len = (state.next_u64() % 64) as usize;
                let mut bytes = header.as_bytes().to_vec();
                bytes.extend((0..len).map(|_| state.next_u64() as u8));
                for ext in ["ply", "obj", "raw"] {
                    let p = dir.path().join(format!("g{h}_{trial}.{ext}"));
                    std::fs::write(&p, &bytes).unwrap();
                    // Either outcome is fine; a panic or a hang is not.
                    let _ = NormalSource::read(&p, false);
                }
            }
        }
    }

    #[test]
    fn ply_ascii_and_binary_agree() {
        let dir = tempfile::tempdir().unwrap();
        let header = |fmt: &str| {
            format!("ply\nformat {fmt} 1.0\nelement vertex 2\nproperty float x\nproperty float nx\nproperty double ny\nproperty float nz\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n")
        };
        let pa = dir.path().join("a.ply");
        std::fs::write(&pa, header("ascii") + "5 0 0 1\n6 1 0 0\n3 0 1 1\n").unwrap();
        let a = NormalSource::read(&pa, false).unwrap();
        assert_eq!(a.normals, vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
        let mut bin = header("binary_little_endian").into_bytes();
        for (x, n) in [(5f32, [0f32, 0.0, 1.0]), (6.0, [1.0, 0.0, 0.0])] {
            bin.extend(x.to_le_bytes());
            bin.extend(n[0].to_le_bytes());
            bin.extend((n[1] as f64).to_le_bytes());
            bin.extend(n[2].to_le_bytes());
        }
        bin.extend([3u8]);
        bin.extend([0i32, 1, 1].iter().flat_map(|i| i.to_le_bytes()));
        let pb = dir.path().join("b.ply");
        std::fs::write(&pb, &bin).unwrap();
        let b = NormalSource::read(&pb, false).unwrap();
        assert_eq!(b.normals, a.normals);
        let new = [[0.0, 1.0, 0.0], [0.0, 0.0, -1.0]];
        std::fs::write(&pb, b.write_back(&pb, &new).unwrap()).unwrap();
        assert_eq!(NormalSource::read(&pb, false).unwrap().normals, new);
        std::fs::write(&pa, a.write_back(&pa, &new).unwrap()).unwrap();
        assert_eq!(NormalSource::read(&pa, false).unwrap().normals, new);
        // Truncated binary: an error, not a panic.
        std::fs::write(&pb, &bin[..bin.len() - 20]).unwrap();
        assert!(NormalSource::read(&pb, false).is_err());
    }
}
