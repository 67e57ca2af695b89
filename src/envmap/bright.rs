//! Compact, very bright sources (the sun, lamps, windows) apart from the rest of a map.
//!
//! A truncated SH expansion of a source 10⁴× brighter than the sky rings at 10⁻⁴ of the
//! source's energy, which is already the sky's own level. Such sources are few texels, so they
//! are cheap to filter exactly in angle; what remains is smooth enough for spherical harmonics.
//! The split clips the map at a threshold T: the remainder is min(L, T) (scaled per texel, so
//! its colour is kept), the bright part is the excess L − min(L, T), kept as a list of texels
//! (direction, solid angle, excess radiance). Remainder + excess = the map, texel for texel.
//!
//! Any layout: texels are weighed by their solid angles.
//!
//! The threshold (`docs/prefilter.md`, "Bright sources apart"): with Y the luminance
//! (the mean of RGB) and Q the value above which the brightest [`AREA_FRACTION`] of the sphere's
//! solid angle lies, T = max(Q, [`MEAN_MULTIPLE`] × mean Y). Q bounds the number of texels the
//! angular pass visits; the mean multiple keeps maps without compact sources (an overcast sky,
//! a white furnace) whole.

use super::EnvMap;
use crate::io::RgbImage;
use crate::sphere::LatLong;
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The brightest share of the sphere that may be moved to the angular pass.
pub const AREA_FRACTION: f64 = 0.01;
/// The threshold is at least this multiple of the mean luminance.
pub const MEAN_MULTIPLE: f64 = 4.0;

/// How the bright sources are chosen (`--bright`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum BrightRule {
    /// No split: everything goes through spherical harmonics (the paper's method).
    Off,
    /// The threshold from the histogram (module docs).
    #[default]
    Auto,
    /// A given luminance threshold.
    Threshold(f64),
}

/// One bright texel: its direction, solid angle and excess radiance above the threshold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrightTexel {
    /// Unit direction of the texel centre.
    pub dir: DVec3,
    /// Solid angle (steradians).
    pub solid_angle: f64,
    /// Radiance above the threshold, RGB.
    pub excess: [f64; 3],
}

/// The bright part of a map.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BrightSources {
    /// The luminance threshold T (infinite when nothing was split).
    pub threshold: f64,
    /// The texels above it.
    pub texels: Vec<BrightTexel>,
    /// Share of the map's radiant energy ∫ Y dω in the bright part.
    pub energy_fraction: f64,
    /// Share of the map's ∫ Y² dω (what drives SH ringing) in the bright part.
    pub squared_fraction: f64,
}

/// The bright part, in figures (for documents).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BrightReport {
    /// The luminance threshold (absent when nothing was split).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threshold: Option<f64>,
    /// Texels filtered in angle.
    pub texels: usize,
    /// Share of the map's radiant energy filtered in angle.
    pub energy_fraction: f64,
    /// Share of ∫ Y² dω (the ringing energy) filtered in angle.
    pub squared_fraction: f64,
}

impl BrightSources {
    /// True when nothing was split.
    pub fn is_empty(&self) -> bool {
        self.texels.is_empty()
    }

    /// The figures of this split.
    pub fn report(&self) -> BrightReport {
        BrightReport {
            threshold: (!self.is_empty()).then_some(self.threshold),
            texels: self.texels.len(),
            energy_fraction: self.energy_fraction,
            squared_fraction: self.squared_fraction,
        }
    }

    /// Puts the excess back into a lat-long image of any size ([`BrightSources::on_latlong`]).
    pub fn add_to_latlong(&self, image: &mut RgbImage) {
        for (x, y, v) in self.on_latlong(LatLong::new(image.width, image.height)) {
            let px = &mut image.pixels[y * image.width + x];
            for c in 0..3 {
                px[c] += v[c] as f32;
            }
        }
    }

    /// The excess as texels (x, y, value) of a lat-long grid of any size: each texel at the
    /// texel its direction falls in, scaled by the ratio of solid angles so the grid keeps its
    /// energy (on the grid the texels were split on, their own places and values).
    pub fn on_latlong(&self, grid: LatLong) -> Vec<(usize, usize, [f64; 3])> {
        self.texels
            .iter()
            .map(|t| {
                let (x, y) = grid.texel_of(t.dir);
                let scale = t.solid_angle / grid.row_solid_angle(y);
                (x, y, t.excess.map(|e| e * scale))
            })
            .collect()
    }
}

