//! The array form of a direction that `rng.rs` returns, kept only until the shared RNG replaces
//! it (issue 10: one seeded RNG, one vector type). Everything else in `normals` uses
//! `glam::DVec3`; convert with `DVec3::from(array)`.

/// A direction as `rng.rs` returns it.
pub type Dir = [f64; 3];
