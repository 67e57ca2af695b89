//! Ring-free prefiltering (`docs/prefilter.md`, "Ring-free bakes"): frequency space where it is
//! exact and cheap, angle where it is not.
//!
//! 1. **Bright sources apart** ([`crate::envmap::bright`]): the excess of compact, very bright
//!    texels over a threshold is filtered in angle with the exact lobe; the clipped remainder is
//!    smooth enough for spherical harmonics.
//! 2. **Orders for this lighting** ([`super::orders`]): F_B from the worst-case per-texel error
//!    bound on the remainder's band energies (or the paper's energy rule); P_B from how well the
//!    expansion represents ρ̂ per view angle.
//! 3. **Out-of-range texels in angle**: for view-dependent BRDFs, reflection-map texels whose
//!    view angle θ_o lies beyond the SHRM's valid range (grazing views) are integrated in angle,
//!    all of a view's at once in the frame whose pole is the view ([`super::view_axis`]).
//! 4. **Window** ([`crate::sh::window`]): applied to the lighting's bands at synthesis; the
//!    default `nonneg` leaves a non-negative map alone and otherwise finds the gentlest heat
//!    window that makes it non-negative.
//!
//! Reflection maps of view-dependent BRDFs skip 2–4: every texel is integrated in angle
//! ([`view_frame_maps`]), which measured both faster and closer to the reference than the SHRM
//! with its fallback, for one view and for many (`docs/prefilter.md`, "Maps in angle").
//!
//! The SHRM itself holds the remainder's expansion plus, for radially symmetric BRDFs, the bright
//! part (its single layer is a reflection map); for view-dependent BRDFs the bright part is
//! projected onto the view basis texel by texel (exact in angle, truncated at P_B like the rest).

use super::angular::{radial_cutoff, radial_truncation, ConePyramid, CutoffTable};
use super::brdf_sh::BrdfSh;
use super::model::Model;
use super::orders::{first_projection, texel_orders, LightEnergy, OrderRule, TexelOrders};
use super::pipeline::{brdf_coefficients, Lighting, Orders, PrefilterError};
use super::shrm::{self, texel_frame, Shrm, ShrmError};
use super::view_axis;
use crate::envmap::bright::{split, BrightReport, BrightRule, BrightSources};
use crate::envmap::zonal::{rule_for_kernel, zonal_filter, Rows, MAX_TEXELS};
use crate::envmap::{self, EnvMap, Layout};
use crate::io::RgbImage;
use crate::progress::{NoProgress, Progress};
use crate::sh::convolve::convolve_zonal_rgb;
use crate::sh::project::{map_energy_rgb, map_integral_rgb, project, project_latlong_texels, TexelQuadrature};
use crate::sh::window::{self, Window, WindowReport};
use crate::sh::ShCoeffs;
use crate::sphere::LatLong;
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Highest band the texel rule considers (the cost of the projection and of the BRDF
/// coefficients grows with it; a 512×256 map resolves up to 255).
pub const MAX_TEXEL_ORDER: usize = 255;

/// Lobe energy left outside the cone of the exact angular passes (bright texels, fallbacks,
/// [`view_frame_maps`], whose documents give it as ε achieved).
pub const ANGULAR_EPSILON: f64 = 1e-5;

/// The share of a radially symmetric lobe's weight the zonal filter's texel rule may misplace
/// ([`rule_for_kernel`]), for the bright texels and for [`zonal_maps`].
const RULE_TOLERANCE: f64 = 1e-3;

/// Radially symmetric lobes narrower than this many texels of the lighting's lat-long grid
/// (width √(∫u dω / u_max)) are filtered in angle whole ([`zonal_maps`]). Phong's width is
/// √(2π/(s + 1)): s = 128 spans 9 texels at 256×128, s = 256 6.4, s = 512 4.5.
pub const ZONAL_TEXELS_PER_WIDTH: f64 = 8.0;

/// How many source texels a radially symmetric lobe must span (its width √(∫u dω / u_max)) for
/// its bright texels to go through spherical harmonics ([`bright_harmonics`]). The texel integrals
/// keep that path exact for any width; the bound is one of cost: the band it needs grows as the
/// lobe narrows (11, 25, 53 for Phong s = 8, 32, 128, 9–34 texels wide at 256×128), while the
/// zonal filter's cost falls with the cone.
const SH_BRIGHT_TEXELS_PER_WIDTH: f64 = 8.0;

/// Gauss–Legendre nodes in z per texel of the bright texels' projection ([`bright_harmonics`]).
/// The lobes on this path span at least 8 texels, a Gaussian of deviation σ ≥ 3.2 texels
/// (width = √(2π) σ), whose texel integral two nodes take within about 3/(4320 σ⁴) ≈ 10⁻⁵ of
/// itself (the midpoint, one node, within 1/(24 σ²) ≈ 4 · 10⁻³); the Legendre columns over the
/// nodes are most of the path's cost, so a third node cost a third more for nothing visible.
const SH_BRIGHT_Z_NODES: usize = 2;

/// How the prefilter chooses its orders and treats the lighting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// The tolerance ε of the order rule.
    pub epsilon: f64,
    /// The order rule.
    pub rule: OrderRule,
    /// Fixed orders (F_B, P_B), overriding the rule.
    pub orders: Option<(usize, usize)>,
    /// Largest P_B considered.
    pub max_p: usize,
    /// Bright sources apart.
    pub bright: BrightRule,
    /// The window at synthesis.
    pub window: Window,
    /// The grid of reflection vectors (W, H); `None`: [`default_size`].
    pub size: Option<(usize, usize)>,
}

/// What the prefilter did, for the document.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Where the reflection maps' texels came from.
    #[serde(default)]
    pub maps: MapsFrom,
    /// The order rule used (`texel`, `energy`, or `fixed`; `none` when no expansion was made).
    pub rule: String,
    /// The texel rule's guarantee, when it chose the orders.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texel: Option<TexelOrders>,
    /// The bright sources: threshold, texels and energy shares.
    pub bright: BrightReport,
    /// The window applied at synthesis.
    pub window: WindowReport,
}

/// Where a bake's reflection maps come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MapsFrom {
    /// The SHRM within its valid view angle, the rest and the bright texels in angle.
    #[default]
    Shrm,
    /// Every texel in angle ([`view_frame_maps`]).
    Angle,
}

/// True when the default bake integrates its reflection maps of `map` in angle, the texel rule
/// choosing the orders:
///
/// - **A view-dependent BRDF.** Per view, the whole map in the view's frame with the bright
///   texels splatted into it costs less than the SHRM path's own per-view work (its bright
///   texels pair by pair and its fallback for grazing texels), before the SHRM's one-off cost:
///   Grace at 256×128, 7 views in angle against 8 through the SHRM, 0.14 against 0.17 s a view
///   at σ = 0.1 and 0.09 against 0.19 s at σ = 0.3 (`docs/prefilter.md`, "Maps in angle").
/// - **A radially symmetric lobe narrower than [`ZONAL_TEXELS_PER_WIDTH`] texels of the map's
///   lat-long grid**, on an output grid as wide as it ([`zonal_maps`]).
pub fn maps_in_angle(model: &Model, settings: &Settings, map: &EnvMap) -> bool {
    if settings.orders.is_some() || settings.rule != OrderRule::Texel {
        return false;
    }
    if model.centre().is_none() {
        return true;
    }
    let grid = latlong_grid(map);
    let (width, height) = settings.size.unwrap_or((grid.width, grid.height));
    let texel = PI / grid.height as f64;
    width == grid.width
        && [grid.height, height].iter().all(|h| width.checked_mul(*h).is_some_and(|n| n <= MAX_TEXELS))
        && radial_truncation(|x| model.lobe(x)[1], ANGULAR_EPSILON).width < ZONAL_TEXELS_PER_WIDTH * texel
}

