//! `encode-normals`: flags → the typed configs of `normals::{encode, decode, table}` and
//! `normals::shader`, one library call, outputs written.

use super::common::{Context, Outcome, Stage};
use super::options::Execution;
use super::outputs::{check_outputs, Holds, Outputs};
use crate::io::{document::to_json_pretty, read_bytes, Output};
use crate::normals::sources::{write_normals, NormalSource, WriteError};
use crate::normals::{decode, encode, pack::Stream, report, shader, table, Codec, NormalsError};
mod args;

use anyhow::{anyhow, bail, Context as _, Result};
pub use args::*;
use std::path::PathBuf;

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
        check_outputs(outputs.iter().flatten().map(|o| (o, Holds::Text)))?;
        if a.decode {
            let config = match &a.header {
                Some(path) => decode::Config::from_report(&report::read(path)?.body),
                None => decode::Config { scheme: a.scheme, bits, stream },
            };
            let [output, ..] = outputs;
            return Ok(Mode::Decode(config, input, output.context("--decode needs --output (normals)")?));
        }
        if outputs.iter().filter(|o| o.as_ref() == Some(&Output::Stdout)).count() + usize::from(a.json) > 1 {
            bail!("only one of --output -, --report - and --json can use standard output");
        }
        let name = |i: usize| outputs[i].as_ref().map(Output::display);
        let (scheme, on_invalid, histogram_bins) = (a.scheme, a.on_invalid, a.bins as usize);
        let files = encode::Files::new(&input, name(0), name(2));
        Ok(Mode::Encode(
            encode::Config {
                scheme,
                bits,
                stream,
                on_invalid,
                histogram_bins,
                files,
                args: std::env::args().collect(),
            },
            input,
            outputs,
        ))
    }
}

/// A write error in the words of `--size`, which sets the image's size; the others as they are.
fn flagged(error: WriteError) -> anyhow::Error {
    match error {
        WriteError::NoSize { path } => {
            anyhow!("{}: invalid OpenEXR file: writing an EXR needs --size WxH", path.display())
        }
        WriteError::Size { path, width, height, normals } => anyhow!(
            "{}: invalid OpenEXR file: --size {width}x{height} holds {} normals, the codes hold {normals}",
            path.display(),
            width * height
        ),
        error => error.into(),
    }
}

impl Stage for Args {
    const NAME: &'static str = "encode-normals";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        let (args, bar, mut out_set) = (&self, ctx.progress(), Outputs::new());
        let summary = match Mode::try_from(args)? {
            Mode::EmitDecoder(codec, lang) => {
                out_set.bytes(&Output::Stdout, shader::decoder(&codec, lang).into()).map(|_| None)?
            }
            Mode::Table(config) => {
                let rows = table::run(&config, bar)?;
                let text = if args.json { to_json_pretty(&rows) } else { table::markdown(&rows, &config) };
                out_set.bytes(&Output::Stdout, text.into_bytes()).map(|_| None)?
            }
            Mode::Decode(config, input, output) => {
                let named = |e| anyhow!("{}: {e}", input.display());
                let codes = read_bytes(&input, "normal codes", crate::limits::max_file_bytes(), |_| Ok(()))?;
                let normals = decode::run(&config, &codes, bar).map_err(named)?;
                let target = if let Output::File(p) = &output { p.clone() } else { PathBuf::from("stdout.raw") };
                out_set.bytes(&output, write_normals(&target, &normals, args.size, args.unorm).map_err(flagged)?)?;
                Some(format!("decoded {} codes to {}", normals.len(), output.display()))
            }
            Mode::Encode(config, input, [codes, report, decoded]) => {
                let source = NormalSource::read(&input, args.unorm)?;
                let out = encode::run(&config, &source.normals, bar).map_err(|e| match e {
                    NormalsError::Invalid { index, .. } => {
                        anyhow!("{}: {e} ({}); use --on-invalid replace", input.display(), source.locate(index))
                    }
                    e => anyhow!("{}: {e}", input.display()),
                })?;
                let (json, stdout) = (out.report.to_json(), args.json.then_some(Output::Stdout));
                for (target, bytes) in [(codes, &out.stream[..]), (report, json.as_bytes()), (stdout, json.as_bytes())]
                {
                    target.map(|t| out_set.bytes(&t, bytes.to_vec())).transpose()?;
                }
                if let Some(Output::File(path)) = &decoded {
                    out_set.bytes(&Output::File(path.clone()), source.write_back(path, &out.decoded)?)?;
                }
                Some(out.report.body.summary())
            }
        };
        out_set.commit()?;
        if let Some(summary) = summary {
            ctx.note(summary);
        }
        Ok(Outcome::Success)
    }
}
