//! OpenEXR reading (half/float/uint, RGB/RGBA/Y, scanline or tiled, any compression — via the
//! `exr` crate) and float writing with several named RGB (or grey) layers in one file.
//!
//! Layers follow the usual EXR naming: channels `R`, `G`, `B` form the unnamed layer, channels
//! `name.R`, `name.G`, `name.B` the layer `name`; in multi-part files the part name is a prefix.

use super::{IoError, RgbImage};
use crate::limits;
use exr::prelude::{
    read, AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, ReadChannels, ReadLayers,
    WritableImage,
};
use rayon::prelude::*;
use std::io::Cursor;
use std::path::Path;

const FORMAT: &str = "OpenEXR";

/// The first four bytes of every OpenEXR file.
pub const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// Reads an EXR file (at most [`limits::max_file_bytes`], refused at once when it does not
/// start like one) and decodes every RGB or grey layer, as [`decode_layers`].
pub fn read_layers(path: &Path) -> Result<Vec<(String, RgbImage)>, IoError> {
    let bytes = super::read_bytes(path, FORMAT, limits::max_file_bytes(), check_magic)?;
    decode_layers(path, &bytes)
}

/// Whether `start` (the first bytes of a file) is the start of an EXR file.
pub fn check_magic(start: &[u8]) -> Result<(), String> {
    if start.starts_with(&MAGIC) {
        Ok(())
    } else {
        Err(format!(
            "does not start with the OpenEXR magic number 76 2f 31 01 (found {:02x?})",
            &start[..start.len().min(4)]
        ))
    }
}

/// Decodes the main RGB layer of an EXR file: the unnamed layer if there is one, else the first.
/// A file with only `Y` (or a single channel) is read as grey.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<RgbImage, IoError> {
    let mut layers = decode_layers(path, bytes)?;
    let index = layers.iter().position(|(name, _)| name.is_empty()).unwrap_or(0);
    Ok(layers.swap_remove(index).1)
}

fn exr_error(path: &Path, e: exr::error::Error) -> IoError {
    match e {
        exr::error::Error::NotSupported(what) => IoError::unsupported(path, FORMAT, what.to_string()),
        other => IoError::invalid(path, FORMAT, other.to_string()),
    }
}

/// Which RGB (or grey) layer a channel belongs to, and its slot (0–2 for R, G, B; 3 for Y):
/// channel `R` of part `""` is layer `""`, `coef.R` is layer `coef`, and in a part named `p`
/// they are `p` and `p.coef`. `None` for other channels (alpha, depth, …).
fn layer_slot(part: &str, channel: &str) -> Option<(String, usize)> {
    let (prefix, base) = match channel.rfind('.') {
        Some(i) => (&channel[..i], &channel[i + 1..]),
        None => ("", channel),
    };
    let slot = match base.to_ascii_uppercase().as_str() {
        "R" => 0,
        "G" => 1,
        "B" => 2,
        "Y" => 3,
        _ => return None,
    };
    let layer = match (part.is_empty(), prefix.is_empty()) {
        (true, _) => prefix.to_string(),
        (false, true) => part.to_string(),
        (false, false) => format!("{part}.{prefix}"),
    };
    Some((layer, slot))
}

