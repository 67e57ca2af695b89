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
//! **Two levels.** A grid of 512 columns or more is summed on two levels: its blocks of 8 × 8
//! texels (more on grids wider than 1024 columns, so that the blocks form a 128-column grid) are
//! taken whole, each as its mean radiance plus the first- and second-order terms of its first and
//! second moments, which is exact to third order in the block's size ([`LobeIntegral`]); blocks
//! the horizon crosses are taken whole with a bound from the kernel's largest value there; the
//! blocks over which the kernel curves too much for a coarse rule, and those whose remainder bound
//! is largest, are summed texel by texel, until what the rest may still be off by is at most 1e-4
//! of the sum. That bound is recorded beside the errors (`reference_bound`). The blocks grouped
//! 4 × 4, their moments from theirs, form a third level above them, summed first the same way:
//! only the groups it cannot take whole are visited block by block, so a sum costs a few hundred
//! groups, not every block of the hemisphere.
//!
//! A level is compared on a fixed, evenly strided set of its texels, with the errors pooled
//! by [`LevelError::pool`]: the relative error ‖a − r‖/‖r‖ over the texels whose reference is
//! above 1 % of the sampled mean.
//!
//! **Large inputs, with a bound.** Summed as it is, an input costs one pass over its texels for
//! the coarse levels' moments and, per sample, the fine texels of the coarse texels refined,
//! whose number grows with the square of the grid's width (above 1024 columns a coarse texel
//! is 1/128 of the width). Up to [`REFERENCE_MAX_INPUT_TEXELS`] that is the cheaper way, and
//! its bound is the two-level sum's alone. A larger map is measured on its box filtering to at
//! most [`REFERENCE_MAX_TEXELS`] (f × f input texels to one, each coarse texel T the
//! solid-angle-weighted mean L̄_T of the block, so it keeps the block's energy), with a bound on
//! what the filtering changes. Within T the input sums
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
//! radius. The manifest states that bound, plus the two-level one, per level
//! (`reference_bound`, relative like the errors) beside the error measured on the filtered grid:
//! the error against the input itself differs from the stated one by at most the bound. (The filtered radiance is stored as f32:
//! rounding adds a relative 6e-8, far below any bound here.)

use super::angular::LevelError;
use super::cube::{texel_direction, CubeMap};
use crate::brdf::ggx::SplitSumLobe;
use crate::envmap::resample::box_latlong;
use crate::envmap::zonal::{choose_rule, TexelRule};
use crate::envmap::{EnvMap, Face, FACES};
use crate::io::RgbImage;
use crate::sphere::{self, LatLong};
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::borrow::Cow;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;

/// Texel-rule tolerance of the reference (ten times stricter than the bake's).
pub const REFERENCE_RULE_TOLERANCE: f64 = 1e-5;

/// The largest input [`Reference::new`] sums as it is (4096 × 2048).
pub const REFERENCE_MAX_INPUT_TEXELS: usize = 4096 * 2048;

/// The largest grid a larger input is box-filtered to, with the bound of the module docs: the
/// filtering's box, its deviations and the bound's blocks cost passes over the input besides
/// the sums, and the bound's blocks opened per sample grow with the filtered grid, so a filtered
/// grid is kept a quarter the size of an input summed as it is.
pub const REFERENCE_MAX_TEXELS: usize = 2048 * 1024;

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

/// The reference integrator over one lat-long environment (prtkit's frame), which it borrows.
pub struct Reference<'a> {
    /// The input, or its box filtering when it has more than the ceiling's texels.
    grid: Grid<'a>,
    input: (usize, usize),
}

/// One box filtering of the input, ready for cone sums and for the bound.
struct Grid<'a> {
    geometry: LatLong,
    texels: Texels<'a>,
    /// What the box filtering changed, for the bound (none when the grid is the input).
    filtering: Option<Filtering>,
}

/// How a grid's radiance is kept for the sums (f32 as read: the sums read it once per texel
/// and sample, so its size is what they wait on).
enum Texels<'a> {
    /// Row by row, for a grid summed texel by texel.
    Rows(Arc<Vec<[f32; 3]>>),
    /// The grid box-filtered into a coarse level, for the two-level sum ([`LobeIntegral`]), which
    /// keeps the fine texels too, and the coarse level's texels grouped [`TOP_GROUP`] ×
    /// [`TOP_GROUP`] above it.
    Levels(Arc<Coarse<'a>>, Option<Arc<Coarse<'a>>>),
}

/// The directions a texel rule is chosen at: one on the equator, where lat-long texels are
/// largest, between two columns, and one at 45°.
fn probe_axes(grid: LatLong) -> [DVec3; 2] {
    [sphere::direction(FRAC_PI_2, 0.3 * TAU / grid.width as f64), sphere::direction(0.25 * PI, 0.0)]
}

/// Texels per side of the [`Block`]s of each level, coarsest first; each divides the one before,
/// so a block opened is the blocks of the next level inside it (the last level's, its texels).
const BLOCK_SIZES: [usize; 3] = [64, 16, 4];

/// How much looser than the texel-by-texel bound the stated bound may be: blocks are bounded at
/// once until what that could add is this share of the texels' bound.
const BOUND_SLACK: f64 = 0.1;

/// A block of a filtered grid's texels, bounded at once. For each texel T of the block,
/// (max_T k − min_T k)/2 = ρ_T |dk/dγ(ξ)| for some ξ in [γ_T − ρ_T, γ_T + ρ_T] (the kernel is
/// monotone in γ), and that interval lies within [γ_B − s, γ_B + s], γ_B the angle to the block's
/// centre and s its `reach`. So the block's texels add between (Σ_T D_T) ρ_min min |dk/dγ| and
/// (Σ_T D_T) ρ_max max |dk/dγ| over the block's interval.
struct Block {
    centre: DVec3,
    /// s: at least the largest angle from the centre to a point of a member texel with D_T ≠ 0.
    reach: f64,
    /// cos s and sin s.
    spread: (f64, f64),
    /// The largest angular radius ρ_T of a member texel.
    texel_radius: f64,
    /// The smallest.
    texel_radius_min: f64,
    /// Σ_T D_T per channel.
    d: [f64; 3],
}

impl Block {
    /// The block with its bound taken at once, seen from `axis`; `None` when every member texel
    /// lies where the kernel is zero, or none has a deviation.
    fn gap(&self, index: usize, axis: DVec3, slope: &Slope) -> Option<Gap> {
        // cos(γ ∓ s) of the block's interval [γ − s, γ + s].
        let cos_gamma = axis.dot(self.centre).clamp(-1.0, 1.0);
        let Span { lo: far, hi: near, .. } = Span::about(cos_gamma, self.spread);
        if near <= 0.0 || self.d == [0.0; 3] {
            return None;
        }
        let (least, most) = slope.between(far.max(0.0), near);
        let steepest = self.texel_radius * most;
        // The slope vanishes at γ = 0 and past π/2, so a block reaching either has no lower end.
        let flattest = if cos_gamma >= self.spread.0 || far <= 0.0 { 0.0 } else { self.texel_radius_min * least };
        let d: f64 = self.d.iter().sum();
        Some(Gap { gap: d * (steepest - flattest), lower: d * flattest, index, steepest })
    }
}

/// One level of [`Block`]s of `size` × `size` texels of a grid, row-major, `across` to a row (the
/// last of each row and column cut at the grid's edge).
struct Blocks {
    grid: LatLong,
    size: usize,
    across: usize,
    blocks: Vec<Block>,
}

impl Blocks {
    /// The level of `size` × `size` blocks over `grid`, block `i` made by `block(&level, i)`.
    fn new(grid: LatLong, size: usize, block: impl Fn(&Blocks, usize) -> Block + Sync) -> Blocks {
        let mut level = Blocks { grid, size, across: grid.width.div_ceil(size), blocks: Vec::new() };
        let blocks = (0..level.across * grid.height.div_ceil(size)).into_par_iter().map(|i| block(&level, i)).collect();
        level.blocks = blocks;
        level
    }

    /// Blocks of `size` × `size` texels from the blocks of `finer` (a level of the same grid)
    /// inside each: the reach is the farthest a member's reach takes from the centre.
    fn grouped(finer: &Blocks, size: usize) -> Blocks {
        Blocks::new(finer.grid, size, |level, i| {
            let middle = level.middle(i);
            let (mut reach, mut d) = (0.0f64, [0.0; 3]);
            let (mut texel_radius, mut texel_radius_min) = (0.0f64, f64::INFINITY);
            for child in level.children(i, finer).map(|j| &finer.blocks[j]) {
                (texel_radius, texel_radius_min) =
                    (texel_radius.max(child.texel_radius), texel_radius_min.min(child.texel_radius_min));
                if child.d != [0.0; 3] {
                    reach = reach.max((middle.dot(child.centre).clamp(-1.0, 1.0).acos() + child.reach).min(PI));
                    (0..3).for_each(|c| d[c] += child.d[c]);
                }
            }
            Block { centre: middle, reach, spread: (reach.cos(), reach.sin()), texel_radius, texel_radius_min, d }
        })
    }

    /// The texels (columns, rows) of block `index`.
    fn texels(&self, index: usize) -> (std::ops::Range<usize>, std::ops::Range<usize>) {
        let (x, y) = (self.size * (index % self.across), self.size * (index / self.across));
        (x..(x + self.size).min(self.grid.width), y..(y + self.size).min(self.grid.height))
    }

    /// The direction at the middle of block `index`.
    fn middle(&self, index: usize) -> DVec3 {
        let (columns, rows) = self.texels(index);
        self.grid.direction_at(0.5 * (columns.start + columns.end) as f64, 0.5 * (rows.start + rows.end) as f64)
    }

    /// Blocks `indices` bounded at once from `axis` ([`Block::gap`]), those that add nothing left
    /// out.
    fn gaps(&self, indices: impl Iterator<Item = usize>, axis: DVec3, slope: &Slope) -> Vec<Gap> {
        indices.filter_map(|i| self.blocks[i].gap(i, axis, slope)).collect()
    }

    /// The blocks of `finer` (a level of the same grid) inside block `index` of this one.
    fn children<'a>(&self, index: usize, finer: &'a Blocks) -> impl Iterator<Item = usize> + 'a {
        let (columns, rows) = self.texels(index);
        let (f, across) = (finer.size, finer.across);
        (rows.start / f..rows.end.div_ceil(f))
            .flat_map(move |by| (columns.start / f..columns.end.div_ceil(f)).map(move |bx| by * across + bx))
    }
}

/// A block in [`Grid::filtering_bound`]: by how much summing it texel by texel could lower the
/// bound at most, the lower end of its texels' bound, and its bound taken at once (without D_T).
struct Gap {
    gap: f64,
    lower: f64,
    index: usize,
    steepest: f64,
}

/// A box-filtered grid's departures from its input: D_T = Σ_{t⊂T} Ω_t |L_t − L̄_T| per channel
/// of every texel T (row-major; summed in f64 and kept as the least f32 not below the sum, in
/// half the memory), the blocks that bound them at once, and what places each texel on the
/// sphere (its centre from per-row and per-column sines and cosines, and the cosine and sine of
/// its angular radius ρ per row).
struct Filtering {
    deviation: Vec<[f32; 3]>,
    /// The blocks at each of [`BLOCK_SIZES`].
    levels: Vec<Blocks>,
    rows: Vec<(f64, f64)>,
    columns: Vec<(f64, f64)>,
    radius: Vec<(f64, f64)>,
}

impl Filtering {
    /// The centre of texel (x, y): the same products as `LatLong::texel_direction`.
    fn centre(&self, x: usize, y: usize) -> DVec3 {
        let ((st, ct), (sp, cp)) = (self.rows[y], self.columns[x]);
        DVec3::new(st * cp, st * sp, ct)
    }
}

impl<'a> Reference<'a> {
    /// Prepares the input lat-long map: as it is up to [`REFERENCE_MAX_INPUT_TEXELS`], else
    /// box-filtered to at most [`REFERENCE_MAX_TEXELS`] ([`Reference::with_max_texels`]).
    pub fn new(latlong: &'a EnvMap) -> Result<Self, ReferenceError> {
        let image = latlong.image();
        let texels = image.width * image.height;
        Self::with_max_texels(latlong, if texels <= REFERENCE_MAX_INPUT_TEXELS { texels } else { REFERENCE_MAX_TEXELS })
    }

    /// The input as it is up to `max_texels`, else box-filtered by the smallest power of two
    /// that fits (or the largest that divides both edges).
    pub fn with_max_texels(latlong: &'a EnvMap, max_texels: usize) -> Result<Self, ReferenceError> {
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

    /// Whether the reference may differ from the texel-by-texel sum over the input (then
    /// [`Measured::reference_bound`] bounds by how much): the input was box-filtered, or is
    /// summed on two or three levels ([`LobeIntegral`]).
    pub fn is_bounded(&self) -> bool {
        self.is_filtered() || matches!(self.grid.texels, Texels::Levels(..))
    }

    /// What the levels are measured against, in words for the manifest.
    pub fn describe(&self) -> String {
        let grid = self.grid.geometry;
        let summed = match &self.grid.texels {
            Texels::Levels(coarse, Some(top)) => format!(
                "summed in angle on three levels ({t}x{t} and {f}x{f} texels taken whole with their first and second moments where the bound allows)",
                t = top.factor,
                f = coarse.factor
            ),
            Texels::Levels(coarse, None) => format!(
                "summed in angle on two levels ({f}x{f} texels taken whole with their first and second moments where the bound allows)",
                f = coarse.factor
            ),
            Texels::Rows(_) => "summed in angle".to_string(),
        };
        if self.is_filtered() {
            format!(
                "the input latlong {}x{} box-filtered to {}x{} and {summed}; reference_bound bounds what the filtering and the summation change",
                self.input.0, self.input.1, grid.width, grid.height
            )
        } else if self.is_bounded() {
            format!(
                "the input, latlong {}x{}, {summed}; reference_bound bounds what the summation changes",
                grid.width, grid.height
            )
        } else {
            format!("the input, latlong {}x{}, {summed}", grid.width, grid.height)
        }
    }

    /// B(R) of `lobe` at any direction, with the texel rule fit for it on this grid chosen once.
    pub fn lobe(&self, lobe: &SplitSumLobe) -> LobeIntegral<'a> {
        self.grid.lobe(lobe)
    }

