//! Projecting environment maps onto SH.
//!
//! Lat-long maps use the separable algorithm of Ramamoorthi & Hanrahan 2002 (§6.1, App. C
//! step 1): per row, an FFT over φ gives Σ_x L(θ_y, φ_x) {cos, sin}(mφ_x) for every m at once in
//! O(W log W); then the θ sum multiplies by N_l^m P_l^m(cos θ_y) and the row's solid angle, O(F²)
//! per row. Total O(H·W log W + H·F²) instead of O(W·H·F²). Other layouts sum Y_lm(ω)·L·Ω
//! texel by texel (O(N·F²)); `docs/sh-project.md` explains why and how fast.
//!
//! Both are the midpoint rule with exact texel solid angles: a single texel of value v projects
//! to exactly v·Ω·Y_lm(centre).
//!
//! Determinism: rows are summed in fixed blocks, and the block sums are added in order, so the
//! result does not depend on the number of threads.

use super::legendre::LegendreTable;
use super::{count, index, ShCoeffs};
use crate::envmap::{EnvMap, Layout};
use crate::progress::Progress;
use crate::sphere::LatLong;
use rayon::prelude::*;
use realfft::RealFftPlanner;
use std::f64::consts::{PI, SQRT_2};

/// Rows per block of the deterministic reduction.
const BLOCK_ROWS: usize = 16;

/// Errors of projection.
#[derive(Debug, thiserror::Error)]
pub enum ProjectError {
    /// The order is beyond what the map's resolution can represent.
    #[error("order {order} is beyond what this {width}x{height} {layout} map resolves (at most {max})")]
    OrderTooHigh {
        /// Requested order.
        order: usize,
        /// Largest sensible order.
        max: usize,
        /// Layout name.
        layout: &'static str,
        /// Width of the (first) image.
        width: usize,
        /// Height.
        height: usize,
    },
}

/// Projects `map` onto SH bands 0..=order.
pub fn project(map: &EnvMap, order: usize, progress: &dyn Progress) -> Result<ShCoeffs, ProjectError> {
    let img = map.image();
    if order > map.max_order() || (map.layout() == Layout::LatLong && order > img.width / 2) {
        return Err(ProjectError::OrderTooHigh {
            order,
            max: map.max_order().min(if map.layout() == Layout::LatLong { img.width / 2 } else { usize::MAX }),
            layout: map.layout().name(),
            width: img.width,
            height: img.height,
        });
    }
    Ok(match map.layout() {
        Layout::LatLong => project_latlong(map, order, progress),
        _ => project_texels(map, order, progress),
    })
}

fn add_into(acc: &mut [[f64; 3]], other: &[[f64; 3]]) {
    for (a, b) in acc.iter_mut().zip(other) {
        for k in 0..3 {
            a[k] += b[k];
        }
    }
}

