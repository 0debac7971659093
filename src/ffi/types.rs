//! `#[repr(C)]` parameter structs and their conversion to the safe API.

use super::boundary::{Failure, read_versioned};
use super::status::*;
use crate::{Config, MeshInput, Mode, SamplerKind};
use glam::Vec3;
use std::ffi::c_void;
use std::sync::Arc;

/// `PlumageConfig.sampler`: orientation-field-guided sampling (paper, Algorithm 1).
pub const PLUMAGE_SAMPLER_GUIDED: u32 = 0;
/// `PlumageConfig.sampler`: area-weighted random dart throwing (the 2015 baseline).
pub const PLUMAGE_SAMPLER_RANDOM: u32 = 1;

/// `PlumageConfig.mode`: incremental reordering and readjustment (paper §3.3).
pub const PLUMAGE_MODE_INCREMENTAL: u32 = 0;
/// `PlumageConfig.mode`: the 2015 method (fixed order, Eq. 2, fine pitch only).
pub const PLUMAGE_MODE_LEGACY: u32 = 1;
/// `PlumageConfig.mode`: everything recomputed every frame (quality reference).
pub const PLUMAGE_MODE_REBUILD: u32 = 2;

/// Parameters of a system. Fill with `plumage_config_init`, then change what
/// you need. Lengths are in model units; a length of 0 means "derive it".
/// Fields are only ever appended; `struct_size` tells the library which ones
/// the caller knows.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PlumageConfig {
    /// `sizeof(PlumageConfig)` as the caller compiled it (set by init).
    pub struct_size: u32,
    /// `PLUMAGE_SAMPLER_*`.
    pub sampler: u32,
    /// Seed of every random choice: same input and seed, same bytes.
    pub seed: u64,
    /// Worker threads: 1 = no worker thread: every call runs on the thread
    /// that makes it, progress callbacks included; 0 = one worker per core,
    /// in a pool shared by every system made with 0; N ≥ 2 = the system's
    /// own N workers, started at create. With workers, the calling thread
    /// waits while they work. Results are byte-identical whatever the count.
    pub threads: u32,
    /// `PLUMAGE_MODE_*`.
    pub mode: u32,
    /// Wanted number of feathers (0 = use `spacing`); met within ±15 %.
    pub target_feathers: u32,
    /// k of the k-nearest-root neighbourhoods (1..64, default 10).
    pub k_neighbours: u32,
    /// Poisson-disk radius between roots; 0 = derived from the mesh size.
    pub spacing: f32,
    /// Stagger angle θ of the guided sampler, radians (default π/4).
    pub theta: f32,
    /// Randomness u0 of the guided sampler, in [0, 1] (default 0).
    pub randomness: f32,
    /// Sample pool size as a multiple of the expected root count (default 30).
    pub pool_factor: f32,
    /// Feather length; 0 = derived from the local spacing.
    pub feather_length: f32,
    /// Feather width; 0 = derived from the local spacing.
    pub feather_width: f32,
    /// Feather thickness; 0 = derived from the width.
    pub feather_thickness: f32,
    /// γ of the priority difference (Eq. 3), 0 ≤ λ < γ < 1 (default 0.6).
    pub gamma: f32,
    /// λ of the priority difference (Eq. 3) (default 0.3).
    pub lambda: f32,
    /// Height-field cells along the shaft (default 32).
    pub height_field_u: u32,
    /// Height-field cells across the vanes (default 16).
    pub height_field_v: u32,
    /// Extra lift added by the fine-pitch step, radians (default 0).
    pub fluffiness: f32,
    /// Allowed penetration into obstacles, as a fraction of thickness (default 0).
    pub collision_allowance: f32,
    /// Propagation threshold θs, radians (default 0.05); a feather is also
    /// readjusted once what surrounds it moved, relative to it, by θs times
    /// its length.
    pub theta_s: f32,
    /// Flow axis for the orientation field when the mesh gives no hints.
    /// (0, 0, 0), the default, derives it from the mesh: its principal
    /// axis, pointing to −Z (glTF models face +Z), else down (−Y), else +X.
    pub flow_axis: [f32; 3],
    /// Non-zero: recompute neighbourhoods at the current pose every frame.
    pub recompute_neighbourhoods: u32,
    /// Optional progress callback for create, step and evaluate (NULL = none).
    pub progress: PlumageProgressFn,
    /// Passed back to `progress` unchanged.
    pub progress_user_data: *mut c_void,
    /// Non-zero: without hints, the orientation field flows away from
    /// `flow_source` along the surface (default 0: it follows `flow_axis`).
    pub flow_source_enabled: u32,
    /// Where the derived flow starts (e.g. the beak tip), in model units.
    pub flow_source: [f32; 3],
    /// Incremental mode: how far a feather may drift (radians, default 0.3)
    /// before it is readjusted, when every moved feather is checked exactly
    /// each frame and readjusted at once if it intersects; at or below
    /// `theta_s`, the paper's rule (readjust at θs, no exact checks).
    pub drift_tolerance: f32,
    /// Smallest spacing multiplier the bending of the surface may set, in
    /// (0, 1] (default 0.4; 1 = off): where the surface bends on a radius
    /// shorter than a feather (thin limbs, wing tips, creases), roots are
    /// closer and feathers shorter, down to this fraction. Not applied when
    /// `feather_length` is set.
    pub curvature_min_scale: f32,
    /// Shaft segments of every feather, 1 to 4 (default 1, the rigid
    /// kite): with more, each joint may bend, so a feather drapes over the
    /// feathers and the skin beneath it instead of standing off them.
    pub shaft_segments: u32,
    /// Largest bend at each joint of a segmented shaft away from the skin,
    /// radians, in [0, 1.2] (default 0.4; 0 keeps feathers straight);
    /// toward the skin a joint may bend twice as far.
    pub bend_limit: f32,
    /// Feather length as a multiple of the local spacing when
    /// `feather_length` is 0 (default 4; scales 2), in (0, 20].
    pub length_per_spacing: f32,
    /// Feather width as a multiple of the local spacing when
    /// `feather_width` is 0 (default 1.75; scales 2), in (0, 20].
    pub width_per_spacing: f32,
    /// A feather whose pose relative to its root (pitch, roll, a bend)
    /// changes by more than this between frames counts as a pop in
    /// `PlumageFrameStats.pops` (radians, default 5°; a figure only).
    pub pop_threshold: f32,
    /// Optional: the host's own parallel-for (TBB, a DCC's thread pool),
    /// through which the system runs all its parallel work instead of
    /// starting threads (NULL, the default: the library's own workers, see
    /// `threads`). See `PlumageParallelForFn` for the contract. With
    /// `threads` N ≥ 2 every call asks for N tasks (0 = one per core); with
    /// `threads` = 1 the work runs on the calling thread and this is never
    /// called. Results are byte-identical to the library's own threads.
    pub parallel_for: PlumageParallelForFn,
    /// Passed back to `parallel_for` unchanged as `host_context`.
    pub parallel_for_context: *mut c_void,
    /// Incremental mode: the most a readjusted feather's pose relative to
    /// its root (pitch, roll, a bend) moves toward its newly solved pose in
    /// one frame (radians, default 2°; 0 = the solved pose at once). A
    /// feather that must lift to stay clear lifts at once; settling down is
    /// spread over frames, so the coat does not pop.
    pub settle_rate: f32,
    /// Scrubbing: every this many steps (and after create) the system
    /// keeps its state blob in memory, so `plumage_system_seek` can go back
    /// to the nearest one and the caller replays from there (default 0:
    /// none kept). Changes no result.
    pub checkpoint_interval: u32,
    /// Most checkpoints kept besides the one after create (default 64, at
    /// least 1); past it the oldest is dropped.
    pub checkpoint_cap: u32,
}

