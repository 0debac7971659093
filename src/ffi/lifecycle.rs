//! A system's life: create (from a config and a rest mesh), destroy, and
//! the two calls that move it to a new pose, step (frame to frame) and
//! evaluate (from scratch).

use super::boundary::{PlumageSystem, quietly, with_system, without_system};
use super::config::{HostConfig, PlumageConfig, read_config};
use super::convention::Failure;
use super::mesh::{PlumageMeshDesc, checked_len, read_mesh};
use super::status::PlumageStatus;
use super::status::{PLUMAGE_STATUS_BUSY, PLUMAGE_STATUS_OK};

/// Creates a system on the rest mesh `rest` with `cfg` (NULL = defaults).
/// On success `*out` receives the new system; on any error `*out` is set to
/// NULL (when `out` is not NULL) and the message is available from
/// `plumage_system_last_error(NULL, ...)` on the same thread.
///
/// # Safety
/// `cfg` is NULL or points to a `PlumageConfig` whose `struct_size` bytes are
/// readable; `rest` is NULL or points to a `PlumageMeshDesc` whose arrays hold
/// the counts it states; `out` is NULL or points to writable memory for one
/// pointer. The config and the mesh's arrays are copied and not read after
/// the call returns; the config's callbacks (`progress`, `parallel_for`)
/// and their `progress_user_data` and `parallel_for_context` are kept and
/// may be called during any later call on the system, until destroy
/// returns OK: they must stay valid that long.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_create(
    cfg: *const PlumageConfig,
    rest: *const PlumageMeshDesc,
    out: *mut *mut PlumageSystem,
) -> PlumageStatus {
    without_system(|| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        // SAFETY: non-NULL out (contract: points to a PlumageSystem*).
        unsafe { *out = std::ptr::null_mut() };
        // SAFETY: forwarded pointer contracts of this function.
        let HostConfig { config, progress: host_progress, parallel_for } = unsafe { read_config(cfg) }?;
        let mut types = Vec::new();
        let mesh = unsafe { read_mesh(rest, &mut types) }?;
        let progress = match &host_progress {
            Some(p) => crate::progress::Progress::to(p),
            None => crate::progress::Progress::none(),
        };
        let system = crate::System::new_with_parallel_for(&config, &mesh, &progress, parallel_for)?;
        let handle = Box::into_raw(Box::new(PlumageSystem::new(system, host_progress)));
        // SAFETY: as above.
        unsafe { *out = handle };
        Ok(())
    })
}

/// Frees a system and everything it owns. NULL is a no-op (OK). Works on a
/// poisoned system too. Returns PLUMAGE_STATUS_BUSY, freeing nothing, when
/// another call is running on the system (see PLUMAGE_STATUS_BUSY).
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`, not used again
/// after a call that returned OK. (The BUSY guard catches a call that
/// overlaps this one; a call made after the system is freed cannot be caught.)
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_destroy(sys: *mut PlumageSystem) -> PlumageStatus {
    if sys.is_null() {
        return PLUMAGE_STATUS_OK;
    }
    // SAFETY: a live handle (contract); read shared until admitted.
    let handle = unsafe { &*sys };
    let Some(access) = handle.enter_exclusive() else {
        handle.set_busy_error();
        return PLUMAGE_STATUS_BUSY;
    };
    // Admitted: nobody else is inside, and the memory goes away with it.
    std::mem::forget(access);
    let _ = quietly(|| {
        // SAFETY: from plumage_system_create, not yet destroyed (contract).
        drop(unsafe { Box::from_raw(sys) });
    });
    PLUMAGE_STATUS_OK
}

/// Advances the animation by one frame: `positions` holds xyz for each of
/// the rest mesh's `vertex_count` vertices, in the caller's numbering. On
/// any error the system is exactly as before the call.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create` that no other
/// thread uses during the call. `positions` is NULL or holds `3 * vertex_count`
/// readable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_step(
    sys: *mut PlumageSystem,
    positions: *const f32,
    vertex_count: usize,
) -> PlumageStatus {
    with_system(sys, |system, progress| {
        // SAFETY: forwarded contract.
        let frame = unsafe { frame_positions(positions, vertex_count) }?;
        system.step_with_progress(frame, progress)?;
        Ok(())
    })
}

/// Solves the pose given by `positions` from scratch, independent of the
/// frames stepped before. On any error the system is exactly as before.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create` that no other
/// thread uses during the call. `positions` is NULL or holds `3 * vertex_count`
/// readable floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_evaluate(
    sys: *mut PlumageSystem,
    positions: *const f32,
    vertex_count: usize,
) -> PlumageStatus {
    with_system(sys, |system, progress| {
        // SAFETY: forwarded contract.
        let frame = unsafe { frame_positions(positions, vertex_count) }?;
        system.evaluate_with_progress(frame, progress)?;
        Ok(())
    })
}

/// The frame's positions as a slice, after NULL and size checks.
unsafe fn frame_positions<'a>(positions: *const f32, vertex_count: usize) -> Result<&'a [f32], Failure> {
    if positions.is_null() {
        return Err(Failure::null("positions"));
    }
    let n = checked_len(vertex_count, 3, "vertex_count")?;
    // SAFETY: non-NULL, `3 * vertex_count` floats (contract).
    Ok(unsafe { std::slice::from_raw_parts(positions, n) })
}
