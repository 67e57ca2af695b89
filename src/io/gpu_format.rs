//! GPU texel formats for HDR textures and the exact f32 → texel packers, shared by the KTX2 and
//! DDS writers.
//!
//! | name | Vulkan | DXGI | bytes | channels in |
//! | --- | --- | --- | --- | --- |
//! | `rgba16f` | R16G16B16A16_SFLOAT (97) | R16G16B16A16_FLOAT (10) | 8 | RGB (A = 1) or RGBA |
//! | `rgba32f` | R32G32B32A32_SFLOAT (109) | R32G32B32A32_FLOAT (2) | 16 | RGB (A = 1) or RGBA |
//! | `b10g11r11` | B10G11R11_UFLOAT_PACK32 (122) | R11G11B10_FLOAT (26) | 4 | RGB |
//! | `e5b9g9r9` | E5B9G9R9_UFLOAT_PACK32 (123) | R9G9B9E5_SHAREDEXP (67) | 4 | RGB |
//! | `rg16f` | R16G16_SFLOAT (83) | R16G16_FLOAT (34) | 4 | RG |
//! | `rg32f` | R32G32_SFLOAT (103) | R32G32_FLOAT (16) | 8 | RG |
//!
//! The two packed formats have the same bit layout in both APIs (Vulkan names list components
//! from the most significant bit, DXGI from the least): R in bits 0–10, G in 11–21, B in 22–31;
//! and R, G, B mantissas in bits 0–8, 9–17, 18–26 with the shared exponent in 27–31.
//!
//! Conversions (Vulkan specification, "Floating Point Numbers" / "Unsigned 11-bit/10-bit
//! Floating-Point Numbers" / "Shared Exponent Format"; EXT_texture_shared_exponent):
//! - f16 and the 11/10-bit unsigned floats round to nearest, ties to even. A finite value beyond
//!   the largest finite code becomes that code (the "closest representable finite value"), and so
//!   does +∞: a texture of light must stay finite.
//! - The unsigned formats store negative values (and −0) as 0.
//! - NaN becomes 0 in every format: NaN has no meaning as radiance, and a NaN texel would spread
//!   through every filter that reads it.
//! - RGB9E5 follows the extension's algorithm exactly, including its round-half-up of mantissas.

use crate::limits::MAX_TEXTURE_SIDE;
use half::f16;

/// Errors of encoding texels.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum FormatError {
    /// The data has a channel count the format cannot take.
    #[error("{format} stores {expected} channels; the data has {channels}")]
    Channels {
        /// The format's name.
        format: &'static str,
        /// What it takes.
        expected: &'static str,
        /// What was given.
        channels: usize,
    },
    /// A format name prtkit does not write.
    #[error("unknown texel format {0:?} (expected rgba16f, rgba32f, b10g11r11, e5b9g9r9, rg16f or rg32f)")]
    Unknown(String),
}

/// A texel format prtkit writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TexelFormat {
    /// Four half floats.
    Rgba16Float,
    /// Four single floats.
    Rgba32Float,
    /// Unsigned 11/11/10-bit floats packed in 32 bits.
    B10G11R11Ufloat,
    /// Three 9-bit mantissas with a shared 5-bit exponent.
    E5B9G9R9Ufloat,
    /// Two half floats (the DFG table).
    Rg16Float,
    /// Two single floats (the DFG table).
    Rg32Float,
}

impl TexelFormat {
    /// Every format, in the order of the table above.
    pub const ALL: [TexelFormat; 6] = [
        TexelFormat::Rgba16Float,
        TexelFormat::Rgba32Float,
        TexelFormat::B10G11R11Ufloat,
        TexelFormat::E5B9G9R9Ufloat,
        TexelFormat::Rg16Float,
        TexelFormat::Rg32Float,
    ];

