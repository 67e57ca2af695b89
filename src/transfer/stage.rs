//! The `transfer` stage as one library call: a mesh in, its per-vertex diffuse transfer
//! (Sloan, Kautz & Snyder 2002) out as a `.glb` with `_PRT_k` vertex attributes, a
//! `prtkit.transfer` manifest and a GLSL snippet (`docs/transfer.md`,
//! `docs/formats/transfer.md`).
//!
//! **Self-intersection.** Shadow rays leave from x + δ·n, with δ = `offset` × the length of the
//! mesh's bounding-box diagonal (default 10⁻⁴): far above the single-precision rounding of the
//! ray casts (2⁻²⁴ ≈ 6·10⁻⁸ of the coordinates), far below any feature a mesh is modelled with.
//! The manifest states both numbers.

use super::albedo::{colourize, Albedo, Reflectance};
use super::atlas::AtlasInfo;
use super::cpca::Cpca;
use super::diffuse::{unshadowed_exact, PointTransfer, Shadowed};
use super::directions::Stratified;
use super::glossy::{Glossy, Visibility, FRAME};
use super::interreflect::{Hits, Storage, Tracer};
use super::jobs::{Job, Joined, Part, Recipe, Transfer};
use super::lightmap::{self, Lightmap, LightmapConfig, LightmapInfo, LightmapUvs};
use super::quantize::{Quantization, Quantized};
use super::shaders::{colour_snippet, dequantize_snippet, glossy_snippet, snippet, Language};
use super::visibility::{triangle_area, Occluders};
use crate::factor::Factorization;
use crate::io::glb::{self, Attribute, Blob, GlbMesh, Values};
use crate::io::{Document, Provenance};
use crate::limits::LimitError;
use crate::limits::{
    MAX_CELL_SAMPLES, MAX_CPCA_CLUSTERS, MAX_CPCA_DIRECTIONS, MAX_CPCA_ROUND_WORK, MAX_TRANSFER_BOUNCES,
    MAX_TRANSFER_ORDER, MAX_TRANSFER_RAYS,
};
use crate::mesh::Mesh;
use crate::progress::Progress;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::ops::Range;
use std::time::Instant;

/// Document kind of the manifest.
pub const FORMAT: &str = "prtkit.transfer";
/// Its schema version.
pub const VERSION: u32 = 1;
/// Basis samples per factor cell along each axis by default (as `render --cell-samples`).
pub const DEFAULT_CELL_SAMPLES: usize = 2;
/// Vertices per unit of progress and per parallel work item.
const CHUNK: usize = 64;

/// Which light transport the transfer holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// V ≡ 1: every direction above the horizon reaches the lighting (Sloan et al. 2002, eq. 7),
    /// computed by an exact quadrature.
    Unshadowed,
    /// With visibility V(x, ω) by ray casting (Sloan et al. 2002, eq. 8).
    Shadowed,
    /// Shadowed plus `bounces` interreflections off the mesh itself (Sloan et al. 2002, eq. 9
    /// and §5), gathered over the same rays.
    Interreflected,
}

/// What `transfer` computes.
#[derive(Clone, Debug, PartialEq)]
pub struct Config {
    /// SH order n: bands 0..n−1, n² coefficients (1 ≤ n ≤ [`MAX_TRANSFER_ORDER`]).
    pub order: usize,
    /// Why n is what it is, when an energy fraction chose it ([`super::order::for_energy`]).
    pub order_reason: Option<String>,
    /// Unshadowed or shadowed.
    pub mode: Mode,
    /// Ray directions per vertex (shadowed and interreflected modes).
    pub rays: usize,
    /// Interreflection bounces B (interreflected mode; 1 ≤ B ≤ [`MAX_TRANSFER_BOUNCES`]).
    pub bounces: usize,
    /// Seed of the directions' jitter.
    pub seed: u64,
    /// The albedo baked into diffuse transfer: grey (one vector per vertex) or coloured (three).
    pub albedo: Albedo,
    /// The ray origin offset along the normal, as a fraction of the bounding-box diagonal.
    pub offset: f64,
    /// The mesh's name, for messages and the manifest.
    pub source: String,
    /// The `.glb`'s file name, for the manifest.
    pub glb_name: String,
    /// The command line, for provenance.
    pub args: Vec<String>,
    /// Glossy, view-dependent transfer through a factorization (`--factors`), else diffuse.
    pub glossy: Option<GlossyConfig>,
    /// Clustered PCA of the transfer (`--clusters C --pca P`), else stored as it is.
    pub compression: Option<Compression>,
    /// A per-texel lightmap beside the per-vertex bake (`--lightmap WxH FILE.exr`).
    pub lightmap: Option<LightmapConfig>,
    /// How the `.glb` stores the per-vertex values (`--quantize`).
    pub quantization: Quantization,
}

/// How many clusters and directions CPCA keeps (Sloan et al. 2003).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Compression {
    /// Clusters C (at most [`MAX_CPCA_CLUSTERS`]; capped at the vertex count).
    pub clusters: usize,
    /// Principal directions per cluster P (at most [`MAX_CPCA_DIRECTIONS`] and the values per vertex).
    pub components: usize,
}

/// What a glossy bake is made from: `factor-brdf`'s factorization, read back as `render
/// --factors` reads it, and how many of its terms to keep.
#[derive(Clone, Debug, PartialEq)]
pub struct GlossyConfig {
    /// The factorization (its leading terms at least).
    pub factorization: Factorization,
    /// Whether max(cos θ_i, 0) is folded into it.
    pub cosine: bool,
    /// Terms K kept.
    pub terms: usize,
    /// Why K is what it is, in words (given, or the energy fraction it reaches).
    pub terms_reason: String,
    /// Samples of the basis per cell along each axis.
    pub cell_samples: usize,
    /// The factor document's name, as given.
    pub factors: String,
    /// The factored BRDF's canonical spec.
    pub brdf: String,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            order: 3,
            order_reason: None,
            mode: Mode::Shadowed,
            rays: 1024,
            bounces: 2,
            seed: 0,
            albedo: Albedo::Grey(1.0),
            offset: 1e-4,
            source: String::new(),
            glb_name: String::new(),
            args: Vec::new(),
            glossy: None,
            compression: None,
            lightmap: None,
            quantization: Quantization::None,
        }
    }
}

/// The manifest's body (`docs/formats/transfer.md`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct TransferBody {
    /// SH order n (bands), as in Sloan et al. 2002.
    pub order: usize,
    /// Why n is what it is, when an energy fraction chose it (absent: given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub order_reason: Option<String>,
    /// Values per vertex: n² (diffuse, grey albedo), 3·n² (diffuse, coloured), K·n² (glossy).
    pub coefficients: usize,
    /// Transfer vectors per vertex, one per colour channel: 3 with a coloured albedo (absent: 1).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub channels: usize,
    /// `unshadowed`, `shadowed` or `interreflected`.
    pub mode: Mode,
    /// The interreflection bounces (interreflected mode, else absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interreflection: Option<Interreflection>,
    /// The albedo baked in: ρ, [r, g, b], or the mesh's colours (their source and range).
    pub albedo: serde_json::Value,
    /// How the integral was computed.
    pub integration: Integration,
    /// The ray origin offset.
    pub offset: Offset,
    /// The mesh.
    pub mesh: MeshInfo,
    /// The `.glb` and its attributes.
    pub glb: GlbInfo,
    /// In which axes the SH basis is evaluated.
    pub frame: String,
    /// The integration error of the direct part, measured (diffuse shadowed and interreflected
    /// modes).
    pub error: Option<ErrorFigures>,
    /// The glossy transfer's factorization (absent for diffuse transfer).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glossy: Option<GlossyInfo>,
    /// The clustered PCA the `.glb` stores the transfer in (absent: stored as it is).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub compression: Option<CompressionInfo>,
    /// The per-texel lightmap written beside the `.glb` (absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lightmap: Option<LightmapInfo>,
    /// How the `.glb`'s per-vertex values are quantized (absent: float).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quantization: Option<QuantizationInfo>,
}

