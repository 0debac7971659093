//! The C ABI. Every `extern "C"` function of Plumage is here and nowhere
//! else; each checks its pointers, then runs behind the panic boundary of
//! [`boundary`]. No algorithm lives in this module.

mod boundary;
mod status;
mod types;

pub use boundary::PlumageSystem;
pub use status::*;
pub use types::*;

use boundary::{Failure, thread_error, with_system, with_system_ref, without_system};
use std::ffi::c_char;

/// The ABI version of this header; bumped only by incompatible changes.
pub const PLUMAGE_ABI_VERSION: u32 = 1;

static VERSION: &std::ffi::CStr =
    match std::ffi::CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes()) {
        Ok(v) => v,
        Err(_) => panic!("version string"),
    };

/// The library version as "MAJOR.MINOR.PATCH". The string is static.
#[unsafe(no_mangle)]
pub extern "C" fn plumage_version() -> *const c_char {
    VERSION.as_ptr()
}

/// The ABI version the library was built with; compare with `PLUMAGE_ABI_VERSION`.
#[unsafe(no_mangle)]
pub extern "C" fn plumage_abi_version() -> u32 {
    PLUMAGE_ABI_VERSION
}

/// The name of a status code ("OK", "NULL_POINTER", ...), or "UNKNOWN_STATUS"
/// for a number this library does not define. Never NULL; the string is static.
#[unsafe(no_mangle)]
pub extern "C" fn plumage_status_name(status: u32) -> *const c_char {
    STATUS_NAMES.iter().find(|(code, _)| *code == status).map_or(c"UNKNOWN_STATUS".as_ptr(), |(_, name)| name.as_ptr())
}

/// Fills `cfg` with the defaults and sets `struct_size`. NULL is ignored.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_config_init(cfg: *mut PlumageConfig) {
    if cfg.is_null() {
        return;
    }
    // SAFETY: non-NULL, points to a PlumageConfig (contract).
    unsafe { cfg.write(PlumageConfig::from_config(&crate::Config::default())) };
}

/// Sets every pointer of `mesh` to NULL, every count to 0 and sets
/// `struct_size`. NULL is ignored.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_mesh_desc_init(mesh: *mut PlumageMeshDesc) {
    if mesh.is_null() {
        return;
    }
    // SAFETY: non-NULL, points to a PlumageMeshDesc (contract).
    unsafe { mesh.write(PlumageMeshDesc::empty()) };
}

/// Creates a system on the rest mesh `rest` with `cfg` (NULL = defaults).
/// On success `*out` receives the new system; on any error `*out` is set to
/// NULL (when `out` is not NULL) and the message is available from
/// `plumage_system_last_error(NULL, ...)` on the same thread.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_create(
    cfg: *const PlumageConfig,
    rest: *const PlumageMeshDesc,
    out: *mut *mut PlumageSystem,
) -> u32 {
    without_system(|| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        // SAFETY: non-NULL out (contract: points to a PlumageSystem*).
        unsafe { *out = std::ptr::null_mut() };
        // SAFETY: forwarded pointer contracts of this function.
        let config = unsafe { types::read_config(cfg) }?;
        let mesh = unsafe { types::read_mesh(rest) }?;
        let system = crate::System::new(&config, &mesh)?;
        let handle = Box::into_raw(Box::new(PlumageSystem::new(system)));
        // SAFETY: as above.
        unsafe { *out = handle };
        Ok(())
    })
}

/// Frees a system and everything it owns. NULL is a no-op. Works on a
/// poisoned system too.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_destroy(sys: *mut PlumageSystem) {
    if sys.is_null() {
        return;
    }
    let _ = std::panic::catch_unwind(|| {
        // SAFETY: from plumage_system_create, not yet destroyed (contract).
        drop(unsafe { Box::from_raw(sys) });
    });
}

/// Advances the animation by one frame: `positions` holds xyz for each of
/// the rest mesh's `vertex_count` vertices, in the caller's numbering. On
/// any error the system is exactly as before the call.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_step(
    sys: *mut PlumageSystem,
    positions: *const f32,
    vertex_count: usize,
) -> u32 {
    with_system(sys, |system| {
        // SAFETY: forwarded contract.
        let frame = unsafe { frame_positions(positions, vertex_count) }?;
        system.step(frame)?;
        Ok(())
    })
}

/// Solves the pose given by `positions` from scratch, independent of the
/// frames stepped before. On any error the system is exactly as before.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_evaluate(
    sys: *mut PlumageSystem,
    positions: *const f32,
    vertex_count: usize,
) -> u32 {
    with_system(sys, |system| {
        // SAFETY: forwarded contract.
        let frame = unsafe { frame_positions(positions, vertex_count) }?;
        system.evaluate(frame)?;
        Ok(())
    })
}

/// Writes the number of feathers to `*out`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_feather_count(sys: *const PlumageSystem, out: *mut usize) -> u32 {
    with_system_ref(sys, |system| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        // SAFETY: non-NULL, points to a size_t (contract).
        unsafe { *out = system.feather_count() };
        Ok(())
    })
}

/// Copies the message of the last failed call on `sys` into `buf` (at most
/// `capacity` bytes, always NUL-terminated when `capacity > 0`) and returns
/// the size needed including the NUL. `buf` may be NULL to ask the size.
/// With `sys == NULL`, reports the last failure on the calling thread of a
/// call that had no usable system (a refused create, a NULL system). An
/// empty string means no failure was recorded.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_last_error(
    sys: *const PlumageSystem,
    buf: *mut c_char,
    capacity: usize,
) -> usize {
    let message = std::panic::catch_unwind(|| {
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

/// The frame's positions as a slice, after NULL and size checks.
unsafe fn frame_positions<'a>(positions: *const f32, vertex_count: usize) -> Result<&'a [f32], Failure> {
    if positions.is_null() {
        return Err(Failure::null("positions"));
    }
    let n = types::checked_len(vertex_count, 3, "vertex_count")?;
    // SAFETY: non-NULL, `3 * vertex_count` floats (contract).
    Ok(unsafe { std::slice::from_raw_parts(positions, n) })
}
