//! Physics and identity tests of the SH projection: analytic cases, Parseval, rotation,
//! orthonormality by Gauss–Legendre quadrature, agreement across layouts, determinism.

use glam::{DMat3, DVec3};
use prtkit::envmap::{resample, EnvMap, Layout};
use prtkit::io::RgbImage;
use prtkit::progress::NoProgress;
use prtkit::quadrature::gauss_legendre;
use prtkit::sh::basis::eval_basis_dir;
use prtkit::sh::legendre::LegendreTable;
use prtkit::sh::project::{
    map_energy, project, project_latlong, project_latlong_texels, project_naive, TexelQuadrature,
};
use prtkit::sh::rotate::ShRotation;
use prtkit::sh::synth::{synthesize_latlong, synthesize_map};
use prtkit::sh::{count, index, ShCoeffs};
use std::f64::consts::PI;

fn all_layouts(fill: impl Fn(DVec3) -> [f32; 3] + Copy) -> Vec<EnvMap> {
    let sized = |layout: Layout, w: usize, h: usize| -> EnvMap {
        let blank = if layout == Layout::Faces {
            EnvMap::from_faces((0..6).map(|_| RgbImage::new(w, h)).collect()).unwrap()
        } else {
            EnvMap::new(layout, RgbImage::new(w, h)).unwrap()
        };
        let mut map = blank.clone();
        for (face, img) in map.images_mut().iter_mut().enumerate() {
            for y in 0..img.height {
                for x in 0..img.width {
                    if let Some((dir, _)) = blank.texel_geometry(face, x, y) {
                        img.set(x, y, fill(dir));
                    }
                }
            }
        }
        map
    };
    vec![
        sized(Layout::LatLong, 256, 128),
        sized(Layout::Angular, 256, 256),
        sized(Layout::CrossHorizontal, 256, 192),
        sized(Layout::CrossVertical, 192, 256),
        sized(Layout::Faces, 64, 64),
    ]
}

#[test]
fn constant_map_gives_only_l00() {
    let c = 0.75f32;
    for map in all_layouts(|_| [c, 2.0 * c, 0.0]) {
        let sh = project(&map, 4, &NoProgress).unwrap();
        let expect = c as f64 * (4.0 * PI).sqrt();
        // Lat-long and cube texel solid angles are exact, so L00 is exact; the angular probe's
        // are integrated numerically to ~1e-5.
        let tol = if map.layout() == Layout::Angular { 1e-4 } else { 1e-12 };
        assert!((sh.rgb[0][0] / expect - 1.0).abs() < tol, "{}: {}", map.layout(), sh.rgb[0][0]);
        assert!((sh.rgb[0][1] / (2.0 * expect) - 1.0).abs() < tol);
        for i in 1..count(4) {
            assert!(sh.rgb[i][0].abs() < 2e-3 * expect, "{} coefficient {i}: {}", map.layout(), sh.rgb[i][0]);
        }
    }
}

#[test]
fn a_single_basis_function_projects_to_a_unit_vector() {
    let order = 12;
    let table = LegendreTable::new(order);
    let (w, h) = (512, 256);
    for (l, m) in [(0usize, 0isize), (1, -1), (1, 0), (1, 1), (2, -2), (3, 2), (5, -4), (8, 8), (12, -7), (12, 0)] {
        let img = RgbImage::from_fn(w, h, |x, row| {
            let mut y = vec![0.0; count(order)];
            let dir = prtkit::sphere::LatLong::new(w, h).texel_direction(x, row);
            eval_basis_dir(&table, dir, &mut y);
            let v = y[index(l, m)] as f32;
            [v, v, v]
        });
        let sh = project(&EnvMap::latlong(img).unwrap(), order, &NoProgress).unwrap();
        for i in 0..count(order) {
            let expect = if i == index(l, m) { 1.0 } else { 0.0 };
            // Midpoint rule in θ: error O((l π/H)²) ≈ 1e-3 at l = 12, H = 256.
            assert!((sh.rgb[i][0] - expect).abs() < 2e-3, "Y({l},{m}) → coefficient {i} = {}", sh.rgb[i][0]);
        }
    }
}

