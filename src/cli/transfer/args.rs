//! The flags of `transfer` (clap declarations only; their help text is the user's reference).

use crate::cli::options::{parse_output, Execution};
use crate::io::Output;
use crate::transfer::albedo::Albedo;
use crate::transfer::quantize::Quantization;
use crate::transfer::stage::Mode;
use clap::Parser;
use std::path::PathBuf;

/// Bake a mesh's precomputed radiance transfer: diffuse (Sloan, Kautz & Snyder 2002) or glossy
/// through the in-out factorization (Mahajan, Tseng & Ramamoorthi 2008).
///
/// Reads an OBJ, PLY or glTF mesh (every object in it; they shadow each other) and writes, per vertex, the
/// transfer vector T_i = (albedo/π) ∫ V(x,ω) max(n·ω,0) Y_i(ω) dω, so that a renderer relights it
/// under any SH lighting L as B = Σ_i T_i L_i: a `.glb` with the transfer as `_PRT_k` vertex
/// attributes, a `prtkit.transfer` manifest and, optionally, the GLSL of the dot product. With
/// --factors, a K × n² matrix per vertex for a glossy, view-dependent BRDF instead:
/// B(x,ω_o) = Σ_k h_k(ω_o) (T_k · L).
#[derive(Debug, Parser)]
#[command(name = "transfer", version)]
pub struct Args {
    /// The mesh (.obj; .ply: ASCII or binary; .gltf or .glb: the scene's meshes placed by their
    /// nodes, in the file's axes). Normals are read from it when every vertex has one, else
    /// computed (area-weighted face normals).
    #[arg(value_name = "MESH")]
    pub mesh: PathBuf,

    /// The `.glb` to write: the mesh with the transfer as vertex attributes.
    #[arg(long, value_name = "FILE", value_parser = parse_output, required_unless_present = "job")]
    pub glb: Option<Output>,

    /// The manifest (`prtkit.transfer` JSON; `-` for stdout).
    #[arg(short, long, default_value = "-", value_parser = parse_output)]
    pub output: Output,

    /// Write the run-time GLSL snippet (the dot product with the lighting's SH, and SH rotation
    /// of the lighting) to FILE.
    #[arg(long, value_name = "FILE", value_parser = parse_output)]
    pub glsl: Option<Output>,

    /// Write the same run-time snippet in HLSL to FILE.
    #[arg(long, value_name = "FILE", value_parser = parse_output)]
    pub hlsl: Option<Output>,

    /// Write the same run-time snippet in WGSL to FILE.
    #[arg(long, value_name = "FILE", value_parser = parse_output)]
    pub wgsl: Option<Output>,

    /// SH order n: bands 0..n-1, n² coefficients per vertex (1 to 8).
    #[arg(short = 'n', long, default_value_t = 3)]
    pub order: usize,

    /// Instead of -n: the fewest bands (at most 8) holding this fraction of the transfer
    /// kernel's energy — the clamped cosine's, or with --factors the kept terms' factors' (0.99:
    /// 3 bands for diffuse transfer); the manifest says what it chose and why.
    #[arg(long, value_name = "F", conflicts_with = "order")]
    pub sh_energy: Option<f64>,

    /// unshadowed (exact quadrature, no rays), shadowed (visibility by ray casting) or
    /// interreflected (shadowed plus --bounces bounces of light off the mesh itself).
    #[arg(long, value_enum, default_value_t = Mode::Shadowed)]
    pub mode: Mode,

    /// Interreflection bounces B (interreflected mode only; 1 to 16, default 2): the transfer is
    /// the shadowed one plus B bounces gathered over the same rays.
    #[arg(long, value_name = "B")]
    pub bounces: Option<usize>,

    /// Rays cast per vertex (shadowed, interreflected): cosine-weighted over the hemisphere about its normal,
    /// stratified in cells of equal projected solid angle.
    #[arg(long, default_value_t = 1024)]
    pub rays: usize,

    /// Seed of the directions' jitter (the same set at every vertex).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,

    /// Albedo baked into diffuse transfer: a number (grey: one transfer vector per vertex), R,G,B
    /// (a linear colour: one vector per colour channel, so interreflections bleed colour), or
    /// `mesh` (each vertex's base colour from the file: glTF base colour factor × texture ×
    /// COLOR_0, a PLY's red green blue). For a glossy bake (--factors) with --mode
    /// interreflected, the grey albedo of the surfaces the light bounces off.
    #[arg(long, default_value = "1", value_parser = Albedo::parse, value_name = "A|R,G,B|mesh")]
    pub albedo: Albedo,

