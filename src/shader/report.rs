//! Statistics of a sampled shader: bound widths per pixel (median, 95th percentile, maximum),
//! the error histogram of the paper's Fig. 3, node and evaluation counts, and a check of the
//! bounds against random point evaluations inside every leaf.

use super::sampler::{point_value, Domain, Node, Raster, Sampled};
use super::{Shader, ShaderError};
use crate::rng::SplitMix64;
use rayon::prelude::*;
use serde::{Deserialize, Deserializer, Serialize};

/// Bin width of the error histogram (Fig. 3 uses 0 … 0.5).
pub const HISTOGRAM_BIN: f64 = 0.025;
/// Bins of the error histogram below 0.5; wider errors go to `overflow`.
pub const HISTOGRAM_BINS: usize = 20;

/// Width statistics over pixels (the width of a pixel is the largest channel's upper − lower).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct WidthStats {
    /// Median (`null` in JSON when unbounded).
    #[serde(deserialize_with = "null_as_infinity")]
    pub median: f64,
    /// 95th percentile (`null` in JSON when unbounded).
    #[serde(deserialize_with = "null_as_infinity")]
    pub p95: f64,
    /// Maximum (`null` in JSON when unbounded).
    #[serde(deserialize_with = "null_as_infinity")]
    pub max: f64,
    /// Mean over the pixels with finite width.
    pub mean: f64,
}

/// Reads a width back: JSON has no infinity, so serde_json writes an unbounded width (∞; NaN
/// widths are counted as ∞ by [`width_stats`]) as `null`, and `null` reads back as ∞.
pub(crate) fn null_as_infinity<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}

/// Error histogram (Fig. 3): pixel counts per width bin.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Histogram {
    /// Bin width.
    pub bin_width: f64,
    /// Counts for [k·w, (k+1)·w).
    pub counts: Vec<u64>,
    /// Pixels with width ≥ bins·w (including unbounded ones).
    pub overflow: u64,
}

/// Per-pixel widths (max over channels).
pub fn pixel_widths(r: &Raster) -> Vec<f64> {
    r.bound_width.iter().map(|w| w[0].max(w[1]).max(w[2])).collect()
}

/// Nearest-rank percentile of sorted data (q in [0, 1]).
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let rank = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len());
    sorted[rank - 1]
}

/// Median, p95, max and mean of per-pixel widths.
pub fn width_stats(widths: &[f64]) -> WidthStats {
    let mut s: Vec<f64> = widths.iter().map(|w| if w.is_nan() { f64::INFINITY } else { *w }).collect();
    s.sort_by(f64::total_cmp);
    let finite: Vec<f64> = s.iter().copied().filter(|w| w.is_finite()).collect();
    let mean = if finite.is_empty() { 0.0 } else { finite.iter().sum::<f64>() / finite.len() as f64 };
    WidthStats { median: percentile(&s, 0.5), p95: percentile(&s, 0.95), max: s.last().copied().unwrap_or(0.0), mean }
}

/// Histogram of per-pixel widths.
pub fn histogram(widths: &[f64]) -> Histogram {
    let mut counts = vec![0u64; HISTOGRAM_BINS];
    let mut overflow = 0;
    for &w in widths {
        let k = (w / HISTOGRAM_BIN).floor();
        if k >= 0.0 && k < HISTOGRAM_BINS as f64 {
            counts[k as usize] += 1;
        } else {
            overflow += 1;
        }
    }
    Histogram { bin_width: HISTOGRAM_BIN, counts, overflow }
}

/// Leaves per depth.
pub fn depth_histogram(leaves: &[Node], max_depth: u32) -> Vec<u64> {
    let mut h = vec![0u64; max_depth as usize + 1];
    for l in leaves {
        h[(l.depth as usize).min(max_depth as usize)] += 1;
    }
    h
}

/// Result of checking bounds against point evaluations.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Verification {
    /// Leaves checked (all of them).
    pub leaves: usize,
    /// Point evaluations.
    pub points: u64,
    /// Points whose value lies outside their leaf's bounds.
    pub violations: u64,
}

/// Evaluates `points_per_leaf` uniform random points (and the four corners) inside every leaf and
/// counts values outside the leaf's bounds (per channel).
pub fn verify(
    shader: &Shader,
    sampled: &Sampled,
    domain: Domain,
    points_per_leaf: usize,
    seed: u64,
) -> Result<Verification, ShaderError> {
    let per_leaf: Vec<Result<u64, ShaderError>> = sampled
        .leaves
        .par_iter()
        .map(|leaf| {
            let (u, v) = leaf.extent();
            let mut rng = SplitMix64::keyed(&[seed, 0xC0FFEE, leaf.depth as u64, leaf.ix as u64, leaf.iy as u64]);
            let mut bad = 0u64;
            for k in 0..points_per_leaf + 4 {
                let (pu, pv) = if k < 4 {
                    (u[k & 1], v[k >> 1])
                } else {
                    (u[0] + (u[1] - u[0]) * rng.next_f64(), v[0] + (v[1] - v[0]) * rng.next_f64())
                };
                let ci = point_value(shader, domain, pu, pv, u[1] - u[0], v[1] - v[0])?;
                if (0..3).any(|c| !(ci[c] >= leaf.lo[c] && ci[c] <= leaf.hi[c])) {
                    bad += 1;
                }
            }
            Ok(bad)
        })
        .collect();
    let mut violations = 0;
    for r in per_leaf {
        violations += r?;
    }
    Ok(Verification {
        leaves: sampled.leaves.len(),
        points: sampled.leaves.len() as u64 * (points_per_leaf as u64 + 4),
        violations,
    })
}
