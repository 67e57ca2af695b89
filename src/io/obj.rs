//! Wavefront OBJ, the one reader of it: the text read within the file ceiling, its lines split
//! into tokens with their columns once ([`lines`]), and from that the two views prtkit takes —
//! the geometry a mesh is built from ([`geometry`]: `v`, `vt`, `vn` and `f`, through `tobj`) and the
//! `vn` lines alone with where they sit, so that decoded normals can be written back in place
//! ([`vertex_normals`], [`replace_vertex_normals`]). The syntax is that of the OBJ
//! specification (Wavefront, "Object Files (.obj)", Appendix B1 of the Advanced Visualizer
//! manual): 1-based indices, negative ones relative to the end of the list defined so far.
//! Errors give the line and the column (in characters), both from 1; the caller names the file.

use glam::DVec3;
use std::path::Path;

/// What is wrong with an OBJ text.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ObjError {
    /// A line is wrong.
    #[error("line {line}, column {column}: {reason}")]
    At {
        /// Line, from 1.
        line: usize,
        /// Column (in characters), from 1.
        column: usize,
        /// What is wrong.
        reason: String,
    },
    /// `tobj` refused the text after the line check passed it.
    #[error("{0}")]
    Load(String),
    /// A face of `tobj`'s output names a vertex it does not have.
    #[error("a face index is out of range")]
    FaceIndex,
}

/// Reads an OBJ file (`-`: standard input) whole, within [`crate::limits::max_file_bytes`]
/// (`docs/limits.md`); bytes that are not UTF-8 are an error at their line and column.
pub fn read(path: &Path) -> Result<String, super::IoError> {
    super::read_text(path, "OBJ", crate::limits::max_file_bytes(), |_| Ok(()))
}

/// Why `Mesh::load_coloured` refuses an OBJ (the caller names the file): the OBJ specification
/// gives a vertex no colour (some writers append `r g b` to a `v` line, an extension prtkit does
/// not read), and a material's `Kd` and `map_Kd` are in the `.mtl` file, which prtkit does not
/// read either.
pub const NO_BASE_COLOURS: &str = "OBJ vertex colours are not read: the OBJ format has no vertex colours, and the \
                                   .mtl file with its Kd and map_Kd is not read; give the mesh as glTF (baseColorFactor, \
                                   baseColorTexture, COLOR_0) or PLY (red green blue per vertex), or use a constant albedo";

/// One line of an OBJ text.
pub struct Line<'a> {
    /// Line number, from 1.
    pub number: usize,
    /// Byte offset of the line in the text.
    pub start: usize,
    /// The line without its end (`\n`, `\r\n`).
    pub body: &'a str,
    /// Whitespace-separated tokens with their columns (in characters, from 1).
    pub tokens: Vec<(usize, &'a str)>,
}

impl Line<'_> {
    /// The column just past the end of the line, where a missing token is reported.
    fn end(&self) -> usize {
        self.body.chars().count() + 1
    }

    /// An error at token `k` (or at the end of the line when there is no token `k`).
    fn at(&self, k: usize, reason: String) -> ObjError {
        ObjError::At { line: self.number, column: self.tokens.get(k).map_or(self.end(), |t| t.0), reason }
    }
}

/// The lines of `text`, each split into tokens once: every view of an OBJ reads them from here.
pub fn lines(text: &str) -> impl Iterator<Item = Line<'_>> {
    let mut start = 0;
    text.split_inclusive('\n').enumerate().map(move |(i, raw)| {
        let body = raw.trim_end_matches(['\n', '\r']);
        let mut tokens = Vec::new();
        let mut open = None;
        for (col, (byte, c)) in body.char_indices().enumerate() {
            match (c.is_whitespace(), open) {
                (false, None) => open = Some((col + 1, byte)),
                (true, Some((col0, b0))) => {
                    tokens.push((col0, &body[b0..byte]));
                    open = None;
                }
                _ => {}
            }
        }
        if let Some((col0, b0)) = open {
            tokens.push((col0, &body[b0..]));
        }
        let line = Line { number: i + 1, start, body, tokens };
        start += raw.len();
        line
    })
}