    /// The command-line name (`rgba16f`, …).
    pub fn name(self) -> &'static str {
        match self {
            TexelFormat::Rgba16Float => "rgba16f",
            TexelFormat::Rgba32Float => "rgba32f",
            TexelFormat::B10G11R11Ufloat => "b10g11r11",
            TexelFormat::E5B9G9R9Ufloat => "e5b9g9r9",
            TexelFormat::Rg16Float => "rg16f",
            TexelFormat::Rg32Float => "rg32f",
        }
    }

    /// Parses a command-line name.
    pub fn parse(name: &str) -> Result<Self, FormatError> {
        Self::ALL.into_iter().find(|f| f.name() == name).ok_or_else(|| FormatError::Unknown(name.to_string()))
    }

    /// The `VkFormat` value.
    pub fn vk_format(self) -> u32 {
        match self {
            TexelFormat::Rgba16Float => 97,
            TexelFormat::Rgba32Float => 109,
            TexelFormat::B10G11R11Ufloat => 122,
            TexelFormat::E5B9G9R9Ufloat => 123,
            TexelFormat::Rg16Float => 83,
            TexelFormat::Rg32Float => 103,
        }
    }

    /// The `DXGI_FORMAT` value.
    pub fn dxgi_format(self) -> u32 {
        match self {
            TexelFormat::Rgba16Float => 10,
            TexelFormat::Rgba32Float => 2,
            TexelFormat::B10G11R11Ufloat => 26,
            TexelFormat::E5B9G9R9Ufloat => 67,
            TexelFormat::Rg16Float => 34,
            TexelFormat::Rg32Float => 16,
        }
    }

    /// Bytes per texel (the Vulkan texel block size).
    pub fn texel_bytes(self) -> usize {
        match self {
            TexelFormat::Rgba16Float => 8,
            TexelFormat::Rgba32Float => 16,
            TexelFormat::B10G11R11Ufloat | TexelFormat::E5B9G9R9Ufloat | TexelFormat::Rg16Float => 4,
            TexelFormat::Rg32Float => 8,
        }
    }

    /// Bytes of the data type an upload is done in: the component size, or 4 for `_PACK32`.
    pub fn type_size(self) -> u32 {
        match self {
            TexelFormat::Rgba16Float | TexelFormat::Rg16Float => 2,
            _ => 4,
        }
    }

    /// The format of a `VkFormat` value, if prtkit writes it.
    pub fn from_vk_format(vk_format: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.vk_format() == vk_format)
    }

    /// The largest value every channel of the format holds, above which encoding saturates:
    /// 65504 for half floats, 64512 for B10G11R11 (the 10-bit blue; red and green hold 65024),
    /// 65408 for E5B9G9R9 (511/512 · 2¹⁶); `None` for single floats.
    pub fn max_value(self) -> Option<f32> {
        match self {
            TexelFormat::Rgba16Float | TexelFormat::Rg16Float => Some(F16_MAX),
            TexelFormat::B10G11R11Ufloat => Some(64512.0),
            TexelFormat::E5B9G9R9Ufloat => Some(65408.0),
            TexelFormat::Rgba32Float | TexelFormat::Rg32Float => None,
        }
    }

    /// How many texels of `values` (`channels` floats each) have a channel above
    /// [`TexelFormat::max_value`]: the texels encoding saturates.
    pub fn saturated_texels(self, values: &[f32], channels: usize) -> usize {
        let Some(max) = self.max_value() else { return 0 };
        values.chunks_exact(channels).filter(|t| t.iter().any(|&v| v > max)).count()
    }

    /// Channels a texel holds: 4 (RGBA), 3 (the packed RGB formats) or 2 (RG).
    pub fn channels(self) -> usize {
        match self {
            TexelFormat::Rgba16Float | TexelFormat::Rgba32Float => 4,
            TexelFormat::B10G11R11Ufloat | TexelFormat::E5B9G9R9Ufloat => 3,
            TexelFormat::Rg16Float | TexelFormat::Rg32Float => 2,
        }
    }

    /// Appends the [`TexelFormat::channels`] floats of each little-endian texel of `bytes` (whole
    /// texels; a trailing partial texel is ignored): the inverse of [`TexelFormat::encode`] up to
    /// its rounding.
    pub fn decode(self, bytes: &[u8], out: &mut Vec<f32>) {
        let half = |b: &[u8]| f16::from_bits(u16::from_le_bytes([b[0], b[1]])).to_f32();
        let single = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        let word = |b: &[u8]| u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        out.reserve(bytes.len() / self.texel_bytes() * self.channels());
        for t in bytes.chunks_exact(self.texel_bytes()) {
            match self {
                TexelFormat::Rgba16Float | TexelFormat::Rg16Float => out.extend(t.chunks_exact(2).map(half)),
                TexelFormat::Rgba32Float | TexelFormat::Rg32Float => out.extend(t.chunks_exact(4).map(single)),
                TexelFormat::B10G11R11Ufloat => out.extend(unpack_b10g11r11(word(t))),
                TexelFormat::E5B9G9R9Ufloat => out.extend(unpack_rgb9e5(word(t))),
            }
        }
    }

    /// Whether `channels` interleaved input channels can be encoded.
    fn check_channels(self, channels: usize) -> Result<(), FormatError> {
        let (ok, expected) = match self {
            TexelFormat::Rgba16Float | TexelFormat::Rgba32Float => {
                (channels == 3 || channels == 4, "3 (RGB, A = 1) or 4")
            }
            TexelFormat::B10G11R11Ufloat | TexelFormat::E5B9G9R9Ufloat => (channels == 3, "3 (RGB)"),
            TexelFormat::Rg16Float | TexelFormat::Rg32Float => (channels == 2, "2 (RG)"),
        };
        if ok {
            Ok(())
        } else {
            Err(FormatError::Channels { format: self.name(), expected, channels })
        }
    }

    /// Appends the little-endian texels of interleaved `data` with `channels` channels.
    pub fn encode(self, data: &[f32], channels: usize, out: &mut Vec<u8>) -> Result<(), FormatError> {
        self.check_channels(channels)?;
        out.reserve(data.len() / channels * self.texel_bytes());
        for px in data.chunks_exact(channels) {
            let alpha = if channels == 4 { px[3] } else { 1.0 };
            match self {
                TexelFormat::Rgba16Float => {
                    for v in [px[0], px[1], px[2], alpha] {
                        out.extend_from_slice(&f16_bits(v).to_le_bytes());
                    }
                }
                TexelFormat::Rgba32Float => {
                    for v in [px[0], px[1], px[2], alpha] {
                        out.extend_from_slice(&finite_f32(v).to_le_bytes());
                    }
                }
                TexelFormat::B10G11R11Ufloat => {
                    out.extend_from_slice(&pack_b10g11r11([px[0], px[1], px[2]]).to_le_bytes())
                }
                TexelFormat::E5B9G9R9Ufloat => out.extend_from_slice(&pack_rgb9e5([px[0], px[1], px[2]]).to_le_bytes()),
                TexelFormat::Rg16Float => {
                    for v in [px[0], px[1]] {
                        out.extend_from_slice(&f16_bits(v).to_le_bytes());
                    }
                }
                TexelFormat::Rg32Float => {
                    for v in [px[0], px[1]] {
                        out.extend_from_slice(&finite_f32(v).to_le_bytes());
                    }
                }
            }
        }
        Ok(())
    }
}

