//! Render benchmarks (harness = false; prints results):
//! - `shrm` mode on a 512×512 sphere: ms per frame (the frame's reflection map from a global
//!   SHRM, eq. 12, plus ray casting and lookups), excluding file I/O; target ≤ 33 ms (§7.5).
//! - factored relighting with K = 75 on a ~10⁴-vertex mesh: ms to re-project a new environment
//!   onto the per-vertex transport (visibility precomputed), and ms to shade a 512×512 frame.
//!
//! Run: `cargo bench --bench render`.

use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::envmap::EnvMap;
use prtkit::factor::{Channel, Domain, Method, Sampling};
use prtkit::io::RgbImage;
use prtkit::mesh::{uv_sphere, Mesh};
use prtkit::prefilter::model::Model;
use prtkit::prefilter::shrm::{local_shrm, to_global};
use prtkit::progress::NoProgress;
use prtkit::render::factored::{Factored, Transport};
use prtkit::render::reflection::ShrmShader;
use prtkit::render::{render, Camera, Scene};
use std::time::Instant;

fn sky(w: usize, h: usize, tilt: f64) -> EnvMap {
    let img = RgbImage::from_fn(w, h, |x, y| {
        let d = prtkit::sphere::LatLong::new(w, h).texel_direction(x, y);
        let sun = (40.0 * (d.dot(DVec3::new(tilt, -0.4, 0.7).normalize()) - 1.0)).exp();
        let v = (0.3 + 0.5 * d.z.max(0.0) + 20.0 * sun) as f32;
        [v, 0.9 * v, 0.8 * v]
    });
    EnvMap::latlong(img).unwrap()
}

fn main() {
    let env = sky(256, 128, 0.5);
    let camera = Camera::look_at(DVec3::new(0.0, -4.0, 0.8), DVec3::ZERO, 30.0, 512, 512).unwrap();

    // SHRM: Phong s = 32 at F_B = 24, global (view-independent lobe: P_B = 0) and a general BRDF.
    for (spec, f, p, cosine) in [("phong:s=32", 24, 0, true), ("torrance-sparrow:sigma=0.2", 16, 4, false)] {
        let model = Model::new(Brdf::parse(spec).unwrap(), cosine).unwrap();
        let light = prtkit::sh::project::project(&env, f, &NoProgress).unwrap();
        let shrm = to_global(&local_shrm(&light, &model.coefficients(f, p), 128, 64, &NoProgress).unwrap());
        let scene = Scene::unit_sphere();
        let frames = 10;
        let t = Instant::now();
        for _ in 0..frames {
            let shader = ShrmShader::new(shrm.clone(), false, camera.view_direction());
            std::hint::black_box(render(&scene, &camera, &env, &shader, &NoProgress));
        }
        let ms = t.elapsed().as_secs_f64() * 1e3 / frames as f64;
        println!("shrm {spec} F_B={f} P_B={p}, 512x512 sphere: {ms:.2} ms/frame ({:.1} fps)", 1e3 / ms);
    }

    // Factored K = 75 on a 10⁴-vertex sphere mesh.
    let (pos, tris) = uv_sphere(100, 100);
    let mesh = Mesh::new(pos.clone(), Some(pos), tris).unwrap();
    let verts = mesh.positions.len();
    let scene = Scene::Mesh(Box::new(mesh));
    let sampling = Sampling { resolution: 32, domain: Domain::Hemisphere, cosine: true, channel: Channel::Mean };
    let brdf = Brdf::parse("phong:s=30").unwrap();
    let f = prtkit::factor::factor(&brdf, &sampling, Method::Auto, 75, &NoProgress).unwrap();
    let t = Instant::now();
    let transport = Transport::mesh(&scene, &f.grid, &NoProgress);
    println!(
        "factored: visibility precomputation, {verts} vertices x {} cells: {:.0} ms",
        f.grid.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let mut shader = Factored::new(&f, 75, true, transport, &env, 1);
    let other = sky(256, 128, -0.5);
    let frames = 5;
    let t = Instant::now();
    for i in 0..frames {
        shader.relight(&f.g, if i % 2 == 0 { &other } else { &env }, 1);
    }
    let relight = t.elapsed().as_secs_f64() * 1e3 / frames as f64;
    let t = Instant::now();
    std::hint::black_box(render(&scene, &camera, &env, &shader, &NoProgress));
    let shade = t.elapsed().as_secs_f64() * 1e3;
    println!("factored K=75, {verts} vertices, 32x32 hemisphere cells: relight {relight:.1} ms/frame, shade 512x512 {shade:.1} ms");
}