    /// Measures `level` (cube frame; `env_from_cube` takes its directions to prtkit's frame) on
    /// `samples` texels at a fixed stride.
    pub fn measure(&self, level: &CubeMap, lobe: &SplitSumLobe, env_from_cube: DMat3, samples: usize) -> Measured {
        self.expect(lobe, env_from_cube, samples, &[level.size()]).remove(0).measure(level)
    }

    /// What [`Reference::measure`] compares a level of each face size in `sizes` with: the
    /// reference at its sampled texels, which needs nothing of the level but its size, so it can
    /// be summed while the level is baked. The lobe's texel rule is chosen once for them all.
    pub fn expect(&self, lobe: &SplitSumLobe, env_from_cube: DMat3, samples: usize, sizes: &[usize]) -> Vec<Expected> {
        let (integral, slope) = (self.lobe(lobe), Slope::of(lobe));
        sizes
            .iter()
            .map(|&size| {
                let total = 6 * size * size;
                let stride = (total / samples.max(1)).max(1);
                let texels = (0..total)
                    .step_by(stride)
                    .map(|i| (i + stride / 2).min(total - 1))
                    .collect::<Vec<usize>>()
                    .into_par_iter()
                    .map(|i| {
                        let (face, row, col) = (FACES[i / (size * size)], (i / size) % size, i % size);
                        let axis = (env_from_cube * texel_direction(face, size, row, col)).normalize();
                        let (reference, two_level) = integral.at_with_bound(axis);
                        let filtering = self.grid.filtering_bound(axis, lobe, &slope);
                        let bound = [0, 1, 2].map(|c| filtering[c] + two_level[c]);
                        ExpectedTexel { at: (face, row, col), reference, bound: length(bound) }
                    })
                    .collect();
                Expected { size, texels }
            })
            .collect()
    }
}

/// The reference at the sampled texels of a level not yet baked ([`Reference::expect`]).
pub struct Expected {
    size: usize,
    texels: Vec<ExpectedTexel>,
}

struct ExpectedTexel {
    at: (Face, usize, usize),
    reference: [f64; 3],
    /// ‖β‖: the bound on how far `reference` may be from the texel-by-texel sum over the input.
    bound: f64,
}

impl Expected {
    /// The face size of the level the samples are taken for.
    pub fn size(&self) -> usize {
        self.size
    }

    /// The level's error at the sampled texels.
    ///
    /// # Panics
    /// When `level` is not of the size the samples were taken for (a caller's mistake).
    pub fn measure(&self, level: &CubeMap) -> Measured {
        assert_eq!(level.size(), self.size, "a level is measured at the size its samples were taken for");
        let pairs: Vec<(f64, f64)> = self
            .texels
            .iter()
            .map(|t| {
                let got = level.get(t.at.0, t.at.1, t.at.2);
                (length([0, 1, 2].map(|c| got[c] as f64 - t.reference[c])), length(t.reference))
            })
            .collect();
        let pooled = LevelError::pool(&pairs);
        let reference_bound = pairs
            .iter()
            .zip(&self.texels)
            .filter(|((_, norm), _)| *norm > pooled.floor)
            .map(|((_, norm), t)| t.bound / norm)
            .fold(0.0, f64::max);
        Measured {
            samples: pooled.samples,
            max_rel_error: pooled.max_rel_error,
            rms_rel_error: pooled.rms_rel_error,
            reference_bound,
        }
    }
}

/// The Euclidean length of an RGB triple.
fn length(v: [f64; 3]) -> f64 {
    v.iter().map(|c| c * c).sum::<f64>().sqrt()
}

impl<'a> Grid<'a> {
    /// The input box-filtered by `factor` (1: as it is, borrowed), with its texels' D_T.
    fn new(input: &'a RgbImage, factor: usize) -> Grid<'a> {
        let texels = |geometry: LatLong, pixels: Cow<'a, [[f32; 3]]>| match Coarse::factor(geometry) {
            Some(f) => {
                let (coarse, top) = Coarse::levels(geometry, f, pixels);
                Texels::Levels(coarse, top)
            }
            None => Texels::Rows(Arc::new(pixels.into_owned())),
        };
        if factor == 1 {
            let geometry = LatLong::new(input.width, input.height);
            return Grid { geometry, texels: texels(geometry, Cow::Borrowed(&input.pixels)), filtering: None };
        }
        let filtered = box_latlong(input, input.width / factor, input.height / factor);
        let filtering = Some(Filtering::of(input, &filtered, factor));
        let geometry = LatLong::new(filtered.width, filtered.height);
        Grid { geometry, texels: texels(geometry, Cow::Owned(filtered.pixels)), filtering }
    }

    /// The lobe's integral: on this grid with the coarsest texel rule whose texel integrals move
    /// by at most [`REFERENCE_RULE_TOLERANCE`] of their sum against the next finer rule's
    /// ([`choose_rule`]), seen from a direction on the equator (where lat-long texels are
    /// largest) and one at 45°; and, for grids of [`TWO_LEVEL_MIN_WIDTH`] columns or more, on
    /// the coarse level too ([`LobeIntegral`]).
    fn lobe(&self, lobe: &SplitSumLobe) -> LobeIntegral<'a> {
        let grid = self.geometry;
        let curve = Curve::of(lobe);
        let fine = |rule: &TexelRule| ConeSum::new(grid, rule, lobe);
        // With a coarse level the fine rule need only be exact where the fine grid is summed
        // whatever the radiance: inside the coarse texels that are always refined. The other
        // texels' weight still counts in the total the tolerance is a share of: it enters once,
        // the same for every rule compared. Texels refined for their bound are summed with the
        // same rule: the kernel is smoother over them than over those it was tried on or, where
        // the horizon crosses them, near its least (f(s) ≤ f(ρ) for s within a fine texel's
        // radius ρ of the kink).
        let probes = probe_axes(grid).map(DVec3::normalize);
        let choice = match &self.texels {
            Texels::Rows(_) => choose_rule(REFERENCE_RULE_TOLERANCE, |rule| {
                let with = fine(rule);
                let mut weights = Vec::new();
                for axis in probes {
                    with.texel_integrals(axis, |_, _, w| weights.push(w));
                }
                weights
            }),
            Texels::Levels(coarse, _) => {
                let refined: Vec<Vec<usize>> = probes
                    .iter()
                    .map(|&axis| {
                        (0..coarse.geometry.height * coarse.geometry.width)
                            .filter(|&i| {
                                let (x, y) = (i % coarse.geometry.width, i / coarse.geometry.width);
                                coarse.span(axis, x, y).is_some_and(|span| curve.always_refined(span))
                            })
                            .collect()
                    })
                    .collect();
                // The kernel's weight is 1 at each probe.
                let midpoint = fine(&TexelRule::new(1).expect("one sub-sample is a rule"));
                let mut rest = probes.len() as f64;
                for (blocks, &axis) in refined.iter().zip(&probes) {
                    midpoint.within(coarse, blocks, axis, |_, _, w| rest -= w.iter().sum::<f64>());
                }
                choose_rule(REFERENCE_RULE_TOLERANCE, |rule| {
                    let with = fine(rule);
                    let mut weights = vec![rest];
                    for (blocks, &axis) in refined.iter().zip(&probes) {
                        with.within(coarse, blocks, axis, |_, _, w| weights.extend_from_slice(w));
                    }
                    weights
                })
            }
        };
        let sums = match &self.texels {
            Texels::Rows(radiance) => Sums::Rows(radiance.clone()),
            Texels::Levels(coarse, top) => Sums::Levels {
                coarse: level_sum(coarse, lobe, &curve),
                top: top.as_ref().map(|t| level_sum(t, lobe, &curve)),
            },
        };
        LobeIntegral { fine: fine(&choice.rule), sums, curve }
    }

    /// Per channel, the bound of the module docs on |B_input(R) − B_grid(R)| for `lobe`, within
    /// [`BOUND_SLACK`] of its texel-by-texel sum. Every block of the coarsest level is bounded at
    /// once ([`Block`]); on each level the blocks whose bound could shrink the most are opened
    /// into the next level's (the last level's into their texels, summed one by one) until what
    /// the rest could still give back is at most half the share left (all of it on the last
    /// level). The share is of the texels' sum, of which the lower ends of the blocks and texels
    /// in hand are a lower bound; it grows as blocks open.
    fn filtering_bound(&self, axis: DVec3, lobe: &SplitSumLobe, slope: &Slope) -> [f64; 3] {
        let Some(filtering) = &self.filtering else { return [0.0; 3] };
        let (mut bound, mut kept_lower, mut kept_gap) = ([0.0; 3], 0.0, 0.0);
        let top = &filtering.levels[0];
        let mut gaps = top.gaps(0..top.blocks.len(), axis, slope);
        for (depth, level) in filtering.levels.iter().enumerate() {
            let share = BOUND_SLACK * (kept_lower + gaps.iter().map(|g| g.lower).sum::<f64>()) - kept_gap;
            let finer = filtering.levels.get(depth + 1);
            let opened =
                take_largest(&mut gaps, |g| g.gap, |g| g.index, if finer.is_some() { 0.5 * share } else { share });
            // The rest taken at once.
            for g in &gaps {
                (0..3).for_each(|c| bound[c] += level.blocks[g.index].d[c] * g.steepest);
                (kept_gap, kept_lower) = (kept_gap + g.gap, kept_lower + g.lower);
            }
            if let Some(finer) = finer {
                gaps = finer.gaps(opened.iter().flat_map(|&i| level.children(i, finer)), axis, slope);
                continue;
            }
            for i in opened {
                let (columns, rows) = level.texels(i);
                for y in rows {
                    for x in columns.clone() {
                        let d = filtering.deviation[y * self.geometry.width + x];
                        if d == [0.0; 3] {
                            continue;
                        }
                        // k over the texel: from its value nearest R (R itself when the texel
                        // holds it, where k peaks) to its farthest.
                        let cos_gamma = axis.dot(filtering.centre(x, y)).clamp(-1.0, 1.0);
                        let span = Span::about(cos_gamma, filtering.radius[y]);
                        let half_range = 0.5 * (lobe.kernel(span.hi) - lobe.kernel(span.lo));
                        (0..3).for_each(|c| bound[c] += d[c] as f64 * half_range);
                    }
                }
            }
        }
        bound
    }
}

/// A coarse level's cone sum: the coarsest texel rule exact to [`REFERENCE_RULE_TOLERANCE`] on
/// the texels the sum may take whole, those over which the kernel is smooth (the others are
/// always refined), seen from the probe directions.
fn level_sum<'a>(level: &Arc<Coarse<'a>>, lobe: &SplitSumLobe, curve: &Curve) -> (ConeSum, Arc<Coarse<'a>>) {
    let choice = choose_rule(REFERENCE_RULE_TOLERANCE, |rule| {
        let with = ConeSum::new(level.geometry, rule, lobe);
        let mut weights = Vec::new();
        for axis in probe_axes(level.geometry) {
            let axis = axis.normalize();
            with.texel_integrals(axis, |y, x, w| {
                if level.span(axis, x, y).is_some_and(|span| !curve.too_curved(span)) {
                    weights.push(w);
                }
            });
        }
        weights
    });
    (ConeSum::new(level.geometry, &choice.rule, lobe), level.clone())
}

/// |dk/dγ| of the split-sum kernel on [0, π/2]: with k = f(cos γ) ([`Curve`]),
/// |dk/dγ| = sin γ · f'(cos γ). It rises from 0 at γ = 0 to one peak γ* and falls after it (or
/// rises all the way, α = 1), so its maximum over an interval is at γ* when the interval holds it
/// and at an end otherwise (`the_slope_has_one_peak`). The bound evaluates it from cos γ, which
/// it has without an angle: √(1 − s²) f'(s).
struct Slope {
    curve: Curve,
    peak: f64,
    /// cos γ* and the slope there.
    peak_cos: f64,
    top: f64,
}

impl Slope {
    fn of(lobe: &SplitSumLobe) -> Slope {
        let mut slope = Slope { curve: Curve::of(lobe), peak: 0.0, peak_cos: 1.0, top: 0.0 };
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
        (slope.peak_cos, slope.top) = (slope.peak.cos(), slope.at(slope.peak));
        slope
    }

    /// |dk/dγ| at cos γ = s ∈ [0, 1].
    fn at_cos(&self, s: f64) -> f64 {
        (1.0 - s * s).max(0.0).sqrt() * self.curve.first(s)
    }

