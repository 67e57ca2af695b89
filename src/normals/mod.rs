//! Compact normal vectors: the sphere parameterizations compared by Meyer et al. 2010 ("On
//! Floating-Point Normal Vectors"), each at any bit budget from 8 to 64, with their closed-form
//! error bounds, the analysis of floating-point normals (FPNV), error metrics, bit packing and
//! shader decoders.
//!
//! | scheme | module | rounding | bound |
//! | --- | --- | --- | --- |
//! | `onv-range` | [`onv`] | best of 4 cell corners on the sphere | eq. 11 |
//! | `onv-domain` | [`onv`] | nearest in `[u, v]` | eq. 10 |
//! | `sc` | [`sc`] | nearest in `(θ, φ)` | eq. 5 |
//! | `pp` | [`pp`] | nearest in `(x, y)` + sign of z | eq. 6 |
//! | `spp` | [`spp`] | nearest minor components + 3 face bits | eq. 7 |
//! | `cm` | [`cm`] | nearest face coordinates + 3 face bits | eq. 8 |
//!
//! Every code of `bits` bits (higher bits ignored) decodes to a unit vector. Bit layouts are in
//! each module and in `docs/formats/normal-codes.md`.

pub mod adversarial;
pub mod bounds;
pub mod cm;
pub mod fixed;
pub mod fpnv;
pub mod metrics;
pub mod onv;
pub mod pack;
pub mod pp;
#[cfg(test)]
mod properties;
pub mod rng;
pub mod sc;
pub mod sextant;
pub mod shader;
pub mod sources;
pub mod spp;
pub mod table;
pub mod vec;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
pub use vec::Dir;

/// Smallest supported budget.
pub const MIN_BITS: u32 = 8;
/// Largest supported budget.
pub const MAX_BITS: u32 = 64;

/// A sphere parameterization with its rounding rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Scheme {
    /// Octahedron normal vectors, rounded in the range (best of four corners, §5).
    OnvRange,
    /// Octahedron normal vectors, rounded in the parameter domain.
    OnvDomain,
    /// Spherical coordinates.
    Sc,
    /// Parallel projection with a sign bit.
    Pp,
    /// Sextant parallel projection.
    Spp,
    /// Cube map.
    Cm,
}

impl Scheme {
    /// Every scheme, in the order of the paper's Table 1 (best first for ONV).
    pub const ALL: [Scheme; 6] = [Scheme::OnvRange, Scheme::OnvDomain, Scheme::Sc, Scheme::Pp, Scheme::Spp, Scheme::Cm];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::OnvRange => "onv-range",
            Scheme::OnvDomain => "onv-domain",
            Scheme::Sc => "sc",
            Scheme::Pp => "pp",
            Scheme::Spp => "spp",
            Scheme::Cm => "cm",
        }
    }
}

impl std::fmt::Display for Scheme {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Scheme {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Scheme::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown scheme {s:?} (expected one of onv-range, onv-domain, sc, pp, spp, cm)"))
    }
}

/// Errors of the normal-vector library.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum NormalsError {
    /// The bit budget is outside 8..=64.
    #[error("bit budget {0} is outside {MIN_BITS}..={MAX_BITS}")]
    Bits(u32),
    /// A normal that cannot be encoded: zero length, NaN or infinite.
    #[error("normal #{index} is {what}: ({x}, {y}, {z})")]
    Invalid {
        /// Index of the first offending normal.
        index: usize,
        /// "zero-length", "NaN" or "infinite".
        what: &'static str,
        /// Components as read.
        x: f32,
        /// Components as read.
        y: f32,
        /// Components as read.
        z: f32,
    },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layout {
    Onv(onv::OnvLayout),
    Sc(sc::ScLayout),
    Pp(pp::PpLayout),
    Face(sextant::FaceLayout),
}

/// A scheme at a bit budget: encodes unit directions to codes and decodes any code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Codec {
    scheme: Scheme,
    bits: u32,
    layout: Layout,
}