#[test]
fn a_single_bright_texel_gives_y_times_solid_angle_in_every_layout() {
    let order = 8;
    let table = LegendreTable::new(order);
    let mut y = vec![0.0; count(order)];
    for blank in all_layouts(|_| [0.0; 3]) {
        let mut map = blank.clone();
        let face = map.images().len() - 1;
        let img = &map.images()[face];
        let (x, row) = (img.width / 3, img.height / 4);
        let (dir, omega) = blank.texel_geometry(face, x, row).unwrap();
        map.images_mut()[face].set(x, row, [5.0, 0.0, 1.0]);
        let sh = project(&map, order, &NoProgress).unwrap();
        eval_basis_dir(&table, dir, &mut y);
        for i in 0..count(order) {
            let expect = 5.0 * y[i] * omega;
            assert!((sh.rgb[i][0] - expect).abs() < 1e-12 * (1.0 + expect.abs()) + 1e-6 * 5.0 * omega);
            assert!((sh.rgb[i][2] - y[i] * omega).abs() < 1e-6 * omega);
        }
    }
}

fn random_coeffs(order: usize, seed: u64) -> ShCoeffs {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let mut c = ShCoeffs::zeros(order);
    for v in &mut c.rgb {
        *v = [next(), next(), next()];
    }
    c
}

#[test]
fn parseval_holds_for_band_limited_maps() {
    let coeffs = random_coeffs(6, 7);
    let img = synthesize_latlong(&coeffs, 512, 256).unwrap();
    let map = EnvMap::latlong(img).unwrap();
    let energy_coeffs: f64 = coeffs.band_energy().iter().sum();
    let energy_map = map_energy(&map);
    assert!((energy_map / energy_coeffs - 1.0).abs() < 1e-3, "{energy_map} vs {energy_coeffs}");
    let back = project(&map, 6, &NoProgress).unwrap();
    let projected: f64 = back.band_energy().iter().sum();
    assert!((projected / energy_coeffs - 1.0).abs() < 1e-3);
    for (a, b) in back.rgb.iter().zip(&coeffs.rgb) {
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 2e-3, "{a:?} vs {b:?}");
        }
    }
}

#[test]
fn every_layout_gives_the_same_coefficients() {
    let coeffs = random_coeffs(5, 11);
    for blank in all_layouts(|_| [0.0; 3]) {
        let mut map = blank;
        synthesize_map(&coeffs, &mut map);
        let back = project(&map, 5, &NoProgress).unwrap();
        let mut worst = 0.0f64;
        for (a, b) in back.rgb.iter().zip(&coeffs.rgb) {
            for k in 0..3 {
                worst = worst.max((a[k] - b[k]).abs());
            }
        }
        // Texel-centre quadrature on ~65k texels: discretization error well under 1 %.
        assert!(worst < 5e-3, "{}: worst coefficient error {worst}", map.layout());
    }
}

#[test]
fn rotating_the_map_about_z_rotates_the_coefficients() {
    let (w, h) = (256, 128);
    let original = RgbImage::from_fn(w, h, |x, y| {
        let d = prtkit::sphere::LatLong::new(w, h).texel_direction(x, y);
        let v = (1.0 + d.x * 0.5 + d.y * d.z + (3.0 * d.x).sin() * 0.3).max(0.0) as f32;
        [v, v * 0.5, 1.0 - v * 0.2]
    });
    // Shifting columns by W/4 is f'(φ) = f(φ − π/2): the map rotated by +90° about +Z.
    let shifted = RgbImage::from_fn(w, h, |x, y| original.get((x + w - w / 4) % w, y));
    let order = 10;
    let a = project(&EnvMap::latlong(original).unwrap(), order, &NoProgress).unwrap();
    let b = project(&EnvMap::latlong(shifted).unwrap(), order, &NoProgress).unwrap();
    let rotated = ShRotation::new(DMat3::from_rotation_z(PI / 2.0), order).apply(&a);
    for (x, y) in rotated.rgb.iter().zip(&b.rgb) {
        for k in 0..3 {
            assert!((x[k] - y[k]).abs() < 1e-9, "{x:?} vs {y:?}");
        }
    }
}

