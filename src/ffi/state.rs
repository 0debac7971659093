//! Saved state and scrubbing: a frame saved as a byte blob and loaded
//! back, and seeking to a frame through the kept checkpoints.

use super::boundary::{PlumageSystem, with_system, with_system_ref};
use super::convention::{Failure, copy_out};
use super::status::*;

/// Saves the current frame (what the last successful create, step,
/// evaluate or load left) as a byte blob, so that a later
/// `plumage_system_load_state` resumes from it: the frames stepped after a
/// load are byte-identical to those stepped after the save. Copy-out
/// convention in bytes: `*out_len` receives the blob's size; a NULL or too
/// small `buf` gives PLUMAGE_STATUS_BUFFER_TOO_SMALL and writes nothing
/// else, so call once with NULL to learn the size. The blob is versioned
/// and checksummed, and only a system created from the same mesh,
/// per-vertex attributes and configuration accepts it (the thread count
/// may differ).
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `buf` is NULL
/// or holds `capacity` writable bytes; `out_len` is NULL or points to a
/// writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_save_state(
    sys: *const PlumageSystem,
    buf: *mut u8,
    capacity: usize,
    out_len: *mut usize,
) -> PlumageStatus {
    with_system_ref(sys, |system| copy_out(&system.save_state(), buf, capacity, out_len))
}

/// Resumes from a blob of `len` bytes written by
/// `plumage_system_save_state`: the feathers, reports and frame count
/// become those of the saved frame, and later steps continue exactly as
/// they did after the save. A NULL `blob` gives PLUMAGE_STATUS_NULL_POINTER;
/// a truncated, corrupt or foreign blob (from a system with another mesh,
/// roots or configuration, or of another format version) gives
/// PLUMAGE_STATUS_INVALID_STATE. On any error the system is exactly as it
/// was. The blob is only read during the call.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create` that no other
/// thread uses during the call. `blob` is NULL or holds `len` readable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_load_state(
    sys: *mut PlumageSystem,
    blob: *const u8,
    len: usize,
) -> PlumageStatus {
    with_system(sys, |system, _| {
        if blob.is_null() {
            return Err(Failure::null("blob"));
        }
        if len > isize::MAX as usize {
            return Err(Failure::new(PLUMAGE_STATUS_SIZE_OVERFLOW, format!("blob length {len} is too large")));
        }
        // SAFETY: non-NULL, `len` readable bytes (contract), len <= isize::MAX.
        let bytes = unsafe { std::slice::from_raw_parts(blob, len) };
        system.load_state(bytes)?;
        Ok(())
    })
}

/// Scrubbing with keyframed checkpoints (`PlumageConfig.checkpoint_interval`
/// K > 0: after create and every K-th step of the playback the system keeps
/// its state blob in memory, at most `checkpoint_cap` besides the first).
/// Prepares the system to reach the state after `frame_index` steps and
/// writes to `*out_from` the frame count it now stands at: the caller then
/// steps it with the positions of frames `*out_from` .. `frame_index` − 1
/// of its clip (step k takes the clip's frame k) and gets byte for byte
/// what playback gave. Seeking forward within the playback keeps the
/// current frame; otherwise the nearest checkpoint at or before
/// `frame_index` is loaded. After `plumage_system_evaluate` or
/// `plumage_system_load_state` no checkpoints are kept until a seek.
/// Checkpoints off: PLUMAGE_STATUS_INVALID_ARGUMENT. On any error the
/// system is exactly as it was.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create` that no other
/// thread uses during the call. `out_from` is NULL or points to a writable
/// `uint64_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_seek(
    sys: *mut PlumageSystem,
    frame_index: u64,
    out_from: *mut u64,
) -> PlumageStatus {
    with_system(sys, |system, _| {
        if out_from.is_null() {
            return Err(Failure::null("out_from"));
        }
        let from = system.seek(frame_index)?;
        // SAFETY: non-NULL, points to a writable uint64_t (contract).
        unsafe { *out_from = from };
        Ok(())
    })
}
