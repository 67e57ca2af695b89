//! Zonal filtering of lat-long maps: B(R) = ∫ L(ω) k(R·ω) dω for a kernel that depends only on
//! the angle between the output direction R and the light direction ω (Phong's lobe about R,
//! Lambert's about N, the GGX split-sum lobe), computed exactly for the piecewise-constant map by
//! circular convolutions in φ.
//!
//! **What is computed.** The map is constant over each texel t (radiance L_t). The filter keeps
//! the texels whose centre c_t lies within the cone angle θ_c of R and integrates the kernel over
//! each one's extent:
//!
//!   B(R) = Σ_{t : R·c_t ≥ cos θ_c} L_t ∫_t k(R·ω) dω.
//!
//! The texel integrals use an n × n Gauss–Legendre product rule in (z = cos θ, φ), in which the
//! solid angle is dz dφ ([`TexelRule`]); n is chosen by measurement ([`choose_rule`]), so a narrow
//! lobe over coarse texels is integrated over their extent rather than sampled at their centres.
//! With n = 1 the rule is the texel's z-midpoint times its exact solid angle.
//!
//! **Shift invariance.** Let the source have W columns and the output W columns too (any number
//! of rows). A rotation about +Z by 2π/W maps both grids onto themselves and leaves R·ω, hence the
//! kernel, unchanged. So the weight between output texel (x_o, y_o) and source texel (x, y) depends
//! only on (y_o, y, d = x − x_o mod W), and is even in d. For each pair of rows the sum over x is a
//! circular convolution: B_{y_o} = Σ_y L_y ⊛ K_{y_o,y}, i.e. B̂_{y_o}(m) = Σ_y L̂_y(m) K̂_{y_o,y}(m)
//! with real K̂ (K is even). The kernel K_{y_o,y} is built once per row pair (the d-window and the
//! source rows outside the cone are skipped, and black source rows too with [`Rows::Lit`]),
//! transformed once, and the products are accumulated
//! per output row in the frequency domain: one inverse FFT per output row and channel. The cost is
//! O(H_out·H_cone·(W log W + n²·W_cone)) instead of the direct O(H_out·W·N_cone·n²).
//!
//! **Mirror symmetry.** Mirroring z maps output row y_o to H_out − 1 − y_o and source row y to
//! H − 1 − y and keeps R·ω, so those two pairs share their kernel: output rows are computed in
//! mirrored pairs, each kernel evaluated and transformed once for both (half the kernel work).
//!
//! **Determinism.** Every mirrored pair of output rows is computed by one thread, accumulating
//! its source rows in a fixed order: the result is bitwise the same for any number of threads.
//!
//! [`zonal_filter_reference`] is the slow, obviously-correct form of the same sum (every texel,
//! every sub-sample, directions from [`crate::sphere::direction`]); the tests hold the fast path
//! to it at 1e-9.

use crate::io::RgbImage;
use crate::limits::MAX_ZONAL_TEXELS;
use crate::progress::Progress;
use crate::quadrature::gauss_legendre_cached;
use crate::sphere::{self, LatLong};
use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use std::f64::consts::{PI, TAU};
use std::sync::Arc;

/// Errors of the zonal filter.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ZonalError {
    /// A map or output of no texels.
    #[error("cannot filter a {width}x{height} map into {out_height} rows")]
    Empty {
        /// Source width.
        width: usize,
        /// Source height.
        height: usize,
        /// Output rows.
        out_height: usize,
    },
    /// Beyond [`MAX_ZONAL_TEXELS`].
    #[error("a {width}x{height} map is beyond the zonal filter's bound of {max} texels")]
    TooLarge {
        /// Width.
        width: usize,
        /// Height.
        height: usize,
        /// The bound.
        max: usize,
    },
    /// A sub-sample count outside 1..=[`TexelRule::MAX_SUBSAMPLES`].
    #[error("texel sub-samples per axis must be 1..={max}, got {n}")]
    Subsamples {
        /// Requested.
        n: usize,
        /// Largest allowed.
        max: usize,
    },
    /// A cone angle that is not in (0, π].
    #[error("the cone angle must be in (0, π] radians, got {0}")]
    Cone(f64),
}

/// One row of a texel rule's nodes: z = cos θ, sin θ, and the weight in z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SubRow {
    /// z = cos θ of the node.
    pub z: f64,
    /// sin θ = √(1 − z²).
    pub sin_theta: f64,
    /// Gauss–Legendre weight in z (the row's weights sum to its z extent).
    pub weight: f64,
}

/// The n × n Gauss–Legendre product rule over a lat-long texel in (z = cos θ, φ): the texel
/// integral ∫_t f dω = ∫∫ f dz dφ is Σ_kj w_k w_j f(z_k, φ_j). Exact for f polynomial of degree
/// < 2n in z and in φ separately; the weights sum to the texel's exact solid angle.
#[derive(Clone, Debug, PartialEq)]
pub struct TexelRule {
    /// Nodes and weights on [−1, 1].
    nodes: Arc<Vec<(f64, f64)>>,
}

impl TexelRule {
    /// The largest sub-sample count per axis.
    pub const MAX_SUBSAMPLES: usize = 16;

