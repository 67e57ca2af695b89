//! The angular reference every level is measured against: the split-sum integral of the input
//! environment itself, taken in angle over the whole kernel support.
//!
//!   B(R) = Σ_t L_t ∫_t k(R·ω) dω
//!
//! over every texel t of the input lat-long map (piecewise constant, radiance L_t) whose centre
//! lies within π/2 + 2h of R (the kernel vanishes beyond π/2), the texel integrals by a
//! Gauss–Legendre product rule fine enough to misplace at most 1e-5 of the kernel's weight. The
//! texels kept cover the kernel's support and ∫ k dω = 1, so no normalization is needed. This
//! is [`crate::prefilter::angular::ConeIntegrator`]'s direct cone sum: no FFT, no pyramid, no
//! working grid, no interpolation, none of the code of either bake path.
//!
//! A level is compared on a fixed, evenly strided set of its texels, with the errors pooled
//! by [`LevelError::pool`]: the relative error ‖a − r‖/‖r‖ over the texels whose reference is
//! above 1 % of the sampled mean.
//!
//! **Large inputs.** The cone sum visits half the input's texels per sampled direction, so an
//! 8192 × 4096 map made the measurement cost minutes and gigabytes. A map above
//! [`REFERENCE_MAX_TEXELS`] is measured against its box-filtered halvings instead (each coarse
//! texel the solid-angle-weighted mean of the 2 × 2 it covers, so it keeps their energy E_T
//! exactly), with a bound on what that changes. Within a coarse texel T the fine texels t sum
//! L_t ∫_t k dω where the coarse one sums L̄_T ∫_T k dω; both put the energy E_T = Σ L_t Ω_t
//! against the kernel's values on T, so
//!
//!   |B_fine(R) − B_coarse(R)| ≤ Σ_T E_T (max_T k − min_T k),
//!
//! per channel, for radiance ≥ 0. The split-sum kernel falls monotonically with the angle γ
//! from R (D(h) with θ_h = γ/2, times cos γ, zero past π/2), so over T it lies between
//! k(γ_T − ρ_T) and k(γ_T + ρ_T), γ_T the angle to T's centre and ρ_T T's angular radius. The
//! manifest states that bound per level (`reference_bound`, relative like the errors), beside the
//! error measured against the coarse integral: the error against the input itself differs from
//! the stated one by at most the bound. (The coarse radiance is stored as f32: rounding adds a
//! relative 6e-8, far below any bound here.)

use super::angular::LevelError;
use super::cube::{texel_direction, CubeMap};
use super::ggx::SplitSumLobe;
use crate::envmap::zonal::rule_for_kernel;
use crate::envmap::{EnvMap, FACES};
use crate::io::RgbImage;
use crate::prefilter::angular::{AngularError, ConeIntegrator};
use crate::sphere::LatLong;
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// Texel-rule tolerance of the reference (ten times stricter than the bake's).
pub const REFERENCE_RULE_TOLERANCE: f64 = 1e-5;

/// The largest lat-long grid the reference sums directly (the 1024 × 512 of the shared probes);
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
    /// The most negative component of the whole level (0 when none is negative).
    pub min_value: f64,
    /// max over the counted texels of ‖β‖/‖r‖, β the bound on what the reference's box
    /// filtering changes (0 when the input was summed as it is).
    pub reference_bound: f64,
}

/// The reference integrator over one lat-long environment (prtkit's frame).
pub struct Reference {
    integrator: ConeIntegrator,
    /// The input's size, and the coarse texels when it was box-filtered (for the bound).
    input: (usize, usize),
    coarse: Option<Vec<CoarseTexel>>,
}

/// A texel of the box-filtered grid: its centre, the cosine and sine of its angular radius ρ,
/// and its energy E_T = L̄_T Ω_T.
struct CoarseTexel {
    centre: DVec3,
    cos_radius: f64,
    sin_radius: f64,
    energy: [f64; 3],
}

impl Reference {
    /// Prepares the input lat-long map: as it is up to [`REFERENCE_MAX_TEXELS`], else halved
    /// (2 × 2 box filter) until it fits or an edge turns odd.
    pub fn new(latlong: &EnvMap) -> Result<Self, AngularError> {
        Self::with_max_texels(latlong, REFERENCE_MAX_TEXELS)
    }