/// Reads the headers alone and checks every part's data window against the image ceilings
/// (`docs/limits.md`) and the memory decoding takes — the `exr` crate's samples of every
/// channel plus prtkit's RGB pixels per layer — against the budget, before any pixel is
/// allocated (a data window patched to 100000×100000 would ask for tens of GB).
fn check_size(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(|e| exr_error(path, e))?;
    let too_large = |e: limits::LimitError| IoError::invalid(path, FORMAT, e.to_string());
    let mut need: u128 = 0;
    for (i, header) in meta.headers.iter().enumerate() {
        let (w, h) = (header.layer_size.0 as u64, header.layer_size.1 as u64);
        let what = if meta.headers.len() == 1 {
            "the data window".to_string()
        } else {
            format!("the data window of part {i}")
        };
        limits::check_image(&what, w, h, 0).map_err(too_large)?;
        let part = header.own_attributes.layer_name.as_ref().map(|t| t.to_string()).unwrap_or_default();
        let mut layers: Vec<String> = Vec::new();
        let mut sample_bytes = 0u64;
        for c in &header.channels.list {
            sample_bytes += if c.sample_type == exr::meta::attribute::SampleType::F16 { 2 } else { 4 };
            if let Some((layer, _)) = layer_slot(&part, &c.name.to_string()) {
                if !layers.contains(&layer) {
                    layers.push(layer);
                }
            }
        }
        let per_texel = sample_bytes + limits::RGB_BYTES_PER_TEXEL * layers.len().max(1) as u64;
        need += w as u128 * h as u128 * per_texel as u128;
    }
    limits::check_memory("decoding the EXR", need).map_err(too_large)
}

/// Decodes every RGB (or grey) layer in an EXR file as `(name, image)`, in file order. The
/// sizes in the headers are checked against the ceilings first (`docs/limits.md`).
pub fn decode_layers(path: &Path, bytes: &[u8]) -> Result<Vec<(String, RgbImage)>, IoError> {
    check_size(path, bytes)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| exr_error(path, e))?;

    let mut out: Vec<(String, RgbImage)> = Vec::new();
    for layer in &image.layer_data {
        let (width, height) = (layer.size.0, layer.size.1);
        let part = layer.attributes.layer_name.as_ref().map(|t| t.to_string()).unwrap_or_default();
        // Group this part's channels into layers.
        let mut groups: Vec<(String, [Option<&FlatSamples>; 4])> = Vec::new();
        for channel in &layer.channel_data.list {
            let Some((full, slot)) = layer_slot(&part, &channel.name.to_string()) else { continue };
            match groups.iter_mut().find(|(n, _)| *n == full) {
                Some((_, slots)) => slots[slot] = Some(&channel.sample_data),
                None => {
                    let mut slots = [None; 4];
                    slots[slot] = Some(&channel.sample_data);
                    groups.push((full, slots));
                }
            }
        }
        if groups.is_empty() && layer.channel_data.list.len() == 1 {
            groups.push((part.clone(), [None, None, None, Some(&layer.channel_data.list[0].sample_data)]));
        }
        for (name, slots) in groups {
            let channels: [&FlatSamples; 3] = match slots {
                [Some(r), Some(g), Some(b), _] => [r, g, b],
                [_, _, _, Some(y)] => [y, y, y],
                _ => continue, // an incomplete colour layer (e.g. only R): not an RGB image
            };
            if channels.iter().any(|c| c.len() != width * height) {
                return Err(IoError::invalid(path, FORMAT, "channel sizes do not match the data window"));
            }
            out.push((name, interleave(width, height, channels)));
        }
    }
    if out.is_empty() {
        return Err(IoError::unsupported(path, FORMAT, "no R,G,B or Y channels found"));
    }
    Ok(out)
}

/// Three channels of `width` × `height` samples as RGB pixels, row by row in parallel, each
/// channel's sample type matched once per row (`FlatSamples::values_as_f32` matches it per
/// sample).
fn interleave(width: usize, height: usize, channels: [&FlatSamples; 3]) -> RgbImage {
    let mut pixels = vec![[0.0f32; 3]; width * height];
    pixels.par_chunks_mut(width.max(1)).enumerate().for_each(|(y, row)| {
        let columns = y * width..(y + 1) * width;
        for (c, channel) in channels.iter().enumerate() {
            let texels = row.iter_mut();
            match channel {
                FlatSamples::F16(v) => texels.zip(&v[columns.clone()]).for_each(|(p, s)| p[c] = s.to_f32()),
                FlatSamples::F32(v) => texels.zip(&v[columns.clone()]).for_each(|(p, s)| p[c] = *s),
                FlatSamples::U32(v) => texels.zip(&v[columns.clone()]).for_each(|(p, s)| p[c] = *s as f32),
            }
        }
    });
    RgbImage { width, height, pixels }
}