/// How the per-vertex values are quantized and what it costs (`docs/formats/transfer.md`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct QuantizationInfo {
    /// `i16` or `i8`.
    pub method: Quantization,
    /// The accessors' component type in words.
    pub component_type: String,
    /// The largest code q: value = max(code / q, −1) × scale.
    pub code_max: i32,
    /// The attributes quantized (`_PRT_k`, or `_PRT_W_k` when compressed).
    pub attributes: String,
    /// `value` (one scale per value index over the mesh) or `cluster` (one per CPCA cluster).
    pub scale_per: String,
    /// The `.glb` blob holding the scales.
    pub scales_blob: String,
    /// The scales, as the blob holds them.
    pub scales: Vec<f32>,
    /// The largest |v − v̂| over the stored values in units of their half code step
    /// scale / (2q): at most 1.
    pub max_error_over_half_step: f64,
    /// ‖T̂ − T_float‖ / ‖T‖ over every vertex and value: T̂ the transfer from the dequantized
    /// values, T_float from the unquantized ones (the CPCA reconstruction when compressed).
    pub relative_rms: f64,
    /// The closed-form bound on `relative_rms` from half a code step per value.
    pub relative_rms_bound: f64,
    /// How a reader dequantizes, in words.
    pub dequantize: String,
}

/// What CPCA kept and what it costs in accuracy (`docs/formats/transfer.md`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CompressionInfo {
    /// `clustered PCA` (Sloan, Hall, Hart & Snyder 2003).
    pub method: String,
    /// Clusters C.
    pub clusters: usize,
    /// Principal directions per cluster P.
    pub components: usize,
    /// Fit-and-assign rounds run.
    pub iterations: usize,
    /// ‖T − T̃‖ / ‖T‖ over every vertex and value.
    pub relative_rms: f64,
    /// The largest per-vertex ‖T(x) − T̃(x)‖ over the RMS of ‖T(x)‖.
    pub max_vertex: f64,
    /// Values per vertex before (n² or K·n²).
    pub values_per_vertex: usize,
    /// Values per vertex stored: the cluster and P weights.
    pub stored_per_vertex: usize,
    /// Values stored per cluster: the mean and P directions, (P + 1)·values_per_vertex.
    pub stored_per_cluster: usize,
    /// In words.
    pub description: String,
}

/// How a glossy transfer was made and how it is relit (`docs/formats/transfer.md`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct GlossyInfo {
    /// Terms K: the transfer is a K × n² matrix per vertex.
    pub terms: usize,
    /// Why K, in words.
    pub terms_reason: String,
    /// Energy fraction of the BRDF matrix the K terms hold (Σ_{k<K} σ_k² / Σ σ²).
    pub energy: f64,
    /// ‖M − M_K‖_F / ‖M‖_F = √(1 − energy): the factorization's own relative error (Eckart–Young).
    pub relative_frobenius_error: f64,
    /// σ_0 … σ_{K−1}, folded into the transfer (h_k is relit unscaled).
    pub singular_values: Vec<f64>,
    /// The factored BRDF.
    pub brdf: String,
    /// The `prtkit.factor` document whose factor file holds g_k and h_k.
    pub factors: String,
    /// Its grid: `sphere` or `hemisphere`.
    pub domain: crate::factor::Domain,
    /// Its bins n along cos θ and φ.
    pub resolution: usize,
    /// Whether the factors hold max(cos θ_i, 0) (else the transfer applies it).
    pub cosine: bool,
    /// Samples of the basis per cell along each axis.
    pub cell_samples: usize,
    /// How B is evaluated at run time, in words.
    pub relighting: String,
    /// The normal's frame F the transfer and h_k are in, [`FRAME`] (bakes that do not name it
    /// used R_z(φ_n)·R_y(θ_n), which `render` does not relight).
    pub frame: String,
}

/// How T was integrated.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Integration {
    /// `exact quadrature` or `stratified rays`.
    pub method: String,
    /// Ray directions per vertex (0 for the exact quadrature).
    pub rays: usize,
    /// Seed of the directions.
    pub seed: u64,
    /// In words.
    pub description: String,
}

/// How the interreflections were gathered (Sloan et al. 2002, §5).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Interreflection {
    /// Bounces B: the transfer is T^0 + T^1 + … + T^B.
    pub bounces: usize,
    /// The rule for rays that reach the back of a surface, in words.
    pub back_faces: String,
    /// `recorded` (each ray's hit traced once and kept) or `re-traced` (every bounce casts the
    /// rays again; when recording could pass the memory budget).
    pub hits: String,
    /// Share of all rays that hit the front of a surface (and carry a bounce).
    pub front_hit_fraction: f64,
    /// Share of all rays that hit the back of a surface (blocked, and nothing reflected).
    pub back_hit_fraction: f64,
    /// Mean over vertices of each pass's response to a uniform white sky of radiance 1
    /// (√(4π) T_0), direct first then bounce 1..B: how fast the bounces fall off (for a glossy
    /// bake, the diffuse passes its cells gather).
    pub white_sky_response: Vec<f64>,
    /// For a glossy bake, how its cells gather the diffuse passes, in words.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glossy_gather: Option<String>,
}

/// The shadow rays' origin offset.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Offset {
    /// Fraction of the bounding-box diagonal.
    pub relative: f64,
    /// In the mesh's units.
    pub absolute: f64,
    /// Along what.
    pub along: String,
}

/// What was read.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MeshInfo {
    /// The input file.
    pub source: String,
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Triangles of zero area (kept in the `.glb`, left out of the BVH).
    pub zero_area_triangles: usize,
    /// `file` or `computed` (area-weighted face normals).
    pub normals: String,
    /// Length of the bounding-box diagonal.
    pub extent: f64,
}

/// The `.glb` written beside the manifest.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct GlbInfo {
    /// Its file name.
    pub file: String,
    /// The transfer attributes, in order: `_PRT_k` holds coefficients 4k..4k+3.
    pub attributes: Vec<String>,
    /// The packing in words.
    pub packing: String,
}

/// The integration error of the direction set, measured on the unshadowed integrand (for which
/// the exact value is known) with the same rays: ‖T_rays − T_exact‖ / ‖T_exact‖ per vertex.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ErrorFigures {
    /// What is measured, in words.
    pub measured: String,
    /// RMS over every vertex and coefficient, relative to the RMS of the exact transfer.
    pub relative_rms: f64,
    /// 99th percentile of the per-vertex relative error.
    pub p99_vertex: f64,
    /// Largest per-vertex relative error.
    pub max_vertex: f64,
    /// Mean over vertices of the share of rays that escaped.
    pub visible_fraction: f64,
}

/// What `transfer` produces.
#[derive(Clone, Debug)]
pub struct Output {
    /// The manifest.
    pub document: Document<TransferBody>,
    /// The `.glb` bytes.
    pub glb: Vec<u8>,
    /// The run-time snippets (`shaders`): GLSL, HLSL, WGSL.
    pub glsl: String,
    /// HLSL.
    pub hlsl: String,
    /// WGSL.
    pub wgsl: String,
    /// The per-vertex transfer in the `.glb`'s layout: n², 3·n² (coloured) or K·n² (glossy) values
    /// per vertex.
    pub transfer: Vec<f64>,
    /// The `--json` summary.
    pub summary: Summary,
    /// The per-texel lightmap (`--lightmap`).
    pub lightmap: Option<Lightmap>,
}

/// The machine-readable summary (`transfer --json`): what the manifest says, plus timings.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    /// Vertices baked.
    pub vertices: usize,
    /// Rays per vertex (0 unshadowed).
    pub rays: usize,
    /// Interreflection bounces (0 unless interreflected).
    pub bounces: usize,
    /// Seconds of the whole computation (BVH build, visibility, bounces).
    pub seconds: f64,
    /// Vertices × rays per second of the visibility pass with the BVH build (0 unshadowed).
    pub rays_per_second: f64,
    /// Seconds of the bounces alone (0 unless interreflected).
    pub bounce_seconds: f64,
}

