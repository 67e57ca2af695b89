//! Closed-form maximum angular errors (Meyer et al. 2010, eqs. 3, 5–8, 10, 11): the printed
//! equations, and the same derivations carried out for the split each layout actually uses
//! ([`bound`]), written so they stay accurate at 64 bits (no `acos` of a number within 1e-16 of
//! 1: every `arccos(c)` is rewritten as `atan` or `2·asin(sqrt((1-c)/2))` with `1-c` computed
//! without cancellation).
//!
//! The mixed-radix schemes (`radix.rs`) choose their radices `N_a`, `N_b` by these bounds: each
//! has an *objective*, a strictly increasing function of its `Δmax` computed with `+ − × ÷ √`
//! only, so that the split, which is part of the code format, is the same on every platform.

use super::fixed::snorm_spacing;
use super::onv::OnvLayout;
use super::{sc, Codec, Layout, Scheme};
use std::f64::consts::{FRAC_1_SQRT_2, PI, SQRT_2};

/// Half the step `ε/2 = 1/(N-1)` of an odd symmetric lattice of `N` points over `[-1, 1]`.
#[inline]
fn half_step(radix: f64) -> f64 {
    1.0 / (radix - 1.0)
}

/// The sample spacing `ε` of a codec in the paper's units: the step of the coarser coordinate
/// in the parameter domain (`[-1,1]` for ONV, PP, CM; `[-1/√2, 1/√2]` for SPP; for SC the larger
/// angular step divided by π, so that eq. 5 reads `Δ ≈ (√2/2)·π·ε`).
pub fn spacing(codec: &Codec) -> f64 {
    match (codec.scheme(), codec.layout()) {
        (_, Layout::Onv(l)) => snorm_spacing(l.u_bits.min(l.v_bits)),
        (Scheme::Sc, Layout::Grid(l)) => sc::theta_step(l).max(sc::phi_step(l)) / PI,
        (Scheme::Spp, Layout::Grid(l)) => SQRT_2 * half_step(l.a.min(l.b) as f64),
        (_, Layout::Grid(l)) => 2.0 * half_step(l.a.min(l.b) as f64),
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
/// the equator, `cos Δ = cos(sθ/2)·cos(sφ/2)` (eq. 5 when `sθ = sφ = πε`). With an odd `θ`
/// lattice the equator is a lattice row, so the worst input is half a `θ` step off it, decoded
/// on it: `cos Δ = cos θ1 · cos θ2 + sin θ1 · sin θ2 · cos Δφ` with `θ2 = π/2`, `θ1 = π/2 - sθ/2`.
pub fn sc(theta_step: f64, phi_step: f64) -> f64 {
    let (vx, vy) = (one_minus_cos_series(0.5 * theta_step), one_minus_cos_series(0.5 * phi_step));
    // 1 - cos a cos b = (1 - cos a) + cos a · (1 - cos b).
    acos_one_minus(vx + (1.0 - vx) * vy)
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

/// The closed-form maximum error of `codec` for the split it uses (each reduces to the printed
/// equation when the two steps are equal and, for the mixed-radix schemes, the lattice holds
/// `0`; half steps are `a = ε_a/2`, `b = ε_b/2`):
/// - ONV_domain (eq. 10): the face centre offset by half a step `(a, b)` in `(u, v)`:
///   `atan(√3·sqrt(a² + b² + (a+b)²))`;
/// - ONV_range (eq. 11): near the face centre a step `(du, dv)` subtends `√3·|(du, dv, -du-dv)|`,
///   so the cell's corners form triangles with sides `ℓu = √6·εu`, `ℓv = √6·εv` at 60°; the
///   nearest-of-four-corners error peaks at their circumradius `ℓ3/√3`,
///   `ℓ3² = ℓu² + ℓv² - ℓu·ℓv` (or at half the longer side if the triangle is obtuse):
///   `√2·ε` for equal steps;
/// - SC (eq. 5): [`sc()`] with the steps `π/(N_θ-1)` and `2π/N_φ`;
/// - PP (eq. 6): [`pp_split`];
/// - SPP (eq. 7): [`spp_split`];
/// - CM (eq. 8): [`cm_split`].
pub fn bound(codec: &Codec) -> f64 {
    match (codec.scheme(), codec.layout()) {
        (scheme, Layout::Onv(l)) => onv_split(scheme, l),
        (Scheme::Sc, Layout::Grid(l)) => sc(sc::theta_step(l), sc::phi_step(l)),
        (Scheme::Pp, Layout::Grid(l)) => pp_split(half_step(l.a as f64), half_step(l.b as f64)),
        (Scheme::Spp, Layout::Grid(l)) => {
            spp_split(FRAC_1_SQRT_2 * half_step(l.a as f64), FRAC_1_SQRT_2 * half_step(l.b as f64))
        }
        (_, Layout::Grid(l)) => cm_split(half_step(l.a as f64), half_step(l.b as f64)),
    }
}

fn onv_split(scheme: Scheme, l: OnvLayout) -> f64 {
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

/// CM for half steps `(a, b)` of the two face coordinates: `atan(sqrt(a² + b²))`.
///
/// Derivation (eq. 8): a face point `(s, t, 1)` and its lattice point `(s', t', 1)` subtend the
/// largest angle for a given offset at the face centre, where the gnomonic projection magnifies
/// most. The odd lattice holds `0`, so the worst input is the corner `(a, b)` of the centre
/// point's rounding box: the angle between `(a, b, 1)` and `(0, 0, 1)`. Eq. 8 is `a = b = ε/2`.
pub fn cm_split(a: f64, b: f64) -> f64 {
    (a * a + b * b).sqrt().atan()
}

/// SPP for half steps `(a, b)` of the two minor components (in the sphere's units).
///
/// Derivation (eq. 7): the rebuilt component `m = sqrt(1 - x² - y²)` has `|∂m/∂x| = |x|/m ≤ 1`
/// inside a sextant, with equality on the cube diagonal, where both are 1. The largest error is
/// an input on the diagonal `D = s·(1, 1, 1)`, `s = 1/√3`, rounded *outwards* to
/// `(s+a, s+b, m')`, `m' = sqrt(1/3 - 2s(a+b) - a² - b²)`: there `m` drops fastest. (The
/// printed eq. 7 is the inward case `(s-ε/2, s-ε/2)`, whose cubic term is smaller, and which
/// measured errors exceed by `~1.5ε` relative.) Chord form: `|P - D|² = a² + b² + (m' - s)²`
/// with `m' - s = -(2s(a+b) + a² + b²)/(m' + s)`, no cancellation; `Δ = 2·asin(chord/2)`.
pub fn spp_split(a: f64, b: f64) -> f64 {
    2.0 * (0.5 * spp_chord2(a, b).sqrt()).asin()
}

/// The squared chord of [`spp_split`]. If `(s+a)² + (s+b)² > 1` (coarse budgets) the lattice
/// point lies off the sphere and the decoder takes `m' = 0`, normalizing `(s+a, s+b, 0)`.
fn spp_chord2(a: f64, b: f64) -> f64 {
    let s = 1.0 / 3f64.sqrt();
    let drop = 2.0 * s * (a + b) + a * a + b * b;
    if drop <= 1.0 / 3.0 {
        let m = (1.0 / 3.0 - drop).sqrt();
        let dm = -drop / (m + s);
        a * a + b * b + dm * dm
    } else {
        let (x, y) = (s + a, s + b);
        let r = (x * x + y * y).sqrt();
        let p = [x / r - s, y / r - s, -s];
        p[0] * p[0] + p[1] * p[1] + p[2] * p[2]
    }
}

/// PP for half steps `(a, b)` of `x` and `y`: `arccos(1 - sqrt(a² + b²))`.
///
/// Derivation (eq. 6): near the equator `z = sqrt(1 - r²)` is steepest. An input on the unit
/// circle whose lattice point lies inwards by the half-cell diagonal `d = sqrt(a² + b²)` (when
/// that diagonal is radial) decodes to `r' = 1 - d`, `|z'| = sqrt(1 - r'²)`: the angle between
/// `(1, 0, 0)` and `(1 - d, 0, |z'|)` is `arccos(1 - d)`. Eq. 6 is `a = b = ε/2`.
pub fn pp_split(a: f64, b: f64) -> f64 {
    acos_one_minus((a * a + b * b).sqrt())
}

/// The split objectives of `radix::best_split` (see the module comment): for radices
/// `(N_a, N_b)` of a mixed-radix layout, a strictly increasing function of its [`bound`].
pub mod objective {
    use super::{half_step, one_minus_cos_series, spp_chord2, FRAC_1_SQRT_2, PI};

    /// CM and PP: `a² + b²` (both bounds increase with it).
    pub fn cm_pp(na: f64, nb: f64) -> f64 {
        let (a, b) = (half_step(na), half_step(nb));
        a * a + b * b
    }

    /// SPP: the squared chord of `spp_split`.
    pub fn spp(na: f64, nb: f64) -> f64 {
        spp_chord2(FRAC_1_SQRT_2 * half_step(na), FRAC_1_SQRT_2 * half_step(nb))
    }

    /// SC with `N_a = N_φ`, `N_b = N_θ`: `1 - cos(θ step/2)·cos(φ step/2)` (eq. 5's cosine).
    pub fn sc(n_phi: f64, n_theta: f64) -> f64 {
        let (x, y) = (0.5 * PI / (n_theta - 1.0), PI / n_phi);
        let (vx, vy) = (one_minus_cos_series(x), one_minus_cos_series(y));
        vx + (1.0 - vx) * vy
    }
}

/// `1 - cos x` for `|x| <= π/4` by its Taylor series `Σ (-1)^(k+1) x^(2k)/(2k)!` to `k = 10`
/// (the next term is below 1e-26): basic operations only, so it rounds identically on every
/// platform (the split search must not depend on libm), and without the cancellation of
/// `1 - cos`.
fn one_minus_cos_series(x: f64) -> f64 {
    let x2 = x * x;
    let mut term = x2 / 2.0;
    let mut sum = term;
    for k in 2..=10 {
        term *= -x2 / ((2 * k - 1) as f64 * (2 * k) as f64);
        sum += term;
    }
    sum
}

/// The smallest budget at which the closed-form bound of `scheme` is at most `target`.
pub fn bits_needed(scheme: Scheme, target: f64) -> Option<u32> {
    (super::MIN_BITS..=super::MAX_BITS).find(|&b| Codec::new(scheme, b).is_ok_and(|c| bound(&c) <= target))
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
    fn split_bounds_reduce_to_the_printed_ones_for_equal_steps() {
        // ONV at even budgets has equal steps: bound() must equal eqs. 10 and 11 exactly.
        for bits in [16, 32, 48] {
            for scheme in [Scheme::OnvDomain, Scheme::OnvRange] {
                let codec = Codec::new(scheme, bits).unwrap();
                let printed =
                    if scheme == Scheme::OnvDomain { onv_domain(spacing(&codec)) } else { onv_range(spacing(&codec)) };
                assert!(rel(bound(&codec), printed) < 1e-12);
            }
        }
        for eps in [1e-2, 1e-4, 1e-7] {
            assert!(rel(cm_split(0.5 * eps, 0.5 * eps), cm(eps)) < 1e-12);
            assert!(rel(pp_split(0.5 * eps, 0.5 * eps), pp(eps)) < 1e-12);
            // SPP: outward rounding (ours) exceeds the printed inward case by ~1.75ε relative.
            let (ours, printed) = (spp_split(0.5 * eps, 0.5 * eps), spp(eps));
            assert!(ours > printed && rel(ours, printed) < 2.0 * eps, "{eps}: {ours} {printed}");
        }
    }

    #[test]
    fn spp_bound_is_the_largest_error_near_the_diagonal() {
        // Brute force: inputs in the sextant near the cube diagonal, every offset of the rounding
        // box's corners; none exceeds spp_split, and the diagonal corner reaches it.
        let p = |x: f64, y: f64| {
            let m = (1.0 - x * x - y * y).max(0.0).sqrt();
            glam::DVec3::new(x, y, m).normalize()
        };
        for (a, b) in [(0.05, 0.05), (0.05, 0.02), (1e-3, 2e-3)] {
            let bound = spp_split(a, b);
            let s = 1.0 / 3f64.sqrt();
            let mut worst = 0f64;
            for i in 0..=200 {
                for j in 0..=200 {
                    let (x, y) = (s + a * (1.0 - i as f64 / 50.0), s + b * (1.0 - j as f64 / 50.0));
                    let m2 = 1.0 - x * x - y * y;
                    if m2 < x * x - 1e-12 || m2 < y * y - 1e-12 {
                        continue;
                    }
                    for (sa, sb) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
                        let e = crate::normals::metrics::angle_between(p(x, y), p(x + sa * a, y + sb * b));
                        worst = worst.max(e);
                        assert!(e <= bound * (1.0 + 1e-12), "{a} {b} at ({x}, {y}): {e} > {bound}");
                    }
                }
            }
            assert!(worst >= bound * (1.0 - 1e-9), "{a} {b}: {worst} < {bound}");
        }
    }

    #[test]
    fn objectives_order_the_splits_like_the_bounds() {
        // Each objective must be increasing in its bound: over many radix pairs, sorting by the
        // objective sorts the bounds.
        let pairs: Vec<(f64, f64)> =
            (0..200).map(|i| (3.0 + 2.0 * (i % 17) as f64 * 7.0, 3.0 + 2.0 * (i / 17) as f64 * 11.0)).collect();
        let check = |objective: &dyn Fn(f64, f64) -> f64, bound: &dyn Fn(f64, f64) -> f64| {
            let mut v: Vec<(f64, f64)> = pairs.iter().map(|&(a, b)| (objective(a, b), bound(a, b))).collect();
            v.sort_by(|x, y| x.0.total_cmp(&y.0));
            for w in v.windows(2) {
                assert!(w[0].1 <= w[1].1 * (1.0 + 1e-14), "{w:?}");
            }
        };
        check(&objective::cm_pp, &|a, b| cm_split(half_step(a), half_step(b)));
        check(&objective::cm_pp, &|a, b| pp_split(half_step(a), half_step(b)));
        check(&objective::spp, &|a, b| spp_split(FRAC_1_SQRT_2 * half_step(a), FRAC_1_SQRT_2 * half_step(b)));
        check(&objective::sc, &|n_phi, n_theta| sc(PI / (n_theta - 1.0), 2.0 * PI / n_phi));
    }

    #[test]
    fn cosine_series_matches_libm() {
        for i in 1..=100 {
            let x = std::f64::consts::FRAC_PI_4 * i as f64 / 100.0;
            let reference = 2.0 * (0.5 * x).sin().powi(2);
            assert!((one_minus_cos_series(x) - reference).abs() <= 1e-15 * reference, "{x}");
        }
    }

    #[test]
    fn mixed_radix_beats_the_papers_48_bit_column() {
        // Table 1, row 3: CM 2.38e-7 and SPP 2.92e-7 with fractional face bits; our mixed-radix
        // splits use log2 6 bits for the faces and must be at or under them.
        let b = |s: Scheme| bound(&Codec::new(s, 48).unwrap());
        assert!(b(Scheme::Cm) <= 2.38e-7, "{}", b(Scheme::Cm));
        assert!(b(Scheme::Spp) <= 2.92e-7, "{}", b(Scheme::Spp));
        assert!(b(Scheme::Sc) <= 3.74e-7, "{}", b(Scheme::Sc));
        // PP: the paper's ε = 2·2^-23.5 is our balanced split up to the odd radix (1e-7).
        assert!(rel(b(Scheme::Pp), pp(2.0 * (-23.5f64).exp2())) < 1e-6, "{}", b(Scheme::Pp));
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
