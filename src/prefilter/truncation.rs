//! How far out a lobe is summed (R&H 2002 App. D): the cone of half-angle θ* that holds 1 − ε of
//! its weight, for radially symmetric lobes ([`radial_truncation`]) and, against the view
//! angle, for 3-D ones ([`CutoffTable`]); and the texel rule a cone sum integrates the lobe with
//! ([`reference_rule`]).

use super::model::Model;
use super::tuning::{CUTOFF_PHI_SAMPLES, CUTOFF_THETA_SAMPLES, TRUNCATION_PANELS as PANELS};
use crate::envmap::zonal::{self, RuleChoice};
use crate::quadrature::gauss_legendre_cached as gauss_legendre;
use crate::sphere::{self, LatLong};
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};
use std::sync::OnceLock;

/// A truncation of a lobe: the cone angle θ* and the share of the lobe's weight outside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Truncation {
    /// θ* in radians.
    pub theta_star: f64,
    /// ∫ outside the cone / ∫ everywhere (≤ ε).
    pub left_out: f64,
    /// The lobe's width √(∫u dω / max u) in radians: the side of a square of its effective
    /// solid angle (√(2π/(s + 1)) for Phong), how many texels it spans.
    pub width: f64,
}

/// θ* for a radially symmetric lobe u(cos γ) (grey or luminance): the smallest angle whose cone
/// holds 1 − ε of ∫ u dω (App. D), with the share it leaves out.
pub fn radial_truncation(u: impl Fn(f64) -> f64, epsilon: f64) -> Truncation {
    // Cumulative ∫_0^γ u(cos γ') sin γ' dγ' outwards from the axis, by a 4-point Gauss rule on
    // each of 512 equal panels in γ (node spacing ~π/2000, as fine near the axis as a 2000-node
    // rule in cos γ, without solving for its nodes), then the first node where it reaches 1 − ε.
    // The nodes (γ, cos γ, weight × sin γ) are the same for every lobe: computed once, they
    // leave 2 048 evaluations of u per lobe.
    static NODES: OnceLock<Vec<(f64, f64, f64)>> = OnceLock::new();
    let nodes = NODES.get_or_init(|| {
        let rule = gauss_legendre(4);
        let h = PI / PANELS as f64;
        (0..PANELS)
            .flat_map(|k| rule.iter().map(move |&(t, w)| (h * (k as f64 + 0.5 + 0.5 * t), 0.5 * h * w)))
            .map(|(gamma, w)| (gamma, gamma.cos(), w * gamma.sin()))
            .collect()
    });
    let values: Vec<f64> = nodes.iter().map(|&(_, cos, _)| u(cos)).collect();
    let total: f64 = nodes.iter().zip(&values).map(|(n, v)| n.2 * v).sum();
    if total <= 0.0 {
        return Truncation { theta_star: PI, left_out: 0.0, width: 0.0 };
    }
    let peak = values.iter().fold(u(1.0), |a, &b| a.max(b));
    let width = (TAU * total / peak).sqrt();
    let mut acc = 0.0;
    for (&(gamma, _, w), v) in nodes.iter().zip(&values) {
        acc += w * v;
        if acc >= (1.0 - epsilon) * total {
            return Truncation { theta_star: gamma, left_out: (1.0 - acc / total).max(0.0), width };
        }
    }
    Truncation { theta_star: PI, left_out: 0.0, width }
}

/// θ* of [`radial_truncation`].
pub fn radial_cutoff(u: impl Fn(f64) -> f64, epsilon: f64) -> f64 {
    radial_truncation(u, epsilon).theta_star
}

/// The texel rule the reference uses for a radially symmetric lobe u on a W × H source and
/// `out_height` output rows: [`zonal::rule_for_kernel`] with tolerance ε/10, so that the texel
/// integrals misplace at most a tenth of what the truncation leaves out.
pub fn reference_rule(
    grid: LatLong,
    u: &(impl Fn(f64) -> f64 + Sync),
    theta_star: f64,
    out_height: usize,
    epsilon: f64,
) -> RuleChoice {
    zonal::rule_for_kernel(grid.width, grid.height, u, theta_star.clamp(1e-9, PI), out_height, epsilon / 10.0)
}

