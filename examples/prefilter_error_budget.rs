//! Where the error of a microfacet SHRM comes from: the frequency result at several (F_B, P_B)
//! against the angular reference truncated at ε = .05 (as in Table 5) and at ε = .001 (nearly
//! exact), for three views of Grace Cathedral at σ = 0.1. See docs/prefilter.md.
//!
//! `cargo run --release --example prefilter_error_budget` (needs ../shared/testdata)
use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::envmap::{resample, EnvMap, Layout};
use prtkit::io::image::read_image;
use prtkit::io::RgbImage;
use prtkit::prefilter::model::Model;
use prtkit::prefilter::pipeline::{self, AngularSettings, Lighting, Orders};
use prtkit::prefilter::shrm;
use prtkit::progress::NoProgress;
fn rel(a: &RgbImage, b: &RgbImage) -> f64 {
    let (mut n, mut d) = (0.0, 0.0);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for k in 0..3 {
            n += (p[k] as f64 - q[k] as f64).powi(2);
            d += (q[k] as f64).powi(2);
        }
    }
    (n / d).sqrt()
}
fn main() {
    let img = read_image(std::path::Path::new("/work/shared/testdata/envmaps/grace_probe_250.pfm")).unwrap();
    let env = resample(&EnvMap::new(Layout::Angular, img).unwrap(), Layout::LatLong, 128, 128, 4).unwrap();
    let model = Model::new(Brdf::parse("torrance-sparrow:sigma=0.1").unwrap(), false).unwrap();
    let views = [DVec3::Z, DVec3::new(1.0, 0.0, 0.3).normalize(), DVec3::new(0.2, 0.3, -0.9).normalize()];
    let a05 =
        pipeline::angular_maps(&model, &env, &views, AngularSettings::paper(0.05), 128, 128, &NoProgress).unwrap();
    let a001 =
        pipeline::angular_maps(&model, &env, &views, AngularSettings::paper(0.001), 128, 128, &NoProgress).unwrap();
    for (f, p) in [(23, 2), (23, 3), (40, 3), (40, 6)] {
        let r = pipeline::frequency(&model, Lighting::Map(&env), Orders::Fixed { f, p }, Some((128, 128)), &NoProgress)
            .unwrap();
        let g = shrm::to_global(&r.shrm);
        for (k, v) in views.iter().enumerate() {
            let m = shrm::reflection_map(&g, *v);
            println!(
                "F={f} P={p} view {k}: vs ang.05 {:.4}  vs ang.001 {:.4}   (ang.05 vs ang.001 {:.4})",
                rel(&m, &a05[k]),
                rel(&m, &a001[k]),
                rel(&a05[k], &a001[k])
            );
        }
    }
}
