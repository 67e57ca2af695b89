//! Choosing the orders F_B, P_B. Two rules (`--order-rule`):
//!
//! - **energy** (R&H 2002 §5.1): the smallest orders keeping 1 − ε of the BRDF's energy. It looks
//!   at the BRDF alone, so under HDR lighting the kernel tail it leaves multiplies a sun 10⁴×
//!   brighter than the sky: rings far above the sky's own level, hidden in a relative RMS.
//! - **texel** (the default): the smallest F_B whose worst-case error at any texel stays under
//!   ε × the texel floor — App. B's residual bound taken to L∞ (`docs/prefilter.md`). Band l of
//!   the light field at a texel is Σ_{p,q} ρ̂_lpq (D^l(R) L_l)_q Y_pq(ω_o); a row of the
//!   rotation matrix D^l has unit norm, so |(D^l L_l)_q| ≤ √E_l (E_l = Σ_m L_lm², the band's
//!   energy) and |Y_pq| ≤ √((2p+1)/4π). Bands beyond F_B thus change a texel by at most
//!
//!   e(F) = Σ_{l > F}^{l_max} √E_l · Σ_{p ≤ P, |q| ≤ min(l,p)} |ρ̂_lpq| √((2p+1)/4π),      (1)
//!
//!   whatever R and ω_o, and the rule asks e(F_B) ≤ ε · floor with floor = [`TEXEL_FLOOR`] × the
//!   mean reflected radiance (the darkest texels the per-texel error counts). l_max is the
//!   highest band the map resolves: beyond it the map holds no information, and F_B is capped
//!   there (the document says so).
//!
//!   The lighting need not be projected to l_max to apply (1): bands above the projected order L
//!   hold at most the map's whole energy ∫ L² dω (Bessel's inequality), so by Cauchy–Schwarz
//!   they add at most √(∫ L² dω) · √(Σ_{l > L} w_l²) to e(F), w_l being band l's factor in (1).
//!   The rule projects to the first L at which that term is under 1 % of ε × the floor
//!   ([`first_projection`]) and projects further only when the term decides F_B: the F_B it
//!   returns is the one a projection to l_max gives, at the cost of a projection to L (Phong
//!   s = 8 on Grace at 256×128: L = 23 against l_max = 127; s = 128: L = 65, F_B = 52).
//!
//!   For view-dependent BRDFs a tighter form per view angle θ_o (cos θ_o = R·V): at a fixed ω_o,
//!   band l of ρ̂ as a function of ω_i has norm n_l(θ_o), and by Cauchy–Schwarz per band
//!
//!   e(F, θ_o) = Σ_{l > F}^{l_max} √E_l · n_l(θ_o).                                         (2)
//!
//!   ρ̂'s horizon (N·ω_i = 0) makes its expansion converge slowly at grazing view angles, which
//!   would drive (1) to l_max; (2) is taken over θ_o ≤ 90° only. P_B is chosen from how well the
//!   expansion represents ρ̂ per view angle: the relative L² residual r(θ_o) = ‖ρ̂ − ρ̂_FP‖/‖ρ̂‖
//!   over ω_i. Texels whose θ_o has r(θ_o) > ε are outside the SHRM's valid range; reflection
//!   maps compute them by angular integration instead.

use super::brdf_sh::BrdfSh;
use super::model::Model;
use super::tuning::{FIRST_PROJECTION_SHARE, VIEW_ANGLES, VIEW_RESIDUAL_FACTOR, VIEW_SAMPLE_NODES as NODES};
use crate::metrics::TEXEL_FLOOR;
use crate::quadrature::gauss_legendre_cached as gauss_legendre;
use crate::sh::legendre::LegendreTable;
use crate::sh::{count, index, ShCoeffs};
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// How the orders are chosen (`--order-rule`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum OrderRule {
    /// The worst-case per-texel error under ε × the texel floor, for this lighting.
    #[default]
    Texel,
    /// 1 − ε of the BRDF's energy (R&H 2002 §5.1; the paper's Tables 4–5).
    Energy,
}

