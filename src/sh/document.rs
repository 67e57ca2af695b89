//! The `prtkit.sh` document: SH coefficients of an environment map (`docs/formats/sh.md`).

use super::ShCoeffs;
use crate::io::document::{parse_document, Document};
use serde::{Deserialize, Serialize};

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
    /// The window applied to the bands: none, hann, lanczos, sigma or nonneg.
    pub window: crate::sh::window::Window,
    /// Lat-long size [W, H].
    pub size: [usize; 2],
    /// For `nonneg`: the heat parameter t of exp(−t·l(l+1)) the reconstruction needed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reconstruction_t: Option<f64>,
    /// For `nonneg`: the t the irradiance map needed.
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

/// Parses a `prtkit.sh` document and checks that its coefficient count matches its order.
pub fn parse(text: &str) -> Result<Document<ShBody>, String> {
    let doc: Document<ShBody> = parse_document(text, FORMAT, VERSION)?;
    let want = super::count(doc.body.order);
    if doc.body.coefficients.len() != want {
        return Err(format!(
            "order {} needs {want} coefficients, the document has {}",
            doc.body.order,
            doc.body.coefficients.len()
        ));
    }
    if doc.body.coefficients.iter().flatten().any(|v| !v.is_finite()) {
        return Err("coefficients must be finite numbers".into());
    }
    Ok(doc)
}