/// Errors of the stage. They speak of the bake, not of the flags that asked for it: the CLI
/// (`cli/transfer.rs`) words the ones a flag sets with that flag's name.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The SH order is outside 1..=[`MAX_TRANSFER_ORDER`].
    #[error("SH order {0} is outside 1..={MAX_TRANSFER_ORDER}")]
    Order(usize),
    /// The ray count is outside 1..=[`MAX_TRANSFER_RAYS`].
    #[error("{0} rays per vertex is outside 1..={MAX_TRANSFER_RAYS}")]
    Rays(usize),
    /// The bounce count is outside 1..=[`MAX_TRANSFER_BOUNCES`].
    #[error("{0} interreflection bounces is outside 1..={MAX_TRANSFER_BOUNCES}")]
    Bounces(usize),
    /// The albedo (or one of its components) is not a finite number ≥ 0.
    #[error("albedo {0} is not a finite number ≥ 0")]
    Albedo(f64),
    /// The albedo is the mesh's, and the mesh holds no colours.
    #[error("{0}: the mesh holds no base colours to take the albedo from")]
    NoColours(String),
    /// A coloured albedo for a glossy bake.
    #[error(
        "a coloured albedo is for diffuse transfer: a glossy bake's colour is its BRDF's, and the surfaces it \
         gathers from reflect a grey albedo"
    )]
    GlossyColour,
    /// The ray offset is outside [0, 0.1) of the bounding-box diagonal.
    #[error("ray offset {0} is outside [0, 0.1) of the bounding-box diagonal")]
    Offset(f64),
    /// The mesh has no triangle of non-zero area.
    #[error("{0}: every triangle has zero area: nothing to bake")]
    ZeroArea(String),
    /// The mesh is larger than the ceilings.
    #[error("{source_name}: {error}")]
    Limit {
        /// The mesh.
        source_name: String,
        /// Which ceiling.
        error: LimitError,
    },
    /// The glossy bake keeps more terms than the factor file holds, or none.
    #[error("{factors}: {terms} terms is outside 1..={stored}, the terms the factor file holds")]
    Terms {
        /// The factor document.
        factors: String,
        /// Terms K asked for.
        terms: usize,
        /// Terms the factor file holds.
        stored: usize,
    },
    /// The basis samples per factor cell are outside 1..=[`MAX_CELL_SAMPLES`].
    #[error("{0} basis samples per cell is outside 1..={MAX_CELL_SAMPLES}")]
    CellSamples(usize),
    /// The clusters or directions of a compression are out of range.
    #[error(
        "{clusters} clusters of {components} directions: clusters must be in 1..={MAX_CPCA_CLUSTERS}, directions in \
         1..={most_components} (the values per vertex, at most {MAX_CPCA_DIRECTIONS})"
    )]
    Compression {
        /// Clusters C asked for.
        clusters: usize,
        /// Directions P asked for.
        components: usize,
        /// The most directions this bake allows.
        most_components: usize,
    },
    /// A round of clustered PCA would take more than [`MAX_CPCA_ROUND_WORK`].
    #[error(
        "{clusters} clusters of {components} directions on {vertices} vertices of {per_vertex} values: a round of \
         clustered PCA would take {work:.2e} multiply-adds, above the ceiling of {MAX_CPCA_ROUND_WORK:.0e} \
         (minutes per round); use fewer clusters or directions"
    )]
    CompressionWork {
        /// Clusters C asked for.
        clusters: usize,
        /// Directions P asked for.
        components: usize,
        /// Vertices of the mesh.
        vertices: usize,
        /// Values per vertex.
        per_vertex: usize,
        /// Multiply-adds of one round.
        work: u128,
    },
    /// Clustered PCA's SVD failed.
    #[error("clustered PCA failed")]
    Cpca(#[source] crate::factor::svd::FactorError),
    /// The mesh has no UV set for a lightmap.
    #[error(
        "{0}: no lightmap UVs (TEXCOORD_1/TEXCOORD_0, vt, or a PLY's s t / u v): a lightmap needs a UV set \
         on every vertex"
    )]
    NoUvs(String),
    /// The lightmap's grid has no texels.
    #[error("{source_name}: a {width}x{height} lightmap has no texels")]
    NoTexels {
        /// The mesh.
        source_name: String,
        /// W.
        width: usize,
        /// H.
        height: usize,
    },
    /// A lightmap of a bake the lightmap does not build.
    #[error("{source_name}: a lightmap bakes diffuse unshadowed or shadowed transfer; {bake} lightmaps are not built")]
    LightmapOf {
        /// The mesh.
        source_name: String,
        /// `interreflected`, `glossy` or `compressed`.
        bake: &'static str,
    },
    /// The mesh gets no lightmap atlas.
    #[error("{source_name}: no lightmap atlas: {error}")]
    Atlas {
        /// The mesh.
        source_name: String,
        /// Why.
        #[source]
        error: super::atlas::AtlasError,
    },
    /// A bake split into jobs with a generated atlas.
    #[error(
        "a lightmap atlas is not baked as jobs: the atlas splits vertices along its seams, and the parts number the \
         mesh's own vertices"
    )]
    JobAtlas,
    /// The lightmap's EXR cannot be encoded.
    #[error("cannot encode the lightmap's EXR: {0}")]
    LightmapEncoding(String),
    /// The `.glb` cannot be encoded.
    #[error("cannot encode the .glb: {0}")]
    GlbEncoding(String),
    /// A part file cannot be read.
    #[error(transparent)]
    Io(#[from] crate::io::IoError),
    /// The energy fraction that chooses the SH order is outside (0, 1].
    #[error("the SH energy fraction {0} must be in (0, 1]")]
    ShEnergy(f64),
    /// A bake split into jobs is interreflected.
    #[error("interreflected transfer is not split into jobs: each bounce gathers the transfer of every vertex")]
    JobInterreflected,
    /// A part file that cannot be read or does not belong to the join.
    #[error("{file}: {reason}")]
    Part {
        /// The part file.
        file: String,
        /// Why.
        reason: String,
    },
    /// The parts leave vertices out.
    #[error("{source_name}: no part holds vertices {missing:?}")]
    PartsMissing {
        /// The mesh.
        source_name: String,
        /// The first range no part holds.
        missing: Range<usize>,
    },
}

/// The bake a [`Config`] asks for, decided once, after every check.
enum Bake {
    /// Diffuse, V ≡ 1, by the exact quadrature (Sloan et al. 2002, eq. 7).
    Unshadowed,
    /// Diffuse with visibility by stratified rays (Sloan et al. 2002, eq. 8).
    Shadowed,
    /// Diffuse shadowed plus B bounces off the mesh itself (Sloan et al. 2002, eq. 9 and §5).
    Interreflected {
        /// Bounces B.
        bounces: usize,
    },
    /// Glossy through the factorization (Mahajan et al. 2008, eq. 4): a K × n² matrix per vertex,
    /// one ray per cell of the factors' grid when shadowed or interreflected.
    Glossy {
        /// The integrator over the factors' grid.
        integrator: Glossy,
        /// Unshadowed, shadowed, or interreflected with the configuration's bounces.
        mode: Mode,
    },
}

/// What one run does: the bake, then, if asked, its clustered PCA and its lightmap.
struct Plan<'a> {
    /// Which transfer is integrated.
    bake: Bake,
    /// Values per vertex as stored: n², 3·n² with a coloured albedo, or K·n² for a glossy bake.
    per_vertex: usize,
    /// Values per vertex as integrated (and as parts hold them): n² or K·n², the albedo grey.
    integrated: usize,
    /// Each vertex's (ρ_r, ρ_g, ρ_b), for a coloured albedo.
    colours: Option<Vec<[f64; 3]>>,
    /// Clustered PCA of the transfer (Sloan et al. 2003).
    compression: Option<Compression>,
    /// The per-texel bake of the same diffuse transfer.
    lightmap: Option<&'a LightmapConfig>,
    /// The lightmap's generated atlas, when it has one.
    atlas: Option<AtlasInfo>,
    /// Triangles of zero area (kept in the `.glb`, left out of the BVH).
    zero_area: usize,
    /// The ray origin offset in the mesh's units.
    offset: f64,
}

