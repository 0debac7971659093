//! The panic boundary and error bookkeeping shared by every entry point.
//!
//! Each `extern "C"` function runs its body through one of `with_system`,
//! `with_system_ref` or `without_system`: NULL checks first, then the body
//! behind `catch_unwind`. A caught panic poisons the handle. Error messages go
//! to the handle's last-error slot, or to a thread-local slot when there is
//! no handle (e.g. a refused create). The slot describes the most recent
//! call: one that returns OK empties it.
//!
//! Silence: the first boundary call installs a process-wide panic hook once.
//! A panic on a thread that is inside a boundary call, or on a worker thread
//! of a system's pool while some boundary call is running, prints nothing;
//! its message and location are kept for `plumage_system_last_error`. Every
//! other panic goes to the hook that was installed before (the host's own,
//! or Rust's default), so the host's hook keeps working for its own code.

use super::config::HostProgress;
use super::convention::{CallResult, Failure, write_struct};
use super::status::*;
use crate::System;
use crate::progress::Progress;
use std::any::Any;
use std::cell::{Cell, RefCell, UnsafeCell};
use std::ffi::CString;
use std::panic::{AssertUnwindSafe, PanicHookInfo, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicUsize, Ordering};
use std::sync::{Mutex, Once};

/// An opaque feathering system. Create with `plumage_system_create`, free
/// with `plumage_system_destroy`.
pub struct PlumageSystem {
    /// Reached only through an [`Access`] guard: exclusive for a mutating
    /// call, shared for a read-only one.
    system: UnsafeCell<System>,
    /// Who is inside the system: [`WRITER`], or the number of read-only
    /// calls running. A call that finds it taken the other way returns
    /// `PLUMAGE_STATUS_BUSY` without touching the system.
    access: AtomicU32,
    progress: Option<HostProgress>,
    /// Held by a read-only call that reports progress (validate), so that
    /// two of them on one system never call the host's callback at once.
    progress_calls: Mutex<()>,
    poisoned: AtomicBool,
    last_error: Mutex<CString>,
    /// Whether `last_error` holds a message.
    has_error: AtomicBool,
}

impl PlumageSystem {
    pub(crate) fn new(system: System, progress: Option<HostProgress>) -> Self {
        Self {
            system: UnsafeCell::new(system),
            access: AtomicU32::new(0),
            progress,
            progress_calls: Mutex::new(()),
            poisoned: AtomicBool::new(false),
            last_error: Mutex::new(CString::default()),
            has_error: AtomicBool::new(false),
        }
    }

    fn set_error(&self, message: &str) {
        let mut slot = self.last_error.lock().unwrap_or_else(|e| e.into_inner());
        *slot = to_cstring(message);
        self.has_error.store(true, Ordering::Release);
    }

    /// Empties the last-error slot (a call returned OK). Without a message
    /// recorded this touches no lock: read-only calls stay lock-free.
    fn clear_error(&self) {
        if self.has_error.swap(false, Ordering::AcqRel) {
            *self.last_error.lock().unwrap_or_else(|e| e.into_inner()) = CString::default();
        }
    }

    pub(crate) fn set_busy_error(&self) {
        self.set_error(BUSY_MESSAGE);
    }

    pub(crate) fn last_error(&self) -> CString {
        self.last_error.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    #[cfg(feature = "test-hooks")]
    pub(crate) fn is_poisoned(&self) -> bool {
        self.poisoned.load(Ordering::SeqCst)
    }

    /// Exclusive access for a mutating call (or destroy), or `None` while
    /// any other call runs on the system.
    pub(crate) fn enter_exclusive(&self) -> Option<Access<'_>> {
        self.access.compare_exchange(0, WRITER, Ordering::Acquire, Ordering::Relaxed).ok()?;
        Some(Access { handle: self, exclusive: true })
    }

