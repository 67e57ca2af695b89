//! `prefilter`: frequency-space prefiltering and spherical harmonic reflection maps.
fn main() -> std::process::ExitCode {
    prtkit::cli::common::main::<prtkit::cli::prefilter::Args>()
}
