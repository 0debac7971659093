//! The message of the last failed call, and (test builds only) the hooks
//! that prove the panic boundary.

#[cfg(feature = "test-hooks")]
use super::boundary::with_system;
use super::boundary::{PlumageSystem, quietly, thread_error};
#[cfg(feature = "test-hooks")]
use super::status::PlumageStatus;
use std::ffi::c_char;

/// Copies the message of the most recent call on `sys` into `buf` (at most
/// `capacity` bytes, always NUL-terminated when `capacity > 0`) and returns
/// the size needed including the NUL. `buf` may be NULL to ask the size.
/// Every call on `sys` that returns PLUMAGE_STATUS_OK empties the message
/// (size queries and figure getters included) and every other status sets
/// it, so it always describes the latest call (with calls on several
/// threads at once, whichever ended last); this call itself changes
/// nothing. With `sys == NULL`, the same for the calling thread's most
/// recent call that had no usable system: create (OK or refused), the
/// preset init, a call given a NULL system.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; `buf` is NULL
/// or holds `capacity` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_last_error(
    sys: *const PlumageSystem,
    buf: *mut c_char,
    capacity: usize,
) -> usize {
    let message = quietly(|| {
        if sys.is_null() {
            thread_error()
        } else {
            // SAFETY: live handle (contract); reading the error is allowed even when poisoned.
            unsafe { &*sys }.last_error()
        }
    })
    .unwrap_or_default();
    let bytes = message.as_bytes_with_nul();
    if !buf.is_null() && capacity > 0 {
        let n = (bytes.len() - 1).min(capacity - 1);
        // SAFETY: buf holds `capacity` bytes (contract), n + 1 <= capacity.
        unsafe {
            std::ptr::copy_nonoverlapping(bytes.as_ptr() as *const c_char, buf, n);
            *buf.add(n) = 0;
        }
    }
    bytes.len()
}

/// Test builds only (cargo feature `test-hooks`): makes the next step,
/// evaluate or validate on `sys` panic inside the library, to prove the
/// panic boundary. Returns PLUMAGE_STATUS_OK when armed.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create` that no other
/// thread uses during the call.
#[cfg(feature = "test-hooks")]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_testing_panic_on_next_call(sys: *mut PlumageSystem) -> PlumageStatus {
    with_system(sys, |system, _| {
        system.arm_test_panic();
        Ok(())
    })
}

/// Test builds only (cargo feature `test-hooks`): 1 when `sys` is poisoned, 0 when not.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call.
#[cfg(feature = "test-hooks")]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_testing_is_poisoned(sys: *const PlumageSystem) -> u32 {
    if sys.is_null() {
        return 0;
    }
    // SAFETY: live handle (contract).
    unsafe { &*sys }.is_poisoned() as u32
}
