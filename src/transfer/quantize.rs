//! Quantized storage of the per-vertex transfer (issue 32, item 5: "half, 8-bit with a
//! per-cluster scale").
//!
//! glTF 2.0 has no half-float accessor (§3.6.2.2 lists BYTE, UNSIGNED_BYTE, SHORT,
//! UNSIGNED_SHORT, UNSIGNED_INT and FLOAT), so the 16-bit form an engine can load is a
//! normalized SHORT and the 8-bit one a normalized BYTE: a client reads code c as
//! max(c / q, −1), q = 32767 or 127 (glTF 2.0 §3.11, the table of normalized integers), and the
//! value is that times a scale s: v̂ = c / q · s. Each value v is coded as c = round(v / s · q),
//! s the largest |v| of its group, so |v − v̂| ≤ s / (2q), half a code step: the closed-form
//! bound the manifest reports beside the measured error.
//!
//! The groups: without clustered PCA, one scale per value index i over the mesh (the i-th
//! coefficient's largest |T_i|: the bands' magnitudes differ by orders, a shared scale would
//! spend the high bands' codes on the DC term's range); with it, one scale per cluster over its
//! vertices' PCA weights (Sloan et al. 2003 store per-cluster data beside the weights already).

use serde::{Deserialize, Serialize};

/// How the `.glb` stores the per-vertex transfer values (`_PRT_k`, or `_PRT_W_k` when
/// compressed).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Quantization {
    /// Float, as computed (rounded to f32).
    #[default]
    None,
    /// Normalized SHORT: value = code / 32767 × scale.
    I16,
    /// Normalized BYTE: value = code / 127 × scale.
    I8,
}

impl Quantization {
    /// The largest code q (value = code / q × scale), `None` for float storage.
    pub fn code_max(self) -> Option<i32> {
        match self {
            Quantization::None => None,
            Quantization::I16 => Some(i16::MAX as i32),
            Quantization::I8 => Some(i8::MAX as i32),
        }
    }

    /// The glTF accessor component type in words.
    pub fn component_type(self) -> &'static str {
        match self {
            Quantization::None => "FLOAT (5126)",
            Quantization::I16 => "SHORT (5122), normalized",
            Quantization::I8 => "BYTE (5120), normalized",
        }
    }
}

/// Values coded against per-group scales.
#[derive(Clone, Debug, PartialEq)]
pub struct Quantized {
    /// The codes, in −q..=q, in the values' layout.
    pub codes: Vec<i32>,
    /// One scale per group: the group's largest |value|, as the f32 the `.glb` stores.
    pub scales: Vec<f32>,
    /// The largest code q.
    pub code_max: i32,
    /// The largest |v − v̂| over the values, in units of their half code step s / (2q) (≤ 1).
    pub max_error_over_half_step: f64,
}

impl Quantized {
    /// Codes `values` with q = `code_max`: value j of vertex v (`per_vertex` per vertex) belongs to
    /// group `group_of(v, j)` of `groups`, whose scale is the group's largest |value|.
    pub fn new(
        values: &[f64],
        per_vertex: usize,
        groups: usize,
        code_max: i32,
        group_of: impl Fn(usize, usize) -> usize,
    ) -> Quantized {
        let mut largest = vec![0.0f64; groups];
        for (v, row) in values.chunks_exact(per_vertex).enumerate() {
            for (j, x) in row.iter().enumerate() {
                let g = group_of(v, j);
                largest[g] = largest[g].max(x.abs());
            }
        }
        // The scale is the f32 a reader gets; the codes are made against that very number.
        let scales: Vec<f32> = largest.iter().map(|&m| m as f32).collect();
        let q = code_max as f64;
        let mut codes = Vec::with_capacity(values.len());
        let mut max_error_over_half_step = 0.0f64;
        for (v, row) in values.chunks_exact(per_vertex).enumerate() {
            for (j, &x) in row.iter().enumerate() {
                let s = scales[group_of(v, j)] as f64;
                let code = if s > 0.0 { (x / s * q).round().clamp(-q, q) } else { 0.0 };
                codes.push(code as i32);
                if s > 0.0 {
                    max_error_over_half_step = max_error_over_half_step.max((x - code / q * s).abs() / (s / (2.0 * q)));
                }
            }
        }
        Quantized { codes, scales, code_max, max_error_over_half_step }
    }

    /// The glTF component type the codes are stored as: `BYTE` (q = 127) or `SHORT`.
    pub fn component(&self) -> &'static str {
        if self.code_max == i8::MAX as i32 {
            "BYTE"
        } else {
            "SHORT"
        }
    }

    /// Value `index` as a reader dequantizes it: max(c / q, −1) × s, s the scale of `group`.
    pub fn value(&self, index: usize, group: usize) -> f64 {
        (self.codes[index] as f64 / self.code_max as f64).max(-1.0) * self.scales[group] as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_value_is_within_half_a_code_step_and_the_extremes_are_exact() {
        let values: Vec<f64> = (0..300).map(|k| ((k as f64) * 0.37).sin() * (1.0 + (k % 3) as f64)).collect();
        for q in [127, 32767] {
            let quantized = Quantized::new(&values, 3, 3, q, |_, j| j);
            for (k, &x) in values.iter().enumerate() {
                let s = quantized.scales[k % 3] as f64;
                assert!((x - quantized.value(k, k % 3)).abs() <= s / (2.0 * q as f64) * (1.0 + 1e-6));
            }
            assert!(quantized.max_error_over_half_step <= 1.0 + 1e-6);
            assert!(quantized.codes.iter().all(|c| c.abs() <= q));
            // Each group's largest |value| is coded as ±q.
            for j in 0..3 {
                assert_eq!((0..100).map(|v| quantized.codes[3 * v + j].abs()).max(), Some(q));
            }
        }
    }

    #[test]
    fn an_all_zero_group_codes_zero() {
        let quantized = Quantized::new(&[0.0, 1.0, 0.0, -2.0], 2, 2, 127, |_, j| j);
        assert_eq!(quantized.scales, vec![0.0, 2.0]);
        assert_eq!(quantized.codes, vec![0, 64, 0, -127]);
        assert_eq!(quantized.value(0, 0), 0.0);
    }
}