/// One task of a parallel section, handed to the host's parallel-for:
/// call it once with each index in `0 .. count` and the `task_context` that
/// came with it. It never unwinds or throws into the host (a panic inside
/// is caught by the library and reported by the call that started the
/// work, as PLUMAGE_STATUS_PANIC).
pub type PlumageTaskFn = Option<unsafe extern "C" fn(task_context: *mut c_void, index: u32)>;

/// A host's parallel-for (`PlumageConfig.parallel_for`): must call
/// `task(task_context, i)` exactly once for every `i` in `0 .. count`, on
/// any of its threads (the calling thread included) and in any order,
/// several at once or one after the other, and return only after every
/// call has returned. The library calls it from inside its own calls
/// (create, step, evaluate, validate, load_state, ...) on the thread that
/// made them; from several threads at once only when the host makes
/// read-only calls on one system concurrently, or uses it for several
/// systems on several threads at once. A task may block until
/// the others finish the work, but never waits for another task to start,
/// so a host that runs fewer tasks at once than `count` is fine. Progress
/// callbacks then come from the calling thread or from any thread running
/// a task, still never two at once. A task run on a thread that is itself
/// inside one of the library's own worker pools does nothing, and the
/// library runs its share on the calling thread after `parallel_for`
/// returns.
pub type PlumageParallelForFn =
    Option<unsafe extern "C" fn(host_context: *mut c_void, count: u32, task: PlumageTaskFn, task_context: *mut c_void)>;

/// `plumage_config_init_preset`: contour feathers (the defaults of
/// `plumage_config_init`).
pub const PLUMAGE_PRESET_FEATHERS: u32 = 0;
/// `plumage_config_init_preset`: fish scales, short and wide (2 spacings
/// each), nearly rigid (2 segments, bend limit 0.15 rad), in staggered rows
/// each overlapping the next by half.
pub const PLUMAGE_PRESET_SCALES: u32 = 1;

/// Progress callback: `phase` is a `PLUMAGE_PHASE_*` value, `fraction` the
/// completed share of it in [0, 1]. Return 0 to continue; any other value
/// stops the running call, which then returns PLUMAGE_STATUS_INTERRUPTED and
/// leaves the system as it was before the call (a stopped create creates
/// nothing). It is called at least every few milliseconds while the library
/// works, never from two threads at once: with `threads = 1` always on the
/// thread that made the call (create, step, evaluate or validate); with more threads
/// on that thread or on one of the system's worker threads. It must not
/// call back into the same system.
pub type PlumageProgressFn = Option<unsafe extern "C" fn(user_data: *mut c_void, phase: u32, fraction: f32) -> i32>;

