//! `encode-normals`: octahedron normal vectors and the comparison parameterizations.
fn main() -> std::process::ExitCode {
    let args = <prtkit::cli::encode_normals::Args as clap::Parser>::parse();
    prtkit::cli::common::run_stage("encode-normals", || prtkit::cli::encode_normals::run(args))
}
