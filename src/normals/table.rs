//! Reproduction of Meyer et al. 2010, Table 1 at any budget: for every scheme the spacing
//! `ε(b)`, the closed-form `Δmax(b)`, and the measured maximum and mean angular error over
//! uniformly random directions plus the adversarial directions of [`super::adversarial`]; and
//! the FPNV rows (§3): the worst error of floats with `m`-bit mantissas against eq. 3.
//!
//! Random directions come in fixed chunks seeded by `(seed, chunk)`, every chunk's statistics
//! are computed independently and merged in chunk order: the table is identical for any number
//! of threads.

use super::bounds;
use super::fpnv::{self, FloatFormat};
use super::metrics::angle_between;
use super::metrics::ErrorStats;
use super::{adversarial, Codec, NormalsError, Scheme};
use crate::progress::Progress;
use crate::rng::SplitMix64;
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Directions per chunk (the unit of determinism and of progress).
const CHUNK: u64 = 1 << 16;

/// One row of the table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// `onv-range`, `onv-domain`, `sc`, `pp`, `spp`, `cm` or `fpnv`.
    pub scheme: String,
    /// Total bits per normal (three floats for `fpnv`).
    pub bits: u32,
    /// How the bits are split ([`Codec::split_text`]), e.g. `v:2^24 u:2^24 = 24+24 bits` or
    /// `3 x binary16 (m=10)`.
    pub split: String,
    /// Sample spacing `ε` in the paper's units (`bounds::spacing`; for `fpnv` the cell size
    /// `2^(-m-1)` at `[1/2, 1)`).
    pub spacing: f64,
    /// Closed-form maximum angular error (radians).
    pub bound: f64,
    /// Measured maximum angular error, random and adversarial directions (radians).
    pub max_error: f64,
    /// Mean angular error over the random directions (radians).
    pub mean_error: f64,
    /// RMS angular error over the random directions (radians).
    pub rms_error: f64,
    /// Maximum over the random directions alone.
    pub random_max_error: f64,
    /// Maximum over the adversarial directions alone.
    pub adversarial_max_error: f64,
    /// `max_error / bound`.
    pub max_over_bound: f64,
    /// Number of random directions.
    pub samples: u64,
    /// Number of adversarial directions.
    pub adversarial_samples: u64,
    /// FPNV only: the worst error of *unit* vectors (random and adversarial unit vectors can
    /// not reach eq. 3's direction-vector worst case).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit_vector_max_error: Option<f64>,
    /// FPNV only: eq. 4, the bits a uniform discretization needs for the same error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub equivalent_bits: Option<u32>,
    /// FPNV only: the smallest budget whose closed-form ONV_range bound is at most this row's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub onv_range_bits_needed: Option<u32>,
    /// FPNV only: measured ONV_range maximum at `onv_range_bits_needed - 1`, `..`, `+ 1` bits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub onv_range_measured: Option<Vec<(u32, f64)>>,
}

/// Options of a table run.
#[derive(Clone, Copy, Debug)]
pub struct TableConfig {
    /// Budget (8..=64).
    pub bits: u32,
    /// Number of random directions (rounded up to whole chunks of 65536).
    pub samples: u64,
    /// Seed of the random directions.
    pub seed: u64,
}

/// Meyer et al. 2010, Table 1, row 3: the printed `Δmax(48)` of each scheme (`fpnv`: three
/// binary16 values).
pub fn paper_48(scheme: &str) -> Option<f64> {
    Some(match scheme {
        "fpnv" => 4.60e-4,
        "pp" => 4.88e-4,
        "spp" => 2.92e-7,
        "sc" => 3.74e-7,
        "cm" => 2.38e-7,
        "onv-domain" => 2.53e-7,
        "onv-range" => 1.69e-7,
        _ => return None,
    })
}

