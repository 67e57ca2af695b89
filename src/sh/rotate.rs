//! Rotation of real SH coefficient vectors by the Ivanic–Ruedenberg recurrences
//! (J. Ivanic, K. Ruedenberg, J. Phys. Chem. 100 (1996) 6342; errata 102 (1998) 9099).
//!
//! Band l's (2l+1)×(2l+1) matrix is built from band l−1's and the 3×3 rotation in the (y, z, x)
//! order of band 1, so the cost is O(F³) for all bands and only products of O(1) numbers occur:
//! the recurrence stays orthogonal to ~1e-12 at order 60 (tested).

use super::{count, index, ShCoeffs};
use glam::DMat3;

/// Block-diagonal SH rotation matrices, one dense block per band.
#[derive(Clone, Debug)]
pub struct ShRotation {
    blocks: Vec<Vec<f64>>, // blocks[l] is (2l+1)², row-major, rows/cols indexed by m + l
}

impl ShRotation {
    /// The matrix taking the coefficients of f to those of f∘R⁻¹ (the function rotated by R),
    /// for bands 0..=order.
    pub fn new(rotation: DMat3, order: usize) -> Self {
        let mut blocks = vec![vec![1.0]];
        if order == 0 {
            return ShRotation { blocks };
        }
        // Band 1: Y_1,(-1,0,1) ∝ (y, z, x), so M¹_mn = R[axis(m)][axis(n)].
        let axis = |m: isize| match m {
            -1 => 1usize,
            0 => 2,
            _ => 0,
        };
        let r = rotation.to_cols_array_2d(); // r[col][row]
        let mut b1 = vec![0.0; 9];
        for m in -1..=1isize {
            for n in -1..=1isize {
                b1[((m + 1) * 3 + (n + 1)) as usize] = r[axis(n)][axis(m)];
            }
        }
        blocks.push(b1);
        for l in 2..=order {
            let next = band(&blocks[1], &blocks[l - 1], l as isize);
            blocks.push(next);
        }
        ShRotation { blocks }
    }

    /// The highest band.
    pub fn order(&self) -> usize {
        self.blocks.len() - 1
    }

    /// Element (m, n) of band l.
    pub fn element(&self, l: usize, m: isize, n: isize) -> f64 {
        let w = 2 * l as isize + 1;
        self.blocks[l][((m + l as isize) * w + (n + l as isize)) as usize]
    }

    /// Rotates RGB coefficients (bands above this rotation's order are an error of use and are
    /// dropped; callers build the rotation at the coefficients' order).
    pub fn apply(&self, coeffs: &ShCoeffs) -> ShCoeffs {
        let order = coeffs.order.min(self.order());
        let mut out = ShCoeffs::zeros(order);
        for l in 0..=order {
            let li = l as isize;
            for m in -li..=li {
                let mut acc = [0.0; 3];
                for n in -li..=li {
                    let e = self.element(l, m, n);
                    let c = coeffs.rgb[index(l, n)];
                    for k in 0..3 {
                        acc[k] += e * c[k];
                    }
                }
                out.rgb[index(l, m)] = acc;
            }
        }
        out
    }

    /// Rotates one scalar coefficient vector of length (order+1)².
    pub fn apply_scalar(&self, coeffs: &[f64]) -> Vec<f64> {
        let order = self.order();
        let mut out = vec![0.0; count(order).min(coeffs.len())];
        for l in 0..=order {
            if count(l) > coeffs.len() {
                break;
            }
            let li = l as isize;
            for m in -li..=li {
                out[index(l, m)] = (-li..=li).map(|n| self.element(l, m, n) * coeffs[index(l, n)]).sum();
            }
        }
        out
    }
}

/// The u, v, w coefficients of Ivanic–Ruedenberg's Table 2 for one band: they depend on l, m, n
/// only, not on the rotation, so they are computed once per band and shared.
struct BandCoefficients {
    uvw: Vec<[f64; 3]>, // (2l+1)², row-major by (m + l, n + l)
}

