//! Evaluating all real SH basis functions at one direction.

use super::legendre::LegendreTable;
use glam::DVec3;
use std::f64::consts::SQRT_2;

/// Fills `out[index(l,m)]` with Y_lm(θ, φ) for all l ≤ `table.order()`, from cos θ, sin θ ≥ 0
/// and φ. `out` must hold `count(order)` values.
pub fn eval_basis(table: &LegendreTable, cos_theta: f64, sin_theta: f64, phi: f64, out: &mut [f64]) {
    let order = table.order();
    table.eval(cos_theta, sin_theta, out);
    for m in 1..=order {
        let (s, c) = (m as f64 * phi).sin_cos();
        for l in m..=order {
            let p = out[super::index(l, m as isize)] * SQRT_2;
            out[super::index(l, m as isize)] = p * c;
            out[super::index(l, -(m as isize))] = p * s;
        }
    }
}

/// [`eval_basis`] at a direction (need not be normalized; must be non-zero).
pub fn eval_basis_dir(table: &LegendreTable, dir: DVec3, out: &mut [f64]) {
    let d = dir.normalize();
    let sin_theta = (d.x * d.x + d.y * d.y).sqrt();
    let phi = crate::sphere::phi(d);
    eval_basis(table, d.z.clamp(-1.0, 1.0), sin_theta, phi, out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sh::{count, index};
    use std::f64::consts::PI;

    #[test]
    fn band_one_is_y_z_x() {
        let t = LegendreTable::new(1);
        let mut y = vec![0.0; 4];
        let d = DVec3::new(0.2, -0.5, 0.7).normalize();
        eval_basis_dir(&t, d, &mut y);
        let k = (3.0 / (4.0 * PI)).sqrt();
        assert!((y[index(1, -1)] - k * d.y).abs() < 1e-14);
        assert!((y[index(1, 0)] - k * d.z).abs() < 1e-14);
        assert!((y[index(1, 1)] - k * d.x).abs() < 1e-14);
    }

    #[test]
    fn band_two_closed_forms() {
        // Ramamoorthi & Hanrahan 2001 ("An efficient representation for irradiance
        // environment maps"), eq. 3: the order-2 real SH in Cartesian form.
        let t = LegendreTable::new(2);
        let mut y = vec![0.0; count(2)];
        let d = DVec3::new(-0.3, 0.4, 0.6).normalize();
        eval_basis_dir(&t, d, &mut y);
        let (x, yy, z) = (d.x, d.y, d.z);
        let c1 = 0.5 * (15.0 / PI).sqrt();
        assert!((y[index(2, -2)] - c1 * x * yy).abs() < 1e-14);
        assert!((y[index(2, -1)] - c1 * yy * z).abs() < 1e-14);
        assert!((y[index(2, 1)] - c1 * x * z).abs() < 1e-14);
        assert!((y[index(2, 0)] - 0.25 * (5.0 / PI).sqrt() * (3.0 * z * z - 1.0)).abs() < 1e-14);
        assert!((y[index(2, 2)] - 0.25 * (15.0 / PI).sqrt() * (x * x - yy * yy)).abs() < 1e-14);
    }
}
