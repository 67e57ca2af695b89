//! `sh-project`: project an environment map onto spherical harmonics.
fn main() -> std::process::ExitCode {
    prtkit::cli::common::main::<prtkit::cli::sh_project::Args>()
}
