//! Radiance RGBE (`.hdr`) reading: flat, old-style and new-style run-length scanlines.
//!
//! Decoding follows Radiance's own `colr_color`: a mantissa m with exponent e means
//! (m + 0.5)·2^(e − 136). (stb_image and others drop the 0.5; the difference is ≤ 0.4 %.)
//! An `EXPOSURE=` line means the pixels were multiplied by it, so values are divided back.

use super::{IoError, RgbImage};
use crate::limits;
use std::path::Path;

const FORMAT: &str = "Radiance HDR";

/// Whether `start` (the first bytes of a file) is the start of a Radiance file (`#?`).
pub fn check_magic(start: &[u8]) -> Result<(), String> {
    if start.starts_with(b"#?") {
        Ok(())
    } else {
        Err("does not start with \"#?\" (\"#?RADIANCE\" or \"#?RGBE\")".into())
    }
}

/// Decodes a Radiance RGBE file.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<RgbImage, IoError> {
    let bad = |reason: String| IoError::invalid(path, FORMAT, reason);
    let mut pos = 0usize;
    let mut line_no = 0usize;
    // The next header line and its 1-based number.
    let mut next_line = |pos: &mut usize| -> Option<(usize, String)> {
        if *pos >= bytes.len() {
            return None;
        }
        let end = bytes[*pos..].iter().position(|&b| b == b'\n').map(|i| *pos + i)?;
        let line = String::from_utf8_lossy(&bytes[*pos..end]).trim_end_matches('\r').to_string();
        *pos = end + 1;
        line_no += 1;
        Some((line_no, line))
    };
    let (_, magic) = next_line(&mut pos).ok_or_else(|| bad("empty file".into()))?;
    if !magic.starts_with("#?") {
        return Err(bad(format!("line 1: expected \"#?RADIANCE\" or \"#?RGBE\", found {magic:?}")));
    }
    let mut exposure = 1.0f64;
    loop {
        let (n, line) =
            next_line(&mut pos).ok_or_else(|| bad("truncated header (no blank line before the resolution)".into()))?;
        if line.is_empty() {
            break;
        }
        if let Some(fmt) = line.strip_prefix("FORMAT=") {
            if fmt.trim() != "32-bit_rle_rgbe" {
                return Err(IoError::unsupported(
                    path,
                    FORMAT,
                    format!("line {n}: pixel format {fmt:?} (only 32-bit_rle_rgbe)"),
                ));
            }
        } else if let Some(e) = line.strip_prefix("EXPOSURE=") {
            let e: f64 = e.trim().parse().map_err(|_| bad(format!("line {n}: bad EXPOSURE line {line:?}")))?;
            if !(e.is_finite() && e > 0.0) {
                return Err(bad(format!("line {n}: bad EXPOSURE value {e}")));
            }
            exposure *= e;
            if !(exposure.is_finite() && exposure > 0.0) {
                return Err(bad(format!("line {n}: the EXPOSURE lines multiply to {exposure}")));
            }
        }
    }
    let (n, res) = next_line(&mut pos).ok_or_else(|| bad("missing resolution line".into()))?;
    let parts: Vec<&str> = res.split_whitespace().collect();
    let (flip_y, height, width) = match parts.as_slice() {
        ["-Y", h, "+X", w] => (false, *h, *w),
        ["+Y", h, "+X", w] => (true, *h, *w),
        _ => {
            return Err(IoError::unsupported(
                path,
                FORMAT,
                format!("line {n}: resolution line {res:?} (only \"-Y H +X W\" and \"+Y H +X W\")"),
            ))
        }
    };
    let height: usize = height.parse().map_err(|_| bad(format!("line {n}: bad height in {res:?}")))?;
    let width: usize = width.parse().map_err(|_| bad(format!("line {n}: bad width in {res:?}")))?;
    if width == 0 || height == 0 {
        return Err(bad(format!("line {n}: the image is empty (zero width or height)")));
    }
    limits::check_image(&format!("the image (line {n})"), width as u64, height as u64, limits::RGB_BYTES_PER_TEXEL)
        .map_err(|e| bad(e.to_string()))?;

    let data = &bytes[pos..];
    let mut cursor = 0usize;
    let mut scan = vec![[0u8; 4]; width];
    // Pixels are appended as scanlines decode (in file order), so a header that promises more
    // than the data holds fails before the whole image is allocated.
    let mut pixels: Vec<[f32; 3]> = Vec::new();
    let scale = 1.0 / exposure;
    for row in 0..height {
        read_scanline(data, &mut cursor, &mut scan)
            .map_err(|reason| bad(format!("scanline {row} of {height}: {reason}")))?;
        pixels.extend(scan.iter().map(|rgbe| rgbe_to_float(*rgbe, scale)));
    }
    let mut image = RgbImage { width, height, pixels };
    if flip_y {
        // "+Y H" stores the bottom row first.
        let rows: Vec<Vec<[f32; 3]>> = image.pixels.chunks(width).rev().map(<[_]>::to_vec).collect();
        image.pixels = rows.concat();
    }
    Ok(image)
}

