//! The flags of `encode-normals` (clap declarations only; their help text is the user's reference).

use crate::cli::options::{parse_size, Execution};
use crate::normals::{shader, InvalidPolicy, Scheme};
use clap::Parser;
use std::path::PathBuf;

/// Encode normal vectors at a bit budget and measure the exact angular error.
///
/// Modes: encode INPUT (default), `--decode CODES`, `--emit-decoder LANG`, `--table`. INPUT by
/// extension: .exr, .obj (vn), .ply (nx ny nz), anything else raw little-endian f32 xyz.
#[derive(Debug, Parser)]
#[command(name = "encode-normals", version)]
pub struct Args {
    /// Input normals (encode) or codes (--decode); `-` reads stdin (raw f32 xyz triples to encode).
    pub input: Option<PathBuf>,
    /// Parameterization: onv-range, onv-domain, sc, pp, spp, cm.
    #[arg(long, default_value = "onv-range", value_parser = |s: &str| s.parse::<Scheme>())]
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
    /// Zero-length, NaN or infinite normals: `error` (exit 2 naming the first) or `replace` (+Z).
    #[arg(long, default_value = "error", value_parser = |s: &str| s.parse::<InvalidPolicy>())]
    pub on_invalid: InvalidPolicy,
    /// Decode INPUT (codes) to normals written to --output (format by its extension).
    #[arg(long, conflicts_with_all = ["table", "emit_decoder", "decoded", "report"])]
    pub decode: bool,
    /// With --decode: scheme, bits and stream layout from this report of the encode run.
    #[arg(long, requires = "decode")]
    pub header: Option<PathBuf>,
    /// Image size for --decode to .exr.
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(usize, usize)>,
    /// Print a shader decode function for --scheme/--bits: glsl, hlsl or wgsl.
    #[arg(long, value_parser = |s: &str| s.parse::<shader::Language>(), conflicts_with_all = ["table", "decode"])]
    pub emit_decoder: Option<shader::Language>,
    /// Reproduce Meyer et al. 2010, Table 1 at --bits: random + adversarial directions.
    #[arg(long)]
    pub table: bool,
    // At most 10^9: the default 10^7 take ~12 s on 2 cores, so 10^9 about 20 minutes.
    /// Random directions for --table (at most 10^9).
    #[arg(long,
        default_value_t = 10_000_000,
        value_parser = clap::value_parser!(u64).range(1..=1_000_000_000))]
    pub samples: u64,
    /// Seed of the random directions for --table.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Histogram bins in the report (over [0, max(bound, max error)]).
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub bins: u32,
    /// Threads, quiet, progress.
    #[command(flatten)]
    pub run: Execution,
}
