//! Perlin gradient noise in 1–3 dimensions (Perlin 1985, with the quintic fade and the
//! gradient set of "Improving Noise", 2002), fbm and turbulence, and its conservative extension
//! to ranges (Heidrich, Slusallek & Seidel 1998, §3.1: noise is one of the "more complicated
//! features").
//!
//! Inside one lattice cell noise is a polynomial of the fractional coordinates t = p − cell, so
//! when a range lies in one cell the very same code runs with interval numbers. Affine inputs
//! take a first-order Taylor extension instead ([`taylor_cell`]): the value and gradient at the
//! centre of the t box, computed in `f64`, and the Lagrange remainder bounded with interval
//! ranges of the second derivatives over the box — one combination of the input forms and one
//! new noise symbol, where the formula takes ~40 affine operations and 10 new symbols, and
//! narrower on the ranges that matter (on wide ranges the formula is evaluated as well and the
//! narrower result kept). A range that straddles cells is split: each touched cell (at most
//! [`MAX_CELLS`]) is evaluated on its part of the box with fresh inputs and the hull of the
//! bounds is taken; beyond that the global bound is used: the value is a convex combination (fade weights in [0, 1] summing to 1) of
//! g·d with gradient components in {−1, 0, 1}, at most two non-zero, and |dᵢ| ≤ 1, so
//! |snoise| ≤ 2 in 2-D and 3-D and ≤ 1 in 1-D (gradients of magnitude ≤ 1).

use crate::affine::approx::{fade_point, fade_slack, UNIT_ROUNDOFF};
use crate::affine::interval::up;
use crate::affine::{Interval, Real};
use crate::rng::SplitMix64;
use std::sync::OnceLock;

/// Most lattice cells evaluated one by one for a range.
pub const MAX_CELLS: i64 = 64;

/// The lattice repeats every `PERIOD` cells along each axis (the hash reduces cell indices
/// modulo 256).
const PERIOD: f64 = 256.0;

/// 2⁵²: from here on every double is an integer (see [`snoise`]).
const INTEGRAL: f64 = 4_503_599_627_370_496.0;

/// Ranges over at most this many cells get the tightest bound of each cell (see [`snoise`]).
const FEW_CELLS: i64 = 4;

/// Rigorous bound on |snoise| by dimension (module docs), with room for rounding.
pub fn bound(dim: usize) -> f64 {
    if dim == 1 {
        1.0 + 1e-9
    } else {
        2.0 + 1e-9
    }
}

fn perm() -> &'static [u8; 512] {
    static PERM: OnceLock<[u8; 512]> = OnceLock::new();
    PERM.get_or_init(|| {
        // A fixed pseudo-random permutation (Fisher–Yates with a fixed seed).
        let mut p: [u8; 256] = std::array::from_fn(|i| i as u8);
        let mut rng = SplitMix64::new(0x5EED_F00D);
        for i in (1..256).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            p.swap(i, j);
        }
        std::array::from_fn(|i| p[i & 255])
    })
}

fn hash(cell: [i64; 3]) -> u8 {
    let p = perm();
    let w = |x: i64| x.rem_euclid(256) as usize;
    p[(p[(p[w(cell[0])] as usize + w(cell[1])) & 255] as usize + w(cell[2])) & 255]
}

/// Quintic fade 6t⁵ − 15t⁴ + 10t³, one primitive of the arithmetic ([`Real::fade`]).
fn fade<N: Real>(t: &N) -> N {
    t.fade()
}

fn lerp<N: Real>(w: &N, a: &N, b: &N) -> N {
    a.add(&w.mul(&b.sub(a)))
}

/// Σ gᵢ·dᵢ for gradient components in {−1, 0, 1}. The first two non-zero terms are combined
/// in one operation (−a + b as b − a, −a − b as −(a + b): the same `f64` results as negating
/// first, since IEEE rounding is symmetric).
fn signed_sum<N: Real>(terms: &[(i8, &N)]) -> N {
    let mut nonzero = terms.iter().filter(|t| t.0 != 0);
    let mut acc = match (nonzero.next(), nonzero.next()) {
        (None, _) => return N::constant(0.0),
        (Some(&(g, a)), None) => return if g > 0 { a.clone() } else { a.neg() },
        (Some(&(ga, a)), Some(&(gb, b))) => match (ga > 0, gb > 0) {
            (true, true) => a.add(b),
            (true, false) => a.sub(b),
            (false, true) => b.sub(a),
            (false, false) => a.add(b).neg(),
        },
    };
    for &(g, d) in nonzero {
        acc = if g > 0 { acc.add(d) } else { acc.sub(d) };
    }
    acc
}

/// The gradients of 2-D noise.
const G2: [(i8, i8); 8] = [(1, 1), (-1, 1), (1, -1), (-1, -1), (1, 0), (-1, 0), (0, 1), (0, -1)];

/// The 12 cube-edge directions of improved noise, 4 repeated to make 16.
const G3: [(i8, i8, i8); 16] = [
    (1, 1, 0),
    (-1, 1, 0),
    (1, -1, 0),
    (-1, -1, 0),
    (1, 0, 1),
    (-1, 0, 1),
    (1, 0, -1),
    (-1, 0, -1),
    (0, 1, 1),
    (0, -1, 1),
    (0, 1, -1),
    (0, -1, -1),
    (1, 1, 0),
    (0, -1, 1),
    (-1, 1, 0),
    (0, -1, -1),
];

/// The 1-D gradient of hash `h`: ±{1/8, …, 8/8} (exact multiples, |g| ≤ 1).
fn gradient_1d(h: u8) -> f64 {
    ((h & 7) + 1) as f64 / 8.0 * if h & 8 != 0 { -1.0 } else { 1.0 }
}

