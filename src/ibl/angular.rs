//! The angular GGX prefilter of one cube level, lobe-truncated and read from a mip pyramid of
//! the input cube, with its exact reference and the per-level error measurement.
//!
//! For each output texel direction R the level holds the split-sum prefiltered radiance (Karis
//! 2013; see [`crate::brdf::ggx`]):
//!
//!   B(R) = Σ_ω L(ω) k(R·ω) Ω(ω) / Σ_ω k(R·ω) Ω(ω),
//!
//! over the source texels ω (centre direction, exact solid angle Ω) inside the cone of half-angle
//! θ_ε that holds 1 − ε of the kernel's weight ([`SplitSumLobe::cone_angle`]). Dividing by the
//! discrete weight makes a white environment exactly white whatever the truncation.
//!
//! **Which source level.** The sum is a midpoint rule over source texels, so a texel must be
//! small against the lobe. The lobe's size is its equivalent solid angle Ω_k = 1/k(0) (4πα² for
//! small α, π at α = 1): the solid angle of a flat lobe of the same peak and mass. The prefilter
//! reads the coarsest pyramid level whose largest texel (the face centre's) subtends at most
//! `texel_ratio`·Ω_k. The pyramid's texels are exact means over their footprints
//! ([`CubeMap::downsample`]), so a coarse level is the environment box-filtered, not aliased; what
//! a coarse level loses is *where* in a texel its light is. For a smooth environment that costs
//! a blur of relative variance ~h²/(12w²) (texel width h, lobe width w), but a bright, small
//! source (a window, the sun) is moved to its texel's centre, an error of about the kernel's
//! slope times h/2, i.e. first order in h/w. Measured on Grace Cathedral (a 128² cube, levels
//! 32² at r = 0.4 and 16² at r = 0.8, ε = 1e-4, 64 sampled texels): ratio 1/16 (h ≈ w/4) leaves
//! 1.5–1.6 % RMS and 4.9–6.6 % maximum relative error, 1/256 (h ≈ w/16) 0.07–0.13 % RMS and 0.25–0.4 %
//! maximum. The default, 1/64, is measured in `docs/ibl-building-blocks.md`.
//!
//! **Truncation.** GGX's tail is heavy (the weight beyond θ is ≈ α²/(α² + θ²/4)), and an HDR
//! environment puts much light in it: on the same probe, ε = 1e-2 leaves 2–5 % RMS error
//! whatever the source level, ε = 1e-4 (the default) well under the level error above.
//!
//! **Which source texels.** Per face, the cone's footprint on the face plane is bounded in closed
//! form: on the cone's rim d(ψ) = cos θ_ε R + sin θ_ε (cos ψ e₁ + sin ψ e₂) the face coordinate
//! s = d·u_s / d·a is a ratio of two sinusoids in ψ, whose extremes solve P sin ψ + Q cos ψ + S = 0
//! (P = AE − BD, Q = CD − AF, S = CE − BF for s = (A + B cos ψ + C sin ψ)/(D + E cos ψ + F sin ψ)).
//! A face whose normal is farther than θ_ε + acos(1/√3) from R is skipped (every face direction
//! is within acos(1/√3) of its normal); one the cone straddles (d·a changes sign on it, which
//! needs θ_ε > 35°) is scanned whole. Every candidate texel is then tested exactly against cos θ_ε.
//!
//! **Determinism.** Each output texel is one sequential sum in a fixed order (faces, rows,
//! columns), computed by whichever thread takes its row: the result is identical for any number of
//! threads.

use super::cube::{face_direction, texel_direction, texel_solid_angles, CubeError, CubeMap, CubeMipChain};
use crate::brdf::ggx::{GgxError, SplitSumLobe};
use crate::envmap::{Face, FACES};
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::FRAC_PI_2;

