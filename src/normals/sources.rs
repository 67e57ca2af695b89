//! Where normals come from and go back to: EXR normal maps, OBJ `vn` lines, PLY vertex
//! `nx ny nz` properties (ascii, binary little- and big-endian), and raw little-endian f32 xyz.
//!
//! The formats are read in [`crate::io`] (`io::obj`, `io::ply`, `io::image`), the one home of each;
//! a source keeps what it needs to write decoded normals back *in the same format*: the EXR size
//! and value encoding, the OBJ text with the `vn` lines replaced, the PLY file with only the
//! normal properties rewritten (binary: patched in place; ascii: the three tokens replaced).

use crate::io::{obj, ply, IoError, RgbImage};
use std::path::{Path, PathBuf};

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
    Ply(ply::NormalLayout),
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
            SourceFormat::Ply => {
                let ply::PlyNormals { normals, layout } = ply::vertex_normals(path, ply::read(path)?)?;
                Ok(NormalSource { normals, kind: Kind::Ply(layout) })
            }
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
            Kind::Ply(layout) => layout.locate(index),
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

/// Errors of writing decoded normals alone.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// Encoding the file failed.
    #[error(transparent)]
    Io(#[from] IoError),
    /// An EXR was asked for without the image's size.
    #[error("{}: invalid OpenEXR file: writing an EXR needs the image's size", path.display())]
    NoSize {
        /// The file.
        path: PathBuf,
    },
    /// The image's size does not hold the normals.
    #[error("{}: invalid OpenEXR file: a {width}x{height} image holds {} normals, the codes hold {normals}", path.display(), width * height)]
    Size {
        /// The file.
        path: PathBuf,
        /// W.
        width: usize,
        /// H.
        height: usize,
        /// The normals decoded.
        normals: usize,
    },
}

/// Writes normals alone in the format of `path`'s extension (used by `--decode`): `.obj` as
/// `vn` lines, `.ply` as an ascii PLY with `nx ny nz`, `.exr` (needs `size`) as an RGB image,
/// anything else raw f32.
pub fn write_normals(
    path: &Path,
    normals: &[[f32; 3]],
    size: Option<(usize, usize)>,
    unorm: bool,
) -> Result<Vec<u8>, WriteError> {
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
            let (width, height) = size.ok_or_else(|| WriteError::NoSize { path: path.into() })?;
            if width * height != normals.len() {
                return Err(WriteError::Size { path: path.into(), width, height, normals: normals.len() });
            }
            let pixels = normals.iter().map(|n| if unorm { n.map(|c| 0.5 * c + 0.5) } else { *n }).collect();
            let image = RgbImage { width, height, pixels };
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
