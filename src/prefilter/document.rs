//! The `prtkit.shrm` document: metadata of an SHRM (and of reflection maps derived from it),
//! `docs/formats/shrm.md`.

use serde::{Deserialize, Serialize};

/// Document kind.
pub const FORMAT: &str = "prtkit.shrm";
/// Schema version.
pub const VERSION: u32 = 1;

/// Body of a `prtkit.shrm` document.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ShrmBody {
    /// The BRDF spec (canonical form).
    pub brdf: String,
    /// Whether max(N·ω_i, 0) was folded into ρ̂ on the general path.
    pub cosine: bool,
    /// `frequency` or `angular`.
    pub method: String,
    /// F_B.
    pub f_b: usize,
    /// P_B.
    pub p_b: usize,
    /// The requested ε, if the orders were chosen from it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon: Option<f64>,
    /// BRDF energy missed by (F_B, P_B).
    pub epsilon_achieved: f64,
    /// The conservative bound of App. B on the light field's missed energy (with `--bound`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon_bound: Option<f64>,
    /// What the SHRM texels are indexed by: `reflection` (R) or `normal` (N, Lambert).
    pub parameterization: String,
    /// Image layout of the outputs (`latlong` or `cross-horizontal`).
    pub layout: String,
    /// Width of the lat-long grid of R.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// `true` if the SHRM file holds global coefficients (eq. 7–8).
    pub global: bool,
    /// The SHRM EXR, if written.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shrm_file: Option<String>,
    /// EXR layer names, in index order p(p+1)+q.
    pub layers: Vec<String>,
    /// The lighting: input path and the order used.
    pub lighting: Lighting,
    /// Reflection maps written: file and view direction (absent for radially symmetric BRDFs).
    #[serde(default)]
    pub maps: Vec<MapEntry>,
    /// Seconds per step: written by versions before 0.1 only. Documents are deterministic (the
    /// same inputs give the same bytes); timings are in `prefilter --json`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub timings: Option<serde_json::Value>,
    /// How the ring-free bake was made: the order rule and its guarantee, the bright sources
    /// filtered in angle, the window (frequency method).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bake: Option<super::hybrid::Report>,
}

/// The lighting an SHRM was computed from.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Lighting {
    /// Input file (environment map or `prtkit.sh` document).
    pub source: String,
    /// Order of the lighting expansion used (F_B).
    pub order: usize,
}

/// One written reflection map.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MapEntry {
    /// The file.
    pub file: String,
    /// The view direction (unit, towards the viewer), if view-dependent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub view: Option<[f64; 3]>,
}

/// Name of SHRM layer (p, q) in the EXR file.
pub fn layer_name(p: usize, q: isize) -> String {
    format!("B{p}{q:+}")
}