/// Orders chosen by the texel rule, with what they guarantee.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TexelOrders {
    /// F_B.
    pub f_b: usize,
    /// P_B.
    pub p_b: usize,
    /// The bound (1) at F_B, relative to the texel floor: ≤ ε unless `capped`.
    pub bound: f64,
    /// The highest band the map resolves.
    pub l_max: usize,
    /// True when even l_max does not meet ε (F_B = l_max then).
    pub capped: bool,
    /// Largest view angle θ_o (degrees) up to which r(θ_o) ≤ ε (180 for radially symmetric
    /// BRDFs): texels beyond it fall back to angular integration in reflection maps.
    pub valid_view_angle: f64,
}

/// |Y_pq(θ_o, ·)| at its largest over φ_o: √2 |P̄_p^|q|(cos θ_o)| (q ≠ 0) or |P̄_p^0(cos θ_o)|,
/// per index p(p+1)+q; `None`: the bound over every θ_o, √((2p+1)/4π).
fn view_weights(p: usize, theta_o: Option<f64>) -> Vec<f64> {
    let mut out = vec![0.0; count(p)];
    match theta_o {
        None => {
            for pp in 0..=p {
                for q in -(pp as isize)..=(pp as isize) {
                    out[index(pp, q)] = ((2 * pp + 1) as f64 / (4.0 * PI)).sqrt();
                }
            }
        }
        Some(t) => {
            let mut plm = vec![0.0; count(p)];
            LegendreTable::new(p).eval(t.cos(), t.sin().abs(), &mut plm);
            for pp in 0..=p {
                for q in -(pp as isize)..=(pp as isize) {
                    let scale = if q == 0 { 1.0 } else { std::f64::consts::SQRT_2 };
                    out[index(pp, q)] = scale * plm[index(pp, q.abs())].abs();
                }
            }
        }
    }
    out
}

/// Band l's factor in (1) per channel for l ≤ l_max: w_l = Σ_{p ≤ P, |q| ≤ min(l,p)} |ρ̂_lpq| ·
/// `weights` (the bound on |Y_pq|, index p(p+1)+q).
fn band_weights(brdf: &BrdfSh, p: usize, l_max: usize, weights: &[f64]) -> Vec<[f64; 3]> {
    (0..=l_max)
        .map(|l| {
            let mut w = [0.0; 3];
            for pp in 0..=p {
                for q in -(l.min(pp) as isize)..=(l.min(pp) as isize) {
                    let r = brdf.get(l, pp, q);
                    for c in 0..3 {
                        w[c] += r[c].abs() * weights[index(pp, q)];
                    }
                }
            }
            w
        })
        .collect()
}

/// The lighting as the texel rule sees it: band energies E_l = Σ_m L_lm² per channel as far as
/// the lighting was projected (l ≤ L), and a bound on all the bands above L up to l_max.
#[derive(Clone, Debug, PartialEq)]
pub struct LightEnergy {
    /// E_l for l ≤ L.
    pub bands: Vec<[f64; 3]>,
    /// At least Σ_{L < l ≤ l_max} E_l per channel.
    pub above: [f64; 3],
    /// The highest band the map resolves (at least L).
    pub l_max: usize,
}

impl LightEnergy {
    /// The bands of `light` (projected to L ≤ `l_max`) with `map_energy` = ∫ L² dω of the map it
    /// was projected from bounding those above (Bessel's inequality; nothing is above when
    /// L = l_max).
    pub fn projected(light: &ShCoeffs, map_energy: [f64; 3], l_max: usize) -> Self {
        let above = if light.order >= l_max { [0.0; 3] } else { map_energy };
        LightEnergy { bands: light.band_energy_rgb().into_iter().take(l_max + 1).collect(), above, l_max }
    }