/// Errors of the angular prefilter.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum AngularError {
    /// A bad roughness.
    #[error(transparent)]
    Roughness(#[from] GgxError),
    /// A bad cube size.
    #[error(transparent)]
    Cube(#[from] CubeError),
    /// Roughness 0 asks for the environment itself, which the pyramid must hold at that size.
    #[error("roughness 0 copies the source, but the pyramid has no {0}² level")]
    NoLevel(usize),
    /// A truncation tolerance ε outside [0, 1).
    #[error("the truncation tolerance ε = {0} is outside [0, 1)")]
    Epsilon(f64),
    /// A largest source texel (as a fraction of the lobe's solid angle) that is not positive.
    #[error("the texel ratio {0} is not positive")]
    TexelRatio(f64),
}

/// How the angular prefilter trades accuracy for time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngularOptions {
    /// ε: the share of the kernel's weight left outside the cone (0 = the whole support).
    /// Default 1e-4.
    pub epsilon: f64,
    /// Largest source texel solid angle as a fraction of the lobe's equivalent solid angle.
    /// Default 1/64 (texels about an eighth of the lobe's width).
    pub texel_ratio: f64,
}

impl Default for AngularOptions {
    fn default() -> Self {
        AngularOptions { epsilon: 1e-4, texel_ratio: 1.0 / 64.0 }
    }
}

/// One pyramid level with its texel directions and solid angles.
struct LevelGeometry {
    size: usize,
    /// Unit centre directions, face-major then row-major.
    dirs: Vec<DVec3>,
    /// Solid angles of one face's texels (the same on every face).
    omega: Vec<f64>,
}

impl LevelGeometry {
    fn new(size: usize) -> Result<Self, CubeError> {
        let mut dirs = Vec::with_capacity(6 * size * size);
        for face in FACES {
            for row in 0..size {
                for col in 0..size {
                    dirs.push(texel_direction(face, size, row, col));
                }
            }
        }
        Ok(LevelGeometry { size, dirs, omega: texel_solid_angles(size)? })
    }

    /// The largest texel solid angle (at the face centre).
    fn max_solid_angle(&self) -> f64 {
        let c = self.size / 2;
        self.omega[c * self.size + c]
    }
}

/// What one prefiltered level was made from.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LevelSource {
    /// Face size of the pyramid level read.
    pub source_size: usize,
    /// The truncation cone's half-angle θ_ε in radians.
    pub cone_angle: f64,
}

/// Error of a level against the exact reference on sampled texels.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LevelError {
    /// Texels sampled.
    pub samples: usize,
    /// Texels whose reference is above the floor (the ones the figures pool).
    pub counted: usize,
    /// The floor: 1 % of the mean reference magnitude ‖rgb‖.
    pub floor: f64,
    /// max ‖a − r‖/‖r‖ over the counted texels.
    pub max_rel_error: f64,
    /// √(mean (‖a − r‖/‖r‖)²) over the counted texels.
    pub rms_rel_error: f64,
}

impl LevelError {
    /// Pools (‖a − r‖, ‖r‖) pairs of sampled texels: relative errors over the texels whose
    /// reference is above 1 % of the sampled mean (darker ones would make any error relative to
    /// nearly nothing).
    pub fn pool(pairs: &[(f64, f64)]) -> Self {
        let floor = 0.01 * pairs.iter().map(|p| p.1).sum::<f64>() / pairs.len().max(1) as f64;
        let rel: Vec<f64> = pairs.iter().filter(|p| p.1 > floor).map(|p| p.0 / p.1).collect();
        let rms = (rel.iter().map(|e| e * e).sum::<f64>() / rel.len().max(1) as f64).sqrt();
        LevelError {
            samples: pairs.len(),
            counted: rel.len(),
            floor,
            max_rel_error: rel.iter().cloned().fold(0.0, f64::max),
            rms_rel_error: rms,
        }
    }
}

/// The angular prefilter over a mip pyramid of the input cube.
pub struct AngularPrefilter {
    chain: CubeMipChain,
    geometry: Vec<LevelGeometry>,
}

impl AngularPrefilter {
    /// Prepares the pyramid (texel directions and solid angles of every level).
    pub fn new(chain: CubeMipChain) -> Result<Self, AngularError> {
        let geometry = chain.levels().iter().map(|l| LevelGeometry::new(l.size())).collect::<Result<_, _>>()?;
        Ok(AngularPrefilter { chain, geometry })
    }

    /// The pyramid.
    pub fn chain(&self) -> &CubeMipChain {
        &self.chain
    }

