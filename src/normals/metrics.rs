//! Error metrics: angular error `atan2(|a×b|, a·b)` (see [`super::vec::angle_between`]) and
//! its statistics, reduced in a fixed order so results do not depend on the thread count.

use super::vec::{angle_between, Dir};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Max, mean and RMS of a set of angular errors (radians).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    /// Number of samples.
    pub count: u64,
    /// Largest error.
    pub max: f64,
    /// Index of the (first) largest error.
    pub max_index: u64,
    /// Sum of errors (kept for merging).
    #[serde(skip)]
    pub sum: f64,
    /// Sum of squared errors (kept for merging).
    #[serde(skip)]
    pub sum_sq: f64,
}

impl ErrorStats {
    /// Adds one error at `index`.
    #[inline]
    pub fn add(&mut self, index: u64, e: f64) {
        if e > self.max || self.count == 0 {
            self.max = e;
            self.max_index = index;
        }
        self.count += 1;
        self.sum += e;
        self.sum_sq += e * e;
    }

    /// Merges statistics of a later chunk (ties on max keep the earlier index).
    pub fn merge(&mut self, other: &ErrorStats) {
        if other.count == 0 {
            return;
        }
        if other.max > self.max || self.count == 0 {
            self.max = other.max;
            self.max_index = other.max_index;
        }
        self.count += other.count;
        self.sum += other.sum;
        self.sum_sq += other.sum_sq;
    }

    /// Mean error.
    pub fn mean(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            self.sum / self.count as f64
        }
    }

    /// Root-mean-square error.
    pub fn rms(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            (self.sum_sq / self.count as f64).sqrt()
        }
    }
}

/// Angular errors between originals and decoded normals, element by element.
pub fn errors(original: &[Dir], decoded: &[Dir]) -> Vec<f64> {
    original.par_iter().zip(decoded.par_iter()).map(|(a, b)| angle_between(*a, *b)).collect()
}

/// Statistics of a list of errors, summed in fixed chunks and merged in order.
pub fn stats(errors: &[f64]) -> ErrorStats {
    const CHUNK: usize = 1 << 14;
    let parts: Vec<ErrorStats> = errors
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut s = ErrorStats::default();
            for (i, &e) in chunk.iter().enumerate() {
                s.add((c * CHUNK + i) as u64, e);
            }
            s
        })
        .collect();
    let mut total = ErrorStats::default();
    for p in &parts {
        total.merge(p);
    }
    total
}

/// A histogram of errors over `[0, upper]` in equal bins; errors above `upper` land in the last.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    /// Upper edge of the last bin (radians); bin `i` covers `[i, i+1)·upper/bins`.
    pub upper: f64,
    /// Counts per bin.
    pub counts: Vec<u64>,
}

/// Histogram of `errors` with `bins` equal bins over `[0, upper]`.
pub fn histogram(errors: &[f64], upper: f64, bins: usize) -> Histogram {
    let mut counts = vec![0u64; bins.max(1)];
    let n = counts.len();
    for &e in errors {
        let i = if upper > 0.0 { ((e / upper) * n as f64) as usize } else { 0 };
        counts[i.min(n - 1)] += 1;
    }
    Histogram { upper, counts }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_match_direct_sums() {
        let e: Vec<f64> = (0..100_000).map(|i| ((i * 7919) % 1000) as f64 * 1e-6).collect();
        let s = stats(&e);
        let mean = e.iter().sum::<f64>() / e.len() as f64;
        let rms = (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt();
        assert!((s.mean() - mean).abs() < 1e-15 && (s.rms() - rms).abs() < 1e-15);
        assert_eq!(s.max, 999.0 * 1e-6);
        assert_eq!(e[s.max_index as usize], s.max);
        assert_eq!(s.max_index, e.iter().position(|&x| x == s.max).unwrap() as u64);
        let h = histogram(&[0.05, 0.15, 0.15, 0.95, 2.0], 1.0, 10);
        assert_eq!(h.counts, vec![1, 2, 0, 0, 0, 0, 0, 0, 0, 2]);
    }
}
