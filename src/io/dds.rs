//! DDS writer for uncompressed HDR textures with the DX10 extension header: 2-D textures and cube
//! maps with mip chains (Microsoft, "DDS programming guide": `DDS_HEADER`, `DDS_PIXELFORMAT`,
//! `DDS_HEADER_DXT10`).
//!
//! Layout: the magic `DDS `, the 124-byte `DDS_HEADER` (flags CAPS | HEIGHT | WIDTH | PITCH |
//! PIXELFORMAT | MIPMAPCOUNT, pitch = width × texel bytes), a pixel format with the FourCC `DX10`,
//! then `DDS_HEADER_DXT10` (the DXGI format, `D3D10_RESOURCE_DIMENSION_TEXTURE2D`,
//! `DDS_RESOURCE_MISC_TEXTURECUBE` for cubes, array size 1). Cubes also set
//! `DDSCAPS2_CUBEMAP | DDSCAPS2_CUBEMAP_ALLFACES` for older readers. Unlike KTX2, DDS stores
//! **each face with all its mips** before the next face (+X, −X, +Y, −Y, +Z, −Z), largest level
//! first, rows top to bottom, no padding.

use super::gpu_format::{TexelFormat, Texture, TextureError, TextureShape};

/// `DDS ` as a little-endian u32.
const MAGIC: u32 = 0x2053_4444;
const DDSD_CAPS: u32 = 0x1;
const DDSD_HEIGHT: u32 = 0x2;
const DDSD_WIDTH: u32 = 0x4;
const DDSD_PITCH: u32 = 0x8;
const DDSD_PIXELFORMAT: u32 = 0x1000;
const DDSD_MIPMAPCOUNT: u32 = 0x2_0000;
const DDPF_FOURCC: u32 = 0x4;
const DDSCAPS_COMPLEX: u32 = 0x8;
const DDSCAPS_TEXTURE: u32 = 0x1000;
const DDSCAPS_MIPMAP: u32 = 0x40_0000;
/// DDSCAPS2_CUBEMAP and the six DDSCAPS2_CUBEMAP_{POSITIVE,NEGATIVE}{X,Y,Z} bits.
const DDSCAPS2_CUBEMAP_ALLFACES: u32 = 0x200 | 0xFC00;
const D3D10_RESOURCE_DIMENSION_TEXTURE2D: u32 = 3;
const DDS_RESOURCE_MISC_TEXTURECUBE: u32 = 0x4;

/// Size of the magic and both headers: 4 + 124 + 20.
pub const HEADER_BYTES: usize = 148;

