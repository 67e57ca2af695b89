//! How every stage runs: exit codes, the thread pool, interruption, progress bars, narration on
//! stderr, and error reporting (`docs/cli.md`).

use super::options::Execution;
use std::fmt::Display;
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
    /// Interrupted by SIGINT, SIGTERM or SIGHUP.
    pub const INTERRUPTED: u8 = 130;
}

/// The outcome of a stage that ran without error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Exit 0.
    Success,
    /// Exit 1 (the stage has already said which item failed and why).
    Negative,
}

/// A stage's command line: its clap arguments and how they run.
pub trait Stage: clap::Parser + Send {
    /// The stage's name, e.g. `sh-project`: the prefix of its messages.
    const NAME: &'static str;
    /// The shared execution options (`--threads`, `--quiet`).
    fn execution(&self) -> &Execution;
    /// Turns the arguments into the library's config, calls the library, writes the outputs.
    fn run(self, ctx: &Context) -> anyhow::Result<Outcome>;
}

/// What a running stage may use of its surroundings: progress and narration on stderr.
pub struct Context {
    stage: &'static str,
    quiet: bool,
    bar: Bar,
}

impl Context {
    /// A context for `stage`; `quiet` silences everything on stderr but errors.
    pub fn new(stage: &'static str, quiet: bool) -> Self {
        Context { stage, quiet, bar: Bar::new(quiet) }
    }

    /// Progress for the library's long computations.
    pub fn progress(&self) -> &dyn crate::progress::Progress {
        &self.bar
    }

    /// Says something on stderr (`stage: message`), unless `--quiet`.
    pub fn note(&self, message: impl Display) {
        if !self.quiet {
            self.bar.suspend(|| eprintln!("{}: {message}", self.stage));
        }
    }

    /// True with `--quiet`.
    pub fn quiet(&self) -> bool {
        self.quiet
    }
}

/// Parses the process's arguments as stage `S` and runs it (the `main` of every binary).
pub fn main<S: Stage>() -> ExitCode {
    run(S::parse())
}

/// Runs a parsed stage: installs the interruption handler, sizes its thread pool, prints errors
/// as `<stage>: error: …` with their causes, and maps the result to an exit code. A broken pipe
/// on stdout ends quietly with status 0.
pub fn run<S: Stage>(args: S) -> ExitCode {
    install_interrupt_handler();
    let ctx = Context::new(S::NAME, args.execution().quiet);
    let result = args.execution().pool(&ctx).and_then(|pool| pool.install(|| args.run(&ctx)));
    match result {
        Ok(Outcome::Success) => ExitCode::from(exit::SUCCESS),
        Ok(Outcome::Negative) => ExitCode::from(exit::NEGATIVE),
        Err(err) if is_broken_pipe(&err) => ExitCode::from(exit::SUCCESS),
        Err(err) => {
            eprintln!("{}: error: {err:#}", S::NAME);
            ExitCode::from(exit::ERROR)
        }
    }
}

/// On SIGINT, SIGTERM or SIGHUP: remove the temporary files of outputs not yet in place and exit
/// 130. Outputs being renamed into place are finished first (`io::atomic`), so a run leaves all
/// of its outputs or none, and never a temporary file.
fn install_interrupt_handler() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // A second handler cannot be set (a test running stages in-process); the first stays.
        let _ = ctrlc::set_handler(|| {
            crate::io::atomic::remove_pending_and_hold();
            std::process::exit(exit::INTERRUPTED as i32);
        });
    });
}

fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| {
        let io = cause.downcast_ref::<std::io::Error>().or_else(|| match cause.downcast_ref::<crate::io::IoError>() {
            Some(crate::io::IoError::Os { error, .. }) => Some(error),
            _ => None,
        });
        io.is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
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

    fn suspend(&self, f: impl FnOnce()) {
        match &self.bar {
            Some(bar) => bar.suspend(f),
            None => f(),
        }
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