    /// Shared access for a read-only call, or `None` while a mutating call
    /// runs. Lock-free: read-only calls never wait for one another.
    pub(crate) fn enter_shared(&self) -> Option<Access<'_>> {
        let mut now = self.access.load(Ordering::Relaxed);
        loop {
            if now & WRITER != 0 || now + 1 == WRITER {
                return None;
            }
            match self.access.compare_exchange_weak(now, now + 1, Ordering::Acquire, Ordering::Relaxed) {
                Ok(_) => return Some(Access { handle: self, exclusive: false }),
                Err(seen) => now = seen,
            }
        }
    }
}

/// The `access` value of a system a mutating call is inside.
const WRITER: u32 = 1 << 31;

/// A call's admission to a system (see [`PlumageSystem::enter_exclusive`]);
/// released when dropped.
pub(crate) struct Access<'a> {
    handle: &'a PlumageSystem,
    exclusive: bool,
}

impl Access<'_> {
    pub(crate) fn system(&self) -> &System {
        // SAFETY: while an Access lives, no exclusive one exists besides it
        // (the access word admits one writer or any number of readers).
        unsafe { &*self.handle.system.get() }
    }

    pub(crate) fn system_mut(&mut self) -> &mut System {
        assert!(self.exclusive, "a shared admission does not give mutable access");
        // SAFETY: this is the only admission (exclusive), borrowed mutably.
        unsafe { &mut *self.handle.system.get() }
    }
}

impl Drop for Access<'_> {
    fn drop(&mut self) {
        if self.exclusive {
            self.handle.access.store(0, Ordering::Release);
        } else {
            self.handle.access.fetch_sub(1, Ordering::Release);
        }
    }
}

// SAFETY: the system inside the UnsafeCell is only reached through Access,
// which the atomic access word hands out as one writer or many readers;
// System itself is Send + Sync.
unsafe impl Sync for PlumageSystem {}

/// The message of a call refused because another call runs on the system.
const BUSY_MESSAGE: &str = "another call is running on this system (on another thread, or from its callback): a system takes one mutating call at a time, and no read-only call during one";

