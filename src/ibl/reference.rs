//! The angular reference every level is measured against: the split-sum integral of the input
//! environment itself, taken in angle over the whole kernel support.
//!
//!   B(R) = Σ_t L_t ∫_t k(R·ω) dω
//!
//! over every texel t of a lat-long map (piecewise constant, radiance L_t) whose centre lies
//! within π/2 + 2h of R (the kernel vanishes beyond π/2), the texel integrals by a
//! Gauss–Legendre product rule fine enough to misplace at most 1e-5 of the kernel's weight. The
//! texels kept cover the kernel's support and ∫ k dω = 1, so no normalization is needed. This
//! is a direct cone sum ([`LobeIntegral`]): no FFT, no pyramid, no interpolation, none of the
//! code of either bake path.
//!
//! A level is compared on a fixed, evenly strided set of its texels, with the errors pooled
//! by [`LevelError::pool`]: the relative error ‖a − r‖/‖r‖ over the texels whose reference is
//! above 1 % of the sampled mean.
//!
//! **Large inputs, with a bound.** The cone sum visits half the grid's texels per sampled
//! direction, so summing an 8192 × 4096 input at every sample would cost minutes. A map above
//! [`REFERENCE_MAX_TEXELS`] is measured on its box filtering (f × f input texels to one, each
//! coarse texel T the solid-angle-weighted mean L̄_T of the block, so it keeps the block's
//! energy), with a bound on what the filtering changes. Within T the input sums
//! Σ_t L_t ∫_t k dω where the filtered grid sums Σ_t L̄_T ∫_t k dω; since Σ_t (L_t − L̄_T) Ω_t = 0,
//! any constant m_T may be subtracted from the texel means k̄_t of the kernel, and with m_T the
//! middle of k's range on T,
//!
//!   |B_input(R) − B_filtered(R)| ≤ Σ_T D_T (max_T k − min_T k) / 2,   D_T = Σ_{t⊂T} Ω_t |L_t − L̄_T|,
//!
//! per channel, for any sign of the radiance. D_T vanishes where the map is flat and the
//! kernel's range where the lobe is, so the bound is second order in the texel size except at
//! sharp edges of the map under the lobe's flank. The split-sum kernel falls monotonically with
//! the angle γ from R (D(h) with θ_h = γ/2, times cos γ, zero past π/2), so over T it lies
//! between k(γ_T − ρ_T) and k(γ_T + ρ_T), γ_T the angle to T's centre and ρ_T T's angular
//! radius. The manifest states that bound per level (`reference_bound`, relative like the
//! errors) beside the error measured on the filtered grid: the error against the input itself
//! differs from the stated one by at most the bound. (The filtered radiance is stored as f32:
//! rounding adds a relative 6e-8, far below any bound here.)

use super::angular::LevelError;
use super::cube::{texel_direction, CubeMap};
use super::ggx::SplitSumLobe;
use crate::envmap::resample::box_latlong;
use crate::envmap::zonal::{choose_rule, TexelRule};
use crate::envmap::{EnvMap, FACES};
use crate::io::RgbImage;
use crate::sphere::{self, LatLong};
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;

/// Texel-rule tolerance of the reference (ten times stricter than the bake's).
pub const REFERENCE_RULE_TOLERANCE: f64 = 1e-5;

/// The largest lat-long grid [`Reference::lobe`] sums (the 1024 × 512 of the shared probes);
/// larger inputs are box-filtered down to it, with the bound of the module docs.
pub const REFERENCE_MAX_TEXELS: usize = 1024 * 512;

/// Error of a level against the reference on sampled texels.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Measured {
    /// Texels sampled.
    pub samples: usize,
    /// max ‖a − r‖/‖r‖ over the texels counted.
    pub max_rel_error: f64,
    /// √(mean (‖a − r‖/‖r‖)²) over the texels counted.
    pub rms_rel_error: f64,
    /// max over the counted texels of ‖β‖/‖r‖, β the bound on what the reference's box
    /// filtering changes (0 when the input was summed as it is).
    pub reference_bound: f64,
}

/// The reference integrator over one lat-long environment (prtkit's frame).
pub struct Reference {
    /// The input, or its box filtering when it has more than the ceiling's texels.
    grid: Grid,
    input: (usize, usize),
}

/// One box filtering of the input, ready for cone sums and for the bound.
struct Grid {
    geometry: LatLong,
    /// Radiance of every texel, row-major.
    radiance: Arc<Vec<[f64; 3]>>,
    /// The texels with D_T ≠ 0 (none when the grid is the input), block by block.
    deviations: Vec<Deviation>,
    /// Blocks of [`BLOCK`] × [`BLOCK`] texels, for the bound.
    blocks: Vec<Block>,
}