    /// n sub-samples per axis (n² per texel).
    pub fn new(n: usize) -> Result<Self, ZonalError> {
        if !(1..=Self::MAX_SUBSAMPLES).contains(&n) {
            return Err(ZonalError::Subsamples { n, max: Self::MAX_SUBSAMPLES });
        }
        Ok(TexelRule { nodes: gauss_legendre_cached(n) })
    }

    /// One node per texel: the z-midpoint times the texel's solid angle.
    pub fn midpoint() -> Self {
        TexelRule { nodes: gauss_legendre_cached(1) }
    }

    /// Sub-samples per axis.
    pub fn subsamples(&self) -> usize {
        self.nodes.len()
    }

    /// The nodes of row `y` of `grid` in z, top (largest z) last.
    pub fn sub_rows(&self, grid: LatLong, y: usize) -> Vec<SubRow> {
        let z_top = (PI * y as f64 / grid.height as f64).cos();
        let z_bottom = (PI * (y + 1) as f64 / grid.height as f64).cos();
        let (mid, half) = (0.5 * (z_top + z_bottom), 0.5 * (z_top - z_bottom));
        self.nodes
            .iter()
            .map(|&(xi, w)| {
                let z = mid + half * xi;
                SubRow { z, sin_theta: (1.0 - z * z).max(0.0).sqrt(), weight: half * w }
            })
            .collect()
    }

    /// The nodes in φ of one column of `grid`: offsets from the column centre in columns (in
    /// (−½, ½)) and weights in radians (summing to 2π/W).
    pub fn sub_columns(&self, grid: LatLong) -> Vec<(f64, f64)> {
        let h = TAU / grid.width as f64;
        self.nodes.iter().map(|&(xi, w)| (0.5 * xi, 0.5 * h * w)).collect()
    }
}

/// A rule chosen by [`choose_rule`], with the measured change that justified it.
#[derive(Clone, Debug, PartialEq)]
pub struct RuleChoice {
    /// The rule.
    pub rule: TexelRule,
    /// Σ|w_n − w_next| / Σ|w_next| between this rule's texel integrals and the next candidate's
    /// (the estimated share of the kernel's weight the rule misplaces).
    pub estimated_error: f64,
}

/// Sub-sample counts [`choose_rule`] tries, in order.
pub const CANDIDATE_SUBSAMPLES: [usize; 8] = [1, 2, 3, 4, 6, 8, 12, 16];

/// The smallest rule of [`CANDIDATE_SUBSAMPLES`] whose texel integrals move by at most
/// `tolerance` of their total when the sub-sample count is raised to the next candidate:
/// Σ|w_n − w_next| ≤ tolerance · Σ|w_next|, with `weights(rule)` the texel integrals of some
/// probe outputs (the same texels, in the same order, for every rule). Gauss–Legendre converges
/// geometrically for a kernel smooth over a texel, so the change to the next candidate bounds
/// the error of the rule itself. The largest candidate if none qualifies.
pub fn choose_rule(tolerance: f64, mut weights: impl FnMut(&TexelRule) -> Vec<f64>) -> RuleChoice {
    let rules: Vec<TexelRule> =
        CANDIDATE_SUBSAMPLES.iter().map(|&n| TexelRule::new(n).expect("candidates are in range")).collect();
    let mut current = weights(&rules[0]);
    let mut last_error = f64::INFINITY;
    for pair in rules.windows(2) {
        let next = weights(&pair[1]);
        let total: f64 = next.iter().map(|w| w.abs()).sum();
        let moved: f64 = current.iter().zip(&next).map(|(a, b)| (a - b).abs()).sum();
        last_error = if total > 0.0 { moved / total } else { 0.0 };
        if last_error <= tolerance {
            return RuleChoice { rule: pair[0].clone(), estimated_error: last_error };
        }
        current = next;
    }
    RuleChoice { rule: rules[rules.len() - 1].clone(), estimated_error: last_error }
}

/// Which source rows [`zonal_filter`] visits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rows {
    /// Every row in the cone, and the kernel's weight per output row is measured.
    All,
    /// Only the rows that hold light. A black row adds nothing to B, so a sparse map (the excess
    /// of a few bright texels, one luminance band) costs what its lit rows cost: the kernel of a
    /// row pair, its lobe evaluations and its transform, is the filter's main expense. The
    /// kernel's weight is not measured (it would need every row).
    Lit,
}

/// A zonally filtered map in f64, with the kernel's total weight per output row.
#[derive(Clone, Debug, PartialEq)]
pub struct ZonalMap {
    /// Columns (the source's).
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Row-major RGB.
    pub pixels: Vec<[f64; 3]>,
    /// Σ_t ∫_t k(R·ω) dω over the kept texels, per output row (the same for every column):
    /// what a white map filters to. Divide by it for a kernel normalized on the texels kept.
    /// `None` when only the lit rows were visited ([`Rows::Lit`]).
    pub row_weight: Option<Vec<f64>>,
}

