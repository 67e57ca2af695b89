//! The umbrella binary `prtkit <stage> …`: the same code as the stand-alone binaries.

use super::common::run;
use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// prtkit bakes assets for real-time rendering and measures how accurate each bake is.
#[derive(Debug, Parser)]
#[command(name = "prtkit", version, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    stage: StageArgs,
}

#[derive(Debug, Subcommand)]
enum StageArgs {
    /// Resample an environment map into another layout.
    Convert(super::convert::Args),
    /// Project an environment map onto spherical harmonics.
    ShProject(super::sh_project::Args),
    /// Prefilter an environment map with a BRDF: SHRMs and reflection maps.
    Prefilter(super::prefilter::Args),
    /// Factor a BRDF into in-out terms by SVD.
    FactorBrdf(super::factor_brdf::Args),
    /// Predict and measure how many BRDF terms materials need (CI check).
    CountTerms(super::count_terms::Args),
    /// Bake a procedural shader with guaranteed error bounds (adaptive area sampling).
    SampleShader(super::sample_shader::Args),
    /// Encode normal vectors at a bit budget and measure the exact angular error.
    EncodeNormals(super::encode_normals::Args),
    /// Bake image-based lighting for glTF/PBR engines: GGX cube mips, irradiance, SH, DFG.
    Ibl(super::ibl::Args),
    /// Render a sphere or mesh with a bake (SH, SHRM, factored) or the reference, and compare.
    Render(Box<super::render::Args>),
    /// Bake a mesh's diffuse precomputed radiance transfer (per-vertex SH: unshadowed, shadowed, interreflected).
    Transfer(super::transfer::Args),
}

/// Parses `prtkit <stage> …` and runs the stage.
pub fn main() -> ExitCode {
    let cli = match super::common::parsed("prtkit", Cli::try_parse()) {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    match cli.stage {
        StageArgs::Convert(args) => run(args),
        StageArgs::ShProject(args) => run(args),
        StageArgs::Prefilter(args) => run(args),
        StageArgs::FactorBrdf(args) => run(args),
        StageArgs::CountTerms(args) => run(args),
        StageArgs::SampleShader(args) => run(args),
        StageArgs::EncodeNormals(args) => run(args),
        StageArgs::Ibl(args) => run(args),
        StageArgs::Render(args) => run(*args),
        StageArgs::Transfer(args) => run(args),
    }
}
