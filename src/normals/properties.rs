//! Property tests over every scheme and every budget 8..=64 (Meyer et al. 2010, §§4–5).

use super::metrics::angle_between;
use super::{adversarial, Codec, Scheme, MAX_BITS, MIN_BITS};
use crate::rng::SplitMix64;
use glam::DVec3;

/// The closed-form bound plus slack: `bound·(1 + slack) + 1e-15` rad. The absolute term covers
/// f64 rounding of the round trip (~1e-16 rad); the relative term covers the higher-order terms
/// the printed formulas leave out, measured with this very test (adversarial + random
/// directions, all budgets; see `docs/encode-normals.md`):
/// - ONV_domain: eq. 10 is exceeded by up to `1.0·ε²` relative (`ε = 1/7` at 8 bits: +2 %);
///   we allow `2ε²`;
/// - SPP: the split bound (`bounds::spp_split`) linearizes around the cube diagonal, which the
///   5 × 7 points per face of 8 bits are too coarse for: +6.6 % there (`0.53·ε²`), never
///   exceeded from 9 bits on; we allow `ε²`;
/// - ONV_range (eq. 11's leading term), SC, PP, CM: never exceeded; a tiny `1e-12` only.
fn allowed(codec: &Codec) -> f64 {
    codec.bound() * (1.0 + slack(codec)) + 1e-15
}

fn slack(codec: &Codec) -> f64 {
    match codec.scheme() {
        Scheme::OnvDomain => 2.0 * codec.spacing().powi(2),
        Scheme::Spp => codec.spacing().powi(2),
        _ => 1e-12,
    }
}

fn worst(codec: &Codec, dirs: &[DVec3]) -> (f64, DVec3) {
    let mut w = (0.0, DVec3::ZERO);
    for &d in dirs {
        let e = angle_between(d, codec.decode(codec.encode(d)));
        if e > w.0 {
            w = (e, d);
        }
    }
    w
}

#[test]
fn round_trip_error_within_closed_form_bound_all_schemes_all_budgets() {
    let mut state = SplitMix64::new(42);
    let random: Vec<DVec3> = (0..3000).map(|_| state.direction()).collect();
    let mut report = String::new();
    for scheme in Scheme::ALL {
        let mut worst_ratio: (f64, u32) = (0.0, 0);
        for bits in MIN_BITS..=MAX_BITS {
            let codec = Codec::new(scheme, bits).unwrap();
            let mut dirs = random.clone();
            dirs.extend(adversarial::directions(&codec));
            let (e, d) = worst(&codec, &dirs);
            let bound = codec.bound();
            assert!(e <= allowed(&codec), "{scheme} {bits} bits: error {e:e} at {d:?} exceeds bound {bound:e}");
            if e / bound > worst_ratio.0 {
                worst_ratio = (e / bound, bits);
            }
        }
        report += &format!("{scheme}: worst max/bound {:.9} at {} bits\n", worst_ratio.0, worst_ratio.1);
    }
    println!("{report}");
}

#[test]
fn adversarial_directions_reach_the_bound() {
    // The adversarial set must come close to each closed form (else the bound or the search is
    // wrong): within 0.1 % at 32 and 48 bits (PP's worst case needs a lattice point exactly on
    // the unit circle, which the lattice only approaches: 0.04 % at 32 bits).
    for bits in [32, 48] {
        for scheme in Scheme::ALL {
            let codec = Codec::new(scheme, bits).unwrap();
            let (e, _) = worst(&codec, &adversarial::directions(&codec));
            let ratio = e / codec.bound();
            let floor = if scheme == Scheme::Pp { 0.999 } else { 0.9999 };
            assert!(ratio >= floor && ratio <= 1.0 + slack(&codec) + 1e-9, "{scheme} {bits}: ratio {ratio}");
        }
    }
}

#[test]
fn range_rounding_never_worse_than_domain_rounding() {
    let mut state = SplitMix64::new(5);
    for bits in MIN_BITS..=MAX_BITS {
        let range = Codec::new(Scheme::OnvRange, bits).unwrap();
        let domain = Codec::new(Scheme::OnvDomain, bits).unwrap();
        let mut dirs: Vec<DVec3> = (0..2000).map(|_| state.direction()).collect();
        dirs.extend(adversarial::directions(&domain));
        for d in dirs {
            let er = angle_between(d, range.decode(range.encode(d)));
            let ed = angle_between(d, domain.decode(domain.encode(d)));
            // Tied candidates may differ in the last ulps of the decoded vectors (~1e-16).
            assert!(er <= ed + 1e-15, "{bits} bits at {d:?}: range {er:e} > domain {ed:e}");
        }
    }
}