impl ZonalMap {
    /// The map as f32.
    pub fn to_image(&self) -> RgbImage {
        let pixels = self.pixels.iter().map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]).collect();
        RgbImage { width: self.width, height: self.height, pixels }
    }

    /// The map divided, row by row, by the weight of the texels kept (a white map gives 1);
    /// `None` when the weights were not measured ([`Rows::Lit`]).
    pub fn normalized_image(&self) -> Option<RgbImage> {
        let weights = self.row_weight.as_ref()?;
        let pixels = self
            .pixels
            .chunks(self.width)
            .zip(weights)
            .flat_map(|(row, &w)| {
                let inv = if w != 0.0 { 1.0 / w } else { 0.0 };
                row.iter().map(move |p| [(p[0] * inv) as f32, (p[1] * inv) as f32, (p[2] * inv) as f32])
            })
            .collect();
        Some(RgbImage { width: self.width, height: self.height, pixels })
    }
}

fn check(latlong: &RgbImage, cone: f64, out_height: usize) -> Result<(), ZonalError> {
    let (width, height) = (latlong.width, latlong.height);
    if width == 0 || height == 0 || out_height == 0 {
        return Err(ZonalError::Empty { width, height, out_height });
    }
    for (w, h) in [(width, height), (width, out_height)] {
        if w.checked_mul(h).is_none_or(|n| n > MAX_ZONAL_TEXELS) {
            return Err(ZonalError::TooLarge { width: w, height: h, max: MAX_ZONAL_TEXELS });
        }
    }
    if cone.is_nan() || cone <= 0.0 || cone > PI {
        return Err(ZonalError::Cone(cone));
    }
    Ok(())
}

/// cos θ_c, or −∞ for the whole sphere (so that no texel is dropped by rounding).
fn cos_cone(cone: f64) -> f64 {
    if cone >= PI {
        f64::NEG_INFINITY
    } else {
        cone.cos()
    }
}

/// What every row pair shares: the source grid, its texel rule and the cosine tables.
struct Plan<'a, K> {
    grid: LatLong,
    kernel: &'a K,
    cone: f64,
    cos_cone: f64,
    /// n sub-rows per source row.
    sub_rows: Vec<SubRow>,
    /// (cos θ, sin θ) of each source row's centre.
    centres: Vec<(f64, f64)>,
    /// Weights in φ of the n sub-columns.
    phi_weights: Vec<f64>,
    /// cos((d + offset_j)·2π/W), sub-column j's run at j·(W/2 + 1) + d, d = 0..=W/2: contiguous
    /// in d, so the kernel loop over a row's offsets vectorizes.
    cos_nodes: Vec<f64>,
    /// cos(d·2π/W) for d = 0..=W/2.
    cos_centres: Vec<f64>,
}

impl<'a, K: Fn(f64) -> f64 + Sync> Plan<'a, K> {
    fn new(width: usize, height: usize, rule: &TexelRule, cone: f64, kernel: &'a K) -> Self {
        let grid = LatLong::new(width, height);
        let h = TAU / width as f64;
        let columns = rule.sub_columns(grid);
        let half = width / 2;
        let cos_nodes =
            columns.iter().flat_map(|&(offset, _)| (0..=half).map(move |d| ((d as f64 + offset) * h).cos())).collect();
        Plan {
            grid,
            kernel,
            cone,
            cos_cone: cos_cone(cone),
            sub_rows: (0..height).flat_map(|y| rule.sub_rows(grid, y)).collect(),
            centres: (0..height).map(|y| grid.row_theta(y).sin_cos()).map(|(s, c)| (c, s)).collect(),
            phi_weights: columns.iter().map(|c| c.1).collect(),
            cos_nodes,
            cos_centres: (0..=half).map(|d| (d as f64 * h).cos()).collect(),
        }
    }

    /// Fills `k[d]`, d = 0..=W/2, with the weight of the source texel d columns from the output
    /// texel, for source row `y` and an output row at (cos θ_R, sin θ_R) (zero where the texel's
    /// centre is outside the cone). Returns false when no texel of the row has its centre in it.
    fn pair_kernel(&self, (z_r, s_r): (f64, f64), theta_r: f64, y: usize, k: &mut [f64]) -> bool {
        // The row's centres are at least |θ_y − θ_R| from R.
        if (self.grid.row_theta(y) - theta_r).abs() > self.cone {
            return false;
        }
        let half = self.grid.width / 2;
        let (ct, st) = self.centres[y];
        // Centres pass when ct·z_R + st·s_R·cos(d h) ≥ cos θ_c, and cos(d h) falls with d on
        // [0, W/2]: the offsets in the cone are 0..end.
        let end = self.cos_centres.iter().take_while(|&&c| ct * z_r + st * s_r * c >= self.cos_cone).count();
        k.fill(0.0);
        let n = self.phi_weights.len();
        for row in &self.sub_rows[y * n..(y + 1) * n] {
            let (a, b) = (row.z * z_r, row.sin_theta * s_r);
            for (j, w) in self.phi_weights.iter().enumerate() {
                let weight = row.weight * w;
                let cos_dphi = &self.cos_nodes[j * (half + 1)..][..end];
                for (kd, c) in k[..end].iter_mut().zip(cos_dphi) {
                    *kd += weight * (self.kernel)(a + b * c);
                }
            }
        }
        end > 0
    }
}

