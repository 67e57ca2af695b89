//! `render`: images of each bake against ground truth.
fn main() -> std::process::ExitCode {
    prtkit::cli::common::main::<prtkit::cli::render::Args>()
}