fn band_coefficients(l: usize) -> std::sync::Arc<BandCoefficients> {
    use std::sync::{Arc, Mutex, OnceLock};
    static CACHE: OnceLock<Mutex<Vec<Arc<BandCoefficients>>>> = OnceLock::new();
    let cache = CACHE.get_or_init(|| Mutex::new(Vec::new()));
    if let Ok(c) = cache.lock() {
        if let Some(b) = c.get(l) {
            return b.clone();
        }
    }
    let mut built = Vec::new();
    let start = cache.lock().map(|c| c.len()).unwrap_or(0);
    for band in start..=l {
        let li = band as isize;
        let w = 2 * li + 1;
        let mut uvw = vec![[0.0; 3]; (w * w) as usize];
        if band >= 2 {
            for m in -li..=li {
                for n in -li..=li {
                    let d = if m == 0 { 1.0 } else { 0.0 };
                    let denom =
                        if n.abs() == li { (2 * li * (2 * li - 1)) as f64 } else { ((li + n) * (li - n)) as f64 };
                    let am = m.abs();
                    let u = (((li + m) * (li - m)) as f64 / denom).sqrt();
                    let v = 0.5 * ((1.0 + d) * ((li + am - 1) * (li + am)) as f64 / denom).sqrt() * (1.0 - 2.0 * d);
                    let wc = -0.5 * (((li - am - 1) * (li - am)) as f64 / denom).sqrt() * (1.0 - d);
                    uvw[((m + li) * w + (n + li)) as usize] = [u, v, wc];
                }
            }
        }
        built.push(Arc::new(BandCoefficients { uvw }));
    }
    match cache.lock() {
        Ok(mut c) => {
            // Another thread may have extended the cache meanwhile: append each band only at
            // its own position.
            for (i, b) in built.into_iter().enumerate() {
                if c.len() == start + i {
                    c.push(b);
                }
            }
            c[l].clone()
        }
        Err(_) => built.pop().unwrap_or_else(|| Arc::new(BandCoefficients { uvw: Vec::new() })),
    }
}

/// Builds band l from band 1 (`r1`) and band l−1 (`prev`), Ivanic–Ruedenberg Table 2 with the
/// 1998 corrections.
fn band(r1: &[f64], prev: &[f64], l: isize) -> Vec<f64> {
    let w = 2 * l + 1;
    let wp = 2 * l - 1;
    let coefficients = band_coefficients(l as usize);
    let product = |i: isize, j: isize, a: isize, b: isize| {
        r1[((i + 1) * 3 + (j + 1)) as usize] * prev[((a + l - 1) * wp + (b + l - 1)) as usize]
    };
    let mut out = vec![0.0; (w * w) as usize];
    for m in -l..=l {
        for n in -l..=l {
            out[((m + l) * w + (n + l)) as usize] =
                band_element(coefficients.uvw[((m + l) * w + (n + l)) as usize], l, m, n, &product);
        }
    }
    out
}

/// The symbolic form of band l ≥ 2: for each element (m, n), row-major by (m + l, n + l), the
/// terms c · R¹_ij · R^(l−1)_ab it sums, as `(c, (i, j), (a, b))` with like terms merged. The same
/// recurrence as [`ShRotation::new`] (one code path, [`band_element`]), written out so that a
/// shader can build the bands of a rotation with no loops or tables (`transfer`'s snippets).
pub type BandTerm = (f64, (isize, isize), (isize, isize));

/// See [`BandTerm`].
pub fn band_terms(l: usize) -> Vec<Vec<BandTerm>> {
    #[derive(Clone, Default)]
    struct Terms(Vec<BandTerm>);
    impl std::ops::Add for Terms {
        type Output = Terms;
        fn add(mut self, other: Terms) -> Terms {
            for t in other.0 {
                match self.0.iter_mut().find(|s| (s.1, s.2) == (t.1, t.2)) {
                    Some(s) => s.0 += t.0,
                    None => self.0.push(t),
                }
            }
            self
        }
    }
    impl std::ops::Mul<f64> for Terms {
        type Output = Terms;
        fn mul(self, c: f64) -> Terms {
            Terms(self.0.into_iter().map(|(k, a, b)| (k * c, a, b)).collect())
        }
    }
    assert!(l >= 2, "band_terms builds bands 2 and up");
    let li = l as isize;
    let w = 2 * li + 1;
    let coefficients = band_coefficients(l);
    let product = |i: isize, j: isize, a: isize, b: isize| Terms(vec![(1.0, (i, j), (a, b))]);
    let mut out = Vec::with_capacity((w * w) as usize);
    for m in -li..=li {
        for n in -li..=li {
            let Terms(mut terms) =
                band_element(coefficients.uvw[((m + li) * w + (n + li)) as usize], li, m, n, &product);
            terms.retain(|t| t.0 != 0.0);
            out.push(terms);
        }
    }
    out
}

