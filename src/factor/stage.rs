//! The `factor-brdf` stage as one library call: the in-out SVD of one BRDF (Mahajan, Tseng &
//! Ramamoorthi 2008): singular values, energy curve, K at 90/95/99/99.9 %, reconstruction
//! error, and the leading factors as maps and as the factor file `render` relights with.

use super::document::{factor_layers, FactorBody, FactorsFile, Reconstruction, FORMAT, LAYOUT, VERSION};
use super::{energy, maps, svd, Domain, FactorError, Method, Sampling};
use crate::brdf::Brdf;
use crate::io::{Document, Provenance, RgbImage};
use crate::progress::Progress;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// What `factor-brdf` computes.
#[derive(Clone, Debug)]
pub struct Config {
    /// How the matrix is sampled.
    pub sampling: Sampling,
    /// SVD method.
    pub method: Method,
    /// Leading terms kept for the maps and the factor file (0: none).
    pub terms: usize,
    /// Draw the factor maps.
    pub maps: bool,
    /// The directory the maps go to, recorded in the document.
    pub maps_dir: Option<String>,
    /// The factor file's name, recorded in the document; `None`: no factor file.
    pub factors_file: Option<String>,
    /// Memory budget of the SVD in bytes.
    pub max_memory: u128,
    /// The command line, for the document's provenance.
    pub args: Vec<String>,
}

/// The leading factors sampled on the grid: two grey layers, n wide and K·n high
/// (`docs/formats/factor.md`).
#[derive(Clone, Debug)]
pub struct FactorLayers {
    /// n.
    pub width: usize,
    /// K·n.
    pub height: usize,
    /// g_k, tile after tile.
    pub g: Vec<f32>,
    /// h_k, tile after tile.
    pub h: Vec<f32>,
}

/// What `factor-brdf` produces.
#[derive(Debug)]
pub struct Output {
    /// The `prtkit.factor` document.
    pub document: Document<FactorBody>,
    /// The factor file's layers, if asked.
    pub factors: Option<FactorLayers>,
    /// The factor maps as named layers and a contact sheet, if asked.
    pub maps: Option<(Vec<(String, RgbImage)>, RgbImage)>,
    /// The `--json` summary.
    pub summary: Summary,
}

/// The machine-readable summary (`factor-brdf --json`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    /// Canonical BRDF spec.
    pub brdf: String,
    /// sphere / hemisphere.
    pub domain: Domain,
    /// n.
    pub resolution: usize,
    /// The method used.
    pub method: Method,
    /// K per energy fraction.
    pub terms: BTreeMap<String, usize>,
}

/// Errors of the stage.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Factor maps or a factor file asked for with no term.
    #[error("factor maps and factor files need at least 1 term")]
    NoTerms,
    /// The factorization failed (method, memory budget, numerics).
    #[error(transparent)]
    Factor(#[from] FactorError),
}

/// Percent label of an energy fraction: 0.999 → "99.9%".
pub fn percent_label(f: f64) -> String {
    let p = (f * 1000.0).round() / 10.0;
    if p.fract() == 0.0 {
        format!("{}%", p as i64)
    } else {
        format!("{p}%")
    }
}

/// Runs `factor-brdf` on `brdf`.
pub fn run(config: &Config, brdf: &Brdf, progress: &dyn Progress) -> Result<Output, Error> {
    let sampling = config.sampling;
    let wants_factors = config.maps || config.factors_file.is_some();
    let terms = if wants_factors { config.terms.min(sampling.grid().len()) } else { 0 };
    if wants_factors && terms == 0 {
        return Err(Error::NoTerms);
    }
    let method = svd::resolve_method(brdf, config.method)?;
    svd::check_budget(&sampling, method, terms, config.max_memory)?;
    let f = svd::factor(brdf, &sampling, method, terms, progress)?;
    let cumulative = f.cumulative_energy();
    let mut term_counts = BTreeMap::new();
    let mut ks: Vec<usize> = Vec::new();
    for fraction in energy::STANDARD_FRACTIONS {
        let k = f.terms_for(fraction);
        term_counts.insert(percent_label(fraction), k);
        ks.push(k);
    }
    if terms > 0 {
        ks.push(terms);
    }
    ks.sort_unstable();
    ks.dedup();
    let reconstruction = ks
        .into_iter()
        .map(|k| Reconstruction {
            terms: k,
            energy: if k == 0 { 0.0 } else { cumulative.get(k - 1).copied().unwrap_or(1.0) },
            relative_frobenius_error: f.reconstruction_error(k),
        })
        .collect();
    let factors = config.factors_file.as_ref().map(|_| {
        let (width, height, g, h) = factor_layers(&f, terms);
        FactorLayers { width, height, g, h }
    });
    let maps = config.maps.then(|| (maps::layers(&f), maps::contact_sheet(&f)));
    let body = FactorBody {
        brdf: brdf.spec(),
        domain: sampling.domain,
        resolution: sampling.resolution,
        directions_per_side: sampling.grid().len(),
        cosine: sampling.cosine,
        channel: sampling.channel,
        method: f.method,
        matrix: format!(
            "M[o,i] = rho(w_i, w_o){} * dOmega, dOmega = {}/n^2; n x n cells uniform in cos(theta) and phi, samples at bin midpoints; direction index = j*n + k (j: cos(theta) bin from the pole, k: phi bin)",
            if sampling.cosine { " * max(cos(theta_i), 0)" } else { "" },
            if sampling.domain == Domain::Sphere { "4 pi" } else { "2 pi" }
        ),
        total_energy: f.total_energy,
        singular_values: f.singular_values.clone(),
        cumulative_energy: cumulative,
        terms: term_counts.clone(),
        reconstruction,
        azimuthal_frequency: f.azimuthal_frequency.clone(),
        maps: config.maps_dir.clone(),
        factors: config.factors_file.as_ref().zip(factors.as_ref()).map(|(file, layers)| FactorsFile {
            file: file.clone(),
            terms: layers.height / layers.width.max(1),
            layout: LAYOUT.into(),
        }),
    };
    let inputs = match brdf {
        Brdf::Merl(m) => vec![m.path().display().to_string()],
        _ => vec![],
    };
    let document = Document::new(FORMAT, VERSION, Provenance::new("factor-brdf", &config.args, inputs), body);
    let summary = Summary {
        brdf: brdf.spec(),
        domain: sampling.domain,
        resolution: sampling.resolution,
        method: f.method,
        terms: term_counts,
    };
    Ok(Output { document, factors, maps, summary })
}