    /// Every band known: l_max is the last one.
    pub fn exact(bands: Vec<[f64; 3]>) -> Self {
        let l_max = bands.len().saturating_sub(1);
        LightEnergy { bands, above: [0.0; 3], l_max }
    }
}

/// e(F) of (1) or (2) per channel for every F ≤ l_max (0 at l_max), given band l's factor
/// `weights[l]`: the projected bands' Σ_{F < l ≤ L} √E_l w_l plus the bands above L by
/// Cauchy–Schwarz, √above · √(Σ_{max(F,L) < l ≤ l_max} w_l²). Second, the projected bands' part
/// alone: no more than e(F) with every band projected, so an F it rejects, a projection to
/// l_max rejects too.
fn tails(weights: &[[f64; 3]], light: &LightEnergy) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let (l_max, projected) = (light.l_max, light.bands.len() - 1);
    let (mut known, mut above) = (vec![[0.0; 3]; l_max + 1], vec![[0.0; 3]; l_max + 1]);
    for f in (0..l_max).rev() {
        let l = f + 1;
        for c in 0..3 {
            if l <= projected {
                known[f][c] = known[f + 1][c] + light.bands[l][c].max(0.0).sqrt() * weights[l][c];
                above[f][c] = above[f + 1][c];
            } else {
                above[f][c] = above[f + 1][c] + weights[l][c] * weights[l][c];
            }
        }
    }
    let tail = known.iter().zip(&above).map(|(k, a)| std::array::from_fn(|c| k[c] + (light.above[c] * a[c]).sqrt()));
    (tail.collect(), known)
}

/// The band [`texel_orders`] is given the lighting to first: the smallest L ≤ `l_max` at which
/// the bound on the bands above it, √(∫ L² dω) · √(Σ_{L < l ≤ l_max} w_l²) with the BRDF's
/// factors w_l of (1) (every view angle, P = `max_p`), is under [`FIRST_PROJECTION_SHARE`] of
/// ε × the texel floor in every channel. `map_energy` is ∫ L² dω, `mean_reflected` the mean
/// reflected radiance the floor is a fraction of. The bound then barely moves e(F), so the rule
/// decides F_B at this L unless the projected bands alone come within 1 % of ε at F_B − 1; and
/// L is no larger than it must be: the projection's cost grows as L² (Phong s = 128 on Grace at
/// 256×128: L = 65 where twice the band at which w_l falls to 10⁻³ was 84, for F_B = 52).
pub fn first_projection(
    model: &Model,
    brdf: &BrdfSh,
    max_p: usize,
    l_max: usize,
    map_energy: [f64; 3],
    mean_reflected: [f64; 3],
    epsilon: f64,
) -> usize {
    let p = if model.centre().is_some() { 0 } else { max_p.min(brdf.p) };
    let l_max = l_max.min(brdf.f);
    let w = band_weights(brdf, p, l_max, &view_weights(p, None));
    let allowed = mean_reflected.map(|m| FIRST_PROJECTION_SHARE * epsilon * TEXEL_FLOOR * m.abs());
    // Σ_{L < l ≤ l_max} w_l² per channel, from L = l_max down.
    let mut above = [0.0; 3];
    let mut first = l_max;
    for l in (0..l_max).rev() {
        for c in 0..3 {
            above[c] += w[l + 1][c] * w[l + 1][c];
        }
        let fits = (0..3).all(|c| allowed[c] <= 0.0 || (map_energy[c] * above[c]).sqrt() <= allowed[c]);
        if !fits {
            break;
        }
        first = l;
    }
    first
}

