//! Scratch exploration (not committed).
use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::envmap::{resample, Layout, LoadOptions};
use prtkit::metrics::compare;
use prtkit::prefilter::angular::{self, ConeIntegrator, CutoffTable};
use prtkit::prefilter::model::Model;
use prtkit::prefilter::shrm;
use prtkit::progress::NoProgress;
use prtkit::sh::project::project;

fn main() {
    let path = std::env::args().nth(1).unwrap_or("../shared/testdata/envmaps/grace_latlong.exr".into());
    let map = LoadOptions::default().load(std::path::Path::new(&path)).unwrap().map;
    let env = resample(&map, Layout::LatLong, 256, 128, 3).unwrap();
    let cone = ConeIntegrator::new(&env).unwrap();
    let eps: f64 = std::env::var("EPS").ok().and_then(|v| v.parse().ok()).unwrap_or(1e-3);
    // Bright split: T = 16 x median luminance (by texel count).
    let mut lum: Vec<f32> = env.image().pixels.iter().map(|p| (p[0] + p[1] + p[2]) / 3.0).collect();
    lum.sort_by(|a, b| a.total_cmp(b));
    let k: f32 = std::env::var("K").ok().and_then(|v| v.parse().ok()).unwrap_or(16.0);
    let t = k * lum[lum.len() / 2];
    let mut remainder = env.clone();
    let mut bright = Vec::new();
    let (w, h) = (256, 128);
    let grid = prtkit::sphere::LatLong::new(w, h);
    for (i, p) in remainder.images_mut()[0].pixels.iter_mut().enumerate() {
        let l = (p[0] + p[1] + p[2]) / 3.0;
        if l > t {
            let s = t / l;
            let excess = [p[0] * (1.0 - s), p[1] * (1.0 - s), p[2] * (1.0 - s)];
            *p = [p[0] * s, p[1] * s, p[2] * s];
            let (x, y) = (i % w, i / w);
            bright.push((grid.texel_direction(x, y), grid.row_solid_angle(y), excess));
        }
    }
    let total: f64 = env.image().pixels.iter().enumerate().map(|(i, p)| grid.row_solid_angle(i / w) * (p[0] + p[1] + p[2]) as f64).sum();
    let be: f64 = bright.iter().map(|b| b.1 * (b.2[0] + b.2[1] + b.2[2]) as f64).sum();
    println!("threshold {t}: {} bright texels ({:.2}% of texels), {:.1}% of energy", bright.len(), 100.0 * bright.len() as f64 / (w * h) as f64, 100.0 * be / total);
    let light_full = project(&remainder, 127, &NoProgress).unwrap();
    for sigma in [0.2f64] {
        let model = Model::new(Brdf::parse(&format!("torrance-sparrow:sigma={sigma}")).unwrap(), true).unwrap();
        let cutoff = CutoffTable::new(|wi, wo| model.rho_hat_grey(wi, wo), eps, 65);
        for view in [DVec3::Z, DVec3::new(0.0, -0.95, 0.3).normalize()] {
            let t = std::time::Instant::now();
            let reference = angular::view_map(&cone, &model, &cutoff, view, 256, 128, &NoProgress);
            let ref_s = t.elapsed().as_secs_f64();
            for (f, p) in [(12, 2), (24, 3), (40, 4), (60, 6)] {
                let t = std::time::Instant::now();
                let coeffs = model.coefficients(f, p);
                let light = light_full.truncated(f);
                let local = shrm::local_shrm(&light, &coeffs, 256, 128, &NoProgress).unwrap();
                let global = shrm::to_global(&local);
                let mut freq = shrm::reflection_map(&global, view);
                for (i, px) in freq.pixels.iter_mut().enumerate() {
                    let r = grid.texel_direction(i % w, i / w);
                    let Some(prep) = model.prepare_view(r, view) else { continue };
                    let mut acc = [0.0f64; 3];
                    for (d, om, e) in &bright {
                        let v = model.rho_hat_prepared(&prep, *d);
                        for c in 0..3 { acc[c] += v[c] * om * e[c] as f64; }
                    }
                    for c in 0..3 { px[c] += acc[c] as f32; }
                }
                let fs = t.elapsed().as_secs_f64();
                let (m, _) = compare(&freq, &reference, &[]).unwrap();
                println!("sigma={sigma} view={view:.2} F={f} P={p}: rel {:.3}% neg {:.2}% p99 {:.2}% max {:.2}% at {:?} (ref {ref_s:.1}s, freq {fs:.2}s) resid {:.2e}", 100.0*m.rel_error, 100.0*m.negative_fraction, 100.0*m.p99_texel_error, 100.0*m.max_texel_error, m.worst_texel, coeffs.residual(f,p));
            }
        }
    }
}
