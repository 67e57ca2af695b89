//! Reading an environment map from a file, a directory of six faces or bytes (standard input),
//! with the bad-pixel policy every stage shares: NaN and ±Inf are always an error, negative
//! radiance per [`NegativePolicy`].

use super::{EnvMap, EnvMapError, Layout, Orientation, FACES};
use crate::io::{self, IoError, RgbImage};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// What to do with negative pixel components (NaN and ±Inf are always an error).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NegativePolicy {
    /// Refuse the file, naming the first negative pixel.
    #[default]
    Error,
    /// Replace negative components by 0 (and count them).
    Clamp,
    /// Keep them (valid for signed data such as SH reconstructions).
    Keep,
}

/// How to read a map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// The layout, or `None` to detect it from the aspect ratio (a directory is six faces).
    pub layout: Option<Layout>,
    /// The negative-pixel policy.
    pub negative: NegativePolicy,
    /// How the map is turned on reading.
    pub orientation: Orientation,
}

/// A map read, with what the policy did to it.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The map.
    pub map: EnvMap,
    /// Negative components replaced by 0 under [`NegativePolicy::Clamp`].
    pub clamped: usize,
}

/// Why a pixel is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PixelFault {
    /// NaN or infinite: refused under every policy.
    #[error("NaN and infinite radiance are not accepted")]
    NotFinite,
    /// Negative, under [`NegativePolicy::Error`] (the CLI names `--negative`).
    #[error("negative radiance, which the reading policy refuses (it can clamp it to 0 or keep it)")]
    Negative,
}

/// Errors of reading an environment map; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file cannot be read or decoded.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A pixel the policy refuses.
    #[error("{path}: pixel ({x}, {y}) channel {channel} is {value}: {fault}")]
    BadPixel {
        /// The file.
        path: PathBuf,
        /// Column.
        x: usize,
        /// Row.
        y: usize,
        /// `R`, `G` or `B`.
        channel: &'static str,
        /// The value.
        value: f32,
        /// Why it is refused.
        fault: PixelFault,
    },
    /// A face file of a cube directory is missing.
    #[error("{}: no face file {face}.exr, {face}.hdr or {face}.pfm", dir.display())]
    MissingFace {
        /// The directory.
        dir: PathBuf,
        /// The face's short name, e.g. `px`.
        face: &'static str,
    },
    /// The image does not fit the layout.
    #[error("{}: cannot use as an environment map: {error}", path.display())]
    Geometry {
        /// The file.
        path: PathBuf,
        /// What does not fit.
        error: EnvMapError,
    },
}

impl LoadOptions {
    /// Reads the map at `path`: an image file, or a directory of six faces `px nx py ny pz nz`
    /// (any of .exr, .hdr, .pfm).
    pub fn load(&self, path: &Path) -> Result<Loaded, LoadError> {
        let mut clamped = 0;
        if path.is_dir() || self.layout == Some(Layout::Faces) {
            let mut faces: Vec<RgbImage> = Vec::with_capacity(6);
            let mut first = PathBuf::new();
            for face in FACES {
                let file = find_face(path, face.short_name())?;
                let mut image = io::image::read_image(&file)?;
                // The face that differs is named, beside the first face it differs from.
                let n = faces.first().map_or(image.width, |f| f.width);
                if image.width != image.height || image.width != n {
                    let reason = match faces.is_empty() {
                        true => "a face must be square".to_string(),
                        false => format!("the faces must be one size: {} is {n}x{n}", first.display()),
                    };
                    let error =
                        EnvMapError::BadSize { layout: "cube face", width: image.width, height: image.height, reason };
                    return Err(LoadError::Geometry { path: file, error });
                }
                if faces.is_empty() {
                    first = file.clone();
                }
                clamped += self.check_pixels(&file, &mut image)?;
                faces.push(image);
            }
            let map = EnvMap::from_faces(faces).map_err(|error| LoadError::Geometry { path: path.into(), error })?;
            return Ok(Loaded { map: map.oriented(self.orientation), clamped });
        }
        self.wrap(path, io::image::read_image(path)?)
    }

    /// Decodes a map held in memory (standard input); `name` is used in messages.
    pub fn load_bytes(&self, name: &Path, bytes: &[u8]) -> Result<Loaded, LoadError> {
        if self.layout == Some(Layout::Faces) {
            return Err(LoadError::Geometry {
                path: name.into(),
                error: EnvMapError::BadSize {
                    layout: "cube faces",
                    width: 0,
                    height: 0,
                    reason: "six face files are read from a directory, not from one stream".into(),
                },
            });
        }
        self.wrap(name, io::image::decode_image(name, bytes)?)
    }

    fn wrap(&self, path: &Path, mut image: RgbImage) -> Result<Loaded, LoadError> {
        let clamped = self.check_pixels(path, &mut image)?;
        let map = match self.layout {
            Some(layout) => EnvMap::new(layout, image),
            None => EnvMap::detect(image),
        }
        .map_err(|error| LoadError::Geometry { path: path.into(), error })?;
        Ok(Loaded { map: map.oriented(self.orientation), clamped })
    }

    /// Applies the policy to every pixel; returns how many components were clamped. Rows are
    /// checked in parallel; the pixel named in an error is the first faulty one in row order,
    /// whatever the threads.
    pub fn check_pixels(&self, path: &Path, image: &mut RgbImage) -> Result<usize, LoadError> {
        let rows: Vec<Result<usize, (usize, usize, f32, PixelFault)>> =
            image.pixels.par_chunks_mut(image.width.max(1)).map(|row| self.check_row(row)).collect();
        let mut clamped = 0;
        for (y, row) in rows.into_iter().enumerate() {
            match row {
                Ok(n) => clamped += n,
                Err((x, c, value, fault)) => {
                    let channel = ["R", "G", "B"][c];
                    return Err(LoadError::BadPixel { path: path.into(), x, y, channel, value, fault });
                }
            }
        }
        Ok(clamped)
    }

