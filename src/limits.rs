//! Ceilings on what prtkit accepts from files, documents and shaders, each derived from memory
//! or time, in one place (the table is `docs/limits.md`). Every reader checks its input against
//! them with a `check_*` helper *before* allocating (files and standard input are read through
//! [`crate::io::read_bytes`], which stops at the ceiling it is given), so a hostile or garbled file ends with a
//! clear error naming the file instead of an allocation failure, a panic or an endless loop.
//!
//! Memory ceilings scale with the machine: [`memory_budget`] is half of the memory the process
//! may use (the smallest of physical memory, the cgroup's limit and the address-space limit of
//! `ulimit -v`). Everything else is a fixed number, so that what a file means does not depend
//! on the machine that reads it.

use std::sync::OnceLock;

/// A value above its ceiling. The message says what, how much, the ceiling and why it exists.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what} is {value}, above the ceiling of {ceiling} ({reason}; see docs/limits.md)")]
pub struct LimitError {
    /// What was too large, e.g. "the image (data window 100000x100000)".
    pub what: String,
    /// Its size, in words.
    pub value: String,
    /// The ceiling, in words.
    pub ceiling: String,
    /// Why the ceiling is there.
    pub reason: &'static str,
}

// ---------------------------------------------------------------------------------------------
// Memory
// ---------------------------------------------------------------------------------------------

/// Memory assumed when none of `/proc/meminfo`, the cgroup limit or `/proc/self/limits` can be
/// read (a non-Linux system): 4 GiB, less than any machine prtkit is meant for has.
pub const FALLBACK_MEMORY: u64 = 4 << 30;