/// Computes the table for one budget (the `--table` mode of `encode-normals`).
pub fn run(config: &TableConfig, progress: &dyn Progress) -> Result<Vec<Row>, NormalsError> {
    let codecs: Vec<Codec> = Scheme::ALL.iter().map(|&s| Codec::new(s, config.bits)).collect::<Result<_, _>>()?;
    let mut formats: Vec<FloatFormat> = fpnv::format_for_budget(config.bits).into_iter().collect();
    if !formats.contains(&fpnv::BINARY32) {
        formats.push(fpnv::BINARY32);
    }
    let chunks = config.samples.div_ceil(CHUNK).max(1);
    progress.start("random directions", chunks);
    let per_chunk: Vec<(Vec<ErrorStats>, Vec<ErrorStats>)> = (0..chunks)
        .into_par_iter()
        .map(|chunk| {
            let mut state = SplitMix64::for_chunk(config.seed, chunk);
            let dirs: Vec<DVec3> = (0..CHUNK).map(|_| state.direction()).collect();
            let base = chunk * CHUNK;
            let schemes = codecs.iter().map(|codec| measure(codec, &dirs, base)).collect();
            let floats = formats
                .iter()
                .map(|f| {
                    let mut s = ErrorStats::default();
                    for (i, d) in dirs.iter().enumerate() {
                        s.add(base + i as u64, fpnv::error(*d, f.mantissa_bits));
                    }
                    s
                })
                .collect();
            progress.advance(1);
            (schemes, floats)
        })
        .collect();
    progress.finish();
    let mut scheme_stats = vec![ErrorStats::default(); codecs.len()];
    let mut float_stats = vec![ErrorStats::default(); formats.len()];
    for (s, f) in &per_chunk {
        for (total, part) in scheme_stats.iter_mut().zip(s) {
            total.merge(part);
        }
        for (total, part) in float_stats.iter_mut().zip(f) {
            total.merge(part);
        }
    }

    let mut rows = Vec::new();
    for (codec, stats) in codecs.iter().zip(&scheme_stats) {
        let adv = adversarial::directions(codec);
        let adv_max = max_error(codec, &adv);
        let bound = codec.bound();
        let max = stats.max.max(adv_max);
        rows.push(Row {
            scheme: codec.scheme().name().to_string(),
            bits: config.bits,
            split: codec.split_text(),
            spacing: codec.spacing(),
            bound,
            max_error: max,
            mean_error: stats.mean(),
            rms_error: stats.rms(),
            random_max_error: stats.max,
            adversarial_max_error: adv_max,
            max_over_bound: max / bound,
            samples: stats.count,
            adversarial_samples: adv.len() as u64,
            unit_vector_max_error: None,
            equivalent_bits: None,
            onv_range_bits_needed: None,
            onv_range_measured: None,
        });
    }
    for (format, stats) in formats.iter().zip(&float_stats) {
        rows.push(fpnv_row(*format, stats, config.seed)?);
    }
    Ok(rows)
}

fn fpnv_row(format: FloatFormat, stats: &ErrorStats, seed: u64) -> Result<Row, NormalsError> {
    let m = format.mantissa_bits;
    let adv = fpnv::adversarial_directions(m);
    let adv_max = adv.iter().map(|d| fpnv::error(*d, m)).fold(0.0, f64::max);
    let bound = bounds::fpnv(m);
    let max = stats.max.max(adv_max);
    let needed = bounds::bits_needed(Scheme::OnvRange, bound);
    let measured = match needed {
        Some(b) => {
            let mut v = Vec::new();
            for bits in b.saturating_sub(1).max(super::MIN_BITS)..=(b + 1).min(super::MAX_BITS) {
                v.push((bits, onv_range_max(bits, seed)?));
            }
            Some(v)
        }
        None => None,
    };
    Ok(Row {
        scheme: "fpnv".to_string(),
        bits: 3 * format.width,
        split: format!("3 x {} (m={m})", format.name),
        spacing: (-(m as f64) - 1.0).exp2(),
        bound,
        max_error: max,
        mean_error: stats.mean(),
        rms_error: stats.rms(),
        random_max_error: stats.max,
        adversarial_max_error: adv_max,
        max_over_bound: max / bound,
        samples: stats.count,
        adversarial_samples: adv.len() as u64,
        unit_vector_max_error: Some(stats.max),
        equivalent_bits: Some(bounds::fpnv_equivalent_bits(m)),
        onv_range_bits_needed: needed,
        onv_range_measured: measured,
    })
}

