//! The angular-domain reference: direct integration over the environment for every output texel
//! (R&H 2002 §6.2, App. D), with the BRDF truncated where it holds less than ε of its energy.
//!
//! For each reflection vector R only the environment texels inside the cone of half-angle θ*
//! around R are visited: per environment row the admissible φ interval is solved in closed form
//! from cos γ = cos θ cos θ_R + sin θ sin θ_R cos Δφ ≥ cos θ*, so no texel outside the lobe is
//! touched. θ* is chosen so that the lobe outside it holds at most ε of ∫ ρ̂ dω_i (App. D:
//! cos θ* = ε^{1/(s+1)} for Phong), per view angle θ_o for 3-D BRDFs.

use crate::envmap::{EnvMap, Layout};
use crate::io::RgbImage;
use crate::progress::Progress;
use crate::quadrature::gauss_legendre_cached as gauss_legendre;
use crate::sphere::{self, LatLong};
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// A lat-long environment prepared for cone queries.
pub struct ConeIntegrator {
    width: usize,
    height: usize,
    dirs: Vec<DVec3>,
    radiance: Vec<[f64; 3]>,
    row_omega: Vec<f64>,
}

/// Errors of the angular reference.
#[derive(Debug, thiserror::Error)]
pub enum AngularError {
    /// The environment is not lat-long.
    #[error("the angular reference integrates lat-long environments; this one is {0} (resample it with `prtkit convert --to latlong`)")]
    NotLatLong(&'static str),
}

impl ConeIntegrator {
    /// Prepares a lat-long environment.
    pub fn new(env: &EnvMap) -> Result<Self, AngularError> {
        if env.layout() != Layout::LatLong {
            return Err(AngularError::NotLatLong(env.layout().name()));
        }
        let img = env.image();
        let (width, height) = (img.width, img.height);
        let mut dirs = Vec::with_capacity(width * height);
        let mut radiance = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                dirs.push(LatLong::new(width, height).texel_direction(x, y));
                let v = img.get(x, y);
                radiance.push([v[0] as f64, v[1] as f64, v[2] as f64]);
            }
        }
        let row_omega = (0..height).map(|y| LatLong::new(width, height).row_solid_angle(y)).collect();
        Ok(ConeIntegrator { width, height, dirs, radiance, row_omega })
    }

    /// Σ over texels ω within angle θ* of `axis` of L(ω)·weight(ω)·Ω(ω).
    pub fn integrate(&self, axis: DVec3, theta_star: f64, mut weight: impl FnMut(DVec3) -> [f64; 3]) -> [f64; 3] {
        let (w, h) = (self.width, self.height);
        let cos_star = theta_star.min(PI).cos();
        let (theta_r, phi_r) = sphere::angles(axis);
        let (st_r, ct_r) = theta_r.sin_cos();
        let dtheta = PI / h as f64;
        let dphi = 2.0 * PI / w as f64;
        let y0 = (((theta_r - theta_star) / dtheta - 0.5).floor().max(0.0)) as usize;
        let y1 = (((theta_r + theta_star) / dtheta - 0.5).ceil().max(0.0) as usize).min(h - 1);
        let mut acc = [0.0; 3];
        for y in y0..=y1 {
            let theta = (y as f64 + 0.5) * dtheta;
            let (st, ct) = theta.sin_cos();
            let denom = st * st_r;
            let c = if denom > 1e-300 {
                (cos_star - ct * ct_r) / denom
            } else if ct * ct_r >= cos_star {
                -2.0
            } else {
                2.0
            };
            if c > 1.0 {
                continue;
            }
            let omega = self.row_omega[y];
            let row = y * w;
            let mut visit = |x: usize, acc: &mut [f64; 3]| {
                let wt = weight(self.dirs[row + x]);
                let l = self.radiance[row + x];
                for k in 0..3 {
                    acc[k] += l[k] * wt[k] * omega;
                }
            };
            if c <= -1.0 {
                for x in 0..w {
                    visit(x, &mut acc);
                }
                continue;
            }
            let half = c.acos();
            let lo = ((phi_r - half) / dphi - 0.5).ceil() as isize;
            let hi = ((phi_r + half) / dphi - 0.5).floor() as isize;
            if hi - lo + 1 >= w as isize {
                for x in 0..w {
                    visit(x, &mut acc);
                }
            } else {
                for x in lo..=hi {
                    visit(x.rem_euclid(w as isize) as usize, &mut acc);
                }
            }
        }
        acc
    }
}