    /// [`Reference::new`] with another ceiling on the texels summed.
    pub fn with_max_texels(latlong: &EnvMap, max_texels: usize) -> Result<Self, AngularError> {
        let image = latlong.image();
        let input = (image.width, image.height);
        let mut grid = image.clone();
        while grid.width * grid.height > max_texels && grid.width % 2 == 0 && grid.height % 2 == 0 {
            grid = halved(&grid);
        }
        if grid.width == input.0 {
            return Ok(Reference { integrator: ConeIntegrator::new(latlong)?, input, coarse: None });
        }
        let geometry = LatLong::new(grid.width, grid.height);
        let radii: Vec<f64> = (0..grid.height).map(|y| angular_radius(geometry, y)).collect();
        let coarse = (0..grid.height)
            .flat_map(|y| (0..grid.width).map(move |x| (x, y)))
            .filter_map(|(x, y)| {
                let omega = geometry.row_solid_angle(y);
                let energy = grid.get(x, y).map(|v| v as f64 * omega);
                (energy != [0.0; 3]).then(|| CoarseTexel {
                    centre: geometry.texel_direction(x, y),
                    cos_radius: radii[y].cos(),
                    sin_radius: radii[y].sin(),
                    energy,
                })
            })
            .collect();
        let map = EnvMap::latlong(grid)?;
        Ok(Reference { integrator: ConeIntegrator::new(&map)?, input, coarse: Some(coarse) })
    }

    /// Whether the input was box-filtered for the reference (then [`Measured::reference_bound`]
    /// bounds what that changes).
    pub fn is_filtered(&self) -> bool {
        self.coarse.is_some()
    }

    /// What the levels are measured against, in words for the manifest.
    pub fn describe(&self) -> String {
        let grid = self.integrator.grid();
        match self.coarse {
            None => format!("the input, latlong {}x{}, summed in angle", grid.width, grid.height),
            Some(_) => format!(
                "the input latlong {}x{} box-filtered to {}x{} and summed in angle; reference_bound bounds what the filtering changes",
                self.input.0, self.input.1, grid.width, grid.height
            ),
        }
    }

    /// Per channel, the bound of the module docs on |B_input(R) − B_reference(R)| for `lobe`
    /// (zero when the input is summed as it is).
    fn filtering_bound(&self, axis: DVec3, lobe: &SplitSumLobe) -> [f64; 3] {
        let Some(coarse) = &self.coarse else { return [0.0; 3] };
        let mut bound = [0.0; 3];
        for t in coarse {
            // cos(γ ∓ ρ) from cos γ = R·c: no angle is computed.
            let cos_gamma = axis.dot(t.centre).clamp(-1.0, 1.0);
            let sin_gamma = (1.0 - cos_gamma * cos_gamma).sqrt();
            let (cc, ss) = (cos_gamma * t.cos_radius, sin_gamma * t.sin_radius);
            // γ − ρ < 0 when cos γ > cos ρ: the texel holds R, where k peaks.
            let nearest = if cos_gamma >= t.cos_radius { 1.0 } else { cc + ss };
            if nearest <= 0.0 {
                continue; // γ − ρ ≥ π/2: the kernel is zero on the whole texel
            }
            // γ + ρ past π when cos γ < −cos ρ; the kernel is zero there anyway.
            let farthest = (cc - ss).max(-1.0);
            let spread = lobe.kernel(nearest) - lobe.kernel(farthest);
            for c in 0..3 {
                bound[c] += t.energy[c] * spread;
            }
        }
        bound
    }

    /// B(R) of `lobe` at any direction, with the texel rule fit for it on this grid chosen once.
    pub fn lobe(&self, lobe: &SplitSumLobe) -> LobeIntegral {
        let grid = self.integrator.grid();
        let cone = (FRAC_PI_2 + 2.0 * PI / grid.height as f64).min(PI);
        let kernel = |c: f64| lobe.kernel(c);
        let choice = rule_for_kernel(grid.width, grid.height, &kernel, cone, grid.height, REFERENCE_RULE_TOLERANCE);
        LobeIntegral { integrator: self.integrator.with_rule(choice.rule), cone, lobe: *lobe }
    }

    /// B(R) at one direction R of prtkit's frame.
    pub fn texel(&self, axis: DVec3, lobe: &SplitSumLobe) -> [f64; 3] {
        self.lobe(lobe).at(axis)
    }

    /// Measures `level` (cube frame; `env_from_cube` takes its directions to prtkit's frame) on
    /// `samples` texels at a fixed stride.
    pub fn measure(&self, level: &CubeMap, lobe: &SplitSumLobe, env_from_cube: DMat3, samples: usize) -> Measured {
        let min_value = level.texels().iter().fold(0.0f32, |m, &v| m.min(v)) as f64;
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
                ((diff, length(reference)), length(self.filtering_bound(axis.normalize(), lobe)))
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
            min_value,
            reference_bound,
        }
    }
}

