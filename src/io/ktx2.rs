//! KTX 2.0 writer for uncompressed HDR textures: 2-D textures and cube maps with mip chains
//! (Khronos, "KTX File Format Specification", version 2.0), and the reader `render --shading ibl`
//! loads them back with ([`decode`], on the independent `ktx2` crate's parser, as an engine would).
//!
//! Layout written (spec §2 "File Structure"): the 12-byte identifier, the header (§3.1–3.8:
//! vkFormat, typeSize, pixelWidth/Height/Depth, layerCount 0, faceCount 1 or 6, levelCount,
//! supercompressionScheme 0), the index (§3.9: DFD, key/value and — empty — supercompression
//! global data offsets), the level index with level 0 (the largest) first, the Data Format
//! Descriptor (§3.10), the key/value data (§3.11, keys sorted by code point, each entry padded to
//! 4 bytes) and the mip level array **smallest level first** (§3.13), each level preceded by
//! mipPadding to a multiple of lcm(texel block size, 4) (§3.13.2). Within a level, faces follow
//! each other in the order +X, −X, +Y, −Y, +Z, −Z, rows top to bottom, tightly packed.
//!
//! Key/values: `KTXorientation` = `rd` (§4.2: s to the right, t down — the cube-map orientation
//! the spec mandates, and row 0 at the top for 2-D textures) and `KTXwriter` (§4.6).
//!
//! The Basic Data Format Descriptor follows the Khronos Data Format Specification 1.3
//! (§5 "Basic Data Format Descriptor Block"): colour model RGBSDA, BT.709 primaries, linear
//! transfer, straight alpha, one sample per channel. Float samples carry the F (and, when signed,
//! S) qualifier and sampleLower/Upper = the IEEE float bits of −1.0 (0 if unsigned) and 1.0. The
//! shared-exponent format is described as in the DF specification's E5B9G9R9 example: for each
//! channel a 9-bit mantissa sample (sampleUpper 8448 = mantissa 256 with exponent 16, i.e. 1.0)
//! and a 5-bit exponent sample at bit 27 with the E qualifier (sampleLower 15 = the bias,
//! sampleUpper 31) — which is also what the Khronos KTX tools generate.

use super::gpu_format::{TexelFormat, Texture, TextureError, TextureShape};

/// The KTX 2.0 file identifier «KTX 20»\r\n\x1A\n.
pub const IDENTIFIER: [u8; 12] = [0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A];

/// Whether `start` (the first bytes of a file) is the start of a KTX 2.0 file: checked before
/// the rest is read, so a device or a file of another kind costs 64 bytes of reading.
pub fn check_identifier(start: &[u8]) -> Result<(), String> {
    if start.starts_with(&IDENTIFIER) {
        Ok(())
    } else {
        Err(format!("does not start with the KTX 2.0 identifier (found {:02x?})", &start[..start.len().min(12)]))
    }
}

/// Rounds `n` up to a multiple of `align`.
fn align_up(n: usize, align: usize) -> usize {
    n.div_ceil(align) * align
}

/// lcm(texel block size, 4): the alignment of every level's data (§3.13.2).
pub fn level_alignment(format: TexelFormat) -> usize {
    let b = format.texel_bytes();
    let gcd = |mut a: usize, mut b: usize| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    b / gcd(b, 4) * 4
}

/// One sample of a Basic DFD block.
struct Sample {
    bit_offset: u32,
    bit_length: u32,
    /// Channel id (RGBSDA: R 0, G 1, B 2, A 15) with the qualifier bits F 0x80, S 0x40, E 0x20.
    channel: u32,
    lower: u32,
    upper: u32,
}

const QUALIFIER_FLOAT: u32 = 0x80;
const QUALIFIER_SIGNED: u32 = 0x40;
const QUALIFIER_EXPONENT: u32 = 0x20;
const CHANNEL_ALPHA: u32 = 15;

