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
//! Determinism: the lat-long path sums each coefficient over the rows in one fixed order (its
//! work is split by order m, not by rows); the texel-by-texel path sums rows in fixed blocks and
//! adds the block sums in order. Neither result depends on the number of threads.

use super::legendre::{column_sums, LegendreTable};
use super::{count, index, ShCoeffs};
use crate::envmap::{EnvMap, Layout};
use crate::io::RgbImage;
use crate::progress::{NoProgress, Progress};
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
        Layout::LatLong => project_latlong(img, order, TexelQuadrature::Midpoint, progress)?,
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

/// How the lat-long projection integrates Y_lm over a texel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelQuadrature {
    /// Y_lm at the texel's centre times its solid angle (App. C's sum; [`project`]).
    Midpoint,
    /// The texel's integral: exact in φ (over a column, ∫ cos or sin mφ dφ is the centre's value
    /// × Δφ · sinc(mΔφ/2)) and Gauss–Legendre with this many nodes in z. For texels that are
    /// large against what the coefficients feed: the excess of a few bright texels under a lobe
    /// a few texels wide.
    Integral {
        /// Nodes in z per texel.
        z_nodes: usize,
    },
}

/// The separable projection of a lat-long image (App. C step 1) onto bands 0..=order ≤ W/2,
/// texels integrated by `quadrature`.
///
/// Rows are taken in mirrored pairs: row y and row H − 1 − y have the same solid angle and z
/// nodes of opposite sign, and P̄_l^m(−z) = (−1)^{l+m} P̄_l^m(z), so one Legendre evaluation
/// serves both, applied to the sum of their Fourier sums where l + m is even and to the
/// difference where it is odd. A pair of black rows is skipped (it adds exactly nothing), so a
/// sparse image costs what its lit rows cost. The θ sum is taken one order m at a time: the
/// column P̄_l^m, l ≥ m, runs over every row's z at once ([`LegendreTable::column`]), and each
/// coefficient is its dot product with the rows' Fourier sums. The work per (l, m) is then a
/// vectorized pass over the rows held in cache, where summing row by row streams the whole
/// accumulator of (F + 1)² coefficients through memory for every row. An order above W/2 (the rows' Nyquist frequency) is an
/// error.
///
/// ```
/// use prtkit::io::RgbImage;
/// use prtkit::progress::NoProgress;
/// use prtkit::sh::project::{project_latlong, TexelQuadrature};
/// // One lit texel of a coarse map: the midpoint puts its energy at the centre, the integral
/// // spreads it over the texel. Band 0 (Y_00 constant) is the same; higher bands differ.
/// let mut map = RgbImage::new(16, 8);
/// map.pixels[2 * 16 + 5] = [1.0; 3];
/// let midpoint = project_latlong(&map, 6, TexelQuadrature::Midpoint, &NoProgress).unwrap();
/// let integral = project_latlong(&map, 6, TexelQuadrature::Integral { z_nodes: 3 }, &NoProgress).unwrap();
/// assert!((midpoint.rgb[0][0] - integral.rgb[0][0]).abs() < 1e-12);
/// assert!((midpoint.rgb[40][0] - integral.rgb[40][0]).abs() > 1e-4);
/// assert!(project_latlong(&map, 9, TexelQuadrature::Midpoint, &NoProgress).is_err());
/// ```
pub fn project_latlong(
    img: &RgbImage,
    order: usize,
    quadrature: TexelQuadrature,
    progress: &dyn Progress,
) -> Result<ShCoeffs, ProjectError> {
    let (w, h) = (img.width, img.height);
    let rows = RowRule::new(w, h, order, quadrature)?;
    let black: Vec<bool> = (0..h).map(|y| img.row(y).iter().all(|p| *p == [0.0; 3])).collect();
    let row_is_black = |y: usize| black[y];
    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(w);
    // Phase that moves the FFT's sample points from φ = 2πx/W to the texel centres
    // φ = 2π(x + ½)/W: Σ_x f_x e^{−imφ_x} = e^{−iπm/W} X_m.
    let phase: Vec<(f64, f64)> = (0..=order).map(|m| (PI * m as f64 / w as f64).sin_cos()).collect();
    let pairs: Vec<(usize, Option<usize>)> = LatLong::new(w, h)
        .mirrored_row_pairs()
        .filter(|&(y, mirror)| !(row_is_black(y) && mirror.is_none_or(row_is_black)))
        .collect();
    let lit_rows: u64 = pairs.iter().map(|p| 1 + p.1.is_some() as u64).sum();
    progress.start("projecting", lit_rows + order as u64 + 1);
    // Per worker: the FFT's buffers and [row of the pair][cos or sin] at m.
    let fft_buffers = || {
        let row_sums = [vec![[0.0; 2]; order + 1], vec![[0.0; 2]; order + 1]];
        (fft.make_input_vec(), fft.make_output_vec(), fft.make_scratch_vec(), row_sums)
    };
    let mut sums = vec![0.0; pairs.len() * rows.stride()];
    sums.par_chunks_mut(rows.stride()).zip(&pairs).for_each_init(
        fft_buffers,
        |(input, spectrum, scratch, row_sums), (out, &(y, mirror))| {
            for c in 0..3 {
                for (row, sum) in std::iter::once(y).chain(mirror).zip(row_sums.iter_mut()) {
                    if row_is_black(row) {
                        // A sparse image's lit row is often mirrored by a black one.
                        sum.fill([0.0; 2]);
                        continue;
                    }
                    for (slot, px) in input.iter_mut().zip(img.row(row)) {
                        *slot = px[c] as f64;
                    }
                    // Lengths come from the plan, so this cannot fail.
                    let _ = fft.process_with_scratch(input, spectrum, scratch);
                    for (m, s) in sum.iter_mut().enumerate() {
                        let (sin, cos) = phase[m];
                        let z = spectrum[m];
                        // e^{−iπm/W}·X_m = (cos − i sin)(re + i im)
                        *s = [cos * z.re + sin * z.im, -(cos * z.im - sin * z.re)];
                    }
                }
                rows.pair_parts(out, c, y, &row_sums[0], mirror.map(|_| &row_sums[1][..]));
            }
            progress.advance(1 + mirror.is_some() as u64);
        },
    );
    let coeffs = rows.theta_sums(&pairs, &sums, progress);
    progress.finish();
    Ok(coeffs)
}

