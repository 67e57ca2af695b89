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

use super::angular::LevelError;
use super::cube::{texel_direction, CubeMap};
use super::ggx::SplitSumLobe;
use crate::envmap::zonal::rule_for_kernel;
use crate::envmap::{EnvMap, FACES};
use crate::prefilter::angular::{AngularError, ConeIntegrator};
use glam::{DMat3, DVec3};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// Texel-rule tolerance of the reference (ten times stricter than the bake's).
pub const REFERENCE_RULE_TOLERANCE: f64 = 1e-5;

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
}

/// The reference integrator over one lat-long environment (prtkit's frame).
pub struct Reference {
    integrator: ConeIntegrator,
}

impl Reference {
    /// Prepares the input lat-long map.
    pub fn new(latlong: &EnvMap) -> Result<Self, AngularError> {
        Ok(Reference { integrator: ConeIntegrator::new(latlong)? })
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
        let pairs: Vec<(f64, f64)> = picks
            .par_iter()
            .map(|&i| {
                let (face, row, col) = (FACES[i / (m * m)], (i / m) % m, i % m);
                let axis = env_from_cube * texel_direction(face, m, row, col);
                let reference = integral.at(axis);
                let got = level.get(face, row, col);
                let diff = (0..3).map(|c| (got[c] as f64 - reference[c]).powi(2)).sum::<f64>().sqrt();
                let norm = reference.iter().map(|v| v * v).sum::<f64>().sqrt();
                (diff, norm)
            })
            .collect();
        let pooled = LevelError::pool(&pairs);
        Measured {
            samples: pooled.samples,
            max_rel_error: pooled.max_rel_error,
            rms_rel_error: pooled.rms_rel_error,
            min_value,
        }
    }
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
