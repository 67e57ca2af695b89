//! Real spherical harmonics: evaluation, projection of environment maps, synthesis, rotation and
//! zonal convolution (Ramamoorthi & Hanrahan 2002).
//!
//! Convention (DESIGN.md, `docs/conventions.md`): real, orthonormal on the sphere, flat index
//! i = l(l+1)+m, no Condon–Shortley phase in the real form, so Y_1,-1 ∝ y, Y_1,0 ∝ z, Y_1,1 ∝ x:
//!
//! Y_lm = √2 N_l^|m| P_l^|m|(cos θ) cos(mφ)  (m > 0),
//! Y_l0 = N_l^0 P_l^0(cos θ),
//! Y_lm = √2 N_l^|m| P_l^|m|(cos θ) sin(|m|φ)  (m < 0),
//!
//! with P_l^m the associated Legendre functions without the (−1)^m phase.

pub mod basis;
pub mod coeffs;
pub mod convolve;
pub mod document;
pub mod legendre;
pub mod project;
pub mod rotate;
pub mod stage;
pub mod synth;
pub mod wigner;
pub mod window;

pub use basis::{eval_basis, eval_basis_dir};
pub use coeffs::ShCoeffs;

/// Flat index of (l, m): l(l+1)+m. The only place this formula lives.
#[inline]
pub const fn index(l: usize, m: isize) -> usize {
    ((l * (l + 1)) as isize + m) as usize
}

/// Index of band l, order m ≥ 0 among the non-negative orders only, band by band:
/// l(l+1)/2 + m. Sums over l at fixed m read the coefficients of m and of −m stored apart in
/// this order, contiguous per band (the separable projection and synthesis).
#[inline]
pub const fn index_nonneg(l: usize, m: usize) -> usize {
    l * (l + 1) / 2 + m
}

/// Number of coefficients up to and including band `order`: (order+1)².
#[inline]
pub const fn count(order: usize) -> usize {
    (order + 1) * (order + 1)
}

/// The (l, m) of a flat index.
#[inline]
pub fn lm(i: usize) -> (usize, isize) {
    let l = (i as f64).sqrt() as usize;
    // Guard against rounding of sqrt near perfect squares.
    let l = if (l + 1) * (l + 1) <= i {
        l + 1
    } else if l * l > i {
        l - 1
    } else {
        l
    };
    (l, i as isize - (l * (l + 1)) as isize)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_round_trip() {
        for i in 0..count(120) {
            let (l, m) = lm(i);
            assert!(m.unsigned_abs() <= l);
            assert_eq!(index(l, m), i);
        }
    }
}
