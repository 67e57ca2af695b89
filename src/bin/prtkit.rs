//! `prtkit <stage> …`: every stage behind one binary.
fn main() -> std::process::ExitCode {
    prtkit::cli::umbrella::main()
}
