//! prtkit: bakes assets for real-time rendering and measures how accurate each bake is.
//!
//! Each module is one domain concept; binaries in `src/bin` are thin wrappers over `cli`.
#![forbid(unsafe_code)]

pub mod cli;
pub mod envmap;
pub mod io;
pub mod normals;
pub mod progress;
pub mod sh;
