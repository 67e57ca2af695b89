//! `encode-normals`: octahedron normal vectors and the comparison parameterizations.
fn main() -> std::process::ExitCode {
    prtkit::cli::common::main::<prtkit::cli::encode_normals::Args>()
}
