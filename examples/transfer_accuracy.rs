//! The accuracy half of `scripts/transfer-results.sh` (`docs/results/transfer.md`): the
//! `transfer` stage's library against independent derivations, one compact JSON row per line on
//! stdout.
//!
//! - `unshadowed`: the exact quadrature on a UV sphere against (ρ/π) Â_l Y_lm(n), Â_l typed in
//!   from Ramamoorthi & Hanrahan 2001 (eq. 8–9).
//! - `shadowed`: a bowl holding a ball against a brute-force integral by another code path (every
//!   triangle tested in double precision for each direction of a Gauss–Legendre × azimuth rule in
//!   world axes, no BVH), at several ray counts.
//! - `furnace`: the inside of a closed sphere with the unshadowed transfer as the source term;
//!   each bounce multiplies the constant-lighting response by ρ, so the total is
//!   T^0 (1 + ρ + … + ρ^B).
//!
//! Run: `cargo run --release --example transfer_accuracy [small]` (`small`: fewer vertices,
//! directions and rays, for the tests).

use glam::DVec3;
use prtkit::mesh::{uv_sphere, Mesh};
use prtkit::progress::NoProgress;
use prtkit::sh::basis::eval_basis_dir;
use prtkit::sh::legendre::LegendreTable;
use prtkit::transfer::albedo::{Albedo, Reflectance};
use prtkit::transfer::diffuse::unshadowed_exact;
use prtkit::transfer::directions::Stratified;
use prtkit::transfer::interreflect::{Storage, Tracer};
use prtkit::transfer::stage::{self, Config, Mode};
use prtkit::transfer::visibility::Occluders;
use std::f64::consts::PI;

/// Â_l of the clamped cosine, l = 0..7 (Ramamoorthi & Hanrahan 2001, eq. 8–9).
const A_HAT: [f64; 8] = [PI, 2.0 * PI / 3.0, PI / 4.0, 0.0, -PI / 24.0, 0.0, PI / 64.0, 0.0];

fn main() {
    let small = std::env::args().nth(1).as_deref() == Some("small");
    unshadowed(small);
    shadowed(small);
    furnace(small);
}

fn unshadowed(small: bool) {
    let (rings, segments) = if small { (8, 16) } else { (32, 64) };
    let (p, t) = uv_sphere(rings, segments);
    let mesh = Mesh::new(p.clone(), Some(p.clone()), t).unwrap();
    let (order, albedo) = (8, 0.8);
    let config = Config { order, mode: Mode::Unshadowed, albedo: Albedo::Grey(albedo), ..Config::default() };
    let out = stage::run(&config, &mesh, &NoProgress).unwrap();
    let table = LegendreTable::new(order - 1);
    let mut y = vec![0.0; 64];
    let mut worst = 0.0f64;
    for (v, n) in mesh.normals.iter().enumerate() {
        eval_basis_dir(&table, *n, &mut y);
        for i in 0..64 {
            let l = (i as f64).sqrt().floor() as usize;
            worst = worst.max((out.transfer[v * 64 + i] - albedo / PI * A_HAT[l] * y[i]).abs());
        }
    }
    println!(r#"{{"check":"unshadowed","order":{order},"vertices":{},"max_abs_error":{worst:e}}}"#, p.len());
}

/// A bowl (the lower unit hemisphere, normals facing its inside) holding a ball of radius 0.35.
pub fn bowl_and_ball() -> (Vec<DVec3>, Vec<DVec3>, Vec<[u32; 3]>) {
    let (rings, segments) = (12usize, 24usize);
    let mut p = Vec::new();
    for r in 0..=rings {
        let theta = PI / 2.0 + PI / 2.0 * r as f64 / rings as f64;
        for s in 0..segments {
            let phi = 2.0 * PI * s as f64 / segments as f64;
            p.push(DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()));
        }
    }
    let mut n: Vec<DVec3> = p.iter().map(|v| -*v).collect();
    let mut t = Vec::new();
    let at = |r: usize, s: usize| (r * segments + s % segments) as u32;
    for r in 0..rings {
        for s in 0..segments {
            t.push([at(r, s), at(r + 1, s), at(r + 1, s + 1)]);
            t.push([at(r, s), at(r + 1, s + 1), at(r, s + 1)]);
        }
    }
    let (sp, st) = uv_sphere(10, 20);
    let base = p.len() as u32;
    let centre = DVec3::new(0.2, 0.0, -0.6);
    for v in &sp {
        p.push(centre + 0.35 * *v);
        n.push(*v);
    }
    t.extend(st.iter().map(|tri| tri.map(|i| i + base)));
    (p, n, t)
}