/// Texels per side of a [`Block`].
const BLOCK: usize = 8;

/// How much looser than the texel-by-texel bound the stated bound may be: blocks are bounded at
/// once until what that could add is this share of the texels' bound.
const BOUND_SLACK: f64 = 0.1;

/// A block of a filtered grid's texels, bounded at once. For each texel T of the block,
/// (max_T k − min_T k)/2 = ρ_T |dk/dγ(ξ)| for some ξ in [γ_T − ρ_T, γ_T + ρ_T] (the kernel is
/// monotone in γ), and that interval lies within [γ_B − s, γ_B + s], γ_B the angle to the block's
/// centre and s its `spread`. So the block's texels add between (Σ_T D_T) ρ_min min |dk/dγ| and
/// (Σ_T D_T) ρ_max max |dk/dγ| over the block's interval.
struct Block {
    centre: DVec3,
    /// The largest angle from the centre to a member texel's centre, plus `texel_radius`.
    spread: f64,
    /// The largest angular radius ρ_T of a member texel.
    texel_radius: f64,
    /// The smallest.
    texel_radius_min: f64,
    /// Σ_T D_T per channel.
    d: [f64; 3],
    /// The members with D_T ≠ 0, in `Grid::deviations`.
    members: std::ops::Range<usize>,
}

/// A texel of a filtered grid, for the bound: its centre, the cosine and sine of its angular
/// radius ρ, and D_T = Σ_{t⊂T} Ω_t |L_t − L̄_T| per channel.
struct Deviation {
    centre: DVec3,
    cos_radius: f64,
    sin_radius: f64,
    d: [f64; 3],
}

impl Reference {
    /// Prepares the input lat-long map: as it is up to [`REFERENCE_MAX_TEXELS`], else box-filtered
    /// by the smallest power of two that fits (or the largest that divides both edges).
    pub fn new(latlong: &EnvMap) -> Result<Self, ReferenceError> {
        Self::with_max_texels(latlong, REFERENCE_MAX_TEXELS)
    }

    /// [`Reference::new`] with another ceiling on the texels summed.
    pub fn with_max_texels(latlong: &EnvMap, max_texels: usize) -> Result<Self, ReferenceError> {
        if latlong.layout() != crate::envmap::Layout::LatLong {
            return Err(ReferenceError::NotLatLong(latlong.layout().name()));
        }
        let image = latlong.image();
        let (w, h) = (image.width, image.height);
        let mut factor = 1;
        while (w / factor) * (h / factor) > max_texels && w % (2 * factor) == 0 && h % (2 * factor) == 0 {
            factor *= 2;
        }
        Ok(Reference { grid: Grid::new(image, factor), input: (w, h) })
    }

    /// Whether the input was box-filtered for the reference (then [`Measured::reference_bound`]
    /// bounds what that changes).
    pub fn is_filtered(&self) -> bool {
        self.grid.geometry.width != self.input.0
    }

    /// What the levels are measured against, in words for the manifest.
    pub fn describe(&self) -> String {
        let grid = self.grid.geometry;
        if self.is_filtered() {
            format!(
                "the input latlong {}x{} box-filtered to {}x{} and summed in angle; reference_bound bounds what the filtering changes",
                self.input.0, self.input.1, grid.width, grid.height
            )
        } else {
            format!("the input, latlong {}x{}, summed in angle", grid.width, grid.height)
        }
    }

    /// B(R) of `lobe` at any direction, with the texel rule fit for it on this grid chosen once.
    pub fn lobe(&self, lobe: &SplitSumLobe) -> LobeIntegral {
        self.grid.lobe(lobe)
    }

    /// B(R) at one direction R of prtkit's frame.
    pub fn texel(&self, axis: DVec3, lobe: &SplitSumLobe) -> [f64; 3] {
        self.lobe(lobe).at(axis)
    }

    /// Measures `level` (cube frame; `env_from_cube` takes its directions to prtkit's frame) on
    /// `samples` texels at a fixed stride.
    pub fn measure(&self, level: &CubeMap, lobe: &SplitSumLobe, env_from_cube: DMat3, samples: usize) -> Measured {
        let m = level.size();
        let total = 6 * m * m;
        let stride = (total / samples.max(1)).max(1);
        let picks: Vec<usize> = (0..total).step_by(stride).map(|i| (i + stride / 2).min(total - 1)).collect();
        let integral = self.lobe(lobe);
        let length = |v: [f64; 3]| v.iter().map(|c| c * c).sum::<f64>().sqrt();
        let measured: Vec<((f64, f64), f64)> = picks
            .par_iter()
            .map(|&i| {
                let (face, row, col) = (FACES[i / (m * m)], (i / m) % m, i % m);
                let axis = env_from_cube * texel_direction(face, m, row, col);
                let reference = integral.at(axis);
                let got = level.get(face, row, col);
                let diff = length([0, 1, 2].map(|c| got[c] as f64 - reference[c]));
                ((diff, length(reference)), length(self.grid.filtering_bound(axis.normalize(), lobe)))
            })
            .collect();
        let pairs: Vec<(f64, f64)> = measured.iter().map(|m| m.0).collect();
        let pooled = LevelError::pool(&pairs);
        let reference_bound = measured
            .iter()
            .filter(|((_, norm), _)| *norm > pooled.floor)
            .map(|((_, norm), bound)| bound / norm)
            .fold(0.0, f64::max);
        Measured {
            samples: pooled.samples,
            max_rel_error: pooled.max_rel_error,
            rms_rel_error: pooled.rms_rel_error,
            reference_bound,
        }
    }
}

