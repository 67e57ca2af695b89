//! The `prtkit.factor` document (`docs/formats/factor.md`) and the factor file it may name: the
//! leading g_k and h_k sampled on the grid, so `render --factors` relights with exactly the
//! factorization `factor-brdf` computed instead of recomputing it.
//!
//! The factor file is an EXR with two grey layers, `g` and `h`, each n pixels wide and K·n
//! high: term k is the n×n tile at rows k·n … k·n + n − 1, row j the cos θ bin (from the pole),
//! column the φ bin — the grid's direction index j·n + column, read in raster order. Values are
//! the L²-normalized factors (Σ g² ΔΩ = 1) as 32-bit floats; σ_k stay in the JSON.

use super::{Channel, Domain, Factorization, Grid, Method};
use crate::io;
use crate::io::document::{read_document, read_named_layers, BundleError, Validate};
use crate::limits;
use std::collections::BTreeMap;
use std::path::Path;

/// Document kind.
pub const FORMAT: &str = "prtkit.factor";
/// Schema version.
pub const VERSION: u32 = 1;

/// The checks every loader of a `prtkit.factor` document gets: the resolution n in
/// 2..=[`limits::MAX_FACTOR_RESOLUTION`] (before n² is formed), n² directions per side, at most
/// n² stored terms whose tiles fit the memory budget, finite singular values and energy.
impl Validate for FactorBody {
    fn validate(&self) -> Result<(), (&'static str, String)> {
        let n = self.resolution;
        if n < 2 {
            return Err(("resolution", format!("resolution {n} must be at least 2")));
        }
        limits::check_count(
            "the resolution",
            n,
            limits::MAX_FACTOR_RESOLUTION,
            "the finest grid factor-brdf can factor",
        )
        .map_err(|e| ("resolution", e.to_string()))?;
        if self.directions_per_side != n * n {
            return Err((
                "directions_per_side",
                format!("resolution {n} and directions_per_side {} disagree", self.directions_per_side),
            ));
        }
        if !self.total_energy.is_finite() || self.singular_values.iter().any(|s| !s.is_finite()) {
            return Err(("singular_values", "singular values and total energy must be finite numbers".into()));
        }
        if let Some(f) = &self.factors {
            limits::check_count("the stored terms", f.terms, n * n, "a factorization has at most n² terms")
                .map_err(|e| ("terms", e.to_string()))?;
            // Two grey layers of n × K·n texels, read as RGB f32 and kept as f64.
            let bytes = 2 * (f.terms * n * n) as u128 * (limits::RGB_BYTES_PER_TEXEL as u128 + 8);
            limits::check_memory("loading the factors", bytes).map_err(|e| ("terms", e.to_string()))?;
        }
        Ok(())
    }
}

/// The body of a `prtkit.factor` document.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub struct FactorBody {
    /// Canonical BRDF spec.
    pub brdf: String,
    /// sphere / hemisphere.
    pub domain: Domain,
    /// Grid resolution n.
    pub resolution: usize,
    /// n².
    pub directions_per_side: usize,
    /// cos θ_i folded in.
    pub cosine: bool,
    /// Channel factored.
    pub channel: Channel,
    /// fft or dense.
    pub method: Method,
    /// How the matrix is built.
    pub matrix: String,
    /// Σ σ².
    pub total_energy: f64,
    /// σ_k descending (the leading ones only for the randomized method).
    pub singular_values: Vec<f64>,
    /// Entry k: energy fraction of the first k+1 terms.
    pub cumulative_energy: Vec<f64>,
    /// K reaching 90 %, 95 %, 99 %, 99.9 % of the energy.
    pub terms: BTreeMap<String, usize>,
    /// Relative Frobenius error of K-term reconstructions.
    pub reconstruction: Vec<Reconstruction>,
    /// Azimuthal frequency m of each singular value (fft method only).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub azimuthal_frequency: Vec<usize>,
    /// Where the maps went, if written.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub maps: Option<String>,
    /// The factor file, if written (`--factors`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub factors: Option<FactorsFile>,
}

