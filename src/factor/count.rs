//! Predicted versus measured term counts for a list of materials, and the CI check of
//! `count-terms` (`docs/count-terms.md`).

use super::predict::{self, Prediction};
use super::svd::{self, FactorError, Method, Sampling};
use super::Channel;
use crate::brdf::Brdf;
use crate::progress::Progress;

/// The singular-value curves of one material, for the left panel.
#[derive(Clone, Debug, Default)]
pub struct Spectrum {
    /// Legend label.
    pub label: String,
    /// Measured singular values, descending.
    pub measured: Vec<f64>,
    /// Predicted singular values (F_l repeated 2l+1 times on the sphere, l+1 on the hemisphere),
    /// empty when there is no prediction of σ itself.
    pub predicted: Vec<f64>,
}

/// One material to count.
#[derive(Clone, Debug)]
pub struct Material {
    /// Display name.
    pub name: String,
    /// The BRDF.
    pub brdf: Brdf,
    /// The scalar factored (a channel of RGB data).
    pub channel: Channel,
    /// Term budget (`--max-terms` or the manifest's).
    pub budget: Option<usize>,
}

/// What to compute for every material: the `count-terms` stage's config.
#[derive(Clone, Copy, Debug)]
pub struct CountConfig {
    /// Matrix sampling (its channel is each material's unless `per_channel` splits it).
    pub sampling: Sampling,
    /// One row per R, G, B channel for RGB (measured) materials, named NAME/r, NAME/g, NAME/b.
    pub per_channel: bool,
    /// Memory budget of one SVD in bytes.
    pub max_memory: u128,
    /// Energy fraction for K (default 0.99).
    pub energy: f64,
    /// Skip the SVD.
    pub predict_only: bool,
    /// SVD method.
    pub method: Method,
    /// Allowed |predicted − measured| / measured.
    pub tolerance: f64,
}

impl CountConfig {
    /// `sampling` with the stage's defaults: 99 % of the energy, a 25 % tolerance, the SVD
    /// method chosen by size, a 4 GiB budget per SVD, one row per material.
    pub fn new(sampling: Sampling) -> Self {
        CountConfig {
            sampling,
            per_channel: false,
            max_memory: 4 << 30,
            energy: 0.99,
            predict_only: false,
            method: Method::Auto,
            tolerance: 0.25,
        }
    }
}

/// One row of the table / JSON array.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Row {
    /// Material name.
    pub name: String,
    /// Canonical BRDF spec.
    pub brdf: String,
    /// Channel factored.
    pub channel: Channel,
    /// sphere / hemisphere.
    pub domain: super::Domain,
    /// Grid resolution n.
    pub resolution: usize,
    /// cos θ_i folded in.
    pub cosine: bool,
    /// Energy fraction.
    pub energy: f64,
    /// Predicted K (rounded up), null if no closed form applies.
    pub predicted_k: Option<usize>,
    /// Measured K from the SVD, null with --predict-only.
    pub measured_k: Option<usize>,
    /// The frequency cut-off behind the prediction.
    pub l_star: Option<usize>,
    /// Which closed form: `reflection-lobe` or `half-angle`.
    pub prediction: Option<predict::PredictionKind>,
    /// The rule used for l*, or why there is no prediction.
    pub rule: String,
    /// The paper's own number where it states one (Phong: 5s sphere, 2.5s hemisphere).
    pub paper_k: Option<f64>,
    /// The paper's printed shortcut l* ≈ 1/(2σ²), K = (l*)²/4 (Torrance-Sparrow only).
    pub paper_shortcut_k: Option<f64>,
    /// (predicted − measured)/measured.
    pub relative_difference: Option<f64>,
    /// The term budget.
    pub budget: Option<usize>,
    /// Reasons this material fails `--check` (empty = passes).
    pub failures: Vec<String>,
}

/// Predicts and (unless predict-only) measures K for one material; also returns the measured
/// and predicted singular values for plots.
pub fn count(
    material: &Material,
    config: &CountConfig,
    progress: &dyn Progress,
) -> Result<(Row, Spectrum), FactorError> {
    let sampling = Sampling { channel: material.channel, ..config.sampling };
    let prediction: Option<Prediction> =
        predict::predict(&material.brdf, sampling.domain, sampling.cosine, material.channel, config.energy);
    let predicted_k = prediction.as_ref().map(|p| p.predicted_k.ceil().max(1.0) as usize);
    let (singular_values, measured_k) = if config.predict_only {
        (vec![], None)
    } else {
        let f = if config.method == Method::Randomized {
            svd::factor_randomized(&material.brdf, &sampling, config.energy.max(svd::RANDOMIZED_TARGET), 0, progress)?
        } else {
            svd::factor(&material.brdf, &sampling, config.method, 0, progress)?
        };
        let k = f.terms_for(config.energy);
        (f.singular_values, Some(k))
    };
    let spectrum = Spectrum {
        label: material.name.clone(),
        measured: singular_values,
        predicted: prediction.as_ref().map_or(vec![], |p| predicted_singular_values(p, sampling.domain)),
    };
    let relative_difference = match (predicted_k, measured_k) {
        (Some(p), Some(m)) if m > 0 => Some((p as f64 - m as f64) / m as f64),
        _ => None,
    };
    let mut failures = Vec::new();
    if let Some(budget) = material.budget {
        match (measured_k, predicted_k) {
            (Some(m), _) if m > budget => failures.push(format!("measured K = {m} exceeds the budget of {budget}")),
            (None, Some(p)) if p > budget => failures.push(format!("predicted K = {p} exceeds the budget of {budget}")),
            _ => {}
        }
    }
    if let (Some(d), Some(p), Some(m)) = (relative_difference, predicted_k, measured_k) {
        if d.abs() > config.tolerance {
            failures.push(format!(
                "predicted K = {p} misses measured K = {m} by {:.0} % (tolerance {:.0} %)",
                100.0 * d.abs(),
                100.0 * config.tolerance
            ));
        }
    }
    let rule = match &prediction {
        Some(p) => p.rule.clone(),
        None => predict::no_prediction_reason(&material.brdf, sampling.domain, sampling.cosine).unwrap_or_default(),
    };
    let row = Row {
        name: material.name.clone(),
        brdf: material.brdf.spec(),
        channel: material.channel,
        domain: sampling.domain,
        resolution: sampling.resolution,
        cosine: sampling.cosine,
        energy: config.energy,
        predicted_k,
        measured_k,
        l_star: prediction.as_ref().map(|p| p.l_star),
        prediction: prediction.as_ref().map(|p| p.kind),
        rule,
        paper_k: predict::paper_phong_k(&material.brdf, sampling.domain),
        paper_shortcut_k: predict::paper_shortcut_k(&material.brdf),
        relative_difference,
        budget: material.budget,
        failures,
    };
    Ok((row, spectrum))
}

