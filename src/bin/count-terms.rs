//! `count-terms`: predicted and measured BRDF term counts, with a CI check.
fn main() -> std::process::ExitCode {
    let args = <prtkit::cli::count_terms::Args as clap::Parser>::parse();
    prtkit::cli::common::run_stage("count-terms", || prtkit::cli::count_terms::run(args))
}
