//! The `encode-normals` stage as one library call: normals in, codes, decoded normals and the
//! `prtkit.normal-codes` report out. The CLI (`cli/encode_normals.rs`) only reads the input,
//! builds the [`Config`] and writes what [`run`] returns; a program calling [`run`] on the same
//! normals gets the same bytes.

use super::metrics::{self, ErrorStats};
use super::pack::{self, Stream};
use super::report::{self, CodeLayout, EncodeReport, ErrorSummary, Replaced};
use super::{prepare, Codec, InvalidPolicy, NormalsError, Scheme};
use crate::io::{Document, Provenance};
use crate::progress::Progress;
use glam::DVec3;

/// How to encode.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// The parameterization.
    pub scheme: Scheme,
    /// Bits per normal (8..=64).
    pub bits: u32,
    /// Code stream layout of [`Output::stream`].
    pub stream: Stream,
    /// What to do with zero-length, NaN or infinite normals.
    pub on_invalid: InvalidPolicy,
    /// Histogram bins of the report (over `[0, max(bound, max error)]`).
    pub histogram_bins: usize,
    /// The files the report names (the library reads and writes none).
    pub files: Files,
    /// The command line recorded in the report's provenance (argv, argv\[0\] included).
    pub args: Vec<String>,
}

/// File names recorded in the report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Files {
    /// The input.
    pub input: String,
    /// Its format: `exr`, `obj`, `ply` or `raw`.
    pub input_format: String,
    /// Where the codes go, if anywhere.
    pub codes: Option<String>,
    /// Where the decoded normals go, if anywhere.
    pub decoded: Option<String>,
}

impl Files {
    /// The names for `input` (its format by extension) and the outputs, if any.
    pub fn new(input: &std::path::Path, codes: Option<String>, decoded: Option<String>) -> Files {
        let input_format = format!("{:?}", super::sources::SourceFormat::from_path(input)).to_lowercase();
        Files { input: input.display().to_string(), input_format, codes, decoded }
    }
}

/// What an encode run produces.
#[derive(Clone, Debug)]
pub struct Output {
    /// One code per input normal.
    pub codes: Vec<u64>,
    /// The codes in the configured stream layout, as written to a file.
    pub stream: Vec<u8>,
    /// The codes decoded to f32 unit normals (the same decoder as the `decode` stage, so both
    /// give identical files).
    pub decoded: Vec<[f32; 3]>,
    /// The `prtkit.normal-codes` report.
    pub report: Document<EncodeReport>,
}

/// Encodes `normals` (f32 as read; each is normalized in f64 first), decodes the codes back and
/// measures every normal's angular error against the closed-form bound.
pub fn run(config: &Config, normals: &[[f32; 3]], progress: &dyn Progress) -> Result<Output, NormalsError> {
    if normals.is_empty() {
        return Err(NormalsError::Empty("normals to encode"));
    }
    let codec = Codec::new(config.scheme, config.bits)?;
    progress.start("encoding normals", 3);
    let (dirs, replaced) = prepare(normals, config.on_invalid)?;
    let mut codes = vec![0u64; dirs.len()];
    codec.encode_all(&dirs, &mut codes);
    progress.advance(1);
    let mut back = vec![DVec3::ZERO; dirs.len()];
    codec.decode_all(&codes, &mut back);
    let errors = metrics::errors(&dirs, &back);
    let stats: ErrorStats = metrics::stats(&errors);
    let bound = codec.bound();
    let histogram = metrics::histogram(&errors, bound.max(stats.max), config.histogram_bins);
    progress.advance(1);
    let mut decoded = vec![[0f32; 3]; codes.len()];
    codec.decode_all_f32(&codes, &mut decoded);
    progress.advance(1);
    progress.finish();

    let body = EncodeReport {
        input: config.files.input.clone(),
        input_format: config.files.input_format.clone(),
        scheme: codec.scheme(),
        bits: codec.bits(),
        count: dirs.len() as u64,
        layout: CodeLayout {
            stream: config.stream,
            word_bytes: (config.stream == Stream::Words).then(|| pack::word_bytes(codec.bits())),
            split: codec.split_text(),
            digits: codec.digits(),
        },
        codes: config.files.codes.clone(),
        decoded: config.files.decoded.clone(),
        error: ErrorSummary {
            max: stats.max,
            mean: stats.mean(),
            rms: stats.rms(),
            max_index: stats.max_index,
            max_over_bound: stats.max / bound,
        },
        bound,
        spacing: codec.spacing(),
        histogram,
        replaced: Replaced { count: replaced.len() as u64, indices: replaced.iter().copied().take(100).collect() },
    };
    let provenance = Provenance::new("encode-normals", &config.args, vec![config.files.input.clone()]);
    Ok(Output {
        stream: config.stream.to_bytes(&codes, codec.bits()),
        codes,
        decoded,
        report: Document::new(report::FORMAT, report::VERSION, provenance, body),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    #[test]
    fn report_matches_an_independent_measurement() {
        let normals: Vec<[f32; 3]> =
            vec![[0.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.6, 0.8, 0.0], [-0.3, 0.2, -0.9], [0.0, 0.0, 0.0]];
        let config = Config {
            scheme: Scheme::Cm,
            bits: 20,
            stream: Stream::Packed,
            on_invalid: InvalidPolicy::Replace,
            histogram_bins: 4,
            files: Files::default(),
            args: Vec::new(),
        };
        let out = run(&config, &normals, &NoProgress).unwrap();
        let r = &out.report.body;
        assert_eq!((r.count, r.replaced.count, r.replaced.indices.clone()), (5, 1, vec![4]));
        assert_eq!(out.stream.len(), (5 * 20usize).div_ceil(8));
        assert_eq!(Stream::Packed.from_bytes(&out.stream, 20).unwrap(), out.codes);
        // The largest error, recomputed here from the codec.
        let codec = Codec::new(Scheme::Cm, 20).unwrap();
        let worst = normals[..4]
            .iter()
            .map(|n| {
                let d = DVec3::from(n.map(f64::from)).normalize();
                metrics::angle_between(d, codec.decode(codec.encode(d)))
            })
            .fold(0.0, f64::max);
        assert!((r.error.max - worst).abs() <= 1e-15, "{} {worst}", r.error.max);
        assert!(r.error.max <= r.bound && r.histogram.counts.iter().sum::<u64>() == 5);
        assert_eq!(run(&config, &[], &NoProgress).unwrap_err(), NormalsError::Empty("normals to encode"));
    }
}
