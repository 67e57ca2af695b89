//! Spherical harmonic reflection maps (Ramamoorthi & Hanrahan 2002, §4, App. C steps 2–3).
//!
//! A local SHRM stores, for each reflection vector R = (α, β), the coefficients B_pq(α, β) of the
//! outgoing radiance as a function of the local view direction ω_o (eq. 6). The local frame of R
//! is R_{α,β} = R_z(β)·R_y(α): +Z along R, +X along ∂R/∂α (towards larger θ), +Y along ∂R/∂β.
//! With the lighting seen from that frame, L∘R_{α,β}, whose coefficients are
//! M(R_y(−α))·M(R_z(−β))·L, the convolution (eq. 5, App. A) gives
//!
//!   B_pq(α, β) = Σ_l ρ̂_{lp|q|} [M(R_{α,β}⁻¹) L]_lq
//!              = Σ_{m ≥ 0} a_{pq,m}(α) cos(mβ) + b_{pq,m}(α) sin(mβ)           (App. C step 3)
//!
//! where R_y preserves the parity of real SH in y, so for q ≥ 0 (d = M^l(R_y(−α)))
//!   a_{pq,m} = Σ_l ρ̂ d_{q,m} L_{l,m},  b_{pq,m} = Σ_l ρ̂ d_{q,m} L_{l,−m},
//! and for q < 0
//!   a_{pq,m} = Σ_l ρ̂ d_{q,−m} L_{l,−m}, b_{pq,m} = −Σ_l ρ̂ d_{q,−m} L_{l,m}.
//! The first sum costs O(F²P²) per pair of rows α and π − α (their rotations differ by signs
//! only, so the sum split by the parity of l serves both), the β-synthesis one inverse FFT per
//! (p, q, row):
//! O(F P² S²) in all, as in the paper. The Λ_l of eq. 5 is absorbed by the rotation matrices
//! (D^l_{m0} = Λ_l Y_lm), exactly as the paper's App. A redefinition B_lmpq = L_lm ρ̂_lpq does.

use super::brdf_sh::BrdfSh;
use super::tuning::GLOBAL_FROM_VIEWS;
use crate::io::RgbImage;
use crate::progress::Progress;
use crate::sh::convolve::{convolve_zonal, convolve_zonal_rgb};
use crate::sh::rotate::ShRotation;
use crate::sh::synth::RowSynth;
use crate::sh::wigner::YRotationPlan;
use crate::sh::{count, index, ShCoeffs};
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// An SHRM on a W×H lat-long grid of reflection vectors: (P+1)² RGB layers B_pq, index p(p+1)+q.
#[derive(Clone, Debug)]
pub struct Shrm {
    /// Order F_B of the lighting/BRDF expansion in l.
    pub f_b: usize,
    /// Order P_B of the view expansion.
    pub p_b: usize,
    /// `true` for a global SHRM (view coefficients in world axes, eq. 7–8).
    pub global: bool,
    /// The layers, each a lat-long image indexed by the reflection vector (α = θ, β = φ).
    pub layers: Vec<RgbImage>,
}

/// Errors of SHRM synthesis.
#[derive(Debug, thiserror::Error)]
pub enum ShrmError {
    /// The lighting was projected to a lower order than F_B.
    #[error("the lighting has order {have}, the SHRM needs F_B = {need}")]
    LightingOrder {
        /// Order available.
        have: usize,
        /// Order needed.
        need: usize,
    },
    /// The output grid cannot hold F_B.
    #[error("a {width}-texel-wide reflection map cannot hold order F_B = {f_b}: use at least {need} (S_B ≈ 10 F_B is the paper's rule, §5.2)")]
    TooSmall {
        /// Requested width.
        width: usize,
        /// Order.
        f_b: usize,
        /// Minimum width.
        need: usize,
    },
}

impl Shrm {
    /// Width of the lat-long grid.
    pub fn width(&self) -> usize {
        self.layers[0].width
    }
    /// Height of the lat-long grid.
    pub fn height(&self) -> usize {
        self.layers[0].height
    }
    /// Layer (p, q).
    pub fn layer(&self, p: usize, q: isize) -> &RgbImage {
        &self.layers[index(p, q)]
    }