fn rgbe_to_float([r, g, b, e]: [u8; 4], scale: f64) -> [f32; 3] {
    if e == 0 {
        return [0.0; 3];
    }
    let f = (e as f64 - 136.0).exp2() * scale;
    [((r as f64 + 0.5) * f) as f32, ((g as f64 + 0.5) * f) as f32, ((b as f64 + 0.5) * f) as f32]
}

fn take<'a>(data: &'a [u8], cursor: &mut usize, n: usize) -> Result<&'a [u8], String> {
    let s = data.get(*cursor..*cursor + n).ok_or("truncated pixel data")?;
    *cursor += n;
    Ok(s)
}

fn read_scanline(data: &[u8], cursor: &mut usize, scan: &mut [[u8; 4]]) -> Result<(), String> {
    let width = scan.len();
    let head = data.get(*cursor..*cursor + 4).ok_or("truncated pixel data")?;
    let new_rle = (8..0x8000).contains(&width) && head[0] == 2 && head[1] == 2 && head[2] & 0x80 == 0;
    if new_rle {
        let encoded_width = ((head[2] as usize) << 8) | head[3] as usize;
        if encoded_width != width {
            return Err(format!("run-length width {encoded_width} differs from image width {width}"));
        }
        *cursor += 4;
        for channel in 0..4 {
            let mut x = 0;
            while x < width {
                let count = take(data, cursor, 1)?[0] as usize;
                if count > 128 {
                    let run = count - 128;
                    if x + run > width {
                        return Err("run overflows the scanline".into());
                    }
                    let value = take(data, cursor, 1)?[0];
                    for px in &mut scan[x..x + run] {
                        px[channel] = value;
                    }
                    x += run;
                } else {
                    if count == 0 || x + count > width {
                        return Err("bad literal count".into());
                    }
                    let values = take(data, cursor, count)?;
                    for (px, &v) in scan[x..x + count].iter_mut().zip(values) {
                        px[channel] = v;
                    }
                    x += count;
                }
            }
        }
        return Ok(());
    }
    // Flat pixels, possibly with old-style runs (1,1,1,n repeats the previous pixel n << shift times).
    let mut x = 0;
    let mut shift = 0;
    while x < width {
        let p = take(data, cursor, 4)?;
        if p[0] == 1 && p[1] == 1 && p[2] == 1 {
            if x == 0 {
                return Err("run with no previous pixel".into());
            }
            let run = (p[3] as usize) << shift;
            if x + run > width {
                return Err("run overflows the scanline".into());
            }
            let prev = scan[x - 1];
            for px in &mut scan[x..x + run] {
                *px = prev;
            }
            x += run;
            shift += 8;
        } else {
            scan[x] = [p[0], p[1], p[2], p[3]];
            x += 1;
            shift = 0;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(w: usize, h: usize) -> Vec<u8> {
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n").into_bytes()
    }

    #[test]
    fn flat_pixels_decode_with_radiance_rounding() {
        let mut bytes = header(2, 1);
        bytes.extend_from_slice(&[128, 64, 0, 129, 0, 0, 0, 0]);
        let img = decode(Path::new("t.hdr"), &bytes).unwrap();
        // e = 129 → 2^(129-136) = 1/128; (128 + 0.5)/128.
        assert_eq!(img.get(0, 0), [128.5 / 128.0, 64.5 / 128.0, 0.5 / 128.0]);
        assert_eq!(img.get(1, 0), [0.0; 3]);
    }

    #[test]
    fn new_rle_scanline() {
        let mut bytes = header(8, 1);
        bytes.extend_from_slice(&[2, 2, 0, 8]);
        for value in [10u8, 20, 30, 128] {
            bytes.extend_from_slice(&[128 + 8, value]);
        }
        let img = decode(Path::new("t.hdr"), &bytes).unwrap();
        for x in 0..8 {
            assert_eq!(img.get(x, 0), [10.5 / 256.0, 20.5 / 256.0, 30.5 / 256.0]);
        }
    }

    #[test]
    fn truncation_names_the_scanline() {
        let mut bytes = header(2, 2);
        bytes.extend_from_slice(&[128, 64, 0, 129]);
        let err = decode(Path::new("t.hdr"), &bytes).unwrap_err().to_string();
        assert!(err.contains("t.hdr") && err.contains("scanline 0"), "{err}");
    }
}
