//! prtkit: bakes assets for real-time rendering and measures how accurate each bake is.
//!
//! Each module is one domain concept; binaries in `src/bin` are thin wrappers over `cli`.
#![forbid(unsafe_code)]
#![warn(missing_docs, unreachable_pub)]

pub mod affine;
pub mod brdf;
pub mod cli;
pub mod envmap;
pub mod factor;
pub mod ibl;
pub mod io;
pub mod limits;
pub mod mesh;
pub mod metrics;
pub mod normals;
pub mod prefilter;
pub mod progress;
pub mod quadrature;
pub mod render;
pub mod rng;
pub mod sh;
pub mod shader;
pub mod sphere;
pub mod transfer;