    /// The SHRM with its view bands p multiplied by `factors[p]` (bands beyond are dropped): a
    /// window on the view truncation P_B, applied at synthesis (`render --window`).
    pub fn with_view_window(&self, factors: &[f64]) -> Shrm {
        let mut out = self.clone();
        for p in 0..=self.p_b {
            let w = factors.get(p).copied().unwrap_or(0.0) as f32;
            for q in -(p as isize)..=(p as isize) {
                for px in &mut out.layers[index(p, q)].pixels {
                    px.iter_mut().for_each(|v| *v *= w);
                }
            }
        }
        out
    }
}

/// The local frame of lat-long texel (x, y): R_{α,β} = R_z(β)·R_y(α) with (α, β) the spherical
/// angles of its reflection vector (R&H 2002, §3).
pub fn texel_frame(width: usize, height: usize, x: usize, y: usize) -> DMat3 {
    let grid = crate::sphere::LatLong::new(width, height);
    crate::sphere::frame(grid.row_theta(y), grid.column_phi(x))
}

/// The local SHRM of lighting `light` under `brdf` on a `width`×`height` lat-long grid. A
/// radially symmetric BRDF takes the 1-D path, B(R) = Σ Λ_l ρ̂_l L_lm Y_lm(R) plus `reflected`
/// (coefficients of radiance already reflected, such as bright texels filtered apart), in one
/// synthesis: the single layer B_00 = √(4π) B. Any other takes App. C ([`local_shrm`]), and
/// `reflected` must be `None`.
pub fn from_lighting(
    radial: bool,
    light: &ShCoeffs,
    brdf: &BrdfSh,
    reflected: Option<&ShCoeffs>,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> Result<Shrm, ShrmError> {
    if !radial {
        debug_assert!(reflected.is_none(), "reflected radiance is added on the 1-D path only");
        return local_shrm(light, brdf, width, height, progress);
    }
    let f_b = brdf.f;
    let too_small = ShrmError::TooSmall { width, f_b, need: 2 * f_b + 2 };
    if width < 2 * f_b + 2 {
        return Err(too_small);
    }
    let root = (4.0 * std::f64::consts::PI).sqrt();
    let mut layer = convolve_zonal_rgb(light, |l| brdf.radial_kernel(l).map(|k| k * root));
    if let Some(reflected) = reflected {
        layer = layer.plus(&convolve_zonal(reflected, |_| root));
    }
    let layer = crate::sh::synth::synthesize_latlong(&layer, width, height).map_err(|_| too_small)?;
    Ok(Shrm { f_b, p_b: 0, global: false, layers: vec![layer] })
}

/// Synthesizes the local SHRM B_pq(α, β) on a `width`×`height` lat-long grid.
pub fn local_shrm(
    light: &ShCoeffs,
    brdf: &BrdfSh,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> Result<Shrm, ShrmError> {
    let (f, p) = (brdf.f, brdf.p);
    if light.order < f {
        return Err(ShrmError::LightingOrder { have: light.order, need: f });
    }
    if width < 2 * f + 2 {
        return Err(ShrmError::TooSmall { width, f_b: f, need: 2 * f + 2 });
    }
    let synthesis = RowPairs { light, brdf, width, height, rows: RowSynth::new(width), plan: YRotationPlan::new(f, p) };
    progress.start("SHRM", height as u64);
    // Rows in mirrored pairs, α and π − α (rows y and H − 1 − y): the elements of
    // D^l(R_y(α − π)) are those of D^l(R_y(−α)) times (−1)^{l+q+m} ε_q, ε_q = −1 for q < 0
    // (`sh::wigner`'s `the_mirrored_angle_flips_signs_only`). So each sum over l, split by the
    // parity of l into A_even and A_odd, serves both rows: a = A_even + A_odd at α, and
    // (−1)^{q+m} ε_q (A_even − A_odd) at π − α (b alike). An odd middle row stands alone.
    let pairs: Vec<(usize, Option<usize>)> = (0..height / 2)
        .map(|y| (y, Some(height - 1 - y)))
        .chain((height % 2 == 1).then_some((height / 2, None)))
        .collect();
    let row_data: Vec<(Row, Option<Row>)> = pairs
        .into_par_iter()
        .map(|(y, mirror)| {
            let pair = synthesis.pair(y, mirror);
            progress.advance(1 + mirror.is_some() as u64);
            pair
        })
        .collect();
    progress.finish();
    let nlayers = count(p);
    let mut layers: Vec<RgbImage> = (0..nlayers).map(|_| RgbImage::new(width, height)).collect();
    for (top, bottom) in &row_data {
        for (y, data) in std::iter::once(top).chain(bottom) {
            for (k, layer) in layers.iter_mut().enumerate() {
                layer.pixels[y * width..(y + 1) * width].copy_from_slice(&data[k * width..(k + 1) * width]);
            }
        }
    }
    Ok(Shrm { f_b: f, p_b: p, global: false, layers })
}

/// A row's index and its layers' texels, layer-major.
type Row = (usize, Vec<[f32; 3]>);

/// The per-row synthesis of [`local_shrm`] (App. C step 3).
struct RowPairs<'a> {
    light: &'a ShCoeffs,
    brdf: &'a BrdfSh,
    width: usize,
    height: usize,
    rows: RowSynth,
    plan: YRotationPlan,
}

/// Per q and channel, the products D^l_{q,±m} L_{l,±m} that every p ≥ |q| sums with its own
/// ρ̂_lpq: triangular in (l, m ≤ l), so each (p, l) term is one contiguous multiply-add over m.
type Products = [(Vec<f64>, Vec<f64>); 3];

/// Index of (l, 0) in the triangular layout of [`Products`].
fn tri(l: usize) -> usize {
    l * (l + 1) / 2
}

/// (−1)^k.
fn parity(k: isize) -> f64 {
    if k.rem_euclid(2) == 0 {
        1.0
    } else {
        -1.0
    }
}

impl RowPairs<'_> {
    /// Row `y` (α) and, when given, its `mirror` (π − α).
    fn pair(&self, y: usize, mirror: Option<usize>) -> (Row, Option<Row>) {
        let (f, p, width) = (self.brdf.f, self.brdf.p, self.width);
        let nlayers = count(p);
        let alpha = PI * (y as f64 + 0.5) / self.height as f64;
        // Only the rows |q| ≤ P_B of D^l(R_y(−α)) are read: Wigner-d rows, O(P_B·F_B²).
        let d = self.plan.rows(-alpha);
        let mut out = vec![[0.0f32; 3]; nlayers * width];
        let mut out_mirror = mirror.map(|_| vec![[0.0f32; 3]; nlayers * width]);
        let mut dl: Products = [(); 3].map(|_| (vec![0.0; tri(f + 1)], vec![0.0; tri(f + 1)]));
        let mut synth = Synth::new(&self.rows, f);
        for q in -(p as isize)..=(p as isize) {
            self.products(&d, q, &mut dl);
            let mirror_sign = parity(q) * if q < 0 { -1.0 } else { 1.0 };
            for pp in q.unsigned_abs()..=p {
                let layer = index(pp, q);
                for (ch, (da, db)) in dl.iter().enumerate() {
                    synth.sums(self.brdf, pp, q, ch, da, db);
                    synth.row(1.0, false, &mut out[layer * width..(layer + 1) * width], ch);
                    if let Some(out_mirror) = &mut out_mirror {
                        let dest = &mut out_mirror[layer * width..(layer + 1) * width];
                        synth.row(mirror_sign, true, dest, ch);
                    }
                }
            }
        }
        ((y, out), mirror.zip(out_mirror))
    }

    /// The [`Products`] of order `q` for the rotation rows `d`.
    fn products(&self, d: &crate::sh::wigner::YRotationRows, q: isize, dl: &mut Products) {
        for l in q.unsigned_abs()..=self.brdf.f {
            let li = l as isize;
            for (ch, (da, db)) in dl.iter_mut().enumerate() {
                let (da, db) = (&mut da[tri(l)..=tri(l) + l], &mut db[tri(l)..=tri(l) + l]);
                let light_at = |m: isize| self.light.rgb[index(l, m)][ch];
                if q >= 0 {
                    da[0] = d.element(l, q, 0) * light_at(0);
                    db[0] = 0.0;
                    for m in 1..=li {
                        let dq = d.element(l, q, m);
                        da[m as usize] = dq * light_at(m);
                        db[m as usize] = dq * light_at(-m);
                    }
                } else {
                    da[0] = 0.0;
                    db[0] = 0.0;
                    for m in 1..=li {
                        let dq = d.element(l, q, -m);
                        da[m as usize] = dq * light_at(-m);
                        db[m as usize] = -dq * light_at(m);
                    }
                }
            }
        }
    }
}

