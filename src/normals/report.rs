//! The `prtkit.normal-codes` document (`docs/formats/normal-codes.md`): what an encode run
//! wrote, the code layout a decoder needs, and how accurate the codes are.

use super::metrics::Histogram;
use super::pack::Stream;
use super::{Digit, Scheme};
use crate::io::document::BundleError;
use crate::io::Document;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The document's format name.
pub const FORMAT: &str = "prtkit.normal-codes";
/// Its schema version. Version 2 describes codes by mixed-radix `digits`; version 1 (bit
/// `fields`, three whole face bits) is not read: its SC, PP, SPP and CM codes use the old layouts.
pub const VERSION: u32 = 2;

/// The body of a `prtkit.normal-codes` report.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct EncodeReport {
    /// Input file.
    pub input: String,
    /// `exr`, `obj`, `ply` or `raw`.
    pub input_format: String,
    /// Scheme name.
    pub scheme: Scheme,
    /// Bits per normal.
    pub bits: u32,
    /// Number of normals.
    pub count: u64,
    /// Code stream layout.
    pub layout: CodeLayout,
    /// Codes file, if written.
    pub codes: Option<String>,
    /// Decoded normals file, if written.
    pub decoded: Option<String>,
    /// Angular error of decode(encode(n)) against the normalized input (radians).
    pub error: ErrorSummary,
    /// Closed-form maximum error for this scheme and budget (radians).
    pub bound: f64,
    /// Sample spacing ε in the paper's units.
    pub spacing: f64,
    /// Histogram of the errors.
    pub histogram: Histogram,
    /// Normals replaced by +Z under `--on-invalid replace` (count and up to 100 indices).
    pub replaced: Replaced,
}

/// Code stream layout in a report.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CodeLayout {
    /// `words` or `packed`.
    pub stream: Stream,
    /// Bytes per word (`words` only).
    pub word_bytes: Option<usize>,
    /// The split in words, e.g. `face:6 a:6847421 b:6851119 = 2.585+22.707+22.708 bits`.
    pub split: String,
    /// Digits of one code, lowest first: `code = Σ d_i · Π_{j<i} N_j`.
    pub digits: Vec<Digit>,
}

/// Error statistics in a report.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ErrorSummary {
    /// Largest error.
    pub max: f64,
    /// Mean error.
    pub mean: f64,
    /// RMS error.
    pub rms: f64,
    /// Index of the largest error.
    pub max_index: u64,
    /// `max / bound`.
    pub max_over_bound: f64,
}

/// Replaced invalid normals.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Replaced {
    /// How many.
    pub count: u64,
    /// The first indices (at most 100).
    pub indices: Vec<usize>,
}

impl EncodeReport {
    /// The one-line summary the CLI prints on stderr.
    pub fn summary(&self) -> String {
        let replaced = match self.replaced.count {
            0 => String::new(),
            n => format!(", {n} invalid replaced by +Z"),
        };
        format!(
            "{} normals, {} at {} bits: max {:.3e} rad, mean {:.3e}, rms {:.3e} (bound {:.3e}){replaced}",
            self.count, self.scheme, self.bits, self.error.max, self.error.mean, self.error.rms, self.bound
        )
    }
}

/// Reads the report at `path` (e.g. the `--header` of a decode run), naming the file in errors.
pub fn read(path: &Path) -> Result<Document<EncodeReport>, BundleError> {
    let text = crate::io::document::read_text(path)?;
    parse(&text).map_err(|reason| BundleError::Document { path: crate::io::read::display_path(path), reason })
}

/// Parses a report, checking format and version.
pub fn parse(text: &str) -> Result<Document<EncodeReport>, String> {
    let version =
        serde_json::from_str::<serde_json::Value>(text).ok().and_then(|v| v.get("version").and_then(|v| v.as_u64()));
    if version == Some(1) {
        return Err(format!(
            "{FORMAT} version 1 describes the bit-field layouts before mixed-radix codes; re-encode, or decode with --scheme/--bits"
        ));
    }
    crate::io::document::parse_document(text, FORMAT, VERSION).map_err(|e| e.to_string())
}