impl Grid {
    /// The input box-filtered by `factor` (1: as it is), with its texels' D_T.
    fn new(input: &RgbImage, factor: usize) -> Grid {
        let radiance = |image: &RgbImage| Arc::new(image.pixels.iter().map(|p| p.map(f64::from)).collect());
        if factor == 1 {
            let geometry = LatLong::new(input.width, input.height);
            return Grid { geometry, radiance: radiance(input), deviations: Vec::new(), blocks: Vec::new() };
        }
        let filtered = box_latlong(input, input.width / factor, input.height / factor);
        let (deviations, blocks) = deviations(input, &filtered, factor);
        Grid {
            geometry: LatLong::new(filtered.width, filtered.height),
            radiance: radiance(&filtered),
            deviations,
            blocks,
        }
    }

    /// The lobe's integral with the coarsest texel rule whose texel integrals move by at most
    /// [`REFERENCE_RULE_TOLERANCE`] of their sum against the next finer rule's ([`choose_rule`]),
    /// seen from a direction on the equator (where lat-long texels are largest) and one at 45°.
    fn lobe(&self, lobe: &SplitSumLobe) -> LobeIntegral {
        let grid = self.geometry;
        let cone = (FRAC_PI_2 + 2.0 * PI / grid.height as f64).min(PI);
        let integral = |rule: &TexelRule| LobeIntegral::new(grid, self.radiance.clone(), rule, cone, lobe);
        let probes = [sphere::direction(FRAC_PI_2, 0.3 * TAU / grid.width as f64), sphere::direction(0.25 * PI, 0.0)];
        let choice = choose_rule(REFERENCE_RULE_TOLERANCE, |rule| {
            let with = integral(rule);
            let mut weights = Vec::new();
            for axis in probes {
                with.texel_integrals(axis, |_, _, w| weights.push(w));
            }
            weights
        });
        integral(&choice.rule)
    }

    /// Per channel, the bound of the module docs on |B_input(R) − B_grid(R)| for `lobe`, within
    /// [`BOUND_SLACK`] of its texel-by-texel sum: every block is bounded at once ([`Block`]), then
    /// the blocks whose bound could shrink the most are summed texel by texel until what the
    /// rest could still give back is at most that share of the texels' sum (of which the blocks'
    /// lower ends are a lower bound).
    fn filtering_bound(&self, axis: DVec3, lobe: &SplitSumLobe) -> [f64; 3] {
        let slope = Slope::of(lobe);
        let mut blocks = Vec::with_capacity(self.blocks.len());
        let (mut lower_total, mut slack) = (0.0, 0.0);
        for (i, block) in self.blocks.iter().enumerate() {
            let gamma = axis.dot(block.centre).clamp(-1.0, 1.0).acos();
            let (lo, hi) = (gamma - block.spread, gamma + block.spread);
            if lo >= FRAC_PI_2 {
                continue; // every texel of the block lies where the kernel is zero
            }
            let (a, b) = (lo.max(0.0), hi.min(FRAC_PI_2));
            let steepest = block.texel_radius * slope.max_over(a, b);
            // The slope vanishes at γ = 0 and past π/2, so a block reaching either has no
            // lower end.
            let flattest =
                if lo <= 0.0 || hi >= FRAC_PI_2 { 0.0 } else { block.texel_radius_min * slope.at(a).min(slope.at(b)) };
            let d: f64 = block.d.iter().sum();
            lower_total += d * flattest;
            slack += d * (steepest - flattest);
            blocks.push((d * (steepest - flattest), i, steepest));
        }
        blocks.sort_by(|x, y| y.0.total_cmp(&x.0));
        let mut bound = [0.0; 3];
        for (gap, i, steepest) in blocks {
            let block = &self.blocks[i];
            if slack <= BOUND_SLACK * lower_total {
                for c in 0..3 {
                    bound[c] += block.d[c] * steepest;
                }
                continue;
            }
            slack -= gap;
            for t in &self.deviations[block.members.clone()] {
                // cos(γ ∓ ρ) from cos γ = R·c: no angle is computed.
                let cos_gamma = axis.dot(t.centre).clamp(-1.0, 1.0);
                let sin_gamma = (1.0 - cos_gamma * cos_gamma).sqrt();
                let (cc, ss) = (cos_gamma * t.cos_radius, sin_gamma * t.sin_radius);
                // γ − ρ < 0 when cos γ > cos ρ: the texel holds R, where k peaks. γ + ρ past π
                // when cos γ < −cos ρ; the kernel is zero there anyway, as it is past π/2.
                let nearest = if cos_gamma >= t.cos_radius { 1.0 } else { cc + ss };
                let half_range = 0.5 * (lobe.kernel(nearest) - lobe.kernel((cc - ss).max(-1.0)));
                for c in 0..3 {
                    bound[c] += t.d[c] * half_range;
                }
            }
        }
        bound
    }
}

