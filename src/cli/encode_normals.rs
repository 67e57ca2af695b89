//! `encode-normals`: flags → the typed configs of `normals::{encode, decode, table}` and
//! `normals::shader`, one library call, outputs written.

use super::common::{init_threads, parse_size, Bar, Execution, Outcome};
use crate::io::{document::to_json_pretty, read_bytes, write_atomic, Output};
use crate::normals::sources::{write_normals, NormalSource};
use crate::normals::{decode, encode, pack::Stream, report, shader, table, Codec, InvalidPolicy, NormalsError, Scheme};
use anyhow::{anyhow, bail, Context, Result};
use clap::Parser;
use std::path::PathBuf;

/// Encode normal vectors at a bit budget and measure the exact angular error.
///
/// Modes: encode INPUT (default), `--decode CODES`, `--emit-decoder LANG`, `--table`. INPUT by
/// extension: .exr, .obj (vn), .ply (nx ny nz), anything else raw little-endian f32 xyz.
#[derive(Debug, Parser)]
#[command(name = "encode-normals", version)]
pub struct Args {
    /// Input normals (encode) or codes (--decode).
    pub input: Option<PathBuf>,
    /// Parameterization: onv-range, onv-domain, sc, pp, spp, cm.
    #[arg(long, default_value = "onv-range", value_parser = |s: &str| s.parse::<Scheme>())]
    pub scheme: Scheme,
    /// Bits per normal, 8..=64 [default: 32; with --table: 48, the paper's Table 1].
    #[arg(long, value_parser = clap::value_parser!(u32).range(8..=64))]
    pub bits: Option<u32>,
    #[arg(short, long, help = "Codes output (encode) or normals output (--decode); `-` is stdout.")]
    pub output: Option<String>,
    #[arg(long, help = "Codes are a bit-packed little-endian stream instead of one u16/u32/u64 word per normal.")]
    pub packed: bool,
    #[arg(long, help = "Write the JSON report (prtkit.normal-codes) to this file; `-` is stdout.")]
    pub report: Option<String>,
    #[arg(long, help = "Print the JSON report (or the --table rows as a JSON array) on stdout.")]
    pub json: bool,
    #[arg(long, help = "Write the decoded normals here, in the input's format (EXR/OBJ/PLY/raw).")]
    pub decoded: Option<PathBuf>,
    #[arg(long, help = "EXR values are in [0, 1] (n = 2c - 1) instead of [-1, 1]; applies to reading and writing.")]
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
    #[arg(long, value_parser = parse_size, help = "Image size for --decode to .exr.")]
    pub size: Option<(usize, usize)>,
    /// Print a shader decode function for --scheme/--bits: glsl, hlsl or wgsl.
    #[arg(long, value_parser = |s: &str| s.parse::<shader::Language>(), conflicts_with_all = ["table", "decode"])]
    pub emit_decoder: Option<shader::Language>,
    #[arg(long, help = "Reproduce Meyer et al. 2010, Table 1 at --bits: random + adversarial directions.")]
    pub table: bool,
    #[arg(long, default_value_t = 10_000_000, help = "Random directions for --table.")]
    pub samples: u64,
    #[arg(long, default_value_t = 1, help = "Seed of the random directions for --table.")]
    pub seed: u64,
    /// Histogram bins in the report (over [0, max(bound, max error)]).
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub bins: u32,
    #[command(flatten)]
    pub run: Execution,
}

/// One run of the stage, as the library takes it.
enum Mode {
    EmitDecoder(Codec, shader::Language),
    Table(table::TableConfig),
    Decode(decode::Config, PathBuf, Output),
    /// Outputs: codes, report, decoded normals.
    Encode(encode::Config, PathBuf, [Option<Output>; 3]),
}