impl<'a> Plan<'a> {
    /// Checks `config` against `mesh` and decides the bake: every refusal comes here, before
    /// anything is baked.
    fn new(config: &'a Config, mesh: &Mesh) -> Result<Plan<'a>, Error> {
        let n = config.order;
        if !(1..=MAX_TRANSFER_ORDER).contains(&n) {
            return Err(Error::Order(n));
        }
        if !(1..=MAX_TRANSFER_RAYS).contains(&config.rays) {
            return Err(Error::Rays(config.rays));
        }
        if config.mode == Mode::Interreflected && !(1..=MAX_TRANSFER_BOUNCES).contains(&config.bounces) {
            return Err(Error::Bounces(config.bounces));
        }
        if let Some(a) = config.albedo.invalid() {
            return Err(Error::Albedo(a));
        }
        if config.albedo.channels() > 1 && config.glossy.is_some() {
            return Err(Error::GlossyColour);
        }
        let colours = config.albedo.colours(mesh);
        if config.albedo == Albedo::Mesh && colours.is_none() {
            return Err(Error::NoColours(config.source.clone()));
        }
        if let Some(a) = colours.iter().flatten().flatten().find(|a| !(a.is_finite() && **a >= 0.0)) {
            return Err(Error::Albedo(*a));
        }
        if !(config.offset.is_finite() && (0.0..0.1).contains(&config.offset)) {
            return Err(Error::Offset(config.offset));
        }
        let name = &config.source;
        crate::limits::check_transfer_mesh(name, mesh.positions.len(), mesh.triangles.len())
            .map_err(|error| Error::Limit { source_name: name.clone(), error })?;
        let zero_area = mesh.triangles.iter().filter(|t| triangle_area(&mesh.positions, t) <= 0.0).count();
        if zero_area == mesh.triangles.len() {
            return Err(Error::ZeroArea(name.clone()));
        }
        if let Some(l) = &config.lightmap {
            lightmap::check(l, config, mesh)?;
        }
        let bake = match (&config.glossy, config.mode) {
            (Some(g), mode) => Bake::Glossy { integrator: glossy_integrator(config, g)?, mode },
            (None, Mode::Unshadowed) => Bake::Unshadowed,
            (None, Mode::Shadowed) => Bake::Shadowed,
            (None, Mode::Interreflected) => Bake::Interreflected { bounces: config.bounces },
        };
        let integrated = match &bake {
            Bake::Glossy { integrator, .. } => integrator.values_per_vertex(),
            _ => n * n,
        };
        let per_vertex = config.albedo.channels() * integrated;
        if let Some(c) = &config.compression {
            check_compression(c, mesh.positions.len(), per_vertex)?;
        }
        Ok(Plan {
            bake,
            per_vertex,
            integrated,
            colours,
            compression: config.compression,
            lightmap: config.lightmap.as_ref(),
            atlas: None,
            zero_area,
            offset: config.offset * mesh.extent(),
        })
    }
}

impl Plan<'_> {
    /// Whether the bake gathers light off the mesh itself: each bounce reads every vertex's
    /// transfer, so it runs whole, not as jobs over vertex ranges.
    fn gathers(&self) -> bool {
        matches!(self.bake, Bake::Interreflected { .. } | Bake::Glossy { mode: Mode::Interreflected, .. })
    }
}

/// A bake's transfer and the manifest's account of how it was integrated.
struct Baked {
    /// `per_vertex` values per vertex.
    transfer: Vec<f64>,
    /// How T was integrated.
    integration: Integration,
    /// The direct part's integration error (diffuse shadowed and interreflected).
    error: Option<ErrorFigures>,
    /// The bounces (interreflected).
    interreflection: Option<Interreflection>,
    /// Seconds of the BVH build and the visibility pass.
    trace_seconds: f64,
    /// Seconds of the bounces.
    bounce_seconds: f64,
    /// Every vertex's T^0 + … + T^{B−1}, which an interreflected lightmap's texels gather.
    gathered: Option<Vec<f64>>,
}

/// Runs `transfer` on `mesh`.
pub fn run(config: &Config, mesh: &Mesh, progress: &dyn Progress) -> Result<Output, Error> {
    let atlas = match &config.lightmap {
        Some(l) => lightmap::atlas_mesh(l, config, mesh)?,
        None => None,
    };
    let (mesh, atlas) = match &atlas {
        Some((split, info)) => (split, Some(info.clone())),
        None => (mesh, None),
    };
    let mut plan = Plan::new(config, mesh)?;
    plan.atlas = atlas;
    let start = Instant::now();
    let all = 0..mesh.positions.len();
    let baked = match &plan.bake {
        Bake::Interreflected { bounces } => {
            let occluders = Occluders::new(&mesh.positions, &mesh.triangles);
            interreflected(config, mesh, &occluders, *bounces, plan.offset, plan.colours.as_deref(), progress)
        }
        Bake::Glossy { integrator, mode: Mode::Interreflected } => {
            glossy_interreflected(config, mesh, &plan, integrator, progress)
        }
        _ => {
            let transfer = per_vertex(config, mesh, &plan, all, progress);
            baked(config, mesh, &plan, transfer, start.elapsed().as_secs_f64())
        }
    };
    finish(config, mesh, &plan, baked, start.elapsed().as_secs_f64(), progress)
}

/// A generated atlas splits the mesh's vertices, so parts over the mesh's own vertex ranges
/// cannot be joined into its bake.
fn refuse_atlas_jobs(config: &Config) -> Result<(), Error> {
    match &config.lightmap {
        Some(l) if l.uvs == LightmapUvs::Atlas => Err(Error::JobAtlas),
        _ => Ok(()),
    }
}

/// Runs job `job` of a `transfer` split into jobs ([`super::jobs`]): the per-vertex transfer of its
/// vertex range, as a part for [`run_joined`].
pub fn run_job(config: &Config, mesh: &Mesh, job: Job, progress: &dyn Progress) -> Result<Part, Error> {
    refuse_atlas_jobs(config)?;
    let plan = Plan::new(config, mesh)?;
    if plan.gathers() {
        return Err(Error::JobInterreflected);
    }
    let vertices = job.vertices(mesh.positions.len());
    let transfer = per_vertex(config, mesh, &plan, vertices.clone(), progress);
    Ok(Part::new(Recipe::new(config, mesh), vertices, plan.integrated, transfer))
}

/// Joins the parts of a `transfer` split into jobs (`(file, part)`, in any order) and does what
/// follows the per-vertex integration as [`run`] does: the same outputs, byte for byte.
pub fn run_joined(
    config: &Config,
    mesh: &Mesh,
    parts: impl IntoIterator<Item = Result<(String, Part), Error>>,
    progress: &dyn Progress,
) -> Result<Output, Error> {
    refuse_atlas_jobs(config)?;
    let plan = Plan::new(config, mesh)?;
    if plan.gathers() {
        return Err(Error::JobInterreflected);
    }
    let mut joined = Joined::new(Recipe::new(config, mesh), plan.integrated);
    for part in parts {
        let (file, part) = part?;
        joined.add(part).map_err(|reason| Error::Part { file, reason })?;
    }
    let transfer =
        joined.finish().map_err(|missing| Error::PartsMissing { source_name: config.source.clone(), missing })?;
    let baked = baked(config, mesh, &plan, transfer, 0.0);
    finish(config, mesh, &plan, baked, 0.0, progress)
}

/// The per-vertex transfer of `vertices` for a bake other than interreflected.
fn per_vertex(config: &Config, mesh: &Mesh, plan: &Plan, vertices: Range<usize>, progress: &dyn Progress) -> Transfer {
    match &plan.bake {
        Bake::Unshadowed => Transfer::Values(unshadowed(config, mesh, vertices, progress)),
        Bake::Shadowed => Transfer::Points(shadowed(config, mesh, vertices, plan.offset, progress)),
        Bake::Glossy { integrator, mode: Mode::Unshadowed } => {
            Transfer::Values(glossy(mesh, integrator, &Visibility::None, vertices, progress))
        }
        Bake::Glossy { integrator, mode: Mode::Shadowed } => {
            let occluders = Occluders::new(&mesh.positions, &mesh.triangles);
            let visibility = Visibility::Shadowed { occluders: &occluders, offset: plan.offset };
            Transfer::Values(glossy(mesh, integrator, &visibility, vertices, progress))
        }
        Bake::Interreflected { .. } | Bake::Glossy { mode: Mode::Interreflected, .. } => {
            unreachable!("interreflections gather every vertex: not a per-vertex bake")
        }
    }
}

/// Every vertex's transfer with the manifest's account of it, `seconds` of integration.
fn baked(config: &Config, mesh: &Mesh, plan: &Plan, transfer: Transfer, seconds: f64) -> Baked {
    let (transfer, error) = match transfer {
        Transfer::Values(values) => (values, None),
        Transfer::Points(points) => {
            let error = integration_error(mesh, &points, config.order, config.rays, config.albedo.folded());
            (points.into_iter().flat_map(|p| p.shadowed).collect(), Some(error))
        }
    };
    let transfer = match &plan.colours {
        Some(colours) => colourize(&transfer, plan.integrated, colours),
        None => transfer,
    };
    let integration = match &plan.bake {
        Bake::Unshadowed => Integration {
            method: "exact quadrature".into(),
            rays: 0,
            seed: config.seed,
            description: "8 Gauss-Legendre nodes in n.w times 18 equally spaced azimuths about the normal: exact for \
                          the band-limited integrand, so T_lm = (albedo/pi) A_l Y_lm(n) to rounding"
                .into(),
        },
        Bake::Glossy { integrator, mode } => Integration {
            method: "factor grid cells".into(),
            rays: if *mode == Mode::Unshadowed { 0 } else { integrator.rays() },
            seed: config.seed,
            description: glossy_description(
                config.glossy.as_ref().expect("a glossy bake has a glossy config"),
                config.mode,
                integrator.rays(),
            ),
        },
        _ => stratified_rays(config),
    };
    let trace_seconds = if integration.rays > 0 { seconds } else { 0.0 };
    Baked { transfer, integration, error, interreflection: None, trace_seconds, bounce_seconds: 0.0, gathered: None }
}

