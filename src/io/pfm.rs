//! Portable float maps (`PF` colour, `Pf` grey). Rows are stored bottom to top; a negative scale
//! means little-endian.

use super::{IoError, RgbImage};
use crate::limits;
use std::path::Path;

const FORMAT: &str = "PFM";

/// Whether `start` (the first bytes of a file) is the start of a PFM file (`PF` or `Pf`).
pub fn check_magic(start: &[u8]) -> Result<(), String> {
    if start.starts_with(b"PF") || start.starts_with(b"Pf") {
        Ok(())
    } else {
        Err("does not start with \"PF\" or \"Pf\"".into())
    }
}

/// Decodes a PFM file.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<RgbImage, IoError> {
    let bad = |reason: &str| IoError::invalid(path, FORMAT, reason);
    // Header: three whitespace-separated tokens after the magic, then one whitespace byte.
    let mut pos = 0;
    let mut tokens = Vec::new();
    while tokens.len() < 4 {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err(bad("truncated header"));
        }
        tokens.push(std::str::from_utf8(&bytes[start..pos]).map_err(|_| bad("header is not text"))?);
        if pos - start > 32 {
            return Err(bad("header token too long"));
        }
    }
    pos += 1; // the single whitespace byte ending the header
    let channels = match tokens[0] {
        "PF" => 3,
        "Pf" => 1,
        other => return Err(bad(&format!("magic is {other:?}, expected \"PF\" or \"Pf\""))),
    };
    let width: usize = tokens[1].parse().map_err(|_| bad("width is not a number"))?;
    let height: usize = tokens[2].parse().map_err(|_| bad("height is not a number"))?;
    let scale: f32 = tokens[3].parse().map_err(|_| bad("scale is not a number"))?;
    if !(scale.is_finite() && scale != 0.0) {
        return Err(bad("scale must be a non-zero number"));
    }
    limits::check_image("the image", width as u64, height as u64, limits::RGB_BYTES_PER_TEXEL)
        .map_err(|e| bad(&e.to_string()))?;
    let little = scale < 0.0;
    let count =
        width.checked_mul(height).and_then(|n| n.checked_mul(channels * 4)).ok_or_else(|| bad("size overflows"))?;
    let data = bytes.get(pos..).unwrap_or(&[]);
    if data.len() < count {
        return Err(bad(&format!("truncated: {width}x{height} needs {count} bytes of samples, found {}", data.len())));
    }
    let sample = |i: usize| {
        let b = [data[4 * i], data[4 * i + 1], data[4 * i + 2], data[4 * i + 3]];
        if little {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut image = RgbImage::new(width, height);
    for y in 0..height {
        let src_row = height - 1 - y;
        for x in 0..width {
            let i = (src_row * width + x) * channels;
            let px = if channels == 3 { [sample(i), sample(i + 1), sample(i + 2)] } else { [sample(i); 3] };
            image.set(x, y, px);
        }
    }
    Ok(image)
}

/// Encodes a colour PFM (little-endian).
pub fn encode(image: &RgbImage) -> Vec<u8> {
    let mut out = format!("PF\n{} {}\n-1.0\n", image.width, image.height).into_bytes();
    for y in (0..image.height).rev() {
        for px in image.row(y) {
            for c in px {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_keeps_rows_top_down() {
        let img = RgbImage::from_fn(3, 2, |x, y| [x as f32, y as f32, 0.5]);
        let back = decode(Path::new("t.pfm"), &encode(&img)).unwrap();
        assert_eq!(back, img);
    }

    #[test]
    fn truncated_file_is_an_error() {
        let img = RgbImage::new(4, 4);
        let bytes = encode(&img);
        let err = decode(Path::new("t.pfm"), &bytes[..bytes.len() - 5]).unwrap_err().to_string();
        assert!(err.contains("t.pfm") && err.contains("truncated"), "{err}");
    }
}