/// The gradient vector of hash `h` in `dim` dimensions (unused axes 0).
fn gradient(dim: usize, h: u8) -> [f64; 3] {
    match dim {
        1 => [gradient_1d(h), 0.0, 0.0],
        2 => {
            let (gx, gy) = G2[(h & 7) as usize];
            [gx as f64, gy as f64, 0.0]
        }
        _ => {
            let (gx, gy, gz) = G3[(h & 15) as usize];
            [gx as f64, gy as f64, gz as f64]
        }
    }
}

/// Gradient · offset for a corner; `d` are the offsets t − corner.
fn gradient_dot<N: Real>(dim: usize, h: u8, d: [&N; 3]) -> N {
    match dim {
        1 => d[0].mul(&N::constant(gradient_1d(h))),
        2 => {
            let (gx, gy) = G2[(h & 7) as usize];
            signed_sum(&[(gx, d[0]), (gy, d[1])])
        }
        _ => {
            let (gx, gy, gz) = G3[(h & 15) as usize];
            signed_sum(&[(gx, d[0]), (gy, d[1]), (gz, d[2])])
        }
    }
}

/// Noise inside one cell, from the fractional coordinates t (unused axes ignored).
fn cell_eval<N: Real>(dim: usize, cell: [i64; 3], t: &[N; 3]) -> N {
    let one = N::constant(1.0);
    let offs: [N; 3] = [t[0].sub(&one), t[1].sub(&one), t[2].sub(&one)];
    let corner = |dx: usize, dy: usize, dz: usize| -> N {
        let c = [cell[0] + dx as i64, cell[1] + dy as i64, cell[2] + dz as i64];
        let pick = |k: usize, on: usize| if on == 1 { &offs[k] } else { &t[k] };
        gradient_dot(dim, hash(c), [pick(0, dx), pick(1, dy), pick(2, dz)])
    };
    let wx = fade(&t[0]);
    match dim {
        1 => lerp(&wx, &corner(0, 0, 0), &corner(1, 0, 0)),
        2 => {
            let wy = fade(&t[1]);
            let a = lerp(&wx, &corner(0, 0, 0), &corner(1, 0, 0));
            let b = lerp(&wx, &corner(0, 1, 0), &corner(1, 1, 0));
            lerp(&wy, &a, &b)
        }
        _ => {
            let (wy, wz) = (fade(&t[1]), fade(&t[2]));
            let a0 = lerp(&wx, &corner(0, 0, 0), &corner(1, 0, 0));
            let b0 = lerp(&wx, &corner(0, 1, 0), &corner(1, 1, 0));
            let a1 = lerp(&wx, &corner(0, 0, 1), &corner(1, 0, 1));
            let b1 = lerp(&wx, &corner(0, 1, 1), &corner(1, 1, 1));
            lerp(&wz, &lerp(&wy, &a0, &b0), &lerp(&wy, &a1, &b1))
        }
    }
}

/// Allowance for the rounding of the point evaluation of noise in a cell ([`cell_eval`] in
/// `f64`) against the exact polynomial, for t ∈ [0, 1]³. Offsets t − 1 are off by ≤ u, corner
/// values (|·| ≤ 2) by ≤ 4u, fade weights by ≤ [`fade_slack`]`(1)` = 2048u; a lerp
/// a + w·(b − a) with |a|, |b| ≤ 2 and error ≤ E in a and b has error ≤ 3E + 4·2048u + 16u,
/// so three levels stay below 1.1·10⁵u ≈ 1.3·10⁻¹¹. The value at the expansion point is the
/// same evaluation, off by as much again; the allowance is about 8 times their sum.
const VALUE_ROUNDING: f64 = 2e-10;

/// Allowance for the rounding of [`cell_gradient`] (8 corners of terms |·| ≤ 4 built from
/// fade values off by ≤ 2048u and fade derivatives off by ≤ 64u: < 10⁵u ≈ 1.1·10⁻¹¹ per
/// component), with the same margin.
const GRADIENT_ROUNDING: f64 = 1e-10;