/// The luminance Y the split thresholds: the mean of RGB.
pub fn luminance(rgb: [f32; 3]) -> f64 {
    (rgb[0] as f64 + rgb[1] as f64 + rgb[2] as f64) / 3.0
}

/// The threshold of [`BrightRule::Auto`]: max(Q, MEAN_MULTIPLE × the mean of min(Y, Q)). The
/// mean is the map's without its brightest share, clipped at Q: a sun 10⁴ × the sky would
/// otherwise raise the mean, and with it the threshold, to well above the sky, leaving a clipped
/// sun of hundreds of times the sky in the remainder.
///
/// Q is found from a histogram of Y, so no texel list is sorted: one pass puts each texel's
/// solid angle and Y × solid angle into its bin, the bins from the top find the one in which the
/// brightest `AREA_FRACTION` of the area is reached, and a second pass gathers the texels of
/// that bin and above, of which only that bin's are sorted. Q is then the full sort's value
/// (ties in Y give the same Q in any order), and the clipped mean is the bins below plus that
/// bin's texels clipped plus Q × the area above.
pub fn auto_threshold(map: &EnvMap) -> f64 {
    Histogram::of(map).auto_threshold(map).0
}

/// Bins of [`auto_threshold`]'s histogram: one per value of the top 11 bits of Y as an f32
/// (sign, exponent and 2 bits of mantissa), so a bin spans at most 1/4 of its values.
const HISTOGRAM_BINS: usize = 1 << 11;

/// Rows per block of the split's parallel passes.
const BLOCK_ROWS: usize = 16;

/// Y's bin: the order of the bins is that of Y for Y ≥ 0 (the bits of non-negative floats
/// order as the floats do; rounding to f32 keeps the order); negative Y and NaN go to bin 0.
fn histogram_bin(y: f64) -> usize {
    ((y.max(0.0) as f32).to_bits() >> 21) as usize
}

/// The split's pass over every texel: per bin of Y its solid angle and ∫ Y dω, and ∫ Y² dω.
/// Per block of rows, in parallel; blocks merged in order, so the sums are the same for any
/// thread count.
struct Histogram {
    bins: Vec<(f64, f64)>,
    squared: f64,
}

/// A texel the split looks at after the histogram: (image, column, row, Y, solid angle).
type Candidate = (usize, usize, usize, f64, f64);

impl Histogram {
    fn of(map: &EnvMap) -> Self {
        let blocks: Vec<Histogram> = map
            .rows()
            .par_chunks(BLOCK_ROWS)
            .map(|block| {
                let mut bins = vec![(0.0f64, 0.0f64); HISTOGRAM_BINS];
                let mut squared = 0.0;
                // Neighbouring texels mostly share a bin: summed in registers while they do, not
                // through the bin in memory (a chain of stores and loads per texel).
                let mut run = (0, 0.0, 0.0);
                for &(face, y) in block {
                    map.for_each_value_in_row(face, y, |_, rgb, omega| {
                        let lum = luminance(rgb);
                        let bin = histogram_bin(lum);
                        if bin != run.0 {
                            bins[run.0].0 += run.1;
                            bins[run.0].1 += run.2;
                            run = (bin, 0.0, 0.0);
                        }
                        run.1 += omega;
                        run.2 += lum * omega;
                        squared += lum * lum * omega;
                    });
                }
                bins[run.0].0 += run.1;
                bins[run.0].1 += run.2;
                Histogram { bins, squared }
            })
            .collect();
        let mut total = Histogram { bins: vec![(0.0, 0.0); HISTOGRAM_BINS], squared: 0.0 };
        for block in &blocks {
            for (b, v) in total.bins.iter_mut().zip(&block.bins) {
                b.0 += v.0;
                b.1 += v.1;
            }
            total.squared += block.squared;
        }
        total
    }

    fn area(&self) -> f64 {
        self.bins.iter().map(|b| b.0).sum()
    }