/// Error of a K-term reconstruction.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub struct Reconstruction {
    /// K.
    pub terms: usize,
    /// Energy fraction of those terms.
    pub energy: f64,
    /// ‖M − M_K‖_F / ‖M‖_F = √(1 − energy) (Eckart–Young).
    pub relative_frobenius_error: f64,
}

/// The factor file named by a document.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct FactorsFile {
    /// Path of the EXR as given on the command line.
    pub file: String,
    /// Number of terms K stored.
    pub terms: usize,
    /// How the samples are laid out, in words.
    pub layout: String,
}

/// The layout sentence recorded in documents.
pub const LAYOUT: &str = "grey layers g and h, n wide and K*n high: term k is rows k*n..k*n+n-1, row j = cos(theta) bin from the pole, column = phi bin; L2-normalized factors";

/// Errors of reading a factorization back: the document/EXR pair's errors.
pub type FactorLoadError = BundleError;

/// The first `terms` factors of `f` as the two layers of the factor file: (width, height, g, h).
pub fn factor_layers(f: &Factorization, terms: usize) -> (usize, usize, Vec<f32>, Vec<f32>) {
    let n = f.grid.n;
    let k = terms.min(f.g.len()).min(f.h.len());
    let flat = |v: &[Vec<f64>]| -> Vec<f32> { v[..k].iter().flatten().map(|&x| x as f32).collect() };
    (n, k * n, flat(&f.g), flat(&f.h))
}

/// Reads a `prtkit.factor` document and the factor file it names (relative to the document's
/// directory when the recorded path does not exist as given), checking the tile size against
/// the document's resolution. The factors come back as f64 (they were stored as f32).
pub fn load(doc_path: &Path) -> Result<(FactorBody, Factorization), FactorLoadError> {
    io::read::refuse_stdin(doc_path, "a factor document")?;
    let bad = |reason: String| FactorLoadError::Document { path: doc_path.into(), reason };
    let body = read_document::<FactorBody>(doc_path, FORMAT, VERSION)?.body;
    let entry = body.factors.clone().ok_or_else(|| {
        bad("the document names no factor file; run factor-brdf with --factors FILE.exr --terms K".into())
    })?;
    let n = body.resolution;
    let (exr, layers) = read_named_layers(doc_path, &entry.file, "factor file")?;
    let mismatch = |reason: String| FactorLoadError::Mismatch { exr: exr.clone(), doc: doc_path.into(), reason };
    let mut tiles = Vec::with_capacity(2);
    for name in ["g", "h"] {
        let img = &layers.iter().find(|(l, _)| l == name).ok_or_else(|| mismatch(format!("no layer {name}")))?.1;
        if img.width != n || img.height % n != 0 {
            return Err(mismatch(format!(
                "layer {name} is {}x{}, not tiles of {n}x{n}: a factorization of another resolution than the document's n = {n}",
                img.width, img.height
            )));
        }
        if img.height != entry.terms * n {
            return Err(mismatch(format!(
                "layer {name} holds {} terms, the document says {}",
                img.height / n,
                entry.terms
            )));
        }
        let values: Vec<f64> = img.pixels.iter().map(|p| p[0] as f64).collect();
        if values.iter().any(|v| !v.is_finite()) {
            return Err(mismatch(format!("non-finite values in layer {name}")));
        }
        tiles.push(values.chunks(n * n).map(<[f64]>::to_vec).collect::<Vec<_>>());
    }
    if body.singular_values.len() < entry.terms {
        return Err(bad(format!(
            "{} singular values listed, the factor file holds {} terms",
            body.singular_values.len(),
            entry.terms
        )));
    }
    let h = tiles.pop().unwrap_or_default();
    let g = tiles.pop().unwrap_or_default();
    let f = Factorization {
        singular_values: body.singular_values.clone(),
        total_energy: body.total_energy,
        method: body.method,
        grid: Grid { n, domain: body.domain },
        g,
        h,
        azimuthal_frequency: body.azimuthal_frequency.clone(),
    };
    Ok((body, f))
}