impl TryFrom<&Args> for Mode {
    type Error = anyhow::Error;
    fn try_from(a: &Args) -> Result<Mode> {
        let bits = a.bits.unwrap_or(if a.table { 48 } else { 32 });
        let stream = if a.packed { Stream::Packed } else { Stream::Words };
        if let Some(lang) = a.emit_decoder {
            return Ok(Mode::EmitDecoder(Codec::new(a.scheme, bits)?, lang));
        } else if a.table {
            return Ok(Mode::Table(table::TableConfig { bits, samples: a.samples, seed: a.seed }));
        }
        let input = a.input.clone().context("missing INPUT (or use --table / --emit-decoder)")?;
        let output = a.output.as_deref().map(Output::parse);
        let outputs = [output, a.report.as_deref().map(Output::parse), a.decoded.clone().map(Output::File)];
        outputs.iter().flatten().try_for_each(Output::check_writable)?;
        if a.decode {
            let config = match &a.header {
                Some(path) => decode::Config::from_report(&report::read(path)?.body),
                None => decode::Config { scheme: a.scheme, bits, stream },
            };
            let [output, ..] = outputs;
            return Ok(Mode::Decode(config, input, output.context("--decode needs --output (normals)")?));
        }
        if outputs.iter().filter(|o| o.as_ref() == Some(&Output::Stdout)).count() + usize::from(a.json) > 1 {
            bail!("only one of --output -, --report - and --json can use stdout");
        }
        let name = |i: usize| outputs[i].as_ref().map(Output::display);
        let (scheme, on_invalid, histogram_bins) = (a.scheme, a.on_invalid, a.bins as usize);
        let files = encode::Files::new(&input, name(0), name(2));
        Ok(Mode::Encode(encode::Config { scheme, bits, stream, on_invalid, histogram_bins, files }, input, outputs))
    }
}

/// Runs `encode-normals`.
pub fn run(args: Args) -> Result<Outcome> {
    init_threads(args.run.threads)?;
    let bar = Bar::new(args.run.quiet);
    let summary = match Mode::try_from(&args)? {
        Mode::EmitDecoder(codec, lang) => {
            Output::Stdout.write(shader::decoder(&codec, lang).as_bytes()).map(|_| None)?
        }
        Mode::Table(config) => {
            let rows = table::run(&config, &bar)?;
            let text = if args.json { to_json_pretty(&rows) } else { table::markdown(&rows, &config) };
            Output::Stdout.write(text.as_bytes()).map(|_| None)?
        }
        Mode::Decode(config, input, output) => {
            let named = |e| anyhow!("{}: {e}", input.display());
            let normals = decode::run(&config, &read_bytes(&input)?, &bar).map_err(named)?;
            let target = if let Output::File(p) = &output { p.clone() } else { PathBuf::from("stdout.raw") };
            output.write(&write_normals(&target, &normals, args.size, args.unorm)?)?;
            Some(format!("decoded {} codes to {}", normals.len(), output.display()))
        }
        Mode::Encode(config, input, [codes, report, decoded]) => {
            let source = NormalSource::read(&input, args.unorm)?;
            let out = encode::run(&config, &source.normals, &bar).map_err(|e| match e {
                NormalsError::Invalid { index, .. } => {
                    anyhow!("{}: {e} ({}); use --on-invalid replace", input.display(), source.locate(index))
                }
                e => anyhow!("{}: {e}", input.display()),
            })?;
            let (json, stdout) = (out.report.to_json(), args.json.then_some(Output::Stdout));
            for (target, bytes) in [(codes, &out.stream[..]), (report, json.as_bytes()), (stdout, json.as_bytes())] {
                target.map(|t| t.write(bytes)).transpose()?;
            }
            if let Some(Output::File(path)) = &decoded {
                write_atomic(path, &source.write_back(path, &out.decoded)?)?;
            }
            Some(out.report.body.summary())
        }
    };
    if let Some(summary) = summary.filter(|_| !args.run.quiet) {
        eprintln!("encode-normals: {summary}");
    }
    Ok(Outcome::Success)
}
