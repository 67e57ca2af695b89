//! Closed-form maximum angular errors (Meyer et al. 2010, eqs. 3, 5–8, 10, 11) evaluated at the
//! *actual* sample spacing of our layouts, and written so they stay accurate at 64 bits (no
//! `acos` of a number within 1e-16 of 1: every `arccos(c)` is rewritten as `atan` or
//! `2·asin(sqrt((1-c)/2))` with `1-c` computed without cancellation).
//!
//! With an odd number of coordinate bits the two axes have different spacings; the bound uses
//! the coarser one (conservative). The paper's Table 1 uses fractional bits, `ε(b) = 2·2^(-b/2)`
//! etc., which our integer fields cannot realize; `docs/encode-normals.md` compares the two.

use super::fixed::snorm_spacing;
use super::sc::ScLayout;
use super::sextant::FaceLayout;
use super::{onv::OnvLayout, pp::PpLayout, Scheme};
use std::f64::consts::{FRAC_1_SQRT_2, PI, SQRT_2};

/// The sample spacing `ε` of `scheme` at `bits`, in the paper's units: the step of the coarser
/// coordinate in the parameter domain (`[-1,1]` for ONV, PP, CM; `[-1/√2, 1/√2]` for SPP; for SC
/// the larger angular step divided by π, so that eq. 5 reads `Δ ≈ (√2/2)·π·ε`).
pub fn spacing(scheme: Scheme, bits: u32) -> f64 {
    match scheme {
        Scheme::OnvRange | Scheme::OnvDomain => snorm_spacing(OnvLayout::new(bits).v_bits),
        Scheme::Sc => {
            let l = ScLayout::new(bits);
            l.theta_step().max(l.phi_step()) / PI
        }
        Scheme::Pp => snorm_spacing(PpLayout::new(bits).y_bits),
        Scheme::Spp => FRAC_1_SQRT_2 * snorm_spacing(FaceLayout::new(bits).b_bits),
        Scheme::Cm => snorm_spacing(FaceLayout::new(bits).b_bits),
    }
}

/// `2·asin(sqrt(one_minus_cos / 2))`: `arccos(1 - x)` without cancellation.
fn acos_one_minus(one_minus_cos: f64) -> f64 {
    2.0 * (0.5 * one_minus_cos).sqrt().asin()
}

/// Eq. 10: `arccos sqrt(2/(2+9ε²)) = atan(3ε/√2)`.
pub fn onv_domain(eps: f64) -> f64 {
    (3.0 * eps / SQRT_2).atan()
}

/// Eq. 11: `√2·ε` (the paper gives only the leading term; the `O(ε³)` remainder is covered by
/// the slack of the property tests, see `docs/encode-normals.md`).
pub fn onv_range(eps: f64) -> f64 {
    SQRT_2 * eps
}

/// Eq. 5 generalized to unequal steps: the worst point sits half a step off in both angles on
/// the equator, `cos Δ = cos(sθ/2)·cos(sφ/2)` (eq. 5 when `sθ = sφ = πε`).
pub fn sc(theta_step: f64, phi_step: f64) -> f64 {
    let (a, b) = (0.5 * theta_step, 0.5 * phi_step);
    // 1 - cos a cos b = 2 sin²(a/2) + cos a · 2 sin²(b/2).
    let one_minus = 2.0 * (0.5 * a).sin().powi(2) + a.cos() * 2.0 * (0.5 * b).sin().powi(2);
    acos_one_minus(one_minus)
}

/// Eq. 6: `arccos(1 - (√2/2)ε)`.
pub fn pp(eps: f64) -> f64 {
    acos_one_minus(0.5 * SQRT_2 * eps)
}

/// Eq. 7: `arccos(2/3 - (√3/3)ε + (1/6)·sqrt(4 + √192·ε - 6ε²))`. With `w = 2√3ε - 3ε²/2` and
/// `R = sqrt(1+w)` the cosine is `2/3 - (√3/3)ε + R/3`, and
/// `1 - cos = (√3·ε·w/(1+R) + 3ε²/2) / (3(1+R))`, a sum of positive terms.
pub fn spp(eps: f64) -> f64 {
    let s3 = 3f64.sqrt();
    let w = 2.0 * s3 * eps - 1.5 * eps * eps;
    let r = (1.0 + w).sqrt();
    let one_minus = (s3 * eps * w / (1.0 + r) + 1.5 * eps * eps) / (3.0 * (1.0 + r));
    acos_one_minus(one_minus)
}

/// Eq. 8: `arccos(2/sqrt(2ε²+4)) = atan(ε/√2)`.
pub fn cm(eps: f64) -> f64 {
    (eps / SQRT_2).atan()
}