/// Reflection maps integrated in angle, with what the document reports of them.
pub struct InAngle {
    /// One map per view.
    pub maps: Vec<RgbImage>,
    /// The grid (W, H).
    pub size: (usize, usize),
    /// What was done.
    pub report: Report,
}

/// Reflection maps with every texel in angle, when [`maps_in_angle`] says so: [`zonal_maps`] for
/// a radially symmetric lobe, [`view_frame_maps`] for a view-dependent one.
pub fn angle_maps(
    model: &Model,
    map: &EnvMap,
    views: &[DVec3],
    bright_rule: BrightRule,
    size: Option<(usize, usize)>,
    progress: &dyn Progress,
) -> Result<InAngle, PrefilterError> {
    match model.centre() {
        Some(_) => zonal_maps(model, map, views, size, progress),
        None => view_frame_maps(model, map, views, bright_rule, size),
    }
}

/// The reflection map of a radially symmetric lobe narrow against the lighting's texels, for
/// every view: the zonal filter of the whole lat-long map ([`zonal_filter`]), each texel's sum
/// over the texels whose centres lie in its lobe's cone (1 − 10⁻⁵ of the lobe) of their exact
/// integrals of it ([`RULE_TOLERANCE`]). No expansion and no split: every texel, the sun's too,
/// takes the same exact path, so nothing rings and nothing is windowed. R&H §6.3: the
/// frequency-space cost grows with the Phong exponent (F_B ~ √s, and (F_B + 1)² coefficients)
/// while the angular cost falls with it (the cone's area ~ 1/s), so past some s* angle is the
/// cheaper; [`ZONAL_TEXELS_PER_WIDTH`] is that crossover, measured. The output is the lighting's
/// width (the filter's shift invariance in φ) and `size`'s height, or the lighting's.
fn zonal_maps(
    model: &Model,
    map: &EnvMap,
    views: &[DVec3],
    size: Option<(usize, usize)>,
    progress: &dyn Progress,
) -> Result<InAngle, PrefilterError> {
    let latlong = as_latlong(map).map_err(|e| PrefilterError::Resample(e.to_string()))?;
    let image = latlong.image();
    let height = size.map_or(image.height, |(_, h)| h);
    let kernel = |x: f64| model.lobe(x)[1];
    let cone = radial_cutoff(kernel, ANGULAR_EPSILON);
    let rule = rule_for_kernel(image.width, image.height, &kernel, cone, height, RULE_TOLERANCE).rule;
    let filtered = zonal_filter(image, kernel, cone, &rule, height, Rows::Lit, progress)
        .map_err(|e| PrefilterError::Angular(e.into()))?;
    let reflected = filtered.to_image();
    let report = Report {
        maps: MapsFrom::Angle,
        rule: "none".into(),
        texel: None,
        // Every texel went through angle.
        bright: BrightReport {
            threshold: None,
            texels: image.pixels.len(),
            energy_fraction: 1.0,
            squared_fraction: 1.0,
        },
        window: WindowReport { kind: Window::None, t: None },
    };
    Ok(InAngle { maps: vec![reflected; views.len()], size: (image.width, height), report })
}

/// Reflection maps of a view-dependent BRDF with every texel in angle: the view-frame integral
/// of [`view_axis::beyond`] over the whole map, of the remainder and of the bright texels'
/// excess added to it as energy (its splat keeps each part's energy and centre, so it errs at
/// second order in the frame's texel against the lobe's width). No spherical harmonics, so
/// nothing rings and no window is needed; the grid is the lighting's own lat-long grid unless `size` is given (there
/// is no F_B to size it by, as for `--method angular`).
fn view_frame_maps(
    model: &Model,
    map: &EnvMap,
    views: &[DVec3],
    bright_rule: BrightRule,
    size: Option<(usize, usize)>,
) -> Result<InAngle, PrefilterError> {
    let (remainder, bright) = split_latlong(map, bright_rule)?;
    let source = LatLong::new(remainder.image().width, remainder.image().height);
    let (w, h) = size.unwrap_or((source.width, source.height));
    let grid = LatLong::new(w, h);
    let cone = ConePyramid::new(&remainder)?;
    let cutoff = CutoffTable::of_model(model, ANGULAR_EPSILON, 33);
    let maps = views
        .iter()
        .map(|&view| {
            let mut out = RgbImage::new(w, h);
            for (i, v) in view_axis::beyond(&cone, model, &cutoff, view, 0.0, grid, Some((&bright, source))) {
                out.pixels[i] = v;
            }
            out
        })
        .collect();
    let report = Report {
        maps: MapsFrom::Angle,
        rule: "none".into(),
        texel: None,
        bright: bright.report(),
        window: WindowReport { kind: Window::None, t: None },
    };
    Ok(InAngle { maps, size: (w, h), report })
}

/// A ring-free prefiltered lighting: everything reflection maps and the SHRM file are made of.
pub struct Prefiltered {
    /// ρ̂_lpq truncated to (F_B, P_B).
    pub brdf: BrdfSh,
    /// For radially symmetric BRDFs, the zonal kernel k_l = Λ_l ρ̂_l to the highest band the
    /// order rule computed (the map's l_max under the texel rule, else F_B); empty otherwise.
    /// The bright texels' spherical-harmonic path reads its tail.
    pub kernel: Vec<[f64; 3]>,
    /// The remainder's lighting coefficients to F_B (raw, before the window).
    pub lighting: ShCoeffs,
    /// The window's band factors.
    pub factors: Vec<f64>,
    /// The local SHRM of the remainder (windowed), plus the bright texels when they went
    /// through spherical harmonics (`bright_harmonics`).
    pub remainder_shrm: Shrm,
    /// The bright texels' reflected radiance as spherical harmonics (kernel applied, no window),
    /// for a radially symmetric lobe wide enough for them ([`bright_harmonics`]); synthesized
    /// with the remainder, so the angular passes leave those texels out.
    pub bright_harmonics: Option<ShCoeffs>,
    /// The bright texels.
    pub bright: BrightSources,
    /// The lat-long remainder (bright sources clipped) for the angular fallback, when the
    /// lighting was a map.
    pub remainder_map: Option<EnvMap>,
    /// What was done.
    pub report: Report,
}

/// The grid size for F_B: 2S × S with S = clamp(10·F_B, 32, 512) (§5.2: S ≈ 10F), at least
/// F_B + 1.
pub fn default_size(f_b: usize) -> (usize, usize) {
    let s = (10 * f_b).clamp(32, 512).max(f_b + 1);
    (2 * s, s)
}

/// The highest band a lat-long map resolves: below its height, below the Nyquist frequency of
/// its rows, and within [`MAX_TEXEL_ORDER`].
fn resolvable_order(map: &EnvMap) -> usize {
    let img = map.image();
    map.max_order().min(img.width / 2 - 1).min(img.height - 1).min(MAX_TEXEL_ORDER)
}