thread_local! {
    static THREAD_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

pub(crate) fn set_thread_error(message: &str) {
    THREAD_ERROR.with(|slot| *slot.borrow_mut() = to_cstring(message));
}

/// Empties this thread's last-error slot (a call without a system returned OK).
fn clear_thread_error() {
    THREAD_ERROR.with(|slot| {
        if !slot.borrow().is_empty() {
            *slot.borrow_mut() = CString::default();
        }
    });
}

pub(crate) fn thread_error() -> CString {
    THREAD_ERROR.with(|slot| slot.borrow().clone())
}

fn to_cstring(message: &str) -> CString {
    CString::new(message.replace('\0', " ")).unwrap_or_default()
}

thread_local! {
    /// Depth of boundary calls on this thread (a callback may re-enter).
    static INSIDE: Cell<u32> = const { Cell::new(0) };
}

/// Boundary calls running in the process (any thread).
static ACTIVE: AtomicUsize = AtomicUsize::new(0);

/// Where the last quiet panic happened ("file:line"), for its message.
static LAST_LOCATION: Mutex<Option<String>> = Mutex::new(None);

type Hook = Box<dyn Fn(&PanicHookInfo<'_>) + Sync + Send + 'static>;

/// Installs the quiet hook once, chaining to the hook found at that moment.
fn install_quiet_hook() {
    static INSTALL: Once = Once::new();
    INSTALL.call_once(|| std::panic::set_hook(quiet_hook(std::panic::take_hook())));
}

/// The quiet hook: Plumage's panics are recorded, every other goes to `previous`.
fn quiet_hook(previous: Hook) -> Hook {
    Box::new(move |info| {
        let ours =
            INSIDE.with(Cell::get) > 0 || (crate::workers::on_worker_thread() && ACTIVE.load(Ordering::SeqCst) > 0);
        if ours {
            let at = info.location().map(|l| format!("{}:{}", l.file(), l.line()));
            *LAST_LOCATION.lock().unwrap_or_else(|e| e.into_inner()) = at;
        } else {
            previous(info);
        }
    })
}

/// Marks the current thread as inside a boundary call while it lives.
struct Inside;

impl Inside {
    fn enter() -> Self {
        install_quiet_hook();
        INSIDE.with(|d| d.set(d.get() + 1));
        ACTIVE.fetch_add(1, Ordering::SeqCst);
        Inside
    }
}

impl Drop for Inside {
    fn drop(&mut self) {
        ACTIVE.fetch_sub(1, Ordering::SeqCst);
        INSIDE.with(|d| d.set(d.get().saturating_sub(1)));
    }
}

/// Runs `f` behind `catch_unwind` with the quiet hook active for it.
pub(crate) fn quietly<R>(f: impl FnOnce() -> R) -> std::thread::Result<R> {
    let _inside = Inside::enter();
    catch_unwind(AssertUnwindSafe(f))
}

fn panic_message(payload: &(dyn Any + Send)) -> String {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic payload".to_string());
    let at = LAST_LOCATION.lock().unwrap_or_else(|e| e.into_inner()).take();
    let at = at.map(|l| format!(" at {l}")).unwrap_or_default();
    format!("internal error (panic) in Plumage: {what}{at}; the system is poisoned, destroy it")
}

/// A call that needs exclusive access to a live system; the body gets the
/// host's progress callback (if any) as a `Progress`.
pub(crate) fn with_system(sys: *mut PlumageSystem, body: impl FnOnce(&mut System, &Progress) -> CallResult) -> u32 {
    if sys.is_null() {
        set_thread_error("system is NULL");
        return PLUMAGE_STATUS_NULL_POINTER;
    }
    // SAFETY: the caller passes a pointer from plumage_system_create that it
    // has not destroyed (header contract); other calls may be running on it,
    // so it is only read shared until the access word admits this call.
    let handle = unsafe { &*sys };
    let Some(mut access) = handle.enter_exclusive() else {
        handle.set_busy_error();
        return PLUMAGE_STATUS_BUSY;
    };
    if handle.poisoned.load(Ordering::SeqCst) {
        handle.set_error("the system is poisoned by an earlier internal error; only destroy is allowed");
        return PLUMAGE_STATUS_POISONED;
    }
    let outcome = quietly(|| {
        let progress = match &handle.progress {
            Some(p) => Progress::to(p),
            None => Progress::none(),
        };
        body(access.system_mut(), &progress)
    });
    drop(access);
    settle(handle, outcome)
}

/// A call that only reads a live system (may run concurrently with other reads).
pub(crate) fn with_system_ref(sys: *const PlumageSystem, body: impl FnOnce(&System) -> CallResult) -> u32 {
    if sys.is_null() {
        set_thread_error("system is NULL");
        return PLUMAGE_STATUS_NULL_POINTER;
    }
    // SAFETY: as in `with_system`, shared access only.
    let handle = unsafe { &*sys };
    let Some(access) = handle.enter_shared() else {
        handle.set_busy_error();
        return PLUMAGE_STATUS_BUSY;
    };
    if handle.poisoned.load(Ordering::SeqCst) {
        handle.set_error("the system is poisoned by an earlier internal error; only destroy is allowed");
        return PLUMAGE_STATUS_POISONED;
    }
    let outcome = quietly(|| body(access.system()));
    drop(access);
    settle(handle, outcome)
}

/// A read-only call that fills one caller struct with `figures` of the
/// system (the figure getters): NULL checks, then [`write_struct`].
///
/// # Safety
/// As [`with_system_ref`]; `out` is NULL or points to at least `struct_size`
/// writable bytes.
pub(crate) unsafe fn figures_out<T: Copy>(
    sys: *const PlumageSystem,
    out: *mut T,
    min_size: usize,
    name: &str,
    figures: impl FnOnce(&System) -> Result<T, Failure>,
) -> u32 {
    // SAFETY: forwarded contract.
    with_system_ref(sys, |system| unsafe { write_struct(out, min_size, name, || figures(system)) })
}

/// A read-only call that reports to the system's progress callback (and
/// may be stopped by it); such calls on one system run one at a time.
pub(crate) fn with_system_ref_progress(
    sys: *const PlumageSystem,
    body: impl FnOnce(&System, &Progress) -> CallResult,
) -> u32 {
    with_system_ref(sys, |system| {
        // SAFETY: with_system_ref checked the pointer (same contract).
        let handle = unsafe { &*sys };
        match &handle.progress {
            Some(p) => {
                let _one_at_a_time = handle.progress_calls.lock().unwrap_or_else(|e| e.into_inner());
                body(system, &Progress::to(p))
            }
            None => body(system, &Progress::none()),
        }
    })
}

fn settle(handle: &PlumageSystem, outcome: std::thread::Result<CallResult>) -> u32 {
    match outcome {
        Ok(Ok(())) => {
            handle.clear_error();
            PLUMAGE_STATUS_OK
        }
        Ok(Err(failure)) => {
            handle.set_error(&failure.message);
            failure.status
        }
        Err(payload) => {
            handle.poisoned.store(true, Ordering::SeqCst);
            handle.set_error(&panic_message(payload.as_ref()));
            PLUMAGE_STATUS_PANIC
        }
    }
}

/// A call without a system (create, and calls on the library itself).
pub(crate) fn without_system(body: impl FnOnce() -> CallResult) -> u32 {
    match quietly(body) {
        Ok(Ok(())) => {
            clear_thread_error();
            PLUMAGE_STATUS_OK
        }
        Ok(Err(failure)) => {
            set_thread_error(&failure.message);
            failure.status
        }
        Err(payload) => {
            set_thread_error(&panic_message(payload.as_ref()));
            PLUMAGE_STATUS_PANIC
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::workers::WorkerPool;

    /// Panics whose message holds this token are counted by the test hook.
    const TOKEN: &str = "quiet-hook-test";
    static FORWARDED: AtomicUsize = AtomicUsize::new(0);

    fn counting() -> Hook {
        Box::new(|info| {
            let text = info.payload().downcast_ref::<&str>().copied().unwrap_or_default();
            if text.contains(TOKEN) {
                FORWARDED.fetch_add(1, Ordering::SeqCst);
            }
        })
    }

    #[test]
    fn plumage_panics_are_silent_and_others_reach_the_previous_hook() {
        install_quiet_hook();
        let installed = std::panic::take_hook();
        std::panic::set_hook(quiet_hook(counting()));

        // Inside the boundary, on the calling thread and on a pool worker:
        // nothing reaches the previous hook, the message and place are kept.
        let status = without_system(|| panic!("quiet-hook-test: caller"));
        let caller = thread_error().into_string().unwrap();
        let pool = WorkerPool::new(2).unwrap();
        let status_worker = without_system(|| {
            pool.install(|| rayon::join(|| (), || panic!("quiet-hook-test: worker")));
            Ok(())
        });
        let worker = thread_error().into_string().unwrap();
        let silenced = FORWARDED.load(Ordering::SeqCst);

        // Outside the boundary (this thread, and a worker used directly by
        // Rust code): the previous hook sees them.
        let _ = catch_unwind(|| panic!("quiet-hook-test: host"));
        let _ = catch_unwind(AssertUnwindSafe(|| {
            pool.install(|| rayon::join(|| (), || panic!("quiet-hook-test: rust worker")))
        }));
        let forwarded = FORWARDED.load(Ordering::SeqCst);
        std::panic::set_hook(installed);

        assert_eq!((status, status_worker), (PLUMAGE_STATUS_PANIC, PLUMAGE_STATUS_PANIC));
        assert!(caller.contains("quiet-hook-test: caller") && caller.contains("boundary.rs:"), "{caller}");
        assert!(worker.contains("quiet-hook-test: worker") && worker.contains("boundary.rs:"), "{worker}");
        assert_eq!(silenced, 0, "a panic inside the boundary reached the previous hook");
        assert_eq!(forwarded, 2, "a panic outside the boundary did not reach the previous hook");
        assert_eq!((INSIDE.with(Cell::get), ACTIVE.load(Ordering::SeqCst)), (0, 0));
    }
}