/// The memory this process may use, in bytes: the smallest of physical memory (`MemTotal` of
/// `/proc/meminfo`), the cgroup's memory limit (v2 `memory.max` or v1 `memory.limit_in_bytes`)
/// and the address-space limit (`ulimit -v`, from `/proc/self/limits`); [`FALLBACK_MEMORY`] when
/// none is readable. Read once per process.
pub fn available_memory() -> u64 {
    static MEMORY: OnceLock<u64> = OnceLock::new();
    *MEMORY.get_or_init(|| {
        let read = |p: &str| std::fs::read_to_string(p).ok();
        let mem_total = read("/proc/meminfo").and_then(|t| {
            let line = t.lines().find(|l| l.starts_with("MemTotal:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            kib.checked_mul(1024)
        });
        let cgroup = ["/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"]
            .iter()
            .filter_map(|p| read(p)?.trim().parse::<u64>().ok())
            .min();
        let address_space = read("/proc/self/limits").and_then(|t| {
            let line = t.lines().find(|l| l.starts_with("Max address space"))?;
            line.split_whitespace().nth(3)?.parse::<u64>().ok()
        });
        [mem_total, cgroup, address_space].into_iter().flatten().min().unwrap_or(FALLBACK_MEMORY)
    })
}

/// The memory one input may take once decoded: half of [`available_memory`], leaving the other
/// half for the stage's own work on it (a projection, a resampled copy, an output image).
pub fn memory_budget() -> u64 {
    available_memory() / 2
}

/// The largest file read whole into memory (images, meshes, normals): half of
/// [`memory_budget`], since decoding needs the bytes and the decoded values at once.
pub fn max_file_bytes() -> u64 {
    memory_budget() / 2
}

// ---------------------------------------------------------------------------------------------
// Images
// ---------------------------------------------------------------------------------------------

/// Largest image any reader accepts, in texels: 2²⁸ (16384 × 16384, a 32768 × 8192 lat-long).
/// Fixed, so that a file means the same on every machine: as an RGB f32 image it is 3 GiB, and
/// the SH projection of the largest order a document may carry ([`MAX_SH_ORDER`]) over it costs
/// 2²⁸·2001² ≈ 10¹⁵ multiply-adds — hours. The memory check of [`check_image`] comes on top.
pub const MAX_IMAGE_TEXELS: u64 = 1 << 28;

/// Bytes per texel of a decoded RGB f32 image (one per Radiance HDR or PFM file, one per RGB or
/// grey layer of an EXR, on top of the `exr` crate's 2 or 4 bytes per channel sample).
pub const RGB_BYTES_PER_TEXEL: u64 = 12;

/// Checks an image size read from a header before anything is allocated for it: at most
/// [`MAX_IMAGE_TEXELS`] texels, and `bytes_per_texel` of them within [`memory_budget`].
/// `what` names the image in the message (e.g. "the data window of layer \"B1+0\"").
pub fn check_image(what: &str, width: u64, height: u64, bytes_per_texel: u64) -> Result<(), LimitError> {
    let texels = width as u128 * height as u128;
    if texels > MAX_IMAGE_TEXELS as u128 {
        return Err(LimitError {
            what: format!("{what} ({width}x{height})"),
            value: format!("{texels} texels"),
            ceiling: format!("{MAX_IMAGE_TEXELS} texels"),
            reason: "the largest image prtkit reads",
        });
    }
    check_memory(what, texels * bytes_per_texel as u128)
}

/// Checks that `bytes` of working memory fit the [`memory_budget`].
pub fn check_memory(what: &str, bytes: u128) -> Result<(), LimitError> {
    let budget = memory_budget();
    if bytes > budget as u128 {
        return Err(LimitError {
            what: format!("the memory {what} needs"),
            value: human_bytes(bytes),
            ceiling: human_bytes(budget as u128),
            reason: "half of the memory this process may use",
        });
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Cube maps, GPU textures and image-based lighting
// ---------------------------------------------------------------------------------------------

/// Widest face a cube map holds (`ibl::cube::CubeMap`, the cube pyramid of the angular
/// prefilter): 8192 texels. Six 8192² faces of RGB f32 are 4.5 GiB, and the next power of two
/// 18 GiB, far beyond what any engine loads as one environment.
pub const MAX_CUBE_FACE_SIZE: usize = 8192;

/// Largest face size `ibl` bakes, for the specular chain's first and last levels and the
/// irradiance cube: 4096. The chain of a 4096² cube is 6 × 4096² × 4/3 = 2²⁷ texels, 1.5 GiB as
/// RGB f32 and 1 GiB more as RGBA16F in its file, both held at once; within
/// [`MAX_CUBE_FACE_SIZE`], so every level the bake makes is a cube map.
pub const MAX_IBL_FACE_SIZE: usize = 4096;
const _: () = assert!(MAX_IBL_FACE_SIZE <= MAX_CUBE_FACE_SIZE);

/// Largest side of the split-sum DFG table: 1024² texels, each an integral over the
/// hemisphere; 8× the default side, far past what a shader's bilinear lookup of these smooth
/// functions resolves.
pub const MAX_DFG_SIZE: usize = 1024;

/// Most texels per level `ibl` measures against the angular integral: 4096, each a cone sum
/// over the input map.
pub const MAX_IBL_MEASURED_TEXELS: usize = 4096;

/// Widest side of a texture the KTX2 and DDS writers encode: 2¹⁶ texels, so that every level's
/// width, height and pitch fit the files' 32-bit fields.
pub const MAX_TEXTURE_SIDE: usize = 1 << 16;

// ---------------------------------------------------------------------------------------------
// Filters and checks
// ---------------------------------------------------------------------------------------------

/// Largest lat-long grid (source or output) the zonal filter (`envmap::zonal`) convolves, in
/// texels: 2²³. Its source spectra take 24 bytes per texel (3 channels × W/2 + 1 complex f64 per
/// row), 200 MB at this bound.
pub const MAX_ZONAL_TEXELS: usize = 1 << 23;

/// Most texels `prefilter --verify` checks per map against the angular reference: 100 000, each
/// a cone sum over the map.
pub const MAX_VERIFY_TEXELS: usize = 100_000;

// ---------------------------------------------------------------------------------------------
// What a stage makes (the CLI's options; `docs/cli.md` words each with its flag)
// ---------------------------------------------------------------------------------------------

/// Widest edge of an image a stage makes at a size it is given (`WxH`): 2¹⁶ texels, the
/// largest edge the [`MAX_IMAGE_TEXELS`] of an image read can have with the other edge 4096.
pub const MAX_IMAGE_EDGE: usize = 1 << 16;

/// Largest sub-sample count per texel edge of a resampled map (`envmap::stage`): 16, k² = 256
/// bilinear lookups per output texel, which already average far below any texel's footprint.
pub const MAX_SUPERSAMPLE: usize = 16;

/// Highest order the ε search of an SH projection (`sh::stage`) considers: 256, (F+1)² = 66 049
/// coefficients projected before the order is chosen. An ε this order does not meet is refused
/// as unreachable, naming the ε it achieves.
pub const MAX_EPSILON_ORDER: usize = 256;

/// Deepest quadtree level of a shader's adaptive sampling (`shader::stage`): 16, 4¹⁶ nodes, each
/// a shader evaluation within the per-evaluation budget ([`MAX_OPERATIONS`]).
pub const MAX_QUADTREE_DEPTH: u32 = 16;

/// Most cells of a material grid (`render::grid`): 64, each rendered twice, the reference at the
/// full cost of the rendering equation.
pub const MAX_GRID_CELLS: usize = 64;

// ---------------------------------------------------------------------------------------------
// Documents
// ---------------------------------------------------------------------------------------------

/// Highest SH order (F, P_B, F_B) a document may carry: 2000, the order `sh-project --order`
/// accepts. (F+1)² = 4·10⁶ RGB coefficients: 96 MB as f64, about 450 MB of pretty JSON.
pub const MAX_SH_ORDER: usize = 2000;

/// Largest JSON document read: 1 GiB, room for a `prtkit.sh` at [`MAX_SH_ORDER`] (≈ 450 MB,
/// one number per line) twice over. Also bounded by [`memory_budget`]/4, as parsing holds the
/// text and the values at once.
pub fn max_document_bytes() -> u64 {
    (1u64 << 30).min(memory_budget() / 4)
}

/// Checks an SH order read from a document (before (F+1)² is computed: it would overflow).
pub fn check_sh_order(what: &str, order: usize) -> Result<(), LimitError> {
    if order > MAX_SH_ORDER {
        return Err(LimitError {
            what: what.to_string(),
            value: order.to_string(),
            ceiling: MAX_SH_ORDER.to_string(),
            reason: "the highest SH order prtkit computes or reads",
        });
    }
    Ok(())
}

/// Highest grid resolution n of a `prtkit.factor` document: 1024. Above it even the FFT
/// factorization needs 2n³·8 bytes = 16 GiB, so no factor-brdf run has written one.
pub const MAX_FACTOR_RESOLUTION: usize = 1024;

/// Checks a count read from a document against its ceiling.
pub fn check_count(what: &str, value: usize, ceiling: usize, reason: &'static str) -> Result<(), LimitError> {
    if value > ceiling {
        return Err(LimitError {
            what: what.to_string(),
            value: value.to_string(),
            ceiling: ceiling.to_string(),
            reason,
        });
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// BRDF specs
// ---------------------------------------------------------------------------------------------

/// Tallest BRDF peak a spec may ask for: 10⁸ sr⁻¹ (Phong s ≈ 6.3·10⁸, Torrance–Sparrow σ ≈
/// 2.8·10⁻⁵). Such a lobe is about 1/√s ≈ 4·10⁻⁵ rad wide, narrower than a texel of the
/// largest image prtkit reads (2π/32768 ≈ 1.9·10⁻⁴ rad), so no stage can resolve anything
/// taller; and the squares the factorization sums (10¹⁶ per entry, over at most 10¹² entries)
/// stay far from f64 overflow, which a Phong s = 10³⁰⁸ reaches (its energy came out −∞).
pub const MAX_BRDF_PEAK: f64 = 1e8;

/// Widest Torrance–Sparrow σ: 100 rad. The lobe exp(−(θ_h/σ)²) then varies by less than
/// 0.1 % over the sphere (a constant), and its peak 1/(4πσ²) stays a normal number, which
/// σ ≳ 10¹⁵³ would not (the BRDF would be 0 and its energy curve 0/0).
pub const MAX_TORRANCE_SPARROW_SIGMA: f64 = 100.0;

// ---------------------------------------------------------------------------------------------
// The shading language
// ---------------------------------------------------------------------------------------------

/// Largest shader source: 1 MiB (the shipped shaders are under 4 KiB).
pub const MAX_SHADER_SOURCE_BYTES: u64 = 1 << 20;

/// Deepest nesting of expressions and statements in a shader (each operand of a chain of
/// binary operators counts as one level: a sum of 300 terms is 300 deep). The parser, checker
/// and interpreter recurse once per level: measured, at most 1.1 KiB of stack per level in the
/// interpreter (affine numbers), so a shader at the ceiling evaluates within 1 MiB, half of a
/// worker thread's 2 MiB stack (a test runs one on a 1 MiB thread). The shipped shaders
/// evaluate at most 12 levels deep.
pub const MAX_NESTING_DEPTH: usize = 256;

/// Deepest user-function call chain in one evaluation (recursion depth).
pub const MAX_CALL_DEPTH: usize = 64;

/// Deepest recursion of the interpreter in one evaluation, counting every nested expression,
/// statement and call: calls multiply nesting (a function nested 200 deep calling itself 64
/// times), so the interpreter checks the sum as it goes. At 1.1 KiB per level, 512 levels
/// stay within 600 KiB of stack.
pub const MAX_EVALUATION_DEPTH: usize = 512;

/// Most loop iterations in one evaluation of the shader.
pub const MAX_LOOP_ITERATIONS: u64 = 1_000_000;

/// Most operations in one evaluation of the shader (expressions and statements evaluated; a
/// noise evaluation counts 1024, fbm 1024 per octave, as they cost that much more): 10⁶, about
/// 30–40 ms of one sample (measured: 10⁷ plain operations took 0.2–0.3 s in each arithmetic,
/// 12 000 affine noise evaluations 0.5 s). The shipped shaders need at most 6287 (bumpmap.sl).
/// It stops exponential recursion (`f(x−1) + f(x−1)`), which the depth limit alone lets run
/// 2⁶⁴ calls, and loops nested so that their iterations multiply.
pub const MAX_OPERATIONS: u64 = 1_000_000;

/// Most octaves of fbm/turbulence (larger counts are clamped): the 17th octave of a unit
/// frequency has wavelength 2⁻¹⁶, below a texel of any image prtkit writes.
pub const MAX_OCTAVES: usize = 16;

// ---------------------------------------------------------------------------------------------
// Messages
// ---------------------------------------------------------------------------------------------

/// A byte count in binary units (KiB, MiB, …, one decimal).
pub fn human_bytes(b: u128) -> String {
    let units = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{b} bytes")
    } else {
        format!("{v:.1} {}", units[u])
    }
}

// ---------------------------------------------------------------------------------------------
// Meshes
// ---------------------------------------------------------------------------------------------

/// Most vertices `transfer` bakes: 2²⁴ (16.8 M). A `.glb` holds at most 4 GiB, and at order 8
/// a vertex takes 24 bytes of position and normal plus 64 f32 of transfer (280 bytes): 2²⁴
/// vertices are 4.7 GB, already beyond it; the check of the `.glb`'s length comes on top.
pub const MAX_TRANSFER_VERTICES: usize = 1 << 24;

/// Highest SH order n (bands; n² coefficients) of a transfer bake: 8, so 64 coefficients per
/// vertex.
pub const MAX_TRANSFER_ORDER: usize = 8;

/// Most ray directions per vertex of a transfer bake: 2²⁰.
pub const MAX_TRANSFER_RAYS: usize = 1 << 20;

/// Most interreflection bounces: each bounce keeps a copy of the transfer and costs a gather over
/// every hit; a white furnace of albedo 0.9 keeps 0.9¹⁶ ≈ 19 % of the first bounce's energy at
/// the 16th, so more bounces only matter for albedos near 1.
pub const MAX_TRANSFER_BOUNCES: usize = 16;

/// Most jobs a transfer bake splits into (`--job I/N`): 65 536, far more than a build farm
/// runs, and small enough that job ranges are computed without overflow.
pub const MAX_TRANSFER_JOBS: usize = 1 << 16;

/// Most basis samples per factor cell along each axis, for the factored render and glossy
/// transfer alike (`--cell-samples`): 8, 64 per cell.
pub const MAX_CELL_SAMPLES: usize = 8;

/// Most clusters of clustered PCA.
pub const MAX_CPCA_CLUSTERS: usize = 4096;

/// Most principal directions per cluster of clustered PCA.
pub const MAX_CPCA_DIRECTIONS: usize = 64;

/// Most multiply-adds one round of clustered PCA may take (vertices × clusters × (P + 1) ×
/// values per vertex): about a minute per round on two cores, so that no option value runs for
/// hours.
pub const MAX_CPCA_ROUND_WORK: u128 = 100_000_000_000;

/// Most texels along either side of a lightmap: 16384, so that W×H stays within the largest
/// image prtkit reads back ([`MAX_IMAGE_TEXELS`]).
pub const MAX_LIGHTMAP_SIDE: usize = 16384;

/// Most values (W·H·n²) of a lightmap: 2²⁸, 1 GiB as the f32 the EXR holds (and 2 GiB as the
/// f64 the bake computes).
pub const MAX_LIGHTMAP_VALUES: u64 = 1 << 28;

/// Longest list a PLY face may hold: 1024 vertices. A polygon of more is a garbled count, and a
/// count read as garbage must not make the reader allocate or loop.
pub const MAX_PLY_LIST_LEN: usize = 1024;

/// Most triangles `transfer` casts rays against: 2²⁶ (67 M, about 4 GiB of BVH and triangles).
pub const MAX_TRANSFER_TRIANGLES: usize = 1 << 26;

/// Checks a mesh's size before its transfer is computed.
pub fn check_transfer_mesh(what: &str, vertices: usize, triangles: usize) -> Result<(), LimitError> {
    if vertices > MAX_TRANSFER_VERTICES {
        return Err(LimitError {
            what: format!("the vertex count of {what}"),
            value: vertices.to_string(),
            ceiling: MAX_TRANSFER_VERTICES.to_string(),
            reason: "a .glb of the transfer holds at most 4 GiB",
        });
    }
    if triangles > MAX_TRANSFER_TRIANGLES {
        return Err(LimitError {
            what: format!("the triangle count of {what}"),
            value: triangles.to_string(),
            ceiling: MAX_TRANSFER_TRIANGLES.to_string(),
            reason: "the BVH of the visibility rays must fit in memory",
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_is_read_and_bounded() {
        let m = available_memory();
        assert!(m >= 64 << 20, "{m} bytes of memory?");
        assert!(memory_budget() == m / 2 && max_file_bytes() == m / 4);
    }

    #[test]
    fn image_ceilings_refuse_before_overflowing() {
        assert!(check_image("x", 512, 256, 12).is_ok());
        let e = check_image("the data window", 100_000, 100_000, 12).unwrap_err().to_string();
        assert!(e.contains("100000x100000") && e.contains("texels") && e.contains("docs/limits.md"), "{e}");
        // u64::MAX² does not wrap to something small.
        assert!(check_image("x", u64::MAX, u64::MAX, u64::MAX).is_err());
        assert!(check_memory("x", u128::MAX).is_err());
    }

    #[test]
    fn sh_orders_above_the_ceiling_are_refused() {
        assert!(check_sh_order("order", MAX_SH_ORDER).is_ok());
        let e = check_sh_order("\"order\"", 4_294_967_295).unwrap_err().to_string();
        assert!(e.contains("4294967295") && e.contains("2000"), "{e}");
    }
}