/// Filters `latlong` (W × H) with the zonal kernel k(cos γ) truncated to the texels whose centres
/// lie within `cone` radians of R (π: the whole sphere), into a W × `out_height` lat-long map of
/// R. Texel integrals use `rule`; `rows` says whether black source rows are skipped. See the
/// module documentation for the definition and the algorithm; `progress` advances once per
/// output row.
pub fn zonal_filter(
    latlong: &RgbImage,
    kernel: impl Fn(f64) -> f64 + Sync,
    cone: f64,
    rule: &TexelRule,
    out_height: usize,
    rows: Rows,
    progress: &dyn Progress,
) -> Result<ZonalMap, ZonalError> {
    check(latlong, cone, out_height)?;
    let (width, height) = (latlong.width, latlong.height);
    let plan = Plan::new(width, height, rule, cone, &kernel);
    // Source rows to visit. Skipping a black one leaves every texel's sum as it was: its
    // spectrum is exactly zero.
    let visit: Vec<bool> =
        (0..height).map(|y| rows == Rows::All || latlong.row(y).iter().flatten().any(|&v| v != 0.0)).collect();
    let bins = width / 2 + 1;
    let mut planner = RealFftPlanner::<f64>::new();
    let forward = planner.plan_fft_forward(width);
    let inverse = planner.plan_fft_inverse(width);
    let even = EvenSpectrum::new(&mut planner, width);

    let spectra = row_spectra(latlong, &*forward, |y| visit[y]);

    let out_grid = LatLong::new(width, out_height);
    let mut pixels = vec![[0.0; 3]; width * out_height];
    let mut row_weight = vec![0.0; out_height];
    progress.start("zonal filter", out_height as u64);
    // North–south symmetry: mirroring z maps output row y_o to H_out − 1 − y_o and source row y
    // to H − 1 − y and keeps R·ω, so the kernel of (y_o, y) is also that of the mirrored pair.
    // Rows are taken in mirrored pairs; each kernel is evaluated and transformed once for both.
    let half = out_height / 2;
    let (top, bottom) = pixels.split_at_mut(half * width);
    let (top_weight, bottom_weight) = row_weight.split_at_mut(half);
    // Pairs (y_o, its mirror): bottom rows taken from the last; an odd middle row pairs with none.
    type OutRow<'a> = (&'a mut [[f64; 3]], &'a mut f64);
    let mut jobs: Vec<(usize, OutRow, Option<OutRow>)> = Vec::with_capacity(out_height - half);
    let mut bottom_rows: Vec<OutRow> = bottom.chunks_mut(width).zip(bottom_weight.iter_mut()).collect();
    for (y_out, (row, weight)) in top.chunks_mut(width).zip(top_weight.iter_mut()).enumerate() {
        let mirror = bottom_rows.pop().expect("the bottom holds at least as many rows as the top");
        jobs.push((y_out, (row, weight), Some(mirror)));
    }
    if let Some(middle) = bottom_rows.pop() {
        jobs.push((half, middle, None));
    }
    jobs.into_par_iter().for_each_init(
        || RowScratch::new(&even, &*inverse, width),
        |s, (y_out, (row, weight), mirror)| {
            let theta_r = out_grid.row_theta(y_out);
            let (s_r, z_r) = theta_r.sin_cos();
            s.acc.iter_mut().chain(s.acc_mirror.iter_mut()).for_each(|a| a.fill(Complex::new(0.0, 0.0)));
            let mut total = 0.0;
            let mut touched = false;
            for y in 0..height {
                let mirrored = mirror.is_some() && visit[height - 1 - y];
                if !(visit[y] || mirrored) || !plan.pair_kernel((z_r, s_r), theta_r, y, &mut s.half) {
                    continue;
                }
                // The even kernel's (real) spectrum.
                s.even.transform(&s.half, &mut s.kernel_spectrum);
                total += s.kernel_spectrum[0];
                touched = true;
                let sources = [(y, &mut s.acc), (height - 1 - y, &mut s.acc_mirror)];
                for (source_row, acc) in sources.into_iter().take(if mirror.is_some() { 2 } else { 1 }) {
                    let source = &spectra[source_row * 3 * bins..(source_row + 1) * 3 * bins];
                    for c in 0..3 {
                        let src = &source[c * bins..(c + 1) * bins];
                        for ((a, l), k) in acc[c].iter_mut().zip(src).zip(&s.kernel_spectrum) {
                            *a += l * k;
                        }
                    }
                }
            }
            let mut outputs = vec![(row, weight, &mut s.acc)];
            let count = if let Some((mirror_row, mirror_weight)) = mirror {
                outputs.push((mirror_row, mirror_weight, &mut s.acc_mirror));
                2
            } else {
                1
            };
            for (row, weight, acc) in outputs {
                *weight = total;
                // No source row reached this one (a sparse map's rows outside every cone): it
                // stays zero, as its transform would leave it.
                if !touched {
                    continue;
                }
                for c in 0..3 {
                    inverse_row(&*inverse, &mut acc[c], &mut s.out, &mut s.inverse_scratch);
                    for (p, v) in row.iter_mut().zip(&s.out) {
                        p[c] = *v;
                    }
                }
            }
            progress.advance(count);
        },
    );
    progress.finish();
    let row_weight = (rows == Rows::All).then_some(row_weight);
    Ok(ZonalMap { width, height: out_height, pixels, row_weight })
}