/// The corners of a cell in `dim` dimensions: offsets e ∈ {0, 1}^dim (unused axes 0) and the
/// gradients there.
fn corners(dim: usize, cell: [i64; 3]) -> ([[f64; 3]; 8], [[f64; 3]; 8], usize) {
    let n = 1usize << dim;
    let (mut e, mut g) = ([[0.0; 3]; 8], [[0.0; 3]; 8]);
    for c in 0..n {
        e[c] = [(c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64];
        let at = [cell[0] + (c & 1) as i64, cell[1] + ((c >> 1) & 1) as i64, cell[2] + ((c >> 2) & 1) as i64];
        g[c] = gradient(dim, hash(at));
    }
    (e, g, n)
}

/// fade'(t) = 30t²(t − 1)².
fn fade_d1(t: f64) -> f64 {
    let s = t * (1.0 - t);
    30.0 * s * s
}

/// Gradient of noise in a cell at the point t ∈ [0, 1]³ of the cell:
/// n = Σ_c W_c(t)·L_c(t) with weights W_c = Πₖ (eₖ ? wₖ : 1 − wₖ), wₖ = fade(tₖ), and corner
/// values L_c = g_c·(t − e_c), so ∂ₖn = Σ_c (∂ₖW_c·L_c + W_c·g_c,ₖ).
fn cell_gradient(dim: usize, t: &[f64; 3], e: &[[f64; 3]; 8], g: &[[f64; 3]; 8], n: usize) -> [f64; 3] {
    let w: [f64; 3] = std::array::from_fn(|k| fade_point(t[k]));
    let dw: [f64; 3] = std::array::from_fn(|k| fade_d1(t[k]));
    let mut grad = [0.0; 3];
    for c in 0..n {
        let l: f64 = (0..dim).map(|k| g[c][k] * (t[k] - e[c][k])).sum();
        let f: [f64; 3] = std::array::from_fn(|k| if e[c][k] == 1.0 { w[k] } else { 1.0 - w[k] });
        let df: [f64; 3] = std::array::from_fn(|k| if e[c][k] == 1.0 { dw[k] } else { -dw[k] });
        for k in 0..dim {
            // W_c and ∂ₖW_c over the used axes.
            let (mut wc, mut dwc) = (1.0, 1.0);
            for j in 0..dim {
                wc *= f[j];
                dwc *= if j == k { df[j] } else { f[j] };
            }
            grad[k] += dwc * l + wc * g[c][k];
        }
    }
    grad
}

/// Slack added to every bound of a second derivative: the bounds are computed in plain `f64`
/// interval arithmetic (no directed rounding) from inputs off by at most [`fade_slack`]`(1)`,
/// through at most ~40 operations on magnitudes ≤ 100, so they are off by < 10⁻¹⁰.
const HESSIAN_SLACK: f64 = 1e-9;

/// Largest width of the sub-boxes over which the second derivatives are bounded (see
/// [`hessian_hull`]).
const HESSIAN_PIECE: f64 = 0.15;

/// Most sub-boxes per axis for a range inside one cell.
const HESSIAN_PIECES: usize = 4;

/// Most sub-boxes per axis for each cell of a range that straddles several (many cells at
/// coarse levels; only the hull of their bounds is kept).
const MULTI_CELL_PIECES: usize = 3;

/// An interval of plain `f64` arithmetic (rounding is covered by [`HESSIAN_SLACK`]).
#[derive(Clone, Copy, Debug)]
struct Iv(f64, f64);

/// min and max of finite numbers (no NaN handling needed: one instruction each).
fn fmin(a: f64, b: f64) -> f64 {
    if a < b {
        a
    } else {
        b
    }
}

fn fmax(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

impl Iv {
    fn point(x: f64) -> Iv {
        Iv(x, x)
    }
    fn add(self, o: Iv) -> Iv {
        Iv(self.0 + o.0, self.1 + o.1)
    }
    fn mul(self, o: Iv) -> Iv {
        let p = [self.0 * o.0, self.0 * o.1, self.1 * o.0, self.1 * o.1];
        Iv(fmin(fmin(p[0], p[1]), fmin(p[2], p[3])), fmax(fmax(p[0], p[1]), fmax(p[2], p[3])))
    }
    fn scale(self, k: f64) -> Iv {
        let (p, q) = (k * self.0, k * self.1);
        Iv(fmin(p, q), fmax(p, q))
    }
    fn abs_max(self) -> f64 {
        fmax(self.0.abs(), self.1.abs())
    }
}

/// (1 − w)·a + w·b for w ∈ `w` ⊆ [0, 1], a ∈ `a`, b ∈ `b`: increasing in a and b and linear
/// in w, so the extremes are at the ends of each.
fn lerp_iv(w: Iv, a: Iv, b: Iv) -> Iv {
    let at = |w: f64, x: f64, y: f64| x + w * (y - x);
    Iv(fmin(at(w.0, a.0, b.0), at(w.1, a.0, b.0)), fmax(at(w.0, a.1, b.1), at(w.1, a.1, b.1)))
}

/// A corner value as a linear function of t: slopes and constant.
#[derive(Clone, Copy, Debug, Default)]
struct Lin([f64; 3], f64);

impl Lin {
    fn sub(self, o: Lin) -> Lin {
        Lin([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]], self.1 - o.1)
    }
    /// (1 − w)·self + w·o.
    fn lerp(self, w: f64, o: Lin) -> Lin {
        let l = |x: f64, y: f64| x + w * (y - x);
        Lin([l(self.0[0], o.0[0]), l(self.0[1], o.0[1]), l(self.0[2], o.0[2])], l(self.1, o.1))
    }
}

/// Ranges of fade (clamped to [0, 1], where it maps the cell), fade' = 30s² with s = t(1 − t)
/// (largest at the point closest to ½, smallest at an end) and fade'' = 60·h with
/// h = t(t − 1)(2t − 1) (extremes at the ends or at the roots t = (3 ∓ √3)/6 of h') over
/// [a, b] ⊆ [0, 1].
fn fade_ranges(a: f64, b: f64) -> (Iv, Iv, Iv) {
    let fs = fade_slack(1.0);
    let w = Iv(fmax(fade_point(a) - fs, 0.0), fmin(fade_point(b) + fs, 1.0));
    let s = |t: f64| t * (1.0 - t);
    let (smin, smax) = (fmin(s(a), s(b)), s(0.5f64.clamp(a, b)));
    let d1 = Iv(30.0 * smin * smin, 30.0 * smax * smax);
    let h = |t: f64| t * (t - 1.0) * (2.0 * t - 1.0);
    let (mut lo, mut hi) = (fmin(h(a), h(b)), fmax(h(a), h(b)));
    const R: f64 = 0.28867513459481287; // √3/6
    for x in [0.5 - R, 0.5 + R] {
        if x > a && x < b {
            lo = fmin(lo, h(x));
            hi = fmax(hi, h(x));
        }
    }
    (w, d1, Iv(60.0 * lo, 60.0 * hi))
}

/// Ranges of the second derivatives of noise over the box `bx` ⊆ [0, 1]^m of a cell, in the
/// coordinates of its `m` active axes (the fixed axes are already folded into the corner values
/// `lin`, which are then lerps of linear functions and still linear; corner bit k is active
/// axis k): the diagonal ∂ᵢᵢn as intervals and max |∂ᵢ∂ⱼn| for i ≠ j. Writing n along axis i
/// as Σ W⁽⁻ⁱ⁾·(L_c + wᵢ·ΔᵢL_c) over the corners c with eᵢ = 0 (W⁽⁻ⁱ⁾ the weights of the other
/// axes, ΔᵢL_c = L_{c+eᵢ} − L_c, linear in t with slope Δᵢg_c,ᵢ along i):
///   ∂ᵢᵢn = Σ W⁽⁻ⁱ⁾·(wᵢ''·ΔᵢL_c + 2wᵢ'·Δᵢg_c,ᵢ),
///   ∂ᵢ∂ⱼn = Σ W⁽⁻ⁱʲ⁾·(wᵢ'wⱼ'·ΔᵢΔⱼL_c + wᵢ'·Σ_{eⱼ} Wⱼ·Δᵢg_c,ⱼ + wⱼ'·Σ_{eᵢ} Wᵢ·Δⱼg_c,ᵢ),
/// each evaluated in interval arithmetic over the box, the weighted sums by nested lerps.
fn hessian_ranges<const M: usize>(bx: &[Iv; 3], lin: &[Lin; 8]) -> ([Iv; 3], [[f64; 3]; 3]) {
    let (m, n) = (M, 1usize << M);
    let (mut w, mut d1, mut d2) = ([Iv::point(0.0); 3], [Iv::point(0.0); 3], [Iv::point(0.0); 3]);
    for k in 0..m {
        (w[k], d1[k], d2[k]) = fade_ranges(bx[k].0, bx[k].1);
    }
    let range = |l: &Lin| {
        let mut r = Iv::point(l.1);
        for k in 0..m {
            r = r.add(bx[k].scale(l.0[k]));
        }
        r
    };
    // Σ over the corners of the axes not in `skip`, by nested lerps; the result is at corner 0.
    let reduce = |vals: &mut [Iv; 8], skip: usize| {
        for j in 0..m {
            let bj = 1 << j;
            if skip & bj == 0 {
                for c in (0..n).filter(|c| c & (skip | bj) == 0) {
                    vals[c] = lerp_iv(w[j], vals[c], vals[c | bj]);
                }
            }
        }
        vals[0]
    };
    let mut diag = [Iv::point(0.0); 3];
    let mut off = [[0.0; 3]; 3];
    let mut vals = [Iv::point(0.0); 8];
    for i in 0..m {
        let bi = 1 << i;
        for c in (0..n).filter(|c| c & bi == 0) {
            let dl = lin[c | bi].sub(lin[c]);
            vals[c] = d2[i].mul(range(&dl)).add(d1[i].scale(2.0 * dl.0[i]));
        }
        diag[i] = reduce(&mut vals, bi);
        for j in i + 1..m {
            let bj = 1 << j;
            for c in (0..n).filter(|c| c & (bi | bj) == 0) {
                let (l00, l10, l01, l11) = (lin[c], lin[c | bi], lin[c | bj], lin[c | bi | bj]);
                let dd = l11.sub(l01).sub(l10.sub(l00));
                let gij = lerp_iv(w[j], Iv::point(l10.0[j] - l00.0[j]), Iv::point(l11.0[j] - l01.0[j]));
                let gji = lerp_iv(w[i], Iv::point(l01.0[i] - l00.0[i]), Iv::point(l11.0[i] - l10.0[i]));
                vals[c] = d1[i].mul(d1[j]).mul(range(&dd)).add(d1[i].mul(gij)).add(d1[j].mul(gji));
            }
            let mx = reduce(&mut vals, bi | bj).abs_max();
            off[i][j] = mx;
            off[j][i] = mx;
        }
    }
    (diag, off)
}

/// [`hessian_ranges`] for `m` active axes (a compile-time count, so that its loops unroll).
fn hessian_dispatch(m: usize, bx: &[Iv; 3], lin: &[Lin; 8]) -> ([Iv; 3], [[f64; 3]; 3]) {
    match m {
        0 => ([Iv::point(0.0); 3], [[0.0; 3]; 3]),
        1 => hessian_ranges::<1>(bx, lin),
        2 => hessian_ranges::<2>(bx, lin),
        _ => hessian_ranges::<3>(bx, lin),
    }
}

/// Second-derivative ranges over the box, as the hull of the ranges over sub-boxes at most
/// [`HESSIAN_PIECE`] wide (up to `most` per axis): interval evaluation overestimates
/// in proportion to the width, the Lagrange remainder only needs a valid range.
fn hessian_hull(m: usize, bx: &[Iv; 3], lin: &[Lin; 8], most: usize) -> ([Iv; 3], [[f64; 3]; 3]) {
    let mut pieces = [1usize; 3];
    for k in 0..m {
        pieces[k] = (((bx[k].1 - bx[k].0) / HESSIAN_PIECE).ceil() as usize).clamp(1, most.max(1));
    }
    if pieces == [1; 3] {
        return hessian_dispatch(m, bx, lin);
    }
    let (mut diag, mut off) = ([Iv(f64::INFINITY, f64::NEG_INFINITY); 3], [[0.0f64; 3]; 3]);
    for sub in 0..pieces[0] * pieces[1] * pieces[2] {
        let (mut sb, mut q) = (*bx, sub);
        for k in 0..m {
            let (p, np) = (q % pieces[k], pieces[k]);
            q /= np;
            let step = (bx[k].1 - bx[k].0) / np as f64;
            // Adjacent pieces share their computed boundary, so they cover the box.
            let lo = if p == 0 { bx[k].0 } else { bx[k].0 + step * p as f64 };
            let hi = if p + 1 == np { bx[k].1 } else { bx[k].0 + step * (p + 1) as f64 };
            sb[k] = Iv(lo, hi);
        }
        let (d, o) = hessian_dispatch(m, &sb, lin);
        for i in 0..m {
            diag[i] = Iv(fmin(diag[i].0, d[i].0), fmax(diag[i].1, d[i].1));
            for j in 0..m {
                off[i][j] = fmax(off[i][j], o[i][j]);
            }
        }
    }
    (diag, off)
}

/// Noise in one cell for values with first-order terms (affine forms): a first-order Taylor
/// expansion at the centre c of the box of the t ranges within the cell (the values the
/// point evaluation sees: t = p − cell lies in [0, 1]), with the Lagrange remainder
///   R = ½ Σᵢ ∂ᵢᵢn(ξ)·dᵢ² + Σ_{i<j} ∂ᵢ∂ⱼn(ξ)·dᵢdⱼ,  d = t − c, |dᵢ| ≤ rᵢ,
/// bounded with the second-derivative ranges over the box: a diagonal term lies between 0 and
/// ½∂ᵢᵢn·rᵢ² (one-sided when ∂ᵢᵢn keeps its sign), a mixed term within ±max|∂ᵢ∂ⱼn|·rᵢrⱼ.
/// The form is n(c) + mid R + ∇n(c)·(t̂ − c) with a new symbol for the rest of R and the
/// rounding: one combination of the inputs' forms and one new symbol, instead of the ~40
/// operations and 10 new symbols of the formula. Axes whose t is exactly known (rᵢ = 0) drop
/// out of R; their corners are folded beforehand. Returns the form and the largest rᵢ;
/// `None` for arithmetics without first-order terms.
fn taylor_cell<N: Real>(
    dim: usize,
    cell: [i64; 3],
    x: &[N; 3],
    scale: f64,
    origin: [f64; 3],
    pieces: usize,
) -> Option<(N, f64)> {
    let (mut c, mut r) = ([0.0; 3], [0.0; 3]);
    let mut bx = [Iv::point(0.0); 3];
    let mut active = 0usize;
    for k in 0..dim {
        // The t the point evaluation computes, fl(fl(x·scale) − origin), lies in the
        // outward-rounded interval of the same operations.
        let (_, range) = x[k].first_order()?;
        let range = if scale == 1.0 { range } else { range.scale(scale) };
        let range = if origin[k] == 0.0 { range } else { range.sub(Interval::point(origin[k])) };
        let (lo, hi) = (range.lo.max(0.0), range.hi.min(1.0));
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return None;
        }
        bx[k] = Iv(lo, hi);
        c[k] = 0.5 * (lo + hi);
        r[k] = up(c[k] - lo).max(up(hi - c[k]));
        if r[k] > 0.0 {
            active |= 1 << k;
        }
    }
    let (e, g, n) = corners(dim, cell);
    let value = cell_eval::<f64>(dim, cell, &c);
    let grad = cell_gradient(dim, &c, &e, &g, n);
    // Corner values L_c = g_c·(t − e_c); the fixed axes folded in with their weights, then
    // everything in the coordinates of the active axes.
    let mut full = [Lin::default(); 8];
    for k in 0..n {
        full[k] = Lin(g[k], -(g[k][0] * e[k][0] + g[k][1] * e[k][1] + g[k][2] * e[k][2]));
    }
    for j in (0..dim).filter(|j| active & (1 << j) == 0) {
        let (bit, wj) = (1 << j, fade_point(c[j]));
        for k in (0..n).filter(|k| k & bit == 0) {
            full[k] = full[k].lerp(wj, full[k | bit]);
        }
    }
    let axes: Vec<usize> = (0..dim).filter(|k| active & (1 << k) != 0).collect();
    let m = axes.len();
    let (mut lin, mut rbx, mut rr) = ([Lin::default(); 8], [Iv::point(0.0); 3], [0.0; 3]);
    for (a, &k) in axes.iter().enumerate() {
        rbx[a] = bx[k];
        rr[a] = r[k];
    }
    for rc in 0..1usize << m {
        let fc: usize = axes.iter().enumerate().map(|(a, &k)| ((rc >> a) & 1) << k).sum();
        let f = full[fc];
        lin[rc] = Lin(std::array::from_fn(|a| if a < m { f.0[axes[a]] } else { 0.0 }), f.1);
    }
    let (diag, off) = hessian_hull(m, &rbx, &lin, pieces);
    let (mut rlo, mut rhi, mut rounding) = (0.0, 0.0, VALUE_ROUNDING);
    for i in 0..m {
        let r2 = 0.5 * rr[i] * rr[i];
        rlo += ((diag[i].0 - HESSIAN_SLACK) * r2).min(0.0);
        rhi += ((diag[i].1 + HESSIAN_SLACK) * r2).max(0.0);
        rounding += GRADIENT_ROUNDING * rr[i];
        for j in i + 1..m {
            let mm = (off[i][j] + HESSIAN_SLACK) * rr[i] * rr[j];
            rlo -= mm;
            rhi += mm;
        }
    }
    // Sums of at most 9 terms of one sign each: relative rounding < 32u.
    let (rlo, rhi) = (rlo * (1.0 + 32.0 * UNIT_ROUNDOFF), rhi * (1.0 + 32.0 * UNIT_ROUNDOFF));
    let mid = 0.5 * (rlo + rhi);
    let centre = value + mid;
    rounding += 8.0 * UNIT_ROUNDOFF * (value.abs() + mid.abs());
    let delta = up(up(rhi - mid).max(up(mid - rlo)) + up(rounding * (1.0 + 32.0 * UNIT_ROUNDOFF)));
    // In terms of x: t − c = scale·(x − (origin + c)/scale), up to the rounding of the point
    // evaluation's t = fl(fl(x·scale) − origin) (≤ u·|x·scale| + u·|t|, |x·scale| ≤ |origin| + 2)
    // and of the expansion point (origin + c)/scale and of the slope ∇n·scale (≤ 2u relative
    // each, on |origin + c| + 1).
    let xs: Vec<(&N, f64, f64)> = axes.iter().map(|&k| (&x[k], (origin[k] + c[k]) / scale, grad[k] * scale)).collect();
    let shift: f64 = axes.iter().map(|&k| grad[k].abs() * (3.0 + origin[k].abs() + c[k])).sum();
    let delta = up(delta + 8.0 * UNIT_ROUNDOFF * shift);
    let rmax = r[0].max(r[1]).max(r[2]);
    Some((N::taylor(&xs, centre, delta, Interval::new(-bound(dim), bound(dim))), rmax))
}