/// Runs steps 1–2 and the SHRM of the remainder: everything but the per-view angular passes.
pub fn prefilter(
    model: &Model,
    lighting: Lighting<'_>,
    settings: &Settings,
    progress: &dyn Progress,
) -> Result<Prefiltered, PrefilterError> {
    let radial = model.centre().is_some();
    let max_p = if radial { 0 } else { settings.max_p };
    let (remainder, bright) = match lighting {
        Lighting::Map(map) => {
            let (rest, bright) = split_latlong(map, settings.bright)?;
            (Some(rest), bright)
        }
        Lighting::Coefficients(_) => (None, BrightSources { threshold: f64::INFINITY, ..Default::default() }),
    };
    // The lighting as far as the rule asked for it (the texel rule projects it itself).
    let mut full_light = match (&remainder, lighting, settings.orders) {
        (Some(rest), _, Some((f, _))) => Some(project(rest, f, progress)?),
        (None, Lighting::Coefficients(c), _) => Some(c.clone()),
        _ => None,
    };
    let mut kernel = Vec::new();
    let (brdf, texel) = match (settings.orders, settings.rule) {
        (Some((f, p)), _) => (brdf_coefficients(model, Orders::Fixed { f, p })?, None),
        (None, OrderRule::Energy) => {
            (brdf_coefficients(model, Orders::Epsilon { epsilon: settings.epsilon, max_p })?, None)
        }
        (None, OrderRule::Texel) => {
            let l_max = match (&remainder, &full_light) {
                // The output grid holds bands up to (W − 2)/2 (synthesis needs W ≥ 2F + 2).
                (Some(rest), _) => {
                    resolvable_order(rest).min(settings.size.map_or(usize::MAX, |(w, _)| w.saturating_sub(2) / 2))
                }
                (None, Some(c)) => c.order,
                (None, None) => unreachable!("coefficients are given when there is no map"),
            };
            let full = model.coefficients(l_max, max_p);
            if radial {
                kernel = (0..=l_max).map(|l| full.radial_kernel(l)).collect();
            }
            let rule = |light: &ShCoeffs, energy: &LightEnergy| {
                texel_orders(
                    model,
                    &full,
                    energy,
                    mean_reflected(&full, light.rgb[0], &bright),
                    settings.epsilon,
                    max_p,
                )
            };
            let orders = match (&remainder, &full_light) {
                (Some(rest), _) => {
                    // Projected as far as the rule needs: bands beyond the first projection are
                    // bounded by the map's energy, and only when that bound decides F_B is the
                    // projection taken further (`orders`: the same F_B as projecting to l_max).
                    let energy = map_energy_rgb(rest);
                    let l00 = map_integral_rgb(rest).map(|v| v / (4.0 * PI).sqrt());
                    let mean = mean_reflected(&full, l00, &bright);
                    let mut order = first_projection(model, &full, max_p, l_max, energy, mean, settings.epsilon);
                    loop {
                        let light = project(rest, order, progress)?;
                        if let Some(orders) = rule(&light, &LightEnergy::projected(&light, energy, l_max)) {
                            full_light = Some(light);
                            break orders;
                        }
                        order = (2 * order).max(1).min(l_max);
                    }
                }
                (None, Some(c)) => {
                    rule(c, &LightEnergy::exact(c.band_energy_rgb())).expect("every band known decides the orders")
                }
                (None, None) => unreachable!("coefficients are given when there is no map"),
            };
            if let Lighting::Coefficients(c) = lighting {
                // A map is cut at its own resolution, but given coefficients were cut by the
                // caller: they must at least hold what the BRDF's energy rule needs.
                let need = brdf_coefficients(model, Orders::Epsilon { epsilon: settings.epsilon, max_p })?.f;
                if c.order < need {
                    return Err(PrefilterError::LightingOrder { have: c.order, need });
                }
            }
            (full.truncated(orders.f_b, orders.p_b), Some(orders))
        }
    };
    let f_b = brdf.f;
    if radial && kernel.is_empty() {
        kernel = (0..=f_b).map(|l| brdf.radial_kernel(l)).collect();
    }
    let light = match (&remainder, lighting, &full_light) {
        (_, Lighting::Coefficients(c), _) if c.order < f_b => {
            return Err(PrefilterError::LightingOrder { have: c.order, need: f_b })
        }
        (Some(rest), _, Some(l)) if l.order < f_b => project(rest, f_b, progress)?,
        (_, _, Some(l)) => l.truncated(f_b),
        (Some(rest), _, None) => project(rest, f_b, progress)?,
        (None, _, None) => unreachable!("coefficients are given when there is no map"),
    };
    let (width, height) = settings.size.unwrap_or_else(|| default_size(f_b));
    if width < 2 * f_b + 2 {
        return Err(ShrmError::TooSmall { width, f_b, need: 2 * f_b + 2 }.into());
    }
    let bright_harmonics = match &remainder {
        Some(rest) if radial && !bright.is_empty() => {
            let source = LatLong::new(rest.image().width, rest.image().height);
            bright_harmonics(model, &bright, source, &kernel, width)
        }
        _ => None,
    };
    let factors = settings.window.factors(f_b);
    let remainder_shrm =
        remainder_shrm(model, &brdf, &light, &factors, bright_harmonics.as_ref(), (width, height), progress)?;
    let report = Report {
        maps: MapsFrom::Shrm,
        rule: match (settings.orders, settings.rule) {
            (Some(_), _) => "fixed".into(),
            (None, OrderRule::Texel) => "texel".into(),
            (None, OrderRule::Energy) => "energy".into(),
        },
        texel,
        bright: bright.report(),
        window: WindowReport { kind: settings.window, t: settings.window.guarded().then_some(0.0) },
    };
    Ok(Prefiltered {
        brdf,
        kernel,
        lighting: light,
        factors,
        remainder_shrm,
        bright_harmonics,
        bright,
        remainder_map: remainder,
        report,
    })
}

/// The mean reflected radiance per channel, which the texel floor is a fraction of: band 0 of
/// the light field, ρ̂_000 L_00 Y_00 (L_00 of the whole map: the remainder's `l00` plus the
/// bright part's).
fn mean_reflected(brdf: &BrdfSh, l00: [f64; 3], bright: &BrightSources) -> [f64; 3] {
    let y00 = 1.0 / (4.0 * PI).sqrt();
    let mut l00 = l00;
    for t in &bright.texels {
        for c in 0..3 {
            l00[c] += t.excess[c] * t.solid_angle * y00;
        }
    }
    let r = brdf.get(0, 0, 0);
    [0, 1, 2].map(|c| (r[c] * l00[c] * y00).abs())
}

/// The local SHRM of the remainder with the window's band `factors`, plus the bright texels
/// when they went through spherical harmonics (`bright`, unwindowed; [`shrm::from_lighting`]).
fn remainder_shrm(
    model: &Model,
    brdf: &BrdfSh,
    light: &ShCoeffs,
    factors: &[f64],
    bright: Option<&ShCoeffs>,
    (width, height): (usize, usize),
    progress: &dyn Progress,
) -> Result<Shrm, PrefilterError> {
    let windowed = window::apply(light, factors);
    Ok(shrm::from_lighting(model.centre().is_some(), &windowed, brdf, bright, width, height, progress)?)
}

impl Prefiltered {
    /// The SHRM file's content: the remainder's SHRM plus the bright part (radially symmetric
    /// BRDFs: its exact map in the single layer; others: projected onto the view basis), global
    /// or local, with the window as it stands: the `nonneg` search runs in
    /// [`Prefiltered::reflection_maps`], so an SHRM made before (or without) reflection maps
    /// carries the window's own factors and records t = 0.
    pub fn shrm(&mut self, model: &Model, global: bool, progress: &dyn Progress) -> Result<Shrm, PrefilterError> {
        let mut out = self.remainder_shrm.clone();
        if !self.bright.is_empty() && self.bright_harmonics.is_none() {
            if model.centre().is_some() {
                let mut layer = RgbImage::new(out.width(), out.height());
                add_bright(&mut layer, model, &self.bright, self.source_grid(), Lobe::Radial);
                let s = (4.0 * PI).sqrt() as f32;
                for (o, b) in out.layers[0].pixels.iter_mut().zip(&layer.pixels) {
                    for c in 0..3 {
                        o[c] += s * b[c];
                    }
                }
            } else {
                add_bright_to_shrm(&mut out, model, &self.bright, progress);
            }
        }
        Ok(if global { shrm::to_global(&out) } else { out })
    }