/// ONV_range's measured maximum at `bits`: adversarial directions plus 2^20 random ones.
fn onv_range_max(bits: u32, seed: u64) -> Result<f64, NormalsError> {
    let codec = Codec::new(Scheme::OnvRange, bits)?;
    let adv = max_error(&codec, &adversarial::directions(&codec));
    let random: f64 = (0..16u64)
        .into_par_iter()
        .map(|chunk| {
            let mut state = SplitMix64::for_chunk(seed ^ 0x5151, chunk);
            let dirs: Vec<DVec3> = (0..CHUNK).map(|_| state.direction()).collect();
            max_error(&codec, &dirs)
        })
        .collect::<Vec<f64>>()
        .into_iter()
        .fold(0.0, f64::max);
    Ok(adv.max(random))
}

/// The table as Markdown: one row per scheme (with the paper's `Δmax(48)` at 48 bits), then a
/// paragraph per FPNV row on eq. 3 and eq. 4.
pub fn markdown(rows: &[Row], config: &TableConfig) -> String {
    let paper_col = config.bits == 48;
    let mut s = format!(
        "### {} bits ({} random directions, seed {}, plus adversarial directions)\n\n",
        config.bits,
        rows.first().map_or(0, |r| r.samples),
        config.seed
    );
    s += "| scheme | bits | split | ε | closed-form Δmax | measured max | max / bound | random only / bound | mean | rms |";
    s += if paper_col { " paper Δmax(48) |\n" } else { "\n" };
    s += "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |";
    s += if paper_col { " --- |\n" } else { "\n" };
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {:.4e} | {:.4e} | {:.4e} | {:.6} | {:.4} | {:.4e} | {:.4e} |",
            r.scheme,
            r.bits,
            r.split,
            r.spacing,
            r.bound,
            r.max_error,
            r.max_over_bound,
            r.random_max_error / r.bound,
            r.mean_error,
            r.rms_error
        );
        if paper_col {
            s += &match paper_48(&r.scheme).filter(|_| r.bits == 48) {
                Some(p) => format!(" {p:.2e} |"),
                None => " |".to_string(),
            };
        }
        s += "\n";
    }
    for r in rows.iter().filter(|r| r.scheme == "fpnv") {
        s += &format!(
            "\nFPNV {} ({} bits): eq. 3 bound {:.4e}; adversarial direction vectors reach {:.4e}; random unit vectors {:.4e}.",
            r.split,
            r.bits,
            r.bound,
            r.adversarial_max_error,
            r.unit_vector_max_error.unwrap_or(0.0)
        );
        if let (Some(eq), Some(need)) = (r.equivalent_bits, r.onv_range_bits_needed) {
            s +=
                &format!(" Eq. 4: a uniform discretization needs {eq} bits; ONV_range's closed form needs {need} bits");
            if let Some(m) = &r.onv_range_measured {
                let parts: Vec<String> = m
                    .iter()
                    .map(|(b, e)| format!("{b} bits: {e:.4e} ({})", if *e <= r.bound { "≤ FPNV" } else { "> FPNV" }))
                    .collect();
                s += &format!("; measured ONV_range max: {}", parts.join(", "));
            }
            s += ".";
        }
        s += "\n";
    }
    s += "\n";
    s
}

/// Error statistics of encoding then decoding `dirs` (indices start at `base`).
pub fn measure(codec: &Codec, dirs: &[DVec3], base: u64) -> ErrorStats {
    let mut s = ErrorStats::default();
    for (i, d) in dirs.iter().enumerate() {
        s.add(base + i as u64, angle_between(*d, codec.decode(codec.encode(*d))));
    }
    s
}

/// The largest round-trip error over `dirs`.
pub fn max_error(codec: &Codec, dirs: &[DVec3]) -> f64 {
    dirs.iter().map(|d| angle_between(*d, codec.decode(codec.encode(*d)))).fold(0.0, f64::max)
}