/// The samples of `format`'s Basic DFD block and its bytesPlane0.
fn dfd_samples(format: TexelFormat) -> Vec<Sample> {
    let float_samples = |bits: u32, channels: &[u32]| -> Vec<Sample> {
        channels
            .iter()
            .enumerate()
            .map(|(i, &c)| Sample {
                bit_offset: i as u32 * bits,
                bit_length: bits,
                channel: c | QUALIFIER_FLOAT | QUALIFIER_SIGNED,
                lower: (-1.0f32).to_bits(),
                upper: 1.0f32.to_bits(),
            })
            .collect()
    };
    match format {
        TexelFormat::Rgba16Float => float_samples(16, &[0, 1, 2, CHANNEL_ALPHA]),
        TexelFormat::Rgba32Float => float_samples(32, &[0, 1, 2, CHANNEL_ALPHA]),
        TexelFormat::Rg16Float => float_samples(16, &[0, 1]),
        TexelFormat::Rg32Float => float_samples(32, &[0, 1]),
        TexelFormat::B10G11R11Ufloat => [(0, 11, 0), (11, 11, 1), (22, 10, 2)]
            .into_iter()
            .map(|(bit_offset, bit_length, c)| Sample {
                bit_offset,
                bit_length,
                channel: c | QUALIFIER_FLOAT,
                lower: 0,
                upper: 1.0f32.to_bits(),
            })
            .collect(),
        TexelFormat::E5B9G9R9Ufloat => (0..3)
            .flat_map(|c| {
                [
                    Sample { bit_offset: 9 * c, bit_length: 9, channel: c, lower: 0, upper: 8448 },
                    Sample { bit_offset: 27, bit_length: 5, channel: c | QUALIFIER_EXPONENT, lower: 15, upper: 31 },
                ]
            })
            .collect(),
    }
}