    /// The pyramid level the rule picks for a lobe: the coarsest whose largest texel subtends at
    /// most `texel_ratio` of the lobe's equivalent solid angle (level 0 if none does).
    pub fn source_level(&self, lobe: &SplitSumLobe, texel_ratio: f64) -> usize {
        let budget = texel_ratio * lobe.equivalent_solid_angle();
        (0..self.geometry.len()).rev().find(|&i| self.geometry[i].max_solid_angle() <= budget).unwrap_or(0)
    }

    /// Prefilters one output level of face size `size` for perceptual roughness r. Roughness 0
    /// copies the pyramid level of that size.
    pub fn prefilter(
        &self,
        size: usize,
        perceptual_roughness: f64,
        options: &AngularOptions,
        progress: &dyn Progress,
    ) -> Result<(CubeMap, LevelSource), AngularError> {
        if !(0.0..1.0).contains(&options.epsilon) {
            return Err(AngularError::Epsilon(options.epsilon));
        }
        if options.texel_ratio.is_nan() || options.texel_ratio <= 0.0 {
            return Err(AngularError::TexelRatio(options.texel_ratio));
        }
        let mut out = CubeMap::new(size)?;
        if perceptual_roughness == 0.0 {
            let level = self.chain.levels().iter().find(|l| l.size() == size).ok_or(AngularError::NoLevel(size))?;
            return Ok((level.clone(), LevelSource { source_size: size, cone_angle: 0.0 }));
        }
        let lobe = SplitSumLobe::new(perceptual_roughness)?;
        let src = self.source_level(&lobe, options.texel_ratio);
        let (level, geometry) = (&self.chain.levels()[src], &self.geometry[src]);
        // At least one source texel spacing, so that the cone never falls between texel centres.
        let spacing = 2.0 / geometry.size as f64;
        let cone = lobe.cone_angle(options.epsilon).max(1.5 * spacing).min(FRAC_PI_2);
        progress.start(&format!("angular GGX r={perceptual_roughness}"), (6 * size) as u64);
        out.texels_mut().par_chunks_mut(size * 3).enumerate().for_each(|(face_row, row)| {
            let (face, r) = (FACES[face_row / size], face_row % size);
            for (c, px) in row.chunks_exact_mut(3).enumerate() {
                let axis = texel_direction(face, size, r, c);
                let texels = level.texels();
                let sum = cone_sum(axis, cone, &lobe, geometry.size, &geometry.omega, |index| {
                    (geometry.dirs[index], [texels[3 * index], texels[3 * index + 1], texels[3 * index + 2]])
                });
                let v = sum.unwrap_or_else(|| level.lookup_nearest(axis).map(|x| x as f64));
                px.copy_from_slice(&[v[0] as f32, v[1] as f32, v[2] as f32]);
            }
            progress.advance(1);
        });
        progress.finish();
        Ok((out, LevelSource { source_size: geometry.size, cone_angle: cone }))
    }

    /// The exact reference at direction R: the kernel over its whole support (no truncation)
    /// against the full-resolution base level taken as piecewise constant, each base texel split
    /// into k² sub-texels with their own directions and exact solid angles (`omega`, one face of
    /// the supersampled grid's).
    fn reference_with(&self, axis: DVec3, lobe: &SplitSumLobe, k: usize, omega: &[f64]) -> [f64; 3] {
        let base = self.chain.base();
        let n = base.size();
        let fine = n * k;
        let texels = base.texels();
        cone_sum(axis, FRAC_PI_2, lobe, fine, omega, |index| {
            let (f, row, col) = (index / (fine * fine), (index / fine) % fine, index % fine);
            let i = 3 * ((f * n + row / k) * n + col / k);
            (texel_direction(FACES[f], fine, row, col), [texels[i], texels[i + 1], texels[i + 2]])
        })
        .unwrap_or([0.0; 3])
    }