/// |dk/dγ| of the split-sum kernel on [0, π/2]: with c = cos γ and k = scale · c / (a + b c)²
/// ([`HalfChord`]'s constants in terms of c: a = (α² + 1)/2, b = (α² − 1)/2),
/// |dk/dγ| = sin γ · scale (a − b c) / (a + b c)³. It rises from 0 at γ = 0 to one peak γ* and
/// falls after it (or rises all the way, α = 1), so its maximum over an interval is at γ* when
/// the interval holds it and at an end otherwise (`the_slope_has_one_peak`).
struct Slope {
    scale: f64,
    a: f64,
    b: f64,
    peak: f64,
}

impl Slope {
    fn of(lobe: &SplitSumLobe) -> Slope {
        let (a2, scale) = kernel_constants(lobe);
        let mut slope = Slope { scale, a: 0.5 * (a2 + 1.0), b: 0.5 * (a2 - 1.0), peak: 0.0 };
        // The peak by a scan, then golden-section search in the bracket around the best sample.
        let steps = 1024;
        let h = FRAC_PI_2 / steps as f64;
        let best = (0..=steps).max_by(|&i, &j| slope.at(i as f64 * h).total_cmp(&slope.at(j as f64 * h))).unwrap_or(0);
        let (mut lo, mut hi) = ((best as f64 - 1.0).max(0.0) * h, ((best + 1) as f64 * h).min(FRAC_PI_2));
        let ratio = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..60 {
            let (m1, m2) = (hi - ratio * (hi - lo), lo + ratio * (hi - lo));
            if slope.at(m1) < slope.at(m2) {
                lo = m1;
            } else {
                hi = m2;
            }
        }
        slope.peak = 0.5 * (lo + hi);
        slope
    }

    /// |dk/dγ| at γ ∈ [0, π/2].
    fn at(&self, gamma: f64) -> f64 {
        let (s, c) = gamma.sin_cos();
        let t = self.a + self.b * c;
        s * self.scale * (self.a - self.b * c) / (t * t * t)
    }

    /// max |dk/dγ| over [a, b] ⊂ [0, π/2].
    fn max_over(&self, a: f64, b: f64) -> f64 {
        if (a..=b).contains(&self.peak) {
            self.at(self.peak)
        } else {
            self.at(a).max(self.at(b))
        }
    }
}

/// D_T = Σ_{t⊂T} Ω_t |L_t − L̄_T| of every texel T of `filtered` (`input` box-filtered by
/// `factor`), keeping those not zero, grouped in [`Block`]s.
fn deviations(input: &RgbImage, filtered: &RgbImage, factor: usize) -> (Vec<Deviation>, Vec<Block>) {
    let (fine, coarse) = (LatLong::new(input.width, input.height), LatLong::new(filtered.width, filtered.height));
    let rows: Vec<Vec<[f64; 3]>> = (0..filtered.height)
        .into_par_iter()
        .map(|y| {
            let mut d = vec![[0.0f64; 3]; filtered.width];
            for yy in y * factor..(y + 1) * factor {
                let omega = fine.row_solid_angle(yy);
                for xx in 0..input.width {
                    let (l, mean) = (input.get(xx, yy), filtered.get(xx / factor, y));
                    for c in 0..3 {
                        d[xx / factor][c] += omega * (l[c] as f64 - mean[c] as f64).abs();
                    }
                }
            }
            d
        })
        .collect();
    let radii: Vec<f64> = (0..filtered.height).map(|y| angular_radius(coarse, y)).collect();
    let (mut members, mut blocks) = (Vec::new(), Vec::new());
    for y0 in (0..filtered.height).step_by(BLOCK) {
        for x0 in (0..filtered.width).step_by(BLOCK) {
            let (y1, x1) = ((y0 + BLOCK).min(filtered.height), (x0 + BLOCK).min(filtered.width));
            let centre = coarse.direction_at(0.5 * (x0 + x1) as f64, 0.5 * (y0 + y1) as f64);
            let (start, mut d, mut reach) = (members.len(), [0.0; 3], 0.0f64);
            let (mut texel_radius, mut texel_radius_min) = (0.0f64, f64::INFINITY);
            for y in y0..y1 {
                texel_radius = texel_radius.max(radii[y]);
                texel_radius_min = texel_radius_min.min(radii[y]);
                for x in x0..x1 {
                    let t = coarse.texel_direction(x, y);
                    reach = reach.max(centre.dot(t).clamp(-1.0, 1.0).acos());
                    if rows[y][x] != [0.0; 3] {
                        (0..3).for_each(|c| d[c] += rows[y][x][c]);
                        members.push(Deviation {
                            centre: t,
                            cos_radius: radii[y].cos(),
                            sin_radius: radii[y].sin(),
                            d: rows[y][x],
                        });
                    }
                }
            }
            if members.len() > start {
                let spread = reach + texel_radius;
                blocks.push(Block { centre, spread, texel_radius, texel_radius_min, d, members: start..members.len() });
            }
        }
    }
    (members, blocks)
}

