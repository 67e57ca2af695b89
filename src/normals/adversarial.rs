//! Directions at the worst-case locations each bound is derived from (Meyer et al. 2010, §§4–5).
//! Uniform random directions reach only ~99.5 % of a true maximum at 10^7 samples; these reach
//! it to within a few 1e-6 (relative), so the measured maximum of `--table` is
//! `max(random, adversarial)`.
//!
//! For every scheme we take the parameter cells around the location the paper names and, in
//! each cell, the points where the rounding error can peak:
//! - domain rounding: just inside the cell centre towards each corner (the centre is the point
//!   farthest from the corner it rounds to);
//! - range rounding: the spherical circumcentres of the cell's corner triples, the midpoints of
//!   its edges and diagonals, and its centre (the maximum over the cell of the distance to the
//!   nearest of four corners sits at one of these).

use super::fixed::{snorm_max, snorm_round, snorm_value, symmetric_round};
use super::radix::GridLayout;
use super::{onv, sc, Codec, Layout, Scheme};
use glam::DVec3;
use std::f64::consts::{FRAC_1_SQRT_2, SQRT_2};

/// Relative nudge from a cell centre towards a corner: small enough to stay at the peak, large
/// enough to decide the rounding.
const NUDGE: f64 = 1e-6;
/// Cells examined on each side of a worst-case location.
const RADIUS: i64 = 2;

/// Adversarial unit directions for `codec`.
pub fn directions(codec: &Codec) -> Vec<DVec3> {
    match (codec.scheme(), codec.layout()) {
        (_, Layout::Onv(l)) => onv_directions(l),
        (Scheme::Sc, Layout::Grid(l)) => sc_directions(l),
        (Scheme::Pp, Layout::Grid(l)) => pp_directions(l),
        (Scheme::Spp, Layout::Grid(l)) => spp_directions(l),
        (_, Layout::Grid(l)) => cm_directions(l),
    }
}

/// Half the number of steps `h = (N-1)/2` of an odd symmetric lattice: its points are `s/h` for
/// integers `-h <= s <= h`.
fn half_count(radix: u64) -> i64 {
    ((radix - 1) / 2) as i64
}

/// Candidate points of a parameter cell `[a0,a1]×[b0,b1]` mapped by `to_dir`.
fn cell_candidates(a: (f64, f64), b: (f64, f64), to_dir: &dyn Fn(f64, f64) -> Option<DVec3>, out: &mut Vec<DVec3>) {
    let (ca, cb) = (0.5 * (a.0 + a.1), 0.5 * (b.0 + b.1));
    let (da, db) = (NUDGE * (a.1 - a.0), NUDGE * (b.1 - b.0));
    for (sa, sb) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        if let Some(d) = to_dir(ca + sa * da, cb + sb * db) {
            out.push(d);
        }
    }
    let corners: Vec<DVec3> =
        [(a.0, b.0), (a.1, b.0), (a.1, b.1), (a.0, b.1)].iter().filter_map(|&(x, y)| to_dir(x, y)).collect();
    if corners.len() < 4 {
        return;
    }
    for i in 0..4 {
        for j in i + 1..4 {
            let m = corners[i] + corners[j];
            if m.length_squared() > 0.0 {
                out.push(m.normalize());
            }
        }
        // Circumcentre of the triple leaving out corner i: the centre of the triple's circle in
        // its plane, `a + ((|e1|²e2 - |e2|²e1) × (e1×e2)) / (2|e1×e2|²)`, lies on the ray of
        // the spherical circumcentre. Computed as `a` plus a small offset, it keeps its accuracy
        // relative to the cell size (the plane normal `e1×e2` alone is only accurate to
        // ~1e-16/|e|, 0.5 % of the circumradius at 48 bits).
        let t: Vec<DVec3> = (0..4).filter(|&k| k != i).map(|k| corners[k]).collect();
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let n = e1.cross(e2);
        let n2 = n.length_squared();
        if n2 > 0.0 {
            let (l1, l2) = (e1.length_squared(), e2.length_squared());
            let w = (l1 * e2 - l2 * e1).cross(n);
            let p = t[0] + w / (2.0 * n2);
            if p.length_squared() > 0.0 {
                out.push(p.normalize());
            }
        }
    }
}

fn onv_directions(layout: onv::OnvLayout) -> Vec<DVec3> {
    let (ku, kv) = (layout.u_bits, layout.v_bits);
    let mut out = Vec::new();
    let to_dir =
        |u: f64, v: f64| -> Option<DVec3> { (u.abs() <= 1.0 && v.abs() <= 1.0).then(|| onv::dir_from_oct([u, v])) };
    // The centres of all eight octahedron faces (eq. 10's derivation point) and, for comparison,
    // the vertices and edge midpoints.
    let mut centres = Vec::new();
    for sx in [1.0, -1.0] {
        for sy in [1.0, -1.0] {
            for sz in [1.0, -1.0] {
                centres.push(DVec3::new(sx, sy, sz));
            }
        }
    }
    centres.extend([DVec3::X, DVec3::Z, DVec3::new(1.0, 1.0, 0.0), DVec3::new(1.0, 0.0, 1.0)]);
    for c in centres {
        let p = onv::oct_from_dir(c);
        let (iu, iv) = (snorm_round(p[0], ku), snorm_round(p[1], kv));
        for di in -RADIUS..RADIUS {
            for dj in -RADIUS..RADIUS {
                let (u0, v0) = (iu + di, iv + dj);
                if u0 < -snorm_max(ku) || u0 + 1 > snorm_max(ku) || v0 < -snorm_max(kv) || v0 + 1 > snorm_max(kv) {
                    continue;
                }
                let a = (snorm_value(u0, ku), snorm_value(u0 + 1, ku));
                let b = (snorm_value(v0, kv), snorm_value(v0 + 1, kv));
                cell_candidates(a, b, &to_dir, &mut out);
            }
        }
    }
    out
}

