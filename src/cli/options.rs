//! The option vocabulary every stage shares, declared once: the environment-map input (`ENVMAP`
//! or `-`), `--brdf` parsed into the typed model, `-o` as an [`Output`] that understands `-`,
//! image sizes and points, `--exposure`, and the execution options `--threads` (bounded by the
//! machine's cores) and `-q`.

use super::common::Context;
use crate::brdf::Brdf;
use crate::envmap::{EnvMap, EnvMapError, Layout, LoadError, LoadOptions, NegativePolicy, Orientation, PixelFault};
use crate::factor::{Channel, Domain, Method, Sampling};
use crate::io::Output;
use crate::limits::MAX_IMAGE_EDGE;
use anyhow::{Context as _, Result};
use clap::builder::PossibleValue;
use clap::ValueEnum;
use std::path::{Path, PathBuf};

/// The options every stage has for how it runs (flattened into each stage's `Args`).
#[derive(Clone, Debug, Default, clap::Args)]
pub struct Execution {
    /// Worker threads; 0 means all cores, more than the machine's cores are clamped to them.
    /// Results do not depend on it.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub threads: usize,

    /// Say nothing on stderr but errors (no progress bars, notes or summaries).
    #[arg(short, long)]
    pub quiet: bool,
}

impl Execution {
    /// The pool the stage runs in: `--threads` workers, at most the machine's cores.
    pub fn pool(&self, ctx: &Context) -> Result<rayon::ThreadPool> {
        let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
        let threads = match self.threads {
            0 => cores,
            n if n > cores => {
                ctx.note(format!("--threads {n}: using {cores}, the machine's cores"));
                cores
            }
            n => n,
        };
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().context("cannot start the worker threads")
    }
}

/// The environment-map input: a file, a directory of six faces, or `-` for standard input.
#[derive(Clone, Debug, clap::Args)]
pub struct EnvArgs {
    /// Environment map: .exr, .hdr or .pfm; a directory holding six faces px, nx, py, ny, pz, nz
    /// (any of those extensions); or `-` to read one image from standard input (format from its
    /// signature).
    #[arg(value_name = "ENVMAP")]
    pub path: PathBuf,

    /// Layout of the input; detected from the aspect ratio when omitted (2:1 latlong, 1:1
    /// angular, 4:3 cross-horizontal, 3:4 cross-vertical; a directory is faces).
    #[arg(long)]
    pub layout: Option<Layout>,

    /// Negative pixel components: error, clamp (to 0) or keep. NaN and infinities are always an
    /// error.
    #[arg(long, default_value = "error")]
    pub negative: NegativePolicy,

    /// How the map is turned on reading.
    #[command(flatten)]
    pub orient: OrientArgs,
}

/// How an environment map is turned on reading: one declaration for every stage that reads one.
#[derive(Clone, Copy, Debug, Default, clap::Args)]
pub struct OrientArgs {
    /// Mirror the map top to bottom on reading (z → −z: a lat-long map's rows reversed; cube maps
    /// and probes to match), for files stored upside down such as pbrt's grace_latlong.exr, whose
    /// row 0 is the floor. Documents record it (conventions.input_orientation).
    #[arg(long)]
    pub flip_vertical: bool,
}

impl OrientArgs {
    /// The library's orientation.
    pub fn orientation(self) -> Orientation {
        if self.flip_vertical {
            Orientation::FlipVertical
        } else {
            Orientation::AsStored
        }
    }
}

impl EnvArgs {
    /// The library's reading options.
    pub fn options(&self) -> LoadOptions {
        LoadOptions { layout: self.layout, negative: self.negative, orientation: self.orient.orientation() }
    }

    /// The input's name in messages and documents (`<stdin>` for `-`).
    pub fn name(&self) -> String {
        crate::io::read::display_path(&self.path).display().to_string()
    }