    /// [`auto_threshold`] and the texels of Q's bin and above, which hold every texel above it.
    fn auto_threshold(&self, map: &EnvMap) -> (f64, Vec<Candidate>) {
        let (bins, total_area) = (&self.bins, self.area());
        let area = AREA_FRACTION * total_area;
        // The bin in which the brightest texels' area first exceeds `area`, and the area above it.
        let mut above = 0.0;
        let Some(critical) = (0..HISTOGRAM_BINS).rev().find(|&b| {
            if above + bins[b].0 > area {
                return true;
            }
            above += bins[b].0;
            false
        }) else {
            // No area (an empty map): nothing is bright.
            return (0.0, Vec::new());
        };
        let candidates = texels_from_bin(map, critical);
        let mut texels: Vec<(f64, f64)> =
            candidates.iter().filter(|t| histogram_bin(t.3) == critical).map(|t| (t.3, t.4)).collect();
        texels.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
        let mut covered = above;
        let q = texels
            .iter()
            .find(|&&(_, omega)| {
                covered += omega;
                covered > area
            })
            .map_or(0.0, |t| t.0);
        let below: f64 = bins[..critical].iter().map(|b| b.1).sum();
        let clipped: f64 = texels.iter().map(|&(y, omega)| y.min(q) * omega).sum();
        let clipped_mean = (below + clipped + q * above) / total_area;
        (q.max(MEAN_MULTIPLE * clipped_mean), candidates)
    }
}

/// The texels whose Y falls in bin `from` or above, in the map's order.
fn texels_from_bin(map: &EnvMap, from: usize) -> Vec<Candidate> {
    map.rows()
        .par_chunks(BLOCK_ROWS)
        .flat_map_iter(|block| {
            let mut found = Vec::new();
            for &(face, y) in block {
                map.for_each_value_in_row(face, y, |x, rgb, omega| {
                    let lum = luminance(rgb);
                    if histogram_bin(lum) >= from {
                        found.push((face, x, y, lum, omega));
                    }
                });
            }
            found
        })
        .collect()
}

/// Splits a map into the remainder (clipped at the threshold) and the bright texels, in any
/// layout. [`BrightRule::Off`] and maps with nothing above the threshold come back whole with an
/// empty bright part.
///
/// Two passes over the texels: the histogram (which gives the energies, and [`auto_threshold`]
/// its Q), and the texels from the threshold's bin up (a threshold above Q lies in Q's bin or
/// above). The few above the threshold are then clipped in a copy of the map.
pub fn split(map: &EnvMap, rule: BrightRule) -> (EnvMap, BrightSources) {
    let histogram = match rule {
        BrightRule::Off => return (map.clone(), BrightSources { threshold: f64::INFINITY, ..Default::default() }),
        _ => Histogram::of(map),
    };
    let (threshold, candidates) = match rule {
        BrightRule::Threshold(t) => (t, texels_from_bin(map, histogram_bin(t))),
        _ => histogram.auto_threshold(map),
    };
    let mut remainder = map.clone();
    let (mut bright, mut bright2) = (0.0, 0.0);
    let mut texels = Vec::new();
    for &(face, x, y, l, omega) in candidates.iter().filter(|t| t.3 > threshold) {
        let image = &mut remainder.images_mut()[face];
        let px = image.get(x, y);
        let keep = threshold / l;
        let excess = px.map(|c| c as f64 * (1.0 - keep));
        image.set(x, y, px.map(|c| (c as f64 * keep) as f32));
        bright += (excess[0] + excess[1] + excess[2]) / 3.0 * omega;
        bright2 += (l * l - threshold * threshold) * omega;
        let (dir, _) = map.texel_geometry(face, x, y).expect("a texel with a solid angle is mapped");
        texels.push(BrightTexel { dir, solid_angle: omega, excess });
    }
    let total: f64 = histogram.bins.iter().map(|b| b.1).sum();
    let fraction = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
    let sources = BrightSources {
        threshold,
        texels,
        energy_fraction: fraction(bright, total),
        squared_fraction: fraction(bright2, histogram.squared),
    };
    (remainder, sources)
}

/// Successive bands of [`luminance_bands`] differ by this factor in luminance.
pub const BAND_RATIO: f64 = 4.0;

/// One band of [`luminance_bands`]: the texels of a map whose luminance lies in the band, whole,
/// every other texel zero.
#[derive(Clone, Debug)]
pub struct LuminanceBand {
    /// The band's texels (same layout and size as the map).
    pub map: EnvMap,
    /// The band's upper luminance bound: no texel of it is brighter.
    pub upper: f64,
    /// Texels with radiance in the band.
    pub texels: usize,
}

