//! Command-line front ends: one module per stage (clap args → the library's typed config → one
//! library call → outputs), plus what they share: [`common`] (running a stage: exit codes, the
//! thread pool, interruption, narration), [`options`] (the option vocabulary) and [`outputs`]
//! (all-or-nothing writing).

pub mod common;
pub mod convert;
pub mod count_terms;
pub mod encode_normals;
pub mod factor_brdf;
pub mod ibl;
pub mod options;
pub mod outputs;
pub mod prefilter;
pub mod render;
pub mod sample_shader;
pub mod sh_project;
pub mod transfer;
pub mod umbrella;