    /// Reflection maps for `views` (eq. 12): the remainder's SHRM, plus the bright part and the
    /// out-of-range texels in angle, then the window. Radially symmetric BRDFs ignore the view.
    pub fn reflection_maps(
        &mut self,
        model: &Model,
        views: &[DVec3],
        progress: &dyn Progress,
    ) -> Result<Vec<RgbImage>, PrefilterError> {
        // The angular parts do not depend on the window: computed once, whatever the search does.
        let angular = self.angular_parts(model, views)?;
        let synthesize = |remainder: &Shrm| -> Vec<RgbImage> {
            let mut maps = remainder_maps(remainder, views);
            for (map, part) in maps.iter_mut().zip(&angular) {
                part.apply(map);
            }
            maps
        };
        let maps = synthesize(&self.remainder_shrm);
        let kind = self.report.window.kind;
        if !kind.guarded() || !maps.iter().any(has_negative) {
            return Ok(maps);
        }
        // The non-negativity guard: the smallest heat parameter t on top of the window for which
        // every map is ≥ 0, bracketed by the kernel-positivity bound (for radially symmetric
        // BRDFs exact; for others the bound of the l-dimension's worst kernel, which the
        // bisection then relaxes).
        let f_b = self.brdf.f;
        let kernel: Vec<f64> = match model.centre() {
            Some(_) => (0..=f_b).map(|l| self.brdf.radial_kernel(l)[1].abs().max(1e-300)).collect(),
            None => vec![1.0; f_b + 1],
        };
        let (w, h) = (self.remainder_shrm.width(), self.remainder_shrm.height());
        let bright = self.bright_harmonics.as_ref();
        let windowed =
            |factors: &[f64]| remainder_shrm(model, &self.brdf, &self.lighting, factors, bright, (w, h), progress);
        // A synthesis that fails ends the search (taken as non-negative); the error is returned
        // with the map the search settles on.
        let min_of = |maps: &Result<Vec<RgbImage>, PrefilterError>| match maps {
            Ok(maps) => maps.iter().flat_map(|m| m.pixels.iter().flatten()).fold(0.0f64, |a, &v| a.min(v as f64)),
            Err(_) => 0.0,
        };
        let found =
            window::nonneg(&kind.factors(f_b), &kernel, |factors| windowed(factors).map(|s| synthesize(&s)), min_of);
        self.remainder_shrm = windowed(&found.factors)?;
        self.factors = found.factors;
        self.report.window.t = Some(found.t);
        found.map
    }

    /// The lat-long grid the bright texels were split on.
    fn source_grid(&self) -> Option<LatLong> {
        self.remainder_map.as_ref().map(|m| LatLong::new(m.image().width, m.image().height))
    }

    /// What each view's map takes from angle: the bright texels' exact contribution, and the
    /// remainder of the texels beyond the SHRM's valid view angle, integrated in angle.
    fn angular_parts(&self, model: &Model, views: &[DVec3]) -> Result<Vec<AngularPart>, PrefilterError> {
        let (w, h) = (self.remainder_shrm.width(), self.remainder_shrm.height());
        let valid = self.report.texel.as_ref().map_or(PI, |t| t.valid_view_angle.to_radians());
        let fallback = model.centre().is_none() && valid < PI;
        let cone = self.remainder_map.as_ref().filter(|_| fallback).map(ConePyramid::new).transpose()?;
        // The view-dependent cones, when anything is summed in angle.
        let cutoff = (model.centre().is_none() && (!self.bright.is_empty() || fallback))
            .then(|| CutoffTable::of_model(model, ANGULAR_EPSILON, 33));
        Ok(views
            .iter()
            .map(|&view| {
                let lobe = match &cutoff {
                    Some(cutoff) => Lobe::View(view, cutoff),
                    None => Lobe::Radial,
                };
                let added = (self.bright_harmonics.is_none() && !self.bright.is_empty()).then(|| {
                    let mut added = RgbImage::new(w, h);
                    add_bright(&mut added, model, &self.bright, self.source_grid(), lobe);
                    added
                });
                let replaced = match (&cone, &cutoff) {
                    (Some(cone), Some(cutoff)) => {
                        view_axis::beyond(cone, model, cutoff, view, valid, LatLong::new(w, h), None)
                    }
                    _ => Vec::new(),
                };
                AngularPart { added, replaced }
            })
            .collect())
    }
}

/// Reflection maps of the remainder's local SHRM: per view from the local layers (a few views),
/// or through the global SHRM (eq. 7–8), whose rotation per texel pays off over many views.
fn remainder_maps(local: &Shrm, views: &[DVec3]) -> Vec<RgbImage> {
    const GLOBAL_FROM_VIEWS: usize = 8;
    if views.len() < GLOBAL_FROM_VIEWS {
        shrm::reflection_maps(local, views)
    } else {
        shrm::reflection_maps(&shrm::to_global(local), views)
    }
}

/// One view's angular share of a reflection map.
struct AngularPart {
    /// Texels whose remainder is replaced (index, value): the fallback beyond the valid view
    /// angle.
    replaced: Vec<(usize, [f32; 3])>,
    /// Added to every texel (the bright sources), when they were not synthesized with the
    /// remainder.
    added: Option<RgbImage>,
}

impl AngularPart {
    fn apply(&self, map: &mut RgbImage) {
        for &(i, v) in &self.replaced {
            map.pixels[i] = v;
        }
        let Some(added) = &self.added else { return };
        for (px, a) in map.pixels.iter_mut().zip(&added.pixels) {
            for c in 0..3 {
                px[c] += a[c];
            }
        }
    }
}

fn has_negative(map: &RgbImage) -> bool {
    // Every value looked at, not up to the first negative one: a reduction without an exit
    // vectorizes, and most maps have none.
    map.pixels.as_flattened().iter().fold(false, |negative, &v| negative | (v < 0.0))
}

/// The lobe the bright texels are filtered with.
#[derive(Clone, Copy)]
enum Lobe<'a> {
    /// Radially symmetric.
    Radial,
    /// View-dependent: the view and the cones per view angle.
    View(DVec3, &'a CutoffTable),
}

