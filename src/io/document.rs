//! JSON documents: every file prtkit writes carries a format name, a version, the conventions it
//! uses and enough provenance to debug a Makefile from the file alone (`docs/formats.md`).

use serde::{Deserialize, Serialize};

/// The SH convention every prtkit document uses (DESIGN.md, `docs/conventions.md`).
pub const SH_CONVENTION: &str =
    "real orthonormal SH, index l(l+1)+m, no Condon-Shortley phase: Y_1,-1 ~ y, Y_1,0 ~ z, Y_1,1 ~ x";
/// The direction frame every prtkit document uses.
pub const FRAME_CONVENTION: &str =
    "right-handed, +Z up, theta from +Z, phi from +X towards +Y; lat-long row 0 is theta = 0";

/// Conventions block written into every document.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Conventions {
    /// Direction frame.
    pub frame: String,
    /// Spherical harmonic basis and ordering.
    pub sh: String,
    /// How the input environment map was turned on reading (`as stored`, or flipped
    /// vertically), in documents made from one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_orientation: Option<String>,
}

impl Default for Conventions {
    fn default() -> Self {
        Conventions { frame: FRAME_CONVENTION.into(), sh: SH_CONVENTION.into(), input_orientation: None }
    }
}

/// Where a document came from.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Provenance {
    /// Program and version, e.g. `prtkit 0.1.0`.
    pub tool: String,
    /// The stage that wrote it, e.g. `sh-project`.
    pub stage: String,
    /// The command line, one argument per element.
    pub args: Vec<String>,
    /// Input files.
    #[serde(default)]
    pub inputs: Vec<String>,
}

/// Options that change how a run goes but never what it writes (`docs/cli.md`: the bytes are the
/// same for any thread count, and narration is on stderr), left out of [`Provenance::args`] so
/// that a document's bytes do not depend on them: (option, whether it takes a value).
const NOT_RECORDED: [(&str, bool); 3] = [("--threads", true), ("--quiet", false), ("-q", false)];

impl Provenance {
    /// Provenance of `stage` run with the command line `args` on `inputs`; the options that do
    /// not change the result ([`NOT_RECORDED`]: `--threads N`, `-q`) are left out of it.
    pub fn new(stage: &str, args: &[String], inputs: Vec<String>) -> Self {
        let mut recorded = Vec::with_capacity(args.len());
        let mut iter = args.iter();
        while let Some(arg) = iter.next() {
            let option = NOT_RECORDED.iter().find(|(name, takes_value)| {
                arg == name || (*takes_value && arg.strip_prefix(name).is_some_and(|rest| rest.starts_with('=')))
            });
            match option {
                Some((name, true)) if arg == name => {
                    iter.next();
                }
                Some(_) => {}
                None => recorded.push(arg.clone()),
            }
        }
        Provenance {
            tool: format!("prtkit {}", env!("CARGO_PKG_VERSION")),
            stage: stage.to_string(),
            args: recorded,
            inputs,
        }
    }

    /// Provenance of the running process for `stage`.
    pub fn current(stage: &str, inputs: Vec<String>) -> Self {
        Provenance::new(stage, &std::env::args().collect::<Vec<_>>(), inputs)
    }
}

/// The header fields every document shares; stage-specific bodies are flattened beside them.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Document<T> {
    /// Document kind, e.g. `prtkit.sh`.
    pub format: String,
    /// Schema version of that kind.
    pub version: u32,
    /// Conventions used.
    pub conventions: Conventions,
    /// Where it came from.
    pub provenance: Provenance,
    /// The stage's content.
    #[serde(flatten)]
    pub body: T,
}

impl<T: Serialize> Document<T> {
    /// A document of `format` version `version` with the standard conventions.
    pub fn new(format: &str, version: u32, provenance: Provenance, body: T) -> Self {
        Document { format: format.to_string(), version, conventions: Conventions::default(), provenance, body }
    }

    /// The document of a stage that read an environment map: records how the map was turned on
    /// reading (`envmap::Orientation::describe`).
    pub fn with_input_orientation(mut self, words: &str) -> Self {
        self.conventions.input_orientation = Some(words.to_string());
        self
    }

    /// Pretty JSON with a trailing newline; floats are written with round-trip precision.
    pub fn to_json(&self) -> String {
        to_json_pretty(self)
    }
}

