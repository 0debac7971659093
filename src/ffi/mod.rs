//! The C ABI. Every `extern "C"` function of Plumage is here and nowhere
//! else; each checks its pointers, then runs behind the panic boundary of
//! `boundary`. No algorithm lives in this module.
//!
//! By topic: the library itself and the init functions of every caller
//! struct (here), statuses (`status`), the call conventions (`convention`:
//! refusals, copy-out, `struct_size` versioning), the panic boundary and the
//! handle (`boundary`), the config and the mesh a host passes in (`config`,
//! `mesh`), create, destroy, step and evaluate (`lifecycle`), the feathers
//! read back (`feathers`), the feathers for instancing (`instancing`:
//! packed records, the template card, what changed), figures (`stats`),
//! validation and per-part figures (`validation`), saved state and
//! scrubbing (`state`), and the last error (`errors`).

// The modules in the order of their declarations in `include/plumage.h`
// (cbindgen keeps the source order; a blank line between each keeps rustfmt
// from sorting them).

// Status codes.
mod status;

// Refusals, copy-out, `struct_size` versioning.
mod convention;

// `PlumageConfig`, its constants and callbacks.
mod carry;
mod config;

// `PlumageMeshDesc`.
mod mesh;

// The handle and the panic boundary.
mod boundary;

// Create, destroy, step, evaluate.
mod lifecycle;

// Counts, feather records, triangles, the feathers as a mesh.
mod feathers;

// Instancing: packed records, the template card, what changed.
mod instancing;

// Sampling, ordering, frame and memory figures.
mod stats;

// Validation, whole or per part; per-part figures.
mod validation;

// Saved state, scrubbing.
mod state;

// The last error; test hooks.
mod errors;

pub use boundary::PlumageSystem;
pub use config::*;
pub use errors::*;
pub use feathers::*;
pub use instancing::*;
pub use lifecycle::*;
pub use mesh::{PlumageFeatherType, PlumageMeshDesc, PlumageSkeleton};
pub use state::*;
pub use stats::*;
pub use status::*;
pub use validation::*;

use boundary::without_system;
use convention::Failure;
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
///
/// # Safety
/// `cfg` is NULL or points to writable memory for one `PlumageConfig`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_config_init(cfg: *mut PlumageConfig) {
    if cfg.is_null() {
        return;
    }
    // SAFETY: non-NULL, points to a PlumageConfig (contract).
    unsafe { cfg.write(PlumageConfig::from_config(&crate::Config::default())) };
}

/// Fills `cfg` with the defaults of a preset (`PLUMAGE_PRESET_*`) and sets
/// `struct_size`: `PLUMAGE_PRESET_FEATHERS` (and its older name
/// `PLUMAGE_PRESET_SLEEK`) gives what `plumage_config_init` gives, feathers
/// with bent shafts that lie down; `PLUMAGE_PRESET_SCALES` fish scales;
/// `PLUMAGE_PRESET_KITE` rigid feathers. An unknown preset is refused
/// with PLUMAGE_STATUS_INVALID_ARGUMENT and leaves `cfg` as it was.
///
/// # Safety
/// `cfg` is NULL or points to writable memory for one `PlumageConfig`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_config_init_preset(cfg: *mut PlumageConfig, preset: u32) -> PlumageStatus {
    without_system(|| {
        if cfg.is_null() {
            return Err(Failure::null("cfg"));
        }
        let preset = preset_of(preset)?;
        // SAFETY: non-NULL, points to a PlumageConfig (contract).
        unsafe { cfg.write(PlumageConfig::from_config(&crate::Config::preset(preset))) };
        Ok(())
    })
}

/// The preset a `PLUMAGE_PRESET_*` value names.
fn preset_of(preset: u32) -> Result<crate::Preset, Failure> {
    Ok(match preset {
        PLUMAGE_PRESET_FEATHERS => crate::Preset::Feathers,
        PLUMAGE_PRESET_SCALES => crate::Preset::Scales,
        PLUMAGE_PRESET_SLEEK => crate::Preset::Sleek,
        PLUMAGE_PRESET_KITE => crate::Preset::Kite,
        p => {
            let text = format!("preset {p} is not a PLUMAGE_PRESET_* value");
            return Err(Failure::new(PLUMAGE_STATUS_INVALID_ARGUMENT, text));
        }
    })
}