/// A map partitioned by luminance Y, every texel whole in one band: from its largest luminance
/// M down by [`BAND_RATIO`], (M/4, M], (M/16, M/4], …, to the first bound F = M/4^B at or below
/// `floor`, and last the floor band [0, F] (the whole map when M ≤ `floor`). The bands sum to
/// the map texel for texel. The angular reference sums each with its own cone, so that what a
/// band's truncation leaves out, at most ε_band × its upper bound, is the same ε F for every band
/// (`docs/prefilter.md`, "The angular reference").
pub fn luminance_bands(map: &EnvMap, floor: f64) -> Vec<LuminanceBand> {
    let largest = map.images().iter().flat_map(|i| &i.pixels).map(|&p| luminance(p)).fold(0.0, f64::max);
    let mut uppers = vec![largest];
    while uppers.last().is_some_and(|&u| u > floor && u > 0.0) {
        let next = uppers[uppers.len() - 1] / BAND_RATIO;
        uppers.push(next);
    }
    // uppers: M, M/4, …, F; band k is (uppers[k + 1], uppers[k]], the last [0, F].
    let band_of = |y: f64| uppers.iter().rposition(|&u| y <= u).unwrap_or(0);
    let mut bands: Vec<LuminanceBand> = uppers
        .iter()
        .map(|&upper| {
            let mut empty = map.clone();
            empty.images_mut().iter_mut().for_each(|i| i.pixels.fill([0.0; 3]));
            LuminanceBand { map: empty, upper, texels: 0 }
        })
        .collect();
    for (face, img) in map.images().iter().enumerate() {
        for (i, &px) in img.pixels.iter().enumerate() {
            let band = &mut bands[band_of(luminance(px))];
            band.map.images_mut()[face].pixels[i] = px;
            band.texels += usize::from(px != [0.0; 3]);
        }
    }
    bands
}