/// The texel rule. `brdf` holds ρ̂_lpq to at least (l_max, max_p), l_max being `light`'s;
/// `mean_reflected` is the mean radiance of the reflection map (per channel) the floor is a
/// fraction of. `None` when the bound on the bands above the projected ones decides F_B: the
/// lighting must then be projected further.
///
/// For view-dependent BRDFs P_B comes first: the smallest P whose expansion (with every band the
/// map resolves) represents ρ̂ within ε for all view angles up to 90° (normals within 45° of the
/// view), or `max_p`; its valid range is where r(θ_o) ≤ ε. F_B then takes the bound (1) with
/// |Y_pq(ω_o)| at its largest over that range only: grazing views, where ρ̂'s horizon makes its
/// expansion converge slowly, are integrated in angle and need not drive F_B.
pub fn texel_orders(
    model: &Model,
    brdf: &BrdfSh,
    light: &LightEnergy,
    mean_reflected: [f64; 3],
    epsilon: f64,
    max_p: usize,
) -> Option<TexelOrders> {
    let l_max = light.l_max.min(brdf.f);
    let light = &LightEnergy { bands: light.bands.iter().take(l_max + 1).copied().collect(), l_max, ..*light };
    let floor = mean_reflected.map(|m| TEXEL_FLOOR * m.abs());
    let relative = |t: [f64; 3]| (0..3).map(|c| if floor[c] > 0.0 { t[c] / floor[c] } else { 0.0 }).fold(0.0, f64::max);
    let max_p = if model.centre().is_some() { 0 } else { max_p.min(brdf.p) };
    let first_under = |worst: &dyn Fn(usize) -> f64| (0..=l_max).find(|&f| worst(f) <= epsilon).unwrap_or(l_max);
    // F_B is the one a projection to l_max gives when the projected bands alone reject F_B − 1.
    let decided = |f_b: usize, known: &dyn Fn(usize) -> f64| f_b == 0 || known(f_b - 1) > epsilon;
    if max_p == 0 {
        let (tail, known) = tails(&band_weights(brdf, 0, l_max, &view_weights(0, None)), light);
        let f_b = first_under(&|f| relative(tail[f]));
        let bound = relative(tail[f_b]);
        return decided(f_b, &|f| relative(known[f])).then_some(TexelOrders {
            f_b,
            p_b: 0,
            bound,
            l_max,
            capped: bound > epsilon,
            valid_view_angle: 180.0,
        });
    }
    let samples = ViewSamples::new(model, VIEW_ANGLES);
    let limit = VIEW_RESIDUAL_FACTOR * epsilon;
    let valid_angle = |r: &[f64]| VIEW_ANGLES.iter().zip(r).take_while(|(_, &e)| e <= limit).last().map(|(&a, _)| a);
    // Each P's residuals cost a pass over the sample grid: measured in increasing P until one
    // is valid to 90°, not for every P up front.
    let p_b = (0..=max_p)
        .find(|&p| valid_angle(&samples.residuals(brdf, l_max, p)).is_some_and(|a| a >= 90.0))
        .unwrap_or(max_p);
    // F: the bound (2) over the view angles up to 90°; the valid range is then what
    // (F_B, P_B) represents within ε.
    let per_angle: Vec<_> = VIEW_ANGLES
        .iter()
        .filter(|&&a| a <= 90.0)
        .map(|&a| tails(&band_norms(brdf, p_b, a.to_radians())[..=l_max], light))
        .collect();
    let worst = |f: usize| per_angle.iter().map(|(t, _)| relative(t[f])).fold(0.0, f64::max);
    let f_b = first_under(&worst);
    if !decided(f_b, &|f| per_angle.iter().map(|(_, k)| relative(k[f])).fold(0.0, f64::max)) {
        return None;
    }
    let valid = valid_angle(&samples.residuals(brdf, f_b, p_b)).unwrap_or(0.0);
    let bound = worst(f_b);
    Some(TexelOrders { f_b, p_b, bound, l_max, capped: bound > epsilon, valid_view_angle: valid })
}