    /// min and max |dk/dγ| over cos γ ∈ [a, b] ⊂ [0, 1]: the least at an end, the most at the
    /// peak when the interval holds it.
    fn between(&self, a: f64, b: f64) -> (f64, f64) {
        let (at_a, at_b) = (self.at_cos(a), self.at_cos(b));
        (at_a.min(at_b), if (a..=b).contains(&self.peak_cos) { self.top } else { at_a.max(at_b) })
    }

    /// |dk/dγ| at γ ∈ [0, π/2].
    fn at(&self, gamma: f64) -> f64 {
        let (s, c) = gamma.sin_cos();
        s * self.curve.first(c)
    }
}

impl Filtering {
    /// D_T = Σ_{t⊂T} Ω_t |L_t − L̄_T| of every texel T of `filtered` (`input` box-filtered by
    /// `factor`), in [`Block`]s of each of [`BLOCK_SIZES`].
    fn of(input: &RgbImage, filtered: &RgbImage, factor: usize) -> Filtering {
        let (fine, coarse) = (LatLong::new(input.width, input.height), LatLong::new(filtered.width, filtered.height));
        let width = filtered.width;
        // Row by row, each summed aside and written once: a row updated in place would fault
        // each page twice (read as the zero page, then copied on the first write).
        let mut deviation = vec![[0.0f32; 3]; width * filtered.height];
        deviation.par_chunks_mut(width).enumerate().for_each(|(y, out)| {
            let mut row = vec![[0.0f64; 3]; width];
            let means = &filtered.pixels[y * width..(y + 1) * width];
            for yy in y * factor..(y + 1) * factor {
                let omega = fine.row_solid_angle(yy);
                let line = &input.pixels[yy * input.width..(yy + 1) * input.width];
                for ((d, mean), texels) in row.iter_mut().zip(means).zip(line.chunks_exact(factor)) {
                    let mut spread = [0.0f64; 3];
                    for l in texels {
                        (0..3).for_each(|c| spread[c] += (l[c] as f64 - mean[c] as f64).abs());
                    }
                    (0..3).for_each(|c| d[c] += omega * spread[c]);
                }
            }
            for (o, d) in out.iter_mut().zip(&row) {
                *o = d.map(f32_at_least);
            }
        });
        let radii: Vec<f64> = (0..coarse.height).map(|y| angular_radius(coarse, y)).collect();
        let mut filtering = Filtering {
            deviation,
            levels: Vec::new(),
            rows: (0..coarse.height).map(|y| coarse.row_theta(y).sin_cos()).collect(),
            columns: (0..coarse.width).map(|x| coarse.column_phi(x).sin_cos()).collect(),
            radius: radii.iter().map(|r| r.sin_cos()).map(|(s, c)| (c, s)).collect(),
        };
        // The finest level from the texels, each coarser one from the level below it.
        let (finest, coarser) = BLOCK_SIZES.split_last().expect("at least one level of blocks");
        let mut levels = vec![filtering.blocks_of_texels(coarse, &radii, *finest)];
        for &size in coarser.iter().rev() {
            let grouped = Blocks::grouped(levels.last().expect("the finest level is made"), size);
            levels.push(grouped);
        }
        levels.reverse();
        filtering.levels = levels;
        filtering
    }

    /// Blocks of `size` × `size` texels of `grid`, from the texels: the reach is the farthest
    /// centre of a texel with D_T ≠ 0 plus the largest texel radius.
    fn blocks_of_texels(&self, grid: LatLong, radii: &[f64], size: usize) -> Blocks {
        Blocks::new(grid, size, |level, i| {
            let (columns, rows) = level.texels(i);
            let middle = level.middle(i);
            let (texel_radius, texel_radius_min) =
                radii[rows.clone()].iter().fold((0.0f64, f64::INFINITY), |(hi, lo), &r| (hi.max(r), lo.min(r)));
            let (mut d, mut nearest) = ([0.0; 3], 1.0f64);
            for y in rows {
                for x in columns.clone() {
                    let texel = self.deviation[y * grid.width + x];
                    if texel != [0.0; 3] {
                        nearest = nearest.min(middle.dot(self.centre(x, y)));
                        (0..3).for_each(|c| d[c] += texel[c] as f64);
                    }
                }
            }
            // The farthest texel centre: acos falls as the cosine grows.
            let reach = (nearest.clamp(-1.0, 1.0).acos() + texel_radius).min(PI);
            Block { centre: middle, reach, spread: (reach.cos(), reach.sin()), texel_radius, texel_radius_min, d }
        })
    }
}

/// The least f32 not below `v` (≥ 0): zero stays zero, so flat texels are still skipped.
fn f32_at_least(v: f64) -> f32 {
    // Without a branch: rounded down for about half the texels, and unpredictably so. For v ≥ 0
    // the next f32 up is the next bit pattern (from 0 the least subnormal, from f32::MAX ∞).
    let nearest = v as f32;
    f32::from_bits(nearest.to_bits() + u32::from((nearest as f64) < v))
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

/// Fine texels per coarse texel edge in the two-level sum, at least: wider grids keep a coarse
/// level of [`COARSE_WIDTH`] columns.
const COARSE_FACTOR: usize = 8;

/// The coarse level's width for grids wider than [`COARSE_FACTOR`] times it: the coarse pass
/// costs a few operations per coarse texel and sample, so it stays this size.
const COARSE_WIDTH: usize = 128;

/// Coarse texels per top texel edge ([`LobeIntegral`]'s third level).
const TOP_GROUP: usize = 4;

/// Coarse levels narrower than this have no top level.
const TOP_MIN_WIDTH: usize = 64;

/// Grids narrower than this are summed texel by texel alone: the coarse level would save little.
const TWO_LEVEL_MIN_WIDTH: usize = 512;

/// The two-level sum refines coarse texels until what the others may still be off by is at most
/// this share of the sum (relative, like the errors it sits beside).
const TWO_LEVEL_TOLERANCE: f64 = 1e-4;

/// Coarse texels over which the kernel's second-order term ½ max|f''| Δs² exceeds this (in units
/// of the normalized kernel) are always refined: near the peak of a sharp lobe no coarse texel
/// rule is exact, whatever the radiance.
const COARSE_CURVATURE: f64 = 1.0;

/// The lobe's reference integral B(R) = Σ_t L_t ∫_t k(R·ω) dω over a grid (the input, or its
/// box filtering), summed on two levels (three with the top one) when the grid is large.
///
/// With the grid box-filtered by F into coarse texels T (radiance L̄_T, the solid-angle-weighted
/// mean), the sum over the fine texels t of T splits as
///
///   Σ_{t⊂T} L_t K_t = L̄_T K_T + Σ_{t⊂T} (L_t − L̄_T) K_t,   K_t = ∫_t k dω, K_T = Σ_{t⊂T} K_t.
///
/// The kernel is k = f(s), s = R·ω. Expanding f about s_T = R·c_T (c_T the texel's centre),
/// f(s) = f(s_T) + f'(s_T)(s − s_T) + ½ f''(s_T)(s − s_T)² + r(s) with |r| ≤ C (s − s_T)²
/// ([`Curve::expansion`]); with e = ω − c_T, s − s_T = R·e, and since Σ_t (L_t − L̄_T) Ω_t = 0
/// the constant term cancels:
///
///   Σ_{t⊂T} (L_t − L̄_T) K_t = f'(s_T) R·M_T + ½ f''(s_T) Rᵀ Q_T R + ρ_T,   |ρ_T| ≤ C Rᵀ A_T R,
///
/// M_T = Σ (L_t − L̄_T) ∫_t e dω, Q_T = Σ (L_t − L̄_T) ∫_t e eᵀ dω, A_T = Σ |L_t − L̄_T| ∫_t e eᵀ dω
/// per channel ([`BlockMoments`]): the coarse texel with its moments is exact to third order, and
/// exact wherever the kernel is linear in s (α = 1: the cosine lobe). Texels the horizon crosses
/// (f has a kink at s = 0) are taken whole with the bound of [`LobeIntegral::taken_whole`]; texels
/// too curved for a coarse rule, and those with the largest bounds (until the rest's is at most
/// [`TWO_LEVEL_TOLERANCE`] of the sum) are summed texel by texel on the fine grid; the bound of the
/// others is returned beside the value.
///
/// A third level above the coarse one ([`Coarse::levels`]) is summed the same way first: its
/// texels too curved for its rule, and those of largest bound until the rest's is at most half
/// the tolerance, are opened into their coarse texels, and only those are visited on the coarse
/// level. Far from a sharp lobe's peak, and inside the cosine lobe, a top texel stands for
/// [`TOP_GROUP`]² coarse ones.
pub struct LobeIntegral<'a> {
    fine: ConeSum,
    sums: Sums<'a>,
    curve: Curve,
}

/// What a [`LobeIntegral`] sums besides its fine rule, by how its grid keeps its texels
/// ([`Texels`]): the texels row by row, or the coarse level's cone sum (and the top level's).
#[expect(clippy::large_enum_variant, reason = "one per lobe, made once and never moved in a loop")]
enum Sums<'a> {
    Rows(Arc<Vec<[f32; 3]>>),
    Levels { coarse: (ConeSum, Arc<Coarse<'a>>), top: Option<(ConeSum, Arc<Coarse<'a>>)> },
}

impl LobeIntegral<'_> {
    /// B(R) at the direction `axis` of prtkit's frame.
    pub fn at(&self, axis: DVec3) -> [f64; 3] {
        self.at_with_bound(axis).0
    }

    /// B(R) and, per channel, the bound on how far it may be from the texel-by-texel sum over
    /// the whole grid (zero when the grid was summed texel by texel).
    pub fn at_with_bound(&self, axis: DVec3) -> ([f64; 3], [f64; 3]) {
        let ((coarse_sum, coarse), top) = match &self.sums {
            Sums::Rows(radiance) => return (self.fine.at(radiance, axis), [0.0; 3]),
            Sums::Levels { coarse, top } => (coarse, top),
        };
        let axis = axis.normalize();
        let size = |t: &Whole| t.bound.iter().sum::<f64>();
        let (mut value, mut bound) = ([0.0; 3], [0.0; 3]);
        let mut add = |whole: &[Whole]| {
            for t in whole {
                for c in 0..3 {
                    value[c] += t.value[c];
                    bound[c] += t.bound[c];
                }
            }
        };
        let share = |estimate: [f64; 3]| TWO_LEVEL_TOLERANCE * estimate.iter().map(|e| e.abs()).sum::<f64>();
        // The top level's texels no rule of its integrates are opened first: the coarse level
        // visits their texels, and its estimate of them joins the top's of the others, the total
        // the tolerance is a share of. Then the top texels of largest bound are opened too, until
        // the rest's is half the tolerance.
        let (CoarsePass { mut whole, mut refined, .. }, target) = match top {
            Some((top_sum, top)) => {
                let (g, width) = (top.factor / coarse.factor, top.geometry.width);
                let children = |opened: &[usize]| -> Vec<(usize, std::ops::Range<usize>)> {
                    opened
                        .iter()
                        .flat_map(|&i| {
                            let (x, y) = (i % width, i / width);
                            (g * y..g * (y + 1)).map(move |cy| (cy, g * x..g * (x + 1)))
                        })
                        .collect()
                };
                let CoarsePass { whole: mut top_whole, refined: curved, estimate, refined_estimate } =
                    self.coarse_pass(top_sum, top, axis, None);
                let mut pass = self.coarse_pass(coarse_sum, coarse, axis, Some(&children(&curved)));
                let target = share([0, 1, 2].map(|c| estimate[c] - refined_estimate[c] + pass.estimate[c]));
                let mut opened = take_largest(&mut top_whole, size, |t| t.index, 0.5 * target);
                opened.sort_unstable();
                let more = self.coarse_pass(coarse_sum, coarse, axis, Some(&children(&opened)));
                pass.whole.extend(more.whole);
                pass.refined.extend(more.refined);
                add(&top_whole);
                (pass, target - top_whole.iter().map(size).sum::<f64>())
            }
            None => {
                let pass = self.coarse_pass(coarse_sum, coarse, axis, None);
                let target = share(pass.estimate);
                (pass, target)
            }
        };
        // Refine the largest bounds until the rest's is within the tolerance.
        refined.extend(take_largest(&mut whole, size, |t| t.index, target));
        add(&whole);
        // The refined texels on the fine grid.
        refined.sort_unstable();
        self.fine.within(coarse, &refined, axis, |y, columns, weights| {
            let run = weighted_radiance(coarse.fine_texels(y, columns), weights);
            (0..3).for_each(|c| value[c] += run[c]);
        });
        (value, bound)
    }

    /// The texels of a coarse level within the kernel's support about `axis` (of the `runs` of
    /// columns, row by row, when given): each taken whole (value and bound) unless no coarse
    /// rule integrates the kernel over it, and the coarse estimate Σ_T L̄_T K̂_T the tolerance
    /// is a share of.
    fn coarse_pass(
        &self,
        coarse_sum: &ConeSum,
        coarse: &Coarse,
        axis: DVec3,
        runs: Option<&[(usize, std::ops::Range<usize>)]>,
    ) -> CoarsePass {
        let (width, table, squares) = (coarse.geometry.width, coarse_sum.axis_tables(axis), Squares::of(axis));
        let mut scratch = coarse_sum.scratch();
        let mut pass =
            CoarsePass { whole: Vec::new(), refined: Vec::new(), estimate: [0.0; 3], refined_estimate: [0.0; 3] };
        let cone: Vec<(usize, std::ops::Range<usize>)>;
        let runs = match runs {
            Some(runs) => runs,
            None => {
                cone = (0..coarse.geometry.height)
                    .flat_map(|y| coarse_sum.cone_columns(&table, y).map(|(start, end)| (y, start..end)))
                    .filter(|(_, columns)| !columns.is_empty())
                    .collect();
                &cone
            }
        };
        for (y, columns) in runs {
            let (y, start, end) = (*y, columns.start, columns.end);
            {
                coarse_sum.columns(&table, y, start..end, &mut scratch);
                for x in start..end {
                    let Some(span) = coarse.span(axis, x, y) else { continue };
                    let index = y * width + x;
                    let (mean, k) = (coarse.radiance[index], scratch.texel[x]);
                    (0..3).for_each(|c| pass.estimate[c] += mean[c] as f64 * k);
                    if self.curve.always_refined(span) {
                        (0..3).for_each(|c| pass.refined_estimate[c] += mean[c] as f64 * k);
                        pass.refined.push(index);
                        continue;
                    }
                    let (value, bound) = self.taken_whole(coarse, (index, y), (axis, &squares), span, k);
                    pass.whole.push(Whole { index, value, bound });
                }
            }
        }
        pass
    }
}

