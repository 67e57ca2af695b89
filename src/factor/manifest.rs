//! The `count-terms` manifest: one material per line (`docs/count-terms.md`).
//!
//! ```text
//! # name          spec                                  budget (optional)
//! gold-paint      merl:brdfs/gold-metallic-paint.binary 64
//! glossy          phong:s=30                            80
//! "matte floor"   lambert
//! ```
//!
//! Fields are separated by spaces or tabs; a field may be double-quoted to hold spaces (no
//! escapes); `#` starts a comment outside quotes; blank lines are ignored. The budget is a
//! positive integer or `-` (none: `--max-terms` applies). Relative MERL paths are relative to
//! the manifest's directory, and MERL files are read as their line is parsed, so that a missing
//! or garbled file is reported at its line and column. Names must be unique.

use crate::brdf::{Brdf, BrdfError};
use crate::io::IoError;
use std::path::Path;

/// One manifest entry.
#[derive(Clone, Debug)]
pub struct Entry {
    /// Material name.
    pub name: String,
    /// Its BRDF.
    pub brdf: Brdf,
    /// Term budget, if given.
    pub budget: Option<usize>,
    /// 1-based line number.
    pub line: usize,
    /// 1-based column of the spec field.
    pub spec_column: usize,
}

/// A manifest error at line:column (1-based; line 0: the file as a whole).
#[derive(Debug, thiserror::Error)]
#[error("{file}{}: {reason}", if *line > 0 { format!(":{line}:{column}") } else { String::new() })]
pub struct ManifestError {
    /// The manifest file.
    pub file: String,
    /// Line.
    pub line: usize,
    /// Column.
    pub column: usize,
    /// What is wrong.
    pub reason: String,
}

/// Splits a line into (column, field) pairs, honouring double quotes and `#` comments.
fn fields(line: &str) -> Result<Vec<(usize, String)>, (usize, String)> {
    let mut out = Vec::new();
    let chars: Vec<(usize, char)> = line.char_indices().collect();
    let mut i = 0;
    while i < chars.len() {
        let (byte, c) = chars[i];
        if c == ' ' || c == '\t' || c == '\r' {
            i += 1;
            continue;
        }
        if c == '#' {
            break;
        }
        let column = line[..byte].chars().count() + 1;
        let mut field = String::new();
        if c == '"' {
            i += 1;
            loop {
                match chars.get(i) {
                    None => return Err((column, "unterminated quoted field".into())),
                    Some((_, '"')) => {
                        i += 1;
                        break;
                    }
                    Some((_, ch)) => field.push(*ch),
                }
                i += 1;
            }
        } else {
            while let Some(&(_, ch)) = chars.get(i) {
                if ch == ' ' || ch == '\t' || ch == '\r' {
                    break;
                }
                field.push(ch);
                i += 1;
            }
        }
        out.push((column, field));
    }
    Ok(out)
}

/// Reads and parses the manifest at `path` (at most [`crate::limits::max_document_bytes`]);
/// relative MERL paths are relative to its directory.
pub fn read(path: &Path) -> Result<Vec<Entry>, ManifestError> {
    let file = crate::io::read::display_path(path).display().to_string();
    let whole = |reason: String| ManifestError { file: file.clone(), line: 0, column: 0, reason };
    let text = crate::io::read_text(path, "manifest", crate::limits::max_document_bytes(), |_| Ok(())).map_err(
        |e| match e {
            IoError::Os { error, .. } => whole(error.to_string()),
            IoError::Invalid { reason, .. } | IoError::Unsupported { reason, .. } => whole(reason),
            other => whole(other.to_string()),
        },
    )?;
    parse(&text, &file, path.parent().unwrap_or(Path::new("")))
}