/// What follows the per-vertex integration: clustered PCA, the lightmap, quantization, the
/// manifest, the `.glb` and the snippets.
fn finish(
    config: &Config,
    mesh: &Mesh,
    plan: &Plan,
    baked: Baked,
    seconds: f64,
    progress: &dyn Progress,
) -> Result<Output, Error> {
    let cpca = match plan.compression {
        Some(c) => {
            progress.start("clustered PCA", 1);
            let cpca = Cpca::new(&baked.transfer, plan.per_vertex, c.clusters, c.components).map_err(Error::Cpca)?;
            progress.finish();
            Some(cpca)
        }
        None => None,
    };
    let lightmap = match plan.lightmap {
        Some(l) => {
            let mut baked = lightmap::bake(l, config, mesh, baked.gathered.as_deref(), progress)?;
            baked.info.atlas = plan.atlas.clone();
            Some(baked)
        }
        None => None,
    };
    let quantized = quantize(config.quantization, &baked.transfer, plan.per_vertex, cpca.as_ref());
    let mut body = manifest(config, mesh, plan, &baked, cpca.as_ref(), lightmap.as_ref().map(|l| l.info.clone()));
    if lightmap.is_some() {
        body.glb.packing += "; TEXCOORD_0: the lightmap's UVs (texel (x, y) at ((x+0.5)/W, (y+0.5)/H))";
    }
    if let Some(q) = &quantized {
        let info = quantization_info(config.quantization, q, &baked.transfer, plan.per_vertex, cpca.as_ref());
        body.glb.packing +=
            &format!("; quantized: {} hold {} VEC4s, {}", info.attributes, info.component_type, info.dequantize);
        body.quantization = Some(info);
    }
    let h = config
        .glossy
        .as_ref()
        .map(|g| g.factorization.h[..g.terms].iter().flatten().map(|&v| v as f32).collect::<Vec<f32>>());
    let stored = Stored {
        transfer: &baked.transfer,
        per_vertex: plan.per_vertex,
        cpca: cpca.as_ref(),
        quantized: quantized.as_ref(),
    };
    let glb = glb::encode(&glb_mesh(mesh, &stored, &body, h)).map_err(Error::GlbEncoding)?;
    let vertices = mesh.positions.len();
    let summary = Summary {
        vertices,
        rays: baked.integration.rays,
        bounces: if config.mode == Mode::Interreflected { config.bounces } else { 0 },
        seconds,
        rays_per_second: if baked.trace_seconds > 0.0 {
            (vertices * baked.integration.rays) as f64 / baked.trace_seconds
        } else {
            0.0
        },
        bounce_seconds: baked.bounce_seconds,
    };
    let provenance = Provenance::new("transfer", &config.args, vec![config.source.clone()]);
    Ok(Output {
        document: Document::new(FORMAT, VERSION, provenance, body),
        glb,
        glsl: run_time_snippet(config, quantized.as_ref(), Language::Glsl),
        hlsl: run_time_snippet(config, quantized.as_ref(), Language::Hlsl),
        wgsl: run_time_snippet(config, quantized.as_ref(), Language::Wgsl),
        transfer: baked.transfer,
        summary,
        lightmap,
    })
}

/// Diffuse transfer without visibility of `vertices`, by the exact quadrature
/// ([`unshadowed_exact`]).
fn unshadowed(config: &Config, mesh: &Mesh, vertices: Range<usize>, progress: &dyn Progress) -> Vec<f64> {
    let coeffs = config.order * config.order;
    let mut transfer = vec![0.0; vertices.len() * coeffs];
    progress.start("transfer (unshadowed)", vertices.len() as u64);
    transfer.par_chunks_mut(CHUNK * coeffs).enumerate().for_each(|(c, out)| {
        for (k, t) in out.chunks_exact_mut(coeffs).enumerate() {
            unshadowed_exact(mesh.normals[vertices.start + c * CHUNK + k], config.order, config.albedo.folded(), t);
        }
        progress.advance((out.len() / coeffs) as u64);
    });
    progress.finish();
    transfer
}

/// Diffuse transfer with visibility of `vertices`, by stratified rays ([`Shadowed`]) through a
/// BVH of the whole scene.
fn shadowed(
    config: &Config,
    mesh: &Mesh,
    vertices: Range<usize>,
    offset: f64,
    progress: &dyn Progress,
) -> Vec<PointTransfer> {
    let occluders = Occluders::new(&mesh.positions, &mesh.triangles);
    let directions = Stratified::new(config.rays, config.seed);
    let integrator = Shadowed::new(&directions, config.order, &occluders);
    progress.start("visibility", vertices.len() as u64);
    // One work item per chunk of vertices; each vertex's sums run in the directions' fixed order,
    // so the bits do not depend on which thread ran which chunk, nor on the vertices' range.
    let points: Vec<PointTransfer> = (0..vertices.len().div_ceil(CHUNK))
        .into_par_iter()
        .flat_map_iter(|c| {
            let range = vertices.start + c * CHUNK..(vertices.start + (c + 1) * CHUNK).min(vertices.end);
            let done: Vec<PointTransfer> = range
                .map(|v| integrator.integrate(mesh.positions[v], mesh.normals[v], offset, config.albedo.folded()))
                .collect();
            progress.advance(done.len() as u64);
            done
        })
        .collect();
    progress.finish();
    points
}

/// Diffuse shadowed transfer plus `bounces` interreflections gathered over the same rays
/// ([`Tracer`]): T = T^0 + T^1 + … + T^B; with `colours`, per channel, the rays traced once.
fn interreflected(
    config: &Config,
    mesh: &Mesh,
    occluders: &Occluders,
    bounces: usize,
    offset: f64,
    colours: Option<&[[f64; 3]]>,
    progress: &dyn Progress,
) -> Baked {
    let start = Instant::now();
    let (n, vertices) = (config.order, mesh.positions.len());
    let coeffs = n * n;
    let directions = Stratified::new(config.rays, config.seed);
    let tracer = Tracer::new(mesh, occluders, &directions, n, offset);
    let first = tracer.first_pass(config.albedo.folded(), Storage::Auto, progress);
    let trace_seconds = start.elapsed().as_secs_f64();
    let direct: Vec<f64> = first.points.iter().flat_map(|p| p.shadowed.iter().copied()).collect();
    let (mut transfer, reflectance) = match colours {
        Some(c) => (colourize(&direct, coeffs, c), Reflectance::Rgb(c)),
        None => (direct, Reflectance::Grey(config.albedo.folded())),
    };
    let passes = tracer.bounces(&transfer, bounces, reflectance, &first.hits, progress);
    let bounce_seconds = start.elapsed().as_secs_f64() - trace_seconds;
    // T_0 of every vertex and channel: the response to a uniform white sky, averaged.
    let channels = reflectance.channels();
    let white = |t: &[f64]| {
        (4.0 * std::f64::consts::PI).sqrt() * t.iter().step_by(coeffs).sum::<f64>() / (vertices * channels) as f64
    };
    let mut white_sky_response = vec![white(&transfer)];
    // Total = T^0 + Σ_b T^b, added bounce after bounce in a fixed order.
    let mut gathered = None;
    for (b, pass) in passes.iter().enumerate() {
        if b + 1 == bounces && config.lightmap.is_some() {
            gathered = Some(transfer.clone());
        }
        white_sky_response.push(white(pass));
        for (t, b) in transfer.iter_mut().zip(pass) {
            *t += b;
        }
    }
    let interreflection = Interreflection {
        bounces,
        back_faces: "a ray that reaches the back of a surface (the hit triangle's geometric normal, turned to the \
                     side of its vertex normals, points along the ray) is blocked and carries no bounce"
            .into(),
        hits: match first.hits {
            Hits::Recorded(_) => "recorded",
            Hits::Retraced => "re-traced",
        }
        .into(),
        front_hit_fraction: first.front_fraction,
        back_hit_fraction: first.back_fraction,
        white_sky_response,
        glossy_gather: None,
    };
    Baked {
        transfer,
        integration: stratified_rays(config),
        error: Some(integration_error(mesh, &first.points, n, config.rays, config.albedo.folded())),
        interreflection: Some(interreflection),
        trace_seconds,
        bounce_seconds,
        gathered,
    }
}

