//! The C ABI. Every `extern "C"` function of Plumage is here and nowhere
//! else; each checks its pointers, then runs behind the panic boundary of
//! `boundary`. No algorithm lives in this module.

mod boundary;
mod status;
mod types;

pub use boundary::PlumageSystem;
pub use status::*;
pub use types::*;

use boundary::{
    Failure, copy_out, read_versioned, thread_error, with_system, with_system_ref, with_system_ref_progress,
    without_system, write_versioned,
};
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
/// `struct_size`: `PLUMAGE_PRESET_FEATHERS` gives what `plumage_config_init`
/// gives; `PLUMAGE_PRESET_SCALES` fish scales. An unknown preset is refused
/// with PLUMAGE_STATUS_INVALID_ARGUMENT and leaves `cfg` as it was.
///
/// # Safety
/// `cfg` is NULL or points to writable memory for one `PlumageConfig`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_config_init_preset(cfg: *mut PlumageConfig, preset: u32) -> u32 {
    without_system(|| {
        if cfg.is_null() {
            return Err(Failure::null("cfg"));
        }
        let preset = match preset {
            PLUMAGE_PRESET_FEATHERS => crate::Preset::Feathers,
            PLUMAGE_PRESET_SCALES => crate::Preset::Scales,
            p => {
                return Err(Failure::new(
                    PLUMAGE_STATUS_INVALID_ARGUMENT,
                    format!("preset {p} is not a PLUMAGE_PRESET_* value"),
                ));
            }
        };
        // SAFETY: non-NULL, points to a PlumageConfig (contract).
        unsafe { cfg.write(PlumageConfig::from_config(&crate::Config::preset(preset))) };
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

/// Creates a system on the rest mesh `rest` with `cfg` (NULL = defaults).
/// On success `*out` receives the new system; on any error `*out` is set to
/// NULL (when `out` is not NULL) and the message is available from
/// `plumage_system_last_error(NULL, ...)` on the same thread.
///
/// # Safety
/// `cfg` is NULL or points to a `PlumageConfig` whose `struct_size` bytes are
/// readable; `rest` is NULL or points to a `PlumageMeshDesc` whose arrays hold
/// the counts it states; `out` is NULL or points to writable memory for one
/// pointer. Nothing is kept after the call returns.
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
        let types::HostConfig { config, progress: host_progress, parallel_for } = unsafe { types::read_config(cfg) }?;
        let mesh = unsafe { types::read_mesh(rest) }?;
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

/// Frees a system and everything it owns. NULL is a no-op. Works on a
/// poisoned system too.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`, not used again
/// afterwards and not in use by another thread.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_destroy(sys: *mut PlumageSystem) {
    if sys.is_null() {
        return;
    }
    let _ = boundary::quietly(|| {
        // SAFETY: from plumage_system_create, not yet destroyed (contract).
        drop(unsafe { Box::from_raw(sys) });
    });
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
) -> u32 {
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
) -> u32 {
    with_system(sys, |system, progress| {
        // SAFETY: forwarded contract.
        let frame = unsafe { frame_positions(positions, vertex_count) }?;
        system.evaluate_with_progress(frame, progress)?;
        Ok(())
    })
}

/// Writes the number of feathers to `*out`.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `out` is NULL
/// or points to a writable `size_t`.
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

/// Writes the number of vertices every frame must provide (the rest mesh's
/// count, in the caller's numbering) to `*out`.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `out` is NULL
/// or points to a writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_vertex_count(sys: *const PlumageSystem, out: *mut usize) -> u32 {
    with_system_ref(sys, |system| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        // SAFETY: non-NULL, points to a size_t (contract).
        unsafe { *out = system.vertex_count() };
        Ok(())
    })
}

/// Copies one `PlumageFeather` per feather into `buf` (`capacity` elements).
/// `*out_len` receives the feather count; a NULL or too small `buf` gives
/// PLUMAGE_STATUS_BUFFER_TOO_SMALL and writes nothing else.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `buf` is NULL
/// or holds `capacity` writable elements; `out_len` is NULL or points to a
/// writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_feathers(
    sys: *const PlumageSystem,
    buf: *mut PlumageFeather,
    capacity: usize,
    out_len: *mut usize,
) -> u32 {
    with_system_ref(sys, |system| {
        let records: Vec<PlumageFeather> = system.feathers().iter().map(PlumageFeather::from).collect();
        copy_out(&records, buf, capacity, out_len)
    })
}