/// Progress phase: checking and welding the mesh, building the surface.
pub const PLUMAGE_PHASE_PREPARING: u32 = 0;
/// Progress phase: planting roots.
pub const PLUMAGE_PHASE_SAMPLING: u32 = 1;
/// Progress phase: neighbourhoods, priorities and the feather order.
pub const PLUMAGE_PHASE_ORDERING: u32 = 2;
/// Progress phase: the height-field adjustment of the feathers.
pub const PLUMAGE_PHASE_ADJUSTING: u32 = 3;
/// Progress phase: `plumage_system_validate`'s exact checks.
pub const PLUMAGE_PHASE_VALIDATING: u32 = 4;

/// Most feathers a system may hold: a larger `target_feathers`, or a
/// `spacing` that would plant more, is refused with
/// PLUMAGE_STATUS_LIMIT_EXCEEDED before anything large is allocated.
pub const PLUMAGE_MAX_FEATHERS: u32 = 2_000_000;
/// Largest coordinate magnitude accepted in a mesh or a frame, and largest
/// spacing, feather length, width and thickness (model units); beyond it,
/// PLUMAGE_STATUS_LIMIT_EXCEEDED.
pub const PLUMAGE_MAX_COORDINATE: f32 = 1e9;
const _: () = assert!(PLUMAGE_MAX_FEATHERS as usize == crate::limits::MAX_FEATHERS);
const _: () = assert!(PLUMAGE_MAX_COORDINATE == crate::limits::MAX_COORDINATE);

/// The host's callback as a progress sink.
#[derive(Clone, Copy)]
pub(crate) struct HostProgress {
    callback: unsafe extern "C" fn(*mut c_void, u32, f32) -> i32,
    user_data: *mut c_void,
}

// SAFETY: the header documents that the callback may run on a worker thread
// (never two at once: `Progress` serialises calls); the host owns user_data.
unsafe impl Send for HostProgress {}
unsafe impl Sync for HostProgress {}

impl HostProgress {
    pub(crate) fn from_config(cfg: &PlumageConfig) -> Option<Self> {
        cfg.progress.map(|callback| Self { callback, user_data: cfg.progress_user_data })
    }
}

impl crate::progress::ProgressSink for HostProgress {
    fn report(&self, phase: crate::progress::Phase, fraction: f32) -> bool {
        use crate::progress::Phase;
        let code = match phase {
            Phase::Preparing => PLUMAGE_PHASE_PREPARING,
            Phase::Sampling => PLUMAGE_PHASE_SAMPLING,
            Phase::Ordering => PLUMAGE_PHASE_ORDERING,
            Phase::Adjusting => PLUMAGE_PHASE_ADJUSTING,
            Phase::Validating => PLUMAGE_PHASE_VALIDATING,
        };
        // SAFETY: a host function pointer with the documented signature.
        unsafe { (self.callback)(self.user_data, code, fraction) == 0 }
    }
}

/// The size of the first published `PlumageConfig` (up to `flow_source`;
/// later fields take their defaults when a caller's struct ends there);
/// smaller is refused.
pub(crate) const CONFIG_V1_SIZE: usize = std::mem::offset_of!(PlumageConfig, drift_tolerance);

/// A mesh handed to `plumage_system_create`, in the caller's own numbering.
/// Triangle soups (vertices split along UV or normal seams) are welded by
/// position internally. Fill with `plumage_mesh_desc_init` first.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PlumageMeshDesc {
    /// `sizeof(PlumageMeshDesc)` as the caller compiled it (set by init).
    pub struct_size: u32,
    /// xyz per vertex, `3 * vertex_count` floats.
    pub positions: *const f32,
    /// Number of vertices; every frame must give exactly this many.
    pub vertex_count: usize,
    /// Three vertex indices per triangle.
    pub indices: *const u32,
    /// Number of triangles.
    pub triangle_count: usize,
    /// Optional xyz tangent hint per vertex (the orientation field); may be NULL.
    pub orientations: *const f32,
    /// Optional spacing multiplier per vertex (0 = bare skin); may be NULL.
    pub spacing_scale: *const f32,
    /// Optional feather length multiplier per vertex; may be NULL.
    pub length_scale: *const f32,
    /// Optional feather width multiplier per vertex; may be NULL.
    pub width_scale: *const f32,
}

pub(crate) const MESH_DESC_V1_SIZE: usize = std::mem::size_of::<PlumageMeshDesc>();

impl PlumageMeshDesc {
    pub(crate) fn empty() -> Self {
        Self {
            struct_size: MESH_DESC_V1_SIZE as u32,
            positions: std::ptr::null(),
            vertex_count: 0,
            indices: std::ptr::null(),
            triangle_count: 0,
            orientations: std::ptr::null(),
            spacing_scale: std::ptr::null(),
            length_scale: std::ptr::null(),
            width_scale: std::ptr::null(),
        }
    }
}

