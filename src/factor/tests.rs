//! Physics and identity tests of the factorization against independent derivations.

use super::energy::terms_for_fraction;
use super::predict::reflection_spectrum;
use super::svd::{dense_matrix, factor, Method, Sampling};
use super::{Channel, Domain};
use crate::brdf::Brdf;
use crate::progress::NoProgress;
use faer::Mat;

fn sampling(n: usize, domain: Domain, cosine: bool) -> Sampling {
    Sampling { resolution: n, domain, cosine, channel: Channel::Luminance }
}

/// F_l of the normalized Phong lobe by 1-D quadrature (Funk–Hecke), not by any SVD.
fn phong_f(s: f64, lmax: usize) -> Vec<f64> {
    let p = crate::brdf::models::Phong { exponent: s };
    reflection_spectrum(|t| p.lobe(t), lmax)
}

#[test]
fn phong_sphere_singular_values_are_f_l_with_multiplicity_2l_plus_1() {
    // Mahajan et al. 2008, eq. 9: on the full sphere σ = F_l = f_l √(4π/(2l+1)), 2l+1 times.
    let s = 4.0;
    let f = phong_f(s, 12);
    // The grid is a quadrature whose error is largest for the zonal (m = 0) modes near the
    // poles and falls like 1/n (1.4 % at n = 32, 0.34 % at n = 128 for l = 5); n = 128 keeps
    // every σ of bands l ≤ 5 within 0.5 % of F_l.
    let fact =
        factor(&Brdf::parse("phong:s=4").unwrap(), &sampling(128, Domain::Sphere, false), Method::Fft, 0, &NoProgress)
            .unwrap();
    let sv = &fact.singular_values;
    let mut k = 0;
    for (l, fl) in f.iter().enumerate().take(6) {
        for _ in 0..(2 * l + 1) {
            let rel = (sv[k] - fl).abs() / fl;
            assert!(rel < 0.005, "band {l}: sigma_{k} = {} vs F_l = {fl} (rel {rel:.2e})", sv[k]);
            k += 1;
        }
        // The multiplicity is exactly 2l+1: the next value belongs to the next band.
        if l < 5 {
            assert!((sv[k] - fl).abs() / fl > 0.05, "band {l} has more than {} copies", 2 * l + 1);
        }
    }
}

/// Real SH of band l sampled on the grid, Gram–Schmidt-orthonormalized in the discrete inner
/// product Σ a b ΔΩ (the grid's midpoint rule is not exactly orthonormal).
fn band_basis(grid: &super::Grid, l: usize) -> Vec<Vec<f64>> {
    let table = crate::sh::legendre::LegendreTable::new(l);
    let mut y = vec![0.0; crate::sh::count(l)];
    let mut basis: Vec<Vec<f64>> = vec![Vec::with_capacity(grid.len()); 2 * l + 1];
    for i in 0..grid.len() {
        crate::sh::eval_basis_dir(&table, grid.direction(i), &mut y);
        for (m, col) in basis.iter_mut().enumerate() {
            col.push(y[crate::sh::index(l, m as isize - l as isize)]);
        }
    }
    let w = grid.cell_solid_angle();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>() * w;
    for i in 0..basis.len() {
        for j in 0..i {
            let p = dot(&basis[i], &basis[j]);
            let bj = basis[j].clone();
            basis[i].iter_mut().zip(&bj).for_each(|(x, y)| *x -= p * y);
        }
        let norm = dot(&basis[i], &basis[i]).sqrt();
        basis[i].iter_mut().for_each(|x| *x /= norm);
    }
    basis
}

/// Largest principal angle (radians) between span(a) and span(b), both orthonormal sets.
fn max_principal_angle(grid: &super::Grid, a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    let w = grid.cell_solid_angle();
    let m = Mat::from_fn(a.len(), b.len(), |i, j| a[i].iter().zip(&b[j]).map(|(x, y)| x * y).sum::<f64>() * w);
    let s = m.singular_values().unwrap();
    let smallest = s.iter().copied().fold(f64::INFINITY, f64::min).min(1.0);
    smallest.acos()
}

#[test]
fn phong_sphere_singular_vectors_span_each_band_of_y_lm() {
    // g_k = Y_lm(ω_i), h_k = (−1)^m Y_lm(ω_o) (eq. 9): each band's 2l+1 singular vectors span
    // the same space as that band's Y_lm, on both sides.
    let sampling = sampling(32, Domain::Sphere, false);
    let grid = sampling.grid();
    let fact = factor(&Brdf::parse("phong:s=4").unwrap(), &sampling, Method::Fft, 16, &NoProgress).unwrap();
    for l in 0..=3usize {
        let range = l * l..(l + 1) * (l + 1);
        let y = band_basis(&grid, l);
        let g_angle = max_principal_angle(&grid, &fact.g[range.clone()], &y);
        let h_angle = max_principal_angle(&grid, &fact.h[range], &y);
        assert!(g_angle < 0.02 && h_angle < 0.02, "band {l}: angles g {g_angle:.3e}, h {h_angle:.3e} rad");
    }
    // And not with the neighbouring band (the test can fail).
    let y2 = band_basis(&grid, 2);
    assert!(max_principal_angle(&grid, &fact.g[1..4], &y2[..3]) > 1.0);
}

