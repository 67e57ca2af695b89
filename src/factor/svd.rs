//! The in-out factorization ρ(ω_i, ω_o) = Σ_k σ_k h_k(ω_o) g_k(ω_i) (Mahajan et al. 2008, eq. 2)
//! as the SVD of the sampled BRDF matrix.
//!
//! The matrix is M[o, i] = ρ(ω_i, ω_o) [· cos θ_i] · ΔΩ with ΔΩ the (equal) cell solid angle, so
//! its singular values approximate those of the integral operator (∫ ρ(ω_i, ω_o) g(ω_i) dω_i) and
//! can be compared with the paper's F_l directly; the unit singular vectors divided by √ΔΩ are
//! the L²-orthonormal factor functions g_k, h_k.
//!
//! Two methods give the same singular values:
//! - **dense**: the full n²×n² matrix and faer's SVD (any BRDF, O(n⁶) time, O(n⁴) memory);
//! - **randomized**: for large dense matrices when only the leading terms matter (Halko,
//!   Martinsson & Tropp 2011, Alg. 4.4: Gaussian sketch, two power iterations, QR, SVD of the
//!   small projected matrix), growing the rank until the leading terms hold the target energy
//!   of ‖M‖_F² (computed exactly). The leading σ are accurate to ~1e-8 relative for these
//!   decaying spectra; K can differ from the exact one only when a σ² straddles the threshold.
//! - **fft**: for an isotropic BRDF, ρ depends on φ_o − φ_i only, so with the φ grid uniform
//!   the matrix is block-circulant, M[(j_o,k_o),(j_i,k_i)] = B_{(k_o−k_i) mod n}[j_o, j_i]. A DFT
//!   over φ block-diagonalizes it: for the azimuthal frequency m, with
//!   C_m = Σ_d B_d cos(2πmd/n) and S_m = Σ_d B_d sin(2πmd/n), M maps
//!   a cos(mφ) + b sin(mφ) (profiles a, b over θ) to (C a − S b) cos(mφ) + (S a + C b) sin(mφ).
//!   So the singular values of M are those of C_0, C_{n/2} (n even) and the real 2n×2n
//!   matrices T_m = [[C_m, −S_m], [S_m, C_m]] for 0 < m < n/2 (which carry frequencies m and
//!   n−m together). Cost O(n³ log n) to sample + n/2 SVDs of 2n×2n: the way to high resolution.

use super::channel::Channel;
use super::grid::{Domain, Grid};
use crate::brdf::Brdf;
use crate::progress::Progress;
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::svd::{self, ComputeSvdVectors};
use faer::{Mat, MatRef, Par};
use rayon::prelude::*;

/// How the BRDF matrix is sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// Grid bins along cos θ and φ (n² directions per side).
    pub resolution: usize,
    /// Sphere or visible hemispheres.
    pub domain: Domain,
    /// Fold max(cos θ_i, 0) into the matrix.
    pub cosine: bool,
    /// Scalar of RGB data.
    pub channel: Channel,
}

impl Sampling {
    /// The direction grid.
    pub fn grid(&self) -> Grid {
        Grid { n: self.resolution, domain: self.domain }
    }

    /// The matrix entry for ω_i, ω_o, without the cell weight.
    #[inline]
    fn entry(&self, brdf: &Brdf, wi: glam::DVec3, wo: glam::DVec3) -> f64 {
        let v = self.channel.apply(brdf.eval(wi, wo));
        if self.cosine {
            v * wi.z.max(0.0)
        } else {
            v
        }
    }
}

/// Which SVD to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// FFT over φ for isotropic BRDFs, dense otherwise.
    Auto,
    /// The full n²×n² matrix.
    Dense,
    /// Block-circulant FFT over φ (isotropic BRDFs only).
    Fft,
    /// Randomized SVD of the dense matrix: leading terms only (any BRDF, large n).
    Randomized,
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::Auto => "auto",
            Method::Dense => "dense",
            Method::Fft => "fft",
            Method::Randomized => "randomized",
        })
    }
}

