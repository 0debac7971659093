//! Progress reporting and interruption. Long calls check in often; when the
//! host's callback asks to stop, the call unwinds with `Interrupted` and the
//! system restores the state it had before the call.

use crate::error::{Error, ErrorKind, Result};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Which part of the work is running.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Welding and checking the mesh, building the surface.
    Preparing,
    /// Planting roots.
    Sampling,
    /// Neighbourhoods, priorities, the feather order.
    Ordering,
    /// Height-field adjustment.
    Adjusting,
    /// The exact validation of the current feathers.
    Validating,
}

/// Receives progress; returns `false` to ask the running call to stop.
/// It may be called from the calling thread or any of the system's worker
/// threads (with one thread: always the calling thread), never from two at
/// once.
pub trait ProgressSink: Send + Sync {
    /// `fraction` is the completed share of `phase`, in [0, 1].
    fn report(&self, phase: Phase, fraction: f32) -> bool;
}

/// The shortest interval between two calls of the sink.
const REPORT_INTERVAL: Duration = Duration::from_millis(1);

/// Throttled check-ins from algorithm code.
pub struct Progress<'a> {
    sink: Option<&'a dyn ProgressSink>,
    stopped: AtomicBool,
    last: Mutex<Option<Instant>>,
}

impl<'a> Progress<'a> {
    /// No reporting; checks always pass.
    pub fn none() -> Progress<'static> {
        Progress { sink: None, stopped: AtomicBool::new(false), last: Mutex::new(None) }
    }

    /// Reports to `sink`.
    pub fn to(sink: &'a dyn ProgressSink) -> Self {
        Self { sink: Some(sink), stopped: AtomicBool::new(false), last: Mutex::new(None) }
    }

    /// Whether anyone listens (callers may skip backups when nobody can stop them).
    pub fn is_interruptible(&self) -> bool {
        self.sink.is_some()
    }

    /// Checks in: calls the sink when at least `REPORT_INTERVAL` has passed
    /// since the last call (always on the first), and fails with
    /// `Interrupted` once the sink has asked to stop.
    pub fn check(&self, phase: Phase, fraction: f32) -> Result<()> {
        let Some(sink) = self.sink else { return Ok(()) };
        if self.stopped.load(Ordering::Relaxed) {
            return Err(interrupted());
        }
        // A worker that finds another one reporting just carries on.
        if let Ok(mut last) = self.last.try_lock() {
            let now = Instant::now();
            if last.is_none_or(|t| now.duration_since(t) >= REPORT_INTERVAL) {
                *last = Some(now);
                if !sink.report(phase, fraction.clamp(0.0, 1.0)) {
                    self.stopped.store(true, Ordering::Relaxed);
                }
            }
        }
        if self.stopped.load(Ordering::Relaxed) { Err(interrupted()) } else { Ok(()) }
    }
}

impl Progress<'_> {
    /// For item `i` of a long loop (any thread): whether to go on. Checks
    /// in as [`Progress::check`] every [`POLL_STRIDE`] items and reads the
    /// stop flag in between, so a loop of short items stops within about
    /// one report interval. A loop that was told to stop skips its
    /// remaining items; the caller's next `check` then returns
    /// `Interrupted` and the partial results are dropped.
    #[inline]
    pub fn poll(&self, phase: Phase, fraction: f32, i: usize) -> bool {
        if self.sink.is_none() {
            return true;
        }
        if self.stopped.load(Ordering::Relaxed) {
            return false;
        }
        i % POLL_STRIDE != 0 || self.check(phase, fraction).is_ok()
    }
}

/// Items of a loop between two check-ins of [`Progress::poll`].
const POLL_STRIDE: usize = 16;

fn interrupted() -> Error {
    Error::new(ErrorKind::Interrupted, "interrupted by the progress callback; the system is as it was before the call")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    struct StopAfter(AtomicUsize);
    impl ProgressSink for StopAfter {
        fn report(&self, _: Phase, _: f32) -> bool {
            self.0.fetch_sub(1, Ordering::SeqCst) > 1
        }
    }

    #[test]
    fn stops_when_the_sink_says_so() {
        let sink = StopAfter(AtomicUsize::new(2));
        let p = Progress::to(&sink);
        assert!(p.check(Phase::Sampling, 0.0).is_ok());
        std::thread::sleep(REPORT_INTERVAL * 2);
        let err = p.check(Phase::Sampling, 0.5).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::Interrupted);
        assert!(p.check(Phase::Adjusting, 0.9).is_err(), "stays stopped");
        assert!(Progress::none().check(Phase::Adjusting, 1.0).is_ok());
    }
}