impl Codec {
    /// `scheme` at `bits` bits (8..=64).
    pub fn new(scheme: Scheme, bits: u32) -> Result<Codec, NormalsError> {
        if !(MIN_BITS..=MAX_BITS).contains(&bits) {
            return Err(NormalsError::Bits(bits));
        }
        let layout = match scheme {
            Scheme::OnvRange | Scheme::OnvDomain => Layout::Onv(onv::OnvLayout::new(bits)),
            Scheme::Sc => Layout::Sc(sc::ScLayout::new(bits)),
            Scheme::Pp => Layout::Pp(pp::PpLayout::new(bits)),
            Scheme::Spp | Scheme::Cm => Layout::Face(sextant::FaceLayout::new(bits)),
        };
        Ok(Codec { scheme, bits, layout })
    }

    /// The scheme.
    pub fn scheme(&self) -> Scheme {
        self.scheme
    }

    /// The budget in bits.
    pub fn bits(&self) -> u32 {
        self.bits
    }

    /// The named bit fields of a code, lowest first: `(name, offset, width, kind)`.
    pub fn fields(&self) -> Vec<Field> {
        let f = |name: &str, offset: u32, width: u32, kind: FieldKind| Field {
            name: name.to_string(),
            offset,
            width,
            kind,
        };
        match self.layout {
            Layout::Onv(l) => {
                vec![f("u", 0, l.u_bits, FieldKind::Snorm), f("v", l.u_bits, l.v_bits, FieldKind::Snorm)]
            }
            Layout::Sc(l) => vec![
                f("theta", 0, l.theta_bits, FieldKind::Snorm),
                f("phi", l.theta_bits, l.phi_bits, FieldKind::Unsigned),
            ],
            Layout::Pp(l) => vec![
                f("z_negative", 0, 1, FieldKind::Unsigned),
                f("x", 1, l.x_bits, FieldKind::Snorm),
                f("y", 1 + l.x_bits, l.y_bits, FieldKind::Snorm),
            ],
            Layout::Face(l) => vec![
                f("face", 0, 3, FieldKind::Unsigned),
                f("a", 3, l.a_bits, FieldKind::Snorm),
                f("b", 3 + l.a_bits, l.b_bits, FieldKind::Snorm),
            ],
        }
    }

    /// Encodes a unit direction (callers normalize first; see [`prepare`]).
    #[inline]
    pub fn encode(&self, n: Dir) -> u64 {
        match (self.scheme, self.layout) {
            (Scheme::OnvRange, Layout::Onv(l)) => onv::encode_range(n, l),
            (_, Layout::Onv(l)) => onv::encode_domain(n, l),
            (_, Layout::Sc(l)) => sc::encode(n, l),
            (_, Layout::Pp(l)) => pp::encode(n, l),
            (Scheme::Spp, Layout::Face(l)) => spp::encode(n, l),
            (_, Layout::Face(l)) => cm::encode(n, l),
        }
    }

    /// Decodes the low `bits` bits of `code` to a unit direction (total: every code decodes).
    #[inline]
    pub fn decode(&self, code: u64) -> Dir {
        let code = code & fixed::mask(self.bits);
        match self.layout {
            Layout::Onv(l) => onv::decode(code, l),
            Layout::Sc(l) => sc::decode(code, l),
            Layout::Pp(l) => pp::decode(code, l),
            Layout::Face(l) if self.scheme == Scheme::Spp => spp::decode(code, l),
            Layout::Face(l) => cm::decode(code, l),
        }
    }

    /// Encodes a batch in parallel (order preserved; identical for any thread count).
    pub fn encode_all(&self, normals: &[Dir], codes: &mut [u64]) {
        normals.par_chunks(1 << 14).zip(codes.par_chunks_mut(1 << 14)).for_each(|(n, c)| {
            for (n, c) in n.iter().zip(c.iter_mut()) {
                *c = self.encode(*n);
            }
        });
    }

    /// Encodes f32 normals (nonzero and finite; ONV needs no normalization, the other schemes
    /// expect unit length), in parallel. ONV takes the vectorized block path with identical codes.
    pub fn encode_all_f32(&self, normals: &[[f32; 3]], codes: &mut [u64]) {
        if let Layout::Onv(l) = self.layout {
            let range = self.scheme == Scheme::OnvRange;
            normals.par_chunks(1 << 14).zip(codes.par_chunks_mut(1 << 14)).for_each(|(n, c)| {
                onv::encode_block_f32(n, c, l, range);
            });
            return;
        }
        normals.par_chunks(1 << 14).zip(codes.par_chunks_mut(1 << 14)).for_each(|(n, c)| {
            for (n, c) in n.iter().zip(c.iter_mut()) {
                *c = self.encode([n[0] as f64, n[1] as f64, n[2] as f64]);
            }
        });
    }

