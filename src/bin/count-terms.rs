//! `count-terms`: predicted and measured BRDF term counts, with a CI check.
fn main() -> std::process::ExitCode {
    prtkit::cli::common::main::<prtkit::cli::count_terms::Args>()
}