impl PlumageConfig {
    pub(crate) fn from_config(c: &Config) -> Self {
        Self {
            struct_size: std::mem::size_of::<PlumageConfig>() as u32,
            sampler: match c.sampler {
                SamplerKind::Guided => PLUMAGE_SAMPLER_GUIDED,
                SamplerKind::Random => PLUMAGE_SAMPLER_RANDOM,
            },
            seed: c.seed,
            threads: c.threads as u32,
            mode: match c.mode {
                Mode::Incremental => PLUMAGE_MODE_INCREMENTAL,
                Mode::Legacy => PLUMAGE_MODE_LEGACY,
                Mode::Rebuild => PLUMAGE_MODE_REBUILD,
            },
            target_feathers: c.target_feathers as u32,
            k_neighbours: c.k_neighbours as u32,
            spacing: c.spacing,
            theta: c.theta,
            randomness: c.randomness,
            pool_factor: c.pool_factor,
            feather_length: c.feather_length,
            feather_width: c.feather_width,
            feather_thickness: c.feather_thickness,
            gamma: c.gamma,
            lambda: c.lambda,
            height_field_u: c.height_field_u as u32,
            height_field_v: c.height_field_v as u32,
            fluffiness: c.fluffiness,
            collision_allowance: c.collision_allowance,
            theta_s: c.theta_s,
            flow_axis: c.flow_axis.to_array(),
            recompute_neighbourhoods: c.recompute_neighbourhoods as u32,
            progress: None,
            progress_user_data: std::ptr::null_mut(),
            flow_source_enabled: u32::from(c.flow_source.is_some()),
            flow_source: c.flow_source.unwrap_or(Vec3::ZERO).to_array(),
            drift_tolerance: c.drift_tolerance,
            curvature_min_scale: c.curvature_min_scale,
            shaft_segments: c.shaft_segments,
            bend_limit: c.bend_limit,
            length_per_spacing: c.length_per_spacing,
            width_per_spacing: c.width_per_spacing,
            pop_threshold: c.pop_threshold,
            parallel_for: None,
            parallel_for_context: std::ptr::null_mut(),
            settle_rate: c.settle_rate,
            checkpoint_interval: c.checkpoint_interval,
            checkpoint_cap: c.checkpoint_cap,
        }
    }

    pub(crate) fn to_config(self) -> Result<Config, Failure> {
        let invalid = |m: String| Failure::new(PLUMAGE_STATUS_INVALID_ARGUMENT, m);
        let sampler = match self.sampler {
            PLUMAGE_SAMPLER_GUIDED => SamplerKind::Guided,
            PLUMAGE_SAMPLER_RANDOM => SamplerKind::Random,
            s => {
                return Err(invalid(format!("config.sampler {s} is not a PLUMAGE_SAMPLER_* value")));
            }
        };
        let mode = match self.mode {
            PLUMAGE_MODE_INCREMENTAL => Mode::Incremental,
            PLUMAGE_MODE_LEGACY => Mode::Legacy,
            PLUMAGE_MODE_REBUILD => Mode::Rebuild,
            m => {
                return Err(invalid(format!("config.mode {m} is not a PLUMAGE_MODE_* value")));
            }
        };
        let floats = [
            self.spacing,
            self.theta,
            self.randomness,
            self.pool_factor,
            self.feather_length,
            self.feather_width,
            self.feather_thickness,
            self.gamma,
            self.lambda,
            self.fluffiness,
            self.collision_allowance,
            self.theta_s,
            self.drift_tolerance,
            self.curvature_min_scale,
            self.bend_limit,
            self.length_per_spacing,
            self.width_per_spacing,
            self.pop_threshold,
            self.settle_rate,
        ];
        if floats.iter().chain(&self.flow_axis).chain(&self.flow_source).any(|x| !x.is_finite()) {
            return Err(Failure::new(PLUMAGE_STATUS_NON_FINITE, "config holds a NaN or infinite value"));
        }
        let cfg = Config {
            seed: self.seed,
            threads: self.threads as usize,
            sampler,
            mode,
            spacing: self.spacing,
            target_feathers: self.target_feathers as usize,
            theta: self.theta,
            randomness: self.randomness,
            pool_factor: self.pool_factor,
            feather_length: self.feather_length,
            feather_width: self.feather_width,
            feather_thickness: self.feather_thickness,
            gamma: self.gamma,
            lambda: self.lambda,
            k_neighbours: self.k_neighbours as usize,
            height_field_u: self.height_field_u as usize,
            height_field_v: self.height_field_v as usize,
            fluffiness: self.fluffiness,
            collision_allowance: self.collision_allowance,
            theta_s: self.theta_s,
            drift_tolerance: self.drift_tolerance,
            flow_axis: Vec3::from_array(self.flow_axis),
            recompute_neighbourhoods: self.recompute_neighbourhoods != 0,
            flow_source: (self.flow_source_enabled != 0).then(|| Vec3::from_array(self.flow_source)),
            curvature_min_scale: self.curvature_min_scale,
            shaft_segments: self.shaft_segments,
            bend_limit: self.bend_limit,
            length_per_spacing: self.length_per_spacing,
            width_per_spacing: self.width_per_spacing,
            pop_threshold: self.pop_threshold,
            settle_rate: self.settle_rate,
            checkpoint_interval: self.checkpoint_interval,
            checkpoint_cap: self.checkpoint_cap,
        };
        cfg.validate()?;
        Ok(cfg)
    }
}