/// NaN → 0, ±∞ → ±f32::MAX; finite values unchanged.
fn finite_f32(x: f32) -> f32 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(-f32::MAX, f32::MAX)
    }
}

/// Largest finite half float.
const F16_MAX: f32 = 65504.0;

/// f32 → IEEE half bits: round to nearest even, saturating at ±65504, NaN → 0.
pub fn f16_bits(x: f32) -> u16 {
    if x.is_nan() {
        return 0;
    }
    f16::from_f32(x.clamp(-F16_MAX, F16_MAX)).to_bits()
}

/// An unsigned small float with 5 exponent bits (bias 15) and `m` mantissa bits.
fn pack_ufloat(x: f32, m: u32) -> u32 {
    let max_code = (30 << m) | ((1 << m) - 1);
    if x.is_nan() || x <= 0.0 {
        return 0;
    }
    let bits = x.to_bits();
    let exp32 = ((bits >> 23) & 0xff) as i32;
    if exp32 == 0xff {
        return max_code; // +∞ (NaN was handled above)
    }
    if exp32 == 0 {
        return 0; // f32 subnormals are below 2^-126, far under the smallest code 2^-(14+m)
    }
    let e = exp32 - 127;
    let significand = u64::from((bits & 0x7f_ffff) | 0x80_0000); // 1.f × 2^23
                                                                 // The value in units of the target's last place: normal codes have ulp 2^(e−m), subnormal
                                                                 // codes (e < −14) ulp 2^(−14−m). Its integer part is the code's significand.
    let ulp_exp = e.max(-14) - m as i32;
    let shift = (23 + ulp_exp - e) as u32; // significand × 2^(e−23) / 2^ulp_exp = significand >> shift
    let q = round_half_even_shift(significand, shift);
    // q includes the implicit 1 for normal numbers: code = (biased exponent << m) + fraction,
    // which for q = 1.f·2^m at exponent e is ((e + 15 − 1) << m) + q. A rounding carry to 2^(m+1)
    // lands on the next exponent automatically.
    let code = if e < -14 { q } else { (((e + 14) as u64) << m) + q };
    (code as u32).min(max_code)
}