/// Pretty JSON with a trailing newline.
pub fn to_json_pretty<T: Serialize + ?Sized>(value: &T) -> String {
    // Serializing plain data structs cannot fail (no maps with non-string keys are used).
    let mut s = serde_json::to_string_pretty(value).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
    s.push('\n');
    s
}

/// An error in a JSON document, at a line and column when one is known (1-based; 0 when not).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}{reason}", if *line > 0 { format!("line {line}, column {column}: ") } else { String::new() })]
pub struct DocumentError {
    /// Line, from 1 (0: the document as a whole).
    pub line: usize,
    /// Column, from 1.
    pub column: usize,
    /// What is wrong.
    pub reason: String,
}

impl DocumentError {
    fn whole(reason: impl Into<String>) -> Self {
        DocumentError { line: 0, column: 0, reason: reason.into() }
    }

    fn from_json(e: &serde_json::Error, what: &str) -> Self {
        // serde_json's message ends with its own " at line L column C": keep the words only.
        let text = e.to_string();
        let words = text.rfind(" at line ").map_or(text.as_str(), |i| &text[..i]);
        DocumentError { line: e.line(), column: e.column(), reason: format!("{what}{words}") }
    }
}

/// What a document body checks beyond its types, before a loader computes with its values:
/// ceilings on orders and sizes (`docs/limits.md`), counts that must agree, finite numbers.
/// Every loader of the document gets the check through [`read_document`] and
/// [`parse_validated`].
pub trait Validate {
    /// `Err((field, reason))` names the offending field (located in the text for the message).
    fn validate(&self) -> Result<(), (&'static str, String)>;
}

/// The `format` and `version` fields alone (other fields are skipped, not built).
#[derive(Deserialize)]
struct Head {
    format: Option<serde_json::Value>,
    version: Option<serde_json::Value>,
}

/// The fields every document shares, read apart from the body.
#[derive(Deserialize)]
struct Header {
    format: String,
    version: u32,
    conventions: Conventions,
    provenance: Provenance,
}

/// Reads a document and checks its `format` and major `version`. Errors carry the line and
/// column of the text where serde_json knows them: the header and the body are read in two
/// passes over the text, each skipping the other's fields, because a flattened body would be
/// buffered first and lose every position.
pub fn parse_document<T: for<'de> Deserialize<'de>>(
    text: &str,
    expected_format: &str,
    max_version: u32,
) -> Result<Document<T>, DocumentError> {
    let head: Head = serde_json::from_str(text).map_err(|e| DocumentError::from_json(&e, "not a JSON object: "))?;
    let format = head.format.as_ref().and_then(|f| f.as_str()).unwrap_or("<none>");
    if format != expected_format {
        return Err(DocumentError::whole(format!(
            "expected a \"{expected_format}\" document, found format \"{format}\""
        )));
    }
    let version = head.version.as_ref().and_then(|v| v.as_u64()).unwrap_or(0);
    if version == 0 || version > max_version as u64 {
        return Err(DocumentError::whole(format!(
            "unsupported {expected_format} version {version} (this prtkit reads 1..={max_version})"
        )));
    }
    let invalid = |e: serde_json::Error| DocumentError::from_json(&e, &format!("invalid {expected_format} document: "));
    let header: Header = serde_json::from_str(text).map_err(invalid)?;
    let body: T = serde_json::from_str(text).map_err(invalid)?;
    Ok(Document {
        format: header.format,
        version: header.version,
        conventions: header.conventions,
        provenance: header.provenance,
        body,
    })
}

/// [`parse_document`], then the body's own checks ([`Validate`]); a failed check names the
/// field and, when the field's key occurs in the text, its line and column.
pub fn parse_validated<T: for<'de> Deserialize<'de> + Validate>(
    text: &str,
    expected_format: &str,
    max_version: u32,
) -> Result<Document<T>, DocumentError> {
    let doc: Document<T> = parse_document(text, expected_format, max_version)?;
    doc.body.validate().map_err(|(field, reason)| {
        let (line, column) = locate_key(text, field).unwrap_or((0, 0));
        DocumentError { line, column, reason: format!("\"{field}\": {reason}") }
    })?;
    Ok(doc)
}

/// Line and column (1-based, in characters) of the first `"key"` followed by a colon.
fn locate_key(text: &str, key: &str) -> Option<(usize, usize)> {
    let quoted = format!("\"{key}\"");
    let mut from = 0;
    while let Some(i) = text[from..].find(&quoted).map(|i| from + i) {
        let after = text[i + quoted.len()..].trim_start();
        if after.starts_with(':') {
            let before = &text[..i];
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            return Some((line, column));
        }
        from = i + quoted.len();
    }
    None
}

/// Errors of reading a document together with the EXR it names (an SHRM, a factor file).
#[derive(Debug, thiserror::Error)]
pub enum BundleError {
    /// I/O or EXR decoding of the document itself.
    #[error(transparent)]
    Io(#[from] super::IoError),
    /// The JSON document is not valid, or lacks what was asked of it.
    #[error("{path}: {reason}")]
    Document {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The JSON document does not parse or fails its checks, at a line and column.
    #[error("{}:{}", path.display(), match error.line { 0 => format!(" {}", error.reason), l => format!("{l}:{}: {}", error.column, error.reason) })]
    Parse {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong, and where.
        error: DocumentError,
    },
    /// The file the document names cannot be read: the document first, then the file's error.
    #[error("{}: cannot read the {what} it names: {error}", doc.display())]
    Named {
        /// The document that names the file.
        doc: std::path::PathBuf,
        /// What the file is, e.g. "SHRM file".
        what: &'static str,
        /// The named file's error (which names that file).
        error: super::IoError,
    },
    /// The EXR does not match its document.
    #[error("{exr}: does not match {doc}: {reason}")]
    Mismatch {
        /// The EXR.
        exr: std::path::PathBuf,
        /// The JSON.
        doc: std::path::PathBuf,
        /// What differs.
        reason: String,
    },
}

/// Reads a JSON document's text: at most [`crate::limits::max_document_bytes`], refused at
/// once when it does not start with `{` (after white space), and UTF-8.
pub fn read_text(path: &std::path::Path) -> Result<String, BundleError> {
    let text = super::read_text(path, "JSON", crate::limits::max_document_bytes(), |start| {
        match start.iter().find(|b| !b.is_ascii_whitespace()) {
            Some(b'{') | None => Ok(()),
            Some(_) => Err("does not start with '{': not a JSON document".into()),
        }
    })?;
    Ok(text)
}

/// Reads the document at `path` as `format` (versions up to `max_version`) and runs the body's
/// checks ([`Validate`]), naming the file (and line:column) in every error.
pub fn read_document<T: for<'de> Deserialize<'de> + Validate>(
    path: &std::path::Path,
    format: &str,
    max_version: u32,
) -> Result<Document<T>, BundleError> {
    let text = read_text(path)?;
    parse_validated(&text, format, max_version)
        .map_err(|error| BundleError::Parse { path: super::read::display_path(path), error })
}

/// The file a document names: as written when that exists (or is absolute), else the file of
/// that name beside the document — so a document and its EXR can be moved together.
pub fn named_file(doc: &std::path::Path, file: &str) -> std::path::PathBuf {
    let as_written = std::path::PathBuf::from(file);
    if as_written.is_absolute() || as_written.exists() {
        return as_written;
    }
    let dir = doc.parent().unwrap_or(std::path::Path::new("."));
    dir.join(std::path::Path::new(file).file_name().unwrap_or_default())
}

/// Reads the EXR a document names ([`named_file`]) with all its layers; an error that
/// concerns the EXR (missing, unreadable, garbled, too large) names the document first.
/// `what` says what the file is to the document, e.g. "SHRM file".
pub fn read_named_layers(
    doc: &std::path::Path,
    file: &str,
    what: &'static str,
) -> Result<(std::path::PathBuf, Vec<(String, super::RgbImage)>), BundleError> {
    let exr = named_file(doc, file);
    let layers = super::exr::read_layers(&exr).map_err(|error| BundleError::Named { doc: doc.into(), what, error })?;
    Ok((exr, layers))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn provenance_leaves_out_the_options_that_do_not_change_the_result() {
        let args: Vec<String> =
            ["ibl", "sky.exr", "--threads", "4", "-o", "bake", "-q", "--threads=2", "--quiet", "--size", "16"]
                .map(String::from)
                .to_vec();
        let recorded = Provenance::new("ibl", &args, vec![]).args;
        assert_eq!(recorded, ["ibl", "sky.exr", "-o", "bake", "--size", "16"]);
        // Only the options themselves: a file named like one's prefix stays.
        let args: Vec<String> = ["x", "--threadsafe.exr", "-qq"].map(String::from).to_vec();
        assert_eq!(Provenance::new("x", &args, vec![]).args, args);
    }
}
