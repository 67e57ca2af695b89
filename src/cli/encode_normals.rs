//! `encode-normals`: compress normals with the sphere parameterizations of Meyer et al. 2010,
//! report the exact error against the closed-form bounds, decode codes back, emit shader
//! decoders, and reproduce Table 1 (`--table`).

use super::common::{init_threads, Bar, Execution, Outcome};
use crate::io::{Document, Output, Provenance};
use crate::normals::metrics::{self, ErrorStats, Histogram};
use crate::normals::shader::{self, Language};
use crate::normals::sources::{self, NormalSource, SourceFormat};
use crate::normals::table::{self, Row, TableConfig};
use crate::normals::{pack, prepare, Codec, Digit, InvalidPolicy, NormalsError, Scheme};
use anyhow::{bail, Context, Result};
use clap::Parser;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Encode normal vectors at a bit budget and measure the exact angular error.
///
/// Modes: encode INPUT (default), `--decode CODES`, `--emit-decoder LANG`, `--table`.
/// INPUT format by extension: .exr (normal map), .obj (vn lines), .ply (nx ny nz; ascii or
/// binary), anything else raw little-endian f32 xyz.
#[derive(Debug, Parser)]
#[command(name = "encode-normals", version)]
pub struct Args {
    /// Input normals (encode) or codes (--decode).
    pub input: Option<PathBuf>,
    /// Parameterization: onv-range, onv-domain, sc, pp, spp, cm.
    #[arg(long, default_value = "onv-range", value_parser = parse_scheme)]
    pub scheme: Scheme,
    /// Bits per normal, 8..=64 [default: 32; with --table: 48, the paper's Table 1].
    #[arg(long, value_parser = clap::value_parser!(u32).range(8..=64))]
    pub bits: Option<u32>,
    /// Codes output (encode) or normals output (--decode); `-` is stdout.
    #[arg(short, long)]
    pub output: Option<String>,
    /// Codes are a bit-packed little-endian stream instead of one u16/u32/u64 word per normal.
    #[arg(long)]
    pub packed: bool,
    /// Write the JSON report (prtkit.normal-codes) to this file; `-` is stdout.
    #[arg(long)]
    pub report: Option<String>,
    /// Print the JSON report (or the --table rows as a JSON array) on stdout.
    #[arg(long)]
    pub json: bool,
    /// Write the decoded normals here, in the input's format (EXR/OBJ/PLY/raw).
    #[arg(long)]
    pub decoded: Option<PathBuf>,
    /// EXR values are in [0, 1] (n = 2c - 1) instead of [-1, 1]; applies to reading and writing.
    #[arg(long)]
    pub unorm: bool,
    /// Zero-length, NaN or infinite normals: `error` (exit 2 naming the first) or `replace`
    /// (encode +Z and count them in the report).
    #[arg(long, default_value = "error", value_parser = parse_policy)]
    pub on_invalid: InvalidPolicy,
    /// Decode INPUT (codes) to normals written to --output (format by its extension).
    #[arg(long, conflicts_with_all = ["table", "emit_decoder", "decoded", "report"])]
    pub decode: bool,
    /// With --decode: take scheme, bits and stream layout from this prtkit.normal-codes report
    /// (the --report of the encode run) instead of --scheme/--bits/--packed.
    #[arg(long, requires = "decode")]
    pub header: Option<PathBuf>,
    /// Image size for --decode to .exr.
    #[arg(long, value_parser = super::common::parse_size)]
    pub size: Option<(usize, usize)>,
    /// Print a shader decode function for --scheme/--bits: glsl, hlsl or wgsl.
    #[arg(long, value_parser = parse_language, conflicts_with_all = ["table", "decode"])]
    pub emit_decoder: Option<Language>,
    /// Reproduce Meyer et al. 2010, Table 1 at --bits: random + adversarial directions.
    #[arg(long)]
    pub table: bool,
    /// Random directions for --table.
    #[arg(long, default_value_t = 10_000_000)]
    pub samples: u64,
    /// Seed of the random directions for --table.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Histogram bins in the report (over [0, max(bound, max error)]).
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub bins: u32,
    #[command(flatten)]
    pub run: Execution,
}

fn parse_scheme(s: &str) -> Result<Scheme, String> {
    s.parse()
}
fn parse_language(s: &str) -> Result<Language, String> {
    s.parse()
}
fn parse_policy(s: &str) -> Result<InvalidPolicy, String> {
    match s {
        "error" => Ok(InvalidPolicy::Error),
        "replace" => Ok(InvalidPolicy::Replace),
        _ => Err(format!("expected error or replace, got {s:?}")),
    }
}

/// The body of a `prtkit.normal-codes` report (`docs/formats/normal-codes.md`).
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
    pub stream: String,
    /// Bytes per word (`words` only).
    pub word_bytes: Option<usize>,
    /// Digits of one code, lowest first.
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