/// Parses manifest text, reading its MERL files; `file` names it in errors and `base`
/// resolves relative MERL paths.
pub fn parse(text: &str, file: &str, base: &Path) -> Result<Vec<Entry>, ManifestError> {
    let err =
        |line: usize, column: usize, reason: String| ManifestError { file: file.to_string(), line, column, reason };
    let mut entries: Vec<Entry> = Vec::new();
    for (idx, line) in text.lines().enumerate() {
        let n = idx + 1;
        let f = fields(line).map_err(|(c, r)| err(n, c, r))?;
        if f.is_empty() {
            continue;
        }
        if f.len() < 2 || f.len() > 3 {
            return Err(err(
                n,
                f[0].0,
                format!("expected `name spec [budget]` (2 or 3 fields), found {} field(s)", f.len()),
            ));
        }
        let (name_col, name) = (&f[0].0, f[0].1.clone());
        if let Some(prev) = entries.iter().find(|e| e.name == name) {
            return Err(err(n, *name_col, format!("material {name:?} is already defined on line {}", prev.line)));
        }
        // A spec error quotes the spec; a MERL file's error names the material.
        let brdf = Brdf::parse_relative_to(&f[1].1, base).map_err(|e| match e {
            BrdfError::Spec(e) => err(n, f[1].0, e.to_string()),
            merl => err(n, f[1].0, format!("material {name:?}: {merl}")),
        })?;
        let budget = match f.get(2) {
            None => None,
            Some((_, b)) if b == "-" => None,
            Some((c, b)) => match b.parse::<usize>() {
                Ok(v) if v > 0 => Some(v),
                _ => return Err(err(n, *c, format!("budget {b:?} is not a positive integer (or `-` for none)"))),
            },
        };
        entries.push(Entry { name, brdf, budget, line: n, spec_column: f[1].0 });
    }
    if entries.is_empty() {
        return Err(err(1, 1, "the manifest lists no material".into()));
    }
    Ok(entries)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_fields_quotes_comments_and_budgets() {
        let text =
            "# header\n\nglossy phong:s=30 80\n\"matte floor\"\tlambert   # no budget\nrough ggx:roughness=0.5 -\n";
        let e = parse(text, "m.txt", Path::new("/data")).unwrap();
        assert_eq!(e.len(), 3);
        assert_eq!((e[0].name.as_str(), e[0].budget, e[0].line), ("glossy", Some(80), 3));
        assert_eq!(e[0].brdf.spec(), "phong:s=30");
        assert_eq!((e[1].name.as_str(), e[1].budget, e[1].spec_column), ("matte floor", None, 15));
        assert_eq!((e[2].brdf.spec().as_str(), e[2].budget), ("ggx:roughness=0.5", None));
    }

    #[test]
    fn errors_carry_line_and_column() {
        let e = |t: &str| parse(t, "m.txt", Path::new(".")).unwrap_err().to_string();
        assert_eq!(e("a phong:s=3 12\nb  phong:s=0 4\n").split(": ").next(), Some("m.txt:2:4"));
        assert!(e("a phong:s=3 zero\n").starts_with("m.txt:1:13: budget \"zero\""));
        assert!(e("a\n").contains("m.txt:1:1: expected `name spec [budget]`"));
        assert!(e("a lambert\na phong:s=2\n").contains("already defined on line 1"));
        assert!(e("\"a lambert\n").contains("unterminated"));
        assert!(e("# nothing\n").contains("no material"));
        assert!(e("x glossy:s=2").contains("m.txt:1:3: invalid BRDF spec"));
    }

    #[test]
    fn a_missing_merl_file_is_reported_at_its_manifest_line() {
        let dir = tempfile::tempdir().unwrap();
        let m = dir.path().join("materials.txt");
        std::fs::write(&m, "# materials\nglossy phong:s=30\n  gold   merl:brdfs/gold.binary 64\n").unwrap();
        let e = read(&m).unwrap_err().to_string();
        let want = format!("{}:3:10: material \"gold\": ", m.display());
        assert!(e.starts_with(&want) && e.contains("gold.binary") && e.contains("cannot read"), "{e}");
        // Relative to the manifest's directory.
        assert!(e.contains(&dir.path().join("brdfs").display().to_string()), "{e}");
        let e = read(&dir.path().join("none.txt")).unwrap_err().to_string();
        assert!(e.contains("none.txt: ") && !e.contains(":0:"), "{e}");
    }
}