/// [`project_latlong`] of a W × H image that is black but for a few texels, given as (x, y,
/// value); texels at the same place add, texels off the grid are left out. Each lit row's
/// Fourier sums are taken directly, Σ_texels v {cos, sin}(mφ_x) with mφ_x = πm(2x + 1)/W read
/// from a table of the 2W multiples of π/W (no recurrence error): O(texels · F), where the
/// image's path pays an image, a scan of every row and an FFT per lit row and channel. The
/// bright texels' excess goes this way (`prefilter`): on Grace at 256 × 128, 315 texels in 31
/// mirrored pairs of rows.
pub fn project_latlong_texels(
    (w, h): (usize, usize),
    texels: &[(usize, usize, [f64; 3])],
    order: usize,
    quadrature: TexelQuadrature,
) -> Result<ShCoeffs, ProjectError> {
    let rows = RowRule::new(w, h, order, quadrature)?;
    let mut by_row: Vec<&(usize, usize, [f64; 3])> = texels.iter().filter(|t| t.0 < w && t.1 < h).collect();
    by_row.sort_by_key(|t| t.1);
    let row_texels = |y: usize| {
        let lo = by_row.partition_point(|t| t.1 < y);
        &by_row[lo..by_row.partition_point(|t| t.1 <= y)]
    };
    let pairs: Vec<(usize, Option<usize>)> = LatLong::new(w, h)
        .mirrored_row_pairs()
        .filter(|&(y, mirror)| !row_texels(y).is_empty() || mirror.is_some_and(|m| !row_texels(m).is_empty()))
        .collect();
    let turns: Vec<(f64, f64)> = (0..2 * w).map(|j| (PI * j as f64 / w as f64).sin_cos()).collect();
    let mut sums = vec![0.0; pairs.len() * rows.stride()];
    sums.par_chunks_mut(rows.stride()).zip(&pairs).for_each(|(out, &(y, mirror))| {
        // [row of the pair][m][channel][cos or sin]
        let mut row_sums = [vec![[[0.0; 2]; 3]; order + 1], vec![[[0.0; 2]; 3]; order + 1]];
        for (row, sum) in std::iter::once(y).chain(mirror).zip(row_sums.iter_mut()) {
            for &&(x, _, v) in row_texels(row) {
                // m(2x + 1) mod 2W, stepped without a division per term.
                let (step, mut turn) = (2 * x + 1, 0);
                for s in sum.iter_mut() {
                    let (sin, cos) = turns[turn];
                    for c in 0..3 {
                        s[c][0] += v[c] * cos;
                        s[c][1] += v[c] * sin;
                    }
                    turn += step;
                    if turn >= 2 * w {
                        turn -= 2 * w;
                    }
                }
            }
        }
        for c in 0..3 {
            let channel = |r: &Vec<[[f64; 2]; 3]>| r.iter().map(|s| s[c]).collect::<Vec<_>>();
            let (top, bottom) = (channel(&row_sums[0]), channel(&row_sums[1]));
            rows.pair_parts(out, c, y, &top, mirror.map(|_| &bottom[..]));
        }
    });
    Ok(rows.theta_sums(&pairs, &sums, &NoProgress))
}