#[test]
fn orthonormal_to_order_100_by_quadrature() {
    // Products of two band-≤100 functions have degree ≤ 200: 101 Gauss–Legendre nodes in cos θ
    // and 202 equispaced φ integrate them exactly. Different m are orthogonal by the φ integral,
    // so per m the θ integrals 2π ∫ P̄_l^m P̄_l'^m dx (× the √2² of m ≠ 0 times the ½ of ∫cos²)
    // must form the identity; we check all (l, l') for every m, and a full Gram block by
    // brute-force quadrature over the sphere for a spread of indices.
    let order = 100;
    let nodes = gauss_legendre(order + 1);
    let table = LegendreTable::new(order);
    let mut p = vec![0.0; count(order)];
    let mut gram = vec![vec![0.0f64; (order + 1) * (order + 1)]; order + 1];
    for &(x, wgt) in &nodes {
        table.eval(x, (1.0 - x * x).sqrt(), &mut p);
        for m in 0..=order {
            for l in m..=order {
                let a = p[index(l, m as isize)];
                for l2 in l..=order {
                    gram[m][l * (order + 1) + l2] += 2.0 * PI * wgt * a * p[index(l2, m as isize)];
                }
            }
        }
    }
    let mut worst = 0.0f64;
    for m in 0..=order {
        for l in m..=order {
            for l2 in l..=order {
                let expect = if l == l2 { 1.0 } else { 0.0 };
                worst = worst.max((gram[m][l * (order + 1) + l2] - expect).abs());
            }
        }
    }
    assert!(worst < 1e-11, "Legendre Gram matrix error {worst}");

    // Full basis, mixed m: a sample of 60 indices spread over 0..(101)².
    let picks: Vec<usize> = (0..60).map(|k| (k * 170 + k * k) % count(order)).collect();
    let nphi = 2 * order + 2;
    let mut y = vec![0.0; count(order)];
    let mut g = vec![0.0f64; picks.len() * picks.len()];
    for &(x, wgt) in &nodes {
        let st = (1.0 - x * x).sqrt();
        for j in 0..nphi {
            let phi = 2.0 * PI * j as f64 / nphi as f64;
            prtkit::sh::basis::eval_basis(&table, x, st, phi, &mut y);
            let wq = wgt * 2.0 * PI / nphi as f64;
            for (a, &i) in picks.iter().enumerate() {
                for (b, &k) in picks.iter().enumerate() {
                    g[a * picks.len() + b] += wq * y[i] * y[k];
                }
            }
        }
    }
    for (a, &i) in picks.iter().enumerate() {
        for (b, &k) in picks.iter().enumerate() {
            let expect = if i == k { 1.0 } else { 0.0 };
            assert!((g[a * picks.len() + b] - expect).abs() < 1e-11, "<Y{i}, Y{k}> = {}", g[a * picks.len() + b]);
        }
    }
}

#[test]
fn separable_projection_equals_the_naive_sum() {
    // Rows are taken in mirrored pairs: an even height, and an odd one whose middle row (on the
    // equator) stands alone.
    for (w, h) in [(128, 64), (96, 47)] {
        let img = RgbImage::from_fn(w, h, |x, y| [((x * 7 + y * 3) % 11) as f32, (x % 5) as f32, (y % 3) as f32]);
        let map = EnvMap::latlong(img).unwrap();
        let fast = project(&map, 20, &NoProgress).unwrap();
        let slow = project_naive(&map, 20);
        for (a, b) in fast.rgb.iter().zip(&slow.rgb) {
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-10 * (1.0 + b[k].abs()), "{w}x{h}: {a:?} vs {b:?}");
            }
        }
    }
}

