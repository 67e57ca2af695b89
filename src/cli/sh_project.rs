//! `sh-project`: project an environment map onto spherical harmonics (Ramamoorthi & Hanrahan
//! 2002, §6.1, App. C step 1), choosing the order from a tolerance (§5.1) if asked.

use super::common::{parse_size, Execution, Outcome};
use super::envinput::EnvInput;
use crate::envmap::{EnvMap, Layout};
use crate::io::document::{to_json_pretty, Document, Provenance};
use crate::io::{self, Output};
use crate::sh::document::{OrderSelection, ShBody, SourceMap, FORMAT, VERSION};
use crate::sh::project::{project_choosing_order, OrderChoice};
use crate::sh::{convolve, synth, ShCoeffs};
use anyhow::{bail, Context, Result};
use clap::Parser;
use std::path::PathBuf;

/// Highest order `--epsilon` searches.
const MAX_EPSILON_ORDER: usize = 256;
/// Highest order `--order` accepts at all.
const MAX_ORDER: usize = 2000;

/// Project an environment map onto real spherical harmonics.
///
/// Writes a `prtkit.sh` JSON document (coefficients indexed by l(l+1)+m, per-band energy) and,
/// optionally, the order-F reconstruction and the irradiance map (the map convolved with the
/// clamped cosine) as lat-long images.
#[derive(Debug, Parser)]
#[command(name = "sh-project", version, about, long_about)]
pub struct Args {
    #[command(flatten)]
    pub input: EnvInput,

    /// SH order F (bands 0..=F, (F+1)² coefficients). Default 2 unless --epsilon is given.
    #[arg(short = 'F', long, conflicts_with = "epsilon")]
    pub order: Option<usize>,

    /// Choose the smallest order capturing 1 - EPSILON of the map's energy (searched up to 256).
    #[arg(short = 'e', long)]
    pub epsilon: Option<f64>,

    /// Output JSON document (`-` for stdout).
    #[arg(short, long, default_value = "-")]
    pub output: String,

    /// Write the order-F reconstruction as a lat-long image (.exr, .pfm or .png; repeatable).
    #[arg(long, value_name = "FILE")]
    pub reconstruct: Vec<PathBuf>,

    /// Write the irradiance map E(n) = ∫ L(ω) max(n·ω, 0) dω, from the order-F coefficients
    /// convolved with the clamped cosine (Â_l), as a lat-long image (repeatable).
    #[arg(long, value_name = "FILE")]
    pub irradiance: Vec<PathBuf>,

    /// Size WxH of the lat-long images. Default: the input's size for a lat-long input, else
    /// 2S x S with S ≈ √(texels/2) (at least 2F+2 wide).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(usize, usize)>,

    /// Exposure in stops for PNG images.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,

    /// Print a JSON summary (order, ε achieved, band energy, timings) on stdout.
    #[arg(long)]
    pub json: bool,

    #[command(flatten)]
    pub run: Execution,
}

/// Runs `sh-project`.
pub fn run(args: Args) -> Result<Outcome> {
    let bar = args.run.start()?;
    let output = Output::parse(&args.output);
    super::common::check_json_output(&output, args.json)?;
    output.check_writable()?;
    for path in args.reconstruct.iter().chain(&args.irradiance) {
        Output::File(path.clone()).check_writable()?;
    }
    let choice = match (args.order, args.epsilon) {
        (Some(order), _) if order > MAX_ORDER => bail!("order {order} is absurd (at most {MAX_ORDER})"),
        (Some(order), _) => OrderChoice::Order(order),
        (None, Some(epsilon)) => OrderChoice::Epsilon { epsilon, max_search: MAX_EPSILON_ORDER },
        (None, None) => OrderChoice::Order(2),
    };

    let start = std::time::Instant::now();
    let map = args.input.load()?;
    let read_seconds = start.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let projection = project_choosing_order(&map, choice, &bar)
        .with_context(|| format!("{}: cannot project", args.input.path.display()))?;
    let project_seconds = t.elapsed().as_secs_f64();
    let coeffs = &projection.coeffs;

    let img = map.image();
    let body = ShBody {
        order: coeffs.order,
        coefficients: coeffs.rgb.clone(),
        band_energy: coeffs.band_energy(),
        total_energy: projection.total_energy,
        selection: OrderSelection {
            method: if args.epsilon.is_some() { "epsilon" } else { "order" }.to_string(),
            epsilon: args.epsilon,
            epsilon_achieved: projection.epsilon_achieved,
        },
        source: SourceMap {
            path: args.input.path.display().to_string(),
            layout: map.layout().name().to_string(),
            width: img.width,
            height: img.height,
            max_order: map.max_order(),
        },
    };
    let provenance = Provenance::current("sh-project", vec![args.input.path.display().to_string()]);
    let doc = Document::new(FORMAT, VERSION, provenance, body);

    if !args.reconstruct.is_empty() || !args.irradiance.is_empty() {
        let (w, h) = output_size(&map, coeffs.order, args.size);
        if w < 2 * coeffs.order {
            bail!("--size {w}x{h} is too narrow for order {} (needs width >= {})", coeffs.order, 2 * coeffs.order);
        }
        write_latlong(coeffs, w, h, &args.reconstruct, args.exposure)?;
        if !args.irradiance.is_empty() {
            write_latlong(&convolve::irradiance(coeffs), w, h, &args.irradiance, args.exposure)?;
        }
    }
    output.write(doc.to_json().as_bytes()).with_context(|| format!("cannot write {}", output.display()))?;

    if args.json {
        let summary = serde_json::json!({
            "input": args.input.path.display().to_string(),
            "layout": map.layout().name(),
            "order": coeffs.order,
            "coefficients": crate::sh::count(coeffs.order),
            "epsilon_achieved": projection.epsilon_achieved,
            "band_energy": coeffs.band_energy(),
            "total_energy": projection.total_energy,
            "read_seconds": read_seconds,
            "project_seconds": project_seconds,
            "output": output.display(),
        });
        Output::Stdout.write(to_json_pretty(&summary).as_bytes())?;
    }
    Ok(Outcome::Success)
}

fn output_size(map: &EnvMap, order: usize, size: Option<(usize, usize)>) -> (usize, usize) {
    if let Some(s) = size {
        return s;
    }
    if map.layout() == Layout::LatLong {
        let img = map.image();
        if img.width >= 2 * order {
            return (img.width, img.height);
        }
    }
    let s = ((map.texel_count() as f64 / 2.0).sqrt().round() as usize).max(order + 1).max(8);
    (2 * s, s)
}

fn write_latlong(coeffs: &ShCoeffs, w: usize, h: usize, paths: &[PathBuf], exposure: f32) -> Result<()> {
    if paths.is_empty() {
        return Ok(());
    }
    let image = synth::synthesize_latlong(coeffs, w, h)?;
    for path in paths {
        io::image::write_image(path, &image, exposure)?;
    }
    Ok(())
}