/// Element (m, n) of band l, Ivanic–Ruedenberg Table 2 with the 1998 corrections, for any value
/// type: `product(i, j, a, b)` is R¹_ij · R^(l−1)_ab (numbers for [`ShRotation::new`], terms for
/// [`band_terms`]), `uvw` the element's u, v, w.
fn band_element<T>(uvw: [f64; 3], l: isize, m: isize, n: isize, product: &impl Fn(isize, isize, isize, isize) -> T) -> T
where
    T: Default + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    // P(i, a, b) of the paper.
    let p = |i: isize, a: isize, b: isize| -> T {
        if b == l {
            product(i, 1, a, l - 1) + product(i, -1, a, -l + 1) * -1.0
        } else if b == -l {
            product(i, 1, a, -l + 1) + product(i, -1, a, l - 1)
        } else {
            product(i, 0, a, b)
        }
    };
    let [u, v, wc] = uvw;
    let mut value = T::default();
    if u != 0.0 {
        value = value + p(0, m, n) * u;
    }
    if v != 0.0 {
        let vv = if m == 0 {
            p(1, 1, n) + p(-1, -1, n)
        } else if m > 0 {
            let d1: f64 = if m == 1 { 1.0 } else { 0.0 };
            p(1, m - 1, n) * (1.0 + d1).sqrt() + p(-1, -m + 1, n) * -(1.0 - d1)
        } else {
            let d1: f64 = if m == -1 { 1.0 } else { 0.0 };
            p(1, m + 1, n) * (1.0 - d1) + p(-1, -m - 1, n) * (1.0 + d1).sqrt()
        };
        value = value + vv * v;
    }
    if wc != 0.0 {
        let ww = if m > 0 { p(1, m + 1, n) + p(-1, -m - 1, n) } else { p(1, m - 1, n) + p(-1, -m + 1, n) * -1.0 };
        value = value + ww * wc;
    }
    value
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::basis::eval_basis_dir;
    use crate::sh::legendre::LegendreTable;
    use glam::DVec3;

    fn some_rotation() -> DMat3 {
        DMat3::from_axis_angle(DVec3::new(0.3, -0.8, 0.52).normalize(), 1.234)
    }

    /// Rotating coefficients must equal re-evaluating the basis at rotated directions:
    /// Σ_n M_mn Y_n(ω) = Y_m(R ω) summed appropriately — equivalently, for f = Y_n,
    /// (M c)(ω) = f(R⁻¹ω). Checked pointwise at random directions.
    #[test]
    fn matches_pointwise_rotation() {
        let order = 12;
        let rot = some_rotation();
        let shr = ShRotation::new(rot, order);
        let table = LegendreTable::new(order);
        let coeffs: Vec<f64> = (0..count(order)).map(|i| ((i * 7919) % 13) as f64 / 13.0 - 0.4).collect();
        let rotated = shr.apply_scalar(&coeffs);
        let mut y = vec![0.0; count(order)];
        for k in 0..50 {
            let w =
                DVec3::new((k as f64 * 1.3).sin(), (k as f64 * 2.1).cos(), (k as f64 * 0.7).sin() - 0.2).normalize();
            eval_basis_dir(&table, w, &mut y);
            let lhs: f64 = rotated.iter().zip(&y).map(|(a, b)| a * b).sum();
            eval_basis_dir(&table, rot.transpose() * w, &mut y);
            let rhs: f64 = coeffs.iter().zip(&y).map(|(a, b)| a * b).sum();
            assert!((lhs - rhs).abs() < 1e-10, "{lhs} vs {rhs}");
        }
    }

    #[test]
    fn blocks_stay_orthogonal_at_high_order() {
        let order = 60;
        let shr = ShRotation::new(some_rotation(), order);
        for l in [30usize, 45, 60] {
            let li = l as isize;
            let mut worst = 0.0f64;
            for a in -li..=li {
                for b in -li..=li {
                    let dot: f64 = (-li..=li).map(|k| shr.element(l, a, k) * shr.element(l, b, k)).sum();
                    let expect = if a == b { 1.0 } else { 0.0 };
                    worst = worst.max((dot - expect).abs());
                }
            }
            assert!(worst < 1e-10, "band {l}: orthogonality error {worst}");
        }
    }
}
