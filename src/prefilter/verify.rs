//! `prefilter --verify N`: every bake says how good it is without a full reference. N texels of
//! each map are checked against the angular integral `--method angular` computes (at
//! ε = [`ANGULAR_EPSILON`], the same truncation and texel rule), and the figures of [`crate::metrics`]
//! (its definitions and floor) are taken over them.
//!
//! **Which texels.** The texels where a frequency-space bake goes wrong first, chosen from the
//! bake and the environment alone, deterministically (no random numbers, no dependence on the
//! thread count), in this order:
//!
//! 1. **Beside the brightest sources** (a quarter, rounded up): up to [`VERIFY_SOURCES`] of the
//!    brightest environment texels at least a cone apart. Around each, the map texels within the
//!    lobe's cone angle θ* (the texels whose exact value sees the source), sorted by their angle
//!    from it and taken at even steps: the texel at the source's direction first, then every ring
//!    radius out to θ*, where truncated expansions ring.
//! 2. **The darkest** (a quarter, rounded up): every negative texel first (most negative first),
//!    then the darkest texels by ‖RGB‖ at or above [`metrics::TEXEL_FLOOR`] of the mean (darker
//!    ones do not count in the per-texel relative error).
//! 3. **The poles** (an eighth): evenly spaced columns of rows 0 and H − 1, where the lat-long
//!    grid is most distorted.
//! 4. **Spread evenly** (the rest): evenly spaced in row-major order among the texels not yet
//!    chosen.
//!
//! N at or above the texel count checks every texel: the figures are then the full comparison.
//! The checked set leans towards hard texels, so its p99 and relative RMS are pessimistic for
//! the map as a whole, and its maximum is a lower bound of the map's.
//!
//! **Cost.** One cone sum per checked texel (the texels of the environment within θ* of it, by
//! the reference's texel rule): for 3-D BRDFs N/(W·H) of a full `--method angular` run.

use super::model::Model;
use super::pipeline::{AngularIntegral, AngularSettings, PrefilterError};
use super::tuning::{ANGULAR_EPSILON, VERIFY_SOURCES};
use crate::envmap::bright::{luminance, MEAN_MULTIPLE};
use crate::envmap::EnvMap;
use crate::io::RgbImage;
use crate::metrics::{self, TEXEL_FLOOR};
use crate::progress::Progress;
use crate::sphere::LatLong;
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::limits::MAX_VERIFY_TEXELS;

/// Errors of the verification.
#[derive(Debug, thiserror::Error)]
pub enum VerifyError {
    /// N is 0 or above [`MAX_VERIFY_TEXELS`].
    #[error("{0} texels to check per map: must be in 1..={MAX_VERIFY_TEXELS}")]
    Texels(usize),
    /// The angular integral cannot be set up.
    #[error(transparent)]
    Angular(#[from] PrefilterError),
    /// Every exact value is zero: no relative error.
    #[error("the exact value of every checked texel of {0} is zero: relative error undefined")]
    ZeroReference(String),
}

/// What `--verify` found, for the document and `--json`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Verification {
    /// Truncation ε of the angular integral ([`ANGULAR_EPSILON`]).
    pub epsilon: f64,
    /// Sub-samples per texel axis of its texel integrals.
    pub subsamples: usize,
    /// Texels asked for per map (N).
    pub requested: usize,
    /// One entry per map checked, in the order the maps are written.
    pub maps: Vec<MapVerification>,
}

/// The figures of one map over its checked texels ([`metrics::Metrics`]' definitions).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MapVerification {
    /// The map's file (`irradiance` for the irradiance map).
    pub map: String,
    /// Texels checked.
    pub texels: usize,
    /// How many of each kind were chosen.
    pub selection: Selection,
    /// Checked texels with a negative channel.
    pub negative: usize,
    /// ‖a − r‖₂/‖r‖₂ over the checked texels.
    pub rel_error: f64,
    /// 99th percentile of ‖a − r‖/‖r‖ over the checked texels at or above 1 % of their mean
    /// ‖r‖ (the largest below 100 such texels).
    pub p99_texel_error: f64,
    /// The largest of those.
    pub max_texel_error: f64,
    /// Where it is.
    pub worst: WorstTexel,
}

/// How many texels of each kind were checked.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq)]
pub struct Selection {
    /// Beside the brightest sources.
    pub bright: usize,
    /// The darkest (negative ones first).
    pub darkest: usize,
    /// On rows 0 and H − 1.
    pub poles: usize,
    /// Spread evenly over the rest.
    pub spread: usize,
}