/// Encodes float RGB layers of equal size into one EXR (ZIP-compressed, single part). The layer
/// named `""` gets the plain channel names `R`, `G`, `B`.
pub fn encode_layers(layers: &[(&str, &RgbImage)]) -> Result<Vec<u8>, String> {
    let first = layers.first().ok_or("no layers to write")?.1;
    let (width, height) = (first.width, first.height);
    let mut channels = Vec::with_capacity(layers.len() * 3);
    for (name, image) in layers {
        if (image.width, image.height) != (width, height) {
            return Err(format!("layer {name:?} is {}x{}, expected {width}x{height}", image.width, image.height));
        }
        for (c, letter) in ["R", "G", "B"].iter().enumerate() {
            channels.push(channel(name, letter, image.pixels.iter().map(|p| p[c]).collect())?);
        }
    }
    encode_channels((width, height), channels)
}

/// Encodes float grey layers (channel `name.Y`, or `Y` for `""`) of `width`×`height` samples
/// each, row-major, into one EXR. They read back through [`decode_layers`] as grey images.
pub fn encode_grey_layers(width: usize, height: usize, layers: &[(&str, &[f32])]) -> Result<Vec<u8>, String> {
    let named: Vec<(&str, &str, &[f32])> = layers.iter().map(|&(name, samples)| (name, "Y", samples)).collect();
    encode_named_channels(width, height, &named)
}

/// Encodes float channels `layer.letter` (`R`, `G`, `B` or `Y`; `letter` alone for layer `""`)
/// of `width`×`height` samples each, row-major, into one EXR: grey and colour layers side by
/// side. They read back through [`decode_layers`].
pub fn encode_named_channels(
    width: usize,
    height: usize,
    channels: &[(&str, &str, &[f32])],
) -> Result<Vec<u8>, String> {
    if channels.is_empty() {
        return Err("no layers to write".into());
    }
    let mut out = Vec::with_capacity(channels.len());
    for (name, letter, samples) in channels {
        if samples.len() != width * height {
            return Err(format!("layer {name:?} has {} samples, expected {width}x{height}", samples.len()));
        }
        out.push(channel(name, letter, samples.to_vec())?);
    }
    encode_channels((width, height), out)
}

fn channel(layer: &str, letter: &str, samples: Vec<f32>) -> Result<AnyChannel<FlatSamples>, String> {
    let channel_name = if layer.is_empty() { letter.to_string() } else { format!("{layer}.{letter}") };
    let text = exr::prelude::Text::new_or_none(&channel_name)
        .ok_or_else(|| format!("layer name {layer:?} cannot be stored in EXR"))?;
    Ok(AnyChannel::new(text, FlatSamples::F32(samples)))
}

fn encode_channels(size: (usize, usize), channels: Vec<AnyChannel<FlatSamples>>) -> Result<Vec<u8>, String> {
    let layer =
        Layer::new(size, LayerAttributes::default(), Encoding::SMALL_LOSSLESS, AnyChannels::sort(channels.into()));
    let image = Image::from_layer(layer);
    let mut bytes = Vec::new();
    image.write().non_parallel().to_buffered(Cursor::new(&mut bytes)).map_err(|e| e.to_string())?;
    Ok(bytes)
}

/// Writes one float RGB image as EXR, atomically.
pub fn write_rgb(path: &Path, image: &RgbImage) -> Result<(), IoError> {
    write_layers(path, &[("", image)])
}

/// Writes several named grey layers as one EXR, atomically (see [`encode_grey_layers`]).
pub fn write_grey_layers(path: &Path, width: usize, height: usize, layers: &[(&str, &[f32])]) -> Result<(), IoError> {
    let bytes = encode_grey_layers(width, height, layers).map_err(|e| IoError::invalid(path, FORMAT, e))?;
    super::write_atomic(path, &bytes)
}

