//! `render`: images of each bake against ground truth.
fn main() -> std::process::ExitCode {
    let args = <prtkit::cli::render::Args as clap::Parser>::parse();
    prtkit::cli::common::run_stage("render", || prtkit::cli::render::run(args))
}