#[test]
fn the_texel_integral_projection_integrates_each_texel() {
    // A sparse map on an odd height: lit texels in a row and its mirror, in a row whose mirror
    // is black, and in the middle row; every other row black (skipped). Against each texel's
    // integral of Y_lm by a 64 × 64 midpoint rule in (z, φ) over its extent.
    let (w, h, order) = (24, 13, 10);
    let lit: [(usize, usize, f32); 4] = [(3, 2, 7.0), (17, 10, 2.0), (5, 4, 3.0), (20, 6, 5.0)];
    let mut img = RgbImage::new(w, h);
    for &(x, y, v) in &lit {
        img.pixels[y * w + x] = [v, 0.5 * v, 2.0 * v];
    }
    let got = project_latlong(&img, order, TexelQuadrature::Integral { z_nodes: 4 }, &NoProgress).unwrap();
    let table = LegendreTable::new(order);
    let mut y_lm = vec![0.0; count(order)];
    let mut expected = vec![[0.0; 3]; count(order)];
    let n = 64;
    for &(x, y, v) in &lit {
        let (z0, z1) = ((PI * y as f64 / h as f64).cos(), (PI * (y + 1) as f64 / h as f64).cos());
        let weight = (z0 - z1) / n as f64 * 2.0 * PI / (w * n) as f64;
        for j in 0..n {
            let z: f64 = z0 + (z1 - z0) * (j as f64 + 0.5) / n as f64;
            for k in 0..n {
                let phi = 2.0 * PI * (x as f64 + (k as f64 + 0.5) / n as f64) / w as f64;
                let s = (1.0 - z * z).sqrt();
                eval_basis_dir(&table, DVec3::new(s * phi.cos(), s * phi.sin(), z), &mut y_lm);
                for (e, y) in expected.iter_mut().zip(&y_lm) {
                    for (c, scale) in [1.0, 0.5, 2.0].into_iter().enumerate() {
                        e[c] += weight * v as f64 * scale * y;
                    }
                }
            }
        }
    }
    let scale = expected.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for (i, (a, b)) in got.rgb.iter().zip(&expected).enumerate() {
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() < 1e-4 * scale, "coefficient {i} channel {c}: {} against {}", a[c], b[c]);
        }
    }
    // The midpoint rule is not the integral at this texel size.
    let midpoint = project_latlong(&img, order, TexelQuadrature::Midpoint, &NoProgress).unwrap();
    // Beyond the rows' Nyquist frequency: an error, not a panic.
    assert!(project_latlong(&img, w / 2 + 1, TexelQuadrature::Midpoint, &NoProgress).is_err());
    let off = midpoint.rgb.iter().zip(&expected).map(|(a, b)| (a[0] - b[0]).abs()).fold(0.0, f64::max);
    assert!(off > 1e-2 * scale, "midpoint off by {off:e} of {scale:e}");
}

#[test]
fn the_texels_projection_is_the_image_projection_of_those_texels() {
    // The same sparse map as above given as texels (the odd height's middle row, a row and its
    // mirror, a row whose mirror is black), one of them split in two at the same place, and two
    // off the grid (left out): each row's Fourier sums taken directly must give the image path's
    // coefficients (FFT) for both quadratures, to rounding.
    let (w, h, order) = (24, 13, 10);
    let lit: [(usize, usize, f64); 4] = [(3, 2, 7.0), (17, 10, 2.0), (5, 4, 3.0), (20, 6, 5.0)];
    let mut img = RgbImage::new(w, h);
    let mut texels = Vec::new();
    for &(x, y, v) in &lit {
        img.pixels[y * w + x] = [v as f32, 0.5 * v as f32, 2.0 * v as f32];
        texels.push((x, y, [v, 0.5 * v, 2.0 * v]));
    }
    texels[0].2 = [3.0, 1.5, 6.0];
    texels.push((3, 2, [4.0, 2.0, 8.0]));
    // Off the grid: left out.
    texels.extend([(w, 0, [9.0; 3]), (0, h, [9.0; 3])]);
    for quadrature in [TexelQuadrature::Midpoint, TexelQuadrature::Integral { z_nodes: 2 }] {
        let image = project_latlong(&img, order, quadrature, &NoProgress).unwrap();
        let direct = project_latlong_texels((w, h), &texels, order, quadrature).unwrap();
        let scale = image.rgb.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        for (i, (a, b)) in direct.rgb.iter().zip(&image.rgb).enumerate() {
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() < 1e-13 * scale,
                    "{quadrature:?}, coefficient {i}, channel {c}: {} against {}",
                    a[c],
                    b[c]
                );
            }
        }
    }
    assert!(project_latlong_texels((w, h), &texels, w / 2 + 1, TexelQuadrature::Midpoint).is_err());
}

#[test]
fn projection_is_identical_for_any_thread_count() {
    let img = RgbImage::from_fn(512, 256, |x, y| [(x as f32 * 0.37).sin().abs(), (y as f32 * 0.11).cos().abs(), 0.5]);
    let map = EnvMap::latlong(img).unwrap();
    let probe = resample(&map, Layout::Angular, 200, 200, 2).unwrap();
    let run = |threads: usize, m: &EnvMap| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| project(m, 16, &NoProgress).unwrap())
    };
    for m in [&map, &probe] {
        let one = run(1, m);
        let many = run(3, m);
        assert!(one.rgb.iter().flatten().zip(many.rgb.iter().flatten()).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
}