/// Largest half-width of the t ranges for which the Taylor extension alone is used. Its
/// remainder grows with r², the formula's error terms more slowly on wide ranges: averaged over
/// random cells with independent inputs the Taylor form is 1–5 % narrower up to r ≈ 0.1 and
/// within 1 % (2 active axes) to 9 % (3 active axes) wider at r = 0.125; beyond this radius
/// both are computed and the narrower kept.
const TAYLOR_ONLY_RADIUS: f64 = 0.13;

/// The same for inputs that share noise symbols (e.g. the direction in lat-long mode): the
/// remainder is bounded over the whole box of t, which correlated inputs do not fill, and the
/// formula keeps the correlation; from r ≈ 0.03 on it is the narrower one on average.
const TAYLOR_ONLY_RADIUS_CORRELATED: f64 = 0.02;

/// Noise in one cell: the Taylor extension where the arithmetic has one (and the formula as
/// well on wide ranges, keeping the narrower), else the formula.
/// `x` are the coordinates, `origin` the cell's corner (0 for coordinates already relative to
/// it): t = x − origin; the formula needs t as values, the Taylor extension does not.
fn cell_value<N: Real>(dim: usize, cell: [i64; 3], x: &[N; 3], origin: [f64; 3], pieces: usize) -> N {
    let t = || -> [N; 3] {
        std::array::from_fn(|k| {
            if k >= dim {
                N::constant(0.0)
            } else if origin[k] == 0.0 {
                x[k].clone()
            } else {
                x[k].sub(&N::constant(origin[k]))
            }
        })
    };
    match taylor_cell(dim, cell, x, 1.0, origin, pieces) {
        Some((v, r)) if r <= TAYLOR_ONLY_RADIUS_CORRELATED || r <= TAYLOR_ONLY_RADIUS && !correlated(dim, x) => v,
        Some((v, _)) => {
            let f = cell_eval(dim, cell, &t());
            if f.bounds().width() < v.bounds().width() {
                f
            } else {
                v
            }
        }
        None => cell_eval(dim, cell, &t()),
    }
}

