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

/// The first and the last band of the search for a BRDF's orders (F_B, P_B)
/// ([`super::model::Model::coefficients_for_epsilon`]): F starts here and doubles until the
/// energy rule is met. R&H 2002 App. C's values, which its measured BRDFs all meet by F = 128.
pub const FIRST_SEARCH_BAND: usize = 16;
/// See [`FIRST_SEARCH_BAND`]: the search ends here, with an error if the rule is not met.
pub const LAST_SEARCH_BAND: usize = 128;

/// Samples of ρ(θ_h) over [0, π] that find where a [`super::model::HalfAngleLobe`] starts (where
/// ρ falls below 10⁻¹² of its peak): one every 0.044°, so that even Torrance-Sparrow at
/// σ = 0.005 has its support sampled about 34 times (derived, not measured:
/// `docs/prefilter-tuning.md`).
pub const HALF_ANGLE_SCAN_STEPS: usize = 4096;

/// Panels in γ ∈ [0, π] of [`super::truncation::radial_truncation`]'s cumulative integral, each
/// with a 4-point Gauss rule: node spacing about π/2000, chosen to be as fine near the axis as
/// the 2 000-node rule in cos γ it replaced (`docs/prefilter-tuning.md`).
pub const TRUNCATION_PANELS: usize = 512;

/// Sample rows in θ_i of the cone table ([`super::truncation::CutoffTable`]) per view-angle bin,
/// midpoints over [0, π]; with [`CUTOFF_PHI_SAMPLES`], set when the table was written, with no
/// measurement recorded (`docs/prefilter-tuning.md`).
pub const CUTOFF_THETA_SAMPLES: usize = 512;
/// See [`CUTOFF_THETA_SAMPLES`]: sample columns in φ_i over [0, π] (ρ̂ is even in φ_i).
pub const CUTOFF_PHI_SAMPLES: usize = 24;

/// View angles (degrees) at which the view residual r(θ_o) is tabulated
/// ([`super::orders`]'s texel rule for view-dependent BRDFs): every 10°, so the valid range
/// recorded in a document is a whole multiple of 10°.
pub const VIEW_ANGLES: &[f64] = &[
    0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0, 110.0, 120.0, 130.0, 140.0, 150.0, 160.0, 170.0,
    180.0,
];

/// Nodes per axis of the grid (Gauss–Legendre in cos θ_i × midpoints in φ_i) on which the view
/// residual r(θ_o) measures ρ̂ against its truncated expansion; set with the texel rule, with no
/// measurement recorded (`docs/prefilter-tuning.md`).
pub const VIEW_SAMPLE_NODES: usize = 192;

/// Bins in cos θ_i ∈ [−1, 1] of the table from which an SHRM file's bright part is read (the
/// lobe projected on the view basis per bin), and the quadrature per bin: this many
/// Gauss–Legendre nodes in cos θ_o and as many points in φ_o. Set when the table was written,
/// with no measurement recorded (`docs/prefilter-tuning.md`).
pub const VIEW_PROJECTION_BINS: usize = 1024;
/// See [`VIEW_PROJECTION_BINS`].
pub const VIEW_PROJECTION_NODES: usize = 96;

/// Steps across texel edges the view frame's lookup ([`super::view_axis`]'s `TexelLocator`)
/// walks from the previous lookup's texel before it computes the direction's angles instead:
/// neighbouring lookups of the rotation land within a texel or two of each other. Set when the
/// locator was written, with no measurement of other values recorded (`docs/prefilter-tuning.md`);
/// a walk and the angles can disagree within f32 rounding of an edge, so it may move bits.
pub const LOCATOR_MAX_STEPS: usize = 2;

/// The most bright sources whose surroundings `--verify` checks (`super::verify`), which share a
/// quarter of the checked texels among them; set with `--verify`, with no measurement recorded
/// (`docs/prefilter-tuning.md`).
pub const VERIFY_SOURCES: usize = 4;
