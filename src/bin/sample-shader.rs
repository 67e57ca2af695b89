//! `sample-shader`: bake a procedural shader with guaranteed error bounds.
fn main() -> std::process::ExitCode {
    prtkit::cli::common::main::<prtkit::cli::sample_shader::Args>()
}
