//! The hierarchical area sampler (Heidrich, Slusallek & Seidel 1998, §3.1): evaluate the
//! shader over the whole (u, v) domain, and subdivide a quadtree wherever upper − lower bound
//! exceeds the tolerance, down to a maximum depth. Each node's bounds are guaranteed for every
//! point of the node (affine or interval arithmetic); the point mode estimates them from a few
//! random point samples per node instead (the paper's Monte-Carlo comparison, Table 1).

use super::interp::Globals;
use super::{Shader, ShaderError};
use crate::affine::{Affine, Interval, Real};
use crate::progress::Progress;
use crate::rng::SplitMix64;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Which arithmetic evaluates a node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arith {
    /// Affine arithmetic (guaranteed, tight).
    Affine,
    /// Interval arithmetic (guaranteed, looser).
    Interval,
    /// Random point samples per node (an estimate, not a bound).
    Point,
}

impl Arith {
    /// Name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Arith::Affine => "affine",
            Arith::Interval => "interval",
            Arith::Point => "point",
        }
    }
}

/// What (u, v) parameterizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// A texture: P = (u, v, 0), D = (0, 0, 1).
    Texture,
    /// Directions: u = φ/2π, v = θ/π (+Z up, row 0 is θ = 0), P = D = (sinθ cosφ, sinθ sinφ, cosθ).
    LatLong,
}

/// Sampler settings.
#[derive(Clone, Debug)]
pub struct SampleConfig {
    /// Subdivide while the widest channel's upper − lower exceeds this.
    pub tolerance: f64,
    /// Deepest level (the root is 0; a node at depth d is 2^−d wide).
    pub max_depth: u32,
    /// Arithmetic.
    pub arith: Arith,
    /// Parameter domain.
    pub domain: Domain,
    /// Point samples per node in point mode.
    pub points_per_node: usize,
    /// Seed of the point samples.
    pub seed: u64,
}

/// A quadtree node with its per-channel bounds.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// Depth.
    pub depth: u32,
    /// Column index at this depth.
    pub ix: u32,
    /// Row index at this depth.
    pub iy: u32,
    /// Lower bound of each channel.
    pub lo: [f64; 3],
    /// Upper bound of each channel.
    pub hi: [f64; 3],
}

impl Node {
    /// The node's (u, v) box: ([u0, u1], [v0, v1]).
    pub fn extent(&self) -> ([f64; 2], [f64; 2]) {
        let s = 1.0 / (1u64 << self.depth) as f64;
        ([self.ix as f64 * s, (self.ix + 1) as f64 * s], [self.iy as f64 * s, (self.iy + 1) as f64 * s])
    }

    /// Largest upper − lower over the channels (∞ for unbounded).
    pub fn width(&self) -> f64 {
        (0..3).map(|c| self.hi[c] - self.lo[c]).fold(0.0, f64::max)
    }
}

/// The result of sampling.
#[derive(Clone, Debug)]
pub struct Sampled {
    /// Leaves, covering [0, 1]² without overlap, in breadth-first order.
    pub leaves: Vec<Node>,
    /// Nodes evaluated (inner nodes and leaves).
    pub nodes: usize,
    /// Shader evaluations (area samples, or point samples in point mode).
    pub evaluations: u64,
}

/// The shader's globals for a (u, v) box in arithmetic `N`.
pub fn globals<N: Real>(domain: Domain, u: [f64; 2], v: [f64; 2]) -> Globals<N> {
    let (un, vn) = (N::input(u[0], u[1]), N::input(v[0], v[1]));
    let c = |x: f64| N::constant(x);
    let (du, dv) = (c(u[1] - u[0]), c(v[1] - v[0]));
    match domain {
        Domain::Texture => {
            Globals { p: [un.clone(), vn.clone(), c(0.0)], d: [c(0.0), c(0.0), c(1.0)], u: un, v: vn, du, dv }
        }
        Domain::LatLong => {
            let theta = vn.mul(&c(PI));
            let phi = un.mul(&c(2.0 * PI));
            let st = theta.sin();
            let d = [st.mul(&phi.cos()), st.mul(&phi.sin()), theta.cos()];
            Globals { p: d.clone(), d, u: un, v: vn, du, dv }
        }
    }
}

fn bounds_of<N: Real>(ci: &[N; 3]) -> ([f64; 3], [f64; 3]) {
    let b: [Interval; 3] = std::array::from_fn(|k| ci[k].bounds());
    (b.map(|i| i.lo), b.map(|i| i.hi))
}