    /// Measures a prefiltered level against the exact reference (`supersample`² sub-texels per
    /// base texel, whole support) on `samples` texels spread evenly over the six faces (a fixed
    /// stride: the same texels every run), pooling texels whose reference magnitude is above 1 %
    /// of the sampled mean.
    pub fn measure(
        &self,
        level: &CubeMap,
        perceptual_roughness: f64,
        samples: usize,
        supersample: usize,
    ) -> Result<LevelError, AngularError> {
        let lobe = SplitSumLobe::new(perceptual_roughness)?;
        let m = level.size();
        let total = 6 * m * m;
        let stride = (total / samples.max(1)).max(1);
        let picks: Vec<usize> = (0..total).step_by(stride).map(|i| (i + stride / 2).min(total - 1)).collect();
        let k = supersample.max(1);
        let omega = texel_solid_angles(self.chain.base().size() * k)?;
        let pairs: Vec<(f64, f64)> = picks
            .par_iter()
            .map(|&i| {
                let (face, row, col) = (FACES[i / (m * m)], (i / m) % m, i % m);
                let reference = self.reference_with(texel_direction(face, m, row, col), &lobe, k, &omega);
                let got = level.get(face, row, col);
                let diff: f64 = (0..3).map(|c| (got[c] as f64 - reference[c]).powi(2)).sum::<f64>().sqrt();
                let norm: f64 = reference.iter().map(|v| v * v).sum::<f64>().sqrt();
                (diff, norm)
            })
            .collect();
        Ok(LevelError::pool(&pairs))
    }
}

/// Σ L k Ω / Σ k Ω over the texels of an n×n cube within `cone` of `axis`, in a fixed order.
/// `omega` holds one face's solid angles; `texel(index)` gives the direction and radiance of
/// texel `index` = (face·n + row)·n + column. `None` if no texel centre lies in the cone.
fn cone_sum(
    axis: DVec3,
    cone: f64,
    lobe: &SplitSumLobe,
    n: usize,
    omega: &[f64],
    texel: impl Fn(usize) -> (DVec3, [f32; 3]),
) -> Option<[f64; 3]> {
    let cos_cone = cone.cos();
    let (mut sum, mut weight) = ([0.0f64; 3], 0.0f64);
    for (f, face) in FACES.iter().enumerate() {
        let Some((r0, r1, c0, c1)) = face_window(*face, axis, cone, n) else { continue };
        for row in r0..=r1 {
            let row_start = (f * n + row) * n;
            for col in c0..=c1 {
                let (d, l) = texel(row_start + col);
                if d.dot(axis) < cos_cone {
                    continue;
                }
                let w = lobe.kernel_from_half_chord(0.25 * (axis - d).length_squared()) * omega[row * n + col];
                for ch in 0..3 {
                    sum[ch] += w * l[ch] as f64;
                }
                weight += w;
            }
        }
    }
    (weight > 0.0).then(|| sum.map(|s| s / weight))
}

/// acos(1/√3): the angle between a face's normal and its corners.
const FACE_CORNER_ANGLE: f64 = 0.955_316_618_124_509_3;

