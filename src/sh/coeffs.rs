//! RGB SH coefficient vectors.

use super::{count, index};
use serde::{Deserialize, Serialize};

/// RGB coefficients of a function on the sphere up to band `order`, indexed by l(l+1)+m.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShCoeffs {
    /// Highest band F.
    pub order: usize,
    /// (F+1)² RGB triples.
    pub rgb: Vec<[f64; 3]>,
}

impl ShCoeffs {
    /// All-zero coefficients up to `order`.
    pub fn zeros(order: usize) -> Self {
        ShCoeffs { order, rgb: vec![[0.0; 3]; count(order)] }
    }

    /// The coefficient of (l, m).
    pub fn get(&self, l: usize, m: isize) -> [f64; 3] {
        self.rgb[index(l, m)]
    }

    /// Σ_m L_lm² per band l, per channel (Parseval: the energy of band l).
    pub fn band_energy_rgb(&self) -> Vec<[f64; 3]> {
        (0..=self.order)
            .map(|l| {
                let mut e = [0.0; 3];
                for m in -(l as isize)..=(l as isize) {
                    let c = self.rgb[index(l, m)];
                    for k in 0..3 {
                        e[k] += c[k] * c[k];
                    }
                }
                e
            })
            .collect()
    }

    /// Band energy summed over the three channels.
    pub fn band_energy(&self) -> Vec<f64> {
        self.band_energy_rgb().iter().map(|e| e[0] + e[1] + e[2]).collect()
    }

    /// The coefficient-wise sum, to the higher of the two orders.
    pub fn plus(&self, other: &ShCoeffs) -> ShCoeffs {
        let (high, low) = if self.order >= other.order { (self, other) } else { (other, self) };
        let mut sum = high.clone();
        for (s, o) in sum.rgb.iter_mut().zip(&low.rgb) {
            for c in 0..3 {
                s[c] += o[c];
            }
        }
        sum
    }

    /// Keeps bands 0..=order (which must not exceed the current order).
    pub fn truncated(&self, order: usize) -> ShCoeffs {
        let order = order.min(self.order);
        ShCoeffs { order, rgb: self.rgb[..count(order)].to_vec() }
    }

    /// The smallest order F whose bands 0..=F hold at least (1 − ε) of `total_energy`
    /// (Ramamoorthi & Hanrahan 2002, §5.1), or `None` if even all bands fall short.
    pub fn order_for_epsilon(&self, epsilon: f64, total_energy: f64) -> Option<usize> {
        let target = (1.0 - epsilon) * total_energy;
        let mut sum = 0.0;
        for (l, e) in self.band_energy().iter().enumerate() {
            sum += e;
            if sum >= target {
                return Some(l);
            }
        }
        None
    }
}
