//! The `prtkit.sh` document: SH coefficients of an environment map (`docs/formats/sh.md`).

use super::ShCoeffs;
use crate::io::document::{parse_validated, read_document, BundleError, Document, DocumentError, Validate};
use crate::limits;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Document kind.
pub const FORMAT: &str = "prtkit.sh";
/// Schema version.
pub const VERSION: u32 = 1;

/// Where the coefficients came from.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SourceMap {
    /// Input path.
    pub path: String,
    /// Layout used.
    pub layout: String,
    /// Width of the (first) image.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Highest order the map resolves.
    pub max_order: usize,
}

/// How the order was chosen.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct OrderSelection {
    /// `"order"` (given) or `"epsilon"` (smallest order capturing 1 − ε of the energy, R&H §5.1).
    pub method: String,
    /// The requested ε, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon: Option<f64>,
    /// 1 − (energy in bands 0..=order)/(total energy of the map): the ε actually achieved.
    pub epsilon_achieved: f64,
    /// With `"epsilon"`: the luminance at which compact bright sources were clipped before ε was
    /// measured (`docs/sh-project.md`), and the ε achieved on that clipped map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clipped_at: Option<f64>,
    /// The ε achieved on the clipped map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon_achieved_clipped: Option<f64>,
}

/// How the images written beside the document were synthesized from the (raw) coefficients.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Synthesis {
    /// The window applied to the reconstruction's bands: none, hann, lanczos, sigma or nonneg.
    pub window: crate::sh::window::Window,
    /// The window applied to the irradiance map's bands.
    #[serde(default)]
    pub irradiance_window: crate::sh::window::Window,
    /// Lat-long size [W, H].
    pub size: [usize; 2],
    /// The heat parameter t of exp(−t·l(l+1)) the non-negativity guard multiplied the window by
    /// for the reconstruction (0: the window alone was non-negative; absent for `none`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reconstruction_t: Option<f64>,
    /// The same for the irradiance map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub irradiance_t: Option<f64>,
}

/// Body of a `prtkit.sh` document.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ShBody {
    /// Highest band F.
    pub order: usize,
    /// (F+1)² RGB triples indexed by l(l+1)+m.
    pub coefficients: Vec<[f64; 3]>,
    /// Σ_m Σ_rgb L_lm² per band l.
    pub band_energy: Vec<f64>,
    /// ∫ |L|² dΩ of the map, summed over RGB (Parseval's total).
    pub total_energy: f64,
    /// Order selection.
    pub selection: OrderSelection,
    /// The input map.
    pub source: SourceMap,
    /// How the reconstruction and irradiance images were made, when written.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub synthesis: Option<Synthesis>,
}

impl ShBody {
    /// The coefficients as [`ShCoeffs`].
    pub fn coeffs(&self) -> ShCoeffs {
        ShCoeffs { order: self.order, rgb: self.coefficients.clone() }
    }
}

/// The checks every `prtkit.sh` loader gets: the order within [`limits::MAX_SH_ORDER`]
/// (before (F+1)² is formed: at 2³² − 1 it wraps), (F+1)² finite coefficients.
impl Validate for ShBody {
    fn validate(&self) -> Result<(), (&'static str, String)> {
        limits::check_sh_order("the order", self.order).map_err(|e| ("order", e.to_string()))?;
        let want = super::count(self.order);
        if self.coefficients.len() != want {
            return Err((
                "coefficients",
                format!("order {} needs {want} coefficients, the document has {}", self.order, self.coefficients.len()),
            ));
        }
        if self.coefficients.iter().flatten().any(|v| !v.is_finite()) {
            return Err(("coefficients", "coefficients must be finite numbers".into()));
        }
        Ok(())
    }
}

/// Parses a `prtkit.sh` document and checks it ([`Validate`]): errors carry line and column.
pub fn parse(text: &str) -> Result<Document<ShBody>, DocumentError> {
    parse_validated(text, FORMAT, VERSION)
}

/// Reads and checks the `prtkit.sh` document at `path` (at most
/// [`limits::max_document_bytes`]); errors name the file, line and column.
pub fn read(path: &Path) -> Result<Document<ShBody>, BundleError> {
    read_document(path, FORMAT, VERSION)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn doc(order: &str, coefficients: &str) -> String {
        format!(
            r#"{{"format": "prtkit.sh", "version": 1,
  "conventions": {{"frame": "f", "sh": "s"}},
  "provenance": {{"tool": "t", "stage": "s", "args": []}},
  "order": {order},
  "coefficients": {coefficients},
  "band_energy": [], "total_energy": 1,
  "selection": {{"method": "order", "epsilon_achieved": 0}},
  "source": {{"path": "p", "layout": "latlong", "width": 2, "height": 1, "max_order": 0}}
}}"#
        )
    }

    #[test]
    fn absurd_orders_are_refused_with_their_position() {
        assert!(parse(&doc("0", "[[1, 2, 3]]")).is_ok());
        // (2^32 - 1 + 1)^2 wraps to 0 in 32 bits: it used to pass the count check and panic later.
        let e = parse(&doc("4294967295", "[]")).unwrap_err();
        assert_eq!((e.line, e.column), (4, 3), "{e}");
        assert!(e.reason.contains("4294967295") && e.reason.contains("ceiling"), "{e}");
        let e = parse(&doc("18446744073709551615", "[]")).unwrap_err().to_string();
        assert!(e.contains("ceiling"), "{e}");
        let e = parse(&doc("1", "[[1, 2, 3]]")).unwrap_err().to_string();
        assert!(e.starts_with("line 5, column 3: \"coefficients\": order 1 needs 4"), "{e}");
        let e = parse(&doc("-1", "[]")).unwrap_err();
        assert_eq!(e.line, 4, "{e}");
    }
}
