//! The systems' worker pools. The process-wide rayon pool is never used:
//! every parallel algorithm runs inside [`WorkerPool::install`].
//!
//! `threads = 0` (all cores) gives every such system the same pool, started
//! with the first of them and ended with the last, so several systems in one
//! process do not each start a thread per core. `threads = N ≥ 2` gives the
//! system a pool of its own.
//!
//! With one thread no worker is started: each call runs on the thread that
//! made it (progress callbacks included). rayon has no "run here" mode, so
//! every call builds a one-worker rayon registry whose worker is never
//! spawned, queues the work on it and then runs the worker's loop on the
//! calling thread until the work is done; the registry goes away with the
//! call and leaves the thread as it was.

use crate::error::{Error, ErrorKind, Result};
use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::{Arc, Mutex, OnceLock, Weak};

thread_local! {
    static WORKER: Cell<bool> = const { Cell::new(false) };
}

/// True on a worker thread of some [`WorkerPool`] (used by the C ABI's
/// quiet panic hook to tell the library's threads from the host's).
pub fn on_worker_thread() -> bool {
    WORKER.with(Cell::get)
}

/// A rayon pool sized from `Config::threads` (0 = all cores, shared), or
/// the calling thread alone (1).
#[derive(Clone, Debug)]
pub struct WorkerPool {
    kind: Kind,
}

#[derive(Clone, Debug)]
enum Kind {
    /// `threads = 1`: inline on the calling thread.
    Inline(Arc<OnceLock<rayon::ThreadPool>>),
    Pool(Arc<rayon::ThreadPool>),
}

impl WorkerPool {
    /// A pool of `threads` workers; 0 = one per available core, shared with
    /// every other live system made with 0. With 1, no thread is started
    /// and work runs on the caller's thread.
    pub fn new(threads: usize) -> Result<Self> {
        match threads {
            0 => {
                static SHARED: Mutex<Weak<rayon::ThreadPool>> = Mutex::new(Weak::new());
                let mut shared = SHARED.lock().unwrap_or_else(|e| e.into_inner());
                if let Some(pool) = shared.upgrade() {
                    return Ok(Self { kind: Kind::Pool(pool) });
                }
                let pool = Arc::new(build_pool(std::thread::available_parallelism().map_or(1, |n| n.get()))?);
                *shared = Arc::downgrade(&pool);
                Ok(Self { kind: Kind::Pool(pool) })
            }
            1 => Ok(Self { kind: Kind::Inline(Arc::default()) }),
            n => Ok(Self { kind: Kind::Pool(Arc::new(build_pool(n)?)) }),
        }
    }

    /// Runs `f` with this pool as the current rayon pool.
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.kind {
            Kind::Pool(pool) => pool.install(f),
            Kind::Inline(fallback) => match rayon::current_thread_index() {
                None => run_inline(f),
                // The caller is already the only worker of a one-thread
                // pool (a progress callback of another one-thread system
                // calling in): running here is running inline.
                Some(_) if rayon::current_num_threads() == 1 => f(),
                // The caller is a worker of a larger rayon pool (a Rust
                // host's): its thread cannot take a second worker's role,
                // so this system starts its one worker after all.
                Some(_) => fallback.get_or_init(|| build_pool(1).expect("cannot start a worker thread")).install(f),
            },
        }
    }

    /// Number of worker threads (1 when running inline).
    pub fn threads(&self) -> usize {
        match &self.kind {
            Kind::Inline(_) => 1,
            Kind::Pool(pool) => pool.current_num_threads(),
        }
    }
}

fn build_pool(n: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .thread_name(|i| format!("plumage-{i}"))
        .start_handler(|_| WORKER.with(|w| w.set(true)))
        .build()
        .map_err(|e| Error::new(ErrorKind::InvalidArgument, format!("cannot start {n} worker threads: {e}")))
}