    /// Decodes a batch in parallel.
    pub fn decode_all(&self, codes: &[u64], normals: &mut [Dir]) {
        codes.par_chunks(1 << 14).zip(normals.par_chunks_mut(1 << 14)).for_each(|(c, n)| {
            for (c, n) in c.iter().zip(n.iter_mut()) {
                *n = self.decode(*c);
            }
        });
    }

    /// Decodes a batch to f32 normals in parallel. ONV codes of at most 32 bits take the
    /// branch-free f32 path ([`onv::decode_f32`], within 3e-7 rad of the f64 decoder).
    pub fn decode_all_f32(&self, codes: &[u64], normals: &mut [[f32; 3]]) {
        if let (Layout::Onv(l), true) = (self.layout, self.bits <= 32) {
            codes.par_chunks(1 << 14).zip(normals.par_chunks_mut(1 << 14)).for_each(|(c, n)| {
                // Blocks of 64 in structure-of-arrays form so the arithmetic vectorizes; the
                // interleaving into xyz is a separate pass.
                for (c, n) in c.chunks(64).zip(n.chunks_mut(64)) {
                    let mut block = [[0f32; 64]; 3];
                    for (i, &code) in c.iter().enumerate() {
                        let d = onv::decode_f32(code, l);
                        block[0][i] = d[0];
                        block[1][i] = d[1];
                        block[2][i] = d[2];
                    }
                    for (i, n) in n.iter_mut().enumerate() {
                        *n = [block[0][i], block[1][i], block[2][i]];
                    }
                }
            });
            return;
        }
        codes.par_chunks(1 << 14).zip(normals.par_chunks_mut(1 << 14)).for_each(|(c, n)| {
            for (c, n) in c.iter().zip(n.iter_mut()) {
                let d = self.decode(*c);
                *n = [d[0] as f32, d[1] as f32, d[2] as f32];
            }
        });
    }
}

/// How a field's integer is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FieldKind {
    /// Two's complement, value `max(s/(2^(k-1)-1), -1)`.
    Snorm,
    /// Plain unsigned integer.
    Unsigned,
}

/// One bit field of a code.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Field {
    /// Field name (`u`, `v`, `theta`, `phi`, `face`, …).
    pub name: String,
    /// Offset of the lowest bit.
    pub offset: u32,
    /// Width in bits.
    pub width: u32,
    /// How the integer is read.
    pub kind: FieldKind,
}

/// What to do with a zero-length, NaN or infinite input normal.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum InvalidPolicy {
    /// Fail, naming the first offending index.
    Error,
    /// Replace by +Z (0, 0, 1) and count it.
    Replace,
}

/// Checks and normalizes input normals (f32 as read) to unit f64 directions. Returns the
/// directions and the indices that were replaced under [`InvalidPolicy::Replace`].
pub fn prepare(raw: &[[f32; 3]], policy: InvalidPolicy) -> Result<(Vec<Dir>, Vec<usize>), NormalsError> {
    let mut out = Vec::with_capacity(raw.len());
    let mut replaced = Vec::new();
    for (index, &[x, y, z]) in raw.iter().enumerate() {
        let what = if x.is_nan() || y.is_nan() || z.is_nan() {
            Some("NaN")
        } else if x.is_infinite() || y.is_infinite() || z.is_infinite() {
            Some("infinite")
        } else if x == 0.0 && y == 0.0 && z == 0.0 {
            Some("zero-length")
        } else {
            None
        };
        match (what, policy) {
            (None, _) => {
                // Scale first so that tiny or huge f32 vectors do not under/overflow in f64.
                let d = [x as f64, y as f64, z as f64];
                let m = d[0].abs().max(d[1].abs()).max(d[2].abs());
                out.push(vec::normalize([d[0] / m, d[1] / m, d[2] / m]));
            }
            (Some(what), InvalidPolicy::Error) => return Err(NormalsError::Invalid { index, what, x, y, z }),
            (Some(_), InvalidPolicy::Replace) => {
                replaced.push(index);
                out.push([0.0, 0.0, 1.0]);
            }
        }
    }
    Ok((out, replaced))
}