/// Reads the caller's config (NULL = defaults) into a checked `Config`.
///
/// # Safety
/// `cfg` is NULL or points to a `PlumageConfig` of at least `struct_size` bytes.
pub(crate) unsafe fn read_config(cfg: *const PlumageConfig) -> Result<HostConfig, Failure> {
    if cfg.is_null() {
        return Ok(HostConfig { config: Config::default(), progress: None, parallel_for: None });
    }
    let defaults = PlumageConfig::from_config(&Config::default());
    // SAFETY: forwarded contract.
    let raw = unsafe { read_versioned(cfg, CONFIG_V1_SIZE, defaults, "PlumageConfig") }?;
    let parallel_for = raw.parallel_for.map(|run| {
        Arc::new(HostParallelFor { run, context: raw.parallel_for_context }) as Arc<dyn crate::pool::ParallelFor>
    });
    Ok(HostConfig { config: raw.to_config()?, progress: HostProgress::from_config(&raw), parallel_for })
}

/// A caller's `PlumageConfig`: the checked configuration and its callbacks.
pub(crate) struct HostConfig {
    pub config: Config,
    pub progress: Option<HostProgress>,
    pub parallel_for: Option<Arc<dyn crate::pool::ParallelFor>>,
}

/// The host's parallel-for as the pools' [`crate::pool::ParallelFor`].
#[derive(Debug)]
struct HostParallelFor {
    run: unsafe extern "C" fn(*mut c_void, u32, PlumageTaskFn, *mut c_void),
    context: *mut c_void,
}

// SAFETY: the header's contract: the host's parallel-for may be called from
// any thread the library calls from, and runs tasks on threads of its
// choosing; the host owns its context.
unsafe impl Send for HostParallelFor {}
unsafe impl Sync for HostParallelFor {}

impl crate::pool::ParallelFor for HostParallelFor {
    fn parallel_for(&self, count: usize, task: &(dyn Fn(usize) + Sync)) {
        /// What a `PlumageTaskFn` calls: the pool's task behind `context`.
        unsafe extern "C" fn trampoline(context: *mut c_void, index: u32) {
            // SAFETY: `context` is the `&&dyn Fn` passed below, alive until
            // the host's parallel-for returns, which is after every task.
            let task = unsafe { &*(context as *const &(dyn Fn(usize) + Sync)) };
            // The pool's tasks catch their panics; nothing may unwind into C.
            let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| task(index as usize)));
        }
        let count = u32::try_from(count).expect("a worker count below 2^32 (threads ≤ 1024)");
        let task: &(dyn Fn(usize) + Sync) = task;
        // SAFETY: a host function with the documented signature and contract.
        unsafe { (self.run)(self.context, count, Some(trampoline), &task as *const _ as *mut c_void) }
    }
}

/// Borrowed view of the caller's mesh arrays.
///
/// # Safety
/// Every non-NULL pointer of `desc` points to as many elements as its count
/// says, alive for `'a`.
pub(crate) unsafe fn read_mesh<'a>(desc: *const PlumageMeshDesc) -> Result<MeshInput<'a>, Failure> {
    if desc.is_null() {
        return Err(Failure::null("mesh description"));
    }
    // SAFETY: forwarded contract.
    let d = unsafe { read_versioned(desc, MESH_DESC_V1_SIZE, PlumageMeshDesc::empty(), "PlumageMeshDesc") }?;
    if d.positions.is_null() {
        return Err(Failure::null("mesh positions"));
    }
    if d.indices.is_null() {
        return Err(Failure::null("mesh indices"));
    }
    if d.vertex_count == 0 {
        return Err(Failure::new(PLUMAGE_STATUS_EMPTY_MESH, "mesh has no vertices"));
    }
    if d.triangle_count == 0 {
        return Err(Failure::new(PLUMAGE_STATUS_EMPTY_MESH, "mesh has no triangles"));
    }
    let floats = checked_len(d.vertex_count, 3, "vertex_count")?;
    let idx = checked_len(d.triangle_count, 3, "triangle_count")?;
    // SAFETY: non-NULL, lengths per the contract; sizes checked against overflow.
    unsafe {
        Ok(MeshInput {
            positions: std::slice::from_raw_parts(d.positions, floats),
            indices: std::slice::from_raw_parts(d.indices, idx),
            orientations: optional_slice(d.orientations, floats),
            spacing_scale: optional_slice(d.spacing_scale, d.vertex_count),
            length_scale: optional_slice(d.length_scale, d.vertex_count),
            width_scale: optional_slice(d.width_scale, d.vertex_count),
        })
    }
}