/// What the lat-long projection's two steps share: the grid, the order and how a texel is
/// integrated (the z nodes within a row; the sinc of a column in φ).
struct RowRule {
    grid: LatLong,
    order: usize,
    /// z nodes of a row as (offset from the row's middle in units of its half-height, share of
    /// its solid angle); empty for the midpoint, the row's centre in θ.
    z_rule: Vec<(f64, f64)>,
    /// ∫ over a texel column of cos or sin mφ, relative to Δφ times the centre's value (a sinc;
    /// 1 for the midpoint rule). Not to be confused with the Legendre columns of step 3.
    column_sinc: Vec<f64>,
}

impl RowRule {
    /// The rule for bands 0..=order on a W × H grid: an error above W/2, the rows' Nyquist
    /// frequency.
    fn new(w: usize, h: usize, order: usize, quadrature: TexelQuadrature) -> Result<Self, ProjectError> {
        if w == 0 || order > w / 2 {
            return Err(ProjectError::OrderTooHigh {
                order,
                max: w / 2,
                layout: Layout::LatLong.name(),
                width: w,
                height: h,
            });
        }
        let z_rule = match quadrature {
            TexelQuadrature::Midpoint => Vec::new(),
            TexelQuadrature::Integral { z_nodes } => {
                crate::quadrature::gauss_legendre_cached(z_nodes.max(1)).iter().map(|&(x, w)| (x, 0.5 * w)).collect()
            }
        };
        let column_sinc = (0..=order)
            .map(|m| {
                let half = PI * m as f64 / w as f64;
                if quadrature == TexelQuadrature::Midpoint || m == 0 {
                    1.0
                } else {
                    half.sin() / half
                }
            })
            .collect();
        Ok(RowRule { grid: LatLong::new(w, h), order, z_rule, column_sinc })
    }

    /// Index of step 1's sums of a pair: [part][cos or sin][channel][m].
    fn part(&self, part: usize, k: usize, c: usize) -> usize {
        ((part * 2 + k) * 3 + c) * (self.order + 1)
    }

    /// Step 1's sums per pair of rows.
    fn stride(&self) -> usize {
        self.part(2, 0, 0)
    }

    /// Step 1, one channel `c` of the pair of rows y and its mirror: from each row's Σ_x f
    /// cos(mφ_x) and Σ_x f sin(mφ_x) (`top`, `bottom`), the even part (top + mirror) and the odd
    /// part (top − mirror) in z, times the row's solid angle and the √2 of m ≠ 0. A lone middle
    /// row (z = 0, no mirror) has only the even part; its odd functions vanish there.
    fn pair_parts(&self, out: &mut [f64], c: usize, y: usize, top: &[[f64; 2]], bottom: Option<&[[f64; 2]]>) {
        let omega = self.grid.row_solid_angle(y);
        for k in 0..2 {
            for m in 0..=self.order {
                let (t, b) = (top[m][k], bottom.map_or(0.0, |b| b[m][k]));
                let weight = if m == 0 { omega } else { omega * SQRT_2 * self.column_sinc[m] };
                out[self.part(0, k, c) + m] = (t + b) * weight;
                out[self.part(1, k, c) + m] = (t - b) * weight;
            }
        }
    }