/// One layer row's sums over l, split by the parity of l, and their β-synthesis.
struct Synth<'r> {
    rows: &'r RowSynth,
    f: usize,
    buffers: (Vec<realfft::num_complex::Complex<f64>>, Vec<f64>, Vec<realfft::num_complex::Complex<f64>>),
    a: Vec<f64>,
    b: Vec<f64>,
    /// [even l, odd l] partial sums of a and b.
    a_parts: [Vec<f64>; 2],
    b_parts: [Vec<f64>; 2],
}

impl<'r> Synth<'r> {
    fn new(rows: &'r RowSynth, f: usize) -> Self {
        let zero = || vec![0.0; f + 1];
        Synth {
            rows,
            f,
            buffers: rows.buffers(),
            a: zero(),
            b: zero(),
            a_parts: [zero(), zero()],
            b_parts: [zero(), zero()],
        }
    }

    /// a_{pq,m} and b_{pq,m} of channel `ch` split by the parity of l: Σ_l ρ̂_lpq × the
    /// products `da`, `db`.
    fn sums(&mut self, brdf: &BrdfSh, pp: usize, q: isize, ch: usize, da: &[f64], db: &[f64]) {
        self.a_parts.iter_mut().chain(self.b_parts.iter_mut()).for_each(|v| v.fill(0.0));
        for l in q.unsigned_abs()..=self.f {
            let r = brdf.get(l, pp, q)[ch];
            if r == 0.0 {
                continue;
            }
            let span = tri(l)..=tri(l) + l;
            let (a_l, b_l) = (&mut self.a_parts[l % 2], &mut self.b_parts[l % 2]);
            for ((av, bv), (x, y)) in a_l.iter_mut().zip(b_l.iter_mut()).zip(da[span.clone()].iter().zip(&db[span])) {
                *av += r * x;
                *bv += r * y;
            }
        }
    }