/// Encodes a texture as a DDS file in `format`.
pub fn encode(texture: &Texture, format: TexelFormat) -> Result<Vec<u8>, TextureError> {
    texture.check()?;
    let (w, h, faces) = texture.shape.dimensions();
    let levels = texture.levels.len();
    let cube = matches!(texture.shape, TextureShape::Cube { .. });
    let images = (0..levels).map(|p| texture.encode_level(p, format)).collect::<Result<Vec<_>, _>>()?;

    let mut header = [0u32; 31]; // DDS_HEADER as 31 little-endian words
    header[0] = 124;
    header[1] = DDSD_CAPS | DDSD_HEIGHT | DDSD_WIDTH | DDSD_PITCH | DDSD_PIXELFORMAT | DDSD_MIPMAPCOUNT;
    header[2] = h as u32;
    header[3] = w as u32;
    header[4] = (w * format.texel_bytes()) as u32; // pitch of the top level
    header[5] = 0; // depth
    header[6] = levels as u32;
    // header[7..18]: reserved. DDS_PIXELFORMAT at words 18..26.
    header[18] = 32;
    header[19] = DDPF_FOURCC;
    header[20] = u32::from_le_bytes(*b"DX10");
    let complex = levels > 1 || cube;
    header[26] =
        DDSCAPS_TEXTURE | if complex { DDSCAPS_COMPLEX } else { 0 } | if levels > 1 { DDSCAPS_MIPMAP } else { 0 };
    header[27] = if cube { DDSCAPS2_CUBEMAP_ALLFACES } else { 0 };

    let dx10 = [
        format.dxgi_format(),
        D3D10_RESOURCE_DIMENSION_TEXTURE2D,
        if cube { DDS_RESOURCE_MISC_TEXTURECUBE } else { 0 },
        1, // one texture (or one cube of six faces)
        0, // DDS_ALPHA_MODE_UNKNOWN
    ];

    let mut out = Vec::with_capacity(HEADER_BYTES + images.iter().map(Vec::len).sum::<usize>());
    out.extend_from_slice(&MAGIC.to_le_bytes());
    for word in header.iter().chain(dx10.iter()) {
        out.extend_from_slice(&word.to_le_bytes());
    }
    for face in 0..faces {
        for image in &images {
            let face_bytes = image.len() / faces;
            out.extend_from_slice(&image[face * face_bytes..(face + 1) * face_bytes]);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ddsfile::{Caps2, D3D10ResourceDimension, Dds, DxgiFormat, MiscFlag};

    #[test]
    fn cube_with_mips_parses_back() {
        // Level p, face f, texel i holds (p, f, i): check every face/level lands where DDS puts it.
        let levels: Vec<Vec<f32>> = (0..4)
            .map(|p| {
                let n = 8usize >> p;
                (0..6 * n * n).flat_map(|i| [p as f32, (i / (n * n)) as f32, (i % (n * n)) as f32]).collect()
            })
            .collect();
        let texture = Texture {
            shape: TextureShape::Cube { size: 8 },
            channels: 3,
            levels: levels.iter().map(|l| l.as_slice()).collect(),
        };
        for (format, dxgi) in [
            (TexelFormat::Rgba16Float, DxgiFormat::R16G16B16A16_Float),
            (TexelFormat::Rgba32Float, DxgiFormat::R32G32B32A32_Float),
            (TexelFormat::B10G11R11Ufloat, DxgiFormat::R11G11B10_Float),
            (TexelFormat::E5B9G9R9Ufloat, DxgiFormat::R9G9B9E5_SharedExp),
        ] {
            let bytes = encode(&texture, format).unwrap();
            let dds = Dds::read(&bytes[..]).unwrap();
            assert_eq!((dds.get_width(), dds.get_height(), dds.get_num_mipmap_levels()), (8, 8, 4));
            assert_eq!(dds.get_dxgi_format(), Some(dxgi));
            assert!(dds.header.caps2.contains(Caps2::CUBEMAP | Caps2::CUBEMAP_ALLFACES));
            let h10 = dds.header10.as_ref().unwrap();
            assert_eq!(h10.resource_dimension, D3D10ResourceDimension::Texture2D);
            assert!(h10.misc_flag.contains(MiscFlag::TEXTURECUBE));
            assert_eq!(h10.array_size, 1);
            assert_eq!(dds.header.pitch, Some(8 * format.texel_bytes() as u32));
            // Six faces × (8² + 4² + 2² + 1²) texels, nothing more.
            let per_face = (64 + 16 + 4 + 1) * format.texel_bytes();
            assert_eq!(dds.data.len(), 6 * per_face);
            assert_eq!(bytes.len(), HEADER_BYTES + 6 * per_face);
            // Face f starts at f × per_face, and within it level p after the larger levels.
            for f in 0..6 {
                let mut offset = f * per_face;
                for p in 0..4 {
                    let n = 8usize >> p;
                    let first = &dds.data[offset..offset + format.texel_bytes()];
                    let mut want = Vec::new();
                    format.encode(&[p as f32, f as f32, 0.0], 3, &mut want).unwrap();
                    assert_eq!(first, &want[..], "{format:?} face {f} level {p}");
                    offset += n * n * format.texel_bytes();
                }
            }
        }
    }

    #[test]
    fn two_dimensional_table_parses_back() {
        let data: Vec<f32> = (0..32 * 32).flat_map(|i| [i as f32 / 1024.0, 0.5]).collect();
        let texture =
            Texture { shape: TextureShape::Texture2d { width: 32, height: 32 }, channels: 2, levels: vec![&data] };
        let bytes = encode(&texture, TexelFormat::Rg16Float).unwrap();
        let dds = Dds::read(&bytes[..]).unwrap();
        assert_eq!((dds.get_width(), dds.get_height(), dds.get_num_mipmap_levels()), (32, 32, 1));
        assert_eq!(dds.get_dxgi_format(), Some(DxgiFormat::R16G16_Float));
        assert!(!dds.header.caps2.contains(Caps2::CUBEMAP));
        assert_eq!(dds.data.len(), 32 * 32 * 4);
    }
}
