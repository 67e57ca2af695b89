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
//! | `spp` | [`spp`] | nearest minor components + face digit | eq. 7 |
//! | `cm` | [`cm`] | nearest face coordinates + face digit | eq. 8 |
//!
//! ONV codes are two SNORM bit fields; the other schemes are mixed-radix numbers ([`radix`])
//! that use the whole budget (6 faces cost log2 6 bits, not 3). Every code of `bits` bits (higher
//! bits ignored) decodes to a unit vector. Layouts are in each module and in
//! `docs/formats/normal-codes.md`.
//!
//! The `encode-normals` stage is one library call per mode: [`encode::run`] (normals → codes,
//! decoded normals and the [`report`] document), [`decode::run`] and [`table::run`] (Meyer et
//! al.'s Table 1); `shader::decoder` prints the matching GLSL/HLSL/WGSL.

pub mod adversarial;
pub mod bounds;
pub mod cm;
pub mod decode;
pub mod encode;
pub mod fixed;
pub mod fpnv;
pub mod metrics;
pub mod onv;
pub mod pack;
pub mod pp;
#[cfg(test)]
mod properties;
pub mod radix;
pub mod report;
pub mod sc;
pub mod sextant;
pub mod shader;
pub mod sources;
pub mod spp;
pub mod table;

use glam::DVec3;
use radix::GridLayout;
pub use radix::{Digit, DigitKind};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

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
    /// Nothing to encode or decode.
    #[error("no {0}")]
    Empty(&'static str),
    /// A code file in the word layout whose length is not a whole number of words.
    #[error(
        "length {len} is not a multiple of the {word_bytes}-byte word of a {bits}-bit code (a bit-packed stream?)"
    )]
    StreamLength {
        /// Length in bytes.
        len: usize,
        /// Bytes per word.
        word_bytes: usize,
        /// Bits per code.
        bits: u32,
    },
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

/// How a codec's integers are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Layout {
    /// Two SNORM bit fields (ONV).
    Onv(onv::OnvLayout),
    /// A mixed-radix number (SC, PP, SPP, CM).
    Grid(GridLayout),
}

/// A scheme at a bit budget: encodes unit directions to codes and decodes any code.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Codec {
    scheme: Scheme,
    bits: u32,
    layout: Layout,
}

/// The mixed-radix splits, searched once per scheme and budget (`radix::best_split`).
fn grid_layout(scheme: Scheme, bits: u32) -> GridLayout {
    const BUDGETS: usize = (MAX_BITS - MIN_BITS + 1) as usize;
    static SPLITS: [[OnceLock<GridLayout>; BUDGETS]; 4] = [const { [const { OnceLock::new() }; BUDGETS] }; 4];
    let (row, search): (usize, fn(u32) -> GridLayout) = match scheme {
        Scheme::Sc => (0, sc::layout),
        Scheme::Pp => (1, pp::layout),
        Scheme::Spp => (2, spp::layout),
        _ => (3, cm::layout),
    };
    *SPLITS[row][(bits - MIN_BITS) as usize].get_or_init(|| search(bits))
}

