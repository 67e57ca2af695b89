//! The decode mode of `encode-normals` as one library call: a code stream in, f32 unit normals
//! out (the same f32 decoder as [`super::encode::Output::decoded`]).

use super::pack::Stream;
use super::report::EncodeReport;
use super::{Codec, NormalsError, Scheme};
use crate::progress::Progress;

/// How the codes were written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Config {
    /// The parameterization.
    pub scheme: Scheme,
    /// Bits per normal (8..=64).
    pub bits: u32,
    /// Code stream layout.
    pub stream: Stream,
}

impl Config {
    /// The layout an encode run recorded in its report.
    pub fn from_report(report: &EncodeReport) -> Config {
        Config { scheme: report.scheme, bits: report.bits, stream: report.layout.stream }
    }
}

/// Decodes every code in `bytes`.
pub fn run(config: &Config, bytes: &[u8], progress: &dyn Progress) -> Result<Vec<[f32; 3]>, NormalsError> {
    let codec = Codec::new(config.scheme, config.bits)?;
    let codes = config.stream.from_bytes(bytes, config.bits)?;
    if codes.is_empty() {
        return Err(NormalsError::Empty("codes"));
    }
    progress.start("decoding normals", 1);
    let mut normals = vec![[0f32; 3]; codes.len()];
    codec.decode_all_f32(&codes, &mut normals);
    progress.advance(1);
    progress.finish();
    Ok(normals)
}
