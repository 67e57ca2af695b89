//! The ring-free bake (`docs/prefilter.md`, "Ring-free bakes"): frequency space where it is
//! exact and cheap, angle where it is not.
//!
//! 1. **Bright sources apart** ([`super::bright_pass`]): the excess of compact, very bright
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
//! Where every texel of the maps is better integrated in angle, the bake skips 2–4
//! ([`super::in_angle`]).
//!
//! The SHRM itself holds the remainder's expansion plus, for radially symmetric BRDFs, the bright
//! part (its single layer is a reflection map); for view-dependent BRDFs the bright part is
//! projected onto the view basis texel by texel (exact in angle, truncated at P_B like the rest).

use super::angular::ConePyramid;
use super::brdf_sh::BrdfSh;
use super::bright_pass::{BrightPass, Lobe};
use super::model::Model;
use super::orders::{first_projection, texel_orders, LightEnergy, OrderRule, TexelOrders};
use super::pipeline::{brdf_coefficients, default_size, Lighting, Orders, PrefilterError};
use super::shrm::{self, Shrm, ShrmError};
use super::truncation::CutoffTable;
use super::tuning::{ANGULAR_EPSILON, CUTOFF_BINS, MAX_TEXEL_ORDER};
use super::view_axis;
use crate::envmap::bright::{BrightReport, BrightRule};
use crate::envmap::EnvMap;
use crate::io::RgbImage;
use crate::progress::Progress;
use crate::sh::project::{map_energy_rgb, map_integral_rgb, project};
use crate::sh::window::{self, Window, WindowReport};
use crate::sh::ShCoeffs;
use crate::sphere::LatLong;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

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
    /// Every texel in angle ([`super::in_angle`]).
    Angle,
}

/// A ring-free prefiltered lighting: everything reflection maps and the SHRM file are made of.
pub struct Prefiltered {
    /// ρ̂_lpq truncated to (F_B, P_B).
    pub brdf: BrdfSh,
    /// The remainder's lighting coefficients to F_B (raw, before the window).
    pub lighting: ShCoeffs,
    /// The local SHRM of the remainder (windowed), plus the bright texels when they went
    /// through spherical harmonics ([`BrightPass::harmonics`]).
    pub remainder_shrm: Shrm,
    /// The bright texels and how they are filtered.
    pub bright: BrightPass,
    /// The lat-long remainder (bright sources clipped) for the angular fallback, when the
    /// lighting was a map.
    pub remainder_map: Option<EnvMap>,
    /// What was done.
    pub report: Report,
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
    let (remainder, mut bright) = BrightPass::split(lighting, settings.bright)?;
    // The lighting as far as the rule asked for it (the texel rule projects it itself).
    let mut light = match (&remainder, lighting, settings.orders) {
        (Some(rest), _, Some((f, _))) => Some(project(rest, f, progress)?),
        (None, Lighting::Coefficients(c), _) => Some(c.clone()),
        _ => None,
    };
    let (brdf, kernel, texel) = match (settings.orders, settings.rule) {
        (Some((f, p)), _) => (brdf_coefficients(model, Orders::Fixed { f, p })?, Vec::new(), None),
        (None, OrderRule::Energy) => {
            let orders = Orders::Epsilon { epsilon: settings.epsilon, max_p: max_p(model, settings) };
            (brdf_coefficients(model, orders)?, Vec::new(), None)
        }
        (None, OrderRule::Texel) => {
            let chosen = TexelRule { model, lighting, remainder: remainder.as_ref(), bright: &bright, settings };
            let (brdf, kernel, orders) = chosen.orders(&mut light, progress)?;
            (brdf, kernel, Some(orders))
        }
    };
    let f_b = brdf.f;
    let kernel = if radial && kernel.is_empty() { (0..=f_b).map(|l| brdf.radial_kernel(l)).collect() } else { kernel };
    let light = lighting_to(f_b, remainder.as_ref(), lighting, light, progress)?;
    let (width, height) = settings.size.unwrap_or_else(|| default_size(f_b));
    if width < 2 * f_b + 2 {
        return Err(ShrmError::TooSmall { width, f_b, need: 2 * f_b + 2 }.into());
    }
    if radial {
        bright.through_harmonics(model, &kernel, width);
    }
    let factors = settings.window.factors(f_b);
    let remainder_shrm = remainder_shrm(model, &brdf, &light, &factors, bright.harmonics(), (width, height), progress)?;
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
    Ok(Prefiltered { brdf, lighting: light, remainder_shrm, bright, remainder_map: remainder, report })
}

