//! The `prtkit.shrm` document: metadata of an SHRM (and of reflection maps derived from it),
//! `docs/formats/shrm.md`.

use crate::io::document::Validate;
use crate::limits;
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
    pub bake: Option<super::ring_free::Report>,
    /// How the angular reference truncated its lobes: ε, the texel rule, the bright sources
    /// summed apart (angular method).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<super::pipeline::AngularReport>,
    /// `--verify`: texels of every map checked against the angular integral, and the figures.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verification: Option<super::verify::Verification>,
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

/// The checks every SHRM loader gets, before it computes with the orders or the grid: F_B, P_B
/// and the lighting order within [`limits::MAX_SH_ORDER`] (a P_B of 10¹² used to overflow
/// (P+1)² into "capacity overflow"), and the (P_B+1)² layers of the W×H grid within the image
/// and memory ceilings.
impl Validate for ShrmBody {
    fn validate(&self) -> Result<(), (&'static str, String)> {
        for (field, order) in [("f_b", self.f_b), ("p_b", self.p_b)] {
            limits::check_sh_order(field, order).map_err(|e| (field, e.to_string()))?;
        }
        limits::check_sh_order("the lighting order", self.lighting.order).map_err(|e| ("order", e.to_string()))?;
        if self.width == 0 || self.height == 0 {
            return Err(("width", format!("the grid is {}x{}: empty", self.width, self.height)));
        }
        let layer_bytes = limits::RGB_BYTES_PER_TEXEL * crate::sh::count(self.p_b) as u64;
        limits::check_image("the SHRM grid", self.width as u64, self.height as u64, layer_bytes)
            .map_err(|e| ("width", e.to_string()))
    }
}

/// Name of SHRM layer (p, q) in the EXR file.
pub fn layer_name(p: usize, q: isize) -> String {
    format!("B{p}{q:+}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::document::parse_validated;

    fn doc(p_b: &str, width: usize) -> String {
        format!(
            r#"{{"format": "prtkit.shrm", "version": 1,
  "conventions": {{"frame": "f", "sh": "s"}},
  "provenance": {{"tool": "t", "stage": "s", "args": []}},
  "brdf": "phong:s=8", "cosine": true, "method": "frequency", "f_b": 4,
  "p_b": {p_b},
  "epsilon_achieved": 0.05, "parameterization": "reflection", "layout": "latlong",
  "width": {width}, "height": 40, "global": false, "shrm_file": "p.shrm.exr", "layers": ["B0+0"],
  "lighting": {{"source": "sky.exr", "order": 4}}, "maps": [], "timings": {{}}
}}"#
        )
    }

    #[test]
    fn absurd_orders_and_grids_are_refused_before_any_loader_computes() {
        assert!(parse_validated::<ShrmBody>(&doc("0", 80), FORMAT, VERSION).is_ok());
        // 10^12 used to end in "capacity overflow", 2^32 in an abort.
        for p_b in ["1000000000000", "4294967296"] {
            let e = parse_validated::<ShrmBody>(&doc(p_b, 80), FORMAT, VERSION).unwrap_err();
            assert_eq!((e.line, e.column), (5, 3), "{e}");
            assert!(e.reason.contains(p_b) && e.reason.contains("ceiling of 2000"), "{e}");
        }
        let e = parse_validated::<ShrmBody>(&doc("0", 0), FORMAT, VERSION).unwrap_err().to_string();
        assert!(e.contains("empty"), "{e}");
        let e = parse_validated::<ShrmBody>(&doc("20", 1 << 30), FORMAT, VERSION).unwrap_err().to_string();
        assert!(e.contains("the SHRM grid") && e.contains("texels"), "{e}");
    }
}