#[test]
fn hemisphere_needs_about_half_the_terms_of_the_sphere() {
    // §3.4: restricting ω_i, ω_o to the visible hemispheres halves K (l+1 instead of 2l+1 per band).
    for s in [10.0, 20.0] {
        let brdf = Brdf::parse(&format!("phong:s={s}")).unwrap();
        let k = |d| {
            let f = factor(&brdf, &sampling(40, d, false), Method::Fft, 0, &NoProgress).unwrap();
            terms_for_fraction(&f.singular_values, 0.99) as f64
        };
        let ratio = k(Domain::Hemisphere) / k(Domain::Sphere);
        assert!((0.4..=0.62).contains(&ratio), "s = {s}: hemisphere/sphere = {ratio}");
    }
}

#[test]
fn fft_and_dense_give_the_same_singular_values() {
    for (spec, domain, cosine, n) in [
        ("phong:s=10", Domain::Hemisphere, false, 12),
        ("torrance-sparrow:sigma=0.3", Domain::Sphere, false, 11),
        ("blinn-phong:s=20", Domain::Hemisphere, true, 10),
        ("lafortune:kd=0.3,lobe=-0.9/1/6,lobe=-0.5/0.4/3", Domain::Hemisphere, false, 9),
    ] {
        let brdf = Brdf::parse(spec).unwrap();
        let s = sampling(n, domain, cosine);
        let a = factor(&brdf, &s, Method::Fft, 0, &NoProgress).unwrap().singular_values;
        let b = factor(&brdf, &s, Method::Dense, 0, &NoProgress).unwrap().singular_values;
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-11 * a[0], "{spec}: {x} vs {y}");
        }
    }
}

#[test]
fn fft_factors_reconstruct_the_matrix() {
    // Σ_k σ_k h_k(ω_o) g_k(ω_i) ΔΩ over all terms is the weighted matrix itself, and the
    // K-term truncation error equals √(Σ_{k>K} σ²/Σ σ²) (Eckart–Young), for both methods.
    let brdf = Brdf::parse("torrance-sparrow:sigma=0.35").unwrap();
    let s = sampling(8, Domain::Hemisphere, true);
    let grid = s.grid();
    let dirs = grid.len();
    let m = dense_matrix(&brdf, &s, &NoProgress);
    let norm: f64 = m.iter().map(|x| x * x).sum::<f64>().sqrt();
    for method in [Method::Fft, Method::Dense] {
        let f = factor(&brdf, &s, method, dirs, &NoProgress).unwrap();
        let w = grid.cell_solid_angle();
        for terms in [3, 10, dirs] {
            let mut err2 = 0.0;
            for i in 0..dirs {
                for o in 0..dirs {
                    let approx: f64 = (0..terms).map(|k| f.singular_values[k] * f.h[k][o] * f.g[k][i] * w).sum();
                    err2 += (m[i * dirs + o] - approx).powi(2);
                }
            }
            let got = err2.sqrt() / norm;
            let want = super::energy::reconstruction_error(&f.singular_values, terms);
            assert!((got - want).abs() < 1e-9, "{method} K={terms}: {got} vs {want}");
        }
    }
}

#[test]
fn anisotropic_brdfs_refuse_the_fft_and_factor_densely() {
    let kk = Brdf::parse("kajiya-kay:s=8").unwrap();
    assert!(factor(&kk, &sampling(6, Domain::Hemisphere, false), Method::Fft, 0, &NoProgress).is_err());
    let f = factor(&kk, &sampling(6, Domain::Hemisphere, false), Method::Auto, 0, &NoProgress).unwrap();
    assert_eq!(f.method, Method::Dense);
    assert_eq!(f.singular_values.len(), 36);
}

#[test]
fn absurd_resolutions_are_refused_with_the_memory_needed() {
    let s = sampling(1000, Domain::Hemisphere, false);
    let e = super::svd::check_budget(&s, Method::Dense, 0, 4 << 30).unwrap_err().to_string();
    assert!(e.contains("TiB") && e.contains("limit 4.0 GiB"), "{e}");
    let e = super::svd::check_budget(&sampling(4000, Domain::Sphere, false), Method::Fft, 0, 4 << 30)
        .unwrap_err()
        .to_string();
    assert!(e.contains("GiB"), "{e}");
    assert!(super::svd::check_budget(&sampling(40, Domain::Sphere, false), Method::Fft, 0, 4 << 30).is_ok());
}

#[test]
fn randomized_svd_matches_the_dense_leading_terms() {
    // Anisotropic (no FFT) and isotropic cases; n = 24 gives a 576² matrix, wide enough for the
    // randomized path not to fall back to the dense one.
    for spec in ["kajiya-kay:s=16", "phong:s=10"] {
        let brdf = Brdf::parse(spec).unwrap();
        let s = sampling(24, Domain::Hemisphere, false);
        let dense = factor(&brdf, &s, Method::Dense, 0, &NoProgress).unwrap();
        let rand = factor(&brdf, &s, Method::Randomized, 4, &NoProgress).unwrap();
        assert_eq!(rand.method, Method::Randomized);
        assert!((rand.total_energy - dense.total_energy).abs() <= 1e-12 * dense.total_energy);
        for fraction in super::energy::STANDARD_FRACTIONS {
            assert_eq!(rand.terms_for(fraction), dense.terms_for(fraction), "{spec} at {fraction}");
        }
        for k in 0..10 {
            let (a, b) = (rand.singular_values[k], dense.singular_values[k]);
            assert!((a - b).abs() <= 1e-8 * dense.singular_values[0], "{spec}: sigma_{k} {a} vs {b}");
        }
        // Factor functions are unit vectors in the grid's L² inner product.
        let w = s.grid().cell_solid_angle();
        for v in rand.g.iter().chain(&rand.h) {
            assert!((v.iter().map(|x| x * x).sum::<f64>() * w - 1.0).abs() < 1e-9);
        }
    }
}
