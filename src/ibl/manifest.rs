//! The `prtkit.ibl` manifest (`DIR/ibl.json`, `docs/formats/ibl.md`) and the `prtkit.ibl-sh`
//! document (`DIR/sh.json`): what each file of an `ibl` bake holds, in which frame, and how
//! accurate every level measured.

use crate::io::document::Validate;
use serde::{Deserialize, Serialize};

/// Format name of the manifest.
pub const FORMAT: &str = "prtkit.ibl";
/// Format name of the SH irradiance document.
pub const SH_FORMAT: &str = "prtkit.ibl-sh";
/// The manifest's file name in the bake's directory.
pub const FILE: &str = "ibl.json";
/// Schema version of both.
pub const VERSION: u32 = 1;

/// Faces in file order.
pub const FACE_ORDER: [&str; 6] = ["+X", "-X", "+Y", "-Y", "+Z", "-Z"];

/// What the face orientation means, for the manifest.
pub const FACE_ORIENTATION: &str = "KTX2/Vulkan cube map convention (KTXorientation rd): texel (row r, column c) of an n x n face, s = 2(c+0.5)/n - 1, t = 2(r+0.5)/n - 1, looks along +X (1,-t,-s), -X (-1,-t,s), +Y (s,1,t), -Y (s,-1,-t), +Z (s,-t,1), -Z (-s,-t,-1) in the output frame";

/// The manifest body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IblBody {
    /// The input environment map.
    pub source: String,
    /// [`crate::envmap::EnvMap::content_hash`] of the map as read (after `--flip-vertical`):
    /// readers given a map check that it is the one baked (absent in bakes before it was added).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source_hash: Option<String>,
    /// What the levels' errors were measured against when it is not the texel-by-texel sum over
    /// the input (a large input box-filtered, or summed on coarser levels, `ibl::reference`);
    /// absent when it is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured_against: Option<String>,
    /// The output frame.
    pub frame: Frame,
    /// The prefiltered specular cube.
    pub specular: Specular,
    /// The irradiance cube.
    pub irradiance: Irradiance,
    /// The SH irradiance files.
    pub sh: ShFiles,
    /// The split-sum DFG table.
    pub dfg: Dfg,
    /// Wall-clock seconds of the bake's parts: said on stderr and in `--json`, never written, so
    /// the manifest is the same bytes for any thread count and any machine.
    #[serde(skip)]
    pub timings: Timings,
}

impl Validate for IblBody {
    fn validate(&self) -> Result<(), (&'static str, String)> {
        let m = glam::DMat3::from_cols_array_2d(&self.frame.world_from_prtkit);
        let orthonormal = (m * m.transpose()).abs_diff_eq(glam::DMat3::IDENTITY, 1e-6);
        if !orthonormal || m.to_cols_array().iter().any(|v| !v.is_finite()) {
            return Err(("world_from_prtkit", "not a rotation (or a rotation with a mirror)".into()));
        }
        let roughness: Vec<f64> = self.specular.levels.iter().map(|l| l.roughness).collect();
        let rising = roughness.windows(2).all(|w| w[0] < w[1]);
        if roughness.is_empty() || !rising || roughness.iter().any(|r| !(0.0..=1.0).contains(r)) {
            return Err(("levels", format!("the levels' roughness {roughness:?} must rise within [0, 1]")));
        }
        Ok(())
    }
}

/// The frame every output is in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// `y` (glTF: prtkit's +Z becomes +Y) or `z` (prtkit's frame kept).
    pub up: String,
    /// Rotation of the environment about the up axis, degrees (counter-clockwise from above).
    pub rotate_degrees: f64,
    /// Whether the environment was mirrored (prtkit's y → −y before the rotation).
    pub mirror: bool,
    /// Whether the input was flipped vertically on reading (z → −z, before everything here):
    /// `world_from_prtkit` takes directions of the map as read, after the flip.
    #[serde(default)]
    pub flip_vertical: bool,
    /// The 3×3 matrix, row-major, that takes a direction of the input (prtkit's frame, +Z up) to
    /// the output frame the cube faces and SH are in: d_out = M d_prtkit.
    pub world_from_prtkit: [[f64; 3]; 3],
    /// Faces in file order.
    pub faces: Vec<String>,
    /// Texel ↔ direction convention of each face.
    pub face_orientation: String,
}