/// Σ_t L_t k_t per channel over a run of fine texels and their kernel integrals. Texel i goes
/// to partial sum i mod 4 of its channel, the partial sums added pairwise at the end and the
/// texels left over after them: twelve chains of additions that do not wait on each other
/// (one chain per channel spent most of the refined texels' time waiting), in a fixed order.
#[inline]
fn weighted_radiance(texels: &[[f32; 3]], weights: &[f64]) -> [f64; 3] {
    const LANES: usize = 4;
    let mut lanes = [[0.0f64; LANES]; 3];
    let (texel_blocks, weight_blocks) = (texels.chunks_exact(LANES), weights.chunks_exact(LANES));
    let (texel_tail, weight_tail) = (texel_blocks.remainder(), weight_blocks.remainder());
    for (l, k) in texel_blocks.zip(weight_blocks) {
        for i in 0..LANES {
            (0..3).for_each(|c| lanes[c][i] += l[i][c] as f64 * k[i]);
        }
    }
    let mut sum = lanes.map(|v| (v[0] + v[1]) + (v[2] + v[3]));
    for (l, k) in texel_tail.iter().zip(weight_tail) {
        (0..3).for_each(|c| sum[c] += l[c] as f64 * k);
    }
    sum
}

/// A coarse texel taken whole: its value and, per channel, its bound.
struct Whole {
    index: usize,
    value: [f64; 3],
    bound: [f64; 3],
}

/// What [`LobeIntegral::coarse_pass`] finds.
struct CoarsePass {
    whole: Vec<Whole>,
    /// Coarse texels to sum texel by texel.
    refined: Vec<usize>,
    /// Σ_T L̄_T K̂_T over the texels visited, and over those refined (where K̂_T is not to be
    /// trusted: no rule was chosen for them).
    estimate: [f64; 3],
    refined_estimate: [f64; 3],
}

/// Takes out of `items` the largest (by `size`) until what is left sums to at most `target`,
/// and returns their indices, largest first; the rest keep their order. `index` names each item
/// (no two alike: it also finds the taken ones among the rest); ties go by it, so the same items
/// on any machine. Only the largest few are ordered (a prefix selected, then sorted,
/// doubled until it is enough), as (size, index) pairs rather than the items themselves.
fn take_largest<T>(
    items: &mut Vec<T>,
    size: impl Fn(&T) -> f64,
    index: impl Fn(&T) -> usize,
    target: f64,
) -> Vec<usize> {
    let mut keys: Vec<(f64, usize)> = items.iter().map(|t| (size(t), index(t))).collect();
    let rest: f64 = keys.iter().map(|k| k.0).sum();
    if rest <= target {
        return Vec::new();
    }
    let order = |x: &(f64, usize), y: &(f64, usize)| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1));
    let mut prefix = 64.min(keys.len());
    let taken = loop {
        if prefix < keys.len() {
            keys.select_nth_unstable_by(prefix - 1, order);
        }
        keys[..prefix].sort_unstable_by(order);
        let (mut left, mut taken) = (rest, 0);
        for k in &keys[..prefix] {
            if left <= target {
                break;
            }
            left -= k.0;
            taken += 1;
        }
        if left <= target || prefix == keys.len() {
            break taken;
        }
        prefix = (2 * prefix).min(keys.len());
    };
    let taken: Vec<usize> = keys[..taken].iter().map(|k| k.1).collect();
    let mut gone = taken.clone();
    gone.sort_unstable();
    items.retain(|t| gone.binary_search(&index(t)).is_err());
    taken
}

impl LobeIntegral<'_> {
    /// Coarse texel `index` (in row `y`) taken whole, with K̂_T its coarse rule's kernel
    /// integral: its value and, per channel, the bound on how far that is from its fine texels'
    /// sum. Inside the support, L̄_T K̂_T plus the first- and second-order terms, the bound
    /// C Rᵀ A_T R ([`LobeIntegral`], [`Curve::expansion`]).
    ///
    /// Across the horizon, where f has a kink, L̄_T times the middle of an interval K_T must lie
    /// in. The kernel there is g(s) = f(max(s, 0)), convex on [lo, hi] and zero at lo ≤ 0; with
    /// s̄ and m₂ the mean of s = R·ω and of s² over T (from the texel's geometry alone) and
    /// P = ∫_T max(s, 0) dω = Ω_T (s̄ + mean |s|)/2:
    ///
    /// - g lies above its tangent at 0 and, on average, above g(s̄) (Jensen), and below the
    ///   chord from lo to hi and below f(hi)/hi · max(s, 0) (the chord from 0), so
    ///   K_T ∈ [max(Ω_T g(s̄), f'(0) P), min(Ω_T f(hi) (s̄ − lo)/(hi − lo), f(hi)/hi · P)];
    /// - mean |s| lies in [max(|s̄|, m₂/max|s|), √m₂] (|s| ≥ s²/max|s|; Cauchy–Schwarz).
    ///
    /// |L̄_T (K_T − middle)| is at most |L̄_T| times half the interval. The texels' deviations are
    /// taken against a line ℓ(s) = a + b s: Σ ΔL_t Ω_t being 0, Σ ΔL_t ∫_t ℓ dω = b R·M_T, and
    /// |Σ ΔL_t ∫_t (g − ℓ) dω| ≤ D_T max |g − ℓ|. ℓ is the chord from lo to hi (b = f(hi)/(hi − lo))
    /// lowered by half its largest gap G above g, so max |g − ℓ| = G/2. On [lo, 0] the gap grows
    /// to the chord's value at 0; on [0, hi] g lies above its tangent at 0, so the gap is at most
    /// the chord less that tangent, largest at an end: G ≤ max(−b lo, f(hi) − f'(0) hi). For the
    /// cosine lobe (f linear) the second term is 0, and a block the horizon only grazes has a
    /// small first. The kernel is small there for all but the widest lobes, and for those the
    /// interval is what the block's geometry allows rather than all of [0, f(hi) Ω_T], so most
    /// such texels are taken whole.
    fn taken_whole(
        &self,
        coarse: &Coarse,
        (index, y): (usize, usize),
        (axis, squares): (DVec3, &Squares),
        span: Span,
        k: f64,
    ) -> ([f64; 3], [f64; 3]) {
        let (mean, spread) = (coarse.radiance[index].map(f64::from), coarse.deviation[index]);
        if crosses_horizon(span) {
            let (omega, top) = (coarse.geometry.row_solid_angle(y), self.curve.value(span.hi));
            let (mean_direction, mean_square) = &coarse.mean_directions[index];
            let (s, s2) = (axis.dot(*mean_direction), mean_square.quadratic(squares).max(0.0));
            let [least_p, most_p] = [s.abs().max(s2 / span.hi.max(-span.lo)), s2.sqrt()].map(|m| 0.5 * omega * (s + m));
            let least = (omega * self.curve.value(s.max(0.0))).max(self.curve.first(0.0) * least_p);
            let most = (omega * top * (s - span.lo) / (span.hi - span.lo)).min(top / span.hi * most_p);
            let (kernel, gap) = (0.5 * (most + least), 0.5 * (most - least).abs());
            // ℓ's slope b, the chord's, and G.
            let b = top / (span.hi - span.lo);
            let widest_gap = (-b * span.lo).max(top - self.curve.first(0.0) * span.hi);
            let value = [0, 1, 2].map(|c| mean[c] * kernel + b * axis.dot(coarse.moment[index][c]));
            let bound = [0, 1, 2].map(|c| mean[c].abs() * gap + 0.5 * spread[c] * widest_gap);
            return (value, bound);
        }
        let (first, half_second, remainder) = self.curve.expansion(span);
        let (mut value, mut bound) = ([0.0; 3], [0.0; 3]);
        for c in 0..3 {
            let quadratic = coarse.second[index][c].quadratic(squares);
            value[c] = mean[c] * k + first * axis.dot(coarse.moment[index][c]) + half_second * quadratic;
            bound[c] = remainder * coarse.spread[index][c].quadratic(squares);
        }
        (value, bound)
    }
}

/// A grid box-filtered by its factor (at least [`COARSE_FACTOR`]), with what the two-level sum
/// needs of each coarse texel T: its mean radiance L̄_T, its spread D_T, its first and second
/// moments M_T and Q_T, and the second moment A_T of |L_t − L̄_T| ([`LobeIntegral`]).
struct Coarse<'a> {
    geometry: LatLong,
    factor: usize,
    radiance: Vec<[f32; 3]>,
    deviation: Vec<[f64; 3]>,
    moment: Vec<[DVec3; 3]>,
    second: Vec<[Symmetric; 3]>,
    spread: Vec<[Symmetric; 3]>,
    /// cos ρ and sin ρ of each row's angular radius ρ.
    radius: Vec<(f64, f64)>,
    /// The direction of every texel's centre.
    centres: Vec<DVec3>,
    /// Every texel's mean direction and mean ω ωᵀ, (∫_T ω dω)/Ω_T and (∫_T ω ωᵀ dω)/Ω_T: the
    /// mean of s = R·ω over the texel and of s² ([`LobeIntegral::taken_whole`]).
    mean_directions: Vec<(DVec3, Symmetric)>,
    /// The fine grid's radiance row by row: the input itself when it is the grid (borrowed, not
    /// copied), else its box filtering. Empty on the top level, which refines into the coarse
    /// one.
    fine: Cow<'a, [[f32; 3]]>,
}

/// Where s = R·ω lies over a coarse texel: at its centre and its extremes.
#[derive(Clone, Copy, Debug)]
struct Span {
    centre: f64,
    lo: f64,
    hi: f64,
}

impl Span {
    /// s over a disc of angular radius ρ (given by its cosine and sine) whose centre c has
    /// R·c = `centre` = cos γ: cos(γ ∓ ρ), with no angle computed. The disc holds R when γ < ρ
    /// (then s reaches 1); γ + ρ may pass π, where s is −1 at the least.
    fn about(centre: f64, (cos_radius, sin_radius): (f64, f64)) -> Span {
        let sin_gamma = (1.0 - centre * centre).sqrt();
        let hi = if centre >= cos_radius { 1.0 } else { centre * cos_radius + sin_gamma * sin_radius };
        let lo = (centre * cos_radius - sin_gamma * sin_radius).max(-1.0);
        Span { centre, lo, hi }
    }
}

/// A symmetric 3 × 3 matrix Q by its six entries (xx, yy, zz, xy, xz, yz), for Rᵀ Q R.
#[derive(Clone, Copy)]
struct Symmetric([f64; 6]);

/// The products of R's components that Rᵀ Q R weighs Q's entries by: x², y², z², 2xy, 2xz, 2yz.
struct Squares([f64; 6]);

impl Squares {
    fn of(r: DVec3) -> Squares {
        Squares([r.x * r.x, r.y * r.y, r.z * r.z, 2.0 * r.x * r.y, 2.0 * r.x * r.z, 2.0 * r.y * r.z])
    }
}

impl Symmetric {
    fn of(m: DMat3) -> Symmetric {
        Symmetric([m.x_axis.x, m.y_axis.y, m.z_axis.z, m.x_axis.y, m.x_axis.z, m.y_axis.z])
    }

    /// Rᵀ Q R.
    fn quadratic(&self, squares: &Squares) -> f64 {
        self.0.iter().zip(&squares.0).map(|(q, w)| q * w).sum()
    }
}

/// ∫_t ω dω and ∫_t ω ωᵀ dω over a lat-long texel t = [θ0, θ1] × [φ0, φ1], in closed form as
/// products of a factor of its row and one of its column: with ω = (sin θ cos φ, sin θ sin φ,
/// cos θ) and dω = sin θ dθ dφ,
///
///   ∫ω = (S2 C1, S2 S1, SC Δφ),
///   ∫ωωᵀ: xx = S3 CC, yy = S3 (Δφ − CC), zz = C2S Δφ, xy = S3 SCφ, xz = S2C C1, yz = S2C S1,
///
/// S2 = ∫sin²θ, SC = ∫sin θ cos θ, S3 = ∫sin³θ, S2C = ∫sin²θ cos θ, C2S = ∫cos²θ sin θ dθ over
/// the row; C1 = ∫cos φ, S1 = ∫sin φ, CC = ∫cos²φ, SCφ = ∫sin φ cos φ dφ over the column.
#[derive(Clone, Copy, Default)]
struct RowFactors {
    solid_angle: f64,
    sin2: f64,
    sin_cos: f64,
    sin3: f64,
    sin2_cos: f64,
    cos2_sin: f64,
}

