//! `convert`: see `prtkit::cli::convert`.
fn main() -> std::process::ExitCode {
    prtkit::cli::common::main::<prtkit::cli::convert::Args>()
}