/// The largest P_B the orders may take: 0 for a radially symmetric BRDF.
fn max_p(model: &Model, settings: &Settings) -> usize {
    if model.centre().is_some() {
        0
    } else {
        settings.max_p
    }
}

/// The remainder's lighting to F_B: `light` as far as the order rule projected it (or the given
/// coefficients), cut to F_B or projected further.
fn lighting_to(
    f_b: usize,
    remainder: Option<&EnvMap>,
    lighting: Lighting<'_>,
    light: Option<ShCoeffs>,
    progress: &dyn Progress,
) -> Result<ShCoeffs, PrefilterError> {
    Ok(match (remainder, lighting, light) {
        (_, Lighting::Coefficients(c), _) if c.order < f_b => {
            return Err(PrefilterError::LightingOrder { have: c.order, need: f_b })
        }
        (Some(rest), _, Some(l)) if l.order < f_b => project(rest, f_b, progress)?,
        (_, _, Some(l)) => l.truncated(f_b),
        (Some(rest), _, None) => project(rest, f_b, progress)?,
        (None, _, None) => unreachable!("coefficients are given when there is no map"),
    })
}

/// The texel rule's inputs ([`super::orders`]): the lighting (its remainder when it was a map)
/// and the bright texels, whose energy counts in the mean the texel floor is a fraction of.
struct TexelRule<'a> {
    model: &'a Model,
    lighting: Lighting<'a>,
    remainder: Option<&'a EnvMap>,
    bright: &'a BrightPass,
    settings: &'a Settings,
}

impl TexelRule<'_> {
    /// ρ̂_lpq cut to the orders the rule chose, the radially symmetric lobe's zonal kernel k_l to
    /// the highest band it computed (l_max; empty otherwise), and the orders with their
    /// guarantee. `light` is left holding the lighting as far as the rule projected it.
    fn orders(
        &self,
        light: &mut Option<ShCoeffs>,
        progress: &dyn Progress,
    ) -> Result<(BrdfSh, Vec<[f64; 3]>, TexelOrders), PrefilterError> {
        let (model, settings) = (self.model, self.settings);
        let max_p = max_p(model, settings);
        let l_max = match (self.remainder, &*light) {
            // The output grid holds bands up to (W − 2)/2 (synthesis needs W ≥ 2F + 2).
            (Some(rest), _) => {
                resolvable_order(rest).min(settings.size.map_or(usize::MAX, |(w, _)| w.saturating_sub(2) / 2))
            }
            (None, Some(c)) => c.order,
            (None, None) => unreachable!("coefficients are given when there is no map"),
        };
        let full = model.coefficients(l_max, max_p);
        let kernel = match model.centre() {
            Some(_) => (0..=l_max).map(|l| full.radial_kernel(l)).collect(),
            None => Vec::new(),
        };
        let orders = match (self.remainder, &*light) {
            (Some(rest), _) => {
                let (orders, projected) = self.projected_far_enough(&full, rest, l_max, progress)?;
                *light = Some(projected);
                orders
            }
            (None, Some(c)) => self
                .rule(&full, c, &LightEnergy::exact(c.band_energy_rgb()))
                .expect("every band known decides the orders"),
            (None, None) => unreachable!("coefficients are given when there is no map"),
        };
        if let Lighting::Coefficients(c) = self.lighting {
            // A map is cut at its own resolution, but given coefficients were cut by the
            // caller: they must at least hold what the BRDF's energy rule needs.
            let need = brdf_coefficients(model, Orders::Epsilon { epsilon: settings.epsilon, max_p })?.f;
            if c.order < need {
                return Err(PrefilterError::LightingOrder { have: c.order, need });
            }
        }
        Ok((full.truncated(orders.f_b, orders.p_b), kernel, orders))
    }

    /// The rule on the lighting `light` with band energies `energy`, against the mean
    /// reflected radiance of the whole lighting.
    fn rule(&self, full: &BrdfSh, light: &ShCoeffs, energy: &LightEnergy) -> Option<TexelOrders> {
        let mean = mean_reflected(full, light.rgb[0], self.bright);
        texel_orders(self.model, full, energy, mean, self.settings.epsilon, max_p(self.model, self.settings))
    }

    /// The remainder `rest` projected as far as the rule needs: bands beyond the first
    /// projection are bounded by the map's energy, and only when that bound decides F_B is the
    /// projection taken further (the same F_B as projecting to l_max).
    fn projected_far_enough(
        &self,
        full: &BrdfSh,
        rest: &EnvMap,
        l_max: usize,
        progress: &dyn Progress,
    ) -> Result<(TexelOrders, ShCoeffs), PrefilterError> {
        let (model, settings) = (self.model, self.settings);
        let energy = map_energy_rgb(rest);
        let l00 = map_integral_rgb(rest).map(|v| v / (4.0 * PI).sqrt());
        let mean = mean_reflected(full, l00, self.bright);
        let max_p = max_p(model, settings);
        let mut order = first_projection(model, full, max_p, l_max, energy, mean, settings.epsilon);
        loop {
            let light = project(rest, order, progress)?;
            if let Some(orders) = self.rule(full, &light, &LightEnergy::projected(&light, energy, l_max)) {
                return Ok((orders, light));
            }
            order = (2 * order).max(1).min(l_max);
        }
    }
}