/// Errors of the factorization. They speak of the matrix and its method, not of the flags that
/// set them: the CLI (`cli/factor_brdf.rs`) words them with the flags' names.
#[derive(Debug, thiserror::Error)]
pub enum FactorError {
    /// The requested problem would not fit the memory budget.
    #[error(
        "resolution {n} on the {domain} ({dirs} directions per side) with the {method} method needs about {need} \
         of memory (limit {limit}); lower the resolution{} or raise the memory limit",
        if *method == Method::Dense { ", use an isotropic BRDF with the fft method" } else { "" }
    )]
    TooLarge {
        /// Resolution.
        n: usize,
        /// Domain.
        domain: Domain,
        /// Directions per side.
        dirs: usize,
        /// Method that would run.
        method: Method,
        /// Human-readable need.
        need: String,
        /// Human-readable limit.
        limit: String,
    },
    /// The FFT method asked for an anisotropic BRDF (its matrix is not block-circulant in φ).
    #[error("the fft method needs an isotropic BRDF; {0} is anisotropic (use the dense method)")]
    Anisotropic(String),
    /// The resolution is below 2.
    #[error("resolution must be at least 2, got {0}")]
    Resolution(usize),
    /// The SVD did not converge.
    #[error("the SVD did not converge ({0})")]
    NoConvergence(String),
}

/// The result: singular values (descending) and optionally the leading factor functions.
#[derive(Clone, Debug, PartialEq)]
pub struct Factorization {
    /// Singular values σ_k of the weighted matrix, descending (all of them, or the leading ones
    /// for the randomized method).
    pub singular_values: Vec<f64>,
    /// Σ σ² over all terms = ‖M‖_F² (exact for every method).
    pub total_energy: f64,
    /// The method that ran (`Dense` or `Fft`).
    pub method: Method,
    /// The grid the factors are sampled on.
    pub grid: Grid,
    /// g_k(ω_i) on the grid (L²-orthonormal: Σ g² ΔΩ = 1), leading terms first.
    pub g: Vec<Vec<f64>>,
    /// h_k(ω_o) on the grid, same normalization.
    pub h: Vec<Vec<f64>>,
    /// For the FFT method, the azimuthal frequency m of each singular value (pairs m, n−m are
    /// reported as m); empty for the dense method.
    pub azimuthal_frequency: Vec<usize>,
}

impl Factorization {
    /// The smallest K holding `fraction` of the total energy.
    pub fn terms_for(&self, fraction: f64) -> usize {
        super::energy::terms_for_fraction_of(&self.singular_values, self.total_energy, fraction)
    }

    /// Entry k: energy fraction of the first k+1 terms.
    pub fn cumulative_energy(&self) -> Vec<f64> {
        super::energy::cumulative_energy_of(&self.singular_values, self.total_energy)
    }

    /// Relative Frobenius error of the K-term reconstruction.
    pub fn reconstruction_error(&self, terms: usize) -> f64 {
        super::energy::reconstruction_error_of(&self.singular_values, self.total_energy, terms)
    }
}

/// Bytes needed by `method` for `terms` singular vectors.
pub fn memory_estimate(sampling: &Sampling, method: Method, terms: usize) -> u128 {
    let n = sampling.resolution as u128;
    let dirs = n * n;
    let vectors = 2 * dirs * terms as u128 * 8;
    match method {
        // Matrix + faer's workspace (about one more copy, bidiagonal reduction) + U, V if wanted.
        Method::Dense | Method::Auto => {
            let uv = if terms > 0 { 2 * dirs * dirs * 8 } else { 0 };
            2 * dirs * dirs * 8 + uv + vectors
        }
        // B_d (n³) + C_m, S_m (2 n³ / 2) + per-thread 2n×2n SVDs with vectors.
        Method::Fft => 2 * n * n * n * 8 + rayon::current_num_threads() as u128 * 6 * (2 * n) * (2 * n) * 8 + vectors,
        // The matrix + sketches of up to half its width (beyond that it falls back to dense).
        Method::Randomized => dirs * dirs * 8 * 2 + vectors,
    }
}