/// The spectra of every row and channel of a lat-long image, laid out [y][channel][m] (W/2 + 1
/// bins each): what the rows of a circular correlation in φ are multiplied with. Rows `wanted`
/// refuses are left zero without a transform (black rows, whose spectrum is zero).
pub(crate) fn row_spectra(
    latlong: &RgbImage,
    forward: &dyn RealToComplex<f64>,
    wanted: impl Fn(usize) -> bool + Sync,
) -> Vec<Complex<f64>> {
    let bins = latlong.width / 2 + 1;
    let mut spectra = vec![Complex::new(0.0, 0.0); latlong.height * 3 * bins];
    spectra.par_chunks_mut(3 * bins).enumerate().filter(|(y, _)| wanted(*y)).for_each_init(
        || (forward.make_input_vec(), forward.make_scratch_vec()),
        |(input, scratch), (y, out)| {
            for (c, spectrum) in out.chunks_exact_mut(bins).enumerate() {
                for (v, p) in input.iter_mut().zip(latlong.row(y)) {
                    *v = p[c] as f64;
                }
                forward.process_with_scratch(input, spectrum, scratch).expect("sizes from the plan");
            }
        },
    );
    spectra
}

/// The spectrum of an even kernel over the W offsets of a row (k_d = k_{W−d}) from its half
/// k_0..=k_{⌊W/2⌋}: K_m = Σ_d k_d e^{−2πimd/W}, m = 0..=⌊W/2⌋, which is real. A circular
/// correlation with the kernel scales bin m of a row's spectrum by K_m.
///
/// For even W = 2N, K is the DCT-I of the half, K_m = k_0 + (−1)^m k_N + 2 Σ_{d=1}^{N−1} k_d
/// cos(πmd/N), taken with a real FFT of length N rather than W (Numerical Recipes' `cosft1`):
/// x_j = ½(k_j + k_{N−j}) − sin(πj/N)(k_j − k_{N−j}) has X = FFT(x) with K_{2m} = 2 Re X_m, since
/// the sine-weighted antisymmetric part sums to zero against cos(2πjm/N); and
/// K_{2m+1} = K_{2m−1} − 2 Im X_m, since 2 sin(πj/N) sin(2πjm/N) = cos(πj(2m−1)/N) −
/// cos(πj(2m+1)/N); K_1 is summed directly. Odd W transforms the whole sequence. A clone
/// shares the plan and has its own buffers (one per thread).
#[derive(Clone)]
pub(crate) struct EvenSpectrum {
    width: usize,
    fft: Arc<dyn RealToComplex<f64>>,
    /// sin(πj/N) and cos(πj/N), j = 0..N (even W).
    sin: Vec<f64>,
    cos: Vec<f64>,
    input: Vec<f64>,
    output: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
}

impl EvenSpectrum {
    /// Buffers and plan for kernels over `width` offsets.
    pub(crate) fn new(planner: &mut RealFftPlanner<f64>, width: usize) -> Self {
        let even = width % 2 == 0;
        let n = if even { width / 2 } else { width };
        let fft = planner.plan_fft_forward(n.max(1));
        let (sin, cos) =
            if even { (0..n).map(|j| (PI * j as f64 / n as f64).sin_cos()).unzip() } else { (vec![], vec![]) };
        EvenSpectrum {
            width,
            input: fft.make_input_vec(),
            output: fft.make_output_vec(),
            scratch: fft.make_scratch_vec(),
            fft,
            sin,
            cos,
        }
    }

    /// K_0..=K_{⌊W/2⌋} of the kernel whose half is `half` (⌊W/2⌋ + 1 values), into `spectrum`.
    pub(crate) fn transform(&mut self, half: &[f64], spectrum: &mut [f64]) {
        let w = self.width;
        if w % 2 == 1 {
            for (d, x) in self.input.iter_mut().enumerate() {
                *x = half[d.min(w - d)];
            }
            self.fft
                .process_with_scratch(&mut self.input, &mut self.output, &mut self.scratch)
                .expect("sizes from the plan");
            for (k, c) in spectrum.iter_mut().zip(&self.output) {
                *k = c.re;
            }
            return;
        }
        let n = w / 2;
        // (k_j, k_{N−j}) for j = 0..N.
        let pairs = half[..n].iter().zip(half[1..=n].iter().rev());
        for ((x, (&a, &b)), s) in self.input.iter_mut().zip(pairs).zip(&self.sin) {
            *x = 0.5 * (a + b) - s * (a - b);
        }
        self.fft
            .process_with_scratch(&mut self.input, &mut self.output, &mut self.scratch)
            .expect("sizes from the plan");
        for (m, c) in self.output.iter().enumerate().take(n / 2 + 1) {
            spectrum[2 * m] = 2.0 * c.re;
        }
        // Four partial sums, so that the products are summed four at a time.
        let mut lanes = [0.0f64; 4];
        let (terms, weights) = (&half[1..n], &self.cos[1..n]);
        for (t, w) in terms.chunks(4).zip(weights.chunks(4)) {
            for ((lane, t), w) in lanes.iter_mut().zip(t).zip(w) {
                *lane += t * w;
            }
        }
        let mut odd = half[0] - half[n] + 2.0 * ((lanes[0] + lanes[1]) + (lanes[2] + lanes[3]));
        spectrum[1] = odd;
        for m in 1..=(n - 1) / 2 {
            odd -= 2.0 * self.output[m].im;
            spectrum[2 * m + 1] = odd;
        }
    }
}