    /// One row of [`LoadOptions::check_pixels`]: the components clamped, or the first fault as
    /// (column, channel, value, fault).
    fn check_row(&self, row: &mut [[f32; 3]]) -> Result<usize, (usize, usize, f32, PixelFault)> {
        let mut clamped = 0;
        for (x, px) in row.iter_mut().enumerate() {
            for (c, v) in px.iter_mut().enumerate() {
                if !v.is_finite() {
                    return Err((x, c, *v, PixelFault::NotFinite));
                }
                if *v < 0.0 {
                    match self.negative {
                        NegativePolicy::Error => return Err((x, c, *v, PixelFault::Negative)),
                        NegativePolicy::Clamp => {
                            *v = 0.0;
                            clamped += 1;
                        }
                        NegativePolicy::Keep => {}
                    }
                }
            }
        }
        Ok(clamped)
    }
}

fn find_face(dir: &Path, face: &'static str) -> Result<PathBuf, LoadError> {
    ["exr", "hdr", "pfm"]
        .iter()
        .map(|ext| dir.join(format!("{face}.{ext}")))
        .find(|p| p.is_file())
        .ok_or_else(|| LoadError::MissingFace { dir: dir.into(), face })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image_with(v: f32) -> RgbImage {
        RgbImage::from_fn(8, 4, |x, y| if (x, y) == (3, 2) { [1.0, v, 1.0] } else { [1.0; 3] })
    }

    #[test]
    fn a_face_of_another_size_is_named() {
        let dir = tempfile::tempdir().unwrap();
        for (i, face) in FACES.iter().enumerate() {
            let n = if i == 3 { 4 } else { 8 };
            let image = RgbImage::from_fn(n, n, |_, _| [1.0; 3]);
            std::fs::write(dir.path().join(format!("{}.pfm", face.short_name())), io::pfm::encode(&image)).unwrap();
        }
        let e = LoadOptions::default().load(dir.path()).unwrap_err().to_string();
        let (bad, first) = (FACES[3].short_name(), FACES[0].short_name());
        assert!(e.contains(&format!("{bad}.pfm: cannot use")) && e.contains("4x4"), "{e}");
        assert!(e.contains(&format!("{first}.pfm is 8x8")), "{e}");
    }

    #[test]
    fn the_policy_names_the_first_bad_pixel_or_clamps_and_counts() {
        let path = Path::new("sky.exr");
        let strict = LoadOptions::default();
        let e = strict.check_pixels(path, &mut image_with(f32::NAN)).unwrap_err().to_string();
        assert!(e.starts_with("sky.exr: pixel (3, 2) channel G is NaN"), "{e}");
        let e = strict.check_pixels(path, &mut image_with(-0.5)).unwrap_err().to_string();
        assert!(e.contains("(3, 2) channel G is -0.5: negative radiance"), "{e}");
        let clamp = LoadOptions { negative: NegativePolicy::Clamp, ..strict };
        let mut img = image_with(-0.5);
        assert_eq!(clamp.check_pixels(path, &mut img).unwrap(), 1);
        assert_eq!(img.get(3, 2), [1.0, 0.0, 1.0]);
        let keep = LoadOptions { negative: NegativePolicy::Keep, ..strict };
        assert_eq!(keep.check_pixels(path, &mut image_with(-0.5)).unwrap(), 0);
        assert!(keep.check_pixels(path, &mut image_with(f32::INFINITY)).is_err());
    }

    /// Rows checked in parallel still name the first fault in row order and count the clamps
    /// of every row, on one thread or several.
    #[test]
    fn the_first_fault_in_row_order_is_named_on_any_number_of_threads() {
        let faulty = || {
            RgbImage::from_fn(64, 96, |x, y| match (x, y) {
                (5, 70) => [1.0, 1.0, f32::NAN],
                (40, 3) | (2, 50) | (63, 95) => [-0.25, 1.0, 1.0],
                _ => [1.0; 3],
            })
        };
        let path = Path::new("sky.exr");
        let strict = LoadOptions::default();
        let clamp = LoadOptions { negative: NegativePolicy::Clamp, ..strict };
        for threads in [1, 4] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let e = strict.check_pixels(path, &mut faulty()).unwrap_err().to_string();
                assert!(e.contains("(40, 3) channel R is -0.25"), "{e}");
                let e = clamp.check_pixels(path, &mut faulty()).unwrap_err().to_string();
                assert!(e.contains("(5, 70) channel B is NaN"), "{e}");
                let mut no_nan = faulty();
                no_nan.pixels[70 * 64 + 5] = [1.0; 3];
                assert_eq!(clamp.check_pixels(path, &mut no_nan).unwrap(), 3);
                assert!(no_nan.pixels.iter().flatten().all(|v| *v >= 0.0));
            });
        }
    }

    #[test]
    fn bytes_are_sniffed_when_the_name_says_nothing() {
        let img = RgbImage::from_fn(8, 4, |x, _| [x as f32, 1.0, 2.0]);
        let pfm = io::pfm::encode(&img);
        let loaded = LoadOptions::default().load_bytes(Path::new("<stdin>"), &pfm).unwrap();
        assert_eq!(loaded.map.layout(), Layout::LatLong);
        assert_eq!(loaded.map.image(), &img);
        let e = LoadOptions::default().load_bytes(Path::new("<stdin>"), b"hello").unwrap_err().to_string();
        assert!(e.starts_with("<stdin>: unknown image format"), "{e}");
    }
}