/// One level of the specular chain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Level {
    /// Mip level (0 = largest).
    pub level: usize,
    /// Face size.
    pub size: usize,
    /// Perceptual roughness r (α = r²).
    pub roughness: f64,
    /// `resample` (r = 0: the environment itself), `zonal` (frequency space: row-pair FFTs on a
    /// lat-long grid, read back by direction) or `angular` (lobe-truncated cone sums over a cube
    /// pyramid).
    pub method: String,
    /// SH order used (null: neither path truncates in SH; the zonal path is exact for the
    /// piecewise-constant grid it filters).
    pub order: Option<usize>,
    /// Working grid W×H (zonal), or the cube pyramid level read (angular), or the input size.
    pub source: String,
    /// Texel-rule sub-samples per axis (zonal), if any.
    pub rule_subsamples: Option<usize>,
    /// Estimated seconds (one core) of each method: the cost model's inputs.
    pub estimated_cost: Option<Costs>,
    /// max relative error against the angular integral on the sampled texels (null: not
    /// measured, or r = 0).
    pub max_rel_error: Option<f64>,
    /// RMS relative error on the sampled texels.
    pub rms_rel_error: Option<f64>,
    /// Texels sampled for the errors.
    pub samples: usize,
    /// When the reference is bounded (`measured_against`: the input box-filtered, or summed on
    /// two levels): max over the sampled texels of the bound on how far it may be from the
    /// texel-by-texel sum over the input, relative like the errors; the error against that sum
    /// is within this of the stated one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_bound: Option<f64>,
    /// The most negative texel component before packing (0 when none).
    pub min_value: f64,
    /// Seconds to compute the level (measurement excluded); not written (see `timings`).
    #[serde(skip)]
    pub seconds: f64,
}

/// The cost model's estimates, in seconds on one core.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Costs {
    /// Zonal path.
    pub zonal: f64,
    /// Angular path.
    pub angular: f64,
}

/// The specular cube file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Specular {
    /// File name in DIR.
    pub file: String,
    /// `ktx2` or `dds`.
    pub container: String,
    /// Texel format name.
    pub format: String,
    /// `linear` or `filament`.
    pub roughness_map: String,
    /// The mapping in words.
    pub roughness_formula: String,
    /// What each level holds.
    pub lobe: String,
    /// The levels.
    pub levels: Vec<Level>,
}

/// The irradiance cube file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Irradiance {
    /// File name.
    pub file: String,
    /// Face size (one level).
    pub size: usize,
    /// Texel format name.
    pub format: String,
    /// What a texel holds.
    pub scale: String,
    /// How, with its measured error.
    pub level: Level,
}

/// The SH files.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShFiles {
    /// The `prtkit.ibl-sh` document.
    pub file: String,
    /// Shader snippets.
    pub shaders: Vec<String>,
    /// What the snippets return.
    pub scale: String,
}

/// The DFG table file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Dfg {
    /// File name.
    pub file: String,
    /// Side N.
    pub size: usize,
    /// `scale-bias` or `multiscatter`.
    pub variant: String,
    /// Texel format name.
    pub format: String,
    /// Texel layout and shader use.
    pub layout: String,
}

/// Seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Timings {
    /// Reading the input into the working lat-long map (after loading).
    pub prepare: f64,
    /// The specular chain.
    pub specular: f64,
    /// The irradiance cube and the SH.
    pub irradiance: f64,
    /// The DFG table.
    pub dfg: f64,
    /// The bake without measurement (the files are encoded by the caller, after it).
    pub bake: f64,
    /// Preparing the angular reference the levels are measured against (beside the bake).
    pub reference: f64,
    /// Measuring the levels against the angular reference.
    pub measure: f64,
}

/// The `prtkit.ibl-sh` body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShBody {
    /// The output frame (as in the manifest).
    pub frame: Frame,
    /// The polynomials b_i(n), in order.
    pub basis: Vec<String>,
    /// What Σ c_i b_i(n) is.
    pub scale: String,
    /// c_i (RGB), the shader coefficients.
    pub coefficients: Vec<[f64; 3]>,
    /// The radiance coefficients L_lm in prtkit's orthonormal real basis, in the output frame,
    /// index l(l+1)+m.
    pub radiance: Vec<[f64; 3]>,
}