/// The mean reflected radiance per channel, which the texel floor is a fraction of: band 0 of
/// the light field, ρ̂_000 L_00 Y_00 (L_00 of the whole map: the remainder's `l00` plus the
/// bright part's).
fn mean_reflected(brdf: &BrdfSh, l00: [f64; 3], bright: &BrightPass) -> [f64; 3] {
    let y00 = 1.0 / (4.0 * PI).sqrt();
    let mut l00 = l00;
    for t in &bright.sources().texels {
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
    pub fn shrm(&self, model: &Model, global: bool, progress: &dyn Progress) -> Result<Shrm, PrefilterError> {
        let mut out = self.remainder_shrm.clone();
        self.bright.add_to_shrm(&mut out, model, progress);
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
            let mut maps = shrm::maps_of_local(remainder, views);
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
        let bright = self.bright.harmonics();
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
        self.report.window.t = Some(found.t);
        found.map
    }

    /// What each view's map takes from angle: the bright texels' exact contribution, and the
    /// remainder of the texels beyond the SHRM's valid view angle, integrated in angle.
    fn angular_parts(&self, model: &Model, views: &[DVec3]) -> Result<Vec<AngularPart>, PrefilterError> {
        let (w, h) = (self.remainder_shrm.width(), self.remainder_shrm.height());
        let valid = self.report.texel.as_ref().map_or(PI, |t| t.valid_view_angle.to_radians());
        let fallback = model.centre().is_none() && valid < PI;
        let cone = self.remainder_map.as_ref().filter(|_| fallback).map(ConePyramid::new).transpose()?;
        // The view-dependent cones, when anything is summed in angle.
        let cutoff = (model.centre().is_none() && (!self.bright.sources().is_empty() || fallback))
            .then(|| CutoffTable::of_model(model, ANGULAR_EPSILON, CUTOFF_BINS));
        Ok(views
            .iter()
            .map(|&view| {
                let lobe = match &cutoff {
                    Some(cutoff) => Lobe::View(view, cutoff),
                    None => Lobe::Radial,
                };
                let added = self.bright.add_to_map(model, lobe, (w, h));
                let replaced = match (&cone, &cutoff) {
                    (Some(cone), Some(cutoff)) => {
                        view_axis::integrate_in_view_frame(cone, model, cutoff, view, valid, LatLong::new(w, h), None)
                    }
                    _ => Vec::new(),
                };
                AngularPart { added, replaced }
            })
            .collect())
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