    /// Reads the map, saying how many negative components were clamped.
    pub fn load(&self, ctx: &Context) -> Result<EnvMap> {
        let loaded = self.options().load(&self.path).map_err(flagged)?;
        if loaded.clamped > 0 {
            ctx.note(format!("{}: clamped {} negative pixel components to 0", self.name(), loaded.clamped));
        }
        Ok(loaded.map)
    }
}

/// A reading error in the words of `--negative` when that policy refused a pixel, and of
/// `--layout` when the layout cannot be told; the others as they are.
fn flagged(error: LoadError) -> anyhow::Error {
    match error {
        LoadError::BadPixel { path, x, y, channel, value, fault: PixelFault::Negative } => anyhow::anyhow!(
            "{}: pixel ({x}, {y}) channel {channel} is {value}: negative radiance; pass --negative clamp or \
             --negative keep",
            path.display()
        ),
        error @ LoadError::Geometry { error: EnvMapError::Undetectable { .. }, .. } => {
            anyhow::anyhow!("{error}; pass --layout")
        }
        error => error.into(),
    }
}

/// Tone mapping of PNG outputs.
#[derive(Clone, Copy, Debug, Default, clap::Args)]
pub struct Exposure {
    /// Exposure in stops for PNG outputs (× 2^EXPOSURE before the sRGB curve).
    #[arg(long = "exposure", value_name = "STOPS", default_value_t = 0.0, allow_hyphen_values = true)]
    pub stops: f32,
}

/// `-` is standard output, anything else a file.
pub fn parse_output(s: &str) -> Result<Output, String> {
    if s.is_empty() {
        return Err("expected a file name or - for standard output".into());
    }
    Ok(Output::parse(s))
}

/// A BRDF spec parsed (and a MERL file read) once, by clap: `docs/brdf-specs.md`.
pub fn parse_brdf(s: &str) -> Result<Brdf, String> {
    Brdf::parse(s).map_err(|e| e.to_string())
}

/// Parses `WxH` (e.g. `512x256`), an image a stage will make: each edge at most [`MAX_IMAGE_EDGE`],
/// and the image within the ceilings of an image read (`limits::check_image`: 2^28 texels, and
/// as RGB f32 within the memory budget), refused here before any work starts.
pub fn parse_size(s: &str) -> Result<(usize, usize), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("expected WxH, e.g. 512x256, got {s:?}"))?;
    let w: usize = w.trim().parse().map_err(|_| format!("bad width in {s:?}"))?;
    let h: usize = h.trim().parse().map_err(|_| format!("bad height in {s:?}"))?;
    if w == 0 || h == 0 || w > MAX_IMAGE_EDGE || h > MAX_IMAGE_EDGE {
        return Err(format!("size {s:?} must be between 1x1 and {MAX_IMAGE_EDGE}x{MAX_IMAGE_EDGE}"));
    }
    crate::limits::check_image("the image", w as u64, h as u64, crate::limits::RGB_BYTES_PER_TEXEL)
        .map_err(|e| e.to_string())?;
    Ok((w, h))
}

/// Parses `x,y,z` (three finite numbers) for points and directions.
pub fn parse_xyz(s: &str) -> Result<glam::DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected x,y,z, got {s:?}"))?;
    if v.len() != 3 || v.iter().any(|c| !c.is_finite()) {
        return Err(format!("expected three finite numbers x,y,z, got {s:?}"));
    }
    Ok(glam::DVec3::new(v[0], v[1], v[2]))
}

/// A direction `x,y,z`: non-zero, normalized.
pub fn parse_direction(s: &str) -> Result<glam::DVec3, String> {
    let d = parse_xyz(s)?;
    if d.length() < 1e-12 {
        return Err("a direction must be non-zero".into());
    }
    Ok(d.normalize())
}

/// `--json` owns stdout: a document that would also go there must be given a file instead.
pub fn check_json_output(document: &Output, json: bool) -> Result<()> {
    if json && *document == Output::Stdout {
        anyhow::bail!("--json prints the summary on stdout: give the document a file with -o FILE");
    }
    Ok(())
}

impl ValueEnum for Layout {
    fn value_variants<'a>() -> &'a [Self] {
        &Layout::ALL
    }
    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.name()))
    }
}