/// The separable lat-long projection (App. C step 1).
fn project_latlong(map: &EnvMap, order: usize, progress: &dyn Progress) -> ShCoeffs {
    let img = map.image();
    let (w, h) = (img.width, img.height);
    let table = LegendreTable::new(order);
    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(w);
    // Phase that moves the FFT's sample points from φ = 2πx/W to the texel centres
    // φ = 2π(x + ½)/W: Σ_x f_x e^{−imφ_x} = e^{−iπm/W} X_m.
    let phase: Vec<(f64, f64)> = (0..=order).map(|m| (PI * m as f64 / w as f64).sin_cos()).collect();
    progress.start("projecting", h as u64);
    let blocks: Vec<Vec<[f64; 3]>> = (0..h.div_ceil(BLOCK_ROWS))
        .into_par_iter()
        .map(|block| {
            let mut acc = vec![[0.0; 3]; count(order)];
            let mut input = fft.make_input_vec();
            let mut spectrum = fft.make_output_vec();
            let mut scratch = fft.make_scratch_vec();
            let mut cos_sum = vec![[0.0f64; 3]; order + 1]; // Σ_x f cos(mφ_x), per channel
            let mut sin_sum = vec![[0.0f64; 3]; order + 1];
            let mut plm = vec![0.0; count(order)];
            let rows = block * BLOCK_ROWS..((block + 1) * BLOCK_ROWS).min(h);
            for y in rows.clone() {
                for c in 0..3 {
                    for (slot, px) in input.iter_mut().zip(img.row(y)) {
                        *slot = px[c] as f64;
                    }
                    // Lengths come from the plan, so this cannot fail.
                    let _ = fft.process_with_scratch(&mut input, &mut spectrum, &mut scratch);
                    for m in 0..=order {
                        let (s, co) = phase[m];
                        let z = spectrum[m];
                        // e^{−iπm/W}·X_m = (co − i s)(re + i im)
                        let re = co * z.re + s * z.im;
                        let im = co * z.im - s * z.re;
                        cos_sum[m][c] = re;
                        sin_sum[m][c] = -im;
                    }
                }
                let theta = PI * (y as f64 + 0.5) / h as f64;
                let (st, ct) = theta.sin_cos();
                table.eval(ct, st, &mut plm);
                let omega = LatLong::new(w, h).row_solid_angle(y);
                for l in 0..=order {
                    let p0 = plm[index(l, 0)] * omega;
                    let a = &mut acc[index(l, 0)];
                    for c in 0..3 {
                        a[c] += p0 * cos_sum[0][c];
                    }
                    for m in 1..=l {
                        let p = plm[index(l, m as isize)] * omega * SQRT_2;
                        let pos = index(l, m as isize);
                        let neg = index(l, -(m as isize));
                        for c in 0..3 {
                            acc[pos][c] += p * cos_sum[m][c];
                            acc[neg][c] += p * sin_sum[m][c];
                        }
                    }
                }
            }
            progress.advance(rows.len() as u64);
            acc
        })
        .collect();
    progress.finish();
    let mut total = vec![[0.0; 3]; count(order)];
    for b in &blocks {
        add_into(&mut total, b);
    }
    ShCoeffs { order, rgb: total }
}

/// Texel-by-texel projection for layouts without a separable structure.
fn project_texels(map: &EnvMap, order: usize, progress: &dyn Progress) -> ShCoeffs {
    let table = LegendreTable::new(order);
    let rows = map.rows();
    progress.start("projecting", rows.len() as u64);
    let blocks: Vec<Vec<[f64; 3]>> = rows
        .par_chunks(BLOCK_ROWS)
        .map(|chunk| {
            let mut acc = vec![[0.0; 3]; count(order)];
            let mut y_lm = vec![0.0; count(order)];
            for &(face, y) in chunk {
                let img = &map.images()[face];
                for x in 0..img.width {
                    if let Some((dir, omega)) = map.texel_geometry(face, x, y) {
                        let v = img.get(x, y);
                        super::basis::eval_basis_dir(&table, dir, &mut y_lm);
                        let wv = [v[0] as f64 * omega, v[1] as f64 * omega, v[2] as f64 * omega];
                        for (a, &b) in acc.iter_mut().zip(&y_lm) {
                            a[0] += b * wv[0];
                            a[1] += b * wv[1];
                            a[2] += b * wv[2];
                        }
                    }
                }
            }
            progress.advance(chunk.len() as u64);
            acc
        })
        .collect();
    progress.finish();
    let mut total = vec![[0.0; 3]; count(order)];
    for b in &blocks {
        add_into(&mut total, b);
    }
    ShCoeffs { order, rgb: total }
}

/// The naive per-texel projection of a lat-long map, O(W·H·F²): the benchmark baseline and the
/// slow reference the separable path is tested against.
pub fn project_naive(map: &EnvMap, order: usize) -> ShCoeffs {
    project_texels(map, order, &crate::progress::NoProgress)
}

