//! `prefilter`: frequency-space prefiltering and spherical harmonic reflection maps.
fn main() -> std::process::ExitCode {
    let args = <prtkit::cli::prefilter::Args as clap::Parser>::parse();
    prtkit::cli::common::run_stage("prefilter", || prtkit::cli::prefilter::run(args))
}