    /// Shadow rays leave from x + offset·n, offset given as a fraction of the mesh's bounding-box
    /// diagonal (stated in the manifest with its absolute value).
    #[arg(long, default_value_t = 1e-4)]
    pub offset: f64,

    /// Glossy, view-dependent transfer: the `prtkit.factor` document `factor-brdf --factors
    /// FILE.exr` wrote (the BRDF's in-out factorization, read back as `render --factors` reads
    /// it). Per vertex a K × n² matrix T with B(x,ω_o) = Σ_k h_k(ω_o) (T_k · L) (Mahajan et al.
    /// 2008, eq. 4); unshadowed, shadowed (one ray per cell of the factors' grid) or interreflected
    #[arg(long, value_name = "FACTOR.json")]
    pub factors: Option<PathBuf>,

    /// With --factors: terms K to keep (at most those the factor file holds). Default: the
    /// fewest holding --energy of the BRDF matrix's energy
    #[arg(short = 'K', long, value_name = "K")]
    pub terms: Option<usize>,

    /// With --factors and no -K: the energy fraction K must reach (the factor document's
    /// cumulative energy; `count-terms` predicts the same figure)
    #[arg(long, value_name = "F")]
    pub energy: Option<f64>,

    /// With --factors: samples of the SH basis per grid cell along each axis (1 to 8; as
    /// `render --cell-samples`)
    #[arg(long, value_name = "S")]
    pub cell_samples: Option<usize>,

    /// Compress the transfer by clustered PCA (Sloan et al. 2003) into C clusters (with --pca):
    /// the `.glb` stores each vertex's cluster and P weights, and each cluster's mean and P
    /// directions; the manifest reports the reconstruction error
    #[arg(long, value_name = "C", requires = "pca")]
    pub clusters: Option<usize>,

    /// With --clusters: principal directions P per cluster (1 to 64, at most the values per vertex)
    #[arg(long, value_name = "P", requires = "clusters")]
    pub pca: Option<usize>,

    /// Store the per-vertex values quantized: i16 (normalized SHORT, glTF's 16-bit form: it has
    /// no half float) or i8 (normalized BYTE), value = code / 32767 (or 127) × a scale per value
    /// index over the mesh, or per cluster with --clusters; the manifest reports the error and
    /// its bound
    #[arg(long, value_enum, value_name = "KIND", default_value_t = Quantization::None)]
    pub quantize: Quantization,

    /// Also bake the transfer per texel of the mesh's UV set (OBJ vt, glTF TEXCOORD_1 else
    /// TEXCOORD_0, PLY s t or u v) into a W×H grid, written as
    /// one multi-layer EXR (layers T0… per coefficient and coverage); unshadowed, shadowed or
    /// interreflected, with the same integrator as the vertices. Example: --lightmap 256x256 floor.exr
    #[arg(long, num_args = 2, value_names = ["WxH", "FILE.exr"])]
    pub lightmap: Option<Vec<String>>,

    /// Like --lightmap, but per texel of a generated atlas (charts of faces within 60° of a
    /// normal, projected, packed at one texel density with a 2-texel gutter), ignoring the
    /// mesh's own UVs; vertices are split along the charts' seams and the .glb carries the
    /// atlas as TEXCOORD_0. Not with --job/--join (the atlas splits the vertices the parts
    /// number). Example: --texels 512x512 knot.exr
    #[arg(long, num_args = 2, value_names = ["WxH", "FILE.exr"], conflicts_with_all = ["lightmap", "join"])]
    pub texels: Option<Vec<String>>,

    /// Bake only job I of N (1 ≤ I ≤ N): the per-vertex transfer of the I-th of N equal vertex
    /// ranges, against the whole scene, written to FILE.part for --join. Not for
    /// interreflected bakes. Example: --job 3/8 bowl-3.part
    #[arg(long, num_args = 2, value_names = ["I/N", "FILE.part"],
          conflicts_with_all = ["join", "glb", "glsl", "hlsl", "wgsl", "clusters", "quantize", "lightmap", "texels", "json"])]
    pub job: Option<Vec<String>>,

    /// Join the parts of a bake split by --job (every part, in any order; the other options as
    /// the jobs had them) and write what one run writes, byte for byte.
    #[arg(long, num_args = 1.., value_name = "FILE.part")]
    pub join: Option<Vec<PathBuf>>,

    /// Print a JSON summary (vertices, rays, seconds, rays per second) on stdout.
    #[arg(long)]
    pub json: bool,

    /// Threads, quiet, progress.
    #[command(flatten)]
    pub run: Execution,
}