/// `count × per` elements of 4 bytes, refused when the byte size overflows
/// or exceeds what a slice may span.
pub(crate) fn checked_len(count: usize, per: usize, name: &str) -> Result<usize, Failure> {
    count
        .checked_mul(per)
        .filter(|n| n.checked_mul(4).is_some_and(|b| b <= isize::MAX as usize))
        .filter(|_| count <= u32::MAX as usize)
        .ok_or_else(|| Failure::new(PLUMAGE_STATUS_SIZE_OVERFLOW, format!("{name} {count} is too large")))
}

unsafe fn optional_slice<'a>(ptr: *const f32, len: usize) -> Option<&'a [f32]> {
    // SAFETY: forwarded contract of `read_mesh`.
    (!ptr.is_null()).then(|| unsafe { std::slice::from_raw_parts(ptr, len) })
}

/// One feather, copied out by `plumage_system_feathers`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PlumageFeather {
    /// Stable 64-bit id derived from the root's rest binding and the seed.
    pub id: u64,
    /// Position of the feather in the adjustment order (0 = placed first).
    pub order_index: u32,
    /// The caller's triangle (index into the rest mesh's triangles) holding the root.
    pub triangle: u32,
    /// Barycentric weights of the root on that triangle's three corners.
    pub barycentric: [f32; 3],
    /// Root position at the current pose.
    pub root: [f32; 3],
    /// Unit surface normal at the root.
    pub normal: [f32; 3],
    /// Unit shaft direction after pitch and roll.
    pub direction: [f32; 3],
    /// Pitch, radians (positive lifts the tip away from the skin).
    pub pitch: f32,
    /// Roll about the shaft, radians.
    pub roll: f32,
    /// Length along the shaft, as placed: a feather that cannot lie down
    /// within the pitch limit is shortened, and one that fits at no size is
    /// left out with length and width 0 (its triangles collapse to the root).
    pub length: f32,
    /// Width across the vanes, as placed (shortened with the length).
    pub width: f32,
    /// Thickness.
    pub thickness: f32,
    /// Always 0 (keeps the struct free of padding bytes).
    pub reserved: u32,
}

impl From<&crate::stats::FeatherRecord> for PlumageFeather {
    fn from(f: &crate::stats::FeatherRecord) -> Self {
        Self {
            id: f.id,
            order_index: f.order_index,
            triangle: f.triangle,
            barycentric: f.barycentric,
            root: f.root,
            normal: f.normal,
            direction: f.direction,
            pitch: f.pitch,
            roll: f.roll,
            length: f.length,
            width: f.width,
            thickness: f.thickness,
            reserved: 0,
        }
    }
}

/// Sampling quality figures (`plumage_system_sampling_stats`). Fill
/// with `plumage_sampling_stats_init` (or set `struct_size = sizeof(PlumageSamplingStats)`)
/// before the call.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PlumageSamplingStats {
    /// Set by the caller to `sizeof(PlumageSamplingStats)`; the library writes back the bytes it filled.
    pub struct_size: u32,
    /// Number of roots planted.
    pub roots: u32,
    /// Global Poisson-disk radius d used, model units.
    pub spacing: f32,
    /// min over roots of (distance to the nearest root on the same side) / d_i.
    pub relative_radius: f32,
    /// max over surface probes of (distance to the nearest root) / local d.
    pub coverage_gap: f32,
    /// Mean of cos 4(φ − θ) over each root's 4 nearest neighbours (1 = lattice turned by θ, 0 = random).
    pub alignment: f32,
    /// Wall time of sampling.
    pub seconds: f64,
}

/// Static ordering figures (`plumage_system_ordering_stats`). Fill
/// with `plumage_ordering_stats_init` (or set `struct_size = sizeof(PlumageOrderingStats)`)
/// before the call.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PlumageOrderingStats {
    /// Set by the caller to `sizeof(PlumageOrderingStats)`; the library writes back the bytes it filled.
    pub struct_size: u32,
    /// Symmetric neighbour pairs.
    pub pairs: u32,
    /// Priority edges kept in the DAG.
    pub edges: u32,
    /// Edges dropped to break cycles.
    pub dropped_edges: u32,
    /// Edges whose head comes after their tail in the order (0 when correct).
    pub violations: u32,
    /// Always 0 (keeps the struct free of padding bytes).
    pub reserved: u32,
    /// Wall time of neighbourhoods, priorities and ordering.
    pub seconds: f64,
}

