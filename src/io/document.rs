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
}

impl Default for Conventions {
    fn default() -> Self {
        Conventions { frame: FRAME_CONVENTION.into(), sh: SH_CONVENTION.into() }
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

impl Provenance {
    /// Provenance of `stage` run with the command line `args` on `inputs`.
    pub fn new(stage: &str, args: &[String], inputs: Vec<String>) -> Self {
        Provenance {
            tool: format!("prtkit {}", env!("CARGO_PKG_VERSION")),
            stage: stage.to_string(),
            args: args.to_vec(),
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

/// Reads a document and checks its `format` and major `version`.
pub fn parse_document<T: for<'de> Deserialize<'de>>(
    text: &str,
    expected_format: &str,
    max_version: u32,
) -> Result<Document<T>, String> {
    let head: serde_json::Value =
        serde_json::from_str(text).map_err(|e| format!("not JSON: line {}, column {}: {e}", e.line(), e.column()))?;
    let format = head.get("format").and_then(|f| f.as_str()).unwrap_or("<none>");
    if format != expected_format {
        return Err(format!("expected a \"{expected_format}\" document, found format \"{format}\""));
    }
    let version = head.get("version").and_then(|v| v.as_u64()).unwrap_or(0);
    if version == 0 || version > max_version as u64 {
        return Err(format!("unsupported {expected_format} version {version} (this prtkit reads 1..={max_version})"));
    }
    serde_json::from_value(head).map_err(|e| format!("invalid {expected_format} document: {e}"))
}

/// Errors of reading a document together with the EXR it names (an SHRM, a factor file).
#[derive(Debug, thiserror::Error)]
pub enum BundleError {
    /// I/O or EXR decoding.
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

/// Reads the document at `path` as `format` (versions up to `max_version`), naming the file in
/// every error.
pub fn read_document<T: for<'de> Deserialize<'de>>(
    path: &std::path::Path,
    format: &str,
    max_version: u32,
) -> Result<Document<T>, BundleError> {
    let bad = |reason: String| BundleError::Document { path: path.into(), reason };
    let text = String::from_utf8(super::read_bytes(path)?).map_err(|_| bad("not UTF-8 text".into()))?;
    parse_document(&text, format, max_version).map_err(bad)
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