    /// Steps 2 and 3: the θ sums of step 1's `sums` of the `pairs` of rows. The z nodes of every
    /// pair's top row; the mirror row's are at −z, which the even and odd parts account for.
    /// Then per order m, c_lm = Σ_nodes P̄_l^m(z) × the part of parity l + m for every l ≥ m,
    /// the column of Legendre values run over all nodes at once. Each coefficient is summed over
    /// the nodes in one fixed order whatever the thread count.
    fn theta_sums(&self, pairs: &[(usize, Option<usize>)], sums: &[f64], progress: &dyn Progress) -> ShCoeffs {
        let (order, stride, h) = (self.order, self.stride(), self.grid.height);
        let table = LegendreTable::new(order);
        // (pair, cos θ, sin θ, share of the row's solid angle)
        let mut nodes: Vec<(usize, f64, f64, f64)> = Vec::new();
        for (i, &(y, _)) in pairs.iter().enumerate() {
            if self.z_rule.is_empty() {
                let (st, ct) = (PI * (y as f64 + 0.5) / h as f64).sin_cos();
                nodes.push((i, ct, st, 1.0));
            } else {
                let (z0, z1) = ((PI * y as f64 / h as f64).cos(), (PI * (y + 1) as f64 / h as f64).cos());
                for &(x, share) in &self.z_rule {
                    let z = (0.5 * (z0 + z1) + 0.5 * (z0 - z1) * x).clamp(-1.0, 1.0);
                    nodes.push((i, z, (1.0 - z * z).sqrt(), share));
                }
            }
        }
        let cos_theta: Vec<f64> = nodes.iter().map(|n| n.1).collect();
        let diagonals = table.diagonals(&nodes.iter().map(|n| n.2).collect::<Vec<_>>());
        let n = nodes.len();
        let scratch = || (vec![0.0; 12 * n], (Vec::new(), Vec::new()));
        let columns: Vec<Vec<[f64; 6]>> = (0..=order)
            .into_par_iter()
            .map_init(scratch, |(gathered, column_scratch), m| {
                // [part][cos or sin][channel][node], each node's share of its row included.
                for (q, g) in gathered.chunks_exact_mut(n).enumerate() {
                    for (g, &(pair, _, _, share)) in g.iter_mut().zip(&nodes) {
                        *g = share * sums[pair * stride + q * (order + 1) + m];
                    }
                }
                let kinds = if m == 0 { 3 } else { 6 };
                let mut out = Vec::with_capacity(order + 1 - m);
                table.column(m, &cos_theta, &diagonals[m * n..(m + 1) * n], column_scratch, |l, values| {
                    let part = &gathered[((l + m) % 2) * 6 * n..][..6 * n];
                    out.push(column_sums::<6>(values, part, kinds));
                });
                progress.advance(1);
                out
            })
            .collect();
        let mut total = vec![[0.0; 3]; count(order)];
        for (m, column) in columns.iter().enumerate() {
            for (l, sums) in (m..=order).zip(column) {
                for c in 0..3 {
                    total[index(l, m as isize)][c] = sums[c];
                    if m > 0 {
                        total[index(l, -(m as isize))][c] = sums[3 + c];
                    }
                }
            }
        }
        ShCoeffs { order, rgb: total }
    }
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
    map_energy_rgb(map).iter().sum()
}

/// ∫ L² dΩ per channel by the same quadrature: by Bessel's inequality, at least the energy of
/// any set of bands of the map.
pub fn map_energy_rgb(map: &EnvMap) -> [f64; 3] {
    map_integral_of(map, |v| v * v)
}

/// ∫ L dΩ per channel by the same quadrature (√(4π) L_00).
pub fn map_integral_rgb(map: &EnvMap) -> [f64; 3] {
    map_integral_of(map, |v| v)
}

/// ∫ f(L) dΩ per channel, each texel's value times its solid angle.
fn map_integral_of(map: &EnvMap, f: impl Fn(f64) -> f64 + Sync) -> [f64; 3] {
    let rows = map.rows();
    let blocks: Vec<[f64; 3]> = rows
        .par_chunks(BLOCK_ROWS)
        .map(|chunk| {
            let mut e = [0.0; 3];
            for &(face, y) in chunk {
                let img = &map.images()[face];
                // A lat-long row's texels share one solid angle.
                let row = (map.layout() == Layout::LatLong).then(|| map.texel_solid_angle(face, 0, y)).flatten();
                for x in 0..img.width {
                    if let Some(omega) = row.or_else(|| map.texel_solid_angle(face, x, y)) {
                        let v = img.get(x, y);
                        for c in 0..3 {
                            e[c] += omega * f(v[c] as f64);
                        }
                    }
                }
            }
            e
        })
        .collect();
    blocks.iter().fold([0.0; 3], |a, b| std::array::from_fn(|c| a[c] + b[c]))
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
