//! The `convert` stage as one library call: resample an environment map into another layout
//! (`docs/envmap-layouts.md`), each output texel the mean of k×k bilinear lookups.

use super::{resample, EnvMap, EnvMapError, Layout};
use crate::limits::MAX_SUPERSAMPLE;

/// What `convert` computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Config {
    /// The output layout.
    pub to: Layout,
    /// Output size (per face for [`Layout::Faces`]); `None` keeps the input's texel count.
    pub size: Option<(usize, usize)>,
    /// Sub-samples per texel edge.
    pub supersample: usize,
}

/// Errors of the stage.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The supersampling factor is out of range.
    #[error("{0} sub-samples per texel edge is outside 1..={MAX_SUPERSAMPLE}")]
    Supersample(usize),
    /// The size does not fit the layout.
    #[error("cannot make a {layout} map of {width}x{height}: {error}")]
    Geometry {
        /// The layout.
        layout: Layout,
        /// Width.
        width: usize,
        /// Height.
        height: usize,
        /// Why.
        error: EnvMapError,
    },
}

/// The output size for `config`: as given, else the size of `to` that keeps `texels`.
pub fn output_size(to: Layout, size: Option<(usize, usize)>, texels: usize) -> (usize, usize) {
    if let Some(s) = size {
        return s;
    }
    let edge = |per: f64| ((texels as f64 / per).sqrt().round() as usize).max(1);
    match to {
        Layout::LatLong => {
            let s = edge(2.0);
            (2 * s, s)
        }
        Layout::CrossHorizontal => {
            let n = edge(6.0);
            (4 * n, 3 * n)
        }
        Layout::CrossVertical => {
            let n = edge(6.0);
            (3 * n, 4 * n)
        }
        Layout::Faces => {
            let n = edge(6.0);
            (n, n)
        }
        Layout::Angular => {
            let s = edge(1.0);
            (s, s)
        }
    }
}

/// Runs `convert` on `map`.
pub fn run(config: &Config, map: &EnvMap) -> Result<EnvMap, Error> {
    if !(1..=MAX_SUPERSAMPLE).contains(&config.supersample) {
        return Err(Error::Supersample(config.supersample));
    }
    let (width, height) = output_size(config.to, config.size, map.texel_count());
    config.to.check_size(width, height).map_err(|error| Error::Geometry { layout: config.to, width, height, error })?;
    resample(map, config.to, width, height, config.supersample).map_err(|error| Error::Geometry {
        layout: config.to,
        width,
        height,
        error,
    })
}