/// Chooses the method for `brdf`: `Auto` → FFT when isotropic, else dense.
pub fn resolve_method(brdf: &Brdf, method: Method) -> Result<Method, FactorError> {
    match method {
        Method::Auto if brdf.is_isotropic() => Ok(Method::Fft),
        Method::Auto => Ok(Method::Dense),
        Method::Fft if !brdf.is_isotropic() => Err(FactorError::Anisotropic(brdf.spec())),
        m => Ok(m),
    }
}

/// Checks the resolution and the memory budget before any work.
pub fn check_budget(sampling: &Sampling, method: Method, terms: usize, max_memory: u128) -> Result<(), FactorError> {
    if sampling.resolution < 2 {
        return Err(FactorError::Resolution(sampling.resolution));
    }
    let need = memory_estimate(sampling, method, terms);
    if need > max_memory {
        let dirs = sampling.resolution * sampling.resolution;
        return Err(FactorError::TooLarge {
            n: sampling.resolution,
            domain: sampling.domain,
            dirs,
            method,
            need: crate::limits::human_bytes(need),
            limit: crate::limits::human_bytes(max_memory),
        });
    }
    Ok(())
}

/// Factors `brdf` sampled by `sampling`, keeping the leading `terms` factor functions.
/// `method` must be resolved (`Dense` or `Fft`; `Auto` resolves here).
pub fn factor(
    brdf: &Brdf,
    sampling: &Sampling,
    method: Method,
    terms: usize,
    progress: &dyn Progress,
) -> Result<Factorization, FactorError> {
    let method = resolve_method(brdf, method)?;
    if sampling.resolution < 2 {
        return Err(FactorError::Resolution(sampling.resolution));
    }
    let terms = terms.min(sampling.grid().len());
    match method {
        Method::Fft => factor_fft(brdf, sampling, terms, progress),
        Method::Randomized => factor_randomized(brdf, sampling, RANDOMIZED_TARGET, terms, progress),
        _ => factor_dense(brdf, sampling, terms, progress),
    }
}

/// The weighted dense matrix M[o, i] = ρ(ω_i, ω_o)[cos θ_i] ΔΩ, column-major (column = ω_i).
pub fn dense_matrix(brdf: &Brdf, sampling: &Sampling, progress: &dyn Progress) -> Vec<f64> {
    let grid = sampling.grid();
    let dirs = grid.len();
    let weight = grid.cell_solid_angle();
    progress.start("sampling", dirs as u64);
    let mut data = vec![0.0; dirs * dirs];
    data.par_chunks_mut(dirs).enumerate().for_each(|(i, col)| {
        let wi = grid.direction(i);
        for (o, x) in col.iter_mut().enumerate() {
            *x = sampling.entry(brdf, wi, grid.direction(o)) * weight;
        }
        progress.advance(1);
    });
    progress.finish();
    data
}

fn factor_dense(
    brdf: &Brdf,
    sampling: &Sampling,
    terms: usize,
    progress: &dyn Progress,
) -> Result<Factorization, FactorError> {
    let grid = sampling.grid();
    let dirs = grid.len();
    let data = dense_matrix(brdf, sampling, progress);
    let m = MatRef::from_column_major_slice(&data, dirs, dirs);
    progress.start("SVD", 1);
    let (s, u, v) = run_svd(m, terms > 0)?;
    progress.finish();
    let scale = 1.0 / grid.cell_solid_angle().sqrt();
    let (mut g, mut h) = (Vec::new(), Vec::new());
    if let (Some(u), Some(v)) = (u, v) {
        for k in 0..terms {
            h.push((0..dirs).map(|r| u[(r, k)] * scale).collect());
            g.push((0..dirs).map(|r| v[(r, k)] * scale).collect());
        }
    }
    let total_energy = s.iter().map(|v| v * v).sum();
    Ok(Factorization {
        singular_values: s,
        total_energy,
        method: Method::Dense,
        grid,
        g,
        h,
        azimuthal_frequency: vec![],
    })
}