impl ValueEnum for NegativePolicy {
    fn value_variants<'a>() -> &'a [Self] {
        &[NegativePolicy::Error, NegativePolicy::Clamp, NegativePolicy::Keep]
    }
    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(match self {
            NegativePolicy::Error => PossibleValue::new("error").help("refuse the file, naming the first"),
            NegativePolicy::Clamp => PossibleValue::new("clamp").help("replace by 0 and say how many"),
            NegativePolicy::Keep => PossibleValue::new("keep").help("keep them (signed data)"),
        })
    }
}

/// How the BRDF matrix is sampled and factored: shared by `factor-brdf` and `count-terms`.
#[derive(Clone, Debug, clap::Args)]
pub struct MatrixArgs {
    /// Directions sampled for ω_i and ω_o: the full sphere or the visible hemispheres.
    #[arg(long, value_enum, default_value_t = Domain::Hemisphere)]
    pub domain: Domain,

    /// Grid bins along cos θ and along φ (n² directions per side; the paper uses 40).
    #[arg(long, default_value_t = 40)]
    pub resolution: usize,

    /// Fold max(cos θ_i, 0) into the matrix (off by default, as in the paper; count-terms
    /// makes no closed-form prediction then).
    #[arg(long)]
    pub cosine: bool,

    /// Scalar factored for RGB (measured) data; analytic models are grey.
    #[arg(long, value_enum, default_value_t = Channel::Luminance)]
    pub channel: Channel,

    /// SVD method: fft (isotropic BRDFs, block-circulant in φ), dense, randomized (leading
    /// terms of the dense matrix, for large n), or auto (fft when isotropic, else dense).
    #[arg(long, value_enum, default_value_t = Method::Auto)]
    pub method: Method,

    /// Memory budget of one SVD, e.g. 512M, 4G (binary units).
    #[arg(long, default_value = "4G", value_parser = parse_memory)]
    pub max_memory: u128,
}

impl MatrixArgs {
    /// The sampling these options describe.
    pub fn sampling(&self) -> Sampling {
        Sampling { resolution: self.resolution, domain: self.domain, cosine: self.cosine, channel: self.channel }
    }
}

/// Parses a memory size with an optional K/M/G/T suffix (powers of 1024).
pub fn parse_memory(s: &str) -> Result<u128, String> {
    let t = s.trim().trim_end_matches(['B', 'b']).trim_end_matches('i');
    let (num, mult) = match t.chars().last() {
        Some('K' | 'k') => (&t[..t.len() - 1], 1u128 << 10),
        Some('M' | 'm') => (&t[..t.len() - 1], 1 << 20),
        Some('G' | 'g') => (&t[..t.len() - 1], 1 << 30),
        Some('T' | 't') => (&t[..t.len() - 1], 1 << 40),
        _ => (t, 1),
    };
    let v: f64 = num.trim().parse().map_err(|_| format!("expected a size like 512M or 4G, got {s:?}"))?;
    if !(v.is_finite() && v > 0.0) {
        return Err(format!("memory size must be positive, got {s:?}"));
    }
    Ok((v * mult as f64) as u128)
}

/// Reads the SH coefficients of a `prtkit.sh` document (`-`: standard input).
pub fn read_sh_document(path: &Path) -> Result<crate::sh::ShCoeffs> {
    Ok(crate::sh::document::read(path)?.body.coeffs())
}

/// `auto`, `off` or a luminance threshold.
pub fn parse_bright(s: &str) -> Result<crate::envmap::bright::BrightRule, String> {
    match s {
        "auto" => Ok(crate::envmap::bright::BrightRule::Auto),
        "off" => Ok(crate::envmap::bright::BrightRule::Off),
        v => match v.parse::<f64>() {
            Ok(t) if t.is_finite() && t > 0.0 => Ok(crate::envmap::bright::BrightRule::Threshold(t)),
            _ => Err(format!("expected auto, off or a positive luminance threshold, got {s:?}")),
        },
    }
}
