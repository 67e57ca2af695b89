//! The flags of `sh-project` (clap declarations only; their help text is the user's reference).

use crate::cli::options::{parse_output, parse_size, EnvArgs, Execution, Exposure};
use crate::io::Output;
use crate::sh::window::Window;
use clap::Parser;

/// Project an environment map onto real spherical harmonics.
///
/// Writes a `prtkit.sh` JSON document (coefficients indexed by l(l+1)+m, per-band energy) and,
/// optionally, the order-F reconstruction and the irradiance map (the map convolved with the
/// clamped cosine) as lat-long images.
#[derive(Debug, Parser)]
#[command(name = "sh-project", version)]
pub struct Args {
    /// The environment map read and how (shared by every stage that reads one).
    #[command(flatten)]
    pub input: EnvArgs,

    /// SH order F (bands 0..=F, (F+1)² coefficients). Default 2 unless --epsilon is given.
    #[arg(short = 'F', long, conflicts_with = "epsilon")]
    pub order: Option<usize>,

    /// Choose the smallest order capturing 1 - EPSILON of the energy of the map with its compact
    /// bright sources clipped (searched up to 256). Unclipped, a sun holds most of an HDR map's
    /// energy in every band and ε = 0.01 asks for orders in the hundreds (docs/sh-project.md).
    #[arg(short = 'e', long)]
    pub epsilon: Option<f64>,

    /// Window applied to the bands of --reconstruct and --irradiance images (the coefficients
    /// written stay raw): none, hann, lanczos, sigma, or nonneg. Every window but none is
    /// followed by the gentlest heat window that makes every texel non-negative (nonneg is that
    /// alone). Default: lanczos for --reconstruct, which damps the ripples a step such as the
    /// horizon leaves (nonneg alone removes negatives, not ripples), and nonneg for
    /// --irradiance, which does not ring (docs/sh-project.md).
    #[arg(long, value_enum)]
    pub window: Option<Window>,

    /// Output JSON document (`-` for stdout).
    #[arg(short, long, default_value = "-", value_parser = parse_output)]
    pub output: Output,

    /// Write the order-F reconstruction as a lat-long image (.exr, .pfm or .png; `-`: EXR on
    /// stdout; repeatable).
    #[arg(long, value_name = "FILE", value_parser = parse_output)]
    pub reconstruct: Vec<Output>,

    /// Write the irradiance map E(n) = ∫ L(ω) max(n·ω, 0) dω, from the order-F coefficients
    /// convolved with the clamped cosine (Â_l), as a lat-long image (repeatable).
    #[arg(long, value_name = "FILE", value_parser = parse_output)]
    pub irradiance: Vec<Output>,

    /// Size WxH of the lat-long images. Default: the input's size for a lat-long input, else
    /// 2S x S with S ≈ √(texels/2) (at least 2F+2 wide).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(usize, usize)>,

    /// The exposure of PNG previews.
    #[command(flatten)]
    pub exposure: Exposure,

    /// Print a JSON summary (order, ε achieved, band energy, timings) on stdout.
    #[arg(long)]
    pub json: bool,

    /// Threads, quiet, progress.
    #[command(flatten)]
    pub run: Execution,
}