impl RowFactors {
    fn of(grid: LatLong, y: usize) -> RowFactors {
        let (t0, t1) = (PI * y as f64 / grid.height as f64, PI * (y + 1) as f64 / grid.height as f64);
        let ((s0, c0), (s1, c1)) = (t0.sin_cos(), t1.sin_cos());
        RowFactors {
            solid_angle: grid.row_solid_angle(y),
            sin2: 0.5 * (t1 - t0) - 0.25 * ((2.0 * t1).sin() - (2.0 * t0).sin()),
            sin_cos: 0.5 * (s1 * s1 - s0 * s0),
            sin3: (c0 - c1) - (c0 * c0 * c0 - c1 * c1 * c1) / 3.0,
            sin2_cos: (s1 * s1 * s1 - s0 * s0 * s0) / 3.0,
            cos2_sin: (c0 * c0 * c0 - c1 * c1 * c1) / 3.0,
        }
    }
}

/// A column's factors ([`RowFactors`]): C1, S1, CC and SCφ (Δφ is every column's).
fn column_factors(grid: LatLong, x: usize) -> [f64; 4] {
    let (p0, p1) = (TAU * x as f64 / grid.width as f64, TAU * (x + 1) as f64 / grid.width as f64);
    let ((s0, c0), (s1, c1)) = (p0.sin_cos(), p1.sin_cos());
    [s1 - s0, c0 - c1, 0.5 * (p1 - p0) + 0.5 * (s1 * c1 - s0 * c0), 0.5 * (s1 * s1 - s0 * s0)]
}

/// Σ_t w_t ∫_t ω dω and Σ_t w_t ∫_t ω ωᵀ dω over texels t of one row with weights w_t, from the
/// row's factors and Σ w_t, Σ w_t C1, Σ w_t S1, Σ w_t CC, Σ w_t SCφ ([`RowFactors`]).
fn row_moments(row: &RowFactors, width: f64, sums: &[f64; 5]) -> (DVec3, DMat3) {
    let [w, c1, s1, cc, sc] = *sums;
    let first = DVec3::new(row.sin2 * c1, row.sin2 * s1, row.sin_cos * width * w);
    let (xx, yy, zz) = (row.sin3 * cc, row.sin3 * (width * w - cc), row.cos2_sin * width * w);
    let (xy, xz, yz) = (row.sin3 * sc, row.sin2_cos * c1, row.sin2_cos * s1);
    let second = DMat3::from_cols(DVec3::new(xx, xy, xz), DVec3::new(xy, yy, yz), DVec3::new(xz, yz, zz));
    (first, second)
}

/// Texel (x, y)'s solid angle Ω_t and its geometric moments ∫_t ω dω and ∫_t ω ωᵀ dω
/// ([`row_moments`] with a weight of one).
fn texel_moments(grid: LatLong, x: usize, y: usize) -> (f64, DVec3, DMat3) {
    let (row, [c1, s1, cc, sc]) = (RowFactors::of(grid, y), column_factors(grid, x));
    let (first, second) = row_moments(&row, TAU / grid.width as f64, &[1.0, c1, s1, cc, sc]);
    (row.solid_angle, first, second)
}

/// What a coarse texel T keeps of its fine texels t (per channel, ΔL_t = L_t − L̄_T and e = ω −
/// c_T, c_T the centre): D_T = Σ Ω_t |ΔL_t|, M_T = Σ ΔL_t ∫_t e dω (= Σ ΔL_t ∫_t ω dω, as
/// Σ ΔL_t Ω_t = 0), Q_T = Σ ΔL_t ∫_t e eᵀ dω and A_T = Σ |ΔL_t| ∫_t e eᵀ dω. The second moments
/// about the centre are the moments about the origin shifted: Σ w ∫ e eᵀ = Σ w ∫ ω ωᵀ − m cᵀ −
/// c mᵀ plus (Σ w Ω) c cᵀ, with m = Σ w ∫ ω. (The shift cancels all but a share ~ (block size)² of the
/// terms: f64 keeps ~1e-9 of A_T, far below any bound here.)
struct BlockMoments {
    mean: [f64; 3],
    deviation: [f64; 3],
    moment: [DVec3; 3],
    second: [DMat3; 3],
    spread: [DMat3; 3],
    /// Σ |ΔL_t| ∫_t e dω, for grouping blocks ([`BlockMoments::group`]).
    spread_first: [DVec3; 3],
}

impl BlockMoments {
    /// A block of mean radiance `mean` with its sums still to add.
    fn about(mean: [f64; 3]) -> BlockMoments {
        BlockMoments {
            mean,
            deviation: [0.0; 3],
            moment: [DVec3::ZERO; 3],
            second: [DMat3::ZERO; 3],
            spread: [DMat3::ZERO; 3],
            spread_first: [DVec3::ZERO; 3],
        }
    }

    /// The block of `f` × `f` texels at (x, y) of the grid they form, from the fine grid's
    /// `radiance` (row-major).
    fn of(fine: LatLong, radiance: &[[f32; 3]], rows: &[RowFactors], columns: &[[f64; 4]], block: [usize; 3]) -> Self {
        let [x, y, f] = block;
        let texels = |fy: usize| &radiance[fy * fine.width + f * x..fy * fine.width + f * (x + 1)];
        let centre = LatLong::new(fine.width / f, fine.height / f).texel_direction(x, y);
        let (mut energy, mut area) = ([0.0; 3], 0.0);
        for fy in f * y..f * (y + 1) {
            for l in texels(fy) {
                area += rows[fy].solid_angle;
                (0..3).for_each(|c| energy[c] += rows[fy].solid_angle * l[c] as f64);
            }
        }
        let mean = energy.map(|e| e / area);
        let width = TAU / fine.width as f64;
        let mut m = BlockMoments::about(mean);
        for fy in f * y..f * (y + 1) {
            // A channel at a time, so that its ten sums stay in registers.
            for c in 0..3 {
                let (mut signed, mut absolute) = ([0.0; 5], [0.0; 5]);
                for (l, &[c1, s1, cc, sc]) in texels(fy).iter().zip(&columns[f * x..f * (x + 1)]) {
                    let d = l[c] as f64 - mean[c];
                    for (sums, w) in [(&mut signed, d), (&mut absolute, d.abs())] {
                        sums[0] += w;
                        sums[1] += w * c1;
                        sums[2] += w * s1;
                        sums[3] += w * cc;
                        sums[4] += w * sc;
                    }
                }
                let (first, second) = row_moments(&rows[fy], width, &signed);
                m.moment[c] += first;
                m.second[c] += second;
                let (first, second) = row_moments(&rows[fy], width, &absolute);
                m.spread_first[c] += first;
                m.spread[c] += second;
                m.deviation[c] += rows[fy].solid_angle * absolute[0];
            }
        }
        for c in 0..3 {
            let about_origin = outer(centre, m.moment[c]);
            m.second[c] -= about_origin + about_origin.transpose();
            let about_origin = outer(centre, m.spread_first[c]);
            m.spread[c] -= about_origin + about_origin.transpose();
            m.spread[c] += outer(centre, centre) * m.deviation[c];
            m.spread_first[c] -= centre * m.deviation[c];
        }
        m
    }

    /// The g × g blocks of `level` (row-major, texels of `grid`) at (x, y) of the grid they
    /// group into, taken as one block T about its centre c_T. A block b's texels t deviate from
    /// T's mean by w_t = δ_t + Δ_b (δ_t from b's mean, Δ_b = L̄_b − L̄_T), and e_T = e_b + d_b
    /// (d_b = c_b − c_T), so with b's own integrals W_b = ∫_b ω dω and G_b = ∫_b e_T e_Tᵀ dω:
    ///
    ///   M_T = Σ_b M_b + Δ_b W_b,   Q_T = Σ_b Q_b + M_b d_bᵀ + d_b M_bᵀ + Δ_b G_b,
    ///
    /// exactly (Σ_t δ_t Ω_t = 0 within b). The absolute deviations only have a bound,
    /// |w_t| ≤ |δ_t| + |Δ_b|: D_T ≤ Σ_b D_b + |Δ_b| Ω_b and, with F_b = Σ |δ_t| ∫ e_b,
    /// A_T ≤ Σ_b A_b + F_b d_bᵀ + d_b F_bᵀ + D_b d_b d_bᵀ + |Δ_b| G_b in the order of positive
    /// semidefinite matrices, which is what the remainder bound C Rᵀ A_T R needs.
    fn group(grid: LatLong, level: &[BlockMoments], [x, y, g]: [usize; 3]) -> BlockMoments {
        let centre = LatLong::new(grid.width / g, grid.height / g).texel_direction(x, y);
        let blocks: Vec<(&BlockMoments, f64, DVec3, DMat3, DVec3)> = (g * y..g * (y + 1))
            .flat_map(|by| (g * x..g * (x + 1)).map(move |bx| (bx, by)))
            .map(|(bx, by)| {
                let (omega, first, second) = texel_moments(grid, bx, by);
                // ∫_b e_T e_Tᵀ from the moments about the origin.
                let about = outer(centre, first);
                let g_b = second - about - about.transpose() + outer(centre, centre) * omega;
                (&level[by * grid.width + bx], omega, first, g_b, grid.texel_direction(bx, by) - centre)
            })
            .collect();
        let area: f64 = blocks.iter().map(|b| b.1).sum();
        let mean = [0, 1, 2].map(|c| blocks.iter().map(|(b, omega, ..)| b.mean[c] * omega).sum::<f64>() / area);
        let mut m = BlockMoments::about(mean);
        for &(b, omega, first, g_b, d) in &blocks {
            for c in 0..3 {
                let delta = b.mean[c] - mean[c];
                m.moment[c] += b.moment[c] + first * delta;
                m.second[c] += b.second[c] + outer(b.moment[c], d) + outer(d, b.moment[c]) + g_b * delta;
                m.deviation[c] += b.deviation[c] + delta.abs() * omega;
                m.spread[c] += b.spread[c]
                    + outer(b.spread_first[c], d)
                    + outer(d, b.spread_first[c])
                    + outer(d, d) * b.deviation[c]
                    + g_b * delta.abs();
                m.spread_first[c] += b.spread_first[c] + d * b.deviation[c] + (first - centre * omega) * delta.abs();
            }
        }
        m
    }
}

/// a bᵀ.
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

impl<'a> Coarse<'a> {
    /// Fine texels per coarse texel edge for a fine grid, when it is wide enough for a coarse
    /// level and divides by the factor.
    fn factor(fine: LatLong) -> Option<usize> {
        let f = COARSE_FACTOR.max(fine.width / COARSE_WIDTH);
        (fine.width >= TWO_LEVEL_MIN_WIDTH && fine.width % f == 0 && fine.height % f == 0).then_some(f)
    }

    /// The coarse level of `f` × `f` texels ([`Coarse::factor`]) of a fine grid's `radiance`
    /// (row-major), which it keeps, and the top level grouping its texels [`TOP_GROUP`] ×
    /// [`TOP_GROUP`] when it is wide enough ([`BlockMoments::group`]).
    fn levels(fine: LatLong, f: usize, radiance: Cow<'a, [[f32; 3]]>) -> (Arc<Coarse<'a>>, Option<Arc<Coarse<'a>>>) {
        let geometry = LatLong::new(fine.width / f, fine.height / f);
        let rows: Vec<RowFactors> = (0..fine.height).map(|y| RowFactors::of(fine, y)).collect();
        let columns: Vec<[f64; 4]> = (0..fine.width).map(|x| column_factors(fine, x)).collect();
        let blocks: Vec<BlockMoments> = (0..geometry.height * geometry.width)
            .into_par_iter()
            .map(|i| BlockMoments::of(fine, &radiance, &rows, &columns, [i % geometry.width, i / geometry.width, f]))
            .collect();
        let g = TOP_GROUP;
        let top = (geometry.width >= TOP_MIN_WIDTH && geometry.width % g == 0 && geometry.height % g == 0).then(|| {
            let grid = LatLong::new(geometry.width / g, geometry.height / g);
            let grouped: Vec<BlockMoments> = (0..grid.height * grid.width)
                .into_par_iter()
                .map(|i| BlockMoments::group(geometry, &blocks, [i % grid.width, i / grid.width, g]))
                .collect();
            Arc::new(Coarse::of_blocks(grid, f * g, &grouped, Cow::Borrowed(&[])))
        });
        (Arc::new(Coarse::of_blocks(geometry, f, &blocks, radiance)), top)
    }