    /// Synthesizes the row into channel `ch` of `dest`: at α a = A_even + A_odd, at π − α
    /// (`mirrored`) a = (−1)^m `sign` (A_even − A_odd), b alike.
    fn row(&mut self, sign: f64, mirrored: bool, dest: &mut [[f32; 3]], ch: usize) {
        let [a_even, a_odd] = &self.a_parts;
        let [b_even, b_odd] = &self.b_parts;
        for m in 0..=self.f {
            (self.a[m], self.b[m]) = if mirrored {
                let sign = sign * parity(m as isize);
                (sign * (a_even[m] - a_odd[m]), sign * (b_even[m] - b_odd[m]))
            } else {
                (a_even[m] + a_odd[m], b_even[m] + b_odd[m])
            };
        }
        self.rows.synth(&self.a, &self.b, &mut self.buffers);
        for (x, v) in self.buffers.1.iter().enumerate() {
            dest[x][ch] = *v as f32;
        }
    }
}

/// Reflection maps of a local SHRM for `views`: per view from the local layers for a few views,
/// through the global SHRM (eq. 7–8), whose rotation per texel pays off over many views, from
/// [`GLOBAL_FROM_VIEWS`] on.
pub fn maps_of_local(local: &Shrm, views: &[DVec3]) -> Vec<RgbImage> {
    if views.len() < GLOBAL_FROM_VIEWS {
        reflection_maps(local, views)
    } else {
        reflection_maps(&to_global(local), views)
    }
}

