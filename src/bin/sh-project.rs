//! `sh-project`: project an environment map onto spherical harmonics.
fn main() -> std::process::ExitCode {
    let args = <prtkit::cli::sh_project::Args as clap::Parser>::parse();
    prtkit::cli::common::run_stage("sh-project", || prtkit::cli::sh_project::run(args))
}