/// Writes several named RGB layers as one EXR, atomically.
pub fn write_layers(path: &Path, layers: &[(&str, &RgbImage)]) -> Result<(), IoError> {
    let bytes = encode_layers(layers).map_err(|e| IoError::invalid(path, FORMAT, e))?;
    super::write_atomic(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layers_round_trip_bit_exactly() {
        let a = RgbImage::from_fn(5, 3, |x, y| [x as f32 * 0.25, y as f32, 1e-7]);
        let b = RgbImage::from_fn(5, 3, |x, y| [-(x as f32), 3.5e4, (x + y) as f32]);
        let bytes = encode_layers(&[("", &a), ("coef.7", &b)]).unwrap();
        let layers = decode_layers(Path::new("t.exr"), &bytes).unwrap();
        assert_eq!(layers.len(), 2);
        let find = |n: &str| &layers.iter().find(|(name, _)| name == n).unwrap().1;
        assert_eq!(find(""), &a);
        assert_eq!(find("coef.7"), &b);
        assert_eq!(decode(Path::new("t.exr"), &bytes).unwrap(), a);
    }

    #[test]
    fn grey_layers_round_trip_bit_exactly() {
        let g: Vec<f32> = (0..12).map(|i| i as f32 * -0.37 + 1e-6).collect();
        let h: Vec<f32> = (0..12).map(|i| (i * i) as f32).collect();
        let bytes = encode_grey_layers(4, 3, &[("g", &g), ("h", &h)]).unwrap();
        let layers = decode_layers(Path::new("t.exr"), &bytes).unwrap();
        for (name, want) in [("g", &g), ("h", &h)] {
            let img = &layers.iter().find(|(n, _)| n == name).unwrap().1;
            assert_eq!((img.width, img.height), (4, 3));
            let got: Vec<f32> = img.pixels.iter().map(|p| p[0]).collect();
            assert_eq!(&got, want);
        }
        assert!(encode_grey_layers(4, 4, &[("g", &g)]).is_err(), "a size mismatch is an error");
    }

    /// Half, float and unsigned-integer channels each read as the value they hold: R stored as
    /// f16, G as f32, B as u32, over several rows (the pixels are filled row by row).
    #[test]
    fn every_sample_type_reads_as_its_value() {
        let (w, h) = (7, 5);
        let reds: Vec<f32> = (0..w * h).map(|i| i as f32 * 0.5 - 3.0).collect();
        let greens: Vec<f32> = (0..w * h).map(|i| (i as f32).sqrt() * 1e-3).collect();
        let blues: Vec<u32> = (0..w * h).map(|i| (i * 977) as u32).collect();
        let samples = [
            ("R", FlatSamples::F16(reds.iter().map(|&v| exr::prelude::f16::from_f32(v)).collect())),
            ("G", FlatSamples::F32(greens.clone())),
            ("B", FlatSamples::U32(blues.clone())),
        ];
        let channels = samples.map(|(name, data)| AnyChannel::new(exr::prelude::Text::from(name), data));
        let bytes = encode_channels((w, h), channels.into_iter().collect()).unwrap();
        let image = decode(Path::new("t.exr"), &bytes).unwrap();
        assert_eq!((image.width, image.height), (w, h));
        for (i, p) in image.pixels.iter().enumerate() {
            // The reds are multiples of 0.5 below 2048: exact in f16.
            assert_eq!(*p, [reds[i], greens[i], blues[i] as f32], "texel {i}");
        }
    }

    #[test]
    fn encoding_is_deterministic() {
        let a = RgbImage::from_fn(64, 64, |x, y| [(x * y) as f32 * 0.1, x as f32, y as f32]);
        assert_eq!(encode_layers(&[("", &a)]).unwrap(), encode_layers(&[("", &a)]).unwrap());
    }

    #[test]
    fn garbage_is_an_error_naming_the_file() {
        let err = decode(Path::new("bad.exr"), b"not an exr file at all").unwrap_err().to_string();
        assert!(err.contains("bad.exr"), "{err}");
    }
}