/// ∫ |L|² dΩ summed over channels by the same quadrature (Parseval's right-hand side): the total
/// energy that ε in `--epsilon` is relative to.
pub fn map_energy(map: &EnvMap) -> f64 {
    let rows = map.rows();
    let blocks: Vec<f64> = rows
        .par_chunks(BLOCK_ROWS)
        .map(|chunk| {
            let mut e = 0.0;
            for &(face, y) in chunk {
                let img = &map.images()[face];
                for x in 0..img.width {
                    if let Some((_, omega)) = map.texel_geometry(face, x, y) {
                        let v = img.get(x, y);
                        e +=
                            omega * (v[0] as f64 * v[0] as f64 + v[1] as f64 * v[1] as f64 + v[2] as f64 * v[2] as f64);
                    }
                }
            }
            e
        })
        .collect();
    blocks.iter().sum()
}

/// How to choose the order of a projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OrderChoice {
    /// Exactly this order.
    Order(usize),
    /// The smallest order capturing 1 − ε of the map's energy (R&H 2002 §5.1), searched up to
    /// `max_search`.
    Epsilon {
        /// Tolerance ε ∈ (0, 1).
        epsilon: f64,
        /// Highest order considered.
        max_search: usize,
    },
}

/// A projection and how its order was chosen.
#[derive(Clone, Debug)]
pub struct Projection {
    /// The coefficients (bands 0..=order).
    pub coeffs: ShCoeffs,
    /// ∫ |L|² dΩ over RGB.
    pub total_energy: f64,
    /// 1 − captured/total.
    pub epsilon_achieved: f64,
}

/// Errors of order selection.
#[derive(Debug, thiserror::Error)]
pub enum SelectError {
    /// Projection failed.
    #[error(transparent)]
    Project(#[from] ProjectError),
    /// ε is not in (0, 1).
    #[error("epsilon must be in (0, 1), got {0}")]
    BadEpsilon(f64),
    /// No order up to the limit reaches the tolerance.
    #[error("no order up to {max} captures 1 - {epsilon} of the energy (order {max} leaves {achieved:.3e}); the map needs more resolution or a larger epsilon")]
    Unreachable {
        /// Requested ε.
        epsilon: f64,
        /// Highest order tried.
        max: usize,
        /// Residual at that order.
        achieved: f64,
    },
}

/// Projects `map`, choosing the order as asked.
pub fn project_choosing_order(
    map: &EnvMap,
    choice: OrderChoice,
    progress: &dyn Progress,
) -> Result<Projection, SelectError> {
    let total_energy = map_energy(map);
    let residual = |c: &ShCoeffs| {
        if total_energy > 0.0 {
            (1.0 - c.band_energy().iter().sum::<f64>() / total_energy).max(0.0)
        } else {
            0.0
        }
    };
    match choice {
        OrderChoice::Order(order) => {
            let coeffs = project(map, order, progress)?;
            let epsilon_achieved = residual(&coeffs);
            Ok(Projection { coeffs, total_energy, epsilon_achieved })
        }
        OrderChoice::Epsilon { epsilon, max_search } => {
            if !(epsilon > 0.0 && epsilon < 1.0) {
                return Err(SelectError::BadEpsilon(epsilon));
            }
            let img = map.image();
            let mut limit = max_search.min(map.max_order());
            if map.layout() == Layout::LatLong {
                limit = limit.min(img.width / 2);
            }
            let full = project(map, limit, progress)?;
            match full.order_for_epsilon(epsilon, total_energy) {
                Some(order) => {
                    let coeffs = full.truncated(order);
                    let epsilon_achieved = residual(&coeffs);
                    Ok(Projection { coeffs, total_energy, epsilon_achieved })
                }
                None => Err(SelectError::Unreachable { epsilon, max: limit, achieved: residual(&full) }),
            }
        }
    }
}
