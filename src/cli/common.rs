//! What every stage's command line shares: exit codes, error printing, progress bars.

use std::io::IsTerminal;
use std::process::ExitCode;

/// Exit status is public API (`docs/cli.md`).
pub mod exit {
    /// Every requested output was fully written.
    pub const SUCCESS: u8 = 0;
    /// A negative answer: a failed `--check`, a comparison beyond tolerance.
    pub const NEGATIVE: u8 = 1;
    /// An error: bad input, I/O, usage.
    pub const ERROR: u8 = 2;
}

/// The outcome of a stage that ran without error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Exit 0.
    Success,
    /// Exit 1 (the stage has already said which item failed and why).
    Negative,
}

/// Runs a stage, printing errors as `<stage>: error: …` with their causes, and maps the result
/// to an exit code. A broken pipe on stdout ends quietly with status 0.
pub fn run_stage(stage: &str, f: impl FnOnce() -> anyhow::Result<Outcome>) -> ExitCode {
    match f() {
        Ok(Outcome::Success) => ExitCode::from(exit::SUCCESS),
        Ok(Outcome::Negative) => ExitCode::from(exit::NEGATIVE),
        Err(err) => {
            if is_broken_pipe(&err) {
                return ExitCode::from(exit::SUCCESS);
            }
            eprintln!("{stage}: error: {err:#}");
            ExitCode::from(exit::ERROR)
        }
    }
}

fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain()
        .any(|cause| cause.downcast_ref::<std::io::Error>().is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe))
}

/// Parses clap arguments; usage errors exit 2 (clap's default), `--help` exits 0.
pub fn parse_args<T: clap::Parser>() -> T {
    T::parse()
}

/// An indicatif bar behind the library's [`crate::progress::Progress`] callback, drawn on stderr
/// only when stderr is a terminal and `--quiet` is not given.
pub struct Bar {
    bar: Option<indicatif::ProgressBar>,
}

impl Bar {
    /// A bar that draws only when stderr is a terminal and `quiet` is false.
    pub fn new(quiet: bool) -> Self {
        let visible = !quiet && std::io::stderr().is_terminal();
        Bar { bar: visible.then(indicatif::ProgressBar::hidden) }
    }
}

impl crate::progress::Progress for Bar {
    fn start(&self, label: &str, total: u64) {
        if let Some(bar) = &self.bar {
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            bar.reset();
            bar.set_length(total);
            bar.set_position(0);
            let style = indicatif::ProgressStyle::with_template("{msg:>14} [{bar:40}] {pos}/{len} ({eta})")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
                .progress_chars("=> ");
            bar.set_style(style);
            bar.set_message(label.to_string());
        }
    }
    fn advance(&self, n: u64) {
        if let Some(bar) = &self.bar {
            bar.inc(n);
        }
    }
    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// Parses `WxH` (e.g. `512x256`) for clap.
pub fn parse_size(s: &str) -> Result<(usize, usize), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("expected WxH, e.g. 512x256, got {s:?}"))?;
    let w: usize = w.trim().parse().map_err(|_| format!("bad width in {s:?}"))?;
    let h: usize = h.trim().parse().map_err(|_| format!("bad height in {s:?}"))?;
    if w == 0 || h == 0 || w > 1 << 16 || h > 1 << 16 {
        return Err(format!("size {s:?} must be between 1x1 and 65536x65536"));
    }
    Ok((w, h))
}

/// Parses `x,y,z` (three finite numbers) for points and directions on the command line.
pub fn parse_xyz(s: &str) -> Result<glam::DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("expected x,y,z, got {s:?}"))?;
    if v.len() != 3 || v.iter().any(|c| !c.is_finite()) {
        return Err(format!("expected three finite numbers x,y,z, got {s:?}"));
    }
    Ok(glam::DVec3::new(v[0], v[1], v[2]))
}

/// The options every stage shares for how it runs (flattened into each stage's `Args`).
#[derive(Clone, Debug, Default, clap::Args)]
pub struct Execution {
    /// Worker threads (default or 0: all cores). Results do not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,

    /// Do not draw progress bars (they are drawn only on a terminal anyway).
    #[arg(short, long)]
    pub quiet: bool,
}

impl Execution {
    /// Sizes the thread pool and returns the progress bar for the stage.
    pub fn start(&self) -> anyhow::Result<Bar> {
        init_threads(self.threads)?;
        Ok(Bar::new(self.quiet))
    }
}

/// Sets the size of rayon's global pool (`--threads`; 0 or none: all cores); results never
/// depend on it. A pool that already exists (a test calling `run` twice) is kept.
pub fn init_threads(threads: Option<usize>) -> anyhow::Result<()> {
    if let Some(n) = threads.filter(|&n| n > 0) {
        if let Err(e) = rayon::ThreadPoolBuilder::new().num_threads(n).build_global() {
            if rayon::current_num_threads() != n {
                anyhow::bail!("cannot start {n} threads: {e}");
            }
        }
    }
    Ok(())
}

/// `--json` owns stdout: a document that would also go there must be given a file instead.
pub fn check_json_output(document: &crate::io::Output, json: bool) -> anyhow::Result<()> {
    if json && *document == crate::io::Output::Stdout {
        anyhow::bail!("--json prints the summary on stdout: give the document a file with -o FILE");
    }
    Ok(())
}
