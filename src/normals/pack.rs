//! Code streams (`docs/formats/normal-codes.md`).
//!
//! - **words**: one little-endian word per normal, the smallest of u16/u32/u64 that holds `b`
//!   bits; unused high bits are zero.
//! - **packed**: a little-endian bit stream: normal `i` occupies stream bits `[i·b, (i+1)·b)`,
//!   lowest code bit first, where stream bit `j` is bit `j mod 8` of byte `⌊j/8⌋`. The last byte
//!   is zero-padded, so the count is `⌊8·len/b⌋` (padding is under 8 ≤ b bits).

use super::fixed::mask;
use super::NormalsError;
use serde::{Deserialize, Serialize};

/// How codes are laid out in a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stream {
    /// One little-endian u16/u32/u64 word per code ([`word_bytes`]).
    Words,
    /// A little-endian bit stream, `bits` per code.
    Packed,
}

impl Stream {
    /// The bytes of `codes` of `bits` bits.
    pub fn to_bytes(self, codes: &[u64], bits: u32) -> Vec<u8> {
        match self {
            Stream::Words => to_words(codes, bits),
            Stream::Packed => to_packed(codes, bits),
        }
    }

    /// The codes in `bytes`: every whole code of a bit stream, or every word (the length must
    /// be a multiple of the word size).
    pub fn from_bytes(self, bytes: &[u8], bits: u32) -> Result<Vec<u64>, NormalsError> {
        match self {
            Stream::Words => from_words(bytes, bits).ok_or(NormalsError::StreamLength {
                len: bytes.len(),
                word_bytes: word_bytes(bits),
                bits,
            }),
            Stream::Packed => Ok(from_packed(bytes, bits)),
        }
    }
}

/// Bytes per code in the word layout.
pub fn word_bytes(bits: u32) -> usize {
    match bits {
        0..=16 => 2,
        17..=32 => 4,
        _ => 8,
    }
}

/// Writes codes one word each.
pub fn to_words(codes: &[u64], bits: u32) -> Vec<u8> {
    let w = word_bytes(bits);
    let mut out = Vec::with_capacity(codes.len() * w);
    for &c in codes {
        out.extend_from_slice(&(c & mask(bits)).to_le_bytes()[..w]);
    }
    out
}

/// Reads codes one word each; `None` if the length is not a multiple of the word size.
pub fn from_words(bytes: &[u8], bits: u32) -> Option<Vec<u64>> {
    let w = word_bytes(bits);
    if bytes.len() % w != 0 {
        return None;
    }
    Some(
        bytes
            .chunks_exact(w)
            .map(|c| {
                let mut b = [0u8; 8];
                b[..w].copy_from_slice(c);
                u64::from_le_bytes(b) & mask(bits)
            })
            .collect(),
    )
}

/// Writes codes as a bit stream.
pub fn to_packed(codes: &[u64], bits: u32) -> Vec<u8> {
    let total_bits = codes.len() * bits as usize;
    let mut out = vec![0u8; total_bits.div_ceil(8)];
    let mut acc: u128 = 0;
    let mut filled = 0u32;
    let mut pos = 0usize;
    for &c in codes {
        acc |= ((c & mask(bits)) as u128) << filled;
        filled += bits;
        while filled >= 8 {
            out[pos] = acc as u8;
            pos += 1;
            acc >>= 8;
            filled -= 8;
        }
    }
    if filled > 0 {
        out[pos] = acc as u8;
    }
    out
}

/// Reads a bit stream of `⌊8·len/bits⌋` codes.
pub fn from_packed(bytes: &[u8], bits: u32) -> Vec<u64> {
    let count = bytes.len() * 8 / bits as usize;
    let mut out = Vec::with_capacity(count);
    let mut acc: u128 = 0;
    let mut filled = 0u32;
    let mut bytes = bytes.iter();
    for _ in 0..count {
        while filled < bits {
            // count guarantees enough bytes remain.
            acc |= (*bytes.next().unwrap_or(&0) as u128) << filled;
            filled += 8;
        }
        out.push((acc as u64) & mask(bits));
        acc >>= bits;
        filled -= bits;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_and_sizes() {
        let mut s = crate::rng::SplitMix64::new(3);
        for bits in 8..=64 {
            let codes: Vec<u64> = (0..37).map(|_| s.next_u64() & mask(bits)).collect();
            let words = to_words(&codes, bits);
            assert_eq!(words.len(), 37 * word_bytes(bits));
            assert_eq!(from_words(&words, bits).unwrap(), codes);
            let packed = to_packed(&codes, bits);
            assert_eq!(packed.len(), (37 * bits as usize).div_ceil(8));
            assert_eq!(from_packed(&packed, bits), codes, "bits {bits}");
        }
    }

    #[test]
    fn packed_bit_order_is_lsb_first() {
        // Two 12-bit codes 0xABC, 0x123 -> bits: BC, 3A, 12.
        assert_eq!(to_packed(&[0xABC, 0x123], 12), vec![0xBC, 0x3A, 0x12]);
        assert_eq!(to_words(&[0xABC], 12), vec![0xBC, 0x0A]);
    }
}