impl Codec {
    /// `scheme` at `bits` bits (8..=64).
    pub fn new(scheme: Scheme, bits: u32) -> Result<Codec, NormalsError> {
        if !(MIN_BITS..=MAX_BITS).contains(&bits) {
            return Err(NormalsError::Bits(bits));
        }
        let layout = match scheme {
            Scheme::OnvRange | Scheme::OnvDomain => Layout::Onv(onv::OnvLayout::new(bits)),
            _ => Layout::Grid(grid_layout(scheme, bits)),
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

    pub(crate) fn layout(&self) -> Layout {
        self.layout
    }

    /// The closed-form maximum angular error for this split (radians, [`bounds::bound`]).
    pub fn bound(&self) -> f64 {
        bounds::bound(self)
    }

    /// The sample spacing `ε` in the paper's units ([`bounds::spacing`]).
    pub fn spacing(&self) -> f64 {
        bounds::spacing(self)
    }

    /// The digits of a code, lowest first: `code = Σ d_i · Π_{j<i} N_j` (`radix.rs`). For ONV
    /// the radices are powers of two, i.e. bit fields.
    pub fn digits(&self) -> Vec<Digit> {
        let d = |name: &str, radix: u64, kind: DigitKind| Digit { name: name.to_string(), radix, kind };
        match (self.scheme, self.layout) {
            (_, Layout::Onv(l)) => {
                vec![d("u", 1 << l.u_bits, DigitKind::Snorm), d("v", 1 << l.v_bits, DigitKind::Snorm)]
            }
            (Scheme::Sc, Layout::Grid(l)) => {
                vec![d("theta", l.b, DigitKind::Symmetric), d("phi", l.a, DigitKind::Turns)]
            }
            (Scheme::Pp, Layout::Grid(l)) => vec![
                d("y", l.b, DigitKind::Symmetric),
                d("x", l.a, DigitKind::Symmetric),
                d("z_negative", l.faces, DigitKind::Index),
            ],
            (_, Layout::Grid(l)) => vec![
                d("b", l.b, DigitKind::Symmetric),
                d("a", l.a, DigitKind::Symmetric),
                d("face", l.faces, DigitKind::Index),
            ],
        }
    }

    /// The split in words, most significant digit first, with each digit's share of the budget
    /// in bits: `v:2^24 u:2^24 = 24+24 bits`, or for mixed radix
    /// `face:6 a:6843017 b:6843011 = 2.585+22.706+22.706 bits`.
    pub fn split_text(&self) -> String {
        let digits: Vec<Digit> = self.digits().into_iter().rev().collect();
        let radix =
            |r: u64| if r.is_power_of_two() && r >= 256 { format!("2^{}", r.trailing_zeros()) } else { r.to_string() };
        let bits = |r: u64| {
            if r.is_power_of_two() {
                r.trailing_zeros().to_string()
            } else {
                format!("{:.3}", (r as f64).log2())
            }
        };
        let names: Vec<String> = digits.iter().map(|d| format!("{}:{}", d.name, radix(d.radix))).collect();
        let shares: Vec<String> = digits.iter().map(|d| bits(d.radix)).collect();
        format!("{} = {} bits", names.join(" "), shares.join("+"))
    }

    /// Encodes a unit direction (callers normalize first; see [`prepare`]).
    #[inline]
    pub fn encode(&self, n: DVec3) -> u64 {
        match (self.scheme, self.layout) {
            (Scheme::OnvRange, Layout::Onv(l)) => onv::encode_range(n, l),
            (_, Layout::Onv(l)) => onv::encode_domain(n, l),
            (Scheme::Sc, Layout::Grid(l)) => sc::encode(n, l),
            (Scheme::Pp, Layout::Grid(l)) => pp::encode(n, l),
            (Scheme::Spp, Layout::Grid(l)) => spp::encode(n, l),
            (_, Layout::Grid(l)) => cm::encode(n, l),
        }
    }

    /// Decodes the low `bits` bits of `code` to a unit direction (total: every code decodes).
    #[inline]
    pub fn decode(&self, code: u64) -> DVec3 {
        let code = code & fixed::mask(self.bits);
        match (self.scheme, self.layout) {
            (_, Layout::Onv(l)) => onv::decode(code, l),
            (Scheme::Sc, Layout::Grid(l)) => sc::decode(code, l),
            (Scheme::Pp, Layout::Grid(l)) => pp::decode(code, l),
            (Scheme::Spp, Layout::Grid(l)) => spp::decode(code, l),
            (_, Layout::Grid(l)) => cm::decode(code, l),
        }
    }

    /// Encodes a batch in parallel (order preserved; identical for any thread count).
    pub fn encode_all(&self, normals: &[DVec3], codes: &mut [u64]) {
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
                onv::encode_batch_f32(n, c, l, range);
            });
            return;
        }
        normals.par_chunks(1 << 14).zip(codes.par_chunks_mut(1 << 14)).for_each(|(n, c)| {
            for (n, c) in n.iter().zip(c.iter_mut()) {
                *c = self.encode(DVec3::from(n.map(f64::from)));
            }
        });
    }

    /// Decodes a batch in parallel.
    pub fn decode_all(&self, codes: &[u64], normals: &mut [DVec3]) {
        codes.par_chunks(1 << 14).zip(normals.par_chunks_mut(1 << 14)).for_each(|(c, n)| {
            for (c, n) in c.iter().zip(n.iter_mut()) {
                *n = self.decode(*c);
            }
        });
    }

    /// Decodes a batch to f32 normals in parallel. ONV codes of at most 32 bits take the
    /// vectorized branch-free f32 path ([`onv::decode_f32`], within 3e-7 rad of the f64 decoder).
    pub fn decode_all_f32(&self, codes: &[u64], normals: &mut [[f32; 3]]) {
        if let (Layout::Onv(l), true) = (self.layout, self.bits <= 32) {
            codes.par_chunks(1 << 14).zip(normals.par_chunks_mut(1 << 14)).for_each(|(c, n)| {
                onv::decode_batch_f32(c, n, l);
            });
            return;
        }
        codes.par_chunks(1 << 14).zip(normals.par_chunks_mut(1 << 14)).for_each(|(c, n)| {
            for (c, n) in c.iter().zip(n.iter_mut()) {
                *n = self.decode(*c).as_vec3().to_array();
            }
        });
    }
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

impl std::str::FromStr for InvalidPolicy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "error" => Ok(InvalidPolicy::Error),
            "replace" => Ok(InvalidPolicy::Replace),
            _ => Err(format!("expected error or replace, got {s:?}")),
        }
    }
}

/// Checks and normalizes input normals (f32 as read) to unit f64 directions. Returns the
/// directions and the indices that were replaced under [`InvalidPolicy::Replace`].
pub fn prepare(raw: &[[f32; 3]], policy: InvalidPolicy) -> Result<(Vec<DVec3>, Vec<usize>), NormalsError> {
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
                let d = DVec3::new(x.into(), y.into(), z.into());
                out.push((d / d.abs().max_element()).normalize());
            }
            (Some(what), InvalidPolicy::Error) => return Err(NormalsError::Invalid { index, what, x, y, z }),
            (Some(_), InvalidPolicy::Replace) => {
                replaced.push(index);
                out.push(DVec3::Z);
            }
        }
    }
    Ok((out, replaced))
}