/// Eq. 3 (exact form above it): the worst angular error of floating-point direction vectors with
/// an `m`-bit mantissa. The cell size at `[1/2, 1)` is `ε = 2^(-m-1)`, and
/// `Δ = arccos sqrt(1 - 8ε²/(9+12ε+12ε²)) = asin sqrt(8ε²/(9+12ε+12ε²)) ≈ (√2/3)·2^(-m)`.
pub fn fpnv(mantissa_bits: u32) -> f64 {
    let eps = (-(mantissa_bits as f64) - 1.0).exp2();
    (8.0 * eps * eps / (9.0 + 12.0 * eps + 12.0 * eps * eps)).sqrt().asin()
}

/// Eq. 4: bits a uniform discretization needs to match `m`-bit-mantissa FPNVs,
/// `⌈log2(18·2^(2m))⌉ = 2m + 5`.
pub fn fpnv_equivalent_bits(mantissa_bits: u32) -> u32 {
    (18f64.log2() + 2.0 * mantissa_bits as f64).ceil() as u32
}

/// The closed-form bound of `scheme` at `bits`, generalized to the unequal per-axis steps of
/// odd splits (each reduces to the printed equation when the steps are equal):
/// - ONV_domain (eq. 10): the face centre offset by half a step `(a, b)` in `(u, v)`:
///   `atan(√3·sqrt(a² + b² + (a+b)²))`;
/// - ONV_range (eq. 11): near the face centre a step `(du, dv)` subtends `√3·|(du, dv, -du-dv)|`,
///   so the cell's corners form triangles with sides `ℓu = √6·εu`, `ℓv = √6·εv` at 60°; the
///   nearest-of-four-corners error peaks at their circumradius `ℓ3/√3`,
///   `ℓ3² = ℓu² + ℓv² - ℓu·ℓv` (or at half the longer side if the triangle is obtuse):
///   `√2·ε` for equal steps;
/// - PP (eq. 6): the half-cell diagonal `sqrt(εx² + εy²)/2` taken radially at the unit circle;
/// - SPP (eq. 7): at the effective spacing `sqrt(2/3)·sqrt(a² + b² + (a+b)²)` (half steps `a`,
///   `b`), which gives the same leading term as the unequal-step derivation;
/// - CM (eq. 8): the face centre offset by half a step: `atan(sqrt(a² + b²))`;
/// - SC (eq. 5): see [`sc`].
pub fn bound(scheme: Scheme, bits: u32) -> f64 {
    match scheme {
        Scheme::OnvRange | Scheme::OnvDomain => {
            let l = OnvLayout::new(bits);
            let (eu, ev) = (snorm_spacing(l.u_bits), snorm_spacing(l.v_bits));
            if scheme == Scheme::OnvDomain {
                let (a, b) = (0.5 * eu, 0.5 * ev);
                (3f64.sqrt() * (a * a + b * b + (a + b) * (a + b)).sqrt()).atan()
            } else {
                let circum = SQRT_2 * (eu * eu + ev * ev - eu * ev).sqrt();
                let half_long = 0.5 * 6f64.sqrt() * eu.max(ev);
                circum.max(half_long)
            }
        }
        Scheme::Sc => {
            let l = ScLayout::new(bits);
            sc(l.theta_step(), l.phi_step())
        }
        Scheme::Pp => {
            let l = PpLayout::new(bits);
            let (ex, ey) = (snorm_spacing(l.x_bits), snorm_spacing(l.y_bits));
            acos_one_minus(0.5 * (ex * ex + ey * ey).sqrt())
        }
        Scheme::Spp => {
            let l = FaceLayout::new(bits);
            let (a, b) = (0.5 * FRAC_1_SQRT_2 * snorm_spacing(l.a_bits), 0.5 * FRAC_1_SQRT_2 * snorm_spacing(l.b_bits));
            spp((2.0 / 3.0 * (a * a + b * b + (a + b) * (a + b))).sqrt())
        }
        Scheme::Cm => {
            let l = FaceLayout::new(bits);
            let (a, b) = (0.5 * snorm_spacing(l.a_bits), 0.5 * snorm_spacing(l.b_bits));
            (a * a + b * b).sqrt().atan()
        }
    }
}