/// θ*(θ_o) for a 3-D ρ̂ in the reflection frame, tabulated on `bins` values of θ_o ∈ [0, π]: the
/// cone around R that holds 1 − ε of ∫ ρ̂ dω_i for that view angle; beside it the lobe's width
/// √(∫ ρ̂ dω_i / max ρ̂), the side of a square of the lobe's effective solid angle (2.5 s for a
/// Gaussian of deviation s): how fine a grid must be to resolve the lobe, wherever its peak lies.
pub struct CutoffTable {
    theta_star: Vec<f64>,
    width: Vec<f64>,
    left_out: f64,
}

impl CutoffTable {
    /// [`CutoffTable::new`] for `model`'s ρ̂ (luminance), its normal and frame prepared once per
    /// bin ([`Model::prepare_view`] with R = +Z is the reflection frame itself), a half-angle
    /// BRDF's read from its table ([`Model::half_angle_lobe`]: within 10⁻⁵ of the peak, far
    /// below what moves a cone by one of the table's θ_i steps).
    pub fn of_model(model: &Model, epsilon: f64, bins: usize) -> Self {
        let half_angle = model.half_angle_lobe();
        let lobe = |wo: DVec3| {
            let view = model.prepare_view(DVec3::Z, wo);
            move |wi: DVec3| {
                view.as_ref().map_or(0.0, |v| match half_angle {
                    Some(lobe) => lobe.rho_hat(v, wi),
                    None => {
                        let r = model.rho_hat_prepared(v, wi);
                        (r[0] + r[1] + r[2]) / 3.0
                    }
                })
            }
        };
        Self::new(lobe, epsilon, bins)
    }

    /// Tabulates θ* and the width for ρ̂(ω_i, ω_o) (reflection frame, luminance), given as
    /// `rho_hat(ω_o)(ω_i)`, which must be even in φ_i (ω_o lies at φ = 0: the mirror y → −y
    /// leaves an isotropic ρ̂ unchanged), so only φ_i ∈ [0, π] is sampled.
    pub fn new<L: Fn(DVec3) -> f64>(rho_hat: impl Fn(DVec3) -> L + Sync, epsilon: f64, bins: usize) -> Self {
        let (n_theta, n_phi) = (CUTOFF_THETA_SAMPLES, CUTOFF_PHI_SAMPLES);
        // The sample directions, shared by every bin.
        let directions: Vec<DVec3> = (0..n_theta)
            .flat_map(|i| {
                let theta_i = PI * (i as f64 + 0.5) / n_theta as f64;
                (0..n_phi).map(move |k| sphere::direction(theta_i, PI * (k as f64 + 0.5) / n_phi as f64))
            })
            .collect();
        let per_bin: Vec<(f64, f64, f64)> = (0..bins)
            .into_par_iter()
            .map(|b| {
                let theta_o = PI * b as f64 / (bins - 1).max(1) as f64;
                let wo = sphere::direction(theta_o.min(PI - 1e-6), 0.0);
                let rho_hat = rho_hat(wo);
                // Mass per θ_i band (midpoint rule in θ_i, uniform φ_i), and the largest sample.
                let mut peak = 0.0f64;
                let mass: Vec<f64> = directions
                    .chunks(n_phi)
                    .enumerate()
                    .map(|(i, row)| {
                        let theta_i = PI * (i as f64 + 0.5) / n_theta as f64;
                        let s: f64 = row.iter().map(|&wi| rho_hat(wi)).inspect(|&v| peak = peak.max(v)).sum();
                        s * theta_i.sin()
                    })
                    .collect();
                let total: f64 = mass.iter().sum();
                if total <= 0.0 {
                    return (0.0, 0.0, f64::INFINITY);
                }
                // ∫ ρ̂ dω_i over the sphere: the half sphere's midpoint sums, twice.
                let integral = 2.0 * total * (PI / n_theta as f64) * (PI / n_phi as f64);
                let width = (integral / peak).sqrt();
                let mut acc = 0.0;
                for (i, m) in mass.iter().enumerate() {
                    acc += m;
                    if acc >= (1.0 - epsilon) * total {
                        return ((PI * (i + 1) as f64 / n_theta as f64).min(PI), (1.0 - acc / total).max(0.0), width);
                    }
                }
                (PI, 0.0, width)
            })
            .collect();
        CutoffTable {
            theta_star: per_bin.iter().map(|b| b.0).collect(),
            width: per_bin.iter().map(|b| b.2).collect(),
            left_out: per_bin.iter().map(|b| b.1).fold(0.0, f64::max),
        }
    }