/// Applies the rotation of texel (x, y)'s frame to the view coefficients of every band:
/// B̃_p·(α, β) = M^p(R_{α,β}) B_p·(α, β) (eq. 8) when `to_global`, the inverse otherwise.
/// M(R_z(β) R_y(α)) = M(R_z(β)) M(R_y(α)): one R_y matrix per row, then per texel the z-rotation,
/// which only mixes the (q, −q) pairs by cos qβ, sin qβ.
fn rotate_views(shrm: &Shrm, to_global: bool) -> Shrm {
    let (w, h, p) = (shrm.width(), shrm.height(), shrm.p_b);
    let n = count(p);
    let mut layers: Vec<RgbImage> = (0..n).map(|_| RgbImage::new(w, h)).collect();
    let rows: Vec<Vec<[f32; 3]>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let alpha = PI * (y as f64 + 0.5) / h as f64;
            let sign = if to_global { 1.0 } else { -1.0 };
            let ry = ShRotation::new(DMat3::from_rotation_y(sign * alpha), p);
            let mut out = vec![[0.0f32; 3]; n * w];
            let mut coeffs = vec![0.0; n];
            for x in 0..w {
                let beta = sign * 2.0 * PI * (x as f64 + 0.5) / w as f64;
                for ch in 0..3 {
                    for (i, c) in coeffs.iter_mut().enumerate() {
                        *c = shrm.layers[i].get(x, y)[ch] as f64;
                    }
                    // Global: R_y(α) first, then R_z(β). Local: R_z(−β) first, then R_y(−α).
                    let r = if to_global {
                        rotate_z(&ry.apply_scalar(&coeffs), p, beta)
                    } else {
                        ry.apply_scalar(&rotate_z(&coeffs, p, beta))
                    };
                    for i in 0..n {
                        out[i * w + x][ch] = r[i] as f32;
                    }
                }
            }
            out
        })
        .collect();
    for (y, data) in rows.iter().enumerate() {
        for (k, layer) in layers.iter_mut().enumerate() {
            layer.pixels[y * w..(y + 1) * w].copy_from_slice(&data[k * w..(k + 1) * w]);
        }
    }
    Shrm { f_b: shrm.f_b, p_b: p, global: to_global, layers }
}

/// Coefficients of f∘R_z(−γ) (f rotated by γ about +Z): c'_q = c_q cos qγ − c_−q sin qγ and
/// c'_−q = c_−q cos qγ + c_q sin qγ for q > 0.
fn rotate_z(c: &[f64], order: usize, gamma: f64) -> Vec<f64> {
    let mut out = c.to_vec();
    for q in 1..=order as isize {
        let (s, co) = (q as f64 * gamma).sin_cos();
        for p in (q as usize)..=order {
            let (i, j) = (index(p, q), index(p, -q));
            out[i] = c[i] * co - c[j] * s;
            out[j] = c[j] * co + c[i] * s;
        }
    }
    out
}

/// The global SHRM B̃_pq(α, β) (eq. 7–8) of a local one.
pub fn to_global(local: &Shrm) -> Shrm {
    if local.global {
        return local.clone();
    }
    rotate_views(local, true)
}

/// The local SHRM of a global one (inverse of [`to_global`]).
pub fn to_local(global: &Shrm) -> Shrm {
    if !global.global {
        return global.clone();
    }
    rotate_views(global, false)
}

