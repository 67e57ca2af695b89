//! The in-memory HDR image every stage passes around, and reading by file extension.

use super::IoError;
use crate::limits;
use std::path::Path;

/// A linear RGB float image, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width * height` pixels, row by row from the top.
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    /// A black image.
    pub fn new(width: usize, height: usize) -> Self {
        RgbImage { width, height, pixels: vec![[0.0; 3]; width * height] }
    }

    /// Builds an image from a per-pixel function of (column, row).
    pub fn from_fn(width: usize, height: usize, f: impl Fn(usize, usize) -> [f32; 3]) -> Self {
        let mut pixels = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                pixels.push(f(x, y));
            }
        }
        RgbImage { width, height, pixels }
    }

    /// The pixel at column `x`, row `y`.
    #[inline]
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        self.pixels[y * self.width + x]
    }

    /// Sets the pixel at column `x`, row `y`.
    #[inline]
    pub fn set(&mut self, x: usize, y: usize, v: [f32; 3]) {
        self.pixels[y * self.width + x] = v;
    }

    /// One row of pixels.
    pub fn row(&self, y: usize) -> &[[f32; 3]] {
        &self.pixels[y * self.width..(y + 1) * self.width]
    }
}

/// Image file formats prtkit reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// OpenEXR.
    Exr,
    /// Radiance RGBE (`.hdr`, `.pic`).
    Rgbe,
    /// Portable float map.
    Pfm,
}

impl ImageFormat {
    /// The format named by a file's extension.
    pub fn from_path(path: &Path) -> Option<ImageFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "exr" => Some(ImageFormat::Exr),
            "hdr" | "pic" | "rgbe" => Some(ImageFormat::Rgbe),
            "pfm" => Some(ImageFormat::Pfm),
            _ => None,
        }
    }
}

/// A check of the first bytes of a file.
type StartCheck = fn(&[u8]) -> Result<(), String>;

/// Reads an HDR image (EXR, Radiance `.hdr`, PFM), chosen by extension (`-`, standard input,
/// by its signature). The input is refused at once when it does not start like its format, and
/// read only up to [`limits::max_file_bytes`]; sizes in its header are checked against the image
/// ceilings before pixels are allocated (`docs/limits.md`).
pub fn read_image(path: &Path) -> Result<RgbImage, IoError> {
    let (name, check_start): (&'static str, StartCheck) = if super::read::is_stdin(path) {
        ("image", |start| match ImageFormat::sniff(start) {
            Some(_) => Ok(()),
            None => Err("does not start like an EXR, Radiance HDR or PFM file".into()),
        })
    } else {
        match ImageFormat::from_path(path) {
            Some(ImageFormat::Exr) => ("OpenEXR", super::exr::check_magic),
            Some(ImageFormat::Rgbe) => ("Radiance HDR", super::rgbe::check_magic),
            Some(ImageFormat::Pfm) => ("PFM", super::pfm::check_magic),
            None => return Err(IoError::UnknownFormat { path: path.to_path_buf(), extra: "" }),
        }
    };
    let bytes = super::read_bytes(path, name, limits::max_file_bytes(), check_start)?;
    decode_image(&super::read::display_path(path), &bytes)
}

/// Writes an image by extension: `.exr` (float), `.pfm`, or `.png` (tone-mapped with `exposure`
/// stops and the sRGB curve).
pub fn write_image(path: &Path, image: &RgbImage, exposure: f32) -> Result<(), IoError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("exr") => super::exr::write_rgb(path, image),
        Some("pfm") => super::write_atomic(path, &super::pfm::encode(image)),
        Some("png") => super::png::write_tonemapped(path, image, exposure),
        _ => Err(IoError::UnknownFormat { path: path.to_path_buf(), extra: ", .png" }),
    }
}

impl ImageFormat {
    /// The format whose signature starts `bytes`: OpenEXR's magic number, Radiance's `#?`,
    /// PFM's `PF`/`Pf`. Used for standard input, which has no file name.
    pub fn sniff(bytes: &[u8]) -> Option<ImageFormat> {
        match bytes {
            [0x76, 0x2f, 0x31, 0x01, ..] => Some(ImageFormat::Exr),
            [b'#', b'?', ..] => Some(ImageFormat::Rgbe),
            [b'P', b'F' | b'f', b'\n' | b'\r' | b' ' | b'\t', ..] => Some(ImageFormat::Pfm),
            _ => None,
        }
    }
}

/// Decodes an HDR image held in memory; `name` is used in messages and, when it has an image
/// extension, chooses the format (else the bytes' signature does, as for standard input).
pub fn decode_image(name: &Path, bytes: &[u8]) -> Result<RgbImage, IoError> {
    let format = ImageFormat::from_path(name)
        .or_else(|| ImageFormat::sniff(bytes))
        .ok_or_else(|| IoError::UnknownFormat { path: name.to_path_buf(), extra: "" })?;
    let image = match format {
        ImageFormat::Exr => super::exr::decode(name, bytes)?,
        ImageFormat::Rgbe => super::rgbe::decode(name, bytes)?,
        ImageFormat::Pfm => super::pfm::decode(name, bytes)?,
    };
    if image.width == 0 || image.height == 0 {
        return Err(IoError::invalid(name, "image", "the image is empty (zero width or height)"));
    }
    Ok(image)
}

/// Encodes an image for a file named `path`, by its extension: `.exr` (float), `.pfm`, or
/// `.png` (tone-mapped with `exposure` stops and the sRGB curve).
pub fn encode_image(path: &Path, image: &RgbImage, exposure: f32) -> Result<Vec<u8>, IoError> {
    let ext = path.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    let fail = |e: String| IoError::invalid(path, "image", e);
    match ext.as_deref() {
        Some("exr") => super::exr::encode_layers(&[("", image)]).map_err(fail),
        Some("pfm") => Ok(super::pfm::encode(image)),
        Some("png") => super::png::encode_png(image, exposure).map_err(fail),
        _ => Err(IoError::UnknownFormat { path: path.to_path_buf(), extra: ", .png" }),
    }
}