/// What the last create, step or evaluate did (`plumage_system_frame_stats`).
/// Fill with `plumage_frame_stats_init` (or set `struct_size =
/// sizeof(PlumageFrameStats)`) before the call.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PlumageFrameStats {
    /// Set by the caller to `sizeof(PlumageFrameStats)`; the library writes back the bytes it filled.
    pub struct_size: u32,
    /// Feathers whose pitch or roll hit a limit.
    pub clamped: u32,
    /// 0 after create, then 1, 2, ... after each step (evaluate keeps it).
    pub frame_index: u64,
    /// Feathers re-adjusted.
    pub adjusted: u64,
    /// Obstacle feathers rasterised (collision detections).
    pub collision_tests: u64,
    /// collision_tests / adjusted (0 when nothing was adjusted).
    pub collision_tests_per_feather: f64,
    /// Neighbour pairs whose priority difference changed sign.
    pub priority_changes: u64,
    /// priority_changes as a percentage of the feather count.
    pub priority_change_percent: f64,
    /// Edge reversals carried out.
    pub reversals: u64,
    /// Reversals refused by the cycle rule.
    pub reversals_refused: u64,
    /// Cycles broken by deleting their smallest-|ΔP| edge.
    pub cycles_broken: u64,
    /// Seconds spent re-posing roots and reordering.
    pub reorder_seconds: f64,
    /// Seconds spent adjusting feathers.
    pub adjust_seconds: f64,
    /// Seconds of the whole call.
    pub step_seconds: f64,
    /// Feathers whose surroundings moved relative to them, since they were
    /// last adjusted, by more than θs times their length (the paper's R_k);
    /// 0 after create and evaluate.
    pub deformed: u64,
    /// Feathers readjusted in any case: surroundings moved by more than the
    /// drift tolerance (θs in the paper's rule) times their length, or
    /// obstacles changed by the reordering; `adjusted` minus this came by
    /// propagation or failed the exact check.
    pub seeds: u64,
    /// Feathers whose surroundings moved that were checked exactly and kept
    /// their pose (incremental mode with `drift_tolerance` above `theta_s`).
    pub verified: u64,
    /// The part of `reorder_seconds` spent finding neighbourhoods and
    /// obstacle candidates at the current pose: every create, evaluate and
    /// rebuild step, incremental steps with `recompute_neighbourhoods`,
    /// never a legacy step (appended; a shorter, older struct is filled up
    /// to its `struct_size`).
    pub neighbourhood_seconds: f64,
    /// Levels the adjustment ran through: the longest chain, among the
    /// feathers the call may visit, of feathers each reading the one before
    /// as an obstacle, plus one per feather of a step's rare second pass.
    /// The feathers of a level run in parallel; levels close to the number
    /// of feathers visited mean the call ran nearly one at a time.
    pub levels: u64,
    /// Feathers whose pose relative to their root (pitch, roll, a bend)
    /// changed by more than `PlumageConfig.pop_threshold` in this call
    /// (appended): what an animator sees flick. 0 after create or a load.
    pub pops: u64,
    /// The largest such change of any feather in this call, degrees.
    pub largest_pose_change_deg: f64,
}

/// Exact validation of the current feathers (`plumage_system_validate`).
/// Fill with `plumage_validation_init` (or set `struct_size =
/// sizeof(PlumageValidation)`) before the call.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PlumageValidation {
    /// Set by the caller to `sizeof(PlumageValidation)`; the library writes back the bytes it filled.
    pub struct_size: u32,
    /// Padding; always 0.
    pub reserved: u32,
    /// Pairs of feathers whose triangles intersect (exact test).
    pub intersecting_pairs: u64,
    /// Feathers crossing the body more than 5 % of their length from the root.
    pub body_penetrations: u64,
    /// Fraction of the probes of the feathered, visible skin whose normal
    /// ray meets a feather within the longest feather length. Bare skin
    /// (spacing multiplier 0) and skin buried inside the body (where the
    /// mesh passes through itself) carry no probes.
    pub coverage: f64,
    /// Mean pitch of the feathers, degrees.
    pub mean_pitch_deg: f64,
    /// Probes behind `coverage` (appended; a shorter, older struct is
    /// filled up to its `struct_size`).
    pub probes: u64,
    /// Probes of the feathered skin left out of `coverage` because they lie
    /// inside the body.
    pub buried_probes: u64,
    /// Median distance from a placed feather's tip to the body surface, in
    /// feather lengths (appended). A coat that lies down keeps it small.
    pub tip_height_median: f64,
    /// 90th percentile of the same, in feather lengths.
    pub tip_height_p90: f64,
    /// Percentage of placed feathers whose tip stands more than half a
    /// feather length off the skin (bristles).
    pub bristle_percent: f64,
}

/// Figures of the last create, step or evaluate restricted to a part of the
/// mesh, a range of the caller's triangles (`plumage_system_part_stats`):
/// the feathers rooted there. A host that dresses several meshes as one
/// system (their triangles one after the other) reads each mesh's figures
/// so. Fill with `plumage_part_stats_init` (or set `struct_size =
/// sizeof(PlumagePartStats)`) before the call.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PlumagePartStats {
    /// Set by the caller to `sizeof(PlumagePartStats)`; the library writes back the bytes it filled.
    pub struct_size: u32,
    /// Padding; always 0.
    pub reserved: u32,
    /// Feathers rooted on the part's triangles.
    pub feathers: u64,
    /// Of those, feathers placed (not left out, collapsed to their root).
    pub placed: u64,
    /// Of those, feathers the last create, step or evaluate readjusted.
    pub adjusted: u64,
    /// Of those, feathers whose pose relative to their root changed by
    /// more than `PlumageConfig.pop_threshold` in the last step or
    /// evaluate (0 after create or a load), as `PlumageFrameStats.pops`.
    pub pops: u64,
    /// The largest such change among them, degrees.
    pub largest_pose_change_deg: f64,
}

