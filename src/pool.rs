//! Each system's own worker pool. The process-wide rayon pool is never used:
//! every parallel algorithm runs inside [`WorkerPool::install`].

use crate::error::{Error, ErrorKind, Result};
use std::cell::Cell;
use std::sync::Arc;

thread_local! {
    static WORKER: Cell<bool> = const { Cell::new(false) };
}

/// True on a worker thread of some [`WorkerPool`] (used by the C ABI's
/// quiet panic hook to tell the library's threads from the host's).
pub fn on_worker_thread() -> bool {
    WORKER.with(Cell::get)
}

/// A private rayon pool sized from `Config::threads` (0 = all cores).
#[derive(Clone, Debug)]
pub struct WorkerPool {
    pool: Arc<rayon::ThreadPool>,
}

impl WorkerPool {
    /// A pool of `threads` workers (0 = one per available core). With 1,
    /// work runs serially on the pool's single worker.
    pub fn new(threads: usize) -> Result<Self> {
        let n = if threads == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { threads };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .thread_name(|i| format!("plumage-{i}"))
            .start_handler(|_| WORKER.with(|w| w.set(true)))
            .build()
            .map_err(|e| Error::new(ErrorKind::InvalidArgument, format!("cannot start {n} worker threads: {e}")))?;
        Ok(Self { pool: Arc::new(pool) })
    }

    /// Runs `f` with this pool as the current rayon pool.
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        self.pool.install(f)
    }

    /// Number of worker threads.
    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }
}