/// Checks the lines of an OBJ that make geometry, in the terms `tobj` reads them: `v` with
/// three finite coordinates (then nothing, a non-zero w or r g b), `vt` with two numbers, `vn`
/// with three, and `f` with at least three vertices `v`, `v/vt`, `v//vn` or `v/vt/vn` whose
/// indices (1-based, or negative: relative to the end) refer to elements defined above.
/// Returns the first problem.
pub fn check(text: &str) -> Result<(), ObjError> {
    let mut counts = [0usize; 3]; // v, vt, vn defined so far
    for line in lines(text) {
        let tokens = &line.tokens;
        let number = |k: usize, what: &str| -> Result<f32, ObjError> {
            let Some(&(_, t)) = tokens.get(k) else {
                return Err(line.at(k, format!("{what} needs more numbers")));
            };
            match t.parse::<f32>() {
                Ok(x) if x.is_finite() => Ok(x),
                Ok(_) => Err(line.at(k, format!("{t:?} is not a finite 32-bit number"))),
                Err(_) => Err(line.at(k, format!("{t:?} is not a number"))),
            }
        };
        match tokens.first().map(|t| t.1) {
            Some("v") => {
                let xyz = [number(1, "v")?, number(2, "v")?, number(3, "v")?];
                match tokens.len() {
                    4 => {}
                    5 => {
                        let w = number(4, "v")?;
                        if xyz.iter().any(|c| !(c / w).is_finite()) {
                            return Err(line.at(4, format!("w = {w} makes the position infinite or undefined")));
                        }
                    }
                    7 => {
                        for k in 4..7 {
                            number(k, "v")?;
                        }
                    }
                    _ => return Err(line.at(4, "v takes x y z, then nothing, w, or r g b".into())),
                }
                counts[0] += 1;
            }
            Some("vt") => {
                number(1, "vt")?;
                number(2, "vt")?;
                counts[1] += 1;
            }
            Some("vn") => {
                for k in 1..4 {
                    number(k, "vn")?;
                }
                counts[2] += 1;
            }
            Some(kw @ ("f" | "l")) => {
                if kw == "f" && tokens.len() < 4 {
                    return Err(
                        line.at(tokens.len(), format!("a face needs at least 3 vertices, found {}", tokens.len() - 1))
                    );
                }
                for k in 1..tokens.len() {
                    let parts: Vec<&str> = tokens[k].1.split('/').collect();
                    if parts.len() > 3 || parts[0].is_empty() {
                        return Err(line.at(k, format!("{:?} is not v, v/vt, v//vn or v/vt/vn", tokens[k].1)));
                    }
                    for (slot, part) in parts.iter().enumerate().filter(|(_, p)| !p.is_empty()) {
                        let what = ["vertex", "texture coordinate", "normal"][slot];
                        let index: i64 =
                            part.parse().map_err(|_| line.at(k, format!("{what} index {part:?} is not an integer")))?;
                        let count = counts[slot] as i64;
                        let resolved = if index < 0 { count.checked_add(index) } else { index.checked_sub(1) };
                        if index == 0 || !resolved.is_some_and(|r| (0..count).contains(&r)) {
                            return Err(line.at(
                                k,
                                format!("{what} index {index} is out of range ({count} defined above this line)"),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// The geometry of an OBJ, as `tobj` builds it from every object of the file (triangulated,
/// one index per vertex: `tobj` numbers the vertices in the order the faces first use each
/// (v, vt, vn) combination, which may differ from the `v` lines'; a position whose faces use
/// different `vt`s is split, as a UV seam needs). Normals as written (not normalized), UVs the
/// `vt` lines, each when every object gives every vertex one.
pub use super::geometry::Geometry;

/// Reads the geometry of an OBJ text: its lines are checked first ([`check`]), so that an error
/// names the line and the column, then `tobj` builds the indexed triangles.
pub fn geometry(text: &str) -> Result<Geometry, ObjError> {
    check(text)?;
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ..Default::default() };
    // Materials are not used: the loader refuses them (tobj keeps that apart from the geometry).
    let (models, _) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(text), &options, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| ObjError::Load(e.to_string()))?;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut triangles = Vec::new();
    let mut uvs = Vec::new();
    let mut all_have_normals = true;
    let mut all_have_uvs = true;
    for m in &models {
        let mesh = &m.mesh;
        let base = positions.len() as u32;
        let nv = mesh.positions.len() / 3;
        for c in mesh.positions.chunks_exact(3) {
            positions.push(DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64));
        }
        if mesh.normals.len() == mesh.positions.len() && nv > 0 {
            for c in mesh.normals.chunks_exact(3) {
                normals.push(DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64));
            }
        } else {
            all_have_normals = false;
            normals.extend(std::iter::repeat_n(DVec3::ZERO, nv));
        }
        if mesh.texcoords.len() == 2 * nv && nv > 0 {
            uvs.extend(mesh.texcoords.chunks_exact(2).map(|c| [c[0] as f64, c[1] as f64]));
        } else {
            all_have_uvs = false;
        }
        for t in mesh.indices.chunks_exact(3) {
            if t.iter().any(|&i| i as usize >= nv) {
                return Err(ObjError::FaceIndex);
            }
            triangles.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    Ok(Geometry {
        positions,
        normals: all_have_normals.then_some(normals),
        triangles,
        uvs: (all_have_uvs && !uvs.is_empty()).then_some(uvs),
    })
}

/// Where a `vn` line sits in the text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VnLine {
    /// Line number, from 1.
    pub line: usize,
    /// Byte range of the line (without its end) in the text.
    pub start: usize,
    /// End of that range.
    pub end: usize,
}

/// The `vn` lines of an OBJ, in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexNormals {
    /// The normals as written (f32, not normalized; not checked for finiteness: the caller
    /// decides what a NaN normal means).
    pub normals: Vec<[f32; 3]>,
    /// Where each sits.
    pub lines: Vec<VnLine>,
}

/// Reads the `vn` lines of an OBJ text, each `vn x y z` (anything after the third number is
/// ignored); the other lines are not looked at, so a file of normals alone is read too.
pub fn vertex_normals(text: &str) -> Result<VertexNormals, ObjError> {
    let mut normals = Vec::new();
    let mut lines_at = Vec::new();
    for line in lines(text) {
        if line.tokens.first().map(|t| t.1) != Some("vn") {
            continue;
        }
        let mut v = [0f32; 3];
        for (k, c) in v.iter_mut().enumerate() {
            let Some(&(_, token)) = line.tokens.get(k + 1) else {
                return Err(line.at(k + 1, format!("vn needs 3 numbers, found {k}")));
            };
            *c = token.parse().map_err(|_| line.at(k + 1, format!("{token:?} is not a number")))?;
        }
        normals.push(v);
        lines_at.push(VnLine { line: line.number, start: line.start, end: line.start + line.body.len() });
    }
    Ok(VertexNormals { normals, lines: lines_at })
}

/// `text` with the `vn` lines at `lines` replaced by `decoded`, one for one, every other byte
/// kept. Numbers are written with the shortest text that reads back to the same f32.
pub fn replace_vertex_normals(text: &str, lines: &[VnLine], decoded: &[[f32; 3]]) -> String {
    let mut out = String::with_capacity(text.len());
    let mut pos = 0;
    for (l, n) in lines.iter().zip(decoded) {
        out.push_str(&text[pos..l.start]);
        out.push_str(&format!("vn {} {} {}", n[0], n[1], n[2]));
        pos = l.end;
    }
    out.push_str(&text[pos..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(e: ObjError) -> (usize, usize, String) {
        match e {
            ObjError::At { line, column, reason } => (line, column, reason),
            other => panic!("not positioned: {other}"),
        }
    }

    #[test]
    fn errors_name_the_line_and_column() {
        let e = |text: &str| check(text).err().map(at);
        assert_eq!(e("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf -1 -2 -3\n"), None);
        assert_eq!(e("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//1 2 3\n").map(|x| (x.0, x.1)), Some((4, 3)));
        assert_eq!(e("v 0 0 0\nv 0 0 0\nv 0 0 0\n\n  f 1 2 4\n").map(|x| (x.0, x.1)), Some((5, 9)));
        assert!(e("v 0 0 0\nf 1 0 1\n").is_some_and(|x| x.1 == 5 && x.2.contains("vertex index 0")));
        assert!(e("v 0 0 0\nf 1 -2 1\n").is_some_and(|x| x.2.contains("out of range (1 defined")));
        assert!(e("v 0 0 1e39\n").is_some_and(|x| (x.0, x.1) == (1, 7) && x.2.contains("finite")));
        assert!(e("v 0 0 1 0\n").is_some_and(|x| x.2.contains("w = 0")));
        assert!(e("v 0 0\n").is_some_and(|x| x.1 == 6 && x.2.contains("needs more numbers")));
        assert!(e("vn 0 x 1\n").is_some_and(|x| x.1 == 6));
        assert!(e("v 0 0 0\nf 1 1\n").is_some_and(|x| x.2.contains("at least 3")));
        assert!(e("v 0 0 0\nf 1/2/3/4 1 1\n").is_some_and(|x| x.1 == 3));
        // The vn view reports in the same terms, columns in characters.
        let vn = |text: &str| vertex_normals(text).err().map(at);
        assert_eq!(vn("vn 0 x 1\n"), Some((1, 6, "\"x\" is not a number".into())));
        assert_eq!(vn("v 0 0 0\n\u{e9}\nvn 1 0\n"), Some((3, 7, "vn needs 3 numbers, found 2".into())));
        assert_eq!(vn("vn n n n\n").map(|x| x.1), Some(4));
    }

    #[test]
    fn both_views_read_the_same_normals_and_write_back_keeps_other_lines() {
        let text = "# c\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 1 0 0\r\nf 1//1 2//2 3//1\n";
        let g = geometry(text).unwrap();
        assert_eq!(g.triangles, vec![[0, 1, 2]]);
        assert_eq!(g.normals.unwrap(), vec![DVec3::Z, DVec3::X, DVec3::Z]);
        let v = vertex_normals(text).unwrap();
        assert_eq!(v.normals, vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
        assert_eq!(v.lines.iter().map(|l| l.line).collect::<Vec<_>>(), vec![5, 6]);
        let out = replace_vertex_normals(text, &v.lines, &[[0.0, 1.0, 0.0], [0.5, 0.25, -1.0]]);
        assert_eq!(out, "# c\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 1 0\nvn 0.5 0.25 -1\r\nf 1//1 2//2 3//1\n");
        assert_eq!(geometry("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap().normals, None);
    }
}