/// The checked texel with the largest relative error.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct WorstTexel {
    /// Column.
    pub x: usize,
    /// Row.
    pub y: usize,
    /// The bake's value.
    pub value: [f64; 3],
    /// The angular integral's.
    pub exact: [f64; 3],
}

/// One map to check: its name, the lat-long image, the view it was made for and the factor
/// between it and the reflection integral (π/albedo for the irradiance map, else 1).
pub struct MapCheck<'a> {
    /// Name in the report.
    pub name: String,
    /// The lat-long map.
    pub image: &'a RgbImage,
    /// Its view (ignored by radially symmetric BRDFs).
    pub view: DVec3,
    /// Exact value = scale × the angular integral.
    pub scale: f64,
}

/// Chooses texels and computes their exact values for one model and environment.
pub struct Verifier<'m> {
    integral: AngularIntegral<'m>,
    radial: bool,
    sources: Vec<DVec3>,
    texels: usize,
}

impl<'m> Verifier<'m> {
    /// Checks `texels` texels per map of `height` rows (the texel rule is the one `--method
    /// angular` chooses for that height) of `model` under the lat-long `env`.
    pub fn new(model: &'m Model, env: &EnvMap, height: usize, texels: usize) -> Result<Self, VerifyError> {
        check_texels(texels)?;
        let integral = AngularIntegral::new(model, env, AngularSettings::new(ANGULAR_EPSILON), height)?;
        let sources = brightest_sources(env, integral.cone_angle());
        Ok(Verifier { integral, radial: model.centre().is_some(), sources, texels })
    }

    /// The texels to check in `map` (row-major indices, in the order of the module docs) and
    /// how many of each kind.
    pub fn choose(&self, map: &RgbImage) -> (Vec<usize>, Selection) {
        let (w, h) = (map.width, map.height);
        let grid = LatLong::new(w, h);
        let n = self.texels.min(w * h);
        let mut pick = Picker { chosen: vec![false; w * h], list: Vec::with_capacity(n), budget: n };
        let mut selection = Selection::default();

        let bright = n.div_ceil(4);
        let reach = self.integral.cone_angle().cos();
        for (k, &source) in self.sources.iter().enumerate() {
            // The share split evenly, the first sources taking the remainder.
            let share = bright / self.sources.len() + usize::from(k < bright % self.sources.len());
            let mut near: Vec<(f64, usize)> = (0..w * h)
                .map(|i| (grid.texel_direction(i % w, i / w).dot(source), i))
                .filter(|&(c, _)| c >= reach)
                .collect();
            near.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            for j in 0..share.min(near.len()) {
                selection.bright += pick.take(near[j * near.len() / share].1);
            }
        }

        let norm = |p: &[f32; 3]| p.iter().map(|&c| (c as f64).powi(2)).sum::<f64>().sqrt();
        let floor = TEXEL_FLOOR * map.pixels.iter().map(norm).sum::<f64>() / (w * h) as f64;
        // Negative texels first (by their most negative channel), then the darkest above the floor.
        let mut dark: Vec<(bool, f64, usize)> = map
            .pixels
            .iter()
            .enumerate()
            .filter_map(|(i, p)| {
                let low = p.iter().fold(f32::INFINITY, |a, &c| a.min(c)) as f64;
                match (low < 0.0, norm(p)) {
                    (true, _) => Some((false, low, i)),
                    (false, r) if r >= floor => Some((true, r, i)),
                    _ => None,
                }
            })
            .collect();
        dark.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
        let wanted = pick.list.len() + n.div_ceil(4);
        for &(_, _, i) in &dark {
            if pick.list.len() >= wanted {
                break;
            }
            selection.darkest += pick.take(i);
        }

        let poles = n / 8;
        for (row, count) in [(0, poles.div_ceil(2)), (h - 1, poles / 2)] {
            for j in 0..count.min(w) {
                selection.poles += pick.take(row * w + (2 * j + 1) * w / (2 * count));
            }
        }

        let rest: Vec<usize> = (0..w * h).filter(|&i| !pick.chosen[i]).collect();
        let m = n - pick.list.len();
        for j in 0..m {
            selection.spread += pick.take(rest[(2 * j + 1) * rest.len() / (2 * m)]);
        }
        (pick.list, selection)
    }

