//! `factor-brdf`: the in-out SVD of a BRDF.
fn main() -> std::process::ExitCode {
    prtkit::cli::common::main::<prtkit::cli::factor_brdf::Args>()
}
