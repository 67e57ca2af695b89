//! Reflection maps with every texel integrated in angle (`docs/prefilter.md`, "Maps in angle"):
//! no spherical harmonics, so nothing rings and nothing is windowed. The default bake takes this
//! path where frequency space is the dearer one:
//!
//! - **a view-dependent BRDF.** Per view, the whole map in the view's frame with the bright
//!   texels splatted into it ([`view_frame_maps`]) costs less than the SHRM path's own per-view
//!   work (its bright texels pair by pair and its fallback for grazing texels), before the SHRM's
//!   one-off cost (`docs/prefilter.md`, "Maps in angle");
//! - **a radially symmetric lobe narrow against the lighting's texels**
//!   ([`tuning::NARROW_LOBE_TEXELS`]), on an output grid as wide as the lighting's
//!   ([`zonal_maps`]). R&H §6.3: the frequency-space cost grows with the Phong exponent
//!   (F_B ~ √s, and (F_B + 1)² coefficients) while the angular cost falls with it (the cone's
//!   area ~ 1/s), so past some s* angle is the cheaper; the threshold is that crossover.

use super::angular::{as_latlong, latlong_grid, ConePyramid};
use super::bright_pass::BrightPass;
use super::model::Model;
use super::orders::OrderRule;
use super::pipeline::{Lighting, PrefilterError};
use super::ring_free::{MapsFrom, Report, Settings};
use super::truncation::{radial_cutoff, radial_truncation, CutoffTable};
use super::tuning::{self, ANGULAR_EPSILON, CUTOFF_BINS, RULE_TOLERANCE};
use super::view_axis;
use crate::envmap::bright::{BrightReport, BrightRule};
use crate::envmap::zonal::{rule_for_kernel, zonal_filter, Rows};
use crate::envmap::EnvMap;
use crate::io::RgbImage;
use crate::limits::MAX_ZONAL_TEXELS;
use crate::progress::Progress;
use crate::sh::window::{Window, WindowReport};
use crate::sphere::LatLong;
use glam::DVec3;

/// True when the bake's settings and lobe call for maps in angle under `map`: the texel rule
/// chooses the orders (fixed orders and the energy rule are asked for an expansion), and the
/// BRDF is view-dependent or its radially symmetric lobe is narrow against `map`'s lat-long
/// texels. Whether an output grid allows it is [`fits`].
pub fn prefers_angle(model: &Model, settings: &Settings, map: &EnvMap) -> bool {
    if settings.orders.is_some() || settings.rule != OrderRule::Texel {
        return false;
    }
    match model.centre() {
        None => true,
        Some(_) => {
            let width = radial_truncation(|x| model.lobe(x)[1], ANGULAR_EPSILON).width;
            tuning::is_narrow(width, latlong_grid(map).height)
        }
    }
}

/// True when the maps in angle can be made on an output grid of `size` (`None`: the lighting's
/// own): any grid for a view-dependent BRDF; for a radially symmetric lobe, whose zonal filter
/// keeps the lighting's width (its shift invariance in φ), a grid as wide as the lighting's
/// lat-long grid, within the filter's size bound.
pub fn fits(model: &Model, map: &EnvMap, size: Option<(usize, usize)>) -> bool {
    if model.centre().is_none() {
        return true;
    }
    let grid = latlong_grid(map);
    let (width, height) = size.unwrap_or((grid.width, grid.height));
    width == grid.width
        && [grid.height, height].iter().all(|h| width.checked_mul(*h).is_some_and(|n| n <= MAX_ZONAL_TEXELS))
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

/// Reflection maps with every texel in angle, when [`prefers_angle`] and [`fits`] say so:
/// [`zonal_maps`] for a radially symmetric lobe, [`view_frame_maps`] for a view-dependent one.
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
/// over the texels whose centres lie in its lobe's cone (1 − [`ANGULAR_EPSILON`] of the lobe) of
/// their exact integrals of it ([`RULE_TOLERANCE`]). No split: every texel, the sun's too, takes
/// the same exact path. The output is the lighting's width and `size`'s height, or the
/// lighting's.
fn zonal_maps(
    model: &Model,
    map: &EnvMap,
    views: &[DVec3],
    size: Option<(usize, usize)>,
    progress: &dyn Progress,
) -> Result<InAngle, PrefilterError> {
    let latlong = as_latlong(map).map_err(PrefilterError::Resample)?;
    let image = latlong.image();
    let height = size.map_or(image.height, |(_, h)| h);
    let kernel = |x: f64| model.lobe(x)[1];
    let cone = radial_cutoff(kernel, ANGULAR_EPSILON);
    let rule = rule_for_kernel(image.width, image.height, &kernel, cone, height, RULE_TOLERANCE).rule;
    let filtered = zonal_filter(image, kernel, cone, &rule, height, Rows::Lit, progress)
        .map_err(|e| PrefilterError::Angular(e.into()))?;
    let reflected = filtered.to_image();
    // Every texel went through angle.
    let all = BrightReport { threshold: None, texels: image.pixels.len(), energy_fraction: 1.0, squared_fraction: 1.0 };
    Ok(InAngle { maps: vec![reflected; views.len()], size: (image.width, height), report: in_angle_report(all) })
}

/// Reflection maps of a view-dependent BRDF with every texel in angle: the view-frame integral
/// ([`view_axis::integrate_in_view_frame`]) over the whole map, of the remainder and of the
/// bright texels' excess splatted into it as energy ([`BrightPass::splat`]). The grid is the
/// lighting's own lat-long grid unless `size` is given (there is no F_B to size it by, as for
/// the angular reference).
fn view_frame_maps(
    model: &Model,
    map: &EnvMap,
    views: &[DVec3],
    bright_rule: BrightRule,
    size: Option<(usize, usize)>,
) -> Result<InAngle, PrefilterError> {
    let (remainder, bright) = BrightPass::split(Lighting::Map(map), bright_rule)?;
    let remainder = remainder.expect("a map splits into a remainder map");
    let (w, h) = size.unwrap_or((remainder.image().width, remainder.image().height));
    let grid = LatLong::new(w, h);
    let cone = ConePyramid::new(&remainder)?;
    let cutoff = CutoffTable::of_model(model, ANGULAR_EPSILON, CUTOFF_BINS);
    let maps = views
        .iter()
        .map(|&view| {
            let mut out = RgbImage::new(w, h);
            for (i, v) in view_axis::integrate_in_view_frame(&cone, model, &cutoff, view, 0.0, grid, Some(&bright)) {
                out.pixels[i] = v;
            }
            out
        })
        .collect();
    Ok(InAngle { maps, size: (w, h), report: in_angle_report(bright.report()) })
}

/// The document's report of maps in angle: no orders, no window, `bright` through angle.
fn in_angle_report(bright: BrightReport) -> Report {
    Report {
        maps: MapsFrom::Angle,
        rule: "none".into(),
        texel: None,
        bright,
        window: WindowReport { kind: Window::None, t: None },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::prefilter::bright_pass::tests::sunlit_sky;
    use crate::progress::NoProgress;
    use crate::sh::window::Window;
    use std::f64::consts::PI;

    fn maps_in_angle(model: &Model, settings: &Settings, map: &EnvMap) -> bool {
        prefers_angle(model, settings, map) && fits(model, map, settings.size)
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