/// Rows r0..=r1 and columns c0..=c1 of an n×n face that can hold directions within `cone` of
/// `axis` (see the module docs), or `None` if the cone misses the face.
fn face_window(face: Face, axis: DVec3, cone: f64, n: usize) -> Option<(usize, usize, usize, usize)> {
    let full = Some((0, n - 1, 0, n - 1));
    let a = face_direction(face, 0.0, 0.0);
    let (sin_c, cos_c) = cone.sin_cos();
    let ra = axis.dot(a);
    // Every direction of the face lies within acos(1/√3) (the corner) of its normal a.
    if ra.clamp(-1.0, 1.0).acos() - cone > FACE_CORNER_ANGLE {
        return None;
    }
    if cone >= FRAC_PI_2 || ra.abs() <= sin_c {
        // The cone reaches behind the face plane: its footprint is unbounded.
        return if ra < -sin_c { None } else { full };
    }
    if ra < 0.0 {
        return None;
    }
    let u_s = face_direction(face, 1.0, 0.0) - a;
    let u_t = face_direction(face, 0.0, 1.0) - a;
    let e1 = axis.any_orthonormal_vector();
    let e2 = axis.cross(e1);
    let extent = |u: DVec3| -> (f64, f64) {
        let (aa, b, c) = (cos_c * axis.dot(u), sin_c * e1.dot(u), sin_c * e2.dot(u));
        let (d, e, f) = (cos_c * ra, sin_c * e1.dot(a), sin_c * e2.dot(a));
        let ratio = |psi: f64| {
            let (s, co) = psi.sin_cos();
            (aa + b * co + c * s) / (d + e * co + f * s)
        };
        let (p, q, r) = (aa * e - b * d, c * d - aa * f, c * e - b * f);
        let rho = p.hypot(q);
        if rho < 1e-300 {
            let v = ratio(0.0);
            return (v, v);
        }
        let phase = q.atan2(p);
        let base = (-r / rho).clamp(-1.0, 1.0).asin();
        let (v1, v2) = (ratio(base - phase), ratio(std::f64::consts::PI - base - phase));
        (v1.min(v2), v1.max(v2))
    };
    let (s_lo, s_hi) = extent(u_s);
    let (t_lo, t_hi) = extent(u_t);
    if s_hi < -1.0 || s_lo > 1.0 || t_hi < -1.0 || t_lo > 1.0 {
        return None;
    }
    // Face coordinate → texel index, with one texel of slack for rounding.
    let lo = |x: f64| (((x + 1.0) * 0.5 * n as f64).floor() as isize - 1).clamp(0, n as isize - 1) as usize;
    let hi = |x: f64| (((x + 1.0) * 0.5 * n as f64).floor() as isize + 1).clamp(0, n as isize - 1) as usize;
    Some((lo(t_lo), hi(t_hi), lo(s_lo), hi(s_hi)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;
    use std::f64::consts::PI;

    fn sky(size: usize) -> CubeMap {
        // A smooth sky with a sun: 1 + 0.5 y + 50·max(d·s, 0)^40 in the cube frame.
        let sun = DVec3::new(0.3, 0.8, -0.5).normalize();
        CubeMap::from_fn(size, |d| {
            let v = 1.0 + 0.5 * d.y + 50.0 * d.dot(sun).max(0.0).powi(40);
            [v as f32, (0.8 * v) as f32, (0.6 * v) as f32]
        })
        .unwrap()
    }

    #[test]
    fn windows_hold_every_texel_of_the_cone() {
        // The closed-form face windows against a full scan: same texel count for many axes and
        // cone angles, on every face.
        let n = 32;
        let mut x = 0.37f64;
        for _ in 0..300 {
            x = (x + 0.618_033_988_749_895) % 1.0;
            let z = 2.0 * x - 1.0;
            let phi = 2.0 * PI * ((x * 104_729.0) % 1.0);
            let axis = DVec3::new((1.0 - z * z).sqrt() * phi.cos(), (1.0 - z * z).sqrt() * phi.sin(), z);
            for cone in [0.01, 0.05, 0.2, 0.6, 1.2, FRAC_PI_2] {
                for face in FACES {
                    let full: usize =
                        (0..n * n).filter(|&i| texel_direction(face, n, i / n, i % n).dot(axis) >= cone.cos()).count();
                    let windowed = face_window(face, axis, cone, n).map_or(0, |(r0, r1, c0, c1)| {
                        (r0..=r1)
                            .flat_map(|r| (c0..=c1).map(move |c| (r, c)))
                            .filter(|&(r, c)| texel_direction(face, n, r, c).dot(axis) >= cone.cos())
                            .count()
                    });
                    assert_eq!(windowed, full, "axis {axis} cone {cone} {face:?}");
                }
            }
        }
    }

    #[test]
    fn white_furnace_is_exact() {
        let white = CubeMap::from_fn(32, |_| [1.0, 2.0, 0.5]).unwrap();
        let pre = AngularPrefilter::new(CubeMipChain::pyramid(white, 1).unwrap()).unwrap();
        for r in [0.05, 0.3, 1.0] {
            let (out, _) = pre.prefilter(8, r, &AngularOptions::default(), &NoProgress).unwrap();
            for px in out.texels().chunks(3) {
                assert!((px[0] - 1.0).abs() < 1e-6 && (px[1] - 2.0).abs() < 1e-6 && (px[2] - 0.5).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn matches_the_frequency_space_answer_for_a_linear_environment() {
        // L(ω) = a + b·ω is band-limited to l ≤ 1, so the prefiltered map is a + Λ_1 k_1 b·R exactly
        // (the convolution theorem with the zonal factors of the lobe).
        let b = DVec3::new(0.2, -0.3, 0.4);
        let env = CubeMap::from_fn(64, |d| [(1.0 + b.dot(d)) as f32; 3]).unwrap();
        let pre = AngularPrefilter::new(CubeMipChain::pyramid(env, 1).unwrap()).unwrap();
        for r in [0.3, 0.6, 1.0] {
            let factor = SplitSumLobe::new(r).unwrap().convolution_factors(1)[1];
            let options = AngularOptions { epsilon: 0.0, texel_ratio: 1.0 / 16.0 };
            let (out, _) = pre.prefilter(8, r, &options, &NoProgress).unwrap();
            for face in FACES {
                for i in 0..64 {
                    let d = texel_direction(face, 8, i / 8, i % 8);
                    let want = 1.0 + factor * b.dot(d);
                    let got = out.get(face, i / 8, i % 8)[0] as f64;
                    assert!((got - want).abs() < 3e-3, "r={r} {face:?} {i}: {got} vs {want}");
                }
            }
        }
    }

    #[test]
    fn pyramid_level_choice_stays_within_the_error_target() {
        let pre = AngularPrefilter::new(CubeMipChain::pyramid(sky(64), 1).unwrap()).unwrap();
        for (size, r) in [(32, 0.3), (16, 0.6), (8, 1.0)] {
            let (out, source) = pre.prefilter(size, r, &AngularOptions::default(), &NoProgress).unwrap();
            let err = pre.measure(&out, r, 96, 1).unwrap();
            assert!(source.source_size < 64 || r == 0.3, "r={r}: read {}", source.source_size);
            assert!(err.rms_rel_error < 0.01 && err.max_rel_error < 0.05, "r={r}: {err:?}");
            assert_eq!(err.samples, 96);
        }
    }

    #[test]
    fn edges_of_adjacent_faces_agree() {
        // Texels are filtered by direction, so the two texels across an edge differ only by the
        // change of B over one texel: compare with the change between neighbours within a face.
        let pre = AngularPrefilter::new(CubeMipChain::pyramid(sky(32), 1).unwrap()).unwrap();
        let (out, _) = pre.prefilter(16, 0.5, &AngularOptions::default(), &NoProgress).unwrap();
        let n = 16;
        let mut worst_seam = 0.0f32;
        let mut worst_inside = 0.0f32;
        for face in FACES {
            for k in 0..n {
                let v = out.get(face, 0, k);
                let d = face_direction(face, super::super::cube::texel_coordinate(n, k), -1.0 - 1.0 / n as f64);
                let across = out.lookup_nearest(d);
                worst_seam = worst_seam.max((v[0] - across[0]).abs());
                worst_inside = worst_inside.max((v[0] - out.get(face, 1, k)[0]).abs());
            }
        }
        assert!(worst_seam <= 1.5 * worst_inside, "seam {worst_seam} vs inside {worst_inside}");
    }

    #[test]
    fn deterministic_across_thread_counts() {
        let pre = AngularPrefilter::new(CubeMipChain::pyramid(sky(32), 1).unwrap()).unwrap();
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| pre.prefilter(16, 0.4, &AngularOptions::default(), &NoProgress).unwrap().0)
        };
        let one = run(1);
        assert_eq!(one.texels(), run(3).texels());
    }

    #[test]
    fn roughness_zero_copies_the_level_and_errors_are_typed() {
        let cube = sky(16);
        let pre = AngularPrefilter::new(CubeMipChain::pyramid(cube.clone(), 4).unwrap()).unwrap();
        assert_eq!(pre.prefilter(16, 0.0, &AngularOptions::default(), &NoProgress).unwrap().0, cube);
        assert_eq!(
            pre.prefilter(32, 0.0, &AngularOptions::default(), &NoProgress).unwrap_err(),
            AngularError::NoLevel(32)
        );
        let bad = AngularOptions { epsilon: 1.0, texel_ratio: 0.1 };
        assert_eq!(pre.prefilter(8, 0.5, &bad, &NoProgress).unwrap_err(), AngularError::Epsilon(1.0));
        let bad = AngularOptions { epsilon: 1e-4, texel_ratio: 0.0 };
        assert_eq!(pre.prefilter(8, 0.5, &bad, &NoProgress).unwrap_err(), AngularError::TexelRatio(0.0));
        assert!(matches!(
            pre.prefilter(8, 1.5, &AngularOptions::default(), &NoProgress),
            Err(AngularError::Roughness(_))
        ));
    }
}