/// Runs `f` on the calling thread, which must not be a rayon worker, as the
/// only worker of a fresh rayon registry (so `f`'s parallel iterators run
/// here, serially). A panic in `f` resumes on the caller.
fn run_inline<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    let mut worker = None;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .spawn_handler(|thread| {
            worker = Some(thread);
            Ok(())
        })
        .build()
        // Only a failing spawn handler or `use_current_thread` make a local
        // registry fail, and this one uses neither.
        .expect("a one-worker rayon registry without threads");
    let mut outcome: Option<std::thread::Result<R>> = None;
    let slot = &mut outcome as *mut Option<std::thread::Result<R>> as usize;
    let job: Box<dyn FnOnce() + Send + '_> = Box::new(move || {
        let result = catch_unwind(AssertUnwindSafe(f));
        // SAFETY: `slot` points to `outcome`, which outlives the job (see below)
        // and is not touched by anything else until `worker.run()` returns.
        unsafe { *(slot as *mut Option<std::thread::Result<R>>) = Some(result) };
    });
    // SAFETY: the job borrows `f`'s captures and `outcome` from this frame.
    // It runs inside `worker.run()` below, which returns only once the
    // registry has terminated, and a registry terminates only after every
    // job spawned into it has run (rayon counts them); so the job has
    // finished before this frame ends. It cannot unwind (caught above).
    let job: Box<dyn FnOnce() + Send + 'static> = unsafe { std::mem::transmute(job) };
    pool.spawn(job);
    drop(pool);
    worker.expect("rayon asks for its one worker while building the registry").run();
    match outcome.expect("the queued work ran before the registry terminated") {
        Ok(r) => r,
        Err(panic) => resume_unwind(panic),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;

    #[test]
    fn one_thread_runs_on_the_caller() {
        let pool = WorkerPool::new(1).unwrap();
        assert_eq!(pool.threads(), 1);
        let caller = std::thread::current().id();
        let (sum, ids) = pool.install(|| {
            let ids: Vec<_> = (0..1000).into_par_iter().map(|_| std::thread::current().id()).collect();
            ((0..1000u64).into_par_iter().sum::<u64>(), ids)
        });
        assert_eq!(sum, 999 * 1000 / 2);
        assert!(ids.iter().all(|&id| id == caller));
        assert_eq!(rayon::current_thread_index(), None, "the thread is left as it was");
        // Again, and nested through a second one-thread pool.
        let other = WorkerPool::new(1).unwrap();
        let inner = pool.install(|| other.install(|| (std::thread::current().id(), rayon::current_num_threads())));
        assert_eq!(inner, (caller, 1));
    }

    #[test]
    fn one_thread_passes_panics_to_the_caller() {
        let pool = WorkerPool::new(1).unwrap();
        let caught = catch_unwind(AssertUnwindSafe(|| {
            pool.install(|| (0..100).into_par_iter().for_each(|i| assert!(i != 57, "boom at {i}")))
        }));
        let msg = caught.unwrap_err().downcast::<String>().map(|s| *s).unwrap_or_default();
        assert!(msg.contains("boom at 57"), "{msg}");
        assert_eq!(pool.install(|| 7), 7, "the pool still works");
    }

    #[test]
    fn all_cores_is_one_pool_for_every_live_system() {
        let a = WorkerPool::new(0).unwrap();
        let b = WorkerPool::new(0).unwrap();
        let (Kind::Pool(pa), Kind::Pool(pb)) = (&a.kind, &b.kind) else { panic!("0 threads is a pool") };
        assert!(Arc::ptr_eq(pa, pb), "two systems with 0 threads share the pool");
        assert_eq!(a.threads(), std::thread::available_parallelism().map_or(1, |n| n.get()));
        let c = WorkerPool::new(2).unwrap();
        let Kind::Pool(pc) = &c.kind else { panic!("2 threads is a pool") };
        assert!(!Arc::ptr_eq(pa, pc), "an explicit count gets its own pool");
        assert_eq!(c.threads(), 2);
    }

    #[test]
    fn one_thread_inside_a_larger_pool_gets_one_worker() {
        let outer = WorkerPool::new(2).unwrap();
        let inner = WorkerPool::new(1).unwrap();
        let threads = outer.install(|| inner.install(rayon::current_num_threads));
        assert_eq!(threads, 1);
    }
}