pub(crate) type Svd = (Vec<f64>, Option<Mat<f64>>, Option<Mat<f64>>);

/// faer's SVD, sequential so that results are bit-identical for any thread count.
pub(crate) fn run_svd(a: MatRef<'_, f64>, vectors: bool) -> Result<Svd, FactorError> {
    let (rows, cols) = a.shape();
    let size = rows.min(cols);
    let mut s = Diag::<f64>::zeros(size);
    let want = if vectors { ComputeSvdVectors::Thin } else { ComputeSvdVectors::No };
    let mut u = vectors.then(|| Mat::<f64>::zeros(rows, size));
    let mut v = vectors.then(|| Mat::<f64>::zeros(cols, size));
    let par = Par::Seq;
    let mut mem = MemBuffer::new(svd::svd_scratch::<f64>(rows, cols, want, want, par, Default::default()));
    svd::svd(
        a,
        s.as_mut(),
        u.as_mut().map(|m| m.as_mut()),
        v.as_mut().map(|m| m.as_mut()),
        par,
        MemStack::new(&mut mem),
        Default::default(),
    )
    .map_err(|e| FactorError::NoConvergence(format!("{e:?}")))?;
    let values = s.column_vector().iter().map(|x| x.max(0.0)).collect();
    Ok((values, u, v))
}

/// One block's singular triplets, before the global sort.
struct BlockSvd {
    m: usize,
    values: Vec<f64>,
    u: Option<Mat<f64>>,
    v: Option<Mat<f64>>,
}

fn factor_fft(
    brdf: &Brdf,
    sampling: &Sampling,
    terms: usize,
    progress: &dyn Progress,
) -> Result<Factorization, FactorError> {
    let grid = sampling.grid();
    let n = grid.n;
    let weight = grid.cell_solid_angle();
    // b[(jo·n + ji)·n + d] = ρ(ω_i = (ji, k=0), ω_o = (jo, k=d)) ΔΩ: one φ_o − φ_i = d·2π/n row
    // per (j_o, j_i) pair, transformed in place by a real FFT over d.
    progress.start("sampling", (n * n) as u64);
    let half = n / 2 + 1;
    let mut spectra = vec![[0.0f64; 2]; n * n * half];
    let fft = realfft::RealFftPlanner::<f64>::new().plan_fft_forward(n);
    spectra.par_chunks_mut(half).enumerate().for_each_init(
        || (fft.make_input_vec(), fft.make_output_vec(), fft.make_scratch_vec()),
        |(input, output, scratch), (pair, out)| {
            let (jo, ji) = (pair / n, pair % n);
            let wi = grid.direction_jk(ji, 0);
            for (d, x) in input.iter_mut().enumerate() {
                *x = sampling.entry(brdf, wi, grid.direction_jk(jo, d)) * weight;
            }
            // Lengths match by construction, so the FFT cannot fail.
            if fft.process_with_scratch(input, output, scratch).is_ok() {
                for (o, c) in out.iter_mut().zip(output.iter()) {
                    // X_m = Σ_d x_d e^{−2πimd/n} = C − iS.
                    *o = [c.re, -c.im];
                }
            }
            progress.advance(1);
        },
    );
    progress.finish();
    let spec = |m: usize, jo: usize, ji: usize| spectra[(jo * n + ji) * half + m];
    // Frequencies 0 ..= n/2; m = 0 and m = n/2 (n even) are real n×n blocks.
    let last = n / 2;
    progress.start("SVD", (last + 1) as u64);
    let blocks: Vec<Result<BlockSvd, FactorError>> = (0..=last)
        .into_par_iter()
        .map(|m| {
            let real_block = m == 0 || (n % 2 == 0 && m == last);
            let a = if real_block {
                Mat::from_fn(n, n, |r, c| spec(m, r, c)[0])
            } else {
                Mat::from_fn(2 * n, 2 * n, |r, c| {
                    let [cm, sm] = spec(m, r % n, c % n);
                    match (r < n, c < n) {
                        (true, true) | (false, false) => cm,
                        (true, false) => -sm,
                        (false, true) => sm,
                    }
                })
            };
            let (values, u, v) = run_svd(a.as_ref(), terms > 0)?;
            progress.advance(1);
            Ok(BlockSvd { m, values, u, v })
        })
        .collect();
    progress.finish();
    let blocks = blocks.into_iter().collect::<Result<Vec<_>, _>>()?;
    // Global order: value descending, ties by (m, index) so the order is deterministic.
    let mut all: Vec<(f64, usize, usize)> = blocks
        .iter()
        .enumerate()
        .flat_map(|(b, blk)| blk.values.iter().enumerate().map(move |(i, &s)| (s, b, i)))
        .collect();
    all.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let singular_values: Vec<f64> = all.iter().map(|t| t.0).collect();
    let azimuthal_frequency = all.iter().map(|t| blocks[t.1].m).collect();
    let (mut g, mut h) = (Vec::new(), Vec::new());
    for &(_, b, i) in all.iter().take(terms) {
        let blk = &blocks[b];
        if let (Some(u), Some(v)) = (&blk.u, &blk.v) {
            h.push(expand_vector(u.as_ref(), i, blk.m, n, weight));
            g.push(expand_vector(v.as_ref(), i, blk.m, n, weight));
        }
    }
    let total_energy = singular_values.iter().map(|v| v * v).sum();
    Ok(Factorization { singular_values, total_energy, method: Method::Fft, grid, g, h, azimuthal_frequency })
}