/// Copies the feathers' triangles as xyz floats, in the order of
/// `plumage_system_feathers`; `capacity` and `*out_len` count floats. A
/// feather of one shaft segment (the default, `shaft_segments` = 1) has two
/// triangles of three corners, 18 floats: (root, tip, left corner), (root,
/// right corner, tip), where "left" lies on the binormal side (normal ×
/// shaft); both face away from the skin, and the root and tip corners of
/// the two triangles are bit-identical, so a host can share them. With S ≥ 2
/// segments each feather has 4·S − 4 triangles (9 floats each), in the
/// order of `plumage_system_feather_geometry`'s indices; that call also
/// gives shared vertices, normals and UVs.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `xyz` is NULL
/// or holds `capacity` writable floats; `out_len` is NULL or points to a
/// writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_feather_triangles(
    sys: *const PlumageSystem,
    xyz: *mut f32,
    capacity: usize,
    out_len: *mut usize,
) -> u32 {
    with_system_ref(sys, |system| copy_out(system.feather_triangles().as_flattened(), xyz, capacity, out_len))
}

/// Fills `geometry` with NULL buffers, zero capacities and totals, and sets
/// `struct_size`. NULL is ignored.
///
/// # Safety
/// `geometry` is NULL or points to writable memory for one `PlumageFeatherGeometry`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_feather_geometry_init(geometry: *mut PlumageFeatherGeometry) {
    if geometry.is_null() {
        return;
    }
    // SAFETY: non-NULL, points to a PlumageFeatherGeometry (contract).
    unsafe { geometry.write(PlumageFeatherGeometry::empty()) };
}

/// Copies every feather out as a mesh at the current pose: positions,
/// normals, UVs, triangle indices, the feather of each vertex, per-feather
/// vertex and triangle counts and whether each feather is placed (see
/// `PlumageFeatherGeometry` for the layout). The totals are always written
/// back. Each non-NULL buffer must hold what it is for; if any is too
/// small the call returns PLUMAGE_STATUS_BUFFER_TOO_SMALL (naming it) and
/// writes no buffer, so call once with no buffers to learn the totals.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `geometry`
/// is NULL or points to a `PlumageFeatherGeometry` whose `struct_size` bytes
/// are readable and writable and whose non-NULL buffers hold their stated
/// capacities of writable elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_feather_geometry(
    sys: *const PlumageSystem,
    geometry: *mut PlumageFeatherGeometry,
) -> u32 {
    with_system_ref(sys, |system| {
        if geometry.is_null() {
            return Err(Failure::null("geometry"));
        }
        let size = std::mem::size_of::<PlumageFeatherGeometry>();
        // SAFETY: non-NULL, caller struct of struct_size bytes (contract).
        let mut io =
            unsafe { read_versioned(geometry, size, PlumageFeatherGeometry::empty(), "PlumageFeatherGeometry") }?;
        let mesh = system.feather_mesh();
        io.feather_count = mesh.vertex_counts.len() as u64;
        io.vertex_count = mesh.positions.len() as u64;
        io.triangle_count = mesh.indices.len() as u64;
        // SAFETY: as above; only the totals change.
        unsafe { write_versioned(geometry, size, io, "PlumageFeatherGeometry") }?;
        let flat = |v: &[[f32; 3]]| v.as_flattened().to_vec();
        let buffers = GeometryBuffers {
            floats: [
                ("positions", io.positions, io.positions_capacity, flat(&mesh.positions)),
                ("normals", io.normals, io.normals_capacity, flat(&mesh.normals)),
                ("uvs", io.uvs, io.uvs_capacity, mesh.uvs.as_flattened().to_vec()),
            ],
            indices: [
                ("indices", io.indices, io.indices_capacity, mesh.indices.as_flattened().to_vec()),
                ("vertex_feathers", io.vertex_feathers, io.vertex_feathers_capacity, mesh.vertex_feathers),
                ("vertex_counts", io.vertex_counts, io.vertex_counts_capacity, mesh.vertex_counts),
                ("triangle_counts", io.triangle_counts, io.triangle_counts_capacity, mesh.triangle_counts),
            ],
            bytes: [("placed", io.placed, io.placed_capacity, mesh.placed)],
        };
        buffers.check()?;
        // SAFETY: every non-NULL buffer holds its capacity (contract), checked above to be enough.
        unsafe { buffers.write() };
        Ok(())
    })
}

