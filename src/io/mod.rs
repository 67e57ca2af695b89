//! File formats: HDR images (OpenEXR, Radiance `.hdr`, PFM), tone-mapped PNG, meshes (OBJ, PLY, glTF),
//! GPU textures (KTX2, DDS), JSON documents, and atomic writes. Everything that touches a file
//! format lives here, once.

pub mod atomic;
pub mod dds;
pub mod document;
pub mod exr;
pub mod geometry;
pub mod glb;
pub mod gltf;
pub mod gpu_format;
pub mod image;
pub mod ktx2;
pub mod obj;
pub mod pfm;
pub mod ply;
pub mod png;
pub mod read;
pub mod rgbe;
pub mod texture;

pub use self::image::{ImageFormat, RgbImage};
pub use atomic::{write_atomic, Output, OutputSet};
pub use document::{Document, Provenance};
pub use read::{read_bytes, read_text};

use std::path::{Path, PathBuf};

/// Errors from reading or writing files. Each variant is a kind of cause; every one names the file.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The operating system refused (missing file, permissions, disk full…).
    #[error("{path}: {error}")]
    Os {
        /// The file involved.
        path: PathBuf,
        /// The underlying error. Shown in the message and deliberately not a `source()`: the
        /// CLI prints the cause chain, which would repeat it.
        error: std::io::Error,
    },
    /// The bytes are not a valid file of the expected format (truncated, garbled).
    #[error("{path}: invalid {format} file: {reason}")]
    Invalid {
        /// The file involved.
        path: PathBuf,
        /// Format name, e.g. "OpenEXR".
        format: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// A valid file that uses a feature prtkit does not read.
    #[error("{path}: unsupported {format} file: {reason}")]
    Unsupported {
        /// The file involved.
        path: PathBuf,
        /// Format name.
        format: &'static str,
        /// What is not supported.
        reason: String,
    },
    /// The file name does not say which format to use.
    #[error("{path}: unknown image format (expected .exr, .hdr, .pfm{extra})")]
    UnknownFormat {
        /// The file involved.
        path: PathBuf,
        /// Extra accepted extensions for the message.
        extra: &'static str,
    },
}

impl IoError {
    pub(crate) fn os(path: &Path, source: std::io::Error) -> Self {
        IoError::Os { path: path.to_path_buf(), error: source }
    }
    pub(crate) fn invalid(path: &Path, format: &'static str, reason: impl Into<String>) -> Self {
        IoError::Invalid { path: path.to_path_buf(), format, reason: reason.into() }
    }
    pub(crate) fn unsupported(path: &Path, format: &'static str, reason: impl Into<String>) -> Self {
        IoError::Unsupported { path: path.to_path_buf(), format, reason: reason.into() }
    }
}