/// ⌊v / 2^shift⌉ with ties to even.
fn round_half_even_shift(v: u64, shift: u32) -> u64 {
    if shift == 0 {
        return v;
    }
    if shift >= 64 {
        return 0;
    }
    let q = v >> shift;
    let rem = v & ((1u64 << shift) - 1);
    let half = 1u64 << (shift - 1);
    if rem > half || (rem == half && q & 1 == 1) {
        q + 1
    } else {
        q
    }
}

fn unpack_ufloat(code: u32, m: u32) -> f32 {
    let (e, f) = (code >> m, code & ((1 << m) - 1));
    let scale = |p: i32| 2f32.powi(p);
    match e {
        0 => f as f32 * scale(-14 - m as i32),
        31 => {
            if f == 0 {
                f32::INFINITY
            } else {
                f32::NAN
            }
        }
        _ => (1.0 + f as f32 / (1 << m) as f32) * scale(e as i32 - 15),
    }
}

/// Unsigned 11-bit float (6 mantissa bits) of x.
pub fn pack_ufloat11(x: f32) -> u32 {
    pack_ufloat(x, 6)
}

/// Unsigned 10-bit float (5 mantissa bits) of x.
pub fn pack_ufloat10(x: f32) -> u32 {
    pack_ufloat(x, 5)
}

/// Value of an 11-bit unsigned float code.
pub fn unpack_ufloat11(code: u32) -> f32 {
    unpack_ufloat(code & 0x7ff, 6)
}

/// Value of a 10-bit unsigned float code.
pub fn unpack_ufloat10(code: u32) -> f32 {
    unpack_ufloat(code & 0x3ff, 5)
}

/// B10G11R11_UFLOAT_PACK32 / R11G11B10_FLOAT: R in bits 0–10, G in 11–21, B in 22–31.
pub fn pack_b10g11r11(rgb: [f32; 3]) -> u32 {
    pack_ufloat11(rgb[0]) | (pack_ufloat11(rgb[1]) << 11) | (pack_ufloat10(rgb[2]) << 22)
}

/// The RGB of a packed 11/11/10 texel.
pub fn unpack_b10g11r11(v: u32) -> [f32; 3] {
    [unpack_ufloat11(v), unpack_ufloat11(v >> 11), unpack_ufloat10(v >> 22)]
}

/// RGB9E5 parameters (EXT_texture_shared_exponent): N = 9 mantissa bits, B = 15 bias, E_max = 31.
const RGB9E5_N: i32 = 9;
const RGB9E5_B: i32 = 15;
/// sharedexp_max = (2^N − 1)/2^N · 2^(E_max − B) = 65408.
pub const RGB9E5_MAX: f32 = 65408.0;