/// The Data Format Descriptor: dfdTotalSize followed by one Basic descriptor block.
pub fn data_format_descriptor(format: TexelFormat) -> Vec<u8> {
    let samples = dfd_samples(format);
    let block_size = 24 + 16 * samples.len() as u32;
    let mut words: Vec<u32> = vec![
        4 + block_size,
        0,                           // vendorId 0 (Khronos), descriptorType 0 (basic)
        2 | (block_size << 16),      // versionNumber 2 (KDF 1.3), descriptorBlockSize
        1 | (1 << 8) | (1 << 16),    // colorModel RGBSDA, primaries BT709, transfer LINEAR, flags straight alpha
        0,                           // texelBlockDimension 0..3: 1×1×1×1
        format.texel_bytes() as u32, // bytesPlane0
        0,                           // bytesPlane4..7
    ];
    for s in samples {
        words.push(s.bit_offset | ((s.bit_length - 1) << 16) | (s.channel << 24));
        words.push(0); // samplePosition0..3
        words.push(s.lower);
        words.push(s.upper);
    }
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// The key/value data: sorted keys, each entry `length, key NUL value` padded to 4 bytes.
fn key_values() -> Vec<u8> {
    let writer = format!("prtkit {}", env!("CARGO_PKG_VERSION"));
    let mut entries: Vec<(&str, Vec<u8>)> =
        vec![("KTXorientation", b"rd\0".to_vec()), ("KTXwriter", [writer.as_bytes(), b"\0"].concat())];
    entries.sort_by(|a, b| a.0.cmp(b.0));
    let mut out = Vec::new();
    for (key, value) in entries {
        let len = key.len() + 1 + value.len();
        out.extend_from_slice(&(len as u32).to_le_bytes());
        out.extend_from_slice(key.as_bytes());
        out.push(0);
        out.extend_from_slice(&value);
        out.resize(align_up(out.len(), 4), 0);
    }
    out
}

/// Encodes a texture as a KTX 2.0 file in `format`.
pub fn encode(texture: &Texture, format: TexelFormat) -> Result<Vec<u8>, TextureError> {
    texture.check()?;
    let (w, h, faces) = texture.shape.dimensions();
    let level_count = texture.levels.len();
    let images = (0..level_count).map(|p| texture.encode_level(p, format)).collect::<Result<Vec<_>, _>>()?;
    let dfd = data_format_descriptor(format);
    let kvd = key_values();
    let dfd_offset = 80 + 24 * level_count;
    let kvd_offset = dfd_offset + dfd.len();
    // Level offsets: smallest level first, each aligned.
    let alignment = level_alignment(format);
    let mut offsets = vec![0usize; level_count];
    let mut end = kvd_offset + kvd.len();
    for p in (0..level_count).rev() {
        end = align_up(end, alignment);
        offsets[p] = end;
        end += images[p].len();
    }
    let mut out = Vec::with_capacity(end);
    out.extend_from_slice(&IDENTIFIER);
    for v in [
        format.vk_format(),
        format.type_size(),
        w as u32,
        h as u32,
        0, // pixelDepth
        0, // layerCount: not an array
        faces as u32,
        level_count as u32,
        0, // supercompressionScheme: none
    ] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for v in [dfd_offset as u32, dfd.len() as u32, kvd_offset as u32, kvd.len() as u32] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.extend_from_slice(&0u64.to_le_bytes()); // sgdByteOffset
    out.extend_from_slice(&0u64.to_le_bytes()); // sgdByteLength
    for p in 0..level_count {
        let len = images[p].len() as u64;
        for v in [offsets[p] as u64, len, len] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out.extend_from_slice(&dfd);
    out.extend_from_slice(&kvd);
    for p in (0..level_count).rev() {
        out.resize(offsets[p], 0); // mipPadding
        out.extend_from_slice(&images[p]);
    }
    Ok(out)
}

/// A texture read back: level p holds its faces one after the other, rows top to bottom, each
/// texel [`TexelFormat::channels`] floats.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedTexture {
    /// The texel format of the file.
    pub format: TexelFormat,
    /// Shape and level-0 size.
    pub shape: TextureShape,
    /// The levels, largest first.
    pub levels: Vec<Vec<f32>>,
}

/// Reads a KTX 2.0 file in one of the formats prtkit writes: a 2-D texture or a cube map, not an
/// array, not supercompressed. The header is parsed by the `ktx2` crate, every level's length is
/// checked against its dimensions before it is decoded.
pub fn decode(bytes: &[u8]) -> Result<DecodedTexture, TextureError> {
    let bad = |why: String| TextureError::Invalid(why);
    let reader = ::ktx2::Reader::new(bytes).map_err(|e| bad(format!("not a KTX 2.0 file: {e}")))?;
    let header = reader.header();
    let vk = header.format.map_or(0, |f| f.value());
    let format = TexelFormat::from_vk_format(vk).ok_or_else(|| {
        bad(format!("VkFormat {vk} is not one prtkit reads (rgba16f, rgba32f, b10g11r11, e5b9g9r9, rg16f, rg32f)"))
    })?;
    if header.supercompression_scheme.is_some() {
        return Err(bad("supercompressed; prtkit reads uncompressed levels".into()));
    }
    if header.layer_count > 0 || header.pixel_depth > 0 {
        return Err(bad("an array or 3-D texture; prtkit reads 2-D textures and cube maps".into()));
    }
    check_level_index(bytes)?;
    let (w, h) = (header.pixel_width as usize, header.pixel_height as usize);
    let shape = match header.face_count {
        1 => TextureShape::Texture2d { width: w, height: h },
        6 if w == h => TextureShape::Cube { size: w },
        n => return Err(bad(format!("{n} faces of {w}×{h}; expected 1, or 6 square faces"))),
    };
    let levels = reader
        .levels()
        .enumerate()
        .map(|(p, level)| {
            let (lw, lh, faces) = ((w >> p).max(1), (h >> p).max(1), shape.dimensions().2);
            let want = faces * lw * lh * format.texel_bytes();
            if level.data.len() != want {
                return Err(bad(format!(
                    "level {p} holds {} bytes; {faces} × {lw}×{lh} texels need {want}",
                    level.data.len()
                )));
            }
            let mut texels = Vec::new();
            format.decode(level.data, &mut texels);
            Ok(texels)
        })
        .collect::<Result<Vec<_>, _>>()?;
    let decoded = DecodedTexture { format, shape, levels };
    // The same consistency rules as a texture to write (sizes, level count).
    let levels = decoded.levels.iter().map(Vec::as_slice).collect();
    Texture { shape, channels: format.channels(), levels }.check()?;
    Ok(decoded)
}

/// Checks the level index of a KTX 2.0 file (KTX 2.0 §3.9, after the 80-byte header): every
/// level's bytes lie after the header, the level index and the descriptors it points to
/// (DFD, key/value data, supercompression data), and no two levels overlap. The `ktx2` crate
/// only checks that the bytes are in the file, so an offset into the header would be read as
/// texels.
fn check_level_index(bytes: &[u8]) -> Result<(), TextureError> {
    let bad = |why: String| TextureError::Invalid(why);
    let u32_at = |o: usize| bytes.get(o..o + 4).map(|b| u32::from_le_bytes(b.try_into().unwrap()) as u64);
    let u64_at = |o: usize| bytes.get(o..o + 8).map(|b| u64::from_le_bytes(b.try_into().unwrap()));
    let truncated = || bad("truncated header".into());
    let level_count = u32_at(40).ok_or_else(truncated)?.max(1);
    let index_end = 80 + 24 * level_count;
    let ranges = [(48, 52, false), (56, 60, false), (64, 72, true)].map(|(offset, length, wide)| {
        let read = |o| if wide { u64_at(o) } else { u32_at(o) };
        Some((read(offset)?, read(length)?))
    });
    let mut metadata_end = index_end;
    for range in ranges {
        let (offset, length) = range.ok_or_else(truncated)?;
        if length > 0 {
            metadata_end = metadata_end.max(offset.saturating_add(length));
        }
    }
    let mut levels = Vec::with_capacity(level_count as usize);
    for p in 0..level_count {
        let at = 80 + 24 * p as usize;
        let (offset, length) = (u64_at(at).ok_or_else(truncated)?, u64_at(at + 8).ok_or_else(truncated)?);
        if offset < metadata_end {
            return Err(bad(format!(
                "level {p} starts at byte {offset}, inside the header, level index and descriptors (bytes 0..{metadata_end})"
            )));
        }
        levels.push((offset, offset.saturating_add(length), p));
    }
    levels.sort_unstable();
    for pair in levels.windows(2) {
        let ((_, end, p), (start, _, q)) = (pair[0], pair[1]);
        if start < end {
            return Err(bad(format!("levels {p} and {q} overlap (bytes {start}..{end})")));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::gpu_format::TextureShape;
    use crate::io::gpu_format::{unpack_b10g11r11, unpack_rgb9e5};
    use ktx2::{ChannelTypeQualifiers, ColorModel, ColorPrimaries, DfdBlockBasic, Format, Reader, TransferFunction};

    /// A cube chain 8, 4, 2 whose texel (level p, face f, row r, col c) encodes its position.
    fn cube_levels() -> Vec<Vec<f32>> {
        (0..3)
            .map(|p| {
                let n = 8 >> p;
                (0..6 * n * n)
                    .flat_map(|i| {
                        let (f, r, c) = (i / (n * n), (i / n) % n, i % n);
                        [p as f32 + 0.25 * f as f32, 0.5 + r as f32, 0.125 * c as f32]
                    })
                    .collect()
            })
            .collect()
    }

    fn decode(format: TexelFormat, bytes: &[u8]) -> Vec<[f32; 4]> {
        let f16 = |b: &[u8]| half::f16::from_le_bytes([b[0], b[1]]).to_f32();
        let f32 = |b: &[u8]| f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        bytes
            .chunks_exact(format.texel_bytes())
            .map(|t| match format {
                TexelFormat::Rgba16Float => [f16(&t[0..]), f16(&t[2..]), f16(&t[4..]), f16(&t[6..])],
                TexelFormat::Rgba32Float => [f32(&t[0..]), f32(&t[4..]), f32(&t[8..]), f32(&t[12..])],
                TexelFormat::Rg16Float => [f16(&t[0..]), f16(&t[2..]), 0.0, 0.0],
                TexelFormat::Rg32Float => [f32(&t[0..]), f32(&t[4..]), 0.0, 0.0],
                TexelFormat::B10G11R11Ufloat => {
                    let v = unpack_b10g11r11(u32::from_le_bytes([t[0], t[1], t[2], t[3]]));
                    [v[0], v[1], v[2], 1.0]
                }
                TexelFormat::E5B9G9R9Ufloat => {
                    let v = unpack_rgb9e5(u32::from_le_bytes([t[0], t[1], t[2], t[3]]));
                    [v[0], v[1], v[2], 1.0]
                }
            })
            .collect()
    }

    /// Writes the samples the npm `ktx-parse` check (`scripts/check-ktx2.sh`) reads.
    fn keep(name: &str, bytes: &[u8]) {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/ktx2-samples");
        if std::fs::create_dir_all(&dir).is_ok() {
            let _ = std::fs::write(dir.join(name), bytes);
        }
    }

    #[test]
    fn cube_maps_read_back_with_the_ktx2_crate() {
        let levels = cube_levels();
        let texture = Texture {
            shape: TextureShape::Cube { size: 8 },
            channels: 3,
            levels: levels.iter().map(|l| l.as_slice()).collect(),
        };
        for format in [
            TexelFormat::Rgba16Float,
            TexelFormat::Rgba32Float,
            TexelFormat::B10G11R11Ufloat,
            TexelFormat::E5B9G9R9Ufloat,
        ] {
            let bytes = encode(&texture, format).unwrap();
            keep(&format!("cube-{}.ktx2", format.name()), &bytes);
            let reader = Reader::new(&bytes).unwrap();
            let header = reader.header();
            assert_eq!(header.format, Format::new(format.vk_format()));
            assert_eq!((header.pixel_width, header.pixel_height, header.pixel_depth), (8, 8, 0));
            assert_eq!((header.face_count, header.layer_count, header.level_count), (6, 0, 3));
            assert_eq!(header.type_size, format.type_size());
            assert_eq!(header.supercompression_scheme, None);
            let read: Vec<_> = reader.levels().collect();
            let alignment = level_alignment(format) as u64;
            let mut previous_offset = u64::MAX;
            for (p, level) in read.iter().enumerate() {
                let n = 8 >> p;
                assert_eq!(level.data.len(), 6 * n * n * format.texel_bytes(), "{format:?} level {p}");
                assert_eq!(level.uncompressed_byte_length, level.data.len() as u64);
                let offset = level.data.as_ptr() as u64 - bytes.as_ptr() as u64;
                assert_eq!(offset % alignment, 0, "{format:?} level {p} at {offset}");
                assert!(offset < previous_offset, "levels must be stored smallest first");
                previous_offset = offset;
                let texels = decode(format, level.data);
                for (i, t) in texels.iter().enumerate() {
                    let want = &levels[p][3 * i..3 * i + 3];
                    for c in 0..3 {
                        let tol = match format {
                            TexelFormat::Rgba32Float => 0.0,
                            TexelFormat::Rgba16Float => 2e-3 * want[c].abs(),
                            TexelFormat::B10G11R11Ufloat => 2f32.powi(-6) * want[c].abs(),
                            _ => 2f32.powi(-9) * want.iter().cloned().fold(0.0, f32::max),
                        };
                        assert!((t[c] - want[c]).abs() <= tol, "{format:?} level {p} texel {i}: {t:?} vs {want:?}");
                    }
                }
            }
            // Level 0, stored last, ends the file.
            let offset0 = read[0].data.as_ptr() as usize - bytes.as_ptr() as usize;
            assert_eq!(offset0 + read[0].data.len(), bytes.len());
            let kv: Vec<(&str, &[u8])> = reader.key_value_data().collect();
            assert_eq!(kv[0], ("KTXorientation", &b"rd\0"[..]));
            assert_eq!(kv[1].0, "KTXwriter");
            assert!(kv[1].1.starts_with(b"prtkit "));
        }
    }

    #[test]
    fn data_format_descriptors_match_the_khronos_definitions() {
        for format in TexelFormat::ALL {
            let dfd = data_format_descriptor(format);
            let total = u32::from_le_bytes(dfd[0..4].try_into().unwrap()) as usize;
            assert_eq!(total, dfd.len());
            let block = DfdBlockBasic::parse(&dfd[12..]).unwrap();
            assert_eq!(block.header.color_model, Some(ColorModel::RGBSDA));
            assert_eq!(block.header.color_primaries, Some(ColorPrimaries::BT709));
            assert_eq!(block.header.transfer_function, Some(TransferFunction::Linear));
            assert_eq!(block.header.bytes_planes[0] as usize, format.texel_bytes());
            assert!(block.header.texel_block_dimensions.iter().all(|d| d.get() == 1));
            let samples: Vec<_> = block.sample_information().collect();
            // Every bit of the texel is covered exactly once (the shared exponent thrice).
            let covered: u32 = samples.iter().map(|s| s.bit_length.get() as u32).sum();
            let float = ChannelTypeQualifiers::FLOAT;
            match format {
                TexelFormat::Rgba16Float
                | TexelFormat::Rgba32Float
                | TexelFormat::Rg16Float
                | TexelFormat::Rg32Float => {
                    assert_eq!(covered as usize, 8 * format.texel_bytes());
                    for s in &samples {
                        assert_eq!(s.channel_type_qualifiers, float | ChannelTypeQualifiers::SIGNED);
                        assert_eq!((s.lower, s.upper), (0xBF80_0000, 0x3F80_0000));
                    }
                    let ids: Vec<u8> = samples.iter().map(|s| s.channel_type).collect();
                    assert_eq!(ids, if samples.len() == 4 { vec![0, 1, 2, 15] } else { vec![0, 1] });
                }
                TexelFormat::B10G11R11Ufloat => {
                    let layout: Vec<_> =
                        samples.iter().map(|s| (s.bit_offset, s.bit_length.get(), s.channel_type)).collect();
                    assert_eq!(layout, vec![(0, 11, 0), (11, 11, 1), (22, 10, 2)]);
                    assert!(samples
                        .iter()
                        .all(|s| s.channel_type_qualifiers == float && s.lower == 0 && s.upper == 0x3F80_0000));
                }
                TexelFormat::E5B9G9R9Ufloat => {
                    assert_eq!(total, 124); // the DF specification's example: 4 + 24 + 6 × 16
                    let layout: Vec<_> = samples
                        .iter()
                        .map(|s| {
                            (
                                s.bit_offset,
                                s.bit_length.get(),
                                s.channel_type,
                                s.channel_type_qualifiers.bits(),
                                s.lower,
                                s.upper,
                            )
                        })
                        .collect();
                    let e = ChannelTypeQualifiers::EXPONENT.bits();
                    assert_eq!(
                        layout,
                        vec![
                            (0, 9, 0, 0, 0, 8448),
                            (27, 5, 0, e, 15, 31),
                            (9, 9, 1, 0, 0, 8448),
                            (27, 5, 1, e, 15, 31),
                            (18, 9, 2, 0, 0, 8448),
                            (27, 5, 2, e, 15, 31)
                        ]
                    );
                }
            }
        }
    }

    #[test]
    fn two_dimensional_tables_read_back() {
        // A 16×8 RG table with two levels (the DFG table has one; a chain checks the sizes).
        let l0: Vec<f32> = (0..16 * 8).flat_map(|i| [i as f32 / 128.0, 1.0 - i as f32 / 128.0]).collect();
        let l1: Vec<f32> = (0..8 * 4).flat_map(|i| [i as f32 / 32.0, 0.5]).collect();
        let texture =
            Texture { shape: TextureShape::Texture2d { width: 16, height: 8 }, channels: 2, levels: vec![&l0, &l1] };
        for format in [TexelFormat::Rg16Float, TexelFormat::Rg32Float] {
            let bytes = encode(&texture, format).unwrap();
            keep(&format!("table-{}.ktx2", format.name()), &bytes);
            let reader = Reader::new(&bytes).unwrap();
            let h = reader.header();
            assert_eq!((h.pixel_width, h.pixel_height, h.face_count, h.level_count), (16, 8, 1, 2));
            let levels: Vec<_> = reader.levels().collect();
            assert_eq!(levels[0].data.len(), 16 * 8 * format.texel_bytes());
            assert_eq!(levels[1].data.len(), 8 * 4 * format.texel_bytes());
            let texels = decode(format, levels[0].data);
            for (i, t) in texels.iter().enumerate() {
                assert!((t[0] - l0[2 * i]).abs() <= 1e-3 && (t[1] - l0[2 * i + 1]).abs() <= 1e-3);
            }
        }
    }

    #[test]
    fn levels_are_padded_to_the_format_alignment() {
        // rgba32f needs 16-byte alignment: a 1×1 level (16 bytes) after an odd-length key/value
        // section must start on a multiple of 16.
        assert_eq!(level_alignment(TexelFormat::Rgba32Float), 16);
        assert_eq!(level_alignment(TexelFormat::Rgba16Float), 8);
        assert_eq!(level_alignment(TexelFormat::E5B9G9R9Ufloat), 4);
        let l0 = vec![1.0f32; 4 * 4 * 4];
        let l1 = vec![2.0f32; 2 * 2 * 4];
        let l2 = vec![3.0f32; 4];
        let texture = Texture {
            shape: TextureShape::Texture2d { width: 4, height: 4 },
            channels: 4,
            levels: vec![&l0, &l1, &l2],
        };
        let bytes = encode(&texture, TexelFormat::Rgba32Float).unwrap();
        let reader = Reader::new(&bytes).unwrap();
        for level in reader.levels() {
            assert_eq!((level.data.as_ptr() as usize - bytes.as_ptr() as usize) % 16, 0);
        }
    }

    #[test]
    fn inconsistent_textures_are_errors() {
        let data = vec![0.0f32; 6 * 4 * 4 * 3];
        let short = vec![0.0f32; 5];
        fn cube(levels: Vec<&[f32]>) -> Texture<'_> {
            Texture { shape: TextureShape::Cube { size: 4 }, channels: 3, levels }
        }
        assert!(matches!(encode(&cube(vec![]), TexelFormat::Rgba16Float), Err(TextureError::Invalid(_))));
        assert!(matches!(encode(&cube(vec![&data, &short]), TexelFormat::Rgba16Float), Err(TextureError::Invalid(_))));
        let too_many = vec![data.as_slice(); 4]; // a 4² base has 3 levels at most
        assert!(matches!(encode(&cube(too_many), TexelFormat::Rgba16Float), Err(TextureError::Invalid(_))));
        assert!(matches!(encode(&cube(vec![&data]), TexelFormat::Rg16Float), Err(TextureError::Format(_))));
    }
}