/// What `count-terms` produces.
#[derive(Clone, Debug)]
pub struct CountOutput {
    /// One row per material (per channel with `per_channel`).
    pub rows: Vec<Row>,
    /// Their singular-value curves, for plots.
    pub spectra: Vec<Spectrum>,
}

impl CountOutput {
    /// The rows that fail the check (a budget exceeded, a prediction off by more than the
    /// tolerance).
    pub fn failing(&self) -> impl Iterator<Item = &Row> {
        self.rows.iter().filter(|r| !r.failures.is_empty())
    }
}

/// Errors of `count-terms`, naming the material. The CLI (`cli/count_terms.rs`) words them with
/// the flags' names.
#[derive(Debug, thiserror::Error)]
pub enum CountError {
    /// No material was given.
    #[error("no material to count the terms of")]
    NoMaterial,
    /// The energy fraction is not in (0, 1).
    #[error("the energy fraction must be in (0, 1), got {0}")]
    Energy(f64),
    /// A material's factorization cannot run (method, memory budget) or failed.
    #[error("material {name}: {error}")]
    Material {
        /// The material.
        name: String,
        /// Why.
        error: FactorError,
    },
}

/// Runs `count-terms`: checks every material's memory budget before the first SVD, then
/// predicts and measures K for each (each channel of RGB materials with `per_channel`).
pub fn run(config: &CountConfig, materials: Vec<Material>, progress: &dyn Progress) -> Result<CountOutput, CountError> {
    if !(config.energy > 0.0 && config.energy < 1.0) {
        return Err(CountError::Energy(config.energy));
    }
    if materials.is_empty() {
        return Err(CountError::NoMaterial);
    }
    let mut expanded = Vec::new();
    for m in materials {
        let fail = |error| CountError::Material { name: m.name.clone(), error };
        if !config.predict_only {
            let method = svd::resolve_method(&m.brdf, config.method).map_err(fail)?;
            svd::check_budget(&config.sampling, method, 0, config.max_memory).map_err(fail)?;
        }
        if config.per_channel && m.brdf.is_rgb() {
            for (suffix, channel) in [("r", Channel::R), ("g", Channel::G), ("b", Channel::B)] {
                expanded.push(Material { name: format!("{}/{suffix}", m.name), channel, ..m.clone() });
            }
        } else {
            expanded.push(m);
        }
    }
    let (mut rows, mut spectra) = (Vec::new(), Vec::new());
    for m in &expanded {
        let (row, spectrum) =
            count(m, config, progress).map_err(|error| CountError::Material { name: m.name.clone(), error })?;
        rows.push(row);
        spectra.push(spectrum);
    }
    Ok(CountOutput { rows, spectra })
}

/// The singular values a reflection-lobe prediction implies: |F_l| repeated 2l+1 times on the
/// sphere (eq. 9) and l+1 times on the hemisphere (Fig. 5), sorted descending. Half-angle
/// predictions give l* only, not σ.
pub fn predicted_singular_values(p: &Prediction, domain: super::Domain) -> Vec<f64> {
    if p.kind != predict::PredictionKind::ReflectionLobe {
        return vec![];
    }
    let mut out = Vec::new();
    for (l, f) in p.spectrum.iter().enumerate() {
        let repeat = match domain {
            super::Domain::Sphere => 2 * l + 1,
            super::Domain::Hemisphere => l + 1,
        };
        out.extend(std::iter::repeat_n(f.abs(), repeat));
    }
    out.sort_by(|a, b| b.total_cmp(a));
    out
}

/// The rows as a Markdown (GitHub) pipe table, readable in a terminal too.
pub fn markdown_table(rows: &[Row]) -> String {
    let opt = |v: Option<usize>| v.map_or("-".to_string(), |v| v.to_string());
    let mut out = String::from(
        "| material | brdf | channel | domain | n | l* | predicted K | measured K | difference | paper | budget | check |\n\
         | --- | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n",
    );
    for r in rows {
        let paper = match (r.paper_k, r.paper_shortcut_k) {
            (Some(k), _) => format!("{k:.1}"),
            (None, Some(k)) => format!("{k:.1} (shortcut)"),
            _ => "-".into(),
        };
        out.push_str(&format!(
            "| {} | `{}` | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.name,
            r.brdf,
            r.channel,
            r.domain,
            r.resolution,
            opt(r.l_star),
            opt(r.predicted_k),
            opt(r.measured_k),
            r.relative_difference.map_or("-".into(), |d| format!("{:+.0} %", 100.0 * d)),
            paper,
            opt(r.budget),
            if r.failures.is_empty() { "ok".to_string() } else { r.failures.join("; ") },
        ));
    }
    out
}