/// n_l(θ_o) per channel: the norm of band l of ρ̂(·, ω_o) as a function of ω_i, for ω_o at
/// angle θ_o from R, √(Σ_q c_lq²) with c_lq = Σ_{p ≤ P} ρ̂_lpq Y_pq(θ_o, 0) (rotating ω_o about R
/// rotates ρ̂ about R and keeps every band's norm, so φ_o = 0 is general).
fn band_norms(brdf: &BrdfSh, p: usize, theta_o: f64) -> Vec<[f64; 3]> {
    let mut plm = vec![0.0; count(p)];
    LegendreTable::new(p).eval(theta_o.cos(), theta_o.sin().abs(), &mut plm);
    (0..=brdf.f)
        .map(|l| {
            let mut n2 = [0.0; 3];
            for q in 0..=l.min(p) {
                let scale = if q == 0 { 1.0 } else { std::f64::consts::SQRT_2 };
                let mut c = [0.0; 3];
                for pp in q..=p {
                    let r = brdf.get(l, pp, q as isize);
                    for ch in 0..3 {
                        c[ch] += r[ch] * plm[index(pp, q as isize)] * scale;
                    }
                }
                for ch in 0..3 {
                    n2[ch] += c[ch] * c[ch];
                }
            }
            n2.map(f64::sqrt)
        })
        .collect()
}

/// ρ̂(·, ω_o) sampled over ω_i for ω_o at each of a list of angles (degrees) from R in the
/// reflection frame (φ_o = 0), on a Gauss–Legendre grid in cos θ_i × a uniform grid in φ_i, to
/// measure how well truncated expansions represent it (green channel). ρ̂ and its expansion are
/// even in φ_i (the mirror y → −y), and the midpoints k and NODES − 1 − k mirror each other, so
/// only φ_i ∈ [0, π] is sampled and its sums count twice.
pub struct ViewSamples {
    angles: Vec<f64>,
    nodes: Vec<(f64, f64)>,
    /// Per angle, NODES × HALF samples (θ_i node major).
    samples: Vec<Vec<f64>>,
}

/// The φ_i midpoints in [0, π].
const HALF: usize = NODES / 2;

impl ViewSamples {
    /// Samples `model`'s ρ̂ at `angles_deg`.
    pub fn new(model: &Model, angles_deg: &[f64]) -> Self {
        let nodes = gauss_legendre(NODES).to_vec();
        let (sin_phi, cos_phi): (Vec<f64>, Vec<f64>) =
            (0..HALF).map(|k| (2.0 * PI * (k as f64 + 0.5) / NODES as f64).sin_cos()).unzip();
        let samples = angles_deg
            .par_iter()
            .map(|&deg| {
                let theta_o = deg.to_radians();
                let wo = DVec3::new(theta_o.sin(), 0.0, theta_o.cos());
                let mut out = Vec::with_capacity(NODES * HALF);
                for &(x, _) in &nodes {
                    let sin_i = (1.0 - x * x).max(0.0).sqrt();
                    for k in 0..HALF {
                        out.push(model.rho_hat(DVec3::new(sin_i * cos_phi[k], sin_i * sin_phi[k], x), wo)[1]);
                    }
                }
                out
            })
            .collect();
        ViewSamples { angles: angles_deg.to_vec(), nodes, samples }
    }

