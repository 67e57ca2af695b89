//! The flags of `ibl` (clap declarations, whose help text is the user's reference).

use crate::cli::options::{EnvArgs, Execution};
use crate::ibl::dfg::DfgVariant;
use crate::ibl::stage::{RoughnessMap, Up};
use crate::io::gpu_format::TexelFormat;
use crate::io::texture::Container;
use crate::limits::MAX_IBL_MEASURED_TEXELS;
use clap::{Parser, ValueEnum};
use std::path::PathBuf;

/// Texel formats of the cubes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum CubeFormat {
    /// Four half floats (alpha 1).
    Rgba16f,
    /// Four single floats (alpha 1).
    Rgba32f,
    /// Packed unsigned 11/11/10-bit floats.
    B10g11r11,
    /// Shared-exponent RGB 9/9/9/5.
    E5b9g9r9,
}

impl CubeFormat {
    /// The library's format.
    pub fn format(self) -> TexelFormat {
        match self {
            CubeFormat::Rgba16f => TexelFormat::Rgba16Float,
            CubeFormat::Rgba32f => TexelFormat::Rgba32Float,
            CubeFormat::B10g11r11 => TexelFormat::B10G11R11Ufloat,
            CubeFormat::E5b9g9r9 => TexelFormat::E5B9G9R9Ufloat,
        }
    }
}

/// Texture file containers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum ContainerArg {
    /// KTX 2.0.
    Ktx2,
    /// DDS with the DX10 header.
    Dds,
}

impl ContainerArg {
    /// The library's container.
    pub fn container(self) -> Container {
        match self {
            ContainerArg::Ktx2 => Container::Ktx2,
            ContainerArg::Dds => Container::Dds,
        }
    }
}

/// The DFG table variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum DfgArg {
    /// (A, B): specular = prefiltered · (F0·A + B) (Karis 2013).
    ScaleBias,
    /// Filament's (B, A + B) with multiple-scattering compensation.
    Multiscatter,
}

impl DfgArg {
    /// The library's variant.
    pub fn variant(self) -> DfgVariant {
        match self {
            DfgArg::ScaleBias => DfgVariant::ScaleBias,
            DfgArg::Multiscatter => DfgVariant::MultiScatter,
        }
    }
}

/// Bake image-based lighting for glTF/PBR engines: a GGX-prefiltered specular cube with a full
/// mip chain, the irradiance cube, order-2 SH irradiance with shader snippets and the split-sum
/// DFG table, with every level's error measured against the angular integral (docs/ibl.md).
#[derive(Debug, Parser)]
#[command(name = "ibl", version)]
pub struct Args {
    /// The environment map read and how (shared by every stage that reads one).
    #[command(flatten)]
    pub input: EnvArgs,

    /// Output directory (created; must not exist or be empty). Receives specular, irradiance
    /// and dfg (.ktx2 or .dds), sh.json, sh.glsl, sh.hlsl, sh.wgsl and the manifest ibl.json.
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,

    /// Face size of the first specular level (a power of two).
    #[arg(long, default_value_t = 256)]
    pub size: usize,

    /// Face size of the last specular level (a power of two, at most --size).
    #[arg(long, default_value_t = 8)]
    pub min_size: usize,

    /// Face size of the irradiance cube (a power of two).
    #[arg(long, default_value_t = 32)]
    pub irradiance_size: usize,

    /// Level → roughness: linear (r_k = k/(levels − 1)) or filament (its lod = r(2 − r)).
    #[arg(long, value_enum, default_value_t = RoughnessMap::Linear)]
    pub roughness_map: RoughnessMap,

    /// Texel format of the cubes (the DFG table is rg16f, or rg32f with rgba32f).
    #[arg(long, value_enum, default_value_t = CubeFormat::Rgba16f)]
    pub format: CubeFormat,

    /// File container.
    #[arg(long, value_enum, default_value_t = ContainerArg::Ktx2)]
    pub container: ContainerArg,

    /// Up axis of the output frame: y (glTF: prtkit's +Z becomes +Y) or z (prtkit's frame).
    #[arg(long, value_enum, default_value_t = Up::Y)]
    pub up: Up,

    /// Turn the environment about the up axis by DEG degrees (counter-clockwise seen from above).
    #[arg(long, value_name = "DEG", default_value_t = 0.0, allow_hyphen_values = true)]
    pub rotate: f64,

    /// Mirror the environment (left and right swapped, as seen from inside).
    #[arg(long)]
    pub mirror: bool,

    /// Clamp input radiance to at most MAX before filtering (tames suns for low-precision formats).
    #[arg(long, value_name = "MAX")]
    pub clamp: Option<f64>,

    /// DFG table variant.
    #[arg(long, value_enum, default_value_t = DfgArg::ScaleBias)]
    pub dfg: DfgArg,

    /// Texels per level measured against the angular integral for the manifest (0: skip; at most
    /// 4096: each is a cone sum over the input map).
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u64).range(0..=MAX_IBL_MEASURED_TEXELS as u64))]
    pub samples: u64,

    /// Threads, quiet, progress.
    #[command(flatten)]
    pub run: Execution,
}