#[test]
fn every_code_decodes_to_a_unit_vector() {
    let mut state = SplitMix64::new(9);
    for scheme in Scheme::ALL {
        for bits in MIN_BITS..=MAX_BITS {
            let codec = Codec::new(scheme, bits).unwrap();
            let mut codes: Vec<u64> = (0..500).map(|_| state.next_u64()).collect();
            // Extremes of every field: all zeros, all ones, each field at its min/max.
            codes.extend([0, u64::MAX, 1, 2, 3, 4, 5, 6, 7]);
            // Every digit at 0, its middle and its largest value, the others at 0 or largest,
            // and the first codes past the last valid one.
            let digits = codec.digits();
            let mut place = 1u128;
            for d in &digits {
                for v in [0, d.radix / 2, d.radix - 1] {
                    let rest_max = (1u128 << bits) / (place * d.radix as u128);
                    codes.push((v as u128 * place) as u64);
                    codes.push(
                        (v as u128 * place + (place - 1) + (rest_max.saturating_sub(1) * place * d.radix as u128))
                            as u64,
                    );
                }
                place *= d.radix as u128;
            }
            codes.extend([place as u64, (place as u64).wrapping_add(1), u64::MAX >> (64 - bits)]);
            for c in codes {
                let n = codec.decode(c);
                assert!(n.is_finite(), "{scheme} {bits}: code {c:#x} -> {n:?}");
                assert!((n.length() - 1.0).abs() <= 4e-16, "{scheme} {bits}: code {c:#x} -> |n| = {}", n.length());
            }
        }
    }
}

#[test]
fn axes_decode_exactly_and_signed_zeros_do_not_matter() {
    for scheme in Scheme::ALL {
        for bits in MIN_BITS..=MAX_BITS {
            let codec = Codec::new(scheme, bits).unwrap();
            for axis in 0..3 {
                for sign in [1.0, -1.0] {
                    let mut n = DVec3::ZERO;
                    n[axis] = sign;
                    let code = codec.encode(n);
                    assert_eq!(codec.decode(code), n, "{scheme} {bits}: axis {n:?}");
                    // Every combination of signed zeros in the other components: same code.
                    for mask in 0..4 {
                        let mut m = n;
                        let others = [(axis + 1) % 3, (axis + 2) % 3];
                        for (k, &o) in others.iter().enumerate() {
                            if mask & (1 << k) != 0 {
                                m[o] = -0.0;
                            }
                        }
                        assert_eq!(codec.encode(m), code, "{scheme} {bits}: {m:?}");
                    }
                }
            }
        }
    }
}

#[test]
fn diagonals_are_mirror_symmetric() {
    let s = 1.0 / 3f64.sqrt();
    for scheme in Scheme::ALL {
        for bits in MIN_BITS..=MAX_BITS {
            let codec = Codec::new(scheme, bits).unwrap();
            let errors: Vec<f64> = (0..8)
                .map(|k| {
                    let d = DVec3::new(
                        if k & 1 == 0 { s } else { -s },
                        if k & 2 == 0 { s } else { -s },
                        if k & 4 == 0 { s } else { -s },
                    );
                    angle_between(d, codec.decode(codec.encode(d)))
                })
                .collect();
            for e in &errors {
                assert!((e - errors[0]).abs() <= 1e-15, "{scheme} {bits}: {errors:?}");
                assert!(*e <= allowed(&codec));
            }
        }
    }
}

#[test]
fn octahedron_fold_is_handled() {
    // Directions on the equator (z = ±0) lie on the fold |u|+|v| = 1: both signs of zero give the
    // same code, and neighbours just above/below the fold round to neighbouring codes.
    let mut state = SplitMix64::new(77);
    for bits in [8, 16, 24, 32, 33, 48, 64] {
        for scheme in [Scheme::OnvRange, Scheme::OnvDomain] {
            let codec = Codec::new(scheme, bits).unwrap();
            for _ in 0..2000 {
                let phi = std::f64::consts::TAU * state.next_f64();
                let (y, x) = phi.sin_cos();
                assert_eq!(codec.encode(DVec3::new(x, y, 0.0)), codec.encode(DVec3::new(x, y, -0.0)));
                let tiny = 1e-12;
                let up = DVec3::new(x, y, tiny).normalize();
                let down = DVec3::new(x, y, -tiny).normalize();
                let (eu, ed) = (
                    angle_between(up, codec.decode(codec.encode(up))),
                    angle_between(down, codec.decode(codec.encode(down))),
                );
                assert!(eu <= allowed(&codec) && ed <= allowed(&codec), "{bits}: fold at φ={phi}");
            }
        }
    }
}

#[test]
fn f32_block_encoder_gives_the_scalar_codes() {
    let mut state = SplitMix64::new(8);
    let mut normals: Vec<[f32; 3]> = (0..20_000).map(|_| state.direction().as_vec3().to_array()).collect();
    normals.extend([[0.0, 0.0, -1.0], [-0.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.5, -0.5, 0.0], [-0.0, -0.0, -1.0]]);
    for scheme in [Scheme::OnvDomain, Scheme::OnvRange] {
        for bits in [8, 15, 16, 32, 47, 64] {
            let codec = Codec::new(scheme, bits).unwrap();
            let mut codes = vec![0; normals.len()];
            codec.encode_all_f32(&normals, &mut codes);
            for (n, c) in normals.iter().zip(&codes) {
                assert_eq!(codec.encode(DVec3::from(n.map(f64::from))), *c, "{scheme} {bits} {n:?}");
            }
        }
    }
}

