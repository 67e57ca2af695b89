//! The prefilter's tuning constants, in one place. Each trades accuracy against time or memory;
//! the sentence beside it says what it trades and which measurement set it. The measured figures
//! are in `docs/prefilter-tuning.md` and `docs/prefilter.md`.

use std::f64::consts::PI;

/// Lobe weight left outside the cone of every exact angular pass (the bright texels, the grazing
/// texels' fallback, maps in angle), which their documents give as ε achieved; and the truncation
/// of `--verify`'s angular integral. Set far below any bake's error, so that what is computed in
/// angle is exact for every figure the bakes report.
pub const ANGULAR_EPSILON: f64 = 1e-5;

/// A lobe is *narrow* when its width √(∫u dω / u_max) spans fewer than this many texels of the
/// lat-long grid it is filtered on ([`is_narrow`]). The one threshold decides three things: a
/// radially symmetric lobe's reflection maps are filtered in angle whole (R&H §6.3's crossover:
/// frequency space costs more as the lobe narrows, angle less); a radially symmetric lobe's
/// bright texels go through the zonal filter rather than spherical harmonics; and the view
/// frame's grid is refined. Set by the cost crossover of the first and the per-texel error of the
/// last, measured on Grace at 256×128 (`docs/prefilter-tuning.md`).
pub const NARROW_LOBE_TEXELS: f64 = 8.0;

/// True when a lobe `width` radians wide spans fewer than [`NARROW_LOBE_TEXELS`] texels of a
/// lat-long grid `height` rows high (texels π/height high).
pub fn is_narrow(width: f64, height: usize) -> bool {
    width < NARROW_LOBE_TEXELS * (PI / height as f64)
}

/// Highest band the texel rule considers: the cost of the projection and of the BRDF
/// coefficients grows with it, and a 512×256 map resolves up to 255.
pub const MAX_TEXEL_ORDER: usize = 255;

/// The share of a radially symmetric lobe's weight the zonal filter's texel rule may misplace
/// (`envmap::zonal::rule_for_kernel`), for the bright texels and for maps in angle: a hundredth
/// of the default ε, so that the texel rule never decides a map's error.
pub const RULE_TOLERANCE: f64 = 1e-3;

/// Gauss–Legendre nodes in z per texel when the bright texels are projected onto spherical
/// harmonics. The lobes on that path span at least [`NARROW_LOBE_TEXELS`] texels, over which two
/// nodes integrate a texel within 10⁻⁵ of itself; a third node cost a third more of the path for
/// no visible change (`docs/prefilter-tuning.md`).
pub const BRIGHT_Z_NODES: usize = 2;

/// Bins in θ_o of the cone table ([`super::truncation::CutoffTable`]) of the ring-free bake's
/// angular passes, and of the angular reference (finer: its cones are its result).
pub const CUTOFF_BINS: usize = 33;
/// See [`CUTOFF_BINS`].
pub const REFERENCE_CUTOFF_BINS: usize = 65;

/// From this many views a bake's reflection maps are read from the global SHRM (eq. 7–8), whose
/// rotation per texel pays off over many views, instead of the local one per view.
pub const GLOBAL_FROM_VIEWS: usize = 8;

/// The share of ε the bound on the unprojected bands may take at the texel rule's first
/// projection (`orders::first_projection`): small enough that the bound barely moves e(F), and
/// the projection, whose cost grows as L², no larger than it must be.
pub const FIRST_PROJECTION_SHARE: f64 = 0.01;

/// The view residual r(θ_o) a texel's view angle may have and still be taken from the SHRM,
/// relative to ε: measured, the 99th-percentile per-texel error of such texels is about twice r
/// (`docs/prefilter.md`).
pub const VIEW_RESIDUAL_FACTOR: f64 = 1.0;

/// View-frame integral ([`super::view_axis`]): θ_o sampled when looking for the narrowest cone
/// and the thinnest lobe of the range.
pub const CONE_SAMPLES: usize = 256;

/// View-frame integral: point lookups per axis and per texel of the lighting in the box filter
/// that rotates it into the view's frame. Past 6 the p99 error against the reference no longer
/// fell (Grace, σ = 0.1, grazing view; `docs/prefilter-tuning.md`).
pub const SUPERSAMPLE: usize = 6;

/// View-frame integral: the frame's grid is this many times finer per axis than the pyramid level
/// when the lobe is narrow against the level's texels, so the rotated map resolves their edges to
/// half a texel; it halved the p99 error of Torrance-Sparrow σ = 0.1 at a grazing view
/// (`docs/prefilter-tuning.md`).
pub const REFINE: usize = 2;

/// Texels of the cone pyramid's level summed per cone angle θ*
/// ([`super::angular::ConePyramid`]): midpoint sums of a smooth lobe over box-filtered texels
/// err by O((Δ/θ*)²), under the prefilter's tolerance at this many.
pub const TEXELS_PER_CONE: f64 = 24.0;

/// Gauss–Legendre nodes per half of [−1, 1] for a radial lobe's coefficients when the lobe is
/// not a polynomial of low degree in cos γ: they integrate Phong exponents into the thousands.
pub const RADIAL_NODES: usize = 1024;

/// Largest interpolation error of a [`super::model::HalfAngleLobe`] at any interval's midpoint, as a share of
/// the curve's peak. A texel's weight then errs by at most this much of the peak, so a cone
/// sum by at most this share of the peak times the lighting over the cone: about 10⁻⁴ of the
/// sum for a cone ten times the lobe's effective solid angle, 100 times below the ε = 10⁻³
/// reference's own truncation.
pub const HALF_ANGLE_TOLERANCE: f64 = 1e-5;

/// The most entries a [`super::model::HalfAngleLobe`] may take (0.5 MB). Torrance-Sparrow takes 4 097 for
/// every σ from 0.005 to 0.3 (2 049 at 0.5): its support in cos θ_h, where ρ is above 10⁻¹² of
/// the peak, is about 14σ², and linear interpolation within the tolerance needs a spacing of
/// about σ²√(2·10⁻⁵), both σ² while θ_h is small. Curves
/// with a kink of unbounded curvature, such as Blinn-Phong's cos^s θ_h for s < 1 at θ_h = 90°,
/// exceed it and are evaluated exactly.
pub const MAX_HALF_ANGLE_ENTRIES: usize = 1 << 16;