/// The reflection map for a distant viewer in direction `view` (unit, towards the viewer):
/// B̃(α, β) = Σ_pq B̃_pq(α, β) Y_pq(view) (eq. 12) for a global SHRM, or
/// Σ_pq B_pq(α, β) Y_pq(R_{α,β}⁻¹ view) for a local one.
pub fn reflection_map(shrm: &Shrm, view: DVec3) -> RgbImage {
    let (w, h, p) = (shrm.width(), shrm.height(), shrm.p_b);
    let table = crate::sh::legendre::LegendreTable::new(p);
    let n = count(p);
    let mut global_y = vec![0.0; n];
    crate::sh::basis::eval_basis_dir(&table, view, &mut global_y);
    let mut image = RgbImage::new(w, h);
    image.pixels.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let mut ylm = vec![0.0; n];
        for (x, px) in row.iter_mut().enumerate() {
            // Y_00 is the same in every frame: a P_B = 0 SHRM (radially symmetric BRDFs) needs
            // no texel frame.
            let weights: &[f64] = if shrm.global || p == 0 {
                &global_y
            } else {
                crate::sh::basis::eval_basis_dir(&table, texel_frame(w, h, x, y).transpose() * view, &mut ylm);
                &ylm
            };
            let mut acc = [0.0f64; 3];
            for (layer, &wt) in shrm.layers.iter().zip(weights) {
                let v = layer.pixels[y * w + x];
                for ch in 0..3 {
                    acc[ch] += wt * v[ch] as f64;
                }
            }
            *px = [acc[0] as f32, acc[1] as f32, acc[2] as f32];
        }
    });
    image
}

/// Reflection maps for many views at once (eq. 12). For a global SHRM the layers are first packed
/// texel by texel, so each map is a contiguous (P+1)²-term dot product per texel; a local SHRM
/// takes [`reflection_map`] per view.
pub fn reflection_maps(shrm: &Shrm, views: &[DVec3]) -> Vec<RgbImage> {
    if !shrm.global {
        return views.iter().map(|&v| reflection_map(shrm, v)).collect();
    }
    let (w, h, n) = (shrm.width(), shrm.height(), count(shrm.p_b));
    let mut packed = vec![[0.0f32; 3]; w * h * n];
    for (k, layer) in shrm.layers.iter().enumerate() {
        for (i, v) in layer.pixels.iter().enumerate() {
            packed[i * n + k] = *v;
        }
    }
    let table = crate::sh::legendre::LegendreTable::new(shrm.p_b);
    views
        .par_iter()
        .map(|&view| {
            let mut y64 = vec![0.0; n];
            crate::sh::basis::eval_basis_dir(&table, view, &mut y64);
            let weights: Vec<f32> = y64.iter().map(|&v| v as f32).collect();
            let mut image = RgbImage::new(w, h);
            for (px, texel) in image.pixels.iter_mut().zip(packed.chunks_exact(n)) {
                let mut acc = [0.0f32; 3];
                for (c, &wt) in texel.iter().zip(&weights) {
                    acc[0] += wt * c[0];
                    acc[1] += wt * c[1];
                    acc[2] += wt * c[2];
                }
                *px = acc;
            }
            image
        })
        .collect()
}

/// The twelve view directions of Cabral et al. 1999: the vertices of an icosahedron.
pub fn icosahedron_views() -> Vec<DVec3> {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v = Vec::with_capacity(12);
    for &(a, b) in &[(1.0, t), (1.0, -t), (-1.0, t), (-1.0, -t)] {
        v.push(DVec3::new(0.0, a, b).normalize());
        v.push(DVec3::new(a, b, 0.0).normalize());
        v.push(DVec3::new(b, 0.0, a).normalize());
    }
    v
}

/// T×T view directions on a lat-long grid of the view sphere (texel centres), for an explicit
/// 4-D tabulation of reflection maps (App. C, "conversion to explicit forms").
pub fn view_grid(t: usize) -> Vec<DVec3> {
    let mut v = Vec::with_capacity(t * t);
    for j in 0..t {
        for i in 0..t {
            let theta = PI * (j as f64 + 0.5) / t as f64;
            let phi = 2.0 * PI * (i as f64 + 0.5) / t as f64;
            v.push(crate::sphere::direction(theta, phi));
        }
    }
    v
}

