//! `factor-brdf`: the in-out SVD of a BRDF.
fn main() -> std::process::ExitCode {
    let args = <prtkit::cli::factor_brdf::Args as clap::Parser>::parse();
    prtkit::cli::common::run_stage("factor-brdf", || prtkit::cli::factor_brdf::run(args))
}
