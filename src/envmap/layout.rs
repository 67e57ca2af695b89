//! The layouts an environment map can come in, and detecting one from an image's size.

use super::EnvMapError;
use std::fmt;
use std::str::FromStr;

/// Environment-map parameterizations (`docs/envmap-layouts.md`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Layout {
    /// Equirectangular, 2:1: row ↔ θ from +Z, column ↔ φ from +X towards +Y.
    LatLong,
    /// Debevec's angular light probe, 1:1: radius ∝ angle from the probe's centre direction.
    Angular,
    /// Horizontal cube cross, 4:3.
    CrossHorizontal,
    /// Vertical cube cross, 3:4 (−Z stored rotated by 180°).
    CrossVertical,
    /// Six square face images +X, −X, +Y, −Y, +Z, −Z (Direct3D/OpenGL cube-map orientation).
    Faces,
}

impl Layout {
    /// All layouts, for help texts.
    pub const ALL: [Layout; 5] =
        [Layout::LatLong, Layout::Angular, Layout::CrossHorizontal, Layout::CrossVertical, Layout::Faces];

    /// The name used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        match self {
            Layout::LatLong => "latlong",
            Layout::Angular => "angular",
            Layout::CrossHorizontal => "cross-horizontal",
            Layout::CrossVertical => "cross-vertical",
            Layout::Faces => "faces",
        }
    }

    /// Detects a single-image layout from the aspect ratio.
    pub fn detect(width: usize, height: usize) -> Result<Layout, EnvMapError> {
        if width == 2 * height {
            Ok(Layout::LatLong)
        } else if width == height {
            Ok(Layout::Angular)
        } else if 3 * width == 4 * height {
            Ok(Layout::CrossHorizontal)
        } else if 4 * width == 3 * height {
            Ok(Layout::CrossVertical)
        } else {
            Err(EnvMapError::Undetectable { width, height })
        }
    }

    /// Checks that a W×H image can hold this layout.
    pub fn check_size(self, width: usize, height: usize) -> Result<(), EnvMapError> {
        let bad =
            |reason: &str| Err(EnvMapError::BadSize { layout: self.name(), width, height, reason: reason.to_string() });
        if width == 0 || height == 0 {
            return bad("the image is empty");
        }
        match self {
            Layout::LatLong if width < 2 || height < 1 => bad("too small"),
            Layout::Angular if width != height => bad("an angular probe must be square"),
            Layout::CrossHorizontal if width % 4 != 0 || 3 * width != 4 * height => {
                bad("a horizontal cross is 4n x 3n")
            }
            Layout::CrossVertical if height % 4 != 0 || 4 * width != 3 * height => bad("a vertical cross is 3n x 4n"),
            Layout::Faces if width != height => bad("cube faces must be square"),
            _ => Ok(()),
        }
    }

    /// Face edge length of a cross layout.
    pub fn face_size(self, width: usize, height: usize) -> usize {
        match self {
            Layout::CrossHorizontal => width / 4,
            Layout::CrossVertical => height / 4,
            _ => width.min(height),
        }
    }
}

impl fmt::Display for Layout {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Layout {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "latlong" | "lat-long" | "equirect" | "equirectangular" => Ok(Layout::LatLong),
            "angular" | "probe" | "lightprobe" => Ok(Layout::Angular),
            "cross-horizontal" | "hcross" | "cross-h" => Ok(Layout::CrossHorizontal),
            "cross-vertical" | "vcross" | "cross-v" => Ok(Layout::CrossVertical),
            "faces" | "cube-faces" => Ok(Layout::Faces),
            other => Err(format!(
                "unknown layout {other:?} (expected latlong, angular, cross-horizontal, cross-vertical or faces)"
            )),
        }
    }
}