/// Whether two of the first `dim` coordinates share a noise symbol.
fn correlated<N: Real>(dim: usize, t: &[N; 3]) -> bool {
    (0..dim).any(|i| (i + 1..dim).any(|j| t[i].shares_symbols(&t[j])))
}

/// Signed gradient noise of `p` (the first `dim` coordinates are used).
pub fn snoise<N: Real>(dim: usize, p: &[N; 3]) -> N {
    let b: [Interval; 3] = std::array::from_fn(|k| if k < dim { p[k].bounds() } else { Interval::point(0.0) });
    let global = || N::from_interval(Interval::new(-bound(dim), bound(dim)));
    if b.iter().any(|iv| !iv.is_finite()) {
        return global();
    }
    if b.iter().any(|iv| iv.lo.abs().max(iv.hi.abs()) >= INTEGRAL) {
        // Every double this large is an integer, so a point there is a lattice point along that
        // axis; the hash repeats every PERIOD cells, so the coordinate modulo PERIOD (exact)
        // gives the same value with cell indices far from overflow. A range there takes the
        // global bound.
        if b.iter().all(|iv| iv.lo == iv.hi) {
            let q: [N; 3] = std::array::from_fn(|k| {
                if b[k].lo.abs() >= INTEGRAL {
                    N::constant(b[k].lo.rem_euclid(PERIOD))
                } else {
                    p[k].clone()
                }
            });
            return snoise(dim, &q);
        }
        return global();
    }
    let lo: [i64; 3] = std::array::from_fn(|k| b[k].lo.floor() as i64);
    let hi: [i64; 3] = std::array::from_fn(|k| b[k].hi.floor() as i64);
    let counts: [i64; 3] = std::array::from_fn(|k| hi[k] - lo[k] + 1);
    // Each count first: the product of three counts of up to 2^53 would overflow.
    if counts.iter().any(|&c| c > MAX_CELLS) || counts.iter().product::<i64>() > MAX_CELLS {
        return global();
    }
    if counts.iter().all(|&c| c == 1) {
        // One cell (always the case for points): the polynomial in the caller's arithmetic.
        let cell = [lo[0], lo[1], lo[2]];
        return cell_value(dim, cell, p, cell.map(|c| c as f64), HESSIAN_PIECES);
    }
    // Each touched cell on its part of the box, in the caller's arithmetic with fresh inputs
    // (affine stays tighter than interval inside a cell); the hull of the cells' bounds. Only
    // bounds are kept, so affine inputs take the Taylor bound alone (the parts of a cell that a
    // leaf-sized range covers are small); a range over many cells (coarse quadtree levels, far
    // wider than any tolerance) without sub-boxes.
    let cells = counts.iter().product::<i64>();
    let few = cells <= FEW_CELLS;
    // With three varying coordinates the remainder grows faster (the formula is the narrower
    // one from r ≈ 0.085 on average): there, up to 8 cells (a 2×2×2 block) also get the
    // formula's bound.
    let active = (0..dim).filter(|&k| b[k].lo < b[k].hi).count();
    let mut hull: Option<Interval> = None;
    for cx in lo[0]..=hi[0] {
        for cy in lo[1]..=hi[1] {
            for cz in lo[2]..=hi[2] {
                let cell = [cx, cy, cz];
                let t: [N; 3] = std::array::from_fn(|k| {
                    let c = cell[k] as f64;
                    if k < dim {
                        let part = Interval::new(b[k].lo.max(c), b[k].hi.min(c + 1.0));
                        let local = Interval::sub(part, Interval::point(c));
                        N::input(local.lo, local.hi)
                    } else {
                        N::constant(0.0)
                    }
                });
                let v = if active == 3 && cells <= 2 * FEW_CELLS {
                    cell_value::<N>(dim, cell, &t, [0.0; 3], MULTI_CELL_PIECES).bounds()
                } else {
                    let pieces = if few { MULTI_CELL_PIECES } else { 1 };
                    match taylor_cell(dim, cell, &t, 1.0, [0.0; 3], pieces) {
                        Some((v, _)) => v.bounds(),
                        None => cell_eval::<N>(dim, cell, &t).bounds(),
                    }
                };
                hull = Some(hull.map_or(v, |h| h.hull(v)));
            }
        }
    }
    let g = Interval::new(-bound(dim), bound(dim));
    N::from_interval(hull.map_or(g, |h| h.intersect(g)))
}

