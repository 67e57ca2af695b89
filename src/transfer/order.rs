//! The SH order a transfer bake needs for an energy fraction (`transfer --sh-energy F`): the
//! fewest bands n whose projection holds F of the transfer kernel's energy, the same rule by
//! which `--energy` chooses the glossy terms K (Mahajan, Tseng & Ramamoorthi 2008, §4's
//! energy fraction) applied to the other axis of the K × n² matrix.
//!
//! The kernel is what the transfer integral projects onto SH before visibility cuts it:
//! diffuse, the clamped cosine (ρ/π) max(cos θ, 0), whose band l holds (ρ/π)² Â_l² (2l+1)/4π
//! of its energy (ρ/π)² 2π/3 (Ramamoorthi & Hanrahan 2001, eq. 8–9: 37.5 %, 87.5 % and 99.2 %
//! within 1, 2 and 3 bands); glossy, the lighting-side factors σ_k g_k(ω) [max(cos θ, 0)] on
//! their grid, whose band energies are those of an unshadowed vertex's transfer rows (rotation
//! keeps each band's energy) and whose whole energy is Σ_k σ_k² ∫ g_k² \[cos²\] dω.

use super::glossy::{Glossy, Visibility};
use super::stage::{check_glossy, Error, GlossyConfig};
use crate::factor::CellSamples;
use crate::limits::MAX_TRANSFER_ORDER;
use crate::sh::convolve::clamped_cosine;
use glam::DVec3;
use std::f64::consts::PI;

/// The order chosen for an energy fraction, and what it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Chosen {
    /// Bands n (1 ≤ n ≤ [`MAX_TRANSFER_ORDER`]).
    pub order: usize,
    /// The fraction of the kernel's energy within n bands.
    pub held: f64,
    /// Why, in words, for the manifest.
    pub reason: String,
}

/// The kernel's energy fraction within 1, 2, … [`MAX_TRANSFER_ORDER`] bands: diffuse without
/// `glossy`, else the glossy bake's factors (checked by [`for_energy`]).
fn cumulative_fractions(glossy: Option<&GlossyConfig>) -> Vec<f64> {
    let (bands, total) = match glossy {
        None => {
            let bands = (0..MAX_TRANSFER_ORDER).map(|l| clamped_cosine(l).powi(2) * (2 * l + 1) as f64 / (4.0 * PI));
            (bands.collect::<Vec<f64>>(), 2.0 * PI / 3.0)
        }
        Some(g) => glossy_bands(g),
    };
    bands
        .iter()
        .scan(0.0, |sum, e| {
            *sum += e;
            Some(*sum / total)
        })
        .collect()
}

/// Per band, the energy of the glossy factors' projection, and their whole energy.
fn glossy_bands(g: &GlossyConfig) -> (Vec<f64>, f64) {
    let f = &g.factorization;
    let n = MAX_TRANSFER_ORDER;
    let integrator = Glossy::new(f, g.terms, g.cosine, n, g.cell_samples);
    let mut rows = vec![0.0; integrator.values_per_vertex()];
    integrator.integrate(DVec3::ZERO, DVec3::Z, &Visibility::None, &mut rows);
    let bands = (0..n)
        .map(|l| {
            rows.chunks_exact(n * n).map(|row| row[l * l..(l + 1) * (l + 1)].iter().map(|t| t * t).sum::<f64>()).sum()
        })
        .collect();
    // ∫ (g [cos])² dω over piecewise-constant g: per cell, the samples' squared weights over
    // the plain weight ΔΩ/sub² give ∫_cell [cos²] dω.
    let samples = CellSamples::new(&f.grid, g.cell_samples, !g.cosine);
    let plain = f.grid.cell_solid_angle() / (g.cell_samples * g.cell_samples) as f64;
    let per_cell: Vec<f64> = (0..f.grid.len()).map(|c| samples.of_cell(c).map(|(_, w)| w * w / plain).sum()).collect();
    let total = (0..integrator.terms())
        .map(|k| f.singular_values[k].powi(2) * f.g[k].iter().zip(&per_cell).map(|(gk, q)| gk * gk * q).sum::<f64>())
        .sum();
    (bands, total)
}

/// The fewest bands holding `fraction` of the kernel's energy, at most [`MAX_TRANSFER_ORDER`];
/// a glossy bake's terms and cell samples are checked first, as the bake checks them.
pub fn for_energy(fraction: f64, glossy: Option<&GlossyConfig>) -> Result<Chosen, Error> {
    if !(fraction > 0.0 && fraction <= 1.0) {
        return Err(Error::ShEnergy(fraction));
    }
    if let Some(g) = glossy {
        check_glossy(g)?;
    }
    let held = cumulative_fractions(glossy);
    let kernel = match glossy {
        None => "the clamped cosine's".to_string(),
        Some(g) => format!("the {} kept terms' lighting-side factors'", g.terms),
    };
    Ok(match held.iter().position(|&h| h >= fraction) {
        Some(k) => Chosen {
            order: k + 1,
            held: held[k],
            reason: format!(
                "the fewest bands holding {fraction} of {kernel} energy: {:.4} within {} bands",
                held[k],
                k + 1
            ),
        },
        None => Chosen {
            order: MAX_TRANSFER_ORDER,
            held: held[MAX_TRANSFER_ORDER - 1],
            reason: format!(
                "{fraction} of {kernel} energy needs more than {MAX_TRANSFER_ORDER} bands, the most a bake holds: \
                 {:.4} within {MAX_TRANSFER_ORDER}",
                held[MAX_TRANSFER_ORDER - 1]
            ),
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clamped_cosine_holds_the_textbook_fractions() {
        // Ramamoorthi & Hanrahan 2001: 3/8, 7/8 and 127/128 of the energy within 1, 2 and 3
        // bands (band 2 adds 15/128; odd bands above 1 are empty).
        let held = cumulative_fractions(None);
        for (n, want) in [(1, 3.0 / 8.0), (2, 7.0 / 8.0), (3, 127.0 / 128.0), (4, 127.0 / 128.0)] {
            assert!((held[n - 1] - want).abs() < 1e-12, "{n} bands: {} against {want}", held[n - 1]);
        }
        let order = |f: f64| for_energy(f, None).unwrap().order;
        assert_eq!((order(0.99), order(0.5), order(1.0)), (3, 2, MAX_TRANSFER_ORDER));
        assert!(for_energy(0.0, None).is_err() && for_energy(f64::NAN, None).is_err());
    }
}