#[test]
fn f32_block_decoder_gives_the_scalar_normals() {
    // The batch decoder may run with other SIMD widths (AVX2 dispatch): bit-identical results.
    let mut state = SplitMix64::new(4);
    for bits in [8, 15, 16, 24, 31, 32] {
        let codec = Codec::new(Scheme::OnvRange, bits).unwrap();
        let layout = super::onv::OnvLayout::new(bits);
        let codes: Vec<u64> = (0..10_007).map(|_| state.next_u64() & super::fixed::mask(bits)).collect();
        let mut normals = vec![[0f32; 3]; codes.len()];
        codec.decode_all_f32(&codes, &mut normals);
        for (c, n) in codes.iter().zip(&normals) {
            assert_eq!(super::onv::decode_f32(*c, layout).map(f32::to_bits), n.map(f32::to_bits), "{bits} {c:#x}");
        }
    }
}

#[test]
fn batch_encode_is_independent_of_chunking() {
    let mut state = SplitMix64::new(1);
    let dirs: Vec<DVec3> = (0..50_000).map(|_| state.direction()).collect();
    let codec = Codec::new(Scheme::OnvRange, 32).unwrap();
    let mut codes = vec![0; dirs.len()];
    codec.encode_all(&dirs, &mut codes);
    for (d, c) in dirs.iter().zip(&codes) {
        assert_eq!(codec.encode(*d), *c);
    }
}

#[test]
fn choosing_range_candidates_by_f32_dot_product_breaks_where_ours_does_not() {
    // The trap the issue names: picking the corner with the largest f32 dot product. From ~24
    // bits the four cosines round to the same f32, the pick becomes arbitrary and the error
    // exceeds eq. 11 (measured: 1.13x the bound at 24 bits, 3.0x at 32 and 48); our f64 sin²
    // comparison stays within it.
    use super::fixed::{snorm_floor, snorm_value};
    use super::onv::{dir_from_oct, oct_from_dir, OnvLayout};
    for bits in [24u32, 32, 48] {
        let layout = OnvLayout::new(bits);
        let codec = Codec::new(Scheme::OnvRange, bits).unwrap();
        let mut dirs = adversarial::directions(&codec);
        let mut state = SplitMix64::new(21);
        dirs.extend((0..20_000).map(|_| state.direction()));
        let (mut naive, mut ours) = (0f64, 0f64);
        for n in dirs {
            let p = oct_from_dir(n);
            let (u0, v0) = (snorm_floor(p[0], layout.u_bits), snorm_floor(p[1], layout.v_bits));
            let nf = n.as_vec3();
            let mut best = (f32::NEG_INFINITY, DVec3::ZERO);
            for (su, sv) in [(u0, v0), (u0 + 1, v0), (u0, v0 + 1), (u0 + 1, v0 + 1)] {
                let q = dir_from_oct([snorm_value(su, layout.u_bits), snorm_value(sv, layout.v_bits)]);
                let d = nf.dot(q.as_vec3());
                if d > best.0 {
                    best = (d, q);
                }
            }
            naive = naive.max(angle_between(n, best.1));
            ours = ours.max(angle_between(n, codec.decode(codec.encode(n))));
        }
        let bound = codec.bound();
        assert!(ours <= allowed(&codec), "{bits}: ours {ours:e}");
        println!("{bits}: naive {:.3} x bound, ours {:.6} x bound", naive / bound, ours / bound);
        assert!(naive > 1.05 * bound, "{bits}: f32 dot products stayed within the bound ({naive:e} vs {bound:e})");
    }
}

#[test]
fn splits_are_the_documented_code_format() {
    // The radices are part of the file format (docs/formats/normal-codes.md lists these): a
    // change to the split search must show up here, not silently in users' files.
    let radices = |scheme, bits| -> Vec<u64> {
        Codec::new(scheme, bits).unwrap().digits().iter().rev().map(|d| d.radix).collect()
    };
    for (scheme, expected) in [
        (Scheme::Sc, [[360, 181], [92680, 46341], [23721256, 11865939]]),
        (Scheme::Pp, [[181, 181], [46271, 46411], [11863283, 11863283]]),
        (Scheme::Spp, [[103, 105], [26707, 26803], [6847421, 6851119]]),
        (Scheme::Cm, [[103, 105], [26707, 26803], [6847421, 6851119]]),
    ] {
        for (bits, want) in [16, 32, 48].into_iter().zip(expected) {
            let got = radices(scheme, bits);
            // Most significant first: faces (PP: 2, SPP/CM: 6; SC has none), then a, then b.
            assert_eq!(&got[got.len() - 2..], &want, "{scheme} {bits}");
        }
    }
    assert_eq!(radices(Scheme::OnvRange, 48), vec![1 << 24, 1 << 24]);
}