/// The buffers of one `plumage_system_feather_geometry` call with what
/// goes into each: (name, caller pointer, capacity, contents).
struct GeometryBuffers {
    floats: [(&'static str, *mut f32, usize, Vec<f32>); 3],
    indices: [(&'static str, *mut u32, usize, Vec<u32>); 4],
    bytes: [(&'static str, *mut u8, usize, Vec<u8>); 1],
}

impl GeometryBuffers {
    /// Refuses the call when a given buffer is too small for its contents.
    fn check(&self) -> Result<(), Failure> {
        let sizes = self.floats.iter().map(|(n, p, c, v)| (*n, p.is_null(), *c, v.len()));
        let sizes = sizes
            .chain(self.indices.iter().map(|(n, p, c, v)| (*n, p.is_null(), *c, v.len())))
            .chain(self.bytes.iter().map(|(n, p, c, v)| (*n, p.is_null(), *c, v.len())));
        for (name, null, capacity, needed) in sizes {
            if !null && capacity < needed {
                return Err(Failure::new(
                    PLUMAGE_STATUS_BUFFER_TOO_SMALL,
                    format!("PlumageFeatherGeometry.{name} holds {capacity} elements but {needed} are needed"),
                ));
            }
        }
        Ok(())
    }

    /// Copies the contents into every non-NULL buffer.
    ///
    /// # Safety
    /// Every non-NULL pointer holds at least as many elements as its contents.
    unsafe fn write(&self) {
        fn put<T: Copy>(ptr: *mut T, items: &[T]) {
            if !ptr.is_null() {
                // SAFETY: the caller's buffer holds items.len() elements (checked).
                unsafe { std::ptr::copy_nonoverlapping(items.as_ptr(), ptr, items.len()) };
            }
        }
        self.floats.iter().for_each(|(_, p, _, v)| put(*p, v));
        self.indices.iter().for_each(|(_, p, _, v)| put(*p, v));
        self.bytes.iter().for_each(|(_, p, _, v)| put(*p, v));
    }
}

/// Sampling quality figures of the roots. PLUMAGE_STATUS_NOT_AVAILABLE when
/// no roots have been planted.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `out` is NULL
/// or points to a struct whose `struct_size` is set and whose `struct_size`
/// bytes are writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_sampling_stats(
    sys: *const PlumageSystem,
    out: *mut PlumageSamplingStats,
) -> u32 {
    with_system_ref(sys, |system| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        let r = system.sampling_report().ok_or_else(|| not_available("sampling figures"))?;
        let value = PlumageSamplingStats {
            struct_size: 0,
            roots: r.roots as u32,
            spacing: r.spacing,
            relative_radius: r.relative_radius,
            coverage_gap: r.coverage_gap,
            alignment: r.alignment,
            seconds: r.seconds,
        };
        // SAFETY: non-NULL, caller struct of struct_size bytes (contract).
        unsafe { write_versioned(out, std::mem::size_of::<PlumageSamplingStats>(), value, "PlumageSamplingStats") }
    })
}

/// Static ordering figures. PLUMAGE_STATUS_NOT_AVAILABLE before any order exists.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `out` is NULL
/// or points to a struct whose `struct_size` is set and whose `struct_size`
/// bytes are writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_ordering_stats(
    sys: *const PlumageSystem,
    out: *mut PlumageOrderingStats,
) -> u32 {
    with_system_ref(sys, |system| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        let r = system.ordering_report().ok_or_else(|| not_available("ordering figures"))?;
        let value = PlumageOrderingStats {
            struct_size: 0,
            pairs: r.pairs as u32,
            edges: r.edges as u32,
            dropped_edges: r.dropped_edges as u32,
            violations: r.violations as u32,
            reserved: 0,
            seconds: r.seconds,
        };
        // SAFETY: non-NULL, caller struct of struct_size bytes (contract).
        unsafe { write_versioned(out, std::mem::size_of::<PlumageOrderingStats>(), value, "PlumageOrderingStats") }
    })
}

/// What the last successful create, step or evaluate did.
/// PLUMAGE_STATUS_NOT_AVAILABLE before feathers exist.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `out` is NULL
/// or points to a struct whose `struct_size` is set and whose `struct_size`
/// bytes are writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_frame_stats(sys: *const PlumageSystem, out: *mut PlumageFrameStats) -> u32 {
    with_system_ref(sys, |system| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        let r = system.frame_report().ok_or_else(|| not_available("frame figures"))?;
        let feathers = system.feather_count().max(1) as f64;
        let value = PlumageFrameStats {
            struct_size: 0,
            clamped: r.clamped as u32,
            frame_index: r.frame_index,
            adjusted: r.adjusted as u64,
            collision_tests: r.collision_tests,
            collision_tests_per_feather: r.collision_tests_per_feather(),
            priority_changes: r.priority_changes as u64,
            priority_change_percent: 100.0 * r.priority_changes as f64 / feathers,
            reversals: r.reversals as u64,
            reversals_refused: r.reversals_refused as u64,
            cycles_broken: r.cycles_broken as u64,
            reorder_seconds: r.reorder_seconds,
            adjust_seconds: r.adjust_seconds,
            step_seconds: r.step_seconds,
            deformed: r.deformed as u64,
            seeds: r.seeds as u64,
            verified: r.verified as u64,
            neighbourhood_seconds: r.neighbourhood_seconds,
            levels: r.levels as u64,
            pops: system.pose_changes().pops as u64,
            largest_pose_change_deg: f64::from(system.pose_changes().largest).to_degrees(),
        };
        // SAFETY: non-NULL, caller struct of struct_size bytes (contract).
        unsafe { write_versioned(out, FRAME_STATS_V1_SIZE, value, "PlumageFrameStats") }
    })
}