/// The row whose (unnormalized) spectrum `acc` holds, into `out` (1/W applied). `acc` is used
/// as scratch.
pub(crate) fn inverse_row(
    inverse: &dyn ComplexToReal<f64>,
    acc: &mut [Complex<f64>],
    out: &mut [f64],
    scratch: &mut [Complex<f64>],
) {
    let (width, bins) = (out.len(), acc.len());
    // The DC and Nyquist bins of a real signal's spectrum are real.
    acc[0].im = 0.0;
    if width % 2 == 0 {
        acc[bins - 1].im = 0.0;
    }
    inverse.process_with_scratch(acc, out, scratch).expect("sizes from the plan");
    let scale = 1.0 / width as f64;
    out.iter_mut().for_each(|v| *v *= scale);
}

/// Per-thread buffers of [`zonal_filter`].
struct RowScratch {
    half: Vec<f64>,
    even: EvenSpectrum,
    kernel_spectrum: Vec<f64>,
    acc: [Vec<Complex<f64>>; 3],
    /// The accumulators of the mirrored output row.
    acc_mirror: [Vec<Complex<f64>>; 3],
    out: Vec<f64>,
    inverse_scratch: Vec<Complex<f64>>,
}

impl RowScratch {
    fn new(even: &EvenSpectrum, inverse: &dyn ComplexToReal<f64>, width: usize) -> Self {
        RowScratch {
            half: vec![0.0; width / 2 + 1],
            even: even.clone(),
            kernel_spectrum: vec![0.0; width / 2 + 1],
            acc: [inverse.make_input_vec(), inverse.make_input_vec(), inverse.make_input_vec()],
            acc_mirror: [inverse.make_input_vec(), inverse.make_input_vec(), inverse.make_input_vec()],
            out: inverse.make_output_vec(),
            inverse_scratch: inverse.make_scratch_vec(),
        }
    }
}

/// The texel integrals of `kernel` seen from probe output rows (the equator, 45° and the first
/// row of a W × `out_height` grid), for [`choose_rule`]: the same texels for every rule.
pub fn probe_weights(
    width: usize,
    height: usize,
    kernel: &(impl Fn(f64) -> f64 + Sync),
    cone: f64,
    out_height: usize,
    rule: &TexelRule,
) -> Vec<f64> {
    let plan = Plan::new(width, height, rule, cone, kernel);
    let out_grid = LatLong::new(width, out_height.max(1));
    let probes = [out_height / 2, out_height / 4, 0];
    let mut k = vec![0.0; width / 2 + 1];
    let mut weights = Vec::new();
    for y_out in probes {
        let theta_r = out_grid.row_theta(y_out);
        let (s_r, z_r) = theta_r.sin_cos();
        for y in 0..height {
            if plan.pair_kernel((z_r, s_r), theta_r, y, &mut k) {
                // Offsets 0 < d < W/2 stand for two texels (±d).
                weights.extend(k.iter().enumerate().map(|(d, w)| if d == 0 || 2 * d == width { *w } else { 2.0 * w }));
            }
        }
    }
    weights
}

/// The rule for `kernel` on a W × H source: [`choose_rule`] over [`probe_weights`].
pub fn rule_for_kernel(
    width: usize,
    height: usize,
    kernel: &(impl Fn(f64) -> f64 + Sync),
    cone: f64,
    out_height: usize,
    tolerance: f64,
) -> RuleChoice {
    choose_rule(tolerance, |rule| probe_weights(width, height, kernel, cone, out_height, rule))
}