/// The largest angle from the centre of a texel of row `y` to a point of the texel: over its
/// corners and edge midpoints (the angle to the centre grows along each edge towards its ends).
fn angular_radius(grid: LatLong, y: usize) -> f64 {
    let centre = grid.direction_at(0.5, y as f64 + 0.5);
    let mut radius: f64 = 0.0;
    for (px, py) in [(0.0, 0.0), (0.5, 0.0), (1.0, 0.0), (0.0, 0.5), (1.0, 0.5), (0.0, 1.0), (0.5, 1.0), (1.0, 1.0)] {
        let point = grid.direction_at(px, y as f64 + py);
        radius = radius.max(centre.dot(point).clamp(-1.0, 1.0).acos());
    }
    radius
}

/// One lobe's angular reference over one environment: B(R) = Σ_t L_t ∫_t k(R·ω) dω, the texel
/// integrals by an n × n Gauss–Legendre product rule in (z, φ).
///
/// Summed row by row: a node of sub-row (z_i, sin θ_i) and sub-column φ_j has
/// R·ω = z_R z_i + sin θ_R sin θ_i cos(φ_j − φ_R), so one table of cos(φ_j − φ_R) per direction
/// serves every row, and the kernel, a rational function of R·ω, is one division per node.
pub struct LobeIntegral {
    grid: LatLong,
    radiance: Arc<Vec<[f64; 3]>>,
    /// n sub-rows per row: (θ, sin θ, weight).
    sub_rows: Vec<(f64, f64, f64)>,
    /// sin(φ/2) and cos(φ/2) of the n sub-columns of every column, column-major in blocks of n.
    sin_half_phi: Vec<f64>,
    cos_half_phi: Vec<f64>,
    /// The weight in φ of every sub-column, as `sin_half_phi`.
    node_weights: Vec<f32>,
    /// Sub-samples per axis.
    n: usize,
    cone: f64,
    kernel: HalfChord,
}

/// α² and the factor α²/(π Z) of the normalized split-sum kernel, which [`HalfChord`] and
/// [`Slope`] write as rational functions of the angle's cosine.
fn kernel_constants(lobe: &SplitSumLobe) -> (f64, f64) {
    let a2 = lobe.ggx().alpha() * lobe.ggx().alpha();
    (a2, a2 / (PI * lobe.normalization()))
}

/// The split-sum kernel as a function of u = 1 − R·ω (`ggx`'s module docs): with
/// cos² θ_h = 1 − u/2, D = α² / (π (α² cos² θ_h + sin² θ_h)²), so
/// k = scale · (1 − u) / (α² + (1 − α²) u/2)² for u < 1, zero beyond. Both terms of the
/// denominator are ≥ 0 and u is summed from non-negative terms ([`LobeIntegral`]), so single
/// precision keeps its relative accuracy at every angle, the lobe's peak included.
#[derive(Clone, Copy, Debug)]
struct HalfChord {
    scale: f32,
    alpha2: f32,
    slope: f32,
}

impl HalfChord {
    fn of(lobe: &SplitSumLobe) -> HalfChord {
        let (a2, scale) = kernel_constants(lobe);
        HalfChord { scale: scale as f32, alpha2: a2 as f32, slope: (0.5 * (1.0 - a2)) as f32 }
    }

    #[inline]
    fn at(&self, u: f32) -> f32 {
        let t = self.alpha2 + self.slope * u;
        // A select rather than a branch, so that the loops over a row's nodes vectorize.
        let k = self.scale * (1.0 - u) / (t * t);
        if u < 1.0 {
            k
        } else {
            0.0
        }
    }
}