/// A block singular vector (column `col`) as a function on the grid: for 0 < m < n/2 the
/// coefficients (a; b) become √(2/n)(a_j cos(mk·2π/n) + b_j sin(mk·2π/n)); for m = 0, a_j/√n;
/// for m = n/2, a_j (−1)^k/√n. Divided by √ΔΩ for L²-orthonormal functions.
fn expand_vector(mat: MatRef<'_, f64>, col: usize, m: usize, n: usize, weight: f64) -> Vec<f64> {
    let scale = 1.0 / weight.sqrt();
    let alpha = 2.0 * std::f64::consts::PI * m as f64 / n as f64;
    let real_block = mat.nrows() == n;
    let mut out = vec![0.0; n * n];
    for j in 0..n {
        for k in 0..n {
            let (s, c) = (alpha * k as f64).sin_cos();
            out[j * n + k] = scale
                * if real_block {
                    mat[(j, col)] * c / (n as f64).sqrt()
                } else {
                    (2.0 / n as f64).sqrt() * (mat[(j, col)] * c + mat[(n + j, col)] * s)
                };
        }
    }
    out
}

/// Energy fraction the randomized method captures by default (the largest standard fraction).
pub const RANDOMIZED_TARGET: f64 = 0.999;

/// Householder QR with Par::Seq (bit-reproducible), returning the thin Q.
fn orthonormal_basis(mut a: Mat<f64>) -> Mat<f64> {
    use faer::linalg::householder;
    use faer::linalg::qr::no_pivoting::factor as qr;
    let (m, n) = a.shape();
    let par = Par::Seq;
    let bs = qr::recommended_block_size::<f64>(m, n);
    let mut coeff = Mat::<f64>::zeros(bs, n.min(m));
    let mut mem = MemBuffer::new(qr::qr_in_place_scratch::<f64>(m, n, bs, par, Default::default()));
    qr::qr_in_place(a.as_mut(), coeff.as_mut(), par, MemStack::new(&mut mem), Default::default());
    let mut q = Mat::<f64>::identity(m, n.min(m));
    let mut mem = MemBuffer::new(householder::apply_block_householder_sequence_on_the_left_in_place_scratch::<f64>(
        m,
        bs,
        n.min(m),
    ));
    householder::apply_block_householder_sequence_on_the_left_in_place_with_conj(
        a.as_ref(),
        coeff.as_ref(),
        faer::Conj::No,
        q.as_mut(),
        par,
        MemStack::new(&mut mem),
    );
    q
}