/// The mean luminance ∫ Y dω / 4π of a map (texels weighed by their solid angles).
pub fn mean_luminance(map: &EnvMap) -> f64 {
    let (mut sum, mut area) = (0.0, 0.0);
    map.for_each_texel(|t| {
        sum += luminance(t.rgb) * t.solid_angle;
        area += t.solid_angle;
    });
    if area > 0.0 {
        sum / area
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sky_with_sun() -> EnvMap {
        let grid = LatLong::new(64, 32);
        let sun = DVec3::new(0.3, 0.2, 0.9).normalize();
        EnvMap::latlong(RgbImage::from_fn(64, 32, |x, y| {
            let d = grid.texel_direction(x, y);
            let v = 1.0 + if d.dot(sun) > 0.995 { 5000.0 } else { 0.0 };
            [v, 0.9 * v, 0.8 * v]
        }))
        .unwrap()
    }

    #[test]
    fn the_excess_put_back_restores_the_map_and_keeps_the_energy_at_any_size() {
        let map = sky_with_sun();
        let (mut rest, bright) = split(&map, BrightRule::Auto);
        assert!(!bright.is_empty());
        // Same grid: remainder + excess is the map, texel for texel.
        bright.add_to_latlong(&mut rest.images_mut()[0]);
        for (a, b) in rest.image().pixels.iter().zip(&map.image().pixels) {
            assert!((0..3).all(|c| (a[c] - b[c]).abs() <= 1e-6 * b[c]), "{a:?} vs {b:?}");
        }
        // A coarser grid: the excess's energy Σ e ΔΩ lands whole.
        let mut coarse = RgbImage::new(16, 8);
        bright.add_to_latlong(&mut coarse);
        let grid = LatLong::new(16, 8);
        let got: f64 = coarse.pixels.iter().enumerate().map(|(i, p)| grid.row_solid_angle(i / 16) * p[0] as f64).sum();
        let want: f64 = bright.texels.iter().map(|t| t.excess[0] * t.solid_angle).sum();
        assert!((got - want).abs() < 1e-5 * want, "{got} vs {want}");
    }

    use crate::sphere::LatLong;

    #[test]
    fn remainder_plus_excess_is_the_map_and_the_sun_goes_apart() {
        let map = sky_with_sun();
        let (rest, bright) = split(&map, BrightRule::Auto);
        assert!(!bright.is_empty() && bright.texels.len() < 20, "{} texels", bright.texels.len());
        assert!(bright.energy_fraction > 0.5, "{bright:?}");
        let grid = LatLong::new(64, 32);
        let mut sum = rest.image().clone();
        for t in &bright.texels {
            let (px, py) = grid.position(t.dir);
            let (x, y) = (px as usize, py as usize);
            let v = sum.get(x, y);
            sum.set(x, y, [0, 1, 2].map(|c| v[c] + t.excess[c] as f32));
        }
        for (a, b) in sum.pixels.iter().zip(&map.image().pixels) {
            for c in 0..3 {
                assert!((a[c] - b[c]).abs() <= 1e-3 * b[c], "{a:?} vs {b:?}");
            }
        }
        // The remainder keeps each texel's colour and is clipped at the threshold.
        assert!(rest.image().pixels.iter().all(|p| luminance(*p) <= bright.threshold * (1.0 + 1e-6)));
    }

    #[test]
    fn luminance_bands_partition_the_map_by_factors_of_four_down_to_the_floor() {
        // Luminances 0.5 … 1000 over a 64×32 map: M = 1000, floor 3 → bounds 1000, 250, 62.5,
        // 15.6, 3.9, 0.98 (the first ≤ 3): five bands above the floor band.
        let grid = LatLong::new(64, 32);
        let map = EnvMap::latlong(RgbImage::from_fn(64, 32, |x, y| {
            let v = 0.5 * (2000f64).powf((x + 64 * y) as f64 / (64.0 * 32.0 - 1.0));
            [v as f32, (0.5 * v) as f32, (1.5 * v) as f32]
        }))
        .unwrap();
        let bands = luminance_bands(&map, 3.0);
        let uppers: Vec<f64> = bands.iter().map(|b| b.upper).collect();
        let want = [1000.0, 250.0, 62.5, 15.625, 3.90625, 0.9765625];
        assert_eq!(uppers.len(), want.len(), "{uppers:?}");
        for (u, w) in uppers.iter().zip(want) {
            assert!((u - w).abs() < 1e-3 * w, "{uppers:?}");
        }
        // Every texel in exactly one band, whole, within that band's bounds; the texel counts add up.
        let mut sum = RgbImage::new(64, 32);
        for (k, band) in bands.iter().enumerate() {
            let lower = if k + 1 < bands.len() { band.upper / BAND_RATIO } else { 0.0 };
            let lit: Vec<&[f32; 3]> = band.map.image().pixels.iter().filter(|p| **p != [0.0; 3]).collect();
            assert_eq!(lit.len(), band.texels);
            assert!(lit
                .iter()
                .all(|p| luminance(**p) > lower * (1.0 - 1e-9) && luminance(**p) <= band.upper * (1.0 + 1e-6)));
            for (s, p) in sum.pixels.iter_mut().zip(&band.map.image().pixels) {
                *s = [0, 1, 2].map(|c| s[c] + p[c]);
            }
        }
        assert_eq!(&sum, map.image());
        assert_eq!(bands.iter().map(|b| b.texels).sum::<usize>(), 64 * 32);
        // A map no brighter than the floor is one band, the whole map.
        let whole = luminance_bands(&map, 1e4);
        assert_eq!(whole.len(), 1);
        assert_eq!(whole[0].map.image(), map.image());
        // The mean luminance weighs texels by solid angle: a map of 1 + z has mean 1.
        let tilt = EnvMap::latlong(RgbImage::from_fn(64, 32, |x, y| [(1.0 + grid.texel_direction(x, y).z) as f32; 3]))
            .unwrap();
        assert!((mean_luminance(&tilt) - 1.0).abs() < 1e-6, "{}", mean_luminance(&tilt));
    }

    #[test]
    fn a_map_without_compact_sources_stays_whole() {
        let grid = LatLong::new(32, 16);
        let map = EnvMap::latlong(RgbImage::from_fn(32, 16, |x, y| {
            let d = grid.texel_direction(x, y);
            [(1.0 + 0.5 * d.z) as f32; 3]
        }))
        .unwrap();
        let (rest, bright) = split(&map, BrightRule::Auto);
        assert!(bright.is_empty());
        assert_eq!(rest.image(), map.image());
        assert!(split(&sky_with_sun(), BrightRule::Off).1.is_empty());
    }

    /// The split against its definition, texel by texel: every texel with Y > T and no other is
    /// bright, with excess L(1 − T/Y) and the remainder L·T/Y, and the energy shares are
    /// Σ (Y − T) ΔΩ / Σ Y ΔΩ and Σ (Y² − T²) ΔΩ / Σ Y² ΔΩ over all texels. For the automatic
    /// threshold and given ones (inside a histogram bin, on a bin's edge, below every texel), on
    /// a lat-long map and on a cube cross (unmapped texels, solid angles per texel).
    #[test]
    fn the_split_moves_exactly_the_texels_above_the_threshold() {
        let sky = sky_with_sun();
        let cross = super::super::resample(&sky, super::super::Layout::CrossHorizontal, 96, 72, 2).unwrap();
        for (name, map) in [("lat-long", sky), ("cross", cross)] {
            let edge = f32::from_bits((histogram_bin(2.0) << 21) as u32) as f64;
            for rule in
                [BrightRule::Auto, BrightRule::Threshold(1.7), BrightRule::Threshold(edge), BrightRule::Threshold(-1.0)]
            {
                let (rest, bright) = split(&map, rule);
                let t = bright.threshold;
                if let BrightRule::Threshold(given) = rule {
                    assert_eq!(t, given);
                }
                let (mut total, mut total2, mut above, mut above2, mut count) = (0.0, 0.0, 0.0, 0.0, 0);
                let mut texels = bright.texels.iter();
                for (face, img) in map.images().iter().enumerate() {
                    for y in 0..img.height {
                        for x in 0..img.width {
                            let Some((dir, omega)) = map.texel_geometry(face, x, y) else { continue };
                            let (px, l) = (img.get(x, y), luminance(img.get(x, y)));
                            let kept = rest.images()[face].get(x, y);
                            total += l * omega;
                            total2 += l * l * omega;
                            if l <= t {
                                assert_eq!(kept, px, "{name} {rule:?}: ({face}, {x}, {y}) moved");
                                continue;
                            }
                            count += 1;
                            above += (l - t) * omega;
                            above2 += (l * l - t * t) * omega;
                            let texel = texels.next().expect("a bright texel for every texel above T");
                            assert!(texel.dir.abs_diff_eq(dir, 1e-12) && texel.solid_angle == omega, "{name} {rule:?}");
                            for c in 0..3 {
                                let v = px[c] as f64;
                                assert!((texel.excess[c] - v * (1.0 - t / l)).abs() <= 1e-12 * v, "{name} {rule:?}");
                                assert!((kept[c] as f64 - v * t / l).abs() <= 1e-6 * v, "{name} {rule:?}");
                            }
                        }
                    }
                }
                assert_eq!(bright.texels.len(), count, "{name} {rule:?}");
                assert!((bright.energy_fraction - above / total).abs() <= 1e-12, "{name} {rule:?}");
                assert!((bright.squared_fraction - above2 / total2).abs() <= 1e-12, "{name} {rule:?}");
            }
        }
    }

    #[test]
    fn the_histogram_finds_the_full_sorts_threshold() {
        // The definition: sort all texels by luminance, brightest first, take Q at the one where
        // the accumulated solid angle first exceeds AREA_FRACTION of the sphere, and the mean
        // of min(Y, Q). Maps with ties (luminance from a few levels, so the critical bin holds
        // many texels), luminance over many decades, negative texels, and a sun.
        let reference = |map: &EnvMap| {
            let mut texels = Vec::new();
            map.for_each_texel(|t| texels.push((luminance(t.rgb), t.solid_angle)));
            let total: f64 = texels.iter().map(|t| t.1).sum();
            texels.sort_by(|a, b| b.0.total_cmp(&a.0));
            let mut covered = 0.0;
            let q = texels.iter().find(|t| (covered += t.1, covered > AREA_FRACTION * total).1).map_or(0.0, |t| t.0);
            let mean = texels.iter().map(|t| t.0.min(q) * t.1).sum::<f64>() / total;
            q.max(MEAN_MULTIPLE * mean)
        };
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut image =
            |width: usize, height: usize, pixel: &mut dyn FnMut(&mut crate::rng::SplitMix64) -> [f32; 3]| {
                let pixels = (0..width * height).map(|_| pixel(&mut rng)).collect();
                EnvMap::latlong(RgbImage { width, height, pixels })
            };
        let levels = image(128, 64, &mut |rng| [(rng.range_i64(0, 40) as f32).powi(2); 3]);
        let decades = image(128, 64, &mut |rng| {
            let v = 10f32.powf(8.0 * rng.next_f64() as f32 - 3.0);
            [v, 0.5 * v, 2.0 * v]
        });
        let signed = image(64, 32, &mut |rng| [rng.next_f64() as f32 - 0.3; 3]);
        for (name, map) in [("levels", levels.unwrap()), ("decades", decades.unwrap()), ("signed", signed.unwrap())]
            .into_iter()
            .chain([("sun", sky_with_sun())])
        {
            let (got, want) = (auto_threshold(&map), reference(&map));
            assert!((got - want).abs() <= 1e-12 * want.abs(), "{name}: {got} vs {want}");
        }
    }
}