/// Adds the bright texels' exact contribution Σ_j e_j ΔΩ_j ρ̂(ω_j; R, V) to every texel of a
/// lat-long map of R (of N for Lambert). A texel visits only the bright texels within its lobe's
/// cone (1 − 10⁻⁵ of the lobe; for view-dependent BRDFs per view angle, from the cutoff table):
/// the bright texels are sorted by θ, and a row of texels at θ_R takes the range θ_R ± θ*. A
/// radially symmetric lobe takes a cheaper exact path when it can (a lobe wide against the
/// texels has already gone through spherical harmonics, [`bright_harmonics`]): on a map as wide
/// as the `source` grid the texels were split on, the zonal filter of their excess
/// ([`add_bright_zonal`]: FFT rows, whose cost does not grow with the number of bright texels,
/// which a wide lobe visits nearly all of per texel).
fn add_bright(map: &mut RgbImage, model: &Model, bright: &BrightSources, source: Option<LatLong>, lobe: Lobe<'_>) {
    if bright.is_empty() {
        return;
    }
    let radial_star = match lobe {
        Lobe::Radial => radial_cutoff(|x| model.lobe(x)[1], ANGULAR_EPSILON),
        Lobe::View(_, cutoff) => cutoff.max(),
    };
    if let (Lobe::Radial, Some(source)) = (lobe, source) {
        if source.width == map.width && add_bright_zonal(map, model, bright, source, radial_star) {
            return;
        }
    }
    let view = match lobe {
        Lobe::View(v, cutoff) => Some((v, cutoff)),
        Lobe::Radial => None,
    };
    let (w, h) = (map.width, map.height);
    let grid = LatLong::new(w, h);
    let mut sorted: Vec<(f64, usize)> =
        bright.texels.iter().enumerate().map(|(i, t)| (crate::sphere::theta(t.dir), i)).collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    map.pixels.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let theta_r = grid.row_theta(y);
        let lo = sorted.partition_point(|t| t.0 < theta_r - radial_star);
        let hi = sorted.partition_point(|t| t.0 <= theta_r + radial_star);
        if lo == hi {
            return;
        }
        for (x, px) in row.iter_mut().enumerate() {
            let r = grid.texel_direction(x, y);
            let (prepared, cos_star) = match view {
                None => (None, radial_star.cos()),
                Some((v, cutoff)) => match model.prepare_view(r, v) {
                    Some(p) => (Some(p), cutoff.at(r.dot(v).clamp(-1.0, 1.0).acos()).cos()),
                    None => continue,
                },
            };
            let mut acc = [0.0f64; 3];
            for &(_, i) in &sorted[lo..hi] {
                let t = &bright.texels[i];
                let c = r.dot(t.dir);
                if c < cos_star {
                    continue;
                }
                let rho = match &prepared {
                    Some(p) => model.rho_hat_prepared(p, t.dir),
                    None => model.lobe(c),
                };
                for k in 0..3 {
                    acc[k] += rho[k] * t.excess[k] * t.solid_angle;
                }
            }
            for k in 0..3 {
                px[k] += acc[k] as f32;
            }
        }
    });
}

/// The bright texels' reflected radiance for a radially symmetric lobe as spherical harmonics,
/// when the lobe spans at least [`SH_BRIGHT_TEXELS_PER_WIDTH`] texels of the `source` grid. The
/// excess, constant e_j over each bright texel t_j of the grid, has coefficients
/// E_lm = Σ_j e_j ∫_{t_j} Y_lm dω, and its reflection map is Σ_l k_l Σ_m E_lm Y_lm(R)
/// (Funk–Hecke): these are k_l E_lm. The texel integrals are exact in φ (∫ cos or sin mφ over a
/// column is the centre's value × Δφ · sinc(mΔφ/2)) and take [`SH_BRIGHT_Z_NODES`]
/// Gauss–Legendre nodes in z, so a lobe a few texels wide sees the texels' extent, as the zonal
/// filter's texel rule does. By the addition theorem |Σ_m Y_lm(ω) Y_lm(R)| ≤ (2l + 1)/4π, so
/// cutting at band F changes a texel by at most Σ_j e_j ΔΩ_j · Σ_{l > F} |k_l| (2l + 1)/4π: F is
/// the smallest band that keeps the second factor under u(cos θ*), what the cone of the angular
/// passes may drop per unit of energy. They are synthesized with the remainder's coefficients in
/// one pass, where a synthesis of their own, clamped at zero, doubled the maps' synthesis:
/// the clamp moved no texel by more than that bound. `None` for a narrower lobe, or when the
/// kernel has not died out by its last band (k_l is known no further), or an output `width` too
/// narrow for band F.
fn bright_harmonics(
    model: &Model,
    bright: &BrightSources,
    source: LatLong,
    kernel: &[[f64; 3]],
    width: usize,
) -> Option<ShCoeffs> {
    let truncation = radial_truncation(|x| model.lobe(x)[1], ANGULAR_EPSILON);
    if kernel.is_empty() || truncation.width < SH_BRIGHT_TEXELS_PER_WIDTH * PI / source.height as f64 {
        return None;
    }
    let dropped = model.lobe(truncation.theta_star.cos())[1];
    let per_band: Vec<f64> = kernel
        .iter()
        .enumerate()
        .map(|(l, k)| k.iter().fold(0.0f64, |m, v| m.max(v.abs())) * (2 * l + 1) as f64 / (4.0 * PI))
        .collect();
    // Bands beyond the kernel's last are taken as nothing: only when that band itself is
    // under a thousandth of the allowance.
    if per_band[per_band.len() - 1] > 1e-3 * dropped {
        return None;
    }
    let mut order = per_band.len() - 1;
    let mut tail = 0.0;
    while order > 0 && tail + per_band[order] <= dropped {
        tail += per_band[order];
        order -= 1;
    }
    if 2 * order > width.min(source.width) {
        return None;
    }
    let quadrature = TexelQuadrature::Integral { z_nodes: SH_BRIGHT_Z_NODES };
    let texels = bright.on_latlong(source);
    let coeffs = project_latlong_texels((source.width, source.height), &texels, order, quadrature).ok()?;
    Some(convolve_zonal_rgb(&coeffs, |l| kernel[l]))
}

/// The bright texels' excess as an image on the grid they were split on (black elsewhere).
fn excess_image(bright: &BrightSources, source: LatLong) -> RgbImage {
    let mut excess = RgbImage::new(source.width, source.height);
    bright.add_to_latlong(&mut excess);
    excess
}

/// [`add_bright`] for a radially symmetric lobe on a map as wide as the `source` grid the
/// texels were split on: the zonal filter of their excess, truncated at `cone`. The texel rule
/// integrates a lobe narrow against the texels over their extent (a sun's few texels under Phong
/// s = 512), chosen by measurement as the references do. False, leaving `map` alone, beyond the
/// filter's size bound.
fn add_bright_zonal(map: &mut RgbImage, model: &Model, bright: &BrightSources, source: LatLong, cone: f64) -> bool {
    let excess = excess_image(bright, source);
    let kernel = |x: f64| model.lobe(x)[1];
    let rule = rule_for_kernel(source.width, source.height, &kernel, cone, map.height, RULE_TOLERANCE).rule;
    let Ok(filtered) = zonal_filter(&excess, kernel, cone, &rule, map.height, Rows::Lit, &NoProgress) else {
        return false;
    };
    for (px, f) in map.pixels.iter_mut().zip(&filtered.pixels) {
        for c in 0..3 {
            px[c] += f[c] as f32;
        }
    }
    true
}

/// Adds the bright texels to a local SHRM of a view-dependent BRDF: per texel R,
/// B_pq(R) += Σ_j e_j ΔΩ_j T_pq(R⁻¹ω_j) with T_pq(ω_i) = ∫ ρ̂(ω_i, ω_o) Y_pq(ω_o) dω_o, the
/// BRDF's view-basis projection (isotropy: T_p|q| depends on θ_i only, times cos/sin qφ_i).
fn add_bright_to_shrm(shrm: &mut Shrm, model: &Model, bright: &BrightSources, progress: &dyn Progress) {
    let table = ViewProjection::new(model, shrm.p_b);
    let (w, h, n) = (shrm.width(), shrm.height(), crate::sh::count(shrm.p_b));
    let energy: Vec<[f64; 3]> = bright.texels.iter().map(|b| b.excess.map(|e| e * b.solid_angle)).collect();
    progress.start("bright", h as u64);
    let rows: Vec<Vec<[f32; 3]>> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut out = vec![[0.0f32; 3]; n * w];
            let mut t = vec![0.0; n];
            // Per channel, one accumulator per layer: contiguous, so the sums vectorize.
            let mut acc = [vec![0.0f64; n], vec![0.0f64; n], vec![0.0f64; n]];
            for x in 0..w {
                let to_local = texel_frame(w, h, x, y).transpose();
                acc.iter_mut().for_each(|a| a.fill(0.0));
                for (b, e) in bright.texels.iter().zip(&energy) {
                    let local = to_local * b.dir;
                    if local.z < table.cull_cos {
                        continue;
                    }
                    table.eval(local, &mut t);
                    for (a, e) in acc.iter_mut().zip(e) {
                        for (a, tv) in a.iter_mut().zip(&t) {
                            *a += tv * e;
                        }
                    }
                }
                for i in 0..n {
                    out[i * w + x] = [acc[0][i] as f32, acc[1][i] as f32, acc[2][i] as f32];
                }
            }
            progress.advance(1);
            out
        })
        .collect();
    progress.finish();
    for (y, row) in rows.iter().enumerate() {
        for (i, layer) in shrm.layers.iter_mut().enumerate() {
            for x in 0..w {
                let px = &mut layer.pixels[y * w + x];
                for c in 0..3 {
                    px[c] += row[i * w + x][c];
                }
            }
        }
    }
}