/// E5B9G9R9_UFLOAT_PACK32 / R9G9B9E5_SHAREDEXP by the algorithm of EXT_texture_shared_exponent
/// (also the Vulkan specification's "Shared Exponent Format" conversion):
///
///   c_c = clamp(c, 0, sharedexp_max)  (NaN → 0)
///   exp' = max(−B − 1, ⌊log2(max c_c)⌋) + 1 + B
///   max_s = ⌊max c_c / 2^(exp' − B − N) + ½⌋,  exp = exp' + 1 if max_s = 2^N else exp'
///   c_s = ⌊c_c / 2^(exp − B − N) + ½⌋.
pub fn pack_rgb9e5(rgb: [f32; 3]) -> u32 {
    let c = rgb.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, RGB9E5_MAX) as f64 });
    let max_c = c[0].max(c[1]).max(c[2]);
    // ⌊log2 x⌋ exactly from the binary exponent (f64 holds every f32 exactly).
    let floor_log2 = if max_c > 0.0 { ((max_c.to_bits() >> 52) & 0x7ff) as i32 - 1023 } else { i32::MIN };
    let exp_p = floor_log2.max(-RGB9E5_B - 1) + 1 + RGB9E5_B;
    let scale = |e: i32| 2f64.powi(e - RGB9E5_B - RGB9E5_N);
    let max_s = (max_c / scale(exp_p) + 0.5).floor() as i64;
    let exp = if max_s == 1 << RGB9E5_N { exp_p + 1 } else { exp_p };
    let m = c.map(|v| ((v / scale(exp) + 0.5).floor() as u32).min(511));
    m[0] | (m[1] << 9) | (m[2] << 18) | ((exp as u32) << 27)
}

/// The RGB of an RGB9E5 texel: mantissa · 2^(exp − B − N).
pub fn unpack_rgb9e5(v: u32) -> [f32; 3] {
    let scale = 2f32.powi((v >> 27) as i32 - RGB9E5_B - RGB9E5_N);
    [(v & 511) as f32 * scale, ((v >> 9) & 511) as f32 * scale, ((v >> 18) & 511) as f32 * scale]
}

/// Errors of encoding a texture file.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum TextureError {
    /// The texel data does not fit the format.
    #[error(transparent)]
    Format(#[from] FormatError),
    /// The texture's shape or levels are inconsistent.
    #[error("invalid texture: {0}")]
    Invalid(String),
}

/// What kind of texture, and the size of level 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureShape {
    /// A 2-D texture of width × height texels.
    Texture2d {
        /// Width of level 0.
        width: usize,
        /// Height of level 0.
        height: usize,
    },
    /// A cube map of six size × size faces.
    Cube {
        /// Face size of level 0.
        size: usize,
    },
}

impl TextureShape {
    /// (width, height, faces) of level 0.
    pub fn dimensions(self) -> (usize, usize, usize) {
        match self {
            TextureShape::Texture2d { width, height } => (width, height, 1),
            TextureShape::Cube { size } => (size, size, 6),
        }
    }
}

/// Texel data to write: interleaved float channels per level, largest level first; each level
/// holds its faces one after the other, rows top to bottom.
#[derive(Clone, Debug)]
pub struct Texture<'a> {
    /// Shape and level-0 size.
    pub shape: TextureShape,
    /// Interleaved channels per texel (2 for RG, 3 for RGB, 4 for RGBA).
    pub channels: usize,
    /// The levels, largest first; level p is max(1, size >> p) on each side.
    pub levels: Vec<&'a [f32]>,
}