/// a · b with Par::Seq.
fn product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(a.nrows(), b.ncols());
    faer::linalg::matmul::matmul(out.as_mut(), faer::Accum::Replace, a, b, 1.0, Par::Seq);
    out
}

/// A deterministic standard-normal N×l sketch (SplitMix64 + Box–Muller, fixed seed): the same
/// inputs give the same factors on every run and thread count.
fn gaussian_sketch(rows: usize, cols: usize) -> Mat<f64> {
    let mut state: u64 = 0x5EED_F00D_CAFE_D00D;
    let mut next = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    };
    let mut values = Vec::with_capacity(rows * cols);
    while values.len() < rows * cols {
        let (u1, u2) = (next(), next());
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (2.0 * std::f64::consts::PI * u2).sin_cos();
        values.push(r * c);
        values.push(r * s);
    }
    Mat::from_fn(rows, cols, |i, j| values[j * rows + i])
}

/// Randomized SVD (Halko, Martinsson & Tropp 2011, Alg. 4.4 with q = 2 power iterations and
/// 16 columns of oversampling): the rank doubles from 64 until the leading terms hold
/// `target_energy` of ‖M‖_F²; falls back to the dense SVD past half the matrix width.
pub fn factor_randomized(
    brdf: &Brdf,
    sampling: &Sampling,
    target_energy: f64,
    terms: usize,
    progress: &dyn Progress,
) -> Result<Factorization, FactorError> {
    let grid = sampling.grid();
    let dirs = grid.len();
    let data = dense_matrix(brdf, sampling, progress);
    let m = MatRef::from_column_major_slice(&data, dirs, dirs);
    let total_energy: f64 = data.iter().map(|x| x * x).sum();
    let oversample = 16;
    let mut rank = 64.max(terms);
    progress.start("randomized SVD", 1);
    loop {
        let width = rank + oversample;
        if 2 * width >= dirs {
            progress.finish();
            return factor_dense(brdf, sampling, terms, progress).map(|f| Factorization { method: Method::Dense, ..f });
        }
        let mut q = orthonormal_basis(product(m, gaussian_sketch(dirs, width).as_ref()));
        for _ in 0..2 {
            let z = orthonormal_basis(product(m.transpose(), q.as_ref()));
            q = orthonormal_basis(product(m, z.as_ref()));
        }
        // B = Qᵀ M (width × N); M ≈ Q B, and B's singular values approximate M's leading ones.
        let b = product(q.as_ref().transpose(), m);
        let (s, u, v) = run_svd(b.as_ref(), terms > 0)?;
        let captured: f64 = s.iter().take(rank).map(|x| x * x).sum();
        if captured >= target_energy * total_energy || total_energy == 0.0 {
            progress.finish();
            let scale = 1.0 / grid.cell_solid_angle().sqrt();
            let (mut g, mut h) = (Vec::new(), Vec::new());
            if let (Some(u), Some(v)) = (u, v) {
                let hq = product(q.as_ref(), u.as_ref());
                for k in 0..terms.min(rank) {
                    h.push((0..dirs).map(|r| hq[(r, k)] * scale).collect());
                    g.push((0..dirs).map(|r| v[(r, k)] * scale).collect());
                }
            }
            let singular_values = s.into_iter().take(rank).collect();
            return Ok(Factorization {
                singular_values,
                total_energy,
                method: Method::Randomized,
                grid,
                g,
                h,
                azimuthal_frequency: vec![],
            });
        }
        rank *= 2;
    }
}