/// How the diffuse shadowed and interreflected bakes integrate.
fn stratified_rays(config: &Config) -> Integration {
    let rays = config.rays;
    Integration {
        method: "stratified rays".into(),
        rays,
        seed: config.seed,
        description: format!(
            "{rays} rays per vertex over the hemisphere about its normal, cosine-weighted and stratified: one \
             jittered in each of {rays} cells of equal projected solid angle pi/{rays} (bands in sin^2 theta, cells \
             in phi), the same local set turned onto every vertex's normal; T_i = (albedo/N) sum_k V(w_k) Y_i(w_k)"
        ),
    }
}

/// Glossy transfer of `vertices` over the factors' grid ([`Glossy`]), the cells' rays seeing
/// what `visibility` says.
fn glossy(
    mesh: &Mesh,
    integrator: &Glossy,
    visibility: &Visibility,
    vertices: Range<usize>,
    progress: &dyn Progress,
) -> Vec<f64> {
    let per_vertex = integrator.values_per_vertex();
    let mut transfer = vec![0.0; vertices.len() * per_vertex];
    let stage = match visibility {
        Visibility::None => "transfer (unshadowed)",
        Visibility::Shadowed { .. } => "visibility",
        Visibility::Interreflected { .. } => "glossy gather",
    };
    progress.start(stage, vertices.len() as u64);
    // Chunks of vertices side by side; each vertex's sums run in the cells' fixed order.
    transfer.par_chunks_mut(CHUNK * per_vertex).enumerate().for_each(|(c, out)| {
        for (k, t) in out.chunks_exact_mut(per_vertex).enumerate() {
            let v = vertices.start + c * CHUNK + k;
            integrator.integrate(mesh.positions[v], mesh.normals[v], visibility, t);
        }
        progress.advance((out.len() / per_vertex) as u64);
    });
    progress.finish();
    transfer
}

/// The manifest's body of a bake (`docs/formats/transfer.md`).
fn manifest(
    config: &Config,
    mesh: &Mesh,
    plan: &Plan,
    baked: &Baked,
    cpca: Option<&Cpca>,
    lightmap: Option<LightmapInfo>,
) -> TransferBody {
    let n = config.order;
    let glossy = config.glossy.as_ref().map(|g| glossy_info(g, n));
    let attributes: Vec<String> = match cpca {
        None => (0..plan.per_vertex.div_ceil(4)).map(|k| format!("_PRT_{k}")).collect(),
        Some(c) => std::iter::once("_PRT_CLUSTER".to_string())
            .chain((0..c.components.div_ceil(4)).map(|k| format!("_PRT_W_{k}")))
            .collect(),
    };
    TransferBody {
        order: n,
        order_reason: config.order_reason.clone(),
        coefficients: plan.per_vertex,
        channels: config.albedo.channels(),
        mode: config.mode,
        interreflection: baked.interreflection.clone(),
        albedo: config.albedo.describe(plan.colours.as_deref()),
        integration: baked.integration.clone(),
        offset: Offset {
            relative: config.offset,
            absolute: plan.offset,
            along: "the vertex normal: shadow rays leave from x + offset * n".into(),
        },
        mesh: MeshInfo {
            source: config.source.clone(),
            vertices: mesh.positions.len(),
            triangles: mesh.triangles.len(),
            zero_area_triangles: plan.zero_area,
            normals: if mesh.normals_computed { "computed" } else { "file" }.into(),
            extent: mesh.extent(),
        },
        glb: GlbInfo {
            file: config.glb_name.clone(),
            attributes,
            packing: packing(n * n, plan.per_vertex, glossy.as_ref(), cpca),
        },
        frame: "the mesh file's own axes (positions as stored): the SH basis is evaluated with x, y, z as \
                stored, so lighting SH must be expressed in those axes (prtkit's +Z-up documents apply as they are \
                when the mesh's +Z is up; a +Y-up glTF asset needs the lighting rotated)"
            .into(),
        error: baked.error.clone(),
        glossy,
        compression: cpca.map(|cpca| compression_info(cpca, &baked.transfer)),
        lightmap,
        quantization: None,
    }
}

/// How the `.glb` packs the transfer, in words: `coeffs` = n² coefficients, `per_vertex` values.
fn packing(coeffs: usize, per_vertex: usize, glossy: Option<&GlossyInfo>, cpca: Option<&Cpca>) -> String {
    match (glossy, cpca) {
        (_, Some(c)) => format!(
            "clustered PCA: _PRT_CLUSTER is a float SCALAR holding the vertex's cluster c (an integer), _PRT_W_k a \
             float VEC4 holding weights 4k..4k+3 of its {} (zeros pad the last); the blobs cpca.means ({} x \
             {per_vertex}) and cpca.bases ({} x {} x {per_vertex}) hold each cluster's mean and directions, so T = \
             means[c] + sum_p w_p bases[c][p], T laid out as below when uncompressed",
            c.components, c.clusters, c.clusters, c.components
        ),
        (None, None) if per_vertex == coeffs => format!(
            "_PRT_k is a float VEC4 holding coefficients 4k..4k+3 in index order i = l(l+1)+m; {coeffs} \
             coefficients, zeros pad the last attribute"
        ),
        (None, None) => format!(
            "_PRT_k is a float VEC4 holding values 4k..4k+3 of the 3 x {coeffs} colour transfer, channel-major: \
             value c*{coeffs} + i is channel c's (R, G, B) coefficient i = l(l+1)+m, dotted with that channel's \
             lighting; {per_vertex} values, zeros pad the last attribute"
        ),
        (Some(g), None) => format!(
            "_PRT_k is a float VEC4 holding values 4k..4k+3 of the {} x {coeffs} matrix, term-major: value \
             t*{coeffs} + i is term t's coefficient i = l(l+1)+m (sigma_t folded in); {per_vertex} values, zeros \
             pad the last attribute",
            g.terms
        ),
    }
}

/// The run-time snippet in `lang`. A glossy bake's adds the view-dependent half: the frame F and
/// the h_k lookup. A compressed bake's `.glb` has no `_PRT_k`: its header says how to get T (or
/// c_k) first.
fn run_time_snippet(config: &Config, quantized: Option<&Quantized>, lang: Language) -> String {
    let mut text = match &config.glossy {
        Some(g) => glossy_snippet(config.order, g.terms, g.factorization.grid, lang),
        None if config.albedo.channels() > 1 => colour_snippet(config.order, lang),
        None => snippet(config.order, lang),
    };
    match (&config.compression, quantized) {
        (None, None) => text,
        (None, Some(q)) => {
            text += &dequantize_snippet(q, lang);
            text
        }
        (Some(c), q) => format!(
            "// This bake's .glb stores the transfer by clustered PCA (transfer --clusters {} --pca {}): it has no\n\
             // _PRT_k attributes but _PRT_CLUSTER, _PRT_W_k and the cpca.means / cpca.bases blobs. Per frame,\n\
             // dot the (turned) lighting with each cluster's mean and directions, then per vertex add P\n\
             // weighted terms (Sloan et al. 2003, eq. 3; docs/formats/transfer.md); the dot product below is\n\
             // that of an uncompressed T, T = mean[c] + sum_p w_p basis[c][p].\n{}{text}",
            c.clusters,
            c.components,
            q.map_or(String::new(), |q| format!(
                "// The weights are quantized (transfer --quantize): _PRT_W_k are normalized {} VEC4s, read by a\n\
                 // glTF client as max(code / {1}, -1); w_p = that * cpca.scales[c], one scale per cluster.\n",
                q.component(),
                q.code_max
            ))
        ),
    }
}

/// What the `.glb` stores per vertex: the transfer (`per_vertex` values a vertex) or its
/// clustered PCA, either as floats or quantized.
struct Stored<'a> {
    transfer: &'a [f64],
    per_vertex: usize,
    cpca: Option<&'a Cpca>,
    quantized: Option<&'a Quantized>,
}