impl Texture<'_> {
    /// Checks the level count and every level's length against the shape.
    pub fn check(&self) -> Result<(), TextureError> {
        let (w, h, faces) = self.shape.dimensions();
        let bad = |why: String| Err(TextureError::Invalid(why));
        if w == 0 || h == 0 || w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
            return bad(format!("level 0 is {w}×{h}; each side must be in 1..={MAX_TEXTURE_SIDE}"));
        }
        let max_levels = usize::BITS - w.max(h).leading_zeros(); // ⌊log2 max⌋ + 1
        if self.levels.is_empty() || self.levels.len() > max_levels as usize {
            return bad(format!(
                "{} levels for a {w}×{h} base; between 1 and {max_levels} are possible",
                self.levels.len()
            ));
        }
        for (p, level) in self.levels.iter().enumerate() {
            let want = faces * (w >> p).max(1) * (h >> p).max(1) * self.channels;
            if level.len() != want {
                return bad(format!("level {p} holds {} values, expected {want}", level.len()));
            }
        }
        Ok(())
    }

    /// The (width, height) of level p.
    pub fn level_dimensions(&self, p: usize) -> (usize, usize) {
        let (w, h, _) = self.shape.dimensions();
        ((w >> p).max(1), (h >> p).max(1))
    }

    /// Level p packed in `format`: its faces one after the other, rows top to bottom.
    pub fn encode_level(&self, p: usize, format: TexelFormat) -> Result<Vec<u8>, TextureError> {
        let mut bytes = Vec::new();
        format.encode(self.levels[p], self.channels, &mut bytes)?;
        Ok(bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_floats_saturate_and_drop_nan() {
        assert_eq!(f16_bits(1.0), 0x3c00);
        assert_eq!(f16_bits(-2.0), 0xc000);
        assert_eq!(f16_bits(65504.0), 0x7bff);
        assert_eq!(f16_bits(1e9), 0x7bff);
        assert_eq!(f16_bits(f32::INFINITY), 0x7bff);
        assert_eq!(f16_bits(f32::NEG_INFINITY), 0xfbff);
        assert_eq!(f16_bits(f32::NAN), 0);
        // 1 + 2^-11 is halfway between 1 and 1 + 2^-10: ties to even → 1.0.
        assert_eq!(f16_bits(1.0 + 2f32.powi(-11)), 0x3c00);
        assert_eq!(f16_bits(1.0 + 3.0 * 2f32.powi(-11)), 0x3c02);
    }

    #[test]
    fn small_floats_hand_computed() {
        // 11-bit: exponent bias 15, 6 mantissa bits. 1.0 = 15 << 6, 0.5 = 14 << 6.
        assert_eq!(pack_ufloat11(1.0), 960);
        assert_eq!(pack_ufloat11(0.5), 896);
        assert_eq!(pack_ufloat11(1.5), 960 + 32);
        // Largest finite: exponent 30, mantissa 63 = (1 + 63/64)·2^15 = 65024; 10-bit: 64512.
        assert_eq!(unpack_ufloat11(pack_ufloat11(65024.0)), 65024.0);
        assert_eq!(pack_ufloat11(65024.0), (30 << 6) | 63);
        assert_eq!(pack_ufloat11(1e30), (30 << 6) | 63);
        assert_eq!(pack_ufloat11(f32::INFINITY), (30 << 6) | 63);
        assert_eq!(pack_ufloat10(1e6), (30 << 5) | 31);
        assert_eq!(unpack_ufloat10((30 << 5) | 31), 64512.0);
        // Negative, −0 and NaN → 0.
        assert_eq!(pack_ufloat11(-3.0), 0);
        assert_eq!(pack_ufloat11(-0.0), 0);
        assert_eq!(pack_ufloat10(f32::NAN), 0);
        // Subnormals: the smallest codes are 2^-20 (11-bit) and 2^-19 (10-bit); 2^-14 is the
        // smallest normal, code 1 << m.
        assert_eq!(pack_ufloat11(2f32.powi(-20)), 1);
        assert_eq!(pack_ufloat10(2f32.powi(-19)), 1);
        assert_eq!(pack_ufloat11(2f32.powi(-14)), 64);
        assert_eq!(pack_ufloat11(2f32.powi(-22)), 0); // a quarter of the smallest code
        assert_eq!(pack_ufloat11(3.0 * 2f32.powi(-21)), 2); // 1.5 codes: tie → even (2)
                                                            // Ties to even in the normal range: 1 + 2^-7 is halfway between mantissas 0 and 1.
        assert_eq!(pack_ufloat11(1.0 + 2f32.powi(-7)), 960);
        assert_eq!(pack_ufloat11(1.0 + 3.0 * 2f32.powi(-7)), 962);
        // A carry out of the mantissa: just below 2 rounds to 2.0 = 16 << 6.
        assert_eq!(pack_ufloat11(2.0 - 2f32.powi(-10)), 1024);
        // Packing order: R bits 0–10, G 11–21, B 22–31.
        assert_eq!(pack_b10g11r11([1.0, 0.0, 0.0]), 960);
        assert_eq!(pack_b10g11r11([0.0, 1.0, 0.0]), 960 << 11);
        assert_eq!(pack_b10g11r11([0.0, 0.0, 1.0]), 480 << 22);
    }

    #[test]
    fn small_floats_round_trip_within_half_an_ulp() {
        let mut x = 1e-5f32;
        while x < 6e4 {
            for (pack, unpack, m) in [
                (pack_ufloat11 as fn(f32) -> u32, unpack_ufloat11 as fn(u32) -> f32, 6),
                (pack_ufloat10, unpack_ufloat10, 5),
            ] {
                let back = unpack(pack(x));
                let ulp = if x < 2f32.powi(-14) { 2f32.powi(-14 - m) } else { 2f32.powi(x.log2().floor() as i32 - m) };
                assert!((back - x).abs() <= 0.5 * ulp * (1.0 + 1e-6), "x={x} m={m}: {back}");
            }
            x *= 1.0137;
        }
    }

    #[test]
    fn shared_exponent_hand_computed() {
        // (1, 1, 1): ⌊log2 1⌋ = 0, exp' = 16, max_s = ⌊1·2^8 + ½⌋ = 256 → mantissas 256, exp 16.
        assert_eq!(pack_rgb9e5([1.0; 3]), 256 | (256 << 9) | (256 << 18) | (16 << 27));
        assert_eq!(pack_rgb9e5([0.0; 3]), 0);
        // The largest value: 511 · 2^(31 − 24) = 65408, exponent 31; beyond it, clamped.
        assert_eq!(pack_rgb9e5([RGB9E5_MAX, 0.0, 0.0]), 511 | (31 << 27));
        assert_eq!(pack_rgb9e5([1e9, f32::INFINITY, 0.0]), 511 | (511 << 9) | (31 << 27));
        // Negative and NaN → 0 (the other channels keep the exponent of the largest).
        assert_eq!(pack_rgb9e5([-1.0, f32::NAN, 2.0]), 256 << 18 | (17 << 27));
        // max_s rounding up to 2^9 bumps the exponent: 1 − 2^-11 → ⌊511.75 + ½⌋ = 512, so exp = 16
        // and the mantissa is ⌊255.875 + ½⌋ = 256: stored as exactly 1.0.
        let v = pack_rgb9e5([1.0 - 2f32.powi(-11), 0.0, 0.0]);
        assert_eq!(v, 256 | (16 << 27));
        assert_eq!(unpack_rgb9e5(v), [1.0, 0.0, 0.0]);
        // (0.5, 0.25, 0.125): exp' = 15, scale 2^-9: mantissas 256, 128, 64.
        assert_eq!(pack_rgb9e5([0.5, 0.25, 0.125]), 256 | (128 << 9) | (64 << 18) | (15 << 27));
        // Tiny values share the smallest exponent 0: ulp 2^-24.
        assert_eq!(pack_rgb9e5([3.0 * 2f32.powi(-24), 0.0, 0.0]), 3);
    }

    #[test]
    fn shared_exponent_round_trip_error_is_bounded() {
        // Each channel is within half a step of the shared scale 2^(exp − 24), and the largest
        // channel within 2^-9 relative.
        let mut x = 1e-4f32;
        while x < 6e4 {
            let rgb = [x, 0.37 * x, 0.011 * x];
            let v = pack_rgb9e5(rgb);
            let back = unpack_rgb9e5(v);
            let step = 2f32.powi((v >> 27) as i32 - 24);
            for c in 0..3 {
                assert!((back[c] - rgb[c]).abs() <= 0.5 * step * (1.0 + 1e-6), "{rgb:?} → {back:?}");
            }
            assert!((back[0] - x).abs() <= x * 2f32.powi(-9), "{x}");
            x *= 1.0173;
        }
    }

    #[test]
    fn encode_checks_channels_and_lays_out_texels() {
        let mut out = Vec::new();
        TexelFormat::Rgba16Float.encode(&[1.0, 2.0, 0.5], 3, &mut out).unwrap();
        assert_eq!(out, [0x00, 0x3c, 0x00, 0x40, 0x00, 0x38, 0x00, 0x3c]);
        out.clear();
        TexelFormat::Rg32Float.encode(&[0.25, f32::NAN], 2, &mut out).unwrap();
        assert_eq!(out, [0.25f32.to_le_bytes(), 0f32.to_le_bytes()].concat());
        assert_eq!(
            TexelFormat::E5B9G9R9Ufloat.encode(&[1.0, 2.0], 2, &mut out),
            Err(FormatError::Channels { format: "e5b9g9r9", expected: "3 (RGB)", channels: 2 })
        );
        for f in TexelFormat::ALL {
            assert_eq!(TexelFormat::parse(f.name()), Ok(f));
        }
        assert!(TexelFormat::parse("bc6h").is_err());
    }
}