    /// The angular integral at `texels` of a `width`×`height` map for `view`, in order.
    pub fn exact(&self, texels: &[usize], width: usize, height: usize, view: DVec3) -> Vec<[f64; 3]> {
        let grid = LatLong::new(width, height);
        texels.par_iter().map(|&i| self.integral.texel(grid.texel_direction(i % width, i / width), view)).collect()
    }

    /// Checks `maps`: the texels of each (for radially symmetric BRDFs, whose maps are one map
    /// whatever the view, the first map's texels and exact values serve them all).
    pub fn verify(&self, maps: &[MapCheck<'_>], progress: &dyn Progress) -> Result<Verification, VerifyError> {
        let mut shared: Option<(Vec<usize>, Selection, Vec<[f64; 3]>)> = None;
        let mut out = Vec::with_capacity(maps.len());
        progress.start("verify", maps.len() as u64);
        for check in maps {
            let (w, h) = (check.image.width, check.image.height);
            let (texels, selection, exact) = match &shared {
                Some(s) if self.radial => s.clone(),
                _ => {
                    let (texels, selection) = self.choose(check.image);
                    let exact = self.exact(&texels, w, h, check.view);
                    (texels, selection, exact)
                }
            };
            out.push(figures(check, &texels, selection, &exact)?);
            shared.get_or_insert((texels, selection, exact));
            progress.advance(1);
        }
        progress.finish();
        Ok(Verification {
            epsilon: ANGULAR_EPSILON,
            subsamples: self.integral.subsamples(),
            requested: self.texels,
            maps: out,
        })
    }
}

/// Refuses N outside 1..=[`MAX_VERIFY_TEXELS`] (before any work).
pub fn check_texels(n: usize) -> Result<(), VerifyError> {
    match n {
        1..=MAX_VERIFY_TEXELS => Ok(()),
        _ => Err(VerifyError::Texels(n)),
    }
}

/// The figures of `check` over `texels` with the exact values `exact` (before the map's scale):
/// [`metrics::compare`] masked to the checked texels.
fn figures(
    check: &MapCheck<'_>,
    texels: &[usize],
    selection: Selection,
    exact: &[[f64; 3]],
) -> Result<MapVerification, VerifyError> {
    let map = check.image;
    let mut reference = RgbImage::new(map.width, map.height);
    let mut mask = vec![false; map.pixels.len()];
    for (&i, e) in texels.iter().zip(exact) {
        reference.pixels[i] = e.map(|v| (v * check.scale) as f32);
        mask[i] = true;
    }
    let (m, _) =
        metrics::compare(map, &reference, &mask).map_err(|_| VerifyError::ZeroReference(check.name.clone()))?;
    let [x, y] = m.worst_texel;
    let i = y * map.width + x;
    let exact_at = texels.iter().position(|&t| t == i).map_or([0.0; 3], |k| exact[k].map(|v| v * check.scale));
    Ok(MapVerification {
        map: check.name.clone(),
        texels: texels.len(),
        selection,
        negative: (m.negative_fraction * m.pixels as f64).round() as usize,
        rel_error: m.rel_error,
        p99_texel_error: m.p99_texel_error,
        max_texel_error: m.max_texel_error,
        worst: WorstTexel { x, y, value: map.pixels[i].map(f64::from), exact: exact_at },
    })
}

/// Texels chosen so far, within a budget.
struct Picker {
    chosen: Vec<bool>,
    list: Vec<usize>,
    budget: usize,
}

impl Picker {
    /// Takes texel `i` if it is new and the budget allows; 1 if taken.
    fn take(&mut self, i: usize) -> usize {
        if self.chosen[i] || self.list.len() >= self.budget {
            return 0;
        }
        self.chosen[i] = true;
        self.list.push(i);
        1
    }
}

/// Up to [`VERIFY_SOURCES`] directions of the brightest texels of the lat-long `env` (luminance:
/// the mean of RGB), each more than `reach` from the others; after the brightest, only texels
/// at least [`MEAN_MULTIPLE`] × the mean luminance count as sources.
fn brightest_sources(env: &EnvMap, reach: f64) -> Vec<DVec3> {
    let image = env.image();
    let grid = LatLong::new(image.width, image.height);
    let mut total = (0.0, 0.0);
    for (i, p) in image.pixels.iter().enumerate() {
        let omega = grid.row_solid_angle(i / image.width);
        total = (total.0 + luminance(*p) * omega, total.1 + omega);
    }
    let bright = MEAN_MULTIPLE * total.0 / total.1;
    let mut order: Vec<(f64, usize)> = image.pixels.iter().map(|&p| luminance(p)).zip(0..).collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut sources: Vec<DVec3> = Vec::new();
    for (y, i) in order {
        if sources.len() == VERIFY_SOURCES || (!sources.is_empty() && y < bright) {
            break;
        }
        let d = grid.texel_direction(i % image.width, i / image.width);
        if sources.iter().all(|s| s.dot(d) < reach.cos()) {
            sources.push(d);
        }
    }
    sources
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;

    fn sun_sky(w: usize, h: usize, sun: DVec3) -> EnvMap {
        let grid = LatLong::new(w, h);
        EnvMap::latlong(RgbImage::from_fn(w, h, |x, y| {
            let d = grid.texel_direction(x, y);
            let v = if d.dot(sun) > 0.995 { 500.0 } else { 1.0 + d.z.max(0.0) };
            [v as f32; 3]
        }))
        .unwrap()
    }

    #[test]
    fn the_choice_has_every_kind_is_distinct_and_fills_n() {
        // The sun low in the south, far from the texels the test makes dark.
        let sun = DVec3::new(-0.5, -0.2, -0.8).normalize();
        let env = sun_sky(64, 32, sun);
        let model = Model::new(Brdf::parse("phong:s=16").unwrap(), true).unwrap();
        let verifier = Verifier::new(&model, &env, 16, 40).unwrap();
        assert_eq!(verifier.sources.len(), 1, "one sun: {:?}", verifier.sources);
        assert!(verifier.sources[0].dot(sun) > 0.99);
        // A map with two negative texels.
        let mut map = RgbImage::from_fn(32, 16, |x, y| [1.0 + (x + y) as f32; 3]);
        map.pixels[100] = [-0.5, 1.0, 1.0];
        map.pixels[200] = [-0.1, 1.0, 1.0];
        let (texels, s) = verifier.choose(&map);
        assert_eq!(texels.len(), 40);
        assert_eq!((s.bright, s.darkest, s.poles, s.spread), (10, 10, 5, 15), "{s:?}");
        let mut unique = texels.clone();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), 40);
        // The texel at the sun first, the negative texels (most negative first) open the darkest.
        let grid = LatLong::new(32, 16);
        assert!(grid.texel_direction(texels[0] % 32, texels[0] / 32).dot(sun) > 0.99);
        assert_eq!(&texels[10..12], &[100, 200]);
        assert_eq!(texels[12], 0, "then the darkest positive texel, at (0, 0)");
        assert!(texels[20..25].iter().all(|&i| !(32..15 * 32).contains(&i)), "poles: {:?}", &texels[20..25]);
        // Asking for more than the map has checks every texel.
        let all = Verifier::new(&model, &env, 16, 10_000).unwrap().choose(&map).0;
        assert_eq!(all.len(), 32 * 16);
        assert!(matches!(Verifier::new(&model, &env, 16, 0), Err(VerifyError::Texels(0))));
    }

    #[test]
    fn the_exact_values_are_the_angular_reference() {
        let sun = DVec3::new(-0.3, 0.6, 0.4).normalize();
        let env = sun_sky(48, 24, sun);
        for spec in ["phong:s=16", "torrance-sparrow:sigma=0.3"] {
            let model = Model::new(Brdf::parse(spec).unwrap(), true).unwrap();
            let view = DVec3::new(0.2, -0.1, 1.0).normalize();
            // Narrower than the map: the cone-sum path of the reference for either BRDF.
            let reference = super::super::pipeline::angular_reference(
                &model,
                &env,
                &[view],
                AngularSettings::new(ANGULAR_EPSILON),
                32,
                16,
                &crate::progress::NoProgress,
            )
            .unwrap()
            .maps
            .remove(0);
            let verifier = Verifier::new(&model, &env, 16, 60).unwrap();
            let (texels, _) = verifier.choose(&reference);
            let exact = verifier.exact(&texels, 32, 16, view);
            for (&i, e) in texels.iter().zip(&exact) {
                let r = reference.pixels[i];
                for c in 0..3 {
                    assert_eq!(e[c] as f32, r[c], "{spec} texel {i}");
                }
            }
        }
    }
}