    /// θ* for view angle θ_o: the larger of the two neighbouring bins (conservative).
    pub fn at(&self, theta_o: f64) -> f64 {
        let (i0, i1) = self.bins(theta_o);
        self.theta_star[i0].max(self.theta_star[i1])
    }

    /// The lobe's width for view angle θ_o: the smaller of the two neighbouring bins
    /// (conservative: a grid chosen by it is fine enough for both).
    pub fn width_at(&self, theta_o: f64) -> f64 {
        let (i0, i1) = self.bins(theta_o);
        self.width[i0].min(self.width[i1])
    }

    /// The two bins on either side of view angle θ_o (the same bin on a bin).
    fn bins(&self, theta_o: f64) -> (usize, usize) {
        let n = self.theta_star.len();
        let t = (theta_o / PI).clamp(0.0, 1.0) * (n - 1) as f64;
        (t.floor() as usize, (t.ceil() as usize).min(n - 1))
    }

    /// The widest cone of the table.
    pub fn max(&self) -> f64 {
        self.theta_star.iter().cloned().fold(0.0, f64::max)
    }

    /// The largest share of ∫ ρ̂ dω_i any bin's cone leaves out (≤ ε).
    pub fn left_out(&self) -> f64 {
        self.left_out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phong_cutoff_matches_appendix_d_and_its_width_is_the_lobes() {
        for s in [8.0f64, 64.0, 512.0] {
            let u = |x: f64| if x > 0.0 { x.powf(s) } else { 0.0 };
            let got = radial_truncation(u, 0.05);
            let want = 0.05f64.powf(1.0 / (s + 1.0)).acos();
            assert!((got.theta_star - want).abs() < 0.01 * want + 2e-3, "s={s}: {got:?} vs {want}");
            assert!(got.left_out <= 0.05 && got.left_out > 0.04, "{got:?}");
            // ∫ x^s dω = 2π/(s + 1) over the hemisphere, and the peak is 1.
            let width = (TAU / (s + 1.0)).sqrt();
            assert!((got.width - width).abs() < 1e-9 * width, "s={s}: width {} vs {width}", got.width);
        }
    }

    #[test]
    fn the_cutoff_table_width_is_the_side_of_the_lobes_effective_solid_angle() {
        // A normalized Phong lobe about R, whatever the view: ∫ u dω = 1 and max u = (s + 1)/2π,
        // so the width is √(2π/(s + 1)) exactly.
        for s in [8, 64, 512] {
            let u = move |_wo: DVec3| move |wi: DVec3| (s as f64 + 1.0) / TAU * wi.z.max(0.0).powi(s);
            let table = CutoffTable::new(u, 1e-3, 5);
            let exact = (TAU / (s as f64 + 1.0)).sqrt();
            for theta_o in [0.0, 1.0, 2.5] {
                let w = table.width_at(theta_o);
                assert!((w / exact - 1.0).abs() < 5e-3, "s = {s}, θ_o = {theta_o}: {w} against {exact}");
            }
        }
    }
}
