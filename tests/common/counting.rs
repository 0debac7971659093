//! A counting allocator for the memory tests: it wraps the system
//! allocator and keeps the live heap ([`LIVE`]) and its peak ([`PEAK`]).
//! A test binary installs it with
//! `#[global_allocator] static ALLOCATOR: Counting<false> = Counting;`
//! (every thread counted) or `Counting<true>` (only the threads marked
//! with [`count_this_thread`]).

use std::alloc::{GlobalAlloc, Layout, System as Heap};
use std::sync::atomic::{AtomicIsize, Ordering};

/// Wraps the system allocator; counts every thread, or with
/// `ONLY_MARKED` only those marked with [`count_this_thread`].
pub struct Counting<const ONLY_MARKED: bool>;

/// The live heap counted.
pub static LIVE: AtomicIsize = AtomicIsize::new(0);
/// The highest [`LIVE`] since it was last stored.
pub static PEAK: AtomicIsize = AtomicIsize::new(0);

thread_local! {
    /// Whether this thread's allocations are counted by `Counting<true>`.
    static COUNTED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Marks this thread as counted by `Counting<true>`.
pub fn count_this_thread() {
    COUNTED.with(|c| c.set(true));
}

impl<const ONLY_MARKED: bool> Counting<ONLY_MARKED> {
    fn counted() -> bool {
        !ONLY_MARKED || COUNTED.try_with(|c| c.get()).unwrap_or(false)
    }

    fn grew(by: isize) {
        if !Self::counted() {
            return;
        }
        let live = LIVE.fetch_add(by, Ordering::Relaxed) + by;
        PEAK.fetch_max(live, Ordering::Relaxed);
    }
}

// SAFETY: forwards every call to the system allocator unchanged.
unsafe impl<const ONLY_MARKED: bool> GlobalAlloc for Counting<ONLY_MARKED> {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: same contract as the caller's.
        let p = unsafe { Heap.alloc(layout) };
        if !p.is_null() {
            Self::grew(layout.size() as isize);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { Heap.dealloc(ptr, layout) };
        if Self::counted() {
            LIVE.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        // SAFETY: same contract as the caller's.
        let p = unsafe { Heap.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            Self::grew(new_size as isize - layout.size() as isize);
        }
        p
    }
}