/// Fills `out` with the proportions of a preset (`PLUMAGE_PRESET_*`), for
/// a type of `PlumageMeshDesc.feather_types`: `PLUMAGE_PRESET_SCALES` gives
/// short, wide scales; the others the default feather. An unknown preset
/// is refused with PLUMAGE_STATUS_INVALID_ARGUMENT and leaves `out` as it was.
///
/// # Safety
/// `out` is NULL or points to writable memory for one `PlumageFeatherType`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_feather_type_init(out: *mut PlumageFeatherType, preset: u32) -> PlumageStatus {
    without_system(|| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        let t = crate::feather::FeatherType::of_preset(preset_of(preset)?);
        // SAFETY: non-NULL, points to a PlumageFeatherType (contract).
        unsafe { out.write(PlumageFeatherType::from(t)) };
        Ok(())
    })
}

/// Sets every pointer of `mesh` to NULL, every count to 0 and sets
/// `struct_size`. NULL is ignored.
///
/// # Safety
/// `mesh` is NULL or points to writable memory for one `PlumageMeshDesc`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_mesh_desc_init(mesh: *mut PlumageMeshDesc) {
    if mesh.is_null() {
        return;
    }
    // SAFETY: non-NULL, points to a PlumageMeshDesc (contract).
    unsafe { mesh.write(PlumageMeshDesc::empty()) };
}

/// Zeroes `out` and sets `struct_size` to `sizeof(PlumageSamplingStats)`, ready for
/// `plumage_system_sampling_stats`. NULL is ignored.
///
/// # Safety
/// `out` is NULL or points to writable memory for one `PlumageSamplingStats`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_sampling_stats_init(out: *mut PlumageSamplingStats) {
    // SAFETY: NULL or writable for one PlumageSamplingStats (contract).
    unsafe { write_sized(out, |s| &mut s.struct_size) }
}

/// Zeroes `out` and sets `struct_size` to `sizeof(PlumageOrderingStats)`, ready for
/// `plumage_system_ordering_stats`. NULL is ignored.
///
/// # Safety
/// `out` is NULL or points to writable memory for one `PlumageOrderingStats`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_ordering_stats_init(out: *mut PlumageOrderingStats) {
    // SAFETY: NULL or writable for one PlumageOrderingStats (contract).
    unsafe { write_sized(out, |s| &mut s.struct_size) }
}

/// Zeroes `out` and sets `struct_size` to `sizeof(PlumageFrameStats)`, ready for
/// `plumage_system_frame_stats`. NULL is ignored.
///
/// # Safety
/// `out` is NULL or points to writable memory for one `PlumageFrameStats`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_frame_stats_init(out: *mut PlumageFrameStats) {
    // SAFETY: NULL or writable for one PlumageFrameStats (contract).
    unsafe { write_sized(out, |s| &mut s.struct_size) }
}

/// Zeroes `out` and sets `struct_size` to `sizeof(PlumageMemory)`, ready for
/// `plumage_system_memory`. NULL is ignored.
///
/// # Safety
/// `out` is NULL or points to writable memory for one `PlumageMemory`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_memory_init(out: *mut PlumageMemory) {
    // SAFETY: NULL or writable for one PlumageMemory (contract).
    unsafe { write_sized(out, |s| &mut s.struct_size) }
}

/// Zeroes `out` and sets `struct_size` to `sizeof(PlumageValidation)`, ready for
/// `plumage_system_validate`. NULL is ignored.
///
/// # Safety
/// `out` is NULL or points to writable memory for one `PlumageValidation`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_validation_init(out: *mut PlumageValidation) {
    // SAFETY: NULL or writable for one PlumageValidation (contract).
    unsafe { write_sized(out, |s| &mut s.struct_size) }
}

/// Zeroes `out` and sets `struct_size` to `sizeof(PlumagePartStats)`, ready for
/// `plumage_system_part_stats`. NULL is ignored.
///
/// # Safety
/// `out` is NULL or points to writable memory for one `PlumagePartStats`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_part_stats_init(out: *mut PlumagePartStats) {
    // SAFETY: NULL or writable for one PlumagePartStats (contract).
    unsafe { write_sized(out, |s| &mut s.struct_size) }
}

/// Writes `T::default()` with its `struct_size` (chosen by `field`) set to
/// `size_of::<T>()`, unless `out` is NULL.
///
/// # Safety
/// `out` is NULL or points to writable memory for one `T`.
unsafe fn write_sized<T: Default>(out: *mut T, field: impl FnOnce(&mut T) -> &mut u32) {
    if out.is_null() {
        return;
    }
    let mut value = T::default();
    *field(&mut value) = std::mem::size_of::<T>() as u32;
    // SAFETY: non-NULL and writable for one T (caller's contract).
    unsafe { out.write(value) };
}
