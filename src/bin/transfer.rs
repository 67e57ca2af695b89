//! `transfer`: bake a mesh's diffuse precomputed radiance transfer.
fn main() -> std::process::ExitCode {
    prtkit::cli::common::main::<prtkit::cli::transfer::Args>()
}