    /// A level of `factor` fine texels per edge from its blocks' moments.
    fn of_blocks(geometry: LatLong, factor: usize, blocks: &[BlockMoments], fine: Cow<'a, [[f32; 3]]>) -> Coarse<'a> {
        Coarse {
            geometry,
            factor,
            radiance: blocks.iter().map(|b| b.mean.map(|v| v as f32)).collect(),
            deviation: blocks.iter().map(|b| b.deviation).collect(),
            moment: blocks.iter().map(|b| b.moment).collect(),
            second: blocks.iter().map(|b| b.second.map(Symmetric::of)).collect(),
            spread: blocks.iter().map(|b| b.spread.map(Symmetric::of)).collect(),
            radius: (0..geometry.height).map(|y| angular_radius(geometry, y).sin_cos()).map(|(s, c)| (c, s)).collect(),
            centres: (0..geometry.height)
                .flat_map(|y| (0..geometry.width).map(move |x| geometry.texel_direction(x, y)))
                .collect(),
            mean_directions: (0..geometry.height)
                .flat_map(|y| (0..geometry.width).map(move |x| texel_moments(geometry, x, y)))
                .map(|(omega, first, second)| (first / omega, Symmetric::of(second / omega)))
                .collect(),
            fine,
        }
    }

    /// The fine texels `columns` of fine row `y`.
    fn fine_texels(&self, y: usize, columns: std::ops::Range<usize>) -> &[[f32; 3]] {
        let row = y * self.geometry.width * self.factor;
        &self.fine[row + columns.start..row + columns.end]
    }

    /// s = R·ω over texel (x, y) ([`Span::about`] its centre, with the texel's angular radius);
    /// `None` when the whole texel lies where the kernel is zero.
    fn span(&self, axis: DVec3, x: usize, y: usize) -> Option<Span> {
        let centre = axis.dot(self.centres[y * self.geometry.width + x]).clamp(-1.0, 1.0);
        Some(Span::about(centre, self.radius[y])).filter(|span| span.hi > 0.0)
    }
}

/// The split-sum kernel as a function of s = cos γ on (0, 1] (zero below): [`HalfChord`]'s
/// kernel (the GGX D(h) with θ_h = γ/2, times cos γ, normalized) with a = (α² + 1)/2,
/// b = (α² − 1)/2,
///
///   f = scale · s/(a + b s)²,               f' = scale (a − b s)/(a + b s)³,
///   f'' = −2b scale (2a − b s)/(a + b s)⁴,  f''' = 6b² scale (3a − b s)/(a + b s)⁵.
///
/// As b ≤ 0 < a and a + b s ≥ a + b = α² > 0 on [−1, 1], f', f'' and f''' are ≥ 0 there and
/// each grows with s (its numerator grows, its denominator falls): the largest value of each over
/// a texel is at the texel's largest s. At α = 1 (b = 0) f is linear.
#[derive(Clone, Copy, Debug)]
struct Curve {
    scale: f64,
    a: f64,
    b: f64,
}

impl Curve {
    fn of(lobe: &SplitSumLobe) -> Curve {
        let (a2, scale) = kernel_constants(lobe);
        Curve { scale, a: 0.5 * (a2 + 1.0), b: 0.5 * (a2 - 1.0) }
    }

    /// f, f', f'' and f''' at s, with one division.
    fn derivatives(&self, s: f64) -> [f64; 4] {
        let (a, b, scale) = (self.a, self.b, self.scale);
        let i = 1.0 / (a + b * s);
        let (i2, i3) = (i * i, i * i * i);
        [
            scale * s * i2,
            scale * (a - b * s) * i3,
            -2.0 * b * scale * (2.0 * a - b * s) * i2 * i2,
            6.0 * b * b * scale * (3.0 * a - b * s) * i2 * i3,
        ]
    }

    fn value(&self, s: f64) -> f64 {
        self.derivatives(s)[0]
    }

    fn first(&self, s: f64) -> f64 {
        self.derivatives(s)[1]
    }

    fn second(&self, s: f64) -> f64 {
        self.derivatives(s)[2]
    }

    /// ½ max f'' max (s − s_T)² over a texel: the size of the kernel's second-order term, which
    /// decides whether a coarse texel rule can integrate it.
    fn second_order(&self, span: Span) -> f64 {
        let reach = (span.hi - span.centre).max(span.centre - span.lo);
        0.5 * self.second(span.hi) * reach * reach
    }

    /// f'(s_T), f''(s_T)/2 and C with |f(s) − f(s_T) − f'(s_T)(s − s_T) − ½ f''(s_T)(s − s_T)²|
    /// ≤ C (s − s_T)² over a texel inside the support ([`LobeIntegral`]). The remainder is
    /// ½ (f''(ξ) − f''(s_T)) (s − s_T)² for some ξ between s_T and s (Lagrange), and also
    /// f'''(η)/6 (s − s_T)³ for some η there. f'' and f''' grow with s, so above the centre it is
    /// at most the smaller of ½ (f''(hi) − f''(s_T)) and f'''(hi)/6 · (hi − s_T) times
    /// (s − s_T)², below it the smaller of ½ (f''(s_T) − f''(lo)) and f'''(s_T)/6 · (s_T − lo);
    /// C is the larger side's. The f'' form is the smaller where f''' changes fast across the
    /// span (near the peak).
    fn expansion(&self, span: Span) -> (f64, f64, f64) {
        let [centre, hi, lo] = [span.centre, span.hi, span.lo].map(|s| self.derivatives(s));
        let above = (0.5 * (hi[2] - centre[2])).min(hi[3] / 6.0 * (span.hi - span.centre));
        let below = (0.5 * (centre[2] - lo[2])).min(centre[3] / 6.0 * (span.centre - span.lo));
        (centre[1], 0.5 * centre[2], above.max(below))
    }

    /// Whether no coarse texel rule integrates the kernel over a coarse texel: the horizon
    /// crosses it (f has a kink at s = 0: [`crosses_horizon`]), or the kernel curves too much over
    /// it (near the peak of a sharp lobe).
    fn too_curved(&self, span: Span) -> bool {
        crosses_horizon(span) || self.second_order(span) > COARSE_CURVATURE
    }

    /// Whether a coarse texel is summed texel by texel whatever the radiance: too curved, and
    /// not one the horizon crosses (those are taken whole by their interval,
    /// [`LobeIntegral::taken_whole`], and refined only for their bound, like any other).
    fn always_refined(&self, span: Span) -> bool {
        !crosses_horizon(span) && self.too_curved(span)
    }
}

/// Whether the horizon (s = 0, where the kernel has a kink) crosses a coarse texel.
fn crosses_horizon(span: Span) -> bool {
    span.lo <= 0.0
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

/// A cone sum on one lat-long grid: B(R) = Σ_t L_t ∫_t k(R·ω) dω, the texel integrals by an
/// n × n Gauss–Legendre product rule in (z, φ).
///
/// Summed row by row: a node of sub-row (z_i, sin θ_i) and sub-column φ_j has
/// R·ω = z_R z_i + sin θ_R sin θ_i cos(φ_j − φ_R), so one table of cos(φ_j − φ_R) per direction
/// serves every row, and the kernel, a rational function of R·ω, is one division per node.
struct ConeSum {
    grid: LatLong,
    /// n sub-rows per row: (sin(θ/2), cos(θ/2), sin θ, weight), the half angle's sine and
    /// cosine for sin((θ − θ_R)/2) as for φ, without a sine per row and direction.
    sub_rows: Vec<[f64; 4]>,
    /// (sin θ, cos θ) of every row's centre, for the cone's columns.
    rows: Vec<(f64, f64)>,
    /// sin(φ/2) and cos(φ/2) of the n sub-columns of every column, column-major in blocks of n.
    sin_half_phi: Vec<f64>,
    cos_half_phi: Vec<f64>,
    /// The weight in φ of every sub-column, as `sin_half_phi`.
    node_weights: Vec<f32>,
    /// Sub-samples per axis.
    n: usize,
    /// The cone's half-angle and its cosine.
    cone: f64,
    cos_cone: f64,
    kernel: HalfChord,
    arch: pulp::Arch,
}

/// The direction R of a cone sum: z_R, sin θ_R, θ_R, sin(θ_R/2), cos(θ_R/2), φ_R, and
/// sin²((φ − φ_R)/2) at every node column of the grid.
struct AxisTables {
    z: f64,
    sin_theta: f64,
    theta: f64,
    half_theta: (f64, f64),
    phi: f64,
    sin2_half_dphi: Vec<f32>,
}

/// Scratch for [`ConeSum::columns`]: n kernel values per texel and the texel integrals of a row.
struct RowScratch {
    kernel: Vec<f32>,
    texel: Vec<f64>,
}

impl ConeSum {
    fn new(grid: LatLong, rule: &TexelRule, lobe: &SplitSumLobe) -> Self {
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
            .map(|r| {
                let (s, c) = (0.5 * r.z.clamp(-1.0, 1.0).acos()).sin_cos();
                [s, c, r.sin_theta, r.weight]
            })
            .collect();
        // The kernel vanishes beyond π/2; texels whose centres lie within two rows of it may
        // still reach inside.
        let cone = (FRAC_PI_2 + 2.0 * PI / grid.height as f64).min(PI);
        ConeSum {
            grid,
            sub_rows,
            sin_half_phi,
            cos_half_phi,
            node_weights: (0..grid.width).flat_map(|_| columns.iter().map(|c| c.1 as f32)).collect(),
            n: columns.len(),
            rows: (0..grid.height).map(|y| grid.row_theta(y).sin_cos()).collect(),
            cone,
            cos_cone: cone.cos(),
            kernel: HalfChord::of(lobe),
            arch: pulp::Arch::new(),
        }
    }

    fn scratch(&self) -> RowScratch {
        RowScratch { kernel: vec![0.0; self.grid.width * self.n], texel: vec![0.0; self.grid.width] }
    }

    /// B(R) at the direction `axis` of prtkit's frame over the grid's `radiance`, row by row.
    fn at(&self, radiance: &[[f32; 3]], axis: DVec3) -> [f64; 3] {
        let w = self.grid.width;
        let mut acc = [0.0; 3];
        self.texel_integrals(axis, |y, x, weight| {
            let l = radiance[y * w + x];
            for k in 0..3 {
                acc[k] += l[k] as f64 * weight;
            }
        });
        // The texels kept cover the kernel's whole support and the kernel is normalized (∫ k dω =
        // 1), so the sum needs no division: its weight is 1 up to the rule's tolerance.
        acc
    }

    /// Calls `visit(y, x, ∫_t k dω)` for every texel t = (x, y) whose centre is within the cone
    /// of `axis`, and some beyond it (where the kernel is zero), row by row.
    fn texel_integrals(&self, axis: DVec3, mut visit: impl FnMut(usize, usize, f64)) {
        let table = self.axis_tables(axis);
        let mut scratch = self.scratch();
        for y in 0..self.grid.height {
            for (start, end) in self.cone_columns(&table, y) {
                self.columns(&table, y, start..end, &mut scratch);
                (start..end).for_each(|x| visit(y, x, scratch.texel[x]));
            }
        }
    }

    /// What every row of a sum about `axis` shares.
    fn axis_tables(&self, axis: DVec3) -> AxisTables {
        let axis = axis.normalize();
        let phi_r = sphere::phi(axis);
        // u = 1 − R·ω = 2 sin²((θ − θ_R)/2) + 2 sin θ_R sin θ sin²((φ − φ_R)/2): a sum of
        // non-negative terms, with sin((φ − φ_R)/2) from the half-angle tables.
        let (s_half_r, c_half_r) = (0.5 * phi_r).sin_cos();
        let sin2_half_dphi = self
            .sin_half_phi
            .iter()
            .zip(&self.cos_half_phi)
            .map(|(s, c)| {
                let d = s * c_half_r - c * s_half_r;
                (d * d) as f32
            })
            .collect();
        let theta = sphere::theta(axis);
        AxisTables {
            z: axis.z,
            sin_theta: axis.x.hypot(axis.y),
            theta,
            half_theta: (0.5 * theta).sin_cos(),
            phi: phi_r,
            sin2_half_dphi,
        }
    }

    /// The columns of row `y` whose texel centres lie within the cone about the table's axis,
    /// one more each side, as at most two ranges (the cone may wrap around φ = 0; unused ranges
    /// are empty): the kernel is zero on every node of a texel whose centre is beyond π/2 + 2h.
    fn cone_columns(&self, table: &AxisTables, y: usize) -> [(usize, usize); 2] {
        let w = self.grid.width;
        let theta = self.grid.row_theta(y);
        if (theta - table.theta).abs() > self.cone {
            return [(0, 0); 2];
        }
        // Closed form of cos θ cos θ_R + sin θ sin θ_R cos Δφ ≥ cos θ*.
        let h = TAU / w as f64;
        let (st, ct) = self.rows[y];
        let denom = st * table.sin_theta;
        let c = if denom > 1e-300 { (self.cos_cone - ct * table.z) / denom } else { -2.0 };
        let half = if c <= -1.0 { PI } else { c.min(1.0).acos() };
        let lo = ((table.phi - half) / h - 0.5).ceil() as i64 - 1;
        let hi = ((table.phi + half) / h - 0.5).floor() as i64 + 1;
        if half >= PI || hi - lo + 1 >= w as i64 {
            return [(0, w), (0, 0)];
        }
        let (lo, hi) = (lo.rem_euclid(w as i64) as usize, hi.rem_euclid(w as i64) as usize);
        if lo <= hi {
            [(lo, hi + 1), (0, 0)]
        } else {
            [(lo, w), (0, hi + 1)]
        }
    }

    /// Calls `visit(y, columns, ∫_t k dω of those columns)` for every run of this grid's texels
    /// inside the texels `blocks` (ascending indices) of its `coarse` level: runs of neighbours
    /// along each coarse row, one call per row of this grid.
    fn within(
        &self,
        coarse: &Coarse,
        blocks: &[usize],
        axis: DVec3,
        mut visit: impl FnMut(usize, std::ops::Range<usize>, &[f64]),
    ) {
        let (f, width) = (coarse.factor, coarse.geometry.width);
        let table = self.axis_tables(axis);
        let mut scratch = self.scratch();
        let mut i = 0;
        while i < blocks.len() {
            let mut j = i + 1;
            while j < blocks.len() && blocks[j] == blocks[j - 1] + 1 && blocks[j] % width != 0 {
                j += 1;
            }
            let (y, x0, x1) = (blocks[i] / width, blocks[i] % width, blocks[j - 1] % width + 1);
            for fy in f * y..f * (y + 1) {
                self.columns(&table, fy, f * x0..f * x1, &mut scratch);
                visit(fy, f * x0..f * x1, &scratch.texel[f * x0..f * x1]);
            }
            i = j;
        }
    }

    /// ∫_t k dω of the texels `columns` of row `y` about the table's axis, into
    /// `scratch.texel[columns]`.
    ///
    /// The node loops are compiled for baseline x86-64 (SSE2) and, through
    /// `pulp::Arch::dispatch`, once more with AVX2 (8 f32 lanes), chosen at run time as in
    /// `normals::onv`: autovectorized safe Rust either way, the same IEEE operations in the same
    /// order, so the same sums.
    fn columns(&self, table: &AxisTables, y: usize, columns: std::ops::Range<usize>, scratch: &mut RowScratch) {
        struct Op<'a>(&'a ConeSum, &'a AxisTables, usize, std::ops::Range<usize>, &'a mut RowScratch);
        impl pulp::WithSimd for Op<'_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _: S) {
                let Op(sum, table, y, columns, scratch) = self;
                sum.node_sums(table, y, columns, scratch);
            }
        }
        self.arch.dispatch(Op(self, table, y, columns, scratch));
    }

    /// [`ConeSum::columns`]' loops: the kernel at every node of a sub-row, then each texel's n
    /// nodes added to its integral.
    #[inline(always)]
    fn node_sums(&self, table: &AxisTables, y: usize, columns: std::ops::Range<usize>, scratch: &mut RowScratch) {
        let n = self.n;
        let (start, end) = (columns.start, columns.end);
        let texel = &mut scratch.texel[start..end];
        texel.fill(0.0);
        let (nodes, out) = (&table.sin2_half_dphi[start * n..end * n], &mut scratch.kernel[start * n..end * n]);
        let weights = &self.node_weights[start * n..end * n];
        let (s_half_r, c_half_r) = table.half_theta;
        for &[s_half, c_half, sin_theta, weight] in &self.sub_rows[y * n..(y + 1) * n] {
            let d = s_half * c_half_r - c_half * s_half_r;
            let (a, b) = ((2.0 * d * d) as f32, (2.0 * table.sin_theta * sin_theta) as f32);
            for ((k, s), wj) in out.iter_mut().zip(nodes).zip(weights) {
                *k = wj * self.kernel.at(a + b * s);
            }
            // With n a constant for the usual rules, so that the texels' sums vectorize.
            match n {
                1 => add_nodes(texel, out, 1, weight),
                2 => add_nodes(texel, out, 2, weight),
                3 => add_nodes(texel, out, 3, weight),
                _ => add_nodes(texel, out, n, weight),
            }
        }
    }
}

