//! `sample-shader`: bake a procedural shader with guaranteed error bounds.
fn main() -> std::process::ExitCode {
    let args = <prtkit::cli::sample_shader::Args as clap::Parser>::parse();
    prtkit::cli::common::run_stage("sample-shader", || prtkit::cli::sample_shader::run(args))
}