/// Shadowed transfer at one point by brute force: every triangle (double-precision
/// Möller–Trumbore) for every direction of `directions` (world axes, with weights).
pub fn brute_force(
    p: &[DVec3],
    tris: &[[u32; 3]],
    origin: DVec3,
    normal: DVec3,
    order: usize,
    directions: &[(DVec3, f64)],
) -> Vec<f64> {
    let table = LegendreTable::new(order - 1);
    let mut y = vec![0.0; order * order];
    let mut t = vec![0.0; order * order];
    for &(d, w) in directions {
        let cos = normal.dot(d);
        if cos <= 0.0 {
            continue;
        }
        let blocked = tris.iter().any(|tri| {
            let [a, b, c] = tri.map(|i| p[i as usize]);
            let (e1, e2) = (b - a, c - a);
            let pv = d.cross(e2);
            let det = e1.dot(pv);
            if det.abs() < 1e-300 {
                return false;
            }
            let tv = origin - a;
            let u = tv.dot(pv) / det;
            let qv = tv.cross(e1);
            let v = d.dot(qv) / det;
            (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && e2.dot(qv) / det > 0.0
        });
        if !blocked {
            eval_basis_dir(&table, d, &mut y);
            for i in 0..y.len() {
                t[i] += w * cos * y[i] / PI;
            }
        }
    }
    t
}

fn shadowed(small: bool) {
    let (p, n, t) = bowl_and_ball();
    let mesh = Mesh::new(p.clone(), Some(n.clone()), t.clone()).unwrap();
    let (nodes, azimuths, step) = if small { (24, 48, 12) } else { (96, 192, 3) };
    let rule = prtkit::quadrature::gauss_legendre(nodes);
    let directions: Vec<(DVec3, f64)> = rule
        .iter()
        .flat_map(|&(z, w)| {
            let s = (1.0 - z * z).sqrt();
            (0..azimuths).map(move |k| {
                let phi = 2.0 * PI * (k as f64 + 0.5) / azimuths as f64;
                (DVec3::new(s * phi.cos(), s * phi.sin(), z), w * 2.0 * PI / azimuths as f64)
            })
        })
        .collect();
    let sample: Vec<usize> = (0..p.len()).step_by(step).collect();
    let offset = 1e-4 * mesh.extent();
    let orders: &[usize] = if small { &[4] } else { &[4, 8] };
    for &order in orders {
        let coeffs = order * order;
        let reference: Vec<Vec<f64>> =
            sample.iter().map(|&v| brute_force(&p, &t, p[v] + offset * n[v], n[v], order, &directions)).collect();
        let ray_counts: &[usize] = if small { &[64, 256] } else { &[256, 1024, 4096, 16384] };
        for &rays in ray_counts {
            let config = Config { order, mode: Mode::Shadowed, rays, ..Config::default() };
            let out = stage::run(&config, &mesh, &NoProgress).unwrap();
            let (mut d2, mut r2) = (0.0, 0.0);
            for (&v, r) in sample.iter().zip(&reference) {
                for i in 0..coeffs {
                    let d = out.transfer[v * coeffs + i] - r[i];
                    d2 += d * d;
                    r2 += r[i] * r[i];
                }
            }
            println!(
                r#"{{"check":"shadowed","order":{order},"rays":{rays},"vertices":{},"of":{},"directions":{},"relative_rms":{:e}}}"#,
                sample.len(),
                p.len(),
                directions.len(),
                (d2 / r2).sqrt()
            );
        }
    }
}

fn furnace(small: bool) {
    let (rings, segments, rays) = if small { (8, 16, 64) } else { (24, 48, 1024) };
    let (p, t) = uv_sphere(rings, segments);
    let inward: Vec<DVec3> = p.iter().map(|v| -*v).collect();
    let mesh = Mesh::new(p.clone(), Some(inward.clone()), t).unwrap();
    let (order, albedo, bounces) = (3, 0.6, 8);
    let coeffs = order * order;
    let occluders = Occluders::new(&mesh.positions, &mesh.triangles);
    let directions = Stratified::new(rays, 0);
    let tracer = Tracer::new(&mesh, &occluders, &directions, order, 1e-4 * mesh.extent());
    let first = tracer.first_pass(albedo, Storage::Record, &NoProgress);
    let mut source = vec![0.0; p.len() * coeffs];
    for (v, n) in inward.iter().enumerate() {
        unshadowed_exact(*n, order, albedo, &mut source[v * coeffs..(v + 1) * coeffs]);
    }
    let t0 = albedo / (4.0 * PI).sqrt();
    let passes = tracer.bounces(&source, bounces, Reflectance::Grey(albedo), &first.hits, &NoProgress);
    let mut total: Vec<f64> = source.iter().step_by(coeffs).copied().collect();
    for (b, pass) in passes.iter().enumerate() {
        for (s, x) in total.iter_mut().zip(pass.iter().step_by(coeffs)) {
            *s += x;
        }
        let series: f64 = (0..=b + 1).map(|k| albedo.powi(k as i32)).sum();
        let errors: Vec<f64> = total.iter().map(|s| (s / (t0 * series) - 1.0).abs()).collect();
        let worst = errors.iter().copied().fold(0.0, f64::max);
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        println!(
            r#"{{"check":"furnace","albedo":{albedo},"bounces":{},"rays":{rays},"vertices":{},"lost_rays":{:e},"total":{},"series":{},"max_relative_error":{worst:e},"mean_relative_error":{mean:e}}}"#,
            b + 1,
            p.len(),
            1.0 - first.front_fraction,
            total.iter().sum::<f64>() / total.len() as f64 / t0,
            series
        );
    }
}