/// snoise(3, p·scale) for a constant scale: for arithmetics with first-order terms whose
/// scaled range lies in one cell, the Taylor extension is applied to p directly (the scaled
/// coordinates are never formed); otherwise p·scale is computed as in the formula.
fn snoise_scaled<N: Real>(p: &[N; 3], scale: f64) -> N {
    if scale.is_finite() && scale != 0.0 && p[0].first_order().is_some() {
        let b: [Interval; 3] = std::array::from_fn(|k| p[k].bounds().scale(scale));
        if b.iter().all(|iv| iv.lo.abs().max(iv.hi.abs()) < INTEGRAL && iv.lo.floor() == iv.hi.floor()) {
            let cell: [i64; 3] = std::array::from_fn(|k| b[k].lo.floor() as i64);
            if let Some((v, r)) = taylor_cell(3, cell, p, scale, cell.map(|c| c as f64), HESSIAN_PIECES) {
                if r <= TAYLOR_ONLY_RADIUS_CORRELATED || r <= TAYLOR_ONLY_RADIUS && !correlated(3, p) {
                    return v;
                }
            }
        }
    }
    let f = N::constant(scale);
    snoise(3, &std::array::from_fn(|k| p[k].mul(&f)))
}

/// Fractional Brownian motion: Σᵢ gainⁱ·snoise(p·lacunarityⁱ), i < octaves (3-D).
pub fn fbm<N: Real>(p: &[N; 3], octaves: usize, lacunarity: &N, gain: &N, turbulence: bool) -> N {
    let mut sum = N::constant(0.0);
    let mut freq = N::constant(1.0);
    let mut amp = N::constant(1.0);
    for _ in 0..octaves {
        let mut n = match freq.as_constant() {
            Some(f) => snoise_scaled(p, f),
            None => snoise(3, &std::array::from_fn(|k| p[k].mul(&freq))),
        };
        if turbulence {
            n = n.abs();
        }
        sum = sum.add(&amp.mul(&n));
        freq = freq.mul(lacunarity);
        amp = amp.mul(gain);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::affine::Affine;

    #[test]
    fn noise_vanishes_at_lattice_points_and_is_continuous() {
        for dim in 1..=3 {
            let at = |x: f64| snoise::<f64>(dim, &[x, 0.3 * x + 0.1, 0.7]);
            // Across a cell boundary the value is continuous.
            let (a, b) = (at(3.0 - 1e-9), at(3.0));
            assert!((a - b).abs() < 1e-6, "dim {dim}: {a} vs {b}");
        }
        assert_eq!(snoise::<f64>(3, &[2.0, 5.0, -1.0]), 0.0);
    }

    #[test]
    fn area_noise_contains_point_noise() {
        let mut rng = SplitMix64::new(3);
        for dim in 1..=3 {
            for trial in 0..300 {
                let size = [0.01, 0.3, 1.7, 9.0][trial % 4];
                let c: [f64; 3] = std::array::from_fn(|_| rng.next_f64() * 20.0 - 10.0);
                let p: [Affine; 3] = std::array::from_fn(|k| Affine::symbol(c[k], size * 0.5));
                let pi: [Interval; 3] = std::array::from_fn(|k| p[k].range());
                let (na, ni) = (snoise(dim, &p).range(), snoise(dim, &pi));
                for _ in 0..200 {
                    let q: [f64; 3] = std::array::from_fn(|k| c[k] + (rng.next_f64() - 0.5) * size);
                    let v = snoise::<f64>(dim, &q);
                    assert!(na.contains(v) && ni.contains(v), "dim {dim} size {size}: {v} not in {na:?} / {ni:?}");
                    assert!(v.abs() <= bound(dim));
                }
            }
        }
    }
}

#[cfg(test)]
mod taylor_tests {
    use super::*;
    use crate::affine::Affine;

    /// Mean range width of noise over random boxes inside one cell: (formula, Taylor).
    fn mean_widths(size: f64, correlated: bool, seed: u64) -> (f64, f64) {
        let mut rng = SplitMix64::new(seed);
        let (mut wf, mut wt, mut count) = (0.0, 0.0, 0);
        while count < 500 {
            let c: [f64; 3] = std::array::from_fn(|_| rng.next_f64() * 20.0 - 10.0);
            let (u, v) = (Affine::symbol(0.0, 0.5 * size), Affine::symbol(0.0, 0.5 * size));
            let k = |x: f64| Affine::constant(x);
            let p: [Affine; 3] = if correlated {
                [u.add(&v).scale(0.6).add(&k(c[0])), u.sub(&v).scale(0.6).add(&k(c[1])), u.scale(0.8).add(&k(c[2]))]
            } else {
                [u.add(&k(c[0])), v.add(&k(c[1])), k(0.37)]
            };
            let b: [Interval; 3] = std::array::from_fn(|k| p[k].range());
            if b.iter().any(|iv| iv.lo.floor() != iv.hi.floor()) {
                continue;
            }
            let cell: [i64; 3] = std::array::from_fn(|k| b[k].lo.floor() as i64);
            let t: [Affine; 3] = std::array::from_fn(|k| p[k].sub(&Affine::constant(cell[k] as f64)));
            let Some((taylor, _)) = taylor_cell(3, cell, &t, 1.0, [0.0; 3], HESSIAN_PIECES) else {
                panic!("affine forms have a Taylor extension")
            };
            wf += cell_eval(3, cell, &t).range().width();
            wt += taylor.range().width();
            count += 1;
        }
        (wf / count as f64, wt / count as f64)
    }

    #[test]
    fn taylor_is_narrower_than_the_formula_on_small_independent_ranges() {
        for (k, size) in [0.005, 0.02, 0.06, 0.1].into_iter().enumerate() {
            let (formula, taylor) = mean_widths(size, false, 40 + k as u64);
            assert!(taylor < formula, "size {size}: Taylor {taylor} vs formula {formula}");
            // Both contain the linear part |∇n|·r, so neither can be far below the other.
            assert!(taylor > 0.8 * formula, "size {size}: Taylor {taylor} vs formula {formula}");
        }
    }

    #[test]
    fn taylor_bounds_hold_for_correlated_scaled_inputs() {
        // Coordinates that are affine combinations of two shared symbols (as in lat-long mode),
        // box sizes from 10⁻³ to 1 cell, noise in 1–3 dimensions and fbm octaves (the scaled
        // path): every point evaluation lies in the affine range.
        let mut rng = SplitMix64::new(2024);
        let mut checked = 0;
        for trial in 0..3000 {
            let dim = 1 + trial % 3;
            let size = 10f64.powf(-3.0 + 3.0 * rng.next_f64());
            let a: [[f64; 2]; 3] = std::array::from_fn(|_| [rng.next_f64() - 0.5, rng.next_f64() - 0.5]);
            let c: [f64; 3] = std::array::from_fn(|_| rng.next_f64() * 20.0 - 10.0);
            let (u, v) = (Affine::symbol(0.0, 1.0), Affine::symbol(0.0, 1.0));
            let p: [Affine; 3] = std::array::from_fn(|k| {
                u.scale(a[k][0] * size).add(&v.scale(a[k][1] * size)).add(&Affine::constant(c[k]))
            });
            let noise = snoise(dim, &p).range();
            let gain = Affine::constant(0.5);
            let fbm_range = fbm(&p, 3, &Affine::constant(2.0), &gain, trial % 2 == 0).range();
            for _ in 0..100 {
                let (eu, ev) = (rng.next_f64() * 2.0 - 1.0, rng.next_f64() * 2.0 - 1.0);
                let q: [f64; 3] = std::array::from_fn(|k| a[k][0] * size * eu + a[k][1] * size * ev + c[k]);
                let n = snoise::<f64>(dim, &q);
                assert!(noise.contains(n), "dim {dim} size {size}: {n} not in {noise:?}");
                let f = fbm::<f64>(&q, 3, &2.0, &0.5, trial % 2 == 0);
                assert!(fbm_range.contains(f), "fbm size {size}: {f} not in {fbm_range:?}");
                checked += 1;
            }
        }
        assert_eq!(checked, 300_000);
    }

    #[test]
    fn correlated_inputs_keep_the_narrower_bound() {
        // With shared symbols the remainder over the whole box of t is pessimistic; above
        // TAYLOR_ONLY_RADIUS_CORRELATED `cell_value` computes both and keeps the narrower.
        let mut rng = SplitMix64::new(77);
        for _ in 0..300 {
            let c: [f64; 3] = std::array::from_fn(|_| rng.next_f64() * 20.0 - 10.0);
            let (u, v) = (Affine::symbol(0.0, 0.1), Affine::symbol(0.0, 0.1));
            let k = |x: f64| Affine::constant(x);
            let p =
                [u.add(&v).scale(0.6).add(&k(c[0])), u.sub(&v).scale(0.6).add(&k(c[1])), u.scale(0.8).add(&k(c[2]))];
            let b: [Interval; 3] = std::array::from_fn(|k| p[k].range());
            if b.iter().any(|iv| iv.lo.floor() != iv.hi.floor()) {
                continue;
            }
            let cell: [i64; 3] = std::array::from_fn(|k| b[k].lo.floor() as i64);
            let t: [Affine; 3] = std::array::from_fn(|k| p[k].sub(&Affine::constant(cell[k] as f64)));
            assert!(correlated(3, &t));
            let chosen = cell_value(3, cell, &p, cell.map(|c| c as f64), HESSIAN_PIECES).range().width();
            assert!(chosen <= cell_eval(3, cell, &t).range().width());
        }
    }
}