/// Caller buffers for `plumage_system_feather_geometry`: every feather as a
/// mesh. Fill with `plumage_feather_geometry_init`, then point the buffers
/// you want at your memory (NULL skips one); capacities count elements
/// (floats, indices or bytes). The library writes the totals back.
///
/// Layout: feathers one after the other, in the order of
/// `plumage_system_feathers`; a feather's vertices are contiguous, and the
/// layout (indices, UVs, vertex-to-feather map, counts) depends only on the
/// configuration and the mesh, never on the frame, so a host can upload it
/// once and refresh positions and normals each frame.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct PlumageFeatherGeometry {
    /// Set by `plumage_feather_geometry_init` to `sizeof(PlumageFeatherGeometry)`.
    pub struct_size: u32,
    /// Padding; always 0.
    pub reserved: u32,
    /// Out: number of feathers.
    pub feather_count: u64,
    /// Out: vertices of all feathers.
    pub vertex_count: u64,
    /// Out: triangles of all feathers.
    pub triangle_count: u64,
    /// xyz per vertex, world space (3 × vertex_count floats).
    pub positions: *mut f32,
    /// Capacity of `positions`, in floats.
    pub positions_capacity: usize,
    /// Unit normal per vertex, facing away from the skin on the feather's
    /// visible side (3 × vertex_count floats).
    pub normals: *mut f32,
    /// Capacity of `normals`, in floats.
    pub normals_capacity: usize,
    /// (u, v) per vertex: u from 0 at the root to 1 at the tip along the
    /// shaft, v from 0 to 1 across the vanes (0.5 on the shaft, 1 on the
    /// binormal side) (2 × vertex_count floats).
    pub uvs: *mut f32,
    /// Capacity of `uvs`, in floats.
    pub uvs_capacity: usize,
    /// Three vertex indices per triangle, into the whole vertex array, each
    /// triangle facing away from the skin (3 × triangle_count).
    pub indices: *mut u32,
    /// Capacity of `indices`, in indices.
    pub indices_capacity: usize,
    /// Per vertex: the index of its feather (vertex_count).
    pub vertex_feathers: *mut u32,
    /// Capacity of `vertex_feathers`.
    pub vertex_feathers_capacity: usize,
    /// Per feather: its vertex count (feather_count).
    pub vertex_counts: *mut u32,
    /// Capacity of `vertex_counts`.
    pub vertex_counts_capacity: usize,
    /// Per feather: its triangle count (feather_count).
    pub triangle_counts: *mut u32,
    /// Capacity of `triangle_counts`.
    pub triangle_counts_capacity: usize,
    /// Per feather: 1 when placed, 0 when left out (no size fitted; its
    /// vertices all lie at its root and its triangles have no area, so a
    /// host may skip it) (feather_count bytes).
    pub placed: *mut u8,
    /// Capacity of `placed`, in bytes.
    pub placed_capacity: usize,
}

impl PlumageFeatherGeometry {
    /// No buffers, no totals, `struct_size` set.
    pub(crate) fn empty() -> Self {
        let null_f = std::ptr::null_mut();
        let null_u = std::ptr::null_mut();
        Self {
            struct_size: std::mem::size_of::<Self>() as u32,
            reserved: 0,
            feather_count: 0,
            vertex_count: 0,
            triangle_count: 0,
            positions: null_f,
            positions_capacity: 0,
            normals: null_f,
            normals_capacity: 0,
            uvs: null_f,
            uvs_capacity: 0,
            indices: null_u,
            indices_capacity: 0,
            vertex_feathers: null_u,
            vertex_feathers_capacity: 0,
            vertex_counts: null_u,
            vertex_counts_capacity: 0,
            triangle_counts: null_u,
            triangle_counts_capacity: 0,
            placed: std::ptr::null_mut(),
            placed_capacity: 0,
        }
    }
}

/// The first published layout of `PlumageValidation` (up to
/// `mean_pitch_deg`): older callers' structs are filled up to their size.
pub(crate) const VALIDATION_V1_SIZE: usize = std::mem::offset_of!(PlumageValidation, probes);
/// The layout of `PlumageFrameStats` before `neighbourhood_seconds` was
/// appended: such structs are filled up to their size.
pub(crate) const FRAME_STATS_V1_SIZE: usize = std::mem::offset_of!(PlumageFrameStats, neighbourhood_seconds);

// Every struct the library copies out must be free of padding, so that the
// bytes a host sees are fully defined (and comparable with memcmp).
const _: () = {
    use std::mem::size_of;
    assert!(size_of::<PlumageFeather>() == 8 + 4 + 4 + 4 * 3 * 4 + 4 * 5 + 4);
    assert!(size_of::<PlumageSamplingStats>() == 4 * 6 + 8);
    assert!(size_of::<PlumageOrderingStats>() == 4 * 6 + 8);
    assert!(size_of::<PlumageFrameStats>() == 4 + 4 + 8 * 19);
    assert!(size_of::<PlumageValidation>() == 4 + 4 + 8 * 9);
    assert!(size_of::<PlumagePartStats>() == 4 + 4 + 8 * 5);
};
