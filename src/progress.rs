//! Progress reporting as a callback: the library never prints; the CLI adapts this to a bar.

/// Receives progress from long computations. Implementations must be cheap and thread-safe.
pub trait Progress: Sync {
    /// A new phase named `label` with `total` units of work.
    fn start(&self, label: &str, total: u64);
    /// `n` more units are done.
    fn advance(&self, n: u64);
    /// The current phase is complete.
    fn finish(&self);
}

/// Progress that goes nowhere (tests, library users who do not care).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn start(&self, _label: &str, _total: u64) {}
    fn advance(&self, _n: u64) {}
    fn finish(&self) {}
}