/// T_p|q|(θ_i) = ∫ ρ̂(θ_i, φ_i = 0; ω_o) Y_p|q|(ω_o) dω_o tabulated in cos θ_i; the full
/// T_pq(θ_i, φ_i) is T_p|q|(θ_i) cos(qφ_i) for q ≥ 0 and T_p|q|(θ_i) sin(|q|φ_i) for q < 0
/// (rotating ω_i about R by φ_i rotates the view basis: real SH of order q pick up cos/sin qφ).
struct ViewProjection {
    p: usize,
    bins: usize,
    /// T_p|q| at [bin · (P+1)² + p(p+1)+q] for every q (±q alike, so a bin is read as one
    /// contiguous row), bins uniform in cos θ_i ∈ [min_cos, 1].
    values: Vec<f64>,
    min_cos: f64,
    /// Bright texels below this cos θ_i are skipped: the table's largest entry per bin, summed
    /// over the bins below it, is at most [`ANGULAR_EPSILON`] of its sum over all bins (the
    /// share of the lobe the angular passes' cones leave out). Torrance-Sparrow σ = 0.25 falls
    /// from 10⁻⁵ of its peak at cos θ_i = 0 to 10⁻¹³ at −0.8, so about half the sphere is skipped.
    cull_cos: f64,
}

impl ViewProjection {
    fn new(model: &Model, p: usize) -> Self {
        let bins = 1024;
        let min_cos = -1.0;
        let nodes = crate::quadrature::gauss_legendre_cached(96);
        let nphi = 96;
        let table = crate::sh::legendre::LegendreTable::new(p);
        let values: Vec<f64> = (0..bins)
            .into_par_iter()
            .map(|b| {
                let ci = min_cos + (1.0 - min_cos) * b as f64 / (bins - 1) as f64;
                let wi = DVec3::new((1.0 - ci * ci).max(0.0).sqrt(), 0.0, ci);
                let mut out = vec![0.0; crate::sh::count(p)];
                let mut ylm = vec![0.0; crate::sh::count(p)];
                let even = |out: Vec<f64>| -> Vec<f64> {
                    (0..crate::sh::count(p))
                        .map(|i| {
                            let (pp, q) = crate::sh::lm(i);
                            out[crate::sh::index(pp, q.abs())]
                        })
                        .collect()
                };
                for &(co, wgt) in nodes.iter() {
                    let so = (1.0 - co * co).max(0.0).sqrt();
                    for k in 0..nphi {
                        let phi = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
                        let wo = DVec3::new(so * phi.cos(), so * phi.sin(), co);
                        let rho = model.rho_hat(wi, wo)[1];
                        if rho == 0.0 {
                            continue;
                        }
                        crate::sh::basis::eval_basis_dir(&table, wo, &mut ylm);
                        let d = wgt * 2.0 * PI / nphi as f64 * rho;
                        for (o, y) in out.iter_mut().zip(&ylm) {
                            *o += d * y;
                        }
                    }
                }
                even(out)
            })
            .flatten()
            .collect();
        let n = crate::sh::count(p);
        let largest: Vec<f64> = values.chunks(n).map(|row| row.iter().fold(0.0, |a: f64, v| a.max(v.abs()))).collect();
        let total: f64 = largest.iter().sum();
        let mut below = 0.0;
        let skipped = largest.iter().take_while(|&&m| {
            below += m;
            below <= ANGULAR_EPSILON * total
        });
        // A pair between the last negligible bin and the next reads both: the cut is at the
        // last negligible one.
        let first = skipped.count().saturating_sub(1);
        let cull_cos = min_cos + (1.0 - min_cos) * first as f64 / (bins - 1) as f64;
        ViewProjection { p, bins, values, min_cos, cull_cos }
    }

    /// T_pq at local direction `l` into `out` (index p(p+1)+q), linear in cos θ_i. cos qφ and
    /// sin qφ come from cos φ and sin φ by the angle-addition recurrence, not from 2P
    /// trigonometric calls: this runs once per (SHRM texel, bright texel) pair, and with the
    /// calls it was most of an SHRM file's time (sky 512×256 with 1 263 bright texels, σ = 0.25,
    /// `--size 256x128`: 14.9 s with them, 4.8 s without, the same file to the bit).
    fn eval(&self, l: DVec3, out: &mut [f64]) {
        let f =
            ((l.z - self.min_cos) / (1.0 - self.min_cos) * (self.bins - 1) as f64).clamp(0.0, (self.bins - 1) as f64);
        let (b0, t) = (f.floor() as usize, f - f.floor());
        let b1 = (b0 + 1).min(self.bins - 1);
        // The azimuthal factor of each index first; φ = 0 on the poles, as `sphere::phi` has it.
        let r = (l.x * l.x + l.y * l.y).sqrt();
        let (cos_phi, sin_phi) = if r > 0.0 { (l.x / r, l.y / r) } else { (1.0, 0.0) };
        let (mut cos_q, mut sin_q) = (1.0, 0.0);
        for q in 0..=self.p {
            for pp in q..=self.p {
                out[crate::sh::index(pp, q as isize)] = cos_q;
                if q > 0 {
                    out[crate::sh::index(pp, -(q as isize))] = sin_q;
                }
            }
            (cos_q, sin_q) = (cos_q * cos_phi - sin_q * sin_phi, sin_q * cos_phi + cos_q * sin_phi);
        }
        let n = out.len();
        let (row0, row1) = (&self.values[b0 * n..(b0 + 1) * n], &self.values[b1 * n..(b1 + 1) * n]);
        for ((o, v0), v1) in out.iter_mut().zip(row0).zip(row1) {
            *o *= (1.0 - t) * v0 + t * v1;
        }
    }
}

/// The map as lat-long ([`as_latlong`]) split into its clipped remainder and bright texels.
fn split_latlong(map: &EnvMap, rule: BrightRule) -> Result<(EnvMap, BrightSources), PrefilterError> {
    if map.layout() == Layout::LatLong {
        // The split's remainder is the one copy of the map.
        return Ok(split(map, rule));
    }
    let latlong = as_latlong(map).map_err(|e| PrefilterError::Resample(e.to_string()))?;
    Ok(split(&latlong, rule))
}

/// The angular passes integrate lat-long maps: other layouts are resampled at a resolution that
/// keeps their texel count.
pub fn as_latlong(env: &EnvMap) -> Result<EnvMap, envmap::EnvMapError> {
    if env.layout() == Layout::LatLong {
        return Ok(env.clone());
    }
    let grid = latlong_grid(env);
    envmap::resample(env, Layout::LatLong, grid.width, grid.height, 3)
}