impl LobeIntegral {
    fn new(grid: LatLong, radiance: Arc<Vec<[f64; 3]>>, rule: &TexelRule, cone: f64, lobe: &SplitSumLobe) -> Self {
        let columns = rule.sub_columns(grid);
        let h = TAU / grid.width as f64;
        let (mut sin_half_phi, mut cos_half_phi) = (Vec::new(), Vec::new());
        for x in 0..grid.width {
            for &(offset, _) in &columns {
                let (s, c) = (0.5 * (x as f64 + 0.5 + offset) * h).sin_cos();
                sin_half_phi.push(s);
                cos_half_phi.push(c);
            }
        }
        let sub_rows = (0..grid.height)
            .flat_map(|y| rule.sub_rows(grid, y))
            .map(|r| (r.z.clamp(-1.0, 1.0).acos(), r.sin_theta, r.weight))
            .collect();
        LobeIntegral {
            grid,
            radiance,
            sub_rows,
            sin_half_phi,
            cos_half_phi,
            node_weights: (0..grid.width).flat_map(|_| columns.iter().map(|c| c.1 as f32)).collect(),
            n: columns.len(),
            cone,
            kernel: HalfChord::of(lobe),
        }
    }

    /// B(R) at the direction `axis` of prtkit's frame.
    pub fn at(&self, axis: DVec3) -> [f64; 3] {
        let w = self.grid.width;
        let mut acc = [0.0; 3];
        self.texel_integrals(axis, |y, x, weight| {
            let l = self.radiance[y * w + x];
            for k in 0..3 {
                acc[k] += l[k] * weight;
            }
        });
        // The texels kept cover the kernel's whole support and the kernel is normalized (∫ k dω =
        // 1), so the sum needs no division: its weight is 1 up to the rule's tolerance.
        acc
    }

    /// Calls `visit(y, x, ∫_t k dω)` for every texel t = (x, y) whose centre is within the cone
    /// of `axis`, and some beyond it (where the kernel is zero), row by row.
    fn texel_integrals(&self, axis: DVec3, mut visit: impl FnMut(usize, usize, f64)) {
        let axis = axis.normalize();
        let (w, n) = (self.grid.width, self.n);
        let (z_r, sin_r) = (axis.z, axis.x.hypot(axis.y));
        let theta_r = sphere::theta(axis);
        let phi_r = sphere::phi(axis);
        // u = 1 − R·ω = 2 sin²((θ − θ_R)/2) + 2 sin θ_R sin θ sin²((φ − φ_R)/2): a sum of
        // non-negative terms, with sin((φ − φ_R)/2) from the half-angle tables.
        let (s_half_r, c_half_r) = (0.5 * phi_r).sin_cos();
        let sin2_half_dphi: Vec<f32> = self
            .sin_half_phi
            .iter()
            .zip(&self.cos_half_phi)
            .map(|(s, c)| {
                let d = s * c_half_r - c * s_half_r;
                (d * d) as f32
            })
            .collect();
        let mut kernel = vec![0.0f32; w * n];
        let h = TAU / w as f64;
        let cos_cone = self.cone.cos();
        let mut texel = vec![0.0; w];
        for y in 0..self.grid.height {
            let theta = self.grid.row_theta(y);
            if (theta - theta_r).abs() > self.cone {
                continue;
            }
            // The columns whose centres lie within the cone (closed form of
            // cos θ cos θ_R + sin θ sin θ_R cos Δφ ≥ cos θ*), one more each side: the kernel is
            // zero on every node of a texel whose centre is beyond π/2 + 2h.
            let (st, ct) = theta.sin_cos();
            let denom = st * sin_r;
            let c = if denom > 1e-300 { (cos_cone - ct * z_r) / denom } else { -2.0 };
            let half = if c <= -1.0 { PI } else { c.min(1.0).acos() };
            let lo = ((phi_r - half) / h - 0.5).ceil() as i64 - 1;
            let hi = ((phi_r + half) / h - 0.5).floor() as i64 + 1;
            let segments = if half >= PI || hi - lo + 1 >= w as i64 {
                [(0, w), (0, 0)]
            } else {
                let (lo, hi) = (lo.rem_euclid(w as i64) as usize, hi.rem_euclid(w as i64) as usize);
                if lo <= hi {
                    [(lo, hi + 1), (0, 0)]
                } else {
                    [(lo, w), (0, hi + 1)]
                }
            };
            for &(start, end) in &segments {
                texel[start..end].fill(0.0);
            }
            for &(theta, sin_theta, weight) in &self.sub_rows[y * n..(y + 1) * n] {
                let d = (0.5 * (theta - theta_r)).sin();
                let (a, b) = ((2.0 * d * d) as f32, (2.0 * sin_r * sin_theta) as f32);
                for &(start, end) in &segments {
                    let (nodes, out) = (&sin2_half_dphi[start * n..end * n], &mut kernel[start * n..end * n]);
                    let weights = &self.node_weights[start * n..end * n];
                    for ((k, s), wj) in out.iter_mut().zip(nodes).zip(weights) {
                        *k = wj * self.kernel.at(a + b * s);
                    }
                    let texel = &mut texel[start..end];
                    if n == 1 {
                        texel.iter_mut().zip(out.iter()).for_each(|(t, k)| *t += weight * *k as f64);
                    } else {
                        for (t, node) in texel.iter_mut().zip(out.chunks_exact(n)) {
                            *t += weight * node.iter().map(|k| *k as f64).sum::<f64>();
                        }
                    }
                }
            }
            for &(start, end) in &segments {
                (start..end).for_each(|x| visit(y, x, texel[x]));
            }
        }
    }
}

