//! Perlin gradient noise in 1–3 dimensions (Perlin 1985, with the quintic fade and the
//! gradient set of "Improving Noise", 2002), fbm and turbulence, and its conservative extension
//! to ranges (Heidrich, Slusallek & Seidel 1998, §3.1: noise is one of the "more complicated
//! features").
//!
//! Inside one lattice cell noise is a polynomial of the fractional coordinates t = p − cell, so
//! when a range lies in one cell the very same code runs with interval or affine numbers. A
//! range that straddles cells is split: each touched cell (at most [`MAX_CELLS`]) is evaluated
//! in interval arithmetic on its part of the box and the hull is taken; beyond that the global
//! bound is used: the value is a convex combination (fade weights in [0, 1] summing to 1) of
//! g·d with gradient components in {−1, 0, 1}, at most two non-zero, and |dᵢ| ≤ 1, so
//! |snoise| ≤ 2 in 2-D and 3-D and ≤ 1 in 1-D (gradients of magnitude ≤ 1).

use super::rng::SplitMix64;
use crate::affine::{Interval, Real};
use std::sync::OnceLock;

/// Most lattice cells evaluated one by one for a range.
pub const MAX_CELLS: i64 = 64;

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

/// Σ gᵢ·dᵢ for gradient components in {−1, 0, 1}.
fn signed_sum<N: Real>(terms: &[(i8, &N)]) -> N {
    let mut acc: Option<N> = None;
    for &(g, d) in terms {
        if g == 0 {
            continue;
        }
        acc = Some(match (acc, g > 0) {
            (None, true) => d.clone(),
            (None, false) => d.neg(),
            (Some(a), true) => a.add(d),
            (Some(a), false) => a.sub(d),
        });
    }
    acc.unwrap_or_else(|| N::constant(0.0))
}

/// Gradient · offset for a corner; `d` are the offsets t − corner.
fn gradient_dot<N: Real>(dim: usize, h: u8, d: &[N; 3]) -> N {
    match dim {
        1 => {
            // g ∈ ±{1/8, …, 8/8}: exact multiples, |g| ≤ 1.
            let g = ((h & 7) + 1) as f64 / 8.0 * if h & 8 != 0 { -1.0 } else { 1.0 };
            d[0].mul(&N::constant(g))
        }
        2 => {
            const G2: [(i8, i8); 8] = [(1, 1), (-1, 1), (1, -1), (-1, -1), (1, 0), (-1, 0), (0, 1), (0, -1)];
            let (gx, gy) = G2[(h & 7) as usize];
            signed_sum(&[(gx, &d[0]), (gy, &d[1])])
        }
        _ => {
            // The 12 cube-edge directions of improved noise, 4 repeated to make 16.
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
            let (gx, gy, gz) = G3[(h & 15) as usize];
            signed_sum(&[(gx, &d[0]), (gy, &d[1]), (gz, &d[2])])
        }
    }
}

/// Noise inside one cell, from the fractional coordinates t (unused axes ignored).
fn cell_eval<N: Real>(dim: usize, cell: [i64; 3], t: &[N; 3]) -> N {
    let one = N::constant(1.0);
    let offs: [N; 3] = [t[0].sub(&one), t[1].sub(&one), t[2].sub(&one)];
    let corner = |dx: usize, dy: usize, dz: usize| -> N {
        let c = [cell[0] + dx as i64, cell[1] + dy as i64, cell[2] + dz as i64];
        let pick = |k: usize, on: usize| if on == 1 { offs[k].clone() } else { t[k].clone() };
        let d = [pick(0, dx), pick(1, dy), pick(2, dz)];
        gradient_dot(dim, hash(c), &d)
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

/// Signed gradient noise of `p` (the first `dim` coordinates are used).
pub fn snoise<N: Real>(dim: usize, p: &[N; 3]) -> N {
    let b: Vec<Interval> = (0..3).map(|k| if k < dim { p[k].bounds() } else { Interval::point(0.0) }).collect();
    let global = || N::from_interval(Interval::new(-bound(dim), bound(dim)));
    if b.iter().any(|iv| !iv.is_finite()) {
        return global();
    }
    let lo: Vec<i64> = b.iter().map(|iv| iv.lo.floor() as i64).collect();
    let hi: Vec<i64> = b.iter().map(|iv| iv.hi.floor() as i64).collect();
    let counts: Vec<i64> = (0..3).map(|k| hi[k] - lo[k] + 1).collect();
    if counts.iter().all(|&c| c == 1) {
        // One cell (always the case for points): the polynomial in the caller's arithmetic.
        let cell = [lo[0], lo[1], lo[2]];
        let t: [N; 3] =
            std::array::from_fn(|k| if k < dim { p[k].sub(&N::constant(cell[k] as f64)) } else { N::constant(0.0) });
        return cell_eval(dim, cell, &t);
    }
    if counts.iter().product::<i64>() > MAX_CELLS {
        return global();
    }
    // Each touched cell on its part of the box, in the caller's arithmetic with fresh inputs
    // (affine stays tighter than interval inside a cell); the hull of the cells' bounds.
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
                let v = cell_eval::<N>(dim, cell, &t).bounds();
                hull = Some(hull.map_or(v, |h| h.hull(v)));
            }
        }
    }
    let g = Interval::new(-bound(dim), bound(dim));
    N::from_interval(hull.map_or(g, |h| h.intersect(g)))
}

/// Fractional Brownian motion: Σᵢ gainⁱ·snoise(p·lacunarityⁱ), i < octaves (3-D).
pub fn fbm<N: Real>(p: &[N; 3], octaves: usize, lacunarity: &N, gain: &N, turbulence: bool) -> N {
    let mut sum = N::constant(0.0);
    let mut freq = N::constant(1.0);
    let mut amp = N::constant(1.0);
    for _ in 0..octaves {
        let q: [N; 3] = std::array::from_fn(|k| p[k].mul(&freq));
        let mut n = snoise(3, &q);
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