/// Runs the exact validation (triangle–triangle intersections, body
/// penetrations, coverage, mean pitch) on the current feathers. Only reads
/// the system. PLUMAGE_STATUS_NOT_AVAILABLE before feathers exist. Reports
/// PLUMAGE_PHASE_VALIDATING to the system's progress callback, which may stop
/// it (PLUMAGE_STATUS_INTERRUPTED, no result written).
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `out` is NULL
/// or points to a struct whose `struct_size` is set and whose `struct_size`
/// bytes are writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_validate(sys: *const PlumageSystem, out: *mut PlumageValidation) -> u32 {
    with_system_ref_progress(sys, |system, progress| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        let r = system.validate_with_progress(progress)?.ok_or_else(|| not_available("validation"))?;
        let value = PlumageValidation {
            struct_size: 0,
            reserved: 0,
            intersecting_pairs: r.intersecting_pairs as u64,
            body_penetrations: r.body_penetrations as u64,
            coverage: r.coverage,
            mean_pitch_deg: r.mean_pitch_deg,
            probes: r.probes as u64,
            buried_probes: r.buried_probes as u64,
            tip_height_median: r.tip_height_median,
            tip_height_p90: r.tip_height_p90,
            bristle_percent: r.bristle_percent,
        };
        // SAFETY: non-NULL, caller struct of struct_size bytes (contract).
        unsafe { write_versioned(out, VALIDATION_V1_SIZE, value, "PlumageValidation") }
    })
}