/// Kautz & McCool's 3-D texture B(α, β, θ_o) = Σ_p B_p0(α, β) Y_p0(θ_o) (App. C) at `slices`
/// values θ_o = π(k+½)/slices, from a local SHRM (only q = 0 terms are used).
pub fn kautz_mccool(shrm: &Shrm, slices: usize) -> Vec<RgbImage> {
    let local = to_local(shrm);
    let table = crate::sh::legendre::LegendreTable::new(local.p_b);
    let mut plm = vec![0.0; count(local.p_b)];
    (0..slices)
        .map(|k| {
            let theta = PI * (k as f64 + 0.5) / slices as f64;
            table.eval(theta.cos(), theta.sin(), &mut plm);
            let mut img = RgbImage::new(local.width(), local.height());
            for p in 0..=local.p_b {
                let wt = plm[index(p, 0)] as f32;
                let layer = local.layer(p, 0);
                for (dst, src) in img.pixels.iter_mut().zip(&layer.pixels) {
                    for ch in 0..3 {
                        dst[ch] += wt * src[ch];
                    }
                }
            }
            img
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_layers_are_the_lighting_seen_from_each_texels_frame() {
        // Eq. 6 texel by texel, independently of the per-row Wigner-d rows and of the mirrored
        // row pairs: B_pq = Σ_l ρ̂_{lp|q|} [M(R_{α,β}⁻¹) L]_lq with the whole Ivanic–Ruedenberg
        // rotation of the lighting into the texel's frame. An odd height puts a row on the
        // equator, alone; a lighting with every coefficient non-zero exercises every sign.
        let (f, p, w, h) = (7, 3, 16, 9);
        let light = ShCoeffs {
            order: f,
            rgb: (0..count(f))
                .map(|i| [(1.3 * i as f64).sin(), (0.7 * i as f64 + 0.2).cos(), 1.0 / (1.0 + i as f64)])
                .collect(),
        };
        let model =
            super::super::model::Model::new(crate::brdf::Brdf::parse("torrance-sparrow:sigma=0.3").unwrap(), false)
                .unwrap();
        let brdf = model.coefficients(f, p);
        let shrm = local_shrm(&light, &brdf, w, h, &crate::progress::NoProgress).unwrap();
        let scale = shrm.layers.iter().flat_map(|l| l.pixels.iter().flatten()).fold(0.0f32, |m, v| m.max(v.abs()));
        for y in 0..h {
            for x in 0..w {
                let seen = ShRotation::new(texel_frame(w, h, x, y).transpose(), f).apply(&light);
                for pp in 0..=p {
                    for q in -(pp as isize)..=pp as isize {
                        for c in 0..3 {
                            let expected: f64 =
                                (q.unsigned_abs()..=f).map(|l| brdf.get(l, pp, q)[c] * seen.rgb[index(l, q)][c]).sum();
                            let got = shrm.layer(pp, q).get(x, y)[c] as f64;
                            assert!(
                                (got - expected).abs() < 2e-6 * scale as f64,
                                "texel ({x}, {y}), layer ({pp}, {q}), channel {c}: {got} against {expected}"
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_view_window_scales_each_view_band_by_its_factor() {
        let layer = |v: f32| RgbImage::from_fn(4, 2, |_, _| [v, 2.0 * v, 3.0 * v]);
        let shrm = Shrm { f_b: 2, p_b: 1, global: false, layers: (0..4).map(|i| layer(1.0 + i as f32)).collect() };
        let windowed = shrm.with_view_window(&[1.0, 0.25]);
        assert_eq!(windowed.layer(0, 0).pixels, layer(1.0).pixels);
        for q in -1..=1 {
            let i = index(1, q);
            assert_eq!(windowed.layers[i].pixels, layer(0.25 * (1.0 + i as f32)).pixels);
        }
        // Missing factors drop their bands.
        assert!(shrm.with_view_window(&[1.0]).layer(1, 0).pixels.iter().flatten().all(|&v| v == 0.0));
    }
}