fn sc_directions(l: GridLayout) -> Vec<DVec3> {
    let (ht, n_phi) = (half_count(l.b), l.a as f64);
    let mut out = Vec::new();
    let to_dir = |t: f64, turns: f64| -> Option<DVec3> { (t.abs() <= 1.0).then(|| sc::dir_from_params(t, turns)) };
    // The equator (t = 0) at a spread of longitudes: eq. 5's worst case.
    for k in 0..16u64 {
        let j0 = ((k as f64 / 16.0 + 0.013) * n_phi).floor();
        for dj in -1..=0 {
            let j = j0 + dj as f64;
            for st in -RADIUS..RADIUS {
                if st < -ht || st + 1 > ht {
                    continue;
                }
                let a = (st as f64 / ht as f64, (st + 1) as f64 / ht as f64);
                let b = (j / n_phi, (j + 1.0) / n_phi);
                cell_candidates(a, b, &to_dir, &mut out);
            }
        }
    }
    out
}

fn pp_directions(l: GridLayout) -> Vec<DVec3> {
    // Eq. 6: a lattice point on (or just outside) the unit circle, reached from half a cell
    // inwards along the cell diagonal, where z = sqrt(1 - x² - y²) is steepest.
    let (hx, hy) = (half_count(l.a), half_count(l.b));
    let (ex, ey) = (1.0 / hx as f64, 1.0 / hy as f64);
    let mut out = Vec::new();
    // The half-cell diagonal (ex, ey)/2 is radial where (cos ψ, sin ψ) ∝ (ex, ey).
    let centre = symmetric_round(ex / ex.hypot(ey), l.a) as i64 - hx;
    let span = 4096.min(hx);
    for i in (centre - span).max(1)..=(centre + span).min(hx) {
        let x = i as f64 / hx as f64;
        // Smallest y lattice value with x² + y² >= 1.
        let y_needed = (1.0 - x * x).max(0.0).sqrt();
        let j = ((y_needed * hy as f64).ceil() as i64).min(hy);
        for j in [j - 1, j] {
            let y = j as f64 / hy as f64;
            let (px, py) = (x - 0.5 * ex * (1.0 - NUDGE), y - 0.5 * ey * (1.0 - NUDGE));
            let r2 = px * px + py * py;
            if r2 <= 1.0 && px >= 0.0 && py >= 0.0 {
                let z = (1.0 - r2).sqrt();
                for (sx, sy, sz) in [(1.0, 1.0, 1.0), (-1.0, 1.0, -1.0), (1.0, -1.0, 1.0), (-1.0, -1.0, -1.0)] {
                    out.push(DVec3::new(sx * px, sy * py, sz * z).normalize());
                }
            }
        }
    }
    out
}

fn spp_directions(l: GridLayout) -> Vec<DVec3> {
    // Eq. 7: the cube diagonal, where the rebuilt largest component m = sqrt(1-a²-b²) is
    // smallest and steepest; the worst lattice points lie just outside it (`bounds::spp_split`).
    let (ha, hb) = (half_count(l.a), half_count(l.b));
    let d = SQRT_2 / 3f64.sqrt();
    let (ia, ib) = (symmetric_round(d, l.a) as i64 - ha, symmetric_round(d, l.b) as i64 - hb);
    let mut out = Vec::new();
    let to_dir = |ta: f64, tb: f64| -> Option<DVec3> {
        let (a, b) = (ta * FRAC_1_SQRT_2, tb * FRAC_1_SQRT_2);
        let m2 = 1.0 - a * a - b * b;
        (m2 >= a * a && m2 >= b * b).then(|| DVec3::new(a, b, m2.sqrt()))
    };
    for di in -RADIUS - 1..RADIUS {
        for dj in -RADIUS - 1..RADIUS {
            let (a0, b0) = (ia + di, ib + dj);
            if a0 + 1 > ha || b0 + 1 > hb {
                continue;
            }
            let a = (a0 as f64 / ha as f64, (a0 + 1) as f64 / ha as f64);
            let b = (b0 as f64 / hb as f64, (b0 + 1) as f64 / hb as f64);
            cell_candidates(a, b, &to_dir, &mut out);
        }
    }
    mirror_and_rotate(out)
}

fn cm_directions(l: GridLayout) -> Vec<DVec3> {
    // Eq. 8: the face centre, where the cube is closest to the sphere and the lattice coarsest.
    let (ha, hb) = (half_count(l.a) as f64, half_count(l.b) as f64);
    let mut out = Vec::new();
    let to_dir = |s: f64, t: f64| -> Option<DVec3> { Some(DVec3::new(s, t, 1.0).normalize()) };
    for di in -RADIUS..RADIUS {
        for dj in -RADIUS..RADIUS {
            let a = (di as f64 / ha, (di + 1) as f64 / ha);
            let b = (dj as f64 / hb, (dj + 1) as f64 / hb);
            cell_candidates(a, b, &to_dir, &mut out);
        }
    }
    mirror_and_rotate(out)
}

/// The same points on every face: sign flips of all components and cyclic rotations.
fn mirror_and_rotate(points: Vec<DVec3>) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(points.len() * 6);
    for p in points {
        for r in 0..3 {
            let q = DVec3::new(p[r % 3], p[(r + 1) % 3], p[(r + 2) % 3]);
            out.push(q);
            out.push(-q);
        }
    }
    out
}