/// `plumage_system_validate` restricted to a part of the mesh: the
/// caller's triangles `first_triangle .. first_triangle + triangle_count`
/// of the rest mesh given to create (e.g. one of several meshes a host
/// dresses as one system, their triangles one after the other). Every
/// feather still counts as an obstacle and as a cover: `intersecting_pairs`
/// counts the pairs with at least one feather rooted on the part (so a
/// pair across two parts counts in both); `body_penetrations`,
/// `mean_pitch_deg` and the tip heights are those of the part's feathers;
/// the coverage probes are drawn on the part's skin (as many per feather as
/// the whole validation draws). Only reads the system.
/// PLUMAGE_STATUS_INDEX_OUT_OF_RANGE when the range runs past the mesh's
/// triangles; PLUMAGE_STATUS_NOT_AVAILABLE before feathers exist.
///
/// # Safety
/// As `plumage_system_validate`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_validate_part(
    sys: *const PlumageSystem,
    first_triangle: usize,
    triangle_count: usize,
    out: *mut PlumageValidation,
) -> u32 {
    with_system_ref(sys, |system| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        let range = part_range(system, first_triangle, triangle_count)?;
        let r = system.validate_part(range).ok_or_else(|| not_available("validation"))?;
        let value = PlumageValidation {
            struct_size: 0,
            reserved: 0,
            intersecting_pairs: r.intersecting_pairs as u64,
            body_penetrations: r.body_penetrations as u64,
            coverage: r.coverage,
            mean_pitch_deg: r.mean_pitch_deg,
            probes: r.probes as u64,
            buried_probes: r.buried_probes as u64,
            tip_height_median: r.tip_height_median,
            tip_height_p90: r.tip_height_p90,
            bristle_percent: r.bristle_percent,
        };
        // SAFETY: non-NULL, caller struct of struct_size bytes (contract).
        unsafe { write_versioned(out, VALIDATION_V1_SIZE, value, "PlumageValidation") }
    })
}

/// The last create, step or evaluate's figures for the feathers rooted on
/// the caller's triangles `first_triangle .. first_triangle +
/// triangle_count` (see `PlumagePartStats`). Only reads the system.
/// PLUMAGE_STATUS_INDEX_OUT_OF_RANGE when the range runs past the mesh's
/// triangles.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `out` is NULL
/// or points to a struct whose `struct_size` is set and whose `struct_size`
/// bytes are writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_part_stats(
    sys: *const PlumageSystem,
    first_triangle: usize,
    triangle_count: usize,
    out: *mut PlumagePartStats,
) -> u32 {
    with_system_ref(sys, |system| {
        if out.is_null() {
            return Err(Failure::null("out"));
        }
        let r = system.part_report(part_range(system, first_triangle, triangle_count)?);
        let value = PlumagePartStats {
            struct_size: 0,
            reserved: 0,
            feathers: r.feathers as u64,
            placed: r.placed as u64,
            adjusted: r.adjusted as u64,
            pops: r.pops as u64,
            largest_pose_change_deg: f64::from(r.largest_pose_change).to_degrees(),
        };
        // SAFETY: non-NULL, caller struct of struct_size bytes (contract).
        unsafe { write_versioned(out, std::mem::size_of::<PlumagePartStats>(), value, "PlumagePartStats") }
    })
}

/// The caller's triangles `first .. first + count`, checked against the rest mesh.
fn part_range(system: &crate::System, first: usize, count: usize) -> Result<std::ops::Range<u32>, Failure> {
    let total = system.caller_triangle_count();
    match first.checked_add(count) {
        Some(end) if end <= total => Ok(first as u32..end as u32),
        _ => Err(Failure::new(
            PLUMAGE_STATUS_INDEX_OUT_OF_RANGE,
            format!("triangles {first} + {count} run past the mesh's {total} triangles"),
        )),
    }
}

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
) -> u32 {
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
pub unsafe extern "C" fn plumage_system_load_state(sys: *mut PlumageSystem, blob: *const u8, len: usize) -> u32 {
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
pub unsafe extern "C" fn plumage_system_seek(sys: *mut PlumageSystem, frame_index: u64, out_from: *mut u64) -> u32 {
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

fn not_available(what: &str) -> Failure {
    Failure::new(PLUMAGE_STATUS_NOT_AVAILABLE, format!("{what} are not available: this system has no feathers yet"))
}

/// Copies the message of the last failed call on `sys` into `buf` (at most
/// `capacity` bytes, always NUL-terminated when `capacity > 0`) and returns
/// the size needed including the NUL. `buf` may be NULL to ask the size.
/// With `sys == NULL`, reports the last failure on the calling thread of a
/// call that had no usable system (a refused create, a NULL system). An
/// empty string means no failure was recorded.
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
    let message = boundary::quietly(|| {
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

/// Test builds only (cargo feature `test-hooks`): makes the next step,
/// evaluate or validate on `sys` panic inside the library, to prove the
/// panic boundary. Returns PLUMAGE_STATUS_OK when armed.
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create` that no other
/// thread uses during the call.
#[cfg(feature = "test-hooks")]
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_testing_panic_on_next_call(sys: *mut PlumageSystem) -> u32 {
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