/// θ* for a radially symmetric lobe u(cos γ) (grey or luminance): the smallest angle whose cone
/// holds 1 − ε of ∫ u dω (App. D).
pub fn radial_cutoff(u: impl Fn(f64) -> f64, epsilon: f64) -> f64 {
    // Cumulative ∫_x^1 u dx on a fine Gauss grid, then the first node where it reaches 1 − ε.
    let nodes = gauss_legendre(2000);
    let total: f64 = nodes.iter().map(|&(x, w)| w * u(x)).sum();
    if total <= 0.0 {
        return PI;
    }
    let mut acc = 0.0;
    for &(x, w) in nodes.iter().rev() {
        acc += w * u(x);
        if acc >= (1.0 - epsilon) * total {
            return x.clamp(-1.0, 1.0).acos();
        }
    }
    PI
}

/// θ*(θ_o) for a 3-D ρ̂ in the reflection frame, tabulated on `bins` values of θ_o ∈ [0, π]: the
/// cone around R that holds 1 − ε of ∫ ρ̂ dω_i for that view angle.
pub struct CutoffTable {
    theta_star: Vec<f64>,
}

impl CutoffTable {
    /// Tabulates θ* for ρ̂(ω_i, ω_o) (reflection frame, luminance).
    pub fn new(rho_hat: impl Fn(DVec3, DVec3) -> f64 + Sync, epsilon: f64, bins: usize) -> Self {
        let n_theta = 512;
        let n_phi = 48;
        let theta_star = (0..bins)
            .into_par_iter()
            .map(|b| {
                let theta_o = PI * b as f64 / (bins - 1).max(1) as f64;
                let wo = crate::sphere::direction(theta_o.min(PI - 1e-6), 0.0);
                // Mass per θ_i band (midpoint rule in θ_i, uniform φ_i).
                let mass: Vec<f64> = (0..n_theta)
                    .map(|i| {
                        let theta_i = PI * (i as f64 + 0.5) / n_theta as f64;
                        let s: f64 = (0..n_phi)
                            .map(|k| {
                                rho_hat(
                                    crate::sphere::direction(theta_i, 2.0 * PI * (k as f64 + 0.5) / n_phi as f64),
                                    wo,
                                )
                            })
                            .sum();
                        s * theta_i.sin()
                    })
                    .collect();
                let total: f64 = mass.iter().sum();
                if total <= 0.0 {
                    return 0.0;
                }
                let mut acc = 0.0;
                for (i, m) in mass.iter().enumerate() {
                    acc += m;
                    if acc >= (1.0 - epsilon) * total {
                        return (PI * (i + 1) as f64 / n_theta as f64).min(PI);
                    }
                }
                PI
            })
            .collect();
        CutoffTable { theta_star }
    }

    /// θ* for view angle θ_o: the larger of the two neighbouring bins (conservative).
    pub fn at(&self, theta_o: f64) -> f64 {
        let n = self.theta_star.len();
        let t = (theta_o / PI).clamp(0.0, 1.0) * (n - 1) as f64;
        let (i0, i1) = (t.floor() as usize, (t.ceil() as usize).min(n - 1));
        self.theta_star[i0].max(self.theta_star[i1])
    }

    /// The widest cone of the table.
    pub fn max(&self) -> f64 {
        self.theta_star.iter().cloned().fold(0.0, f64::max)
    }
}