/// The `.glb`: positions, unit normals, the transfer packed four coefficients per `_PRT_k`, and
/// the manifest's body in the mesh's `extras` (so that the file explains itself).
fn glb_mesh(mesh: &Mesh, stored: &Stored, body: &TransferBody, h: Option<Vec<f32>>) -> GlbMesh {
    let mut extras = serde_json::json!({ "order": body.order, "mode": body.mode, "albedo": body.albedo });
    if body.channels != 1 {
        extras["channels"] = body.channels.into();
    }
    if let Some(g) = &body.glossy {
        extras["glossy"] = serde_json::json!({
            "terms": g.terms,
            "brdf": g.brdf,
            "factors": g.factors,
            "domain": g.domain,
            "resolution": g.resolution,
            "cosine": g.cosine,
            "singular_values": g.singular_values,
            "frame": g.frame,
        });
    }
    let vertices = mesh.positions.len();
    let mut attributes = vec![Attribute {
        name: "NORMAL".into(),
        components: 3,
        values: Values::Float(mesh.normals.iter().flat_map(|n| n.as_vec3().to_array()).collect()),
    }];
    // The lightmap's UVs, so that an engine can look the EXR up: as TEXCOORD_0, since glTF asks
    // for indexed semantics from 0 on (the Khronos validator rejects TEXCOORD_1 alone).
    if let (Some(_), Some(uvs)) = (&body.lightmap, &mesh.uvs) {
        attributes.push(Attribute {
            name: "TEXCOORD_0".into(),
            components: 2,
            values: Values::Float(uvs.iter().flat_map(|uv| uv.map(|c| c as f32)).collect()),
        });
    }
    let mut blobs: Vec<Blob> = h.map(|values| Blob { name: GLOSSY_H_BLOB.into(), values }).into_iter().collect();
    let quantized = stored.quantized;
    match stored.cpca {
        None => attributes.extend(vec4_attributes("_PRT_", stored.transfer, stored.per_vertex, vertices, quantized)),
        Some(c) => {
            extras["cpca"] = serde_json::json!({ "clusters": c.clusters, "components": c.components });
            attributes.push(Attribute {
                name: "_PRT_CLUSTER".into(),
                components: 1,
                values: Values::Float(c.cluster_of.iter().map(|&k| k as f32).collect()),
            });
            attributes.extend(vec4_attributes("_PRT_W_", &c.weights, c.components, vertices, quantized));
            let floats = |v: &[f64]| v.iter().map(|&x| x as f32).collect();
            blobs.push(Blob { name: "cpca.means".into(), values: floats(&c.means) });
            blobs.push(Blob { name: "cpca.bases".into(), values: floats(&c.bases) });
        }
    }
    // The scales beside the data they scale (after the clusters' means and directions).
    if let (Some(q), Some(info)) = (quantized, &body.quantization) {
        extras["quantization"] = serde_json::json!({
            "type": info.method,
            "code_max": q.code_max,
            "scale_per": info.scale_per,
            "scales": info.scales_blob,
        });
        blobs.push(Blob { name: info.scales_blob.clone(), values: q.scales.clone() });
    }
    GlbMesh {
        positions: mesh.positions.iter().map(|p| p.as_vec3().to_array()).collect(),
        attributes,
        triangles: mesh.triangles.clone(),
        generator: format!("prtkit {} transfer", env!("CARGO_PKG_VERSION")),
        extras: serde_json::json!({ "prtkit.transfer": extras }),
        blobs,
    }
}

/// `values` (`per_vertex` per vertex) as VEC4 attributes `PREFIX0`, `PREFIX1`, …, four values
/// each, zeros padding the last: floats, or the codes of `quantized` (normalized SHORT or BYTE).
fn vec4_attributes(
    prefix: &str,
    values: &[f64],
    per_vertex: usize,
    vertices: usize,
    quantized: Option<&Quantized>,
) -> Vec<Attribute> {
    let packed = |k: usize| {
        (0..vertices).flat_map(move |v| (4 * k..4 * k + 4).map(move |i| (i < per_vertex).then_some(v * per_vertex + i)))
    };
    (0..per_vertex.div_ceil(4))
        .map(|k| {
            let values = match quantized {
                None => Values::Float(packed(k).map(|i| i.map_or(0.0, |i| values[i] as f32)).collect()),
                // Codes lie in -q..=q, so they fit the type q is the largest of.
                Some(q) if q.code_max == i8::MAX as i32 => {
                    Values::NormalizedByte(packed(k).map(|i| i.map_or(0, |i| q.codes[i] as i8)).collect())
                }
                Some(q) => Values::NormalizedShort(packed(k).map(|i| i.map_or(0, |i| q.codes[i] as i16)).collect()),
            };
            Attribute { name: format!("{prefix}{k}"), components: 4, values }
        })
        .collect()
}

/// The per-vertex values of a bake coded by `quantization` (`None` for float storage): the
/// transfer with one scale per value index, or, compressed, the PCA weights with one scale per
/// cluster ([`super::quantize`]).
fn quantize(quantization: Quantization, transfer: &[f64], per_vertex: usize, cpca: Option<&Cpca>) -> Option<Quantized> {
    let q = quantization.code_max()?;
    Some(match cpca {
        None => Quantized::new(transfer, per_vertex, per_vertex, q, |_, j| j),
        Some(c) => Quantized::new(&c.weights, c.components, c.clusters, q, |v, _| c.cluster_of[v] as usize),
    })
}

/// The manifest's account of a quantization: the error of the transfer it stores against the
/// unquantized file's, and its closed-form bound. Each stored value moves by at most half a code
/// step, s / (2q). Uncompressed, that is the transfer's own change, so
/// ‖ΔT‖² ≤ V Σ_i (s_i / 2q)² over V vertices. Compressed, ΔT(x) = Σ_p Δw_p b_cp with the
/// cluster's directions orthonormal (or zero), so ‖ΔT(x)‖ ≤ ‖Δw‖ ≤ √P s_c / (2q) (Sloan et al.
/// 2003, eq. 2).
fn quantization_info(
    quantization: Quantization,
    q: &Quantized,
    transfer: &[f64],
    per_vertex: usize,
    cpca: Option<&Cpca>,
) -> QuantizationInfo {
    let half_step = |s: f32| s as f64 / (2.0 * q.code_max as f64);
    let reference2: f64 = transfer.iter().map(|t| t * t).sum();
    let (diff2, bound2, attributes, scale_per, scales_blob) = match cpca {
        None => {
            let diff2: f64 = transfer.iter().enumerate().map(|(k, t)| (t - q.value(k, k % per_vertex)).powi(2)).sum();
            let vertices = transfer.len() / per_vertex;
            let bound2 = vertices as f64 * q.scales.iter().map(|&s| half_step(s).powi(2)).sum::<f64>();
            (diff2, bound2, "_PRT_k", "value", TRANSFER_SCALES_BLOB)
        }
        Some(c) => {
            let (p, d) = (c.components, c.dim);
            let (mut diff2, mut bound2) = (0.0, 0.0);
            let mut delta = vec![0.0; d];
            for (v, &cluster) in c.cluster_of.iter().enumerate() {
                let cluster = cluster as usize;
                delta.fill(0.0);
                for j in 0..p {
                    let dw = c.weights[v * p + j] - q.value(v * p + j, cluster);
                    let basis = &c.bases[(cluster * p + j) * d..(cluster * p + j + 1) * d];
                    delta.iter_mut().zip(basis).for_each(|(t, b)| *t += dw * b);
                }
                diff2 += delta.iter().map(|t| t * t).sum::<f64>();
                bound2 += p as f64 * half_step(q.scales[cluster]).powi(2);
            }
            (diff2, bound2, "_PRT_W_k", "cluster", CPCA_SCALES_BLOB)
        }
    };
    let relative = |x2: f64| if reference2 > 0.0 { (x2 / reference2).sqrt() } else { 0.0 };
    QuantizationInfo {
        method: quantization,
        component_type: quantization.component_type().into(),
        code_max: q.code_max,
        attributes: attributes.into(),
        scale_per: scale_per.into(),
        scales_blob: scales_blob.into(),
        scales: q.scales.clone(),
        max_error_over_half_step: q.max_error_over_half_step,
        relative_rms: relative(diff2),
        relative_rms_bound: relative(bound2),
        dequantize: format!(
            "value = max(code / {q}, -1) * {scales_blob}[{which} (a glTF client's normalized read gives \
             max(code / {q}, -1))",
            q = q.code_max,
            which = if cpca.is_some() { "c], c the vertex's cluster" } else { "i], i the value's index in the layout" }
        ),
    }
}

/// The blob of a quantized, uncompressed `.glb` holding one scale per value index (the layout's
/// n² or K·n² values).
pub const TRANSFER_SCALES_BLOB: &str = "transfer.scales";
/// The blob of a quantized, compressed `.glb` holding one scale per cluster for its weights.
pub const CPCA_SCALES_BLOB: &str = "cpca.scales";