/// Runs `encode-normals`.
pub fn run(args: Args) -> Result<Outcome> {
    init_threads(args.run.threads)?;
    let codec = Codec::new(args.scheme, args.bits.unwrap_or(32))?;
    if let Some(lang) = args.emit_decoder {
        Output::Stdout.write(shader::decoder(&codec, lang).as_bytes())?;
        return Ok(Outcome::Success);
    }
    if args.table {
        return run_table(&args);
    }
    let input = args.input.as_deref().context("missing INPUT (or use --table / --emit-decoder)")?;
    if args.decode {
        if let Some(path) = &args.header {
            let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            let doc = crate::io::document::parse_document::<EncodeReport>(&text, "prtkit.normal-codes", 1)
                .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            let codec = Codec::new(doc.body.scheme, doc.body.bits)?;
            let packed = doc.body.layout.stream == "packed";
            return run_decode(&args, &codec, input, packed);
        }
        return run_decode(&args, &codec, input, args.packed);
    }
    run_encode(&args, &codec, input)
}

fn codes_bytes(codes: &[u64], bits: u32, packed: bool) -> Vec<u8> {
    if packed {
        pack::to_packed(codes, bits)
    } else {
        pack::to_words(codes, bits)
    }
}

fn run_encode(args: &Args, codec: &Codec, input: &Path) -> Result<Outcome> {
    let output = args.output.as_deref().map(Output::parse);
    let report = args.report.as_deref().map(Output::parse);
    let decoded_out = args.decoded.as_ref().map(|p| Output::File(p.clone()));
    for out in output.iter().chain(&report).chain(&decoded_out) {
        out.check_writable()?;
    }
    let stdout_users = [output.as_ref(), report.as_ref()].iter().filter(|o| matches!(o, Some(Output::Stdout))).count()
        + usize::from(args.json);
    if stdout_users > 1 {
        bail!("only one of --output -, --report - and --json can use stdout");
    }
    let source = NormalSource::read(input, args.unorm)?;
    if source.normals.is_empty() {
        bail!("{}: no normals to encode", input.display());
    }
    let (dirs, replaced) = prepare(&source.normals, args.on_invalid).map_err(|e| match e {
        NormalsError::Invalid { index, .. } => {
            anyhow::anyhow!(
                "{}: {} ({}); use --on-invalid replace to encode such normals as +Z",
                input.display(),
                e,
                source.locate(index)
            )
        }
        other => other.into(),
    })?;
    let mut codes = vec![0u64; dirs.len()];
    codec.encode_all(&dirs, &mut codes);
    let mut decoded = vec![[0.0f64; 3]; dirs.len()];
    codec.decode_all(&codes, &mut decoded);
    let errors = metrics::errors(&dirs, &decoded);
    let stats: ErrorStats = metrics::stats(&errors);
    let bound = codec.bound();
    let histogram = metrics::histogram(&errors, bound.max(stats.max), args.bins as usize);

    if let Some(out) = &output {
        out.write(&codes_bytes(&codes, codec.bits(), args.packed))
            .with_context(|| format!("writing {}", out.display()))?;
    }
    if let Some(path) = &args.decoded {
        // The same f32 decoder as --decode, so both give identical files.
        let mut f32s = vec![[0f32; 3]; codes.len()];
        codec.decode_all_f32(&codes, &mut f32s);
        let bytes = source.write_back(path, &f32s)?;
        crate::io::write_atomic(path, &bytes)?;
    }
    let body = EncodeReport {
        input: input.display().to_string(),
        input_format: format!("{:?}", SourceFormat::from_path(input)).to_lowercase(),
        scheme: codec.scheme(),
        bits: codec.bits(),
        count: dirs.len() as u64,
        layout: CodeLayout {
            stream: if args.packed { "packed" } else { "words" }.to_string(),
            word_bytes: (!args.packed).then(|| pack::word_bytes(codec.bits())),
            digits: codec.digits(),
        },
        codes: output.as_ref().map(Output::display),
        decoded: args.decoded.as_ref().map(|p| p.display().to_string()),
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
    let doc = Document::new(
        "prtkit.normal-codes",
        1,
        Provenance::current("encode-normals", vec![input.display().to_string()]),
        body,
    );
    let json = doc.to_json();
    if let Some(out) = &report {
        out.write(json.as_bytes())?;
    }
    if args.json {
        Output::Stdout.write(json.as_bytes())?;
    }
    eprintln!(
        "encode-normals: {} normals, {} at {} bits: max {:.3e} rad, mean {:.3e}, rms {:.3e} (bound {:.3e}){}",
        dirs.len(),
        codec.scheme(),
        codec.bits(),
        stats.max,
        stats.mean(),
        stats.rms(),
        bound,
        if replaced.is_empty() { String::new() } else { format!(", {} invalid replaced by +Z", replaced.len()) }
    );
    Ok(Outcome::Success)
}

fn run_decode(args: &Args, codec: &Codec, input: &Path, packed: bool) -> Result<Outcome> {
    let out_path = args.output.as_deref().context("--decode needs --output (normals; format by extension)")?;
    let output = Output::parse(out_path);
    output.check_writable()?;
    let bytes = crate::io::read_bytes(input)?;
    let codes = if packed {
        pack::from_packed(&bytes, codec.bits())
    } else {
        pack::from_words(&bytes, codec.bits()).with_context(|| {
            format!(
                "{}: length {} is not a multiple of the {}-byte word of a {}-bit code (use --packed for bit streams)",
                input.display(),
                bytes.len(),
                pack::word_bytes(codec.bits()),
                codec.bits()
            )
        })?
    };
    if codes.is_empty() {
        bail!("{}: no codes", input.display());
    }
    let mut normals = vec![[0f32; 3]; codes.len()];
    codec.decode_all_f32(&codes, &mut normals);
    let target = match &output {
        Output::File(p) => p.clone(),
        Output::Stdout => PathBuf::from("stdout.raw"),
    };
    let data = sources::write_normals(&target, &normals, args.size, args.unorm)?;
    output.write(&data)?;
    eprintln!(
        "encode-normals: decoded {} {} codes of {} bits to {}",
        codes.len(),
        codec.scheme(),
        codec.bits(),
        output.display()
    );
    Ok(Outcome::Success)
}

/// Paper's Table 1, row 3 (48 bits), for the markdown table.
fn paper_48(scheme: &str) -> Option<f64> {
    Some(match scheme {
        "onv-range" => 1.69e-7,
        "onv-domain" => 2.53e-7,
        "cm" => 2.38e-7,
        "sc" => 3.74e-7,
        "spp" => 2.92e-7,
        "pp" => 4.88e-4,
        _ => return None,
    })
}

fn run_table(args: &Args) -> Result<Outcome> {
    let bar = Bar::new(args.run.quiet);
    let bits = args.bits.unwrap_or(48);
    let rows = table::table(TableConfig { bits, samples: args.samples, seed: args.seed }, &bar)?;
    if args.json {
        Output::Stdout.write(crate::io::document::to_json_pretty(&rows).as_bytes())?;
    } else {
        Output::Stdout.write(markdown(&rows, bits, args.seed).as_bytes())?;
    }
    Ok(Outcome::Success)
}

fn markdown(rows: &[Row], bits: u32, seed: u64) -> String {
    let paper_col = bits == 48;
    let mut s = format!(
        "### {} bits ({} random directions, seed {}, plus adversarial directions)\n\n",
        bits,
        rows.first().map_or(0, |r| r.samples),
        seed
    );
    s += "| scheme | bits | split | ε | closed-form Δmax | measured max | max / bound | random only / bound | mean | rms |";
    s += if paper_col { " paper Δmax(48) |\n" } else { "\n" };
    s += "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |";
    s += if paper_col { " --- |\n" } else { "\n" };
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {:.4e} | {:.4e} | {:.4e} | {:.6} | {:.4} | {:.4e} | {:.4e} |",
            r.scheme,
            r.bits,
            r.split,
            r.spacing,
            r.bound,
            r.max_error,
            r.max_over_bound,
            r.random_max_error / r.bound,
            r.mean_error,
            r.rms_error
        );
        if paper_col {
            let p = paper_48(&r.scheme).or((r.scheme == "fpnv" && r.bits == 48).then_some(4.60e-4));
            s += &match p {
                Some(p) => format!(" {p:.2e} |"),
                None => " |".to_string(),
            };
        }
        s += "\n";
    }
    for r in rows.iter().filter(|r| r.scheme == "fpnv") {
        s += &format!(
            "\nFPNV {} ({} bits): eq. 3 bound {:.4e}; adversarial direction vectors reach {:.4e}; random unit vectors {:.4e}.",
            r.split, r.bits, r.bound, r.adversarial_max_error, r.unit_vector_max_error.unwrap_or(0.0)
        );
        if let (Some(eq), Some(need)) = (r.equivalent_bits, r.onv_range_bits_needed) {
            s +=
                &format!(" Eq. 4: a uniform discretization needs {eq} bits; ONV_range's closed form needs {need} bits");
            if let Some(m) = &r.onv_range_measured {
                let parts: Vec<String> = m
                    .iter()
                    .map(|(b, e)| format!("{b} bits: {e:.4e} ({})", if *e <= r.bound { "≤ FPNV" } else { "> FPNV" }))
                    .collect();
                s += &format!("; measured ONV_range max: {}", parts.join(", "));
            }
            s += ".";
        }
        s += "\n";
    }
    s += "\n";
    s
}
