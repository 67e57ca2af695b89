//! The paper's algorithm (R&H 2002 App. C) through the stage: `--order-rule energy --bright off
//! --window none` is `pipeline::frequency`, orders from the BRDF's energy (§5.1), the whole
//! lighting through spherical harmonics, no window. Checked against the analytic reflection of a
//! low-order lighting (eq. 5: B_lm = Λ_l ρ̂_l L_lm) and against `pipeline::frequency` called
//! directly.

use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::envmap::bright::BrightRule;
use prtkit::envmap::EnvMap;
use prtkit::io::RgbImage;
use prtkit::prefilter::model::Model;
use prtkit::prefilter::orders::OrderRule;
use prtkit::prefilter::pipeline::{self, Lighting, Orders};
use prtkit::prefilter::shrm;
use prtkit::prefilter::stage::{run, Config, MapRequest};
use prtkit::progress::NoProgress;
use prtkit::sh::window::Window;
use prtkit::sh::ShCoeffs;
use prtkit::sphere::LatLong;
use std::f64::consts::PI;

/// The paper's algorithm for `brdf`, one map for a view along +Z on a 64×32 grid.
fn paper_config(brdf: &str) -> Config {
    Config {
        order_rule: OrderRule::Energy,
        bright: BrightRule::Off,
        window: Window::None,
        size: Some((64, 32)),
        maps: vec![MapRequest { file: "m.exr".into(), view: DVec3::Z }],
        source: "test".into(),
        ..Config::new(Brdf::parse(brdf).unwrap())
    }
}

/// A lighting of bands 0–2, zonal (m = 0 only, whose Y_l0 are the same in every real-SH
/// convention), per channel different, given to order 24 (bands 3–24 zero).
fn zonal_lighting() -> ShCoeffs {
    let mut light = ShCoeffs::zeros(24);
    light.rgb[0] = [1.0, 2.0, 0.5];
    light.rgb[2] = [0.5, -0.3, 0.2];
    light.rgb[6] = [0.3, 0.1, -0.2];
    light
}

/// B(R) = Σ_l k_l L_l0 Y_l0(R) with Y_00 = 1/(2√π), Y_10 = √(3/4π) z, Y_20 = √(5/16π)(3z² − 1).
fn reflected(k: [f64; 3], light: &ShCoeffs, z: f64) -> [f64; 3] {
    let y = [0.5 / PI.sqrt(), (3.0 / (4.0 * PI)).sqrt() * z, (5.0 / (16.0 * PI)).sqrt() * (3.0 * z * z - 1.0)];
    let l0 = [light.rgb[0], light.rgb[2], light.rgb[6]];
    [0, 1, 2].map(|c| (0..3).map(|l| k[l] * l0[l][c] * y[l]).sum())
}

/// Λ_l ρ̂_l in closed form (Funk–Hecke): Lambert (albedo 1) is the clamped cosine over π,
/// 1, 2/3, 1/4 (Ramamoorthi & Hanrahan 2001); normalized Phong (s + 1)/2π (R·ω)^s is
/// (s + 1) ∫₀¹ x^s P_l(x) dx: 1, (s + 1)/(s + 2), (s + 1)/2 · (3/(s + 3) − 1/(s + 1)).
#[test]
fn the_paper_order_bake_reflects_a_low_order_lighting_exactly() {
    let s = 8.0;
    for (brdf, k) in [
        ("lambert", [1.0, 2.0 / 3.0, 0.25]),
        ("phong:s=8", [1.0, (s + 1.0) / (s + 2.0), (s + 1.0) / 2.0 * (3.0 / (s + 3.0) - 1.0 / (s + 1.0))]),
    ] {
        let light = zonal_lighting();
        let out = run(&paper_config(brdf), Lighting::Coefficients(&light), &NoProgress).unwrap();
        let body = &out.document.body;
        let bake = body.bake.as_ref().expect("the frequency method reports its bake");
        assert_eq!(bake.rule, "energy", "{brdf}");
        assert_eq!((bake.bright.texels, bake.window.kind, bake.window.t), (0, Window::None, None), "{brdf}");
        assert!(body.f_b >= 2 && body.p_b == 0, "{brdf}: F_B = {}", body.f_b);
        let map = &out.maps[0];
        let grid = LatLong::new(map.width, map.height);
        let peak = 2.5;
        for y in 0..map.height {
            for x in 0..map.width {
                let want = reflected(k, &light, grid.texel_direction(x, y).z);
                let got = map.pixels[y * map.width + x];
                for c in 0..3 {
                    let error = (got[c] as f64 - want[c]).abs();
                    assert!(error < 1e-5 * peak, "{brdf} ({x}, {y}) channel {c}: {} against {}", got[c], want[c]);
                }
            }
        }
    }
}

/// Through a map, the stage's paper-order bake is `pipeline::frequency` on it, to the bit: the
/// same orders, the same SHRM, the same map.
#[test]
fn the_paper_order_bake_is_pipeline_frequency() {
    let grid = LatLong::new(64, 32);
    let sky = EnvMap::latlong(RgbImage::from_fn(64, 32, |x, y| {
        let d = grid.texel_direction(x, y);
        let sun = if d.dot(DVec3::new(0.6, 0.0, 0.8)) > 0.98 { 50.0 } else { 0.0 };
        [(1.0 + d.z.max(0.0) + sun) as f32, (0.8 + 0.2 * d.x + sun) as f32, (0.5 + sun) as f32]
    }))
    .unwrap();
    let config = Config { max_p: 3, ..paper_config("torrance-sparrow:sigma=0.3") };
    let out = run(&config, Lighting::Map(&sky), &NoProgress).unwrap();
    let model = Model::new(config.brdf.clone(), true).unwrap();
    let orders = Orders::Epsilon { epsilon: config.epsilon, max_p: 3 };
    let direct = pipeline::frequency(&model, Lighting::Map(&sky), orders, config.size, &NoProgress).unwrap();
    assert_eq!((out.summary.f_b, out.summary.p_b), (direct.brdf.f, direct.brdf.p));
    assert_eq!(out.summary.epsilon_achieved, direct.epsilon_achieved);
    assert_eq!(out.maps[0], shrm::reflection_map(&direct.shrm, DVec3::Z));
}
