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
//!
//! A host with its own task system (TBB, a DCC's thread pool) may hand the
//! library its parallel-for ([`ParallelFor`]) instead: each call then builds
//! a rayon registry of N workers whose threads are never spawned, queues the
//! work on it, and asks the host to run the N workers' loops as N tasks, on
//! whatever threads the host chooses. A worker's loop returns once the work
//! is done, and no worker waits for another to start, so the host may run
//! the tasks one after the other or several at once; a task the host runs
//! on a thread that is already a rayon worker, or does not run at all, is
//! run on the calling thread after the host returns.

use crate::error::{Error, ErrorKind, Result};
use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::{Arc, Condvar, Mutex, OnceLock, Weak};

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
    /// The host's parallel-for runs `workers` worker loops per call.
    Host {
        host: Arc<dyn ParallelFor>,
        workers: usize,
        fallback: Arc<OnceLock<rayon::ThreadPool>>,
    },
}

/// A host's parallel-for: calls `task(i)` once for every `i` in
/// `0..count`, on any threads and in any order, and returns only after
/// every call has returned. `task` never unwinds.
pub trait ParallelFor: Send + Sync + std::fmt::Debug {
    /// Runs `task(0)` .. `task(count - 1)` and returns when all have run.
    fn parallel_for(&self, count: usize, task: &(dyn Fn(usize) + Sync));
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

    /// Work runs through the host's parallel-for, `threads` tasks at a
    /// time (0 = one per available core); with one, inline as
    /// [`WorkerPool::new`]`(1)` and the host is never called.
    pub fn with_parallel_for(threads: usize, host: Arc<dyn ParallelFor>) -> Result<Self> {
        let workers = if threads == 0 { std::thread::available_parallelism().map_or(1, |n| n.get()) } else { threads };
        if workers == 1 {
            return Self::new(1);
        }
        Ok(Self { kind: Kind::Host { host, workers, fallback: Arc::default() } })
    }

    /// Runs `f` with this pool as the current rayon pool.
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.kind {
            Kind::Pool(pool) => pool.install(f),
            Kind::Host { host, workers, fallback } => match rayon::current_thread_index() {
                None => run_on_host(host.as_ref(), *workers, f),
                // Called from a rayon worker (a progress callback calling
                // in, a Rust host's pool): its thread cannot run another
                // registry's worker loop, so as with one thread.
                Some(_) if rayon::current_num_threads() == 1 => f(),
                Some(_) => fallback.get_or_init(|| build_pool(1).expect("cannot start a worker thread")).install(f),
            },
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
            Kind::Host { workers, .. } => *workers,
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

/// Runs `f` (on a thread that is no rayon worker) on a fresh registry of
/// `workers` workers whose loops the host's parallel-for runs. A panic in
/// `f` resumes on the caller.
fn run_on_host<R: Send>(host: &dyn ParallelFor, workers: usize, f: impl FnOnce() -> R + Send) -> R {
    let mut builders = Vec::with_capacity(workers);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(workers)
        .spawn_handler(|thread| {
            builders.push(thread);
            Ok(())
        })
        .build()
        // As in `run_inline`: a spawn handler that never fails.
        .expect("a rayon registry without threads");
    let done = Arc::new((Mutex::new(false), Condvar::new()));
    let signal = Arc::clone(&done);
    let mut outcome: Option<std::thread::Result<R>> = None;
    let slot = &mut outcome as *mut Option<std::thread::Result<R>> as usize;
    let job: Box<dyn FnOnce() + Send + '_> = Box::new(move || {
        let result = catch_unwind(AssertUnwindSafe(f));
        // SAFETY: `slot` points to `outcome`, which this frame reads only
        // after `done` is set below (it waits for it before returning).
        unsafe { *(slot as *mut Option<std::thread::Result<R>>) = Some(result) };
        let (finished, wake) = &*signal;
        *finished.lock().unwrap_or_else(|e| e.into_inner()) = true;
        wake.notify_all();
    });
    // SAFETY: the job borrows `f`'s captures and `outcome` from this frame,
    // which does not end before the job has set `done` (waited for below);
    // after that the job touches only `signal`, which it owns. It cannot
    // unwind (caught above).
    let job: Box<dyn FnOnce() + Send + 'static> = unsafe { std::mem::transmute(job) };
    pool.spawn(job);
    drop(pool);
    let slots: Vec<Mutex<Option<rayon::ThreadBuilder>>> = builders.into_iter().map(|b| Mutex::new(Some(b))).collect();
    let run_worker = |i: usize| {
        if rayon::current_thread_index().is_some() {
            return; // a rayon worker already: left to the caller
        }
        let Some(worker) = slots.get(i).and_then(|s| s.lock().unwrap_or_else(|e| e.into_inner()).take()) else {
            return; // out of range, or run already
        };
        let was_worker = WORKER.with(|w| w.replace(true));
        worker.run();
        WORKER.with(|w| w.set(was_worker));
    };
    host.parallel_for(workers, &run_worker);
    (0..workers).for_each(run_worker);
    let (finished, wake) = &*done;
    let mut is_done = finished.lock().unwrap_or_else(|e| e.into_inner());
    while !*is_done {
        is_done = wake.wait(is_done).unwrap_or_else(|e| e.into_inner());
    }
    drop(is_done);
    match outcome.expect("the queued work ran before it signalled") {
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
        passes_panics_to_the_caller(&WorkerPool::new(1).unwrap());
    }

