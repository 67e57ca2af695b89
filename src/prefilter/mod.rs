//! Frequency-space prefiltering and spherical harmonic reflection maps (Ramamoorthi & Hanrahan
//! 2002), with the angular-domain reference. `docs/prefilter.md` has the derivations.

pub mod angular;
pub mod brdf_sh;
pub mod bright_pass;
pub mod document;
pub mod in_angle;
pub mod model;
pub mod orders;
pub mod pipeline;
pub mod ring_free;
pub mod shrm;
pub mod stage;
pub mod truncation;
pub mod tuning;
pub mod verify;
pub mod view_axis;
