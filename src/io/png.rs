//! Tone-mapped 8-bit PNG previews: linear × 2^exposure, clamped, sRGB-encoded.

use super::{IoError, RgbImage};
use std::path::Path;

/// The sRGB transfer function (IEC 61966-2-1) for a linear value in [0, 1].
pub fn srgb_encode(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`srgb_encode`] (IEC 61966-2-1): the linear value of an sRGB-encoded value in
/// [0, 1] (an 8-bit code over 255). Base colours read from meshes (`Mesh::load_coloured`) go
/// through it: glTF's base-colour textures (glTF 2.0 §3.9.2) and a PLY's 8-bit vertex colours.
pub fn srgb_decode(encoded: f64) -> f64 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

/// Converts a linear HDR image to 8-bit sRGB bytes (RGB, row-major).
pub fn tonemap_to_srgb8(image: &RgbImage, exposure: f32) -> Vec<u8> {
    let gain = exposure.exp2();
    let mut out = Vec::with_capacity(image.pixels.len() * 3);
    for px in &image.pixels {
        for &c in px {
            let v = if c.is_finite() { (c * gain).clamp(0.0, 1.0) } else { 0.0 };
            out.push((srgb_encode(v) * 255.0 + 0.5) as u8);
        }
    }
    out
}

/// Encodes a tone-mapped PNG in memory.
pub fn encode_png(image: &RgbImage, exposure: f32) -> Result<Vec<u8>, String> {
    let bytes = tonemap_to_srgb8(image, exposure);
    let mut out = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut out);
    image::ImageEncoder::write_image(
        encoder,
        &bytes,
        image.width as u32,
        image.height as u32,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| e.to_string())?;
    Ok(out)
}

/// Writes a tone-mapped PNG atomically.
pub fn write_tonemapped(path: &Path, image: &RgbImage, exposure: f32) -> Result<(), IoError> {
    let bytes = encode_png(image, exposure).map_err(|e| IoError::invalid(path, "PNG", e))?;
    super::write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_curve_end_points_and_mid_grey() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        // 18 % grey encodes to about 46 % (118/255).
        assert!((srgb_encode(0.18) * 255.0 - 118.0).abs() < 1.0);
    }

    #[test]
    fn srgb_decode_inverts_the_encoding() {
        assert_eq!(srgb_decode(0.0), 0.0);
        assert!((srgb_decode(1.0) - 1.0).abs() < 1e-15);
        // The two pieces meet at the breakpoint: 0.04045 / 12.92 = ((0.04045 + 0.055) / 1.055)^2.4
        // to 1e-7 (IEC 61966-2-1's constants are rounded).
        assert!((0.04045 / 12.92 - ((0.04045f64 + 0.055) / 1.055).powf(2.4)).abs() < 1e-7);
        for k in 0..=255 {
            let c = k as f64 / 255.0;
            let back = srgb_encode(srgb_decode(c) as f32) as f64;
            assert!((back - c).abs() < 1e-5, "{k}: {back}");
        }
    }
}