/// The lat-long grid [`as_latlong`] puts `env` on.
fn latlong_grid(env: &EnvMap) -> LatLong {
    if env.layout() == Layout::LatLong {
        return LatLong::new(env.image().width, env.image().height);
    }
    let s = env.max_order().max(16);
    LatLong::new(2 * s, s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::envmap::bright::BrightRule;

    /// T_pq(ω_i) = ∫ ρ̂(ω_i; R = +Z, ω_o) Y_pq(ω_o) dω_o against a brute-force midpoint sum over
    /// ω_o, and the directions the bright pass skips (cos θ_i below the cut) hold next to nothing.
    #[test]
    fn the_view_projection_is_the_lobe_projected_on_the_view_basis_and_skips_only_a_negligible_part() {
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.3").unwrap(), true).unwrap();
        let p = 3;
        let n = crate::sh::count(p);
        let table = ViewProjection::new(&model, p);
        let basis = crate::sh::legendre::LegendreTable::new(p);
        let brute = |wi: DVec3| {
            let (rows, cols) = (300, 600);
            let (mut sum, mut y) = (vec![0.0; n], vec![0.0; n]);
            for a in 0..rows {
                let z = 1.0 - 2.0 * (a as f64 + 0.5) / rows as f64;
                let s = (1.0 - z * z).sqrt();
                for b in 0..cols {
                    let phi = 2.0 * PI * (b as f64 + 0.5) / cols as f64;
                    let wo = DVec3::new(s * phi.cos(), s * phi.sin(), z);
                    let rho = model.rho_hat(wi, wo)[1];
                    crate::sh::basis::eval_basis_dir(&basis, wo, &mut y);
                    for (o, v) in sum.iter_mut().zip(&y) {
                        *o += rho * v * 4.0 * PI / (rows * cols) as f64;
                    }
                }
            }
            sum
        };
        let peak = brute(DVec3::Z).iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let mut got = vec![0.0; n];
        for (cos_i, phi) in [(0.95f64, 0.4f64), (0.6, 2.5), (0.1, -1.2)] {
            let s = (1.0 - cos_i * cos_i).sqrt();
            let wi = DVec3::new(s * phi.cos(), s * phi.sin(), cos_i);
            table.eval(wi, &mut got);
            for (i, (g, w)) in got.iter().zip(brute(wi)).enumerate() {
                assert!((g - w).abs() <= 2e-3 * peak, "cos θ_i {cos_i}, index {i}: {g} against {w} (peak {peak})");
            }
        }
        assert!(table.cull_cos > -1.0 && table.cull_cos < 0.5, "cut at {}", table.cull_cos);
        let below = table.cull_cos - 0.05;
        let wi = DVec3::new((1.0 - below * below).sqrt(), 0.0, below);
        let skipped = brute(wi).iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(skipped <= 1e-4 * peak, "skipped {skipped} against peak {peak}");
    }

    /// The view projection's azimuthal factors by recurrence are cos qφ and sin |q|φ of the
    /// direction's own φ: against the trigonometric calls, on either side of φ = π and at a
    /// pole (φ = 0 there).
    #[test]
    fn the_view_projection_turns_with_the_azimuth() {
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.3").unwrap(), true).unwrap();
        let p = 5;
        let table = ViewProjection::new(&model, p);
        let mut got = vec![0.0; crate::sh::count(p)];
        let mut flat = vec![0.0; crate::sh::count(p)];
        for l in [DVec3::new(0.3, 0.4, 0.6), DVec3::new(-0.7, 0.1, -0.2), DVec3::new(-0.5, -0.6, 0.1), DVec3::Z] {
            let l = l.normalize();
            table.eval(l, &mut got);
            // φ = 0 gives the table's own values, T_p|q|(θ_i) for q ≥ 0.
            let r = l.x.hypot(l.y);
            table.eval(DVec3::new(r, 0.0, l.z), &mut flat);
            let phi = crate::sphere::phi(l);
            for pp in 0..=p {
                for q in -(pp as isize)..=(pp as isize) {
                    let base = flat[crate::sh::index(pp, q.abs())];
                    let a = q.unsigned_abs() as f64 * phi;
                    let want = if q >= 0 { base * a.cos() } else { base * a.sin() };
                    let g = got[crate::sh::index(pp, q)];
                    assert!((g - want).abs() <= 1e-12 * (1.0 + base.abs()), "{l}: ({pp}, {q}) {g} against {want}");
                }
            }
        }
    }

    /// A dim sky with a small sun on coarse texels (5.6°), 64×32.
    fn sunlit_sky() -> RgbImage {
        let grid = LatLong::new(64, 32);
        let sun = DVec3::new(0.6, 0.2, 0.5).normalize();
        RgbImage::from_fn(64, 32, |x, y| {
            let d = grid.texel_direction(x, y);
            let v = if d.dot(sun) > 0.995 { 5000.0 } else { 1.0 + 0.5 * d.z as f32 };
            [v, 0.5 * v, 0.25 * v]
        })
    }

    /// [`sunlit_sky`]'s grid and bright texels.
    fn sky_with_sun() -> (LatLong, BrightSources) {
        let grid = LatLong::new(64, 32);
        let (_, bright) = split(&EnvMap::latlong(sunlit_sky()).unwrap(), BrightRule::Auto);
        assert!(!bright.is_empty() && bright.texels.len() < 20, "{} bright texels", bright.texels.len());
        (grid, bright)
    }

    /// Every bright texel's integral of the lobe by a 32 × 32 midpoint rule in (z, φ), summed
    /// per texel of `grid` over the bright texels whose centres are within θ* (π: all).
    fn brute_force(grid: LatLong, model: &Model, bright: &BrightSources, theta_star: f64) -> Vec<[f64; 3]> {
        brute_force_lobe(grid, bright, theta_star, |r, w| model.lobe(r.dot(w))[1])
    }

    /// [`brute_force`] for any lobe `rho(R, ω)` (green channel).
    fn brute_force_lobe(
        grid: LatLong,
        bright: &BrightSources,
        theta_star: f64,
        rho: impl Fn(DVec3, DVec3) -> f64,
    ) -> Vec<[f64; 3]> {
        let (w, h, n) = (grid.width, grid.height, 32);
        let cos_star = theta_star.cos();
        (0..w * h)
            .map(|i| {
                let r = grid.texel_direction(i % w, i / w);
                let mut acc = [0.0; 3];
                for t in bright.texels.iter().filter(|t| theta_star >= PI || r.dot(t.dir) >= cos_star) {
                    let (px, py) = grid.position(t.dir);
                    let (x, y) = (px.floor(), py.floor());
                    let (z0, z1) = ((PI * y / h as f64).cos(), (PI * (y + 1.0) / h as f64).cos());
                    let mut integral = 0.0;
                    for j in 0..n {
                        for k in 0..n {
                            let z = z0 + (z1 - z0) * (j as f64 + 0.5) / n as f64;
                            let phi = 2.0 * PI * (x + (k as f64 + 0.5) / n as f64) / w as f64;
                            let weight = (z0 - z1) / n as f64 * 2.0 * PI / w as f64 / n as f64;
                            integral += weight * rho(r, crate::sphere::direction(z.acos(), phi));
                        }
                    }
                    // The texel's excess radiance: t.excess·ΔΩ_t is its energy.
                    let scale = t.solid_angle / grid.row_solid_angle(y as usize);
                    for c in 0..3 {
                        acc[c] += t.excess[c] * scale * integral;
                    }
                }
                acc
            })
            .collect()
    }

    /// Within `relative` of `expected` plus `absolute` (per channel).
    fn assert_close(spec: &str, got: &RgbImage, expected: &[[f64; 3]], relative: f64, absolute: [f64; 3]) {
        assert!(expected.iter().any(|p| p[0] > 0.0));
        for (i, (a, b)) in got.pixels.iter().zip(expected).enumerate() {
            for c in 0..3 {
                let a = a[c] as f64;
                assert!(
                    (a - b[c]).abs() <= relative * b[c].abs() + absolute[c],
                    "{spec}, texel {i} channel {c}: {a} against {}",
                    b[c]
                );
            }
        }
    }

    #[test]
    fn bright_texels_through_the_zonal_filter_are_their_texel_integrals() {
        // The zonal path's excess, filtered with a measured texel rule, against the brute-force
        // texel integrals in the same cone (an empty kernel keeps the harmonics out).
        let (grid, bright) = sky_with_sun();
        for spec in ["phong:s=8", "phong:s=128"] {
            let model = Model::new(Brdf::parse(spec).unwrap(), true).unwrap();
            let mut zonal = RgbImage::new(64, 32);
            add_bright(&mut zonal, &model, &bright, Some(grid), Lobe::Radial);
            let theta_star = radial_cutoff(|x| model.lobe(x)[1], ANGULAR_EPSILON);
            let expected = brute_force(grid, &model, &bright, theta_star);
            let peak = expected.iter().map(|p| p[0]).fold(0.0, f64::max);
            assert_close(spec, &zonal, &expected, 3e-3, [1e-5 * peak; 3]);
        }
    }

    #[test]
    fn bright_texels_through_harmonics_are_their_texel_integrals() {
        // Lobes 8.5 and 4.3 texels wide (√(2π/(s+1)) against 5.6° texels): the harmonics take
        // the first and leave the second to the zonal filter. Against the whole lobe's texel
        // integrals (no cone): the cut at band F may differ from them by its bound, what the
        // cone may drop per unit of bright energy times that energy.
        let (grid, bright) = sky_with_sun();
        for (spec, wide) in [("phong:s=8", true), ("phong:s=32", false)] {
            let model = Model::new(Brdf::parse(spec).unwrap(), true).unwrap();
            let coefficients = model.coefficients(31, 0);
            let kernel: Vec<[f64; 3]> = (0..=31).map(|l| coefficients.radial_kernel(l)).collect();
            let theta_star = radial_cutoff(|x| model.lobe(x)[1], ANGULAR_EPSILON);
            let dropped = model.lobe(theta_star.cos())[1];
            let harmonics = bright_harmonics(&model, &bright, grid, &kernel, 64);
            assert_eq!(harmonics.is_some(), wide, "{spec}");
            if let Some(coeffs) = harmonics {
                let map = crate::sh::synth::synthesize_latlong(&coeffs, 64, 32).unwrap();
                let energy = [0, 1, 2].map(|c| bright.texels.iter().map(|t| t.excess[c] * t.solid_angle).sum::<f64>());
                let bound = energy.map(|e| dropped * e);
                // The cut series may dip below zero by no more than its bound.
                for p in &map.pixels {
                    for c in 0..3 {
                        assert!(p[c] as f64 >= -bound[c], "{spec}: {} below −{}", p[c], bound[c]);
                    }
                }
                assert_close(spec, &map, &brute_force(grid, &model, &bright, PI), 1e-3, bound);
                // Cut before the kernel has died out, the path declines: k_l is not known further.
                assert!(bright_harmonics(&model, &bright, grid, &kernel[..8], 64).is_none());
            }
        }
    }

    #[test]
    fn bright_texels_splatted_in_the_view_frame_are_their_texel_integrals() {
        // Only the sun (a black remainder): the view-frame integral of its splatted energy
        // against each bright texel's brute-force integral of the view-dependent lobe, for a
        // view at the pole and a tilted one (rotated into the frame).
        let (grid, bright) = sky_with_sun();
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.3").unwrap(), true).unwrap();
        let black = EnvMap::latlong(RgbImage::new(grid.width, grid.height)).unwrap();
        let pyramid = ConePyramid::new(&black).unwrap();
        let cutoff = CutoffTable::of_model(&model, ANGULAR_EPSILON, 65);
        for view in [DVec3::Z, DVec3::new(0.3, -0.5, 0.8).normalize()] {
            let got = view_axis::beyond(&pyramid, &model, &cutoff, view, 0.0, grid, Some((&bright, grid)));
            assert_eq!(got.len(), grid.width * grid.height);
            let expected = brute_force_lobe(grid, &bright, PI, |r, w| {
                model.prepare_view(r, view).map_or(0.0, |p| model.rho_hat_prepared(&p, w)[1])
            });
            let peak = expected.iter().map(|p| p[1]).fold(0.0, f64::max);
            let mut worst = 0.0f64;
            for &(i, v) in &got {
                let (a, b) = (v[1] as f64, expected[i][1]);
                if b > 0.05 * peak {
                    worst = worst.max((a - b).abs() / b);
                }
            }
            assert!(worst < 0.05, "view {view}: worst relative error {worst} over texels ≥ 5 % of the peak");
        }
    }

    /// A lobe narrow against the lighting's texels (Phong s = 512, about one 5.6° texel wide)
    /// takes the zonal filter of the whole map, a wide one (s = 8, 8.5 texels) the SHRM, as do
    /// fixed orders, the energy rule and an output of another width. The map in angle is the
    /// brute-force sum over every texel of its 16 × 16-node integral of the lobe, within the
    /// texel rule's tolerance plus the cone's 10⁻⁵, for every view.
    #[test]
    fn a_lobe_narrow_against_the_texels_is_filtered_in_angle_whole() {
        let image = sunlit_sky();
        let map = EnvMap::latlong(image.clone()).unwrap();
        let settings = Settings {
            epsilon: 0.01,
            rule: OrderRule::Texel,
            orders: None,
            max_p: 6,
            bright: BrightRule::Auto,
            window: Window::Nonneg,
            size: None,
        };
        let sharp = Model::new(Brdf::parse("phong:s=512").unwrap(), true).unwrap();
        let wide = Model::new(Brdf::parse("phong:s=8").unwrap(), true).unwrap();
        assert!(maps_in_angle(&sharp, &settings, &map));
        assert!(maps_in_angle(&sharp, &Settings { size: Some((64, 48)), ..settings }, &map));
        assert!(!maps_in_angle(&wide, &settings, &map));
        assert!(!maps_in_angle(&sharp, &Settings { size: Some((128, 64)), ..settings }, &map));
        assert!(!maps_in_angle(&sharp, &Settings { rule: OrderRule::Energy, ..settings }, &map));
        assert!(!maps_in_angle(&sharp, &Settings { orders: Some((20, 0)), ..settings }, &map));

        let views = [DVec3::Z, DVec3::new(1.0, 0.0, 0.2).normalize()];
        let done = angle_maps(&sharp, &map, &views, BrightRule::Auto, None, &NoProgress).unwrap();
        assert_eq!((done.size, done.report.maps, done.maps.len()), ((64, 32), MapsFrom::Angle, 2));
        assert_eq!(done.maps[0], done.maps[1], "a radially symmetric lobe ignores the view");
        assert_eq!(done.report.bright.energy_fraction, 1.0);
        let kernel = |x: f64| sharp.lobe(x)[1];
        let expected = crate::envmap::zonal::zonal_filter_reference(
            &image,
            kernel,
            PI,
            &crate::envmap::zonal::TexelRule::new(16).unwrap(),
            32,
        )
        .unwrap();
        // The rule misplaces at most 10⁻³ of the lobe's weight over its probe texels; one texel
        // of a lobe a texel wide errs by a few times that (0.32 % here).
        let peak = expected.pixels.iter().map(|p| p[0]).fold(0.0, f64::max);
        for (got, want) in done.maps[0].pixels.iter().zip(&expected.pixels) {
            for c in 0..3 {
                let (a, b) = (got[c] as f64, want[c]);
                let (error, allowed) =
                    if b > 0.01 * peak { ((a - b).abs() / b, 5e-3) } else { ((a - b).abs() / peak, 2e-4) };
                assert!(error <= allowed, "{got:?} vs {want:?}: {error}");
            }
        }
    }
}
