//! The environment-map input every stage shares: a file (or a directory of six faces), an
//! optional `--layout`, and the policy for bad pixels.

use crate::envmap::{EnvMap, Layout, FACES};
use crate::io::{self, RgbImage};
use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};

/// What to do with negative pixels (NaN and ±Inf are always an error).
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum NegativePolicy {
    /// Refuse the file, naming the first negative pixel.
    Error,
    /// Replace negative components by 0 and say how many were clamped.
    Clamp,
    /// Keep them (they are valid for signed data such as SH reconstructions).
    Keep,
}

/// Environment-map input arguments.
#[derive(Debug, Args)]
pub struct EnvInput {
    /// Environment map: .exr, .hdr or .pfm; or a directory holding six faces
    /// px, nx, py, ny, pz, nz (any of those extensions).
    #[arg(value_name = "ENVMAP")]
    pub path: PathBuf,

    /// Layout of the input; detected from the aspect ratio when omitted
    /// (2:1 latlong, 1:1 angular, 4:3 cross-horizontal, 3:4 cross-vertical; a directory is faces).
    #[arg(long, value_parser = clap::value_parser!(Layout))]
    pub layout: Option<Layout>,

    /// Negative pixel components: error (default), clamp to 0, or keep.
    #[arg(long, value_enum, default_value_t = NegativePolicy::Error)]
    pub negative: NegativePolicy,
}

impl EnvInput {
    /// Reads, validates and wraps the map.
    pub fn load(&self) -> Result<EnvMap> {
        let path = &self.path;
        if path.is_dir() || self.layout == Some(Layout::Faces) {
            let mut faces = Vec::with_capacity(6);
            for face in FACES {
                let file = find_face(path, face.short_name())?;
                faces.push(self.read_checked(&file)?);
            }
            return EnvMap::from_faces(faces).with_context(|| format!("{}: bad cube faces", path.display()));
        }
        let image = self.read_checked(path)?;
        let map = match self.layout {
            Some(layout) => EnvMap::new(layout, image),
            None => EnvMap::detect(image),
        };
        map.with_context(|| format!("{}: cannot use as an environment map", path.display()))
    }

    fn read_checked(&self, path: &Path) -> Result<RgbImage> {
        let mut image = io::image::read_image(path)?;
        check_pixels(path, &mut image, self.negative)?;
        Ok(image)
    }
}

fn find_face(dir: &Path, name: &str) -> Result<PathBuf> {
    for ext in ["exr", "hdr", "pfm"] {
        let p = dir.join(format!("{name}.{ext}"));
        if p.is_file() {
            return Ok(p);
        }
    }
    bail!("{}: no face file {name}.exr, {name}.hdr or {name}.pfm", dir.display())
}

/// Applies the bad-pixel policy: NaN/Inf always fail, negatives per `policy`.
pub fn check_pixels(path: &Path, image: &mut RgbImage, policy: NegativePolicy) -> Result<()> {
    let width = image.width;
    let mut clamped = 0usize;
    for (i, px) in image.pixels.iter_mut().enumerate() {
        for (c, v) in px.iter_mut().enumerate() {
            let (x, y) = (i % width, i / width);
            if !v.is_finite() {
                bail!(
                    "{}: pixel ({x}, {y}) channel {} is {v}: NaN and infinite radiance are not accepted",
                    path.display(),
                    ["R", "G", "B"][c]
                );
            }
            if *v < 0.0 {
                match policy {
                    NegativePolicy::Error => bail!(
                        "{}: pixel ({x}, {y}) channel {} is negative ({v}); pass --negative clamp or --negative keep",
                        path.display(),
                        ["R", "G", "B"][c]
                    ),
                    NegativePolicy::Clamp => {
                        *v = 0.0;
                        clamped += 1;
                    }
                    NegativePolicy::Keep => {}
                }
            }
        }
    }
    if clamped > 0 {
        eprintln!("{}: clamped {clamped} negative pixel components to 0", path.display());
    }
    Ok(())
}
