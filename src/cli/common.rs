//! How every stage runs: exit codes, the thread pool, interruption, progress bars, narration on
//! stderr, and error reporting (`docs/cli.md`).

use super::options::Execution;
use std::fmt::Display;
use std::io::IsTerminal;
use std::process::ExitCode;
use std::sync::Mutex;
use std::time::{Duration, Instant};

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
        Context { stage, quiet, bar: Bar::new(stage, quiet) }
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
    parsed(S::NAME, S::try_parse()).map_or_else(|code| code, run)
}

/// The arguments, or the exit code of a command line that does not parse: `--help` and
/// `--version` print to stdout (status 0); a usage error prints `<stage>: error: …` (the prefix
/// of every other error, so a Makefile's log says which stage refused) with clap's suggestion,
/// status 2.
pub fn parsed<T>(stage: &str, result: Result<T, clap::Error>) -> Result<T, ExitCode> {
    result.map_err(|err| {
        if err.use_stderr() {
            eprint!("{stage}: {}", err.render());
            ExitCode::from(exit::ERROR)
        } else {
            let _ = err.print();
            ExitCode::from(exit::SUCCESS)
        }
    })
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

/// The library's [`crate::progress::Progress`] on stderr: an indicatif bar when stderr is a
/// terminal; otherwise (a Makefile's log, CI, a pipe) a line every [`Bar::LOG_EVERY`] while a
/// phase runs, so a long phase is never silent and a short one adds nothing; nothing with
/// `--quiet`.
pub struct Bar {
    view: View,
}

enum View {
    Hidden,
    Terminal(indicatif::ProgressBar),
    Log(Mutex<LogState>),
}

/// The phase a log is narrating.
struct LogState {
    stage: &'static str,
    label: String,
    total: u64,
    done: u64,
    started: Instant,
    last_line: Instant,
}

impl Bar {
    /// How often a log line reports a running phase.
    pub const LOG_EVERY: Duration = Duration::from_secs(10);

    /// A bar on a terminal, a log elsewhere, nothing when `quiet`.
    pub fn new(stage: &'static str, quiet: bool) -> Self {
        let view = if quiet {
            View::Hidden
        } else if std::io::stderr().is_terminal() {
            View::Terminal(indicatif::ProgressBar::hidden())
        } else {
            let now = Instant::now();
            View::Log(Mutex::new(LogState {
                stage,
                label: String::new(),
                total: 0,
                done: 0,
                started: now,
                last_line: now,
            }))
        };
        Bar { view }
    }

    fn suspend(&self, f: impl FnOnce()) {
        match &self.view {
            View::Terminal(bar) => bar.suspend(f),
            _ => f(),
        }
    }

    fn log(&self) -> Option<std::sync::MutexGuard<'_, LogState>> {
        match &self.view {
            View::Log(state) => Some(state.lock().unwrap_or_else(|poisoned| poisoned.into_inner())),
            _ => None,
        }
    }
}

impl crate::progress::Progress for Bar {
    fn start(&self, label: &str, total: u64) {
        if let View::Terminal(bar) = &self.view {
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
        if let Some(mut log) = self.log() {
            let now = Instant::now();
            *log = LogState { label: label.to_string(), total, done: 0, started: now, last_line: now, ..*log };
        }
    }
    fn advance(&self, n: u64) {
        if let View::Terminal(bar) = &self.view {
            bar.inc(n);
        }
        if let Some(mut log) = self.log() {
            log.done += n;
            if log.last_line.elapsed() >= Self::LOG_EVERY && log.done < log.total {
                log.last_line = Instant::now();
                let percent = 100.0 * log.done as f64 / log.total.max(1) as f64;
                let elapsed = log.started.elapsed().as_secs();
                eprintln!("{}: {} {}/{} ({percent:.0} %, {elapsed} s)", log.stage, log.label, log.done, log.total);
            }
        }
    }
    fn finish(&self) {
        if let View::Terminal(bar) = &self.view {
            bar.finish_and_clear();
        }
    }
}