/// Angular reflection map of a radially symmetric lobe u(R·ω): B(R) = ∫_{cone} L(ω) u(R·ω) dω,
/// on a `width`×`height` lat-long grid of R.
pub fn radial_map(
    env: &ConeIntegrator,
    u: impl Fn(f64) -> [f64; 3] + Sync,
    theta_star: f64,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> RgbImage {
    progress.start("angular", height as u64);
    let mut image = RgbImage::new(width, height);
    image.pixels.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, px) in row.iter_mut().enumerate() {
            let r = crate::sphere::LatLong::new(width, height).texel_direction(x, y);
            let v = env.integrate(r, theta_star, |l| u(r.dot(l)));
            *px = [v[0] as f32, v[1] as f32, v[2] as f32];
        }
        progress.advance(1);
    });
    progress.finish();
    image
}

/// Angular reflection map for a distant viewer in direction `view`: for each reflection vector
/// R, B̃(R) = ∫_{cone(θ*(θ_o))} L(ω) ρ̂(ω, view) dω, with cos θ_o = R·view. Everything that depends
/// on R and the view only (the normal and its frame) is computed once per output texel.
pub fn view_map(
    env: &ConeIntegrator,
    model: &super::model::Model,
    cutoff: &CutoffTable,
    view: DVec3,
    width: usize,
    height: usize,
    progress: &dyn Progress,
) -> RgbImage {
    let mut image = RgbImage::new(width, height);
    image.pixels.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for (x, px) in row.iter_mut().enumerate() {
            let r = crate::sphere::LatLong::new(width, height).texel_direction(x, y);
            let Some(prepared) = model.prepare_view(r, view) else { continue };
            let theta_star = cutoff.at(r.dot(view).clamp(-1.0, 1.0).acos());
            let v = env.integrate(r, theta_star, |l| model.rho_hat_prepared(&prepared, l));
            *px = [v[0] as f32, v[1] as f32, v[2] as f32];
        }
        progress.advance(1);
    });
    image
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phong_cutoff_matches_appendix_d() {
        for s in [8.0f64, 64.0, 512.0] {
            let u = |x: f64| if x > 0.0 { x.powf(s) } else { 0.0 };
            let got = radial_cutoff(u, 0.05);
            let want = 0.05f64.powf(1.0 / (s + 1.0)).acos();
            assert!((got - want).abs() < 0.01 * want + 2e-3, "s={s}: {got} vs {want}");
        }
    }

    #[test]
    fn a_full_cone_integrates_the_whole_sphere() {
        let img = RgbImage::from_fn(64, 32, |_, _| [1.0, 2.0, 3.0]);
        let env = ConeIntegrator::new(&EnvMap::latlong(img).unwrap()).unwrap();
        let v = env.integrate(DVec3::new(0.3, 0.4, 0.5).normalize(), PI, |_| [1.0; 3]);
        assert!((v[0] - 4.0 * PI).abs() < 1e-9 && (v[2] - 12.0 * PI).abs() < 1e-9);
        // A cone of half-angle θ* covers 2π(1 − cos θ*) up to the texel discretization.
        let cap = env.integrate(DVec3::new(0.3, 0.4, 0.5).normalize(), 0.5, |_| [1.0; 3]);
        let want = 2.0 * PI * (1.0 - 0.5f64.cos());
        assert!((cap[0] / want - 1.0).abs() < 0.05, "{} vs {want}", cap[0]);
    }

    #[test]
    fn the_cone_visits_exactly_the_texels_within_theta_star() {
        let img = RgbImage::from_fn(96, 48, |_, _| [1.0; 3]);
        let map = EnvMap::latlong(img).unwrap();
        let env = ConeIntegrator::new(&map).unwrap();
        for axis in [DVec3::Z, DVec3::new(1.0, -2.0, 0.3).normalize(), DVec3::new(-0.1, 0.05, -1.0).normalize()] {
            for theta_star in [0.1, 0.7, 2.0] {
                let got = env.integrate(axis, theta_star, |_| [1.0; 3])[0];
                let mut want = 0.0;
                map.for_each_texel(|t| {
                    if t.dir.dot(axis) >= theta_star.cos() {
                        want += t.solid_angle;
                    }
                });
                assert!((got - want).abs() < 1e-9, "axis {axis} θ* {theta_star}: {got} vs {want}");
            }
        }
    }
}