/// The same sum as [`zonal_filter`], directly: for every output texel, every source texel whose
/// centre is in the cone and every sub-sample, L_t·w·k(R·ω) with R and ω from
/// [`sphere::direction`]. O(N_out·N_in·n²): for tests on small maps.
pub fn zonal_filter_reference(
    latlong: &RgbImage,
    kernel: impl Fn(f64) -> f64,
    cone: f64,
    rule: &TexelRule,
    out_height: usize,
) -> Result<ZonalMap, ZonalError> {
    check(latlong, cone, out_height)?;
    let (width, height) = (latlong.width, latlong.height);
    let (grid, out_grid) = (LatLong::new(width, height), LatLong::new(width, out_height));
    let cos_cone = cos_cone(cone);
    let h = TAU / width as f64;
    let mut pixels = Vec::with_capacity(width * out_height);
    let mut row_weight = vec![0.0; out_height];
    for y_out in 0..out_height {
        for x_out in 0..width {
            let r = out_grid.texel_direction(x_out, y_out);
            let (mut acc, mut weight) = ([0.0; 3], 0.0);
            for y in 0..height {
                for x in 0..width {
                    if r.dot(grid.texel_direction(x, y)) < cos_cone {
                        continue;
                    }
                    let mut w = 0.0;
                    for row in rule.sub_rows(grid, y) {
                        for (offset, w_phi) in rule.sub_columns(grid) {
                            let omega = sphere::direction(row.z.acos(), (x as f64 + 0.5 + offset) * h);
                            w += row.weight * w_phi * kernel(r.dot(omega));
                        }
                    }
                    let l = latlong.get(x, y);
                    for c in 0..3 {
                        acc[c] += l[c] as f64 * w;
                    }
                    weight += w;
                }
            }
            if x_out == 0 {
                row_weight[y_out] = weight;
            }
            pixels.push(acc);
        }
    }
    Ok(ZonalMap { width, height: out_height, pixels, row_weight: Some(row_weight) })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    /// A map with structure at every scale and a bright, small source.
    fn test_map(w: usize, h: usize) -> RgbImage {
        RgbImage::from_fn(w, h, |x, y| {
            let d = LatLong::new(w, h).texel_direction(x, y);
            let sun = if x == w / 3 && y == h / 3 { 500.0 } else { 0.0 };
            let v = 1.0 + 0.5 * (3.0 * d.x).sin() + (d.z > 0.2) as u8 as f64;
            [(v + sun) as f32, (0.7 * v + (x % 3) as f64 * 0.1) as f32, (0.2 + (y % 2) as f64 + sun) as f32]
        })
    }

    fn phong(s: f64) -> impl Fn(f64) -> f64 + Sync {
        move |x: f64| if x > 0.0 { (s + 1.0) / TAU * x.powf(s) } else { 0.0 }
    }

    fn max_relative_difference(a: &ZonalMap, b: &ZonalMap) -> f64 {
        let scale = b.pixels.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        a.pixels
            .iter()
            .flatten()
            .zip(b.pixels.iter().flatten())
            .map(|(p, q)| (p - q).abs() / q.abs().max(1e-6 * scale))
            .fold(0.0, f64::max)
    }

    #[test]
    fn the_even_spectrum_is_the_transform_of_the_whole_kernel() {
        let mut planner = RealFftPlanner::<f64>::new();
        for width in [2, 3, 4, 6, 8, 9, 10, 12, 15, 64, 100, 512] {
            let n = width / 2;
            // A kernel with a support shorter than the half, as the filters' are, and a full one.
            for support in [n / 3, n] {
                let half: Vec<f64> =
                    (0..=n).map(|d| if d <= support { 1.0 + (d as f64 * 1.3).sin() * 0.7 } else { 0.0 }).collect();
                let mut full: Vec<f64> = (0..width).map(|d| half[d.min(width - d)]).collect();
                let fft = planner.plan_fft_forward(width);
                let mut want = fft.make_output_vec();
                fft.process(&mut full, &mut want).unwrap();
                let mut got = vec![f64::NAN; n + 1];
                EvenSpectrum::new(&mut planner, width).transform(&half, &mut got);
                let scale: f64 = half.iter().map(|v| v.abs()).sum();
                for (m, (g, w)) in got.iter().zip(&want).enumerate() {
                    assert!((g - w.re).abs() < 1e-12 * scale, "W = {width}, m = {m}: {g} vs {}", w.re);
                    assert!(w.im.abs() < 1e-12 * scale, "an even kernel's spectrum is real");
                }
            }
        }
    }

    #[test]
    fn the_fast_filter_equals_the_direct_sum() {
        for (w, h, out_h) in [(24, 12, 12), (17, 9, 5), (32, 16, 7)] {
            let map = test_map(w, h);
            for (s, cone, n) in [(8.0, PI, 2), (8.0, 0.9, 1), (40.0, 0.731, 3), (2.0, 2.2, 2)] {
                let rule = TexelRule::new(n).unwrap();
                let fast = zonal_filter(&map, phong(s), cone, &rule, out_h, Rows::All, &NoProgress).unwrap();
                let slow = zonal_filter_reference(&map, phong(s), cone, &rule, out_h).unwrap();
                let diff = max_relative_difference(&fast, &slow);
                assert!(diff < 1e-9, "{w}x{h}→{out_h}, s={s}, cone {cone}, n={n}: {diff:e}");
                for (a, b) in fast.row_weight.as_ref().unwrap().iter().zip(slow.row_weight.as_ref().unwrap()) {
                    assert!((a - b).abs() < 1e-12 * b.abs().max(1.0), "{a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn a_white_map_filters_to_the_kernel_integral() {
        // White furnace: ∫ (s+1)/2π max(x, 0)^s dω = 1 over the whole sphere, and a constant
        // kernel 1/4π integrates exactly to 1 under any rule (the weights sum to solid angles).
        let white = RgbImage::from_fn(64, 32, |_, _| [1.0; 3]);
        let constant =
            zonal_filter(&white, |_| 1.0 / (4.0 * PI), PI, &TexelRule::midpoint(), 16, Rows::All, &NoProgress).unwrap();
        assert!(constant.pixels.iter().flatten().all(|v| (v - 1.0).abs() < 1e-12));
        for s in [1.0, 8.0, 64.0] {
            let choice = rule_for_kernel(64, 32, &phong(s), PI, 32, 1e-7);
            let map = zonal_filter(&white, phong(s), PI, &choice.rule, 32, Rows::All, &NoProgress).unwrap();
            for (row, w) in map.pixels.chunks(64).zip(map.row_weight.as_ref().unwrap()) {
                for p in row {
                    assert!((p[0] - w).abs() < 1e-12, "{} vs row weight {w}", p[0]);
                }
                assert!((w - 1.0).abs() < 1e-6, "s={s} (n={}): {w}", choice.rule.subsamples());
            }
            assert!(map.normalized_image().unwrap().pixels.iter().flatten().all(|v| (v - 1.0).abs() < 1e-6));
        }
    }

    #[test]
    fn narrow_lobes_over_coarse_texels_need_and_get_more_subsamples() {
        // Phong s = 512 (lobe width ≈ 1/√s = 2.5°) over 7.5° texels: the midpoint misplaces a
        // large share of the lobe; the chosen rule meets the tolerance, measured against n = 16.
        let kernel = phong(512.0);
        let choice = rule_for_kernel(48, 24, &kernel, PI, 24, 1e-4);
        assert!(choice.rule.subsamples() > 1, "{choice:?}");
        let best = probe_weights(48, 24, &kernel, PI, 24, &TexelRule::new(16).unwrap());
        let total: f64 = best.iter().sum();
        for (rule, within) in [(TexelRule::midpoint(), false), (choice.rule.clone(), true)] {
            let w = probe_weights(48, 24, &kernel, PI, 24, &rule);
            let moved: f64 = w.iter().zip(&best).map(|(a, b)| (a - b).abs()).sum::<f64>() / total;
            assert_eq!(moved <= 1e-4, within, "n={}: {moved:e}", rule.subsamples());
        }
    }

    #[test]
    fn the_result_is_the_same_for_any_thread_count() {
        let map = test_map(40, 20);
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                zonal_filter(&map, phong(16.0), 1.2, &TexelRule::new(2).unwrap(), 20, Rows::All, &NoProgress).unwrap()
            })
        };
        let one = run(1);
        for threads in [2, 3] {
            assert_eq!(run(threads), one, "{threads} threads");
        }
    }

    #[test]
    fn skipping_black_rows_changes_no_texel() {
        // Light in three rows only: one near each pole (whose mirror rows are black, so the
        // mirrored pairs are visited for one side) and one in the middle (the odd output row).
        let (w, h) = (32, 17);
        let lit = [1, 8, 14];
        let map = RgbImage::from_fn(w, h, |x, y| {
            let v = if lit.contains(&y) { 1.0 + (x * y % 5) as f32 } else { 0.0 };
            [v, 0.5 * v, 2.0 * v]
        });
        let rule = TexelRule::new(2).unwrap();
        for (cone, out_h) in [(PI, 17), (0.6, 9)] {
            let all = zonal_filter(&map, phong(8.0), cone, &rule, out_h, Rows::All, &NoProgress).unwrap();
            let only_lit = zonal_filter(&map, phong(8.0), cone, &rule, out_h, Rows::Lit, &NoProgress).unwrap();
            assert!(all.pixels.iter().flatten().any(|&v| v > 0.0));
            assert_eq!(all.pixels, only_lit.pixels, "cone {cone}, {out_h} rows");
            assert!(only_lit.row_weight.is_none() && only_lit.normalized_image().is_none());
        }
    }

    #[test]
    fn rotating_the_map_about_z_shifts_the_output() {
        let map = test_map(30, 15);
        let rolled = RgbImage::from_fn(30, 15, |x, y| map.get((x + 30 - 7) % 30, y));
        let rule = TexelRule::new(2).unwrap();
        let a = zonal_filter(&map, phong(8.0), 1.0, &rule, 10, Rows::All, &NoProgress).unwrap();
        let b = zonal_filter(&rolled, phong(8.0), 1.0, &rule, 10, Rows::All, &NoProgress).unwrap();
        for y in 0..10 {
            for x in 0..30 {
                let (p, q) = (b.pixels[y * 30 + x], a.pixels[y * 30 + (x + 30 - 7) % 30]);
                assert!((0..3).all(|c| (p[c] - q[c]).abs() < 1e-10 * q[c].abs().max(1.0)));
            }
        }
    }

    #[test]
    fn bad_requests_are_errors() {
        let map = test_map(8, 4);
        let rule = TexelRule::midpoint();
        assert!(matches!(
            zonal_filter(&map, phong(8.0), 1.0, &rule, 0, Rows::All, &NoProgress),
            Err(ZonalError::Empty { .. })
        ));
        assert_eq!(
            zonal_filter(&map, phong(8.0), 0.0, &rule, 4, Rows::All, &NoProgress).unwrap_err(),
            ZonalError::Cone(0.0)
        );
        assert!(zonal_filter(&map, phong(8.0), f64::NAN, &rule, 4, Rows::All, &NoProgress).is_err());
        assert!(matches!(
            zonal_filter(&map, phong(8.0), 1.0, &rule, MAX_ZONAL_TEXELS, Rows::All, &NoProgress),
            Err(ZonalError::TooLarge { .. })
        ));
        assert_eq!(TexelRule::new(0).unwrap_err(), ZonalError::Subsamples { n: 0, max: 16 });
        assert!(TexelRule::new(17).is_err());
    }
}
