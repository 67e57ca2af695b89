//! Error metrics: the angular error [`angle_between`] and its statistics, reduced in a fixed
//! order so results do not depend on the thread count.

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The angle between two directions of any length, `atan2(|a×b|, a·b)`: accurate for tiny
/// angles where `acos(a·b)` (and glam's `angle_between`, which uses it) loses everything (at
/// 1e-7 rad, `acos` of a rounded cosine is off by 100 % in f32 and ~1e-9 rad in f64).
#[inline]
pub fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

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
pub fn errors(original: &[DVec3], decoded: &[DVec3]) -> Vec<f64> {
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
    fn atan2_angle_is_accurate_where_acos_fails() {
        let a = DVec3::X;
        for k in [1e-3f64, 1e-7, 1e-9, 1e-12] {
            let b = DVec3::new(k.cos(), k.sin(), 0.0);
            assert!((angle_between(a, b) - k).abs() <= 1e-15 * k + 1e-30, "{k}");
        }
        // acos of the f64 dot product at 1e-9 rad is visibly wrong: the reason for atan2.
        let b = DVec3::new(1e-9f64.cos(), 1e-9f64.sin(), 0.0);
        assert!((a.dot(b).acos() - 1e-9).abs() > 1e-10);
        assert!((a.angle_between(b) - 1e-9).abs() > 1e-10, "glam's angle_between is acos-based");
    }

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