/// The manifest's account of a compression.
fn compression_info(cpca: &Cpca, transfer: &[f64]) -> CompressionInfo {
    let r = cpca.reconstruction(transfer);
    CompressionInfo {
        method: "clustered PCA".into(),
        clusters: cpca.clusters,
        components: cpca.components,
        iterations: cpca.iterations,
        relative_rms: r.relative_rms,
        max_vertex: r.max_vertex,
        values_per_vertex: cpca.dim,
        stored_per_vertex: 1 + cpca.components,
        stored_per_cluster: (1 + cpca.components) * cpca.dim,
        description: format!(
            "Sloan, Hall, Hart & Snyder 2003: clusters cut along the first principal direction, then rounds of \
             fitting each cluster's mean and {} leading directions and moving every vertex to the cluster that \
             reconstructs it best, until none moves or a round gains less than 0.1 % of the error (at most {} rounds); errors of the stored f64 fit, before \
             the f32 the .glb keeps",
            cpca.components,
            super::cpca::MAX_ITERATIONS
        ),
    }
}

/// The blob of a glossy `.glb` holding h_0 … h_{K−1} on the factors' grid: term-major, each
/// n² values in the grid's index order j·n + k (j the cos θ bin from the pole, k the φ bin),
/// as the factor file's `h` layer (`docs/formats/transfer.md`), so the `.glb` relights alone.
pub const GLOSSY_H_BLOB: &str = "glossy.h";

/// Refuses a compression whose clusters or directions are out of range, or whose rounds would
/// take longer than [`MAX_CPCA_ROUND_WORK`] allows, before anything is baked.
fn check_compression(c: &Compression, vertices: usize, per_vertex: usize) -> Result<(), Error> {
    let (clusters, components) = (c.clusters, c.components);
    let most_components = MAX_CPCA_DIRECTIONS.min(per_vertex);
    if !(1..=MAX_CPCA_CLUSTERS).contains(&clusters) || !(1..=most_components).contains(&components) {
        return Err(Error::Compression { clusters, components, most_components });
    }
    // Each round compares every vertex with every cluster: bound its work up front.
    let work = vertices as u128 * clusters.min(vertices) as u128 * (components as u128 + 1) * per_vertex as u128;
    if work > MAX_CPCA_ROUND_WORK {
        return Err(Error::CompressionWork { clusters, components, vertices, per_vertex, work });
    }
    Ok(())
}

/// Glossy transfer with B = `config.bounces` bounces: the surfaces the cells' rays meet shine
/// with their diffuse interreflected transfer of B − 1 bounces (albedo ρ), so that light reaches
/// the glossy vertex after 1 to B diffuse bounces, as the diffuse bake's T^1 … T^B do.
fn glossy_interreflected(
    config: &Config,
    mesh: &Mesh,
    plan: &Plan,
    integrator: &Glossy,
    progress: &dyn Progress,
) -> Baked {
    let start = Instant::now();
    let bounces = config.bounces;
    let occluders = Occluders::new(&mesh.positions, &mesh.triangles);
    let diffuse = interreflected(config, mesh, &occluders, bounces - 1, plan.offset, None, progress);
    let visibility =
        Visibility::Interreflected { occluders: &occluders, offset: plan.offset, mesh, radiance: &diffuse.transfer };
    let transfer = glossy(mesh, integrator, &visibility, 0..mesh.positions.len(), progress);
    let mut baked = baked(config, mesh, plan, Transfer::Values(transfer), start.elapsed().as_secs_f64());
    baked.interreflection = diffuse.interreflection.map(|i| Interreflection {
        bounces,
        glossy_gather: Some(format!(
            "a cell whose ray meets the front of a surface receives that surface's outgoing radiance, its diffuse \
             interreflected transfer (albedo {}, {} bounce(s): the passes white_sky_response lists, traced with \
             {} stratified rays per vertex) interpolated at the hit, times sigma_k g_k(c) and the cell's weight; \
             light between glossy surfaces is carried as if they were diffuse",
            config.albedo.folded(),
            bounces - 1,
            config.rays
        )),
        ..i
    });
    baked.bounce_seconds = diffuse.trace_seconds + diffuse.bounce_seconds;
    baked
}

/// The integrator of a glossy bake, after checking what the factorization can give.
fn glossy_integrator(config: &Config, g: &GlossyConfig) -> Result<Glossy, Error> {
    check_glossy(g)?;
    Ok(Glossy::new(&g.factorization, g.terms, g.cosine, config.order, g.cell_samples))
}

/// Checks the terms a glossy bake keeps against those the factorization holds, and its basis
/// samples per cell against [`MAX_CELL_SAMPLES`].
pub(super) fn check_glossy(g: &GlossyConfig) -> Result<(), Error> {
    let stored = g.factorization.g.len().min(g.factorization.h.len());
    if g.terms == 0 || g.terms > stored {
        return Err(Error::Terms { factors: g.factors.clone(), terms: g.terms, stored });
    }
    if !(1..=MAX_CELL_SAMPLES).contains(&g.cell_samples) {
        return Err(Error::CellSamples(g.cell_samples));
    }
    Ok(())
}

/// How a glossy bake integrates, in words.
fn glossy_description(g: &GlossyConfig, mode: Mode, cells: usize) -> String {
    let (n, sub) = (g.factorization.grid.n, g.cell_samples);
    format!(
        "over the {cells} cells of the factors' {n}x{n} (cos theta, phi) grid in the normal's frame F = {FRAME}: \
         T_kj = sigma_k sum_c V(c) g_k(c) sum_s w_s Y_j(F w_cs), {sub}x{sub} basis samples per cell \
         weighted by the cell's solid angle{}; {}",
        if g.cosine { "" } else { " times max(cos theta, 0)" },
        match mode {
            Mode::Unshadowed => "V = 1 (unshadowed)",
            Mode::Shadowed => "V(c) by one ray along the cell's centre",
            Mode::Interreflected =>
                "V(c) by one ray along the cell's centre, which gathers the light of the surface it \
                                     meets (interreflection)",
        }
    )
}

/// The manifest's account of a glossy bake.
fn glossy_info(g: &GlossyConfig, order: usize) -> GlossyInfo {
    let f = &g.factorization;
    let energy = f.cumulative_energy().get(g.terms - 1).copied().unwrap_or(1.0);
    GlossyInfo {
        terms: g.terms,
        terms_reason: g.terms_reason.clone(),
        energy,
        relative_frobenius_error: f.reconstruction_error(g.terms),
        singular_values: f.singular_values[..g.terms].to_vec(),
        brdf: g.brdf.clone(),
        factors: g.factors.clone(),
        domain: f.grid.domain,
        resolution: f.grid.n,
        cosine: g.cosine,
        cell_samples: g.cell_samples,
        relighting: format!(
            "B(x, w_o) = sum_k h_k(F^T w_o) c_k(x), c_k = sum_i T_ki L_i over the {} coefficients of the lighting; \
             F = {FRAME}, the shortest-arc rotation carrying +Z to the unit normal (the turn by theta_n about +Z x \
             n; its third column the normal); h_k bilinear on the factor file's grid",
            order * order
        ),
        frame: FRAME.to_string(),
    }
}

/// The direction set's integration error on the unshadowed integrand ([`ErrorFigures`]).
fn integration_error(mesh: &Mesh, points: &[PointTransfer], order: usize, rays: usize, albedo: f64) -> ErrorFigures {
    let coeffs = order * order;
    let mut exact = vec![0.0; coeffs];
    let (mut diff2, mut ref2) = (0.0, 0.0);
    let mut per_vertex = Vec::with_capacity(points.len());
    let mut visible = 0.0;
    for (p, n) in points.iter().zip(&mesh.normals) {
        unshadowed_exact(*n, order, albedo, &mut exact);
        let d2: f64 = p.unshadowed.iter().zip(&exact).map(|(a, b)| (a - b) * (a - b)).sum();
        let r2: f64 = exact.iter().map(|b| b * b).sum();
        diff2 += d2;
        ref2 += r2;
        per_vertex.push(if r2 > 0.0 { (d2 / r2).sqrt() } else { 0.0 });
        visible += p.visible as f64 / rays as f64;
    }
    per_vertex.sort_by(f64::total_cmp);
    let at = |q: f64| {
        per_vertex.get(((per_vertex.len() as f64 * q).ceil() as usize).saturating_sub(1)).copied().unwrap_or(0.0)
    };
    ErrorFigures {
        measured: "the same rays with visibility ignored against the exact unshadowed transfer: \
                   |T_rays - T_exact| / |T_exact| per vertex"
            .into(),
        relative_rms: if ref2 > 0.0 { (diff2 / ref2).sqrt() } else { 0.0 },
        p99_vertex: at(0.99),
        max_vertex: at(1.0),
        visible_fraction: visible / points.len().max(1) as f64,
    }
}

/// Serde's default for [`TransferBody::channels`].
fn one() -> usize {
    1
}

/// Whether [`TransferBody::channels`] is the grey 1 (left out of the manifest).
fn is_one(channels: &usize) -> bool {
    *channels == 1
}
