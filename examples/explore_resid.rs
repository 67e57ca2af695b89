use glam::DVec3;
use prtkit::brdf::Brdf;
use prtkit::prefilter::model::Model;
use prtkit::sh::legendre::LegendreTable;
use prtkit::sh::{basis::eval_basis_dir, count, index};
fn main() {
    let sigma: f64 = std::env::args().nth(1).and_then(|v| v.parse().ok()).unwrap_or(0.2);
    let cosine = std::env::args().nth(2).map(|v| v == "cos").unwrap_or(true);
    let model = Model::new(Brdf::parse(&format!("torrance-sparrow:sigma={sigma}")).unwrap(), cosine).unwrap();
    for (f, p) in [(12usize, 2usize), (24, 3), (40, 4), (60, 6), (100, 10)] {
        let c = model.coefficients(f, p);
        let tl = LegendreTable::new(f);
        let tp = LegendreTable::new(p);
        let mut yl = vec![0.0; count(f)];
        let mut yp = vec![0.0; count(p)];
        let mut line = format!("F={f} P={p}:");
        for deg in [0.0f64, 30.0, 60.0, 90.0, 120.0, 140.0, 150.0, 160.0, 170.0] {
            let to = deg.to_radians();
            let wo = DVec3::new(to.sin(), 0.0, to.cos());
            eval_basis_dir(&tp, wo, &mut yp);
            let (mut e2, mut r2) = (0.0, 0.0);
            let (nt, np) = (200, 200);
            for a in 0..nt {
                let ti = std::f64::consts::PI * (a as f64 + 0.5) / nt as f64;
                for b in 0..np {
                    let ph = 2.0 * std::f64::consts::PI * (b as f64 + 0.5) / np as f64;
                    let wi = prtkit::sphere::direction(ti, ph);
                    let om = ti.sin();
                    let exact = model.rho_hat(wi, wo)[0];
                    eval_basis_dir(&tl, wi, &mut yl);
                    let mut approx = 0.0;
                    for l in 0..=f { for pp in 0..=p { for q in -(l.min(pp) as isize)..=(l.min(pp) as isize) {
                        approx += c.get(l, pp, q)[0] * yl[index(l, q)] * yp[index(pp, q)];
                    }}}
                    e2 += (exact - approx).powi(2) * om; r2 += exact * exact * om;
                }
            }
            line += &format!(" {deg}°:{:.3}", (e2 / r2).sqrt());
        }
        println!("{line}");
    }
}
