//! `ibl`: image-based lighting for glTF/PBR engines (specular cube, irradiance, SH, DFG).
fn main() -> std::process::ExitCode {
    prtkit::cli::common::main::<prtkit::cli::ibl::Args>()
}