/// Adds `weight` times the sum of each texel's `n` node values to its integral.
#[inline(always)]
fn add_nodes(texel: &mut [f64], nodes: &[f32], n: usize, weight: f64) {
    for (t, node) in texel.iter_mut().zip(nodes.chunks_exact(n)) {
        *t += weight * node.iter().map(|k| *k as f64).sum::<f64>();
    }
}

/// Why the reference cannot be set up.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// The environment is not lat-long.
    #[error("the angular reference integrates lat-long environments; this one is {0} (resample it to lat-long first)")]
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
                let (f, c, slope) = (fine.lobe(&lobe), coarse.lobe(&lobe), Slope::of(&lobe));
                let mut widest: f64 = 0.0;
                for k in 0..40 {
                    let z = 1.0 - 2.0 * (k as f64 + 0.5) / 40.0;
                    let phi = k as f64 * 2.399_963;
                    let axis = DVec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
                    let (b_fine, b_coarse, bound) =
                        (f.at(axis), c.at(axis), coarse.grid.filtering_bound(axis, &lobe, &slope));
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

    /// An input up to 4096 × 2048 is summed as it is, with no filtering to bound; a larger one is
    /// box-filtered to 2048 × 1024 or less, not to the largest grid summed as it is.
    #[test]
    fn inputs_up_to_4096_by_2048_are_summed_as_they_are() {
        let flat = |w, h| EnvMap::latlong(RgbImage::from_fn(w, h, |_, _| [1.0, 1.0, 1.0])).unwrap();
        let map = flat(4096, 2048);
        let as_is = Reference::new(&map).unwrap();
        assert!(!as_is.is_filtered(), "{}", as_is.describe());
        assert!(as_is.describe().starts_with("the input, latlong 4096x2048"), "{}", as_is.describe());
        let map = flat(8192, 2048);
        let filtered = Reference::new(&map).unwrap();
        assert!(filtered.describe().contains("8192x2048 box-filtered to 2048x512"), "{}", filtered.describe());
    }

    /// D_T is each block's Σ Ω_t |L_t − L̄_T| (summed here texel by texel), and the filtered grid
    /// keeps each block's energy; a flat map has no deviation to bound.
    #[test]
    fn the_deviations_are_each_blocks_spread_about_its_mean() {
        let map = detailed(64, 32);
        let (fine, coarse) = (LatLong::new(64, 32), LatLong::new(16, 8));
        let filtered = box_latlong(map.image(), 16, 8);
        let found = Filtering::of(map.image(), &filtered, 4);
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
                let got_d = found.deviation[y * 16 + x];
                assert!(found.centre(x, y).distance(coarse.texel_direction(x, y)) < 1e-12);
                for c in 0..3 {
                    let kept = mean[c] as f64 * coarse.row_solid_angle(y);
                    assert!((kept - energy[c]).abs() <= 1e-6 * energy[c], "({x}, {y}): {kept} vs {}", energy[c]);
                    // Kept as the least f32 not below the sum: above it by less than one f32 step.
                    let got = got_d[c] as f64;
                    assert!(
                        got >= d[c] * (1.0 - 1e-12) && got <= d[c] * (1.0 + f32::EPSILON as f64) + 1e-40,
                        "({x}, {y}): D {got} vs {}",
                        d[c]
                    );
                }
            }
        }
        let flat = RgbImage::from_fn(64, 32, |_, _| [2.0, 1.0, 0.5]);
        let kept = Filtering::of(&flat, &box_latlong(&flat, 16, 8), 4);
        assert!(kept.deviation.iter().all(|d| *d == [0.0; 3]), "a flat map deviates nowhere");
        let lobe = SplitSumLobe::new(0.5).unwrap();
        let bound = Grid::new(&flat, 4).filtering_bound(DVec3::Z, &lobe, &Slope::of(&lobe));
        assert!(bound.iter().all(|b| *b < 1e-6), "{bound:?}");
    }

    /// The bound taken through the block levels is the texel-by-texel one (every texel's
    /// D_T (max k − min k)/2) loosened by at most [`BOUND_SLACK`] of it, never tightened: at
    /// directions all over the sphere, for narrow and wide lobes; and blocks are taken at once
    /// (the bound is not merely the texels' sum).
    #[test]
    fn the_bound_through_the_blocks_is_within_its_slack_of_the_texels() {
        // A grid every block size divides, and one where the last block of each row and column
        // is cut at the edge (300 × 150: 5 × 3, 19 × 10 and 75 × 38 blocks).
        for ((w, h), counts) in [((512, 256), [8, 128, 2048]), ((600, 300), [15, 190, 2850])] {
            let map = detailed(w, h);
            let grid = Grid::new(map.image(), 2);
            let filtering = grid.filtering.as_ref().expect("a box-filtered grid bounds its filtering");
            assert_eq!(filtering.levels.iter().map(|l| l.blocks.len()).collect::<Vec<_>>(), counts);
            let mut loosest: f64 = 0.0;
            for r in [0.1, 0.3, 1.0] {
                let (lobe, slope) = (SplitSumLobe::new(r).unwrap(), Slope::of(&SplitSumLobe::new(r).unwrap()));
                for k in 0..24 {
                    let z = 1.0 - 2.0 * (k as f64 + 0.5) / 24.0;
                    let phi = k as f64 * 2.399_963;
                    let axis = DVec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
                    let mut texels = 0.0;
                    for y in 0..grid.geometry.height {
                        for x in 0..grid.geometry.width {
                            let cos_gamma = axis.dot(filtering.centre(x, y)).clamp(-1.0, 1.0);
                            let span = Span::about(cos_gamma, filtering.radius[y]);
                            let d: f64 =
                                filtering.deviation[y * grid.geometry.width + x].iter().map(|&v| v as f64).sum();
                            texels += d * 0.5 * (lobe.kernel(span.hi) - lobe.kernel(span.lo));
                        }
                    }
                    let bound: f64 = grid.filtering_bound(axis, &lobe, &slope).iter().sum();
                    let at = format!("{w}x{h} r {r} axis {axis}");
                    assert!(bound >= texels * (1.0 - 1e-12), "{at}: {bound:e} below the texels' {texels:e}");
                    assert!(
                        bound <= texels * (1.0 + BOUND_SLACK) + 1e-15,
                        "{at}: {bound:e} looser than the slack allows over {texels:e}"
                    );
                    loosest = loosest.max(bound / texels - 1.0);
                }
            }
            assert!(loosest > 1e-3, "{w}x{h}: no block was taken at once ({loosest:e})");
        }
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
                let integral = ConeSum::new(grid.geometry, &rule, &lobe);
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
                    let got = integral.at(&map.image().pixels, axis);
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

    /// The two-level sum is within its bound of the texel-by-texel sum over the same grid, for
    /// sharp and wide lobes all over the sphere (texels across the horizon taken whole by their
    /// bound included), and the bound keeps to its tolerance.
    #[test]
    fn the_two_level_sum_is_within_its_bound_of_the_texel_sum() {
        let map = detailed(512, 256);
        let grid = Grid::new(map.image(), 1);
        assert!(matches!(grid.texels, Texels::Levels(_, Some(_))), "a 512-wide grid is summed on three levels");
        let exact = TexelRule::new(6).unwrap();
        for r in [0.1, 0.25, 0.5, 1.0] {
            let lobe = SplitSumLobe::new(r).unwrap();
            let (two_level, plain) = (grid.lobe(&lobe), ConeSum::new(grid.geometry, &exact, &lobe));
            for k in 0..24 {
                let z = 1.0 - 2.0 * (k as f64 + 0.5) / 24.0;
                let phi = k as f64 * 2.399_963;
                let axis = DVec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
                let ((got, bound), want) = (two_level.at_with_bound(axis), plain.at(&map.image().pixels, axis));
                for c in 0..3 {
                    // Both texel rules misplace at most 1e-5 of the kernel's weight.
                    assert!(
                        (got[c] - want[c]).abs() <= bound[c] + 3e-5 * want[c],
                        "r {r} axis {axis}: {} vs {} (bound {:e})",
                        got[c],
                        want[c],
                        bound[c]
                    );
                }
                let (b, w): (f64, f64) = (bound.iter().sum(), want.iter().sum());
                assert!(b <= 2.0 * TWO_LEVEL_TOLERANCE * w, "r {r} axis {axis}: bound {b:e} of {w:e}");
            }
        }
    }

    /// M_T = Σ_t (L_t − L̄_T) ∫_t ω dω with the closed-form texel moments equals the same sum
    /// with ∫_t ω dω integrated numerically, for a map that is one in a single fine texel; a
    /// flat map has neither spread nor moment. (The numeric integral, 64² midpoints a texel, is
    /// good to a few 1e-6 next to the poles.)
    #[test]
    fn the_first_moments_are_the_texels_integrals() {
        let (w, h) = (512, 256);
        let fine = LatLong::new(w, h);
        let numeric = |x: usize, y: usize| {
            let n = 64;
            let mut m = DVec3::ZERO;
            for i in 0..n {
                let theta = PI * (y as f64 + (i as f64 + 0.5) / n as f64) / h as f64;
                let d_theta = PI / (h * n) as f64;
                for j in 0..n {
                    let phi = TAU * (x as f64 + (j as f64 + 0.5) / n as f64) / w as f64;
                    m += sphere::direction(theta, phi) * theta.sin() * d_theta * TAU / (w * n) as f64;
                }
            }
            m
        };
        for (x0, y0) in [(3, 1), (200, 60), (511, 130), (77, 255)] {
            let mut map = vec![[0.0; 3]; w * h];
            map[y0 * w + x0] = [1.0, 2.0, 0.0];
            let coarse = Coarse::levels(fine, Coarse::factor(fine).unwrap(), Cow::Borrowed(&map)).0;
            let f = coarse.factor;
            let t = (y0 / f) * coarse.geometry.width + x0 / f;
            let texels =
                (f * (y0 / f)..f * (y0 / f + 1)).flat_map(|y| (f * (x0 / f)..f * (x0 / f + 1)).map(move |x| (x, y)));
            let area: f64 = texels.clone().map(|(_, y)| fine.row_solid_angle(y)).sum();
            let mean = fine.row_solid_angle(y0) / area;
            let want = numeric(x0, y0) - texels.map(|(x, y)| numeric(x, y)).sum::<DVec3>() * mean;
            for (c, scale) in [(0, 1.0), (1, 2.0)] {
                let got = coarse.moment[t][c];
                assert!(
                    (got - want * scale).length() <= 1e-5 * (want * scale).length(),
                    "({x0}, {y0}) {c}: {got} vs {}",
                    want * scale
                );
            }
            assert!(coarse.moment[t][2].length() == 0.0 && (coarse.radiance[t][0] as f64 - mean).abs() < 1e-7);
        }
        let flat = Coarse::levels(fine, Coarse::factor(fine).unwrap(), Cow::Owned(vec![[1.0; 3]; w * h])).0;
        assert!(flat.moment.iter().all(|m| m[0].length() < 1e-15) && flat.deviation.iter().all(|d| d[0] < 1e-15));
    }

    /// Blocks grouped from their moments ([`BlockMoments::group`]) have the mean and signed
    /// moments of the same texels taken as one block ([`BlockMoments::of`]), and the absolute
    /// ones bounded from above, within a small factor: D_T and Rᵀ A_T R at directions all round.
    #[test]
    fn grouped_blocks_have_their_texels_moments() {
        let map = detailed(512, 256);
        let fine = LatLong::new(512, 256);
        let rows: Vec<RowFactors> = (0..256).map(|y| RowFactors::of(fine, y)).collect();
        let columns: Vec<[f64; 4]> = (0..512).map(|x| column_factors(fine, x)).collect();
        let radiance = &map.image().pixels;
        let (f, g) = (8, 4);
        let coarse = LatLong::new(512 / f, 256 / f);
        let blocks: Vec<BlockMoments> = (0..coarse.height * coarse.width)
            .map(|i| BlockMoments::of(fine, radiance, &rows, &columns, [i % coarse.width, i / coarse.width, f]))
            .collect();
        let directions: Vec<DVec3> = (0..16)
            .map(|k| {
                let z = 1.0 - 2.0 * (k as f64 + 0.5) / 16.0;
                let phi = k as f64 * 2.399_963;
                DVec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z)
            })
            .collect();
        let (mut loosest, mut checked): (f64, usize) = (1.0, 0);
        for (x, y) in [(0, 0), (5, 1), (9, 3), (15, 7), (3, 4), (12, 2)] {
            let grouped = BlockMoments::group(coarse, &blocks, [x, y, g]);
            let direct = BlockMoments::of(fine, radiance, &rows, &columns, [x, y, f * g]);
            for c in 0..3 {
                let scale = direct.mean[c].abs() * fine.row_solid_angle(128) * (f * g * f * g) as f64;
                assert!((grouped.mean[c] - direct.mean[c]).abs() <= 1e-12 * direct.mean[c].abs(), "({x}, {y}) mean");
                assert!((grouped.moment[c] - direct.moment[c]).length() <= 1e-9 * scale, "({x}, {y}) M");
                let q = (grouped.second[c] - direct.second[c]).to_cols_array();
                assert!(q.iter().all(|v| v.abs() <= 1e-9 * scale), "({x}, {y}) Q {q:?}");
                assert!(grouped.deviation[c] >= direct.deviation[c] - 1e-12 * scale, "({x}, {y}) D below");
                for r in &directions {
                    let (a, b) = (r.dot(grouped.spread[c] * *r), r.dot(direct.spread[c] * *r));
                    assert!(a >= b - 1e-12 * scale, "({x}, {y}) {c} RᵀAR {a:e} < {b:e}");
                    if b > 1e-6 * scale {
                        loosest = loosest.max(a / b);
                        checked += 1;
                    }
                }
                if direct.deviation[c] > 1e-6 * scale {
                    loosest = loosest.max(grouped.deviation[c] / direct.deviation[c]);
                }
            }
        }
        assert!(checked > 50, "only {checked} spreads compared");
        assert!(loosest < 2.0, "the grouped bounds are {loosest} times the texels'");
    }

    /// `Curve`'s f' and |f''| are the kernel's derivatives in s = cos γ (central differences of
    /// `SplitSumLobe::kernel`), and |f''| grows with s, as the remainder bound assumes.
    #[test]
    fn the_curve_has_the_kernels_derivatives() {
        for r in [0.05, 0.2, 0.5, 0.9] {
            let lobe = SplitSumLobe::new(r).unwrap();
            let curve = Curve::of(&lobe);
            let f = |s: f64| lobe.kernel(s);
            let mut last = 0.0;
            for s in [0.05f64, 0.2, 0.5, 0.8, 0.95, 0.99] {
                let h = 1e-4 * (1.0 - s).min(s);
                let first = (f(s + h) - f(s - h)) / (2.0 * h);
                let second = (f(s + h) - 2.0 * f(s) + f(s - h)) / (h * h);
                assert!(
                    (curve.first(s) - first).abs() <= 1e-5 * first.abs(),
                    "r {r} s {s}: f' {} vs {first}",
                    curve.first(s)
                );
                let got = curve.second(s);
                assert!((got - second.abs()).abs() <= 1e-3 * got, "r {r} s {s}: |f''| {got} vs {second}");
                assert!(got >= last, "r {r} s {s}: |f''| falls");
                last = got;
            }
        }
    }

    /// f''' is the derivative of f'' (central differences of `Curve::second`), ≥ 0 and growing
    /// with s, as `Curve::expansion`'s remainder assumes.
    #[test]
    fn the_third_derivative_is_the_seconds_slope() {
        for r in [0.05, 0.2, 0.5, 0.9] {
            let curve = Curve::of(&SplitSumLobe::new(r).unwrap());
            let mut last = 0.0;
            for s in [-0.5f64, 0.05, 0.2, 0.5, 0.8, 0.95, 0.99] {
                let h = 1e-5 * (1.0 - s).min(s.abs());
                let numeric = (curve.second(s + h) - curve.second(s - h)) / (2.0 * h);
                let got = curve.derivatives(s)[3];
                assert!((got - numeric).abs() <= 1e-5 * got, "r {r} s {s}: f''' {got} vs {numeric}");
                assert!(got >= last, "r {r} s {s}: f''' falls");
                last = got;
            }
        }
    }

    /// Every coarse texel of a 512 × 256 [`detailed`] map that `select` keeps, seen from `axis`
    /// through `lobe`, taken whole against its texel-by-texel sum Σ_t L_t ∫_t k dω (a 6 × 6 rule
    /// on every fine texel, independent of the moments): asserts the difference is within the
    /// bound, and returns how many texels were checked and the least ratio of bound to difference.
    fn taken_whole_against_texels(lobe: f64, axis: DVec3, select: impl Fn(&Curve, Span) -> bool) -> (usize, f64) {
        let map = detailed(512, 256);
        let grid = Grid::new(map.image(), 1);
        let Texels::Levels(coarse, _) = &grid.texels else { panic!("a 512-wide grid has a coarse level") };
        let exact = TexelRule::new(6).unwrap();
        let lobe = SplitSumLobe::new(lobe).unwrap();
        let integral = LobeIntegral {
            fine: ConeSum::new(grid.geometry, &exact, &lobe),
            sums: Sums::Rows(Arc::new(map.image().pixels.clone())),
            curve: Curve::of(&lobe),
        };
        let axis = axis.normalize();
        let (mut checked, mut tightest) = (0, f64::INFINITY);
        for y in 0..coarse.geometry.height {
            for x in 0..coarse.geometry.width {
                let Some(span) = coarse.span(axis, x, y).filter(|s| select(&integral.curve, *s)) else { continue };
                let index = y * coarse.geometry.width + x;
                let (mut sum, mut kernel) = ([0.0; 3], 0.0);
                integral.fine.within(coarse, &[index], axis, |fy, columns, weights| {
                    for (fx, k) in columns.zip(weights) {
                        let l = map.image().pixels[fy * grid.geometry.width + fx];
                        (0..3).for_each(|c| sum[c] += l[c] as f64 * k);
                        kernel += k;
                    }
                });
                let (value, bound) = integral.taken_whole(coarse, (index, y), (axis, &Squares::of(axis)), span, kernel);
                for c in 0..3 {
                    let diff = (value[c] - sum[c]).abs();
                    // The fine rule and the f32 radiance add a few 1e-7 of the texel's sum.
                    assert!(diff <= bound[c] + 1e-6 * sum[c].abs(), "({x}, {y}) {c}: |Δ| {diff:e} > {:e}", bound[c]);
                    tightest = tightest.min(bound[c] / (diff + 1e-300));
                }
                checked += 1;
            }
        }
        (checked, tightest)
    }

    /// A coarse texel taken whole (its mean radiance times its coarse-rule integral plus the
    /// second-order moment terms) is within its remainder bound of the texel-by-texel sum, on
    /// the texels near a sharp lobe's peak where the kernel curves most; the bound is not vacuous.
    #[test]
    fn a_block_taken_whole_is_within_its_bound_of_its_texels() {
        // Only where the kernel curves strongly.
        let curved = |curve: &Curve, span: Span| !crosses_horizon(span) && curve.expansion(span).2 >= 1.0;
        let (checked, tightest) = taken_whole_against_texels(0.3, DVec3::new(0.3, -0.5, 0.8), curved);
        assert!(checked >= 4, "only {checked} curved texels");
        assert!(tightest < 100.0, "the bound is vacuous: at least {tightest} times the error");
    }

    /// A coarse texel the horizon crosses, taken whole (its mean radiance times the middle of
    /// where its kernel integral must lie), is within its bound of the texel-by-texel sum, for
    /// narrow and wide lobes and axes towards the sun, the ground and the map's seam; the bound
    /// is not vacuous.
    #[test]
    fn a_block_the_horizon_crosses_is_within_its_bound_of_its_texels() {
        let axes = [DVec3::new(0.3, -0.5, 0.8), DVec3::new(0.9, 0.1, -0.4), DVec3::new(-1.0, 0.02, 0.1)];
        for r in [0.1, 0.3, 0.6, 1.0] {
            for axis in axes {
                let (checked, tightest) = taken_whole_against_texels(r, axis, |_, span| crosses_horizon(span));
                assert!(checked >= 50, "r {r}: only {checked} texels on the horizon");
                assert!(tightest < 20.0, "r {r}: the bound is vacuous: at least {tightest} times the error");
            }
        }
    }

    #[test]
    fn weighted_radiance_is_the_plain_sum() {
        // Every length around the four lanes (the tail alone, whole blocks, both), against the
        // sum in texel order; only the order of the additions differs.
        let mut rng = crate::rng::SplitMix64::new(3);
        for n in 0..14 {
            let texels: Vec<[f32; 3]> =
                (0..n).map(|_| [0, 1, 2].map(|c| (rng.next_f64() * (c + 1) as f64) as f32)).collect();
            let weights: Vec<f64> = (0..n).map(|_| rng.next_f64() - 0.25).collect();
            let got = weighted_radiance(&texels, &weights);
            for c in 0..3 {
                let want: f64 = texels.iter().zip(&weights).map(|(l, k)| l[c] as f64 * k).sum();
                let scale: f64 = texels.iter().zip(&weights).map(|(l, k)| (l[c] as f64 * k).abs()).sum();
                assert!((got[c] - want).abs() <= 1e-15 * scale, "{n} texels, channel {c}: {got:?} vs {want}");
            }
        }
    }

    /// take_largest takes what a full sort takes: the largest by size (ties by index) until the
    /// rest sums to at most the target, largest first, and leaves the rest in their order; past
    /// the first prefix of 64 too, and with ties and zeros.
    #[test]
    fn take_largest_takes_what_a_full_sort_takes() {
        let mut state = 12345u64;
        let items: Vec<(usize, f64)> = (0..1000)
            .map(|i| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                // Sizes on a coarse grid, so that many tie; a tenth of them zero.
                (i, ((state >> 33) % 50) as f64 * if i % 10 == 0 { 0.0 } else { 1.0 })
            })
            .collect();
        let total: f64 = items.iter().map(|t| t.1).sum();
        for share in [1.0, 0.9, 0.5, 0.1, 0.01, 0.0] {
            let target = share * total;
            let mut sorted = items.clone();
            sorted.sort_by(|x, y| y.1.total_cmp(&x.1).then(x.0.cmp(&y.0)));
            let (mut left, mut expected) = (total, Vec::new());
            for t in &sorted {
                if left <= target {
                    break;
                }
                left -= t.1;
                expected.push(t.0);
            }
            let mut rest = items.clone();
            let taken = take_largest(&mut rest, |t| t.1, |t| t.0, target);
            assert_eq!(taken, expected, "share {share}");
            let kept: Vec<(usize, f64)> = items.iter().filter(|t| !expected.contains(&t.0)).copied().collect();
            assert_eq!(rest, kept, "share {share}");
            if share < 0.5 {
                assert!(taken.len() > 64, "share {share}: the test should pass the first prefix");
            }
        }
    }

    /// f32_at_least(v) is the least f32 not below v: at v = 0, at f32 values and between them,
    /// from the subnormals to beyond f32::MAX.
    #[test]
    fn the_least_f32_not_below() {
        let mut values = vec![0.0, 1e-46, f64::from(f32::MAX), 1.0e39];
        let mut x = 1e-45f64;
        while x < 1e39 {
            let f = x as f32;
            values.extend([x, f64::from(f), f64::from(f) * (1.0 + 1e-12), f64::from(f) * (1.0 - 1e-12)]);
            x *= 1.37;
        }
        for v in values {
            let got = f32_at_least(v);
            assert!(f64::from(got) >= v, "{v:e}: {got:e} is below");
            if got > 0.0 {
                assert!(f64::from(got.next_down()) < v, "{v:e}: {:e} is not below it either", got.next_down());
            }
        }
    }

    /// |dk/dγ| has one peak on [0, π/2] (what `Slope::between` relies on), `Slope::at` is the
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