    /// r(θ_o) = ‖ρ̂(·, ω_o) − ρ̂_FP(·, ω_o)‖ / ‖ρ̂(·, ω_o)‖ over ω_i at each angle. At φ_o = 0
    /// the expansion is Σ_{l,q≥0} c_lq Y_lq(ω_i) with c_lq = Σ_p ρ̂_lpq Y_pq(ω_o) (ρ̂ is even in
    /// φ, so the sin terms vanish), evaluated per θ_i row as Σ_q cos(qφ) Σ_l c_lq Y-factors.
    pub fn residuals(&self, brdf: &BrdfSh, f: usize, p: usize) -> Vec<f64> {
        let (f, p) = (f.min(brdf.f), p.min(brdf.p));
        let (table_o, table_i) = (LegendreTable::new(p), LegendreTable::new(f));
        let mut plm_o = vec![0.0; count(p)];
        let cos_q: Vec<Vec<f64>> = (0..=p)
            .map(|q| (0..HALF).map(|k| (q as f64 * 2.0 * PI * (k as f64 + 0.5) / NODES as f64).cos()).collect())
            .collect();
        let y = |q: usize| if q == 0 { 1.0 } else { std::f64::consts::SQRT_2 };
        // c_lq per angle.
        let c: Vec<Vec<Vec<f64>>> = self
            .angles
            .iter()
            .map(|&deg| {
                let theta_o = deg.to_radians();
                table_o.eval(theta_o.cos(), theta_o.sin().abs(), &mut plm_o);
                (0..=f)
                    .map(|l| {
                        (0..=l.min(p))
                            .map(|q| {
                                (q..=p)
                                    .map(|pp| brdf.get(l, pp, q as isize)[1] * plm_o[index(pp, q as isize)] * y(q))
                                    .sum()
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect();
        // Rows in fixed chunks, each summed by one thread, the chunks added in order: the same
        // figures for any number of threads.
        let partial = |rows: &[(f64, f64)], first: usize| {
            let (mut err, mut norm) = (vec![0.0; self.angles.len()], vec![0.0; self.angles.len()]);
            let mut plm_i = vec![0.0; count(f)];
            let mut g = vec![0.0; p + 1];
            for (row, &(x, w)) in rows.iter().enumerate().map(|(i, n)| (first + i, n)) {
                // Only the orders q ≤ P of the bands l ≤ F are read: O(F·P) per node.
                table_i.eval_to_m(x, (1.0 - x * x).max(0.0).sqrt(), p, &mut plm_i);
                for (a, (c, samples)) in c.iter().zip(&self.samples).enumerate() {
                    for (q, gq) in g.iter_mut().enumerate() {
                        *gq = (q..=f)
                            .map(|l| c[l].get(q).copied().unwrap_or(0.0) * plm_i[index(l, q as isize)] * y(q))
                            .sum();
                    }
                    for k in 0..HALF {
                        let approx: f64 = (0..=p).map(|q| g[q] * cos_q[q][k]).sum();
                        let exact = samples[row * HALF + k];
                        err[a] += w * (exact - approx).powi(2);
                        norm[a] += w * exact * exact;
                    }
                }
            }
            (err, norm)
        };
        const CHUNK: usize = 8;
        let chunks: Vec<(Vec<f64>, Vec<f64>)> =
            self.nodes.par_chunks(CHUNK).enumerate().map(|(i, rows)| partial(rows, i * CHUNK)).collect();
        let (mut err, mut norm) = (vec![0.0; self.angles.len()], vec![0.0; self.angles.len()]);
        for (e, n) in &chunks {
            for a in 0..err.len() {
                err[a] += e[a];
                norm[a] += n[a];
            }
        }
        err.iter().zip(&norm).map(|(e, n)| if *n > 0.0 { (e / n).sqrt() } else { 0.0 }).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::Brdf;
    use crate::sh::basis::eval_basis_dir;

    #[test]
    fn view_residuals_are_the_same_for_any_thread_count() {
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.2").unwrap(), true).unwrap();
        let brdf = model.coefficients(24, 4);
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| ViewSamples::new(&model, VIEW_ANGLES).residuals(&brdf, 24, 4))
        };
        let one = run(1);
        assert!(one.iter().all(|r| r.is_finite()) && one.iter().any(|&r| r > 0.0), "{one:?}");
        assert_eq!(run(2), one);
        assert_eq!(run(3), one);
    }

    /// r(θ_o) from Parseval against the brute-force residual: sample ρ̂ and its truncated
    /// expansion over ω_i and integrate the difference.
    #[test]
    fn view_residuals_match_a_brute_force_integral() {
        let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.3").unwrap(), true).unwrap();
        let (f, p) = (16, 3);
        let brdf = model.coefficients(f, p);
        let angles = [0.0, 60.0, 130.0];
        let fast = ViewSamples::new(&model, &angles).residuals(&brdf, f, p);
        let (tl, tp) = (LegendreTable::new(f), LegendreTable::new(p));
        let (mut yl, mut yp) = (vec![0.0; count(f)], vec![0.0; count(p)]);
        for (deg, got) in angles.iter().zip(&fast) {
            let theta_o = deg.to_radians();
            let wo = DVec3::new(theta_o.sin(), 0.0, theta_o.cos());
            eval_basis_dir(&tp, wo, &mut yp);
            let (mut e2, mut r2) = (0.0, 0.0);
            let n = 300;
            for a in 0..n {
                let ti = PI * (a as f64 + 0.5) / n as f64;
                for b in 0..n {
                    let wi = crate::sphere::direction(ti, 2.0 * PI * (b as f64 + 0.5) / n as f64);
                    eval_basis_dir(&tl, wi, &mut yl);
                    let mut approx = 0.0;
                    for l in 0..=f {
                        for pp in 0..=p {
                            for q in -(l.min(pp) as isize)..=(l.min(pp) as isize) {
                                approx += brdf.get(l, pp, q)[1] * yl[index(l, q)] * yp[index(pp, q)];
                            }
                        }
                    }
                    let exact = model.rho_hat(wi, wo)[1];
                    e2 += (exact - approx).powi(2) * ti.sin();
                    r2 += exact * exact * ti.sin();
                }
            }
            let want = (e2 / r2).sqrt();
            assert!((got - want).abs() < 0.05 * want + 1e-3, "θ_o = {deg}: Parseval {got}, brute force {want}");
        }
        assert!(fast[0] < fast[2], "grazing views are represented worse: {fast:?}");
    }

    /// A constant lighting has energy in band 0 only: any F meets the bound, and F_B = 0.
    #[test]
    fn constant_lighting_needs_only_band_zero() {
        let model = Model::new(Brdf::parse("phong:s=32").unwrap(), true).unwrap();
        let brdf = model.coefficients(40, 0);
        let mut energy = vec![[0.0; 3]; 41];
        energy[0] = [4.0 * PI; 3];
        let o = texel_orders(&model, &brdf, &LightEnergy::exact(energy), [1.0; 3], 0.01, 0).unwrap();
        assert_eq!((o.f_b, o.p_b, o.capped), (0, 0, false));
    }

    /// The bound (1) is monotone in F and the rule picks the first F under ε.
    #[test]
    fn the_texel_rule_picks_the_first_order_under_the_tolerance() {
        let model = Model::new(Brdf::parse("phong:s=64").unwrap(), true).unwrap();
        let brdf = model.coefficients(60, 0);
        // A white-noise-like lighting: equal energy in every band.
        let energy = vec![[1.0; 3]; 61];
        let o = texel_orders(&model, &brdf, &LightEnergy::exact(energy.clone()), [1.0; 3], 0.01, 0).unwrap();
        let (tail, _) = tails(&band_weights(&brdf, 0, 60, &view_weights(0, None)), &LightEnergy::exact(energy));
        assert!(tail.windows(2).all(|t| t[1][0] <= t[0][0]));
        assert!(tail[o.f_b][0] / TEXEL_FLOOR <= 0.01 && tail[o.f_b - 1][0] / TEXEL_FLOOR > 0.01, "{o:?}");
        // Phong's kernel falls like exp(−l²/2s): F ≈ √(2s ln(1/tolerance)) plus a few.
        assert!((20..60).contains(&o.f_b), "{o:?}");
    }

    /// A lighting with energy in every band up to l_max, projected only part of the way: the
    /// rule either returns the F_B of the whole projection or asks for more, and always decides
    /// once every band is in. A Gaussian-like kernel (Phong) is decided long before l_max; a
    /// kernel with a slowly converging horizon (Torrance-Sparrow) may need every band.
    #[test]
    fn a_partial_projection_gives_the_whole_projections_orders_or_asks_for_more() {
        for (spec, max_p) in [("phong:s=64", 0), ("torrance-sparrow:sigma=0.3", 3)] {
            let model = Model::new(Brdf::parse(spec).unwrap(), true).unwrap();
            let l_max = 60;
            let brdf = model.coefficients(l_max, max_p);
            // A falling spectrum (E_l ∝ 1/(l + 1)²), per channel different.
            let energy: Vec<[f64; 3]> =
                (0..=l_max).map(|l| [1.0, 0.5, 2.0].map(|s| s / ((l + 1) * (l + 1)) as f64)).collect();
            let total: [f64; 3] = std::array::from_fn(|c| energy.iter().map(|e| e[c]).sum());
            let whole = texel_orders(&model, &brdf, &LightEnergy::exact(energy.clone()), [0.05; 3], 0.01, max_p)
                .expect("every band known decides");
            assert!(whole.f_b > 0 && !whole.capped, "{spec}: {whole:?}");
            let mut first_decided = None;
            for projected in 0..=l_max {
                let above = if projected == l_max { [0.0; 3] } else { total };
                let light = LightEnergy { bands: energy[..=projected].to_vec(), above, l_max };
                if let Some(o) = texel_orders(&model, &brdf, &light, [0.05; 3], 0.01, max_p) {
                    assert_eq!((o.f_b, o.p_b), (whole.f_b, whole.p_b), "{spec}, projected to {projected}");
                    assert!(o.bound >= whole.bound * (1.0 - 1e-12), "{spec}: the bound only grows");
                    first_decided.get_or_insert(projected);
                }
            }
            let first = first_decided.expect("decided with every band");
            if spec.starts_with("phong") {
                // F_B ≈ 36 here; a projection a few bands past it decides.
                assert!(first < whole.f_b + 15, "{spec}: F_B {} first decided at {first}", whole.f_b);
            }
        }
    }

    /// The first projection is the smallest band whose unprojected bound fits 1 % of ε: one band
    /// less does not, and a kernel that falls faster (a rougher lobe) or a brighter floor needs
    /// fewer bands.
    #[test]
    fn the_first_projection_is_where_the_bound_on_the_bands_above_fits() {
        let (energy, mean, epsilon) = ([50.0; 3], [1.0; 3], 0.01);
        let allowed = FIRST_PROJECTION_SHARE * epsilon * TEXEL_FLOOR;
        let bound = |brdf: &BrdfSh, l: usize| {
            let w = band_weights(brdf, 0, 127, &view_weights(0, None));
            (energy[0] * w[l + 1..].iter().map(|w| w[0] * w[0]).sum::<f64>()).sqrt()
        };
        let mut firsts = Vec::new();
        for s in ["phong:s=8", "phong:s=32", "phong:s=128"] {
            let model = Model::new(Brdf::parse(s).unwrap(), true).unwrap();
            let brdf = model.coefficients(127, 0);
            let l = first_projection(&model, &brdf, 0, 127, energy, mean, epsilon);
            assert!(bound(&brdf, l) <= allowed && bound(&brdf, l - 1) > allowed, "{s}: {l}");
            // Phong's kernel falls like exp(−l²/2s).
            assert!(l as f64 > (2.0 * 8.0f64).sqrt() && l < 127, "{s}: {l}");
            assert!(first_projection(&model, &brdf, 0, 127, energy, [100.0; 3], epsilon) < l, "{s}");
            assert_eq!(first_projection(&model, &brdf, 0, 15, energy, [1e-9; 3], epsilon), 15);
            firsts.push(l);
        }
        assert!(firsts.windows(2).all(|f| f[0] < f[1]), "{firsts:?}");
    }
}