/// The smallest budget at which the closed-form bound of `scheme` is at most `target`.
pub fn bits_needed(scheme: Scheme, target: f64) -> Option<u32> {
    (super::MIN_BITS..=super::MAX_BITS).find(|&b| bound(scheme, b) <= target)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn stable_forms_match_the_printed_arccos_forms_where_those_are_accurate() {
        for eps in [1e-1f64, 3e-2, 1e-2, 1e-3] {
            let printed_domain = (2.0 / (2.0 + 9.0 * eps * eps)).sqrt().acos();
            assert!(rel(onv_domain(eps), printed_domain) < 1e-9);
            let printed_cm = (2.0 / (2.0 * eps * eps + 4.0).sqrt()).acos();
            assert!(rel(cm(eps), printed_cm) < 1e-9);
            let printed_pp = (1.0 - 0.5 * SQRT_2 * eps).acos();
            assert!(rel(pp(eps), printed_pp) < 1e-9);
            let s3 = 3f64.sqrt();
            let printed_spp =
                (2.0 / 3.0 - s3 / 3.0 * eps + (4.0 + 192f64.sqrt() * eps - 6.0 * eps * eps).sqrt() / 6.0).acos();
            assert!(rel(spp(eps), printed_spp) < 1e-6, "{eps} {} {printed_spp}", spp(eps));
            let printed_sc = ((PI * eps / 2.0).cos().powi(2)).acos();
            assert!(rel(sc(PI * eps, PI * eps), printed_sc) < 1e-9);
        }
    }

    #[test]
    fn leading_terms_of_the_paper() {
        // ε → 0: eq. 5 ≈ (√2/2)πε, eq. 6 ≈ 2^(1/4)√ε, eq. 7 ≈ (√2/2)√3ε, eq. 8 ≈ (√2/2)ε,
        // eq. 10 ≈ (√2/2)3ε, eq. 3 ≈ (√2/3)2^-m.
        let eps = 1e-7;
        assert!(rel(sc(PI * eps, PI * eps), 0.5 * SQRT_2 * PI * eps) < 1e-9);
        assert!(rel(pp(eps), 2f64.powf(0.25) * eps.sqrt()) < 1e-6);
        assert!(rel(spp(eps), 0.5 * SQRT_2 * 3f64.sqrt() * eps) < 1e-6);
        assert!(rel(cm(eps), 0.5 * SQRT_2 * eps) < 1e-9);
        assert!(rel(onv_domain(eps), 1.5 * SQRT_2 * eps) < 1e-9);
        assert!(rel(fpnv(23), SQRT_2 / 3.0 * (-23f64).exp2()) < 1e-6);
    }

    #[test]
    fn paper_table_1_at_48_bits_with_the_papers_spacings() {
        // Table 1, row 3, from row 1's ε(48) (fractional bits): the paper's printed values.
        let cases = [
            (onv_range(2.0 * (-24f64).exp2()), 1.69e-7),
            (onv_domain(2.0 * (-24f64).exp2()), 2.53e-7),
            (cm(2.0 * (-22.5f64).exp2()), 2.38e-7),
            (spp(SQRT_2 * (-22.5f64).exp2()), 2.92e-7),
            (pp(2.0 * (-23.5f64).exp2()), 4.88e-4),
            (fpnv(10), 4.60e-4),
        ];
        for (value, printed) in cases {
            assert!(rel(value, printed) < 5e-3, "{value} vs {printed}");
        }
        // SC: 3.74e-7 corresponds to angular steps of π·2^-22.5 (the paper's split is not given).
        assert!(rel(sc(PI * (-22.5f64).exp2(), PI * (-22.5f64).exp2()), 3.74e-7) < 5e-3);
    }

    #[test]
    fn generalized_bounds_reduce_to_the_printed_ones_for_equal_steps() {
        // ONV at even budgets has equal steps: bound() must equal eqs. 10 and 11 exactly.
        for bits in [16, 32, 48] {
            let eps = spacing(Scheme::OnvDomain, bits);
            assert!(rel(bound(Scheme::OnvDomain, bits), onv_domain(eps)) < 1e-12);
            assert!(rel(bound(Scheme::OnvRange, bits), onv_range(eps)) < 1e-12);
        }
        // Unequal steps never give more than the coarse step used on both axes.
        for bits in 8..=64 {
            for scheme in Scheme::ALL {
                let eps = spacing(scheme, bits);
                let coarse = match scheme {
                    Scheme::OnvRange => onv_range(eps),
                    Scheme::OnvDomain => onv_domain(eps),
                    Scheme::Pp => pp(eps),
                    Scheme::Spp => spp(eps),
                    Scheme::Cm => cm(eps),
                    Scheme::Sc => bound(scheme, bits),
                };
                assert!(bound(scheme, bits) <= coarse * (1.0 + 1e-12), "{scheme} {bits}");
            }
        }
    }

    #[test]
    fn bits_claims_of_section_3_and_5() {
        // Eq. 4: 51 bits match single-precision FPNVs; eq. 11 vs. eq. 3: ONV_range needs 52.
        assert_eq!(fpnv_equivalent_bits(23), 51);
        assert_eq!(bits_needed(Scheme::OnvRange, fpnv(23)), Some(52));
        // The 96-bit FPNV error is 5.62e-8 (§6).
        assert!(rel(fpnv(23), 5.62e-8) < 2e-3);
    }
}
