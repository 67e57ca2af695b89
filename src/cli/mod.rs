//! Command-line front ends: one module per stage (clap args → typed config → library call →
//! outputs), plus the conventions they share (exit codes, progress bars, error reporting).

pub mod common;
pub mod convert;
pub mod count_terms;
pub mod encode_normals;
pub mod envinput;
pub mod factor_brdf;
pub mod prefilter;
pub mod render;
pub mod sample_shader;
pub mod sh_project;
pub mod umbrella;