/// Why the reference cannot be set up.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// The environment is not lat-long.
    #[error("the angular reference integrates lat-long environments; this one is {0} (resample it with `prtkit convert --to latlong`)")]
    NotLatLong(&'static str),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sphere::latlong::LatLong;

    /// A map with detail at every scale: a sun a few texels wide, a sharp horizon and a ramp.
    fn detailed(w: usize, h: usize) -> EnvMap {
        let grid = LatLong::new(w, h);
        let sun = DVec3::new(0.3, -0.5, 0.8).normalize();
        EnvMap::latlong(RgbImage::from_fn(w, h, |x, y| {
            let d = grid.texel_direction(x, y);
            let sky = if d.z > 0.0 { 0.5 + 0.5 * d.x.abs() } else { 0.05 };
            let glow = (-(1.0 - d.dot(sun)) * 400.0).exp() * 50.0;
            [(sky + glow) as f32, (0.7 * sky + glow) as f32, (0.4 * sky + 0.8 * glow) as f32]
        }))
        .unwrap()
    }

    /// The bound of the module docs holds: at directions all over the sphere and for narrow and
    /// wide lobes, the box-filtered reference is within β of the input's, channel by channel,
    /// and β is not vacuous.
    #[test]
    fn the_filtered_reference_is_within_its_bound_of_the_inputs() {
        let map = detailed(256, 128);
        let fine = Reference::new(&map).unwrap();
        assert!(!fine.is_filtered());
        for (max_texels, grid) in [(128 * 64, "128x64"), (64 * 32, "64x32")] {
            let coarse = Reference::with_max_texels(&map, max_texels).unwrap();
            assert!(coarse.is_filtered());
            assert!(coarse.describe().contains(&format!("256x128 box-filtered to {grid}")), "{}", coarse.describe());
            for (r, vacuous) in [(0.2, 1.0), (0.5, 0.1), (1.0, 0.1)] {
                let lobe = SplitSumLobe::new(r).unwrap();
                let (f, c) = (fine.lobe(&lobe), coarse.lobe(&lobe));
                let mut widest: f64 = 0.0;
                for k in 0..40 {
                    let z = 1.0 - 2.0 * (k as f64 + 0.5) / 40.0;
                    let phi = k as f64 * 2.399_963;
                    let axis = DVec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
                    let (b_fine, b_coarse, bound) = (f.at(axis), c.at(axis), coarse.grid.filtering_bound(axis, &lobe));
                    for ch in 0..3 {
                        let diff = (b_fine[ch] - b_coarse[ch]).abs();
                        // The two sums' texel rules misplace at most 1e-5 of the kernel's weight each.
                        assert!(
                            diff <= bound[ch] + 3e-5 * b_fine[ch],
                            "{grid} r {r} axis {axis}: |ΔB| {diff:e} > β {:e}",
                            bound[ch]
                        );
                        widest = widest.max(bound[ch] / b_fine[ch]);
                    }
                }
                assert!(widest < vacuous, "{grid} r {r}: the bound is vacuous ({widest})");
            }
        }
    }

    /// D_T is each block's Σ Ω_t |L_t − L̄_T| (summed here texel by texel), and the filtered grid
    /// keeps each block's energy; a flat map has no deviation to bound.
    #[test]
    fn the_deviations_are_each_blocks_spread_about_its_mean() {
        let map = detailed(64, 32);
        let (fine, coarse) = (LatLong::new(64, 32), LatLong::new(16, 8));
        let filtered = box_latlong(map.image(), 16, 8);
        let (found, _) = deviations(map.image(), &filtered, 4);
        for y in 0..8 {
            for x in 0..16 {
                let (mut energy, mut d) = ([0.0f64; 3], [0.0f64; 3]);
                let mean = filtered.get(x, y);
                for yy in 4 * y..4 * y + 4 {
                    for xx in 4 * x..4 * x + 4 {
                        let v = map.image().get(xx, yy);
                        for c in 0..3 {
                            energy[c] += v[c] as f64 * fine.row_solid_angle(yy);
                            d[c] += (v[c] as f64 - mean[c] as f64).abs() * fine.row_solid_angle(yy);
                        }
                    }
                }
                // Texels with D_T = 0 are not kept.
                let kept_d = found.iter().find(|t| t.centre.distance(coarse.texel_direction(x, y)) < 1e-12);
                let got_d = kept_d.map_or([0.0; 3], |t| t.d);
                for c in 0..3 {
                    let kept = mean[c] as f64 * coarse.row_solid_angle(y);
                    assert!((kept - energy[c]).abs() <= 1e-6 * energy[c], "({x}, {y}): {kept} vs {}", energy[c]);
                    assert!((got_d[c] - d[c]).abs() <= 1e-12 + 1e-9 * d[c], "({x}, {y}): D {} vs {}", got_d[c], d[c]);
                }
            }
        }
        let flat = RgbImage::from_fn(64, 32, |_, _| [2.0, 1.0, 0.5]);
        let bound = Grid::new(&flat, 4).filtering_bound(DVec3::Z, &SplitSumLobe::new(0.5).unwrap());
        assert!(bound.iter().all(|b| *b < 1e-6), "{bound:?}");
    }

    /// The row-factored sum equals the plain one (every texel, every node's direction from
    /// `sphere::direction`, the kernel in double precision) with the same rule, to the single
    /// precision of its kernel values, for sharp and wide lobes at the poles, the equator and a
    /// seam.
    #[test]
    fn the_row_factored_sum_is_the_plain_sum() {
        let map = detailed(64, 32);
        let grid = Grid::new(map.image(), 1);
        for r in [0.1, 0.3, 0.7, 1.0] {
            let lobe = SplitSumLobe::new(r).unwrap();
            for n in [1, 3] {
                let rule = TexelRule::new(n).unwrap();
                let integral = LobeIntegral::new(grid.geometry, grid.radiance.clone(), &rule, PI, &lobe);
                for axis in [DVec3::Z, -DVec3::Z, DVec3::X, DVec3::new(0.3, -0.8, 0.2), DVec3::new(-1.0, -1e-3, 0.4)] {
                    let axis = axis.normalize();
                    let mut plain = [0.0; 3];
                    for y in 0..32 {
                        for x in 0..64 {
                            let l = map.image().get(x, y);
                            for row in rule.sub_rows(grid.geometry, y) {
                                for (offset, w_phi) in rule.sub_columns(grid.geometry) {
                                    let phi = (x as f64 + 0.5 + offset) * TAU / 64.0;
                                    let k = lobe.kernel(axis.dot(sphere::direction(row.z.acos(), phi)));
                                    for c in 0..3 {
                                        plain[c] += l[c] as f64 * row.weight * w_phi * k;
                                    }
                                }
                            }
                        }
                    }
                    let got = integral.at(axis);
                    for c in 0..3 {
                        assert!(
                            (got[c] - plain[c]).abs() <= 1e-6 * plain[c],
                            "r {r} n {n} axis {axis}: {} vs {}",
                            got[c],
                            plain[c]
                        );
                    }
                }
            }
        }
    }

    /// |dk/dγ| has one peak on [0, π/2] (what `Slope::max_over` relies on), `Slope::at` is the
    /// derivative of the kernel, and the peak found is the scan's.
    #[test]
    fn the_slope_has_one_peak() {
        for r in [0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.7, 0.85, 1.0] {
            let lobe = SplitSumLobe::new(r).unwrap();
            let slope = Slope::of(&lobe);
            let n = 20_000;
            let values: Vec<f64> = (0..=n).map(|i| slope.at(FRAC_PI_2 * i as f64 / n as f64)).collect();
            let top = values.iter().cloned().fold(0.0, f64::max);
            let rises = values.windows(2).take_while(|w| w[1] >= w[0]).count();
            assert!(values[rises..].windows(2).all(|w| w[1] <= w[0]), "r {r}: a second rise after the peak");
            assert!(
                slope.at(slope.peak) >= top * (1.0 - 1e-9),
                "r {r}: peak {} misses the scan's {top}",
                slope.at(slope.peak)
            );
            for gamma in [0.01f64, 0.1, 0.7, 1.5] {
                let h = 1e-6;
                let numeric = (lobe.kernel((gamma - h).cos()) - lobe.kernel((gamma + h).cos())) / (2.0 * h);
                assert!((numeric - slope.at(gamma)).abs() <= 1e-5 * numeric.abs().max(1e-3), "r {r} γ {gamma}");
            }
        }
    }
}