/// The 2 × 2 box filter of a lat-long image: each texel the solid-angle-weighted mean of the
/// four it covers (the two rows' solid angles differ), so that it keeps their energy.
fn halved(image: &RgbImage) -> RgbImage {
    let fine = LatLong::new(image.width, image.height);
    RgbImage::from_fn(image.width / 2, image.height / 2, |x, y| {
        let (w0, w1) = (fine.row_solid_angle(2 * y), fine.row_solid_angle(2 * y + 1));
        let mut sum = [0.0f64; 3];
        for (row, w) in [(2 * y, w0), (2 * y + 1, w1)] {
            for col in [2 * x, 2 * x + 1] {
                let v = image.get(col, row);
                for c in 0..3 {
                    sum[c] += w * v[c] as f64;
                }
            }
        }
        sum.map(|s| (s / (2.0 * (w0 + w1))) as f32)
    })
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

/// One lobe's angular reference over one environment: B(R) = Σ_t L_t ∫_t k(R·ω) dω.
pub struct LobeIntegral {
    integrator: ConeIntegrator,
    cone: f64,
    lobe: SplitSumLobe,
}

impl LobeIntegral {
    /// B(R) at the direction `axis` of prtkit's frame.
    pub fn at(&self, axis: DVec3) -> [f64; 3] {
        let axis = axis.normalize();
        // The texels kept cover the kernel's whole support and the kernel is normalized (∫ k dω =
        // 1), so the sum needs no division: its weight is 1 up to the rule's tolerance.
        self.integrator.integrate(axis, self.cone, |w| {
            let k = self.lobe.kernel(axis.dot(w));
            [k, k, k]
        })
    }
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
    /// and β is not vacuous (a small share of B for the wide lobes).
    #[test]
    fn the_filtered_reference_is_within_its_bound_of_the_inputs() {
        let map = detailed(256, 128);
        let fine = Reference::new(&map).unwrap();
        let coarse = Reference::with_max_texels(&map, 128 * 64).unwrap();
        assert!(!fine.is_filtered() && coarse.is_filtered());
        assert!(coarse.describe().contains("256x128 box-filtered to 128x64"), "{}", coarse.describe());
        for r in [0.2, 0.5, 1.0] {
            let lobe = SplitSumLobe::new(r).unwrap();
            let (f, c) = (fine.lobe(&lobe), coarse.lobe(&lobe));
            let mut widest: f64 = 0.0;
            for k in 0..40 {
                let z = 1.0 - 2.0 * (k as f64 + 0.5) / 40.0;
                let phi = k as f64 * 2.399_963;
                let axis = DVec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
                let (b_fine, b_coarse, bound) = (f.at(axis), c.at(axis), coarse.filtering_bound(axis, &lobe));
                for ch in 0..3 {
                    let diff = (b_fine[ch] - b_coarse[ch]).abs();
                    // The two sums' texel rules misplace at most 1e-5 of the kernel's weight each.
                    assert!(
                        diff <= bound[ch] + 3e-5 * b_fine[ch],
                        "r {r} axis {axis}: |ΔB| {diff:e} > β {:e}",
                        bound[ch]
                    );
                    widest = widest.max(bound[ch] / b_fine[ch]);
                }
            }
            // Measured: 1.49 at r = 0.2 (the lobe spans a few 2.8° texels), 0.29 at r = 0.5.
            if r >= 0.5 {
                assert!(widest < 0.35, "r {r}: the bound is vacuous ({widest})");
            }
        }
    }

    #[test]
    fn halving_keeps_every_coarse_texels_energy() {
        let map = detailed(64, 32);
        let (fine, coarse) = (LatLong::new(64, 32), LatLong::new(32, 16));
        let half = halved(map.image());
        for y in 0..16 {
            for x in 0..32 {
                let mut e = [0.0f64; 3];
                for (xx, yy) in [(2 * x, 2 * y), (2 * x + 1, 2 * y), (2 * x, 2 * y + 1), (2 * x + 1, 2 * y + 1)] {
                    let v = map.image().get(xx, yy);
                    (0..3).for_each(|c| e[c] += v[c] as f64 * fine.row_solid_angle(yy));
                }
                let v = half.get(x, y);
                for c in 0..3 {
                    let got = v[c] as f64 * coarse.row_solid_angle(y);
                    assert!((got - e[c]).abs() <= 1e-6 * e[c], "({x}, {y}): {got} vs {}", e[c]);
                }
            }
        }
    }
}