/// Evaluates one node; returns (lo, hi, evaluations).
pub fn evaluate_node(shader: &Shader, cfg: &SampleConfig, depth: u32, ix: u32, iy: u32) -> Result<Node, ShaderError> {
    let mut node = Node { depth, ix, iy, lo: [0.0; 3], hi: [0.0; 3] };
    let (u, v) = node.extent();
    let (lo, hi) = match cfg.arith {
        Arith::Affine => bounds_of(&shader.eval(&globals::<Affine>(cfg.domain, u, v))?),
        Arith::Interval => bounds_of(&shader.eval(&globals::<Interval>(cfg.domain, u, v))?),
        Arith::Point => {
            let mut rng = SplitMix64::keyed(&[cfg.seed, depth as u64, ix as u64, iy as u64]);
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for _ in 0..cfg.points_per_node.max(1) {
                let pu = u[0] + (u[1] - u[0]) * rng.next_f64();
                let pv = v[0] + (v[1] - v[0]) * rng.next_f64();
                let ci = shader
                    .eval(&globals::<f64>(cfg.domain, [pu, pu], [pv, pv]).with_sizes(u[1] - u[0], v[1] - v[0]))?;
                for k in 0..3 {
                    lo[k] = lo[k].min(ci[k]);
                    hi[k] = hi[k].max(ci[k]);
                }
            }
            (lo, hi)
        }
    };
    node.lo = lo;
    node.hi = hi;
    Ok(node)
}

impl Globals<f64> {
    /// Point samples see the node's size as du, dv (the same filter width as the area sample).
    pub fn with_sizes(mut self, du: f64, dv: f64) -> Self {
        self.du = du;
        self.dv = dv;
        self
    }
}

/// Runs the hierarchical sampler, level by level (each level in parallel, results in a fixed
/// order, so the output does not depend on the thread count).
pub fn sample(shader: &Shader, cfg: &SampleConfig, progress: &dyn Progress) -> Result<Sampled, ShaderError> {
    let mut level: Vec<(u32, u32)> = vec![(0, 0)];
    let mut leaves = Vec::new();
    let (mut nodes, mut evaluations) = (0usize, 0u64);
    let per_node = if cfg.arith == Arith::Point { cfg.points_per_node.max(1) as u64 } else { 1 };
    progress.start("sampling", cfg.max_depth as u64 + 1);
    for depth in 0..=cfg.max_depth {
        if level.is_empty() {
            break;
        }
        let evaluated: Vec<Result<Node, ShaderError>> =
            level.par_iter().map(|&(ix, iy)| evaluate_node(shader, cfg, depth, ix, iy)).collect();
        nodes += level.len();
        evaluations += level.len() as u64 * per_node;
        let mut next = Vec::new();
        for n in evaluated {
            let n = n?;
            if n.width() > cfg.tolerance && depth < cfg.max_depth {
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    next.push((2 * n.ix + dx, 2 * n.iy + dy));
                }
            } else {
                leaves.push(n);
            }
        }
        level = next;
        progress.advance(1);
    }
    progress.finish();
    Ok(Sampled { leaves, nodes, evaluations })
}

/// Per-pixel layers of a sampled quadtree on a W×H grid (row 0 is v = 0): the range midpoint,
/// the bound width and the depth of the leaf holding the pixel centre.
pub struct Raster {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Midpoints (RGB).
    pub mid: Vec<[f64; 3]>,
    /// Bound widths (RGB).
    pub bound_width: Vec<[f64; 3]>,
    /// Leaf depth.
    pub depth: Vec<u32>,
}

/// Rasterizes leaves: each pixel takes the leaf that contains its centre.
pub fn rasterize(leaves: &[Node], width: usize, height: usize) -> Raster {
    let n = width * height;
    let mut r = Raster { width, height, mid: vec![[0.0; 3]; n], bound_width: vec![[0.0; 3]; n], depth: vec![0; n] };
    for leaf in leaves {
        let (u, v) = leaf.extent();
        let first = |a: f64, size: usize| ((a * size as f64 - 0.5).ceil().max(0.0) as usize).min(size);
        let (x0, x1) = (first(u[0], width), first(u[1], width));
        let (y0, y1) = (first(v[0], height), first(v[1], height));
        let mid: [f64; 3] = std::array::from_fn(|k| Interval::new(leaf.lo[k], leaf.hi[k]).mid());
        let w: [f64; 3] = std::array::from_fn(|k| leaf.hi[k] - leaf.lo[k]);
        for y in y0..y1 {
            for x in x0..x1 {
                let i = y * width + x;
                r.mid[i] = mid;
                r.bound_width[i] = w;
                r.depth[i] = leaf.depth;
            }
        }
    }
    r
}

/// Evaluates the shader at a point of (u, v) (for checks and tests).
pub fn point_value(shader: &Shader, domain: Domain, u: f64, v: f64, du: f64, dv: f64) -> Result<[f64; 3], ShaderError> {
    shader.eval(&globals::<f64>(domain, [u, u], [v, v]).with_sizes(du, dv))
}