    fn passes_panics_to_the_caller(pool: &WorkerPool) {
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

    /// A parallel-for on scoped std threads, one per task, that records
    /// how many tasks it was asked for and on which threads they ran.
    #[derive(Debug, Default)]
    struct Threads {
        counts: Mutex<Vec<usize>>,
        serial: bool,
    }

    impl ParallelFor for Threads {
        fn parallel_for(&self, count: usize, task: &(dyn Fn(usize) + Sync)) {
            self.counts.lock().unwrap().push(count);
            if self.serial {
                (0..count).rev().for_each(task);
                return;
            }
            std::thread::scope(|s| {
                for i in 0..count {
                    s.spawn(move || task(i));
                }
            });
        }
    }

    #[test]
    fn a_host_parallel_for_runs_the_work_on_its_threads() {
        let host = Arc::new(Threads::default());
        let pool = WorkerPool::with_parallel_for(3, host.clone()).unwrap();
        assert_eq!(pool.threads(), 3);
        let caller = std::thread::current().id();
        let (sum, ids) = pool.install(|| {
            let ids: Vec<_> = (0..20_000)
                .into_par_iter()
                .with_max_len(1)
                .map(|i| {
                    if i % 1000 == 0 {
                        std::thread::sleep(std::time::Duration::from_millis(2));
                    }
                    std::thread::current().id()
                })
                .collect();
            ((0..100_000u64).into_par_iter().sum::<u64>(), ids)
        });
        assert_eq!(sum, 99_999 * 100_000 / 2);
        let mut threads: Vec<_> = ids.iter().collect();
        threads.sort_by_key(|id| format!("{id:?}"));
        threads.dedup();
        assert!(threads.len() > 1, "the work spread over the host's threads");
        assert!(!threads.contains(&&caller), "the host's threads, not the caller's");
        assert_eq!(*host.counts.lock().unwrap(), vec![3]);
        assert_eq!(rayon::current_thread_index(), None, "the thread is left as it was");
        assert!(!on_worker_thread());
    }

    #[test]
    fn a_host_running_tasks_one_after_another_still_finishes() {
        let host = Arc::new(Threads { serial: true, ..Threads::default() });
        let pool = WorkerPool::with_parallel_for(4, host.clone()).unwrap();
        for _ in 0..3 {
            assert_eq!(
                pool.install(|| (0..10_000u64).into_par_iter().map(|x| x * x).sum::<u64>()),
                (0..10_000u64).map(|x| x * x).sum()
            );
        }
        assert_eq!(*host.counts.lock().unwrap(), vec![4, 4, 4]);
    }

    #[test]
    fn a_host_parallel_for_passes_panics_to_the_caller() {
        passes_panics_to_the_caller(&WorkerPool::with_parallel_for(2, Arc::new(Threads::default())).unwrap());
    }

    #[test]
    fn one_host_task_is_inline() {
        let host = Arc::new(Threads::default());
        let pool = WorkerPool::with_parallel_for(1, host.clone()).unwrap();
        let caller = std::thread::current().id();
        assert_eq!(pool.install(|| std::thread::current().id()), caller);
        assert!(host.counts.lock().unwrap().is_empty(), "one thread never calls the host");
    }

    #[test]
    fn one_thread_inside_a_larger_pool_gets_one_worker() {
        let outer = WorkerPool::new(2).unwrap();
        let inner = WorkerPool::new(1).unwrap();
        let threads = outer.install(|| inner.install(rayon::current_num_threads));
        assert_eq!(threads, 1);
    }
}
