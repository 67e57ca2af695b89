//! Lambertian shading from SH lighting (Ramamoorthi & Hanrahan 2001, eq. 7–9):
//! B(n) = (albedo/π) E(n), E(n) = Σ_lm Â_l L_lm Y_lm(n), Â_l the clamped-cosine kernel.
//! No visibility: the unshadowed irradiance environment map of the paper.

use super::{Hit, Shade};
use crate::sh::convolve::irradiance;
use crate::sh::legendre::LegendreTable;
use crate::sh::synth::eval;
use crate::sh::ShCoeffs;
use glam::DVec3;
use std::f64::consts::PI;

/// The irradiance shader.
pub struct Irradiance {
    e: ShCoeffs,
    table: LegendreTable,
    albedo: f64,
}

impl Irradiance {
    /// From radiance coefficients `light` (any order) and the Lambert albedo.
    pub fn new(light: &ShCoeffs, albedo: f64) -> Self {
        Irradiance { e: irradiance(light), table: LegendreTable::new(light.order), albedo }
    }
}

impl Shade for Irradiance {
    fn shade(&self, hit: &Hit, _wo: DVec3) -> [f64; 3] {
        let mut scratch = Vec::new();
        let e = eval(&self.e, &self.table, hit.n, &mut scratch);
        let k = self.albedo / PI;
        [k * e[0], k * e[1], k * e[2]]
    }
}
