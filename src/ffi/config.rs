//! The configuration a host passes to `plumage_system_create`:
//! `PlumageConfig` and its constants (samplers, modes, presets), the
//! progress and parallel-for callbacks, and the conversion to and from the
//! safe API's [`Config`].

use super::carry::{Bytes, Finite, Flag, Narrow, OptionalPoint, Same, Triple};
use super::convention::{Failure, read_versioned};
use super::status::*;
use crate::{Config, Mode, SamplerKind};
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
    /// Extra lift added by the fine-pitch step, radians (default 0); a bent
    /// feather's root segment is lifted by it above where it drapes.
    pub fluffiness: f32,
    /// Allowed penetration into obstacles, as a fraction of thickness
    /// (default 0), in the straight feather's fine-pitch step: the kite's.
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
    /// Always 0 (keeps `memory_limit` aligned without padding bytes).
    pub reserved: u32,
    /// Most heap bytes the system may hold (`plumage_system_memory`), 0
    /// (the default) for no limit. Create refuses with
    /// PLUMAGE_STATUS_LIMIT_EXCEEDED before its large allocations when the
    /// feathers' own arrays alone would pass it, and after building when the
    /// whole system does (everything it built is then freed); a step or
    /// evaluate that would leave the system above it is refused and undone
    /// (with a limit set, as with a progress callback, the system keeps a
    /// copy of the coat from call to call to undo a call with, and counts
    /// it).
    pub memory_limit: u64,
}

const _: () = assert!(
    std::mem::offset_of!(PlumageConfig, memory_limit) == std::mem::offset_of!(PlumageConfig, checkpoint_cap) + 8
        && std::mem::size_of::<PlumageConfig>() == std::mem::offset_of!(PlumageConfig, memory_limit) + 8
);

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

/// `plumage_config_init_preset`: contour feathers that lie down (the
/// defaults of `plumage_config_init`): bent shafts of 4 segments, each
/// feather draped over what lies beneath it.
pub const PLUMAGE_PRESET_FEATHERS: u32 = 0;

/// `plumage_config_init_preset`: fish scales, short and wide (2 spacings
/// each), nearly rigid (2 segments, bend limit 0.15 rad), in staggered rows
/// each overlapping the next by half.
pub const PLUMAGE_PRESET_SCALES: u32 = 1;

/// `plumage_config_init_preset`: another name for
/// `PLUMAGE_PRESET_FEATHERS`, always with the same defaults.
pub const PLUMAGE_PRESET_SLEEK: u32 = 2;

/// `plumage_config_init_preset`: the paper's rigid feather, the defaults of
/// `plumage_config_init` with one shaft segment (a flat kite): cheaper to
/// adjust, but a coat of kites stands off the body.
pub const PLUMAGE_PRESET_KITE: u32 = 3;

/// Progress callback: `phase` is a `PLUMAGE_PHASE_*` value, `fraction` the
/// completed share of it in [0, 1]. Return 0 to continue; any other value
/// stops the running call, which then returns PLUMAGE_STATUS_INTERRUPTED and
/// leaves the system as it was before the call (a stopped create creates
/// nothing). It is called at least every few milliseconds while the library
/// works, never from two threads at once: with `threads = 1` always on the
/// thread that made the call (create, step, evaluate or validate); with more threads
/// on that thread or on one of the system's worker threads. A call from it
/// into the same system returns PLUMAGE_STATUS_BUSY (read-only calls from
/// validate's callback excepted: they may run beside it).
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

/// Most shaft segments a feather may have (`PlumageConfig.shaft_segments`
/// is 1 to this).
pub const PLUMAGE_MAX_SHAFT_SEGMENTS: u32 = 4;

/// Most triangles of one feather as `plumage_system_feather_triangles`
/// copies them out (nine floats each): for sizing a buffer per feather.
pub const PLUMAGE_MAX_FEATHER_TRIANGLES: u32 = 14;

/// Bend limit of the defaults, radians (`PlumageConfig.bend_limit`).
pub const PLUMAGE_DEFAULT_BEND_LIMIT: f32 = 0.4;

const _: () = assert!(PLUMAGE_MAX_SHAFT_SEGMENTS as usize == crate::feather::MAX_SEGMENTS);
const _: () = assert!(PLUMAGE_MAX_FEATHER_TRIANGLES as usize == crate::feather::MAX_TRIANGLES);
const _: () = assert!(PLUMAGE_DEFAULT_BEND_LIMIT == crate::adjustment::DEFAULT_BEND_LIMIT);

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

/// `PLUMAGE_SAMPLER_*` as a carrier (see `carry`).
struct SamplerCode;

impl SamplerCode {
    fn to_c(v: &SamplerKind) -> (u32,) {
        (match v {
            SamplerKind::Guided => PLUMAGE_SAMPLER_GUIDED,
            SamplerKind::Random => PLUMAGE_SAMPLER_RANDOM,
        },)
    }

    fn from_c((v,): (u32,)) -> Result<SamplerKind, Failure> {
        match v {
            PLUMAGE_SAMPLER_GUIDED => Ok(SamplerKind::Guided),
            PLUMAGE_SAMPLER_RANDOM => Ok(SamplerKind::Random),
            s => Err(Failure::new(
                PLUMAGE_STATUS_INVALID_ARGUMENT,
                format!("config.sampler {s} is not a PLUMAGE_SAMPLER_* value"),
            )),
        }
    }
}

/// `PLUMAGE_MODE_*` as a carrier (see `carry`).
struct ModeCode;

impl ModeCode {
    fn to_c(v: &Mode) -> (u32,) {
        (match v {
            Mode::Incremental => PLUMAGE_MODE_INCREMENTAL,
            Mode::Legacy => PLUMAGE_MODE_LEGACY,
            Mode::Rebuild => PLUMAGE_MODE_REBUILD,
        },)
    }

    fn from_c((v,): (u32,)) -> Result<Mode, Failure> {
        match v {
            PLUMAGE_MODE_INCREMENTAL => Ok(Mode::Incremental),
            PLUMAGE_MODE_LEGACY => Ok(Mode::Legacy),
            PLUMAGE_MODE_REBUILD => Ok(Mode::Rebuild),
            m => Err(Failure::new(
                PLUMAGE_STATUS_INVALID_ARGUMENT,
                format!("config.mode {m} is not a PLUMAGE_MODE_* value"),
            )),
        }
    }
}

/// Both conversions between [`Config`] and `PlumageConfig`, from
/// [`crate::config::config_fields!`]. The C struct is built and taken
/// apart in full (struct literal and pattern, no `..`), so a C field that
/// no table entry and no C-only line below names is a compile error.
macro_rules! define_conversions {
    ($($(#[$doc:meta])* $name:ident: $ty:ty = $default:expr, c[$($cname:ident),+] by $carry:ident, check $check:ident;)*) => {
        impl PlumageConfig {
            /// The fields that carry a [`Config`] field, in the table's order
            /// (the rest are `struct_size`, the callbacks and `reserved`).
            #[cfg(test)]
            const CARRYING_FIELDS: &'static [&'static str] = &[$($(stringify!($cname)),+),*];

            /// The C struct holding `c` (no callbacks; `struct_size` this
            /// library's).
            pub(crate) fn from_config(c: &Config) -> Self {
                $(let ($($cname,)+) = $carry::to_c(&c.$name);)*
                Self {
                    struct_size: std::mem::size_of::<PlumageConfig>() as u32,
                    progress: None,
                    progress_user_data: std::ptr::null_mut(),
                    parallel_for: None,
                    parallel_for_context: std::ptr::null_mut(),
                    reserved: 0,
                    $($($cname,)+)*
                }
            }

            /// The checked configuration a caller's struct holds: refused
            /// with PLUMAGE_STATUS_INVALID_ARGUMENT for an unknown sampler or
            /// mode, PLUMAGE_STATUS_NON_FINITE for a NaN or infinity in any
            /// float field (set or not), and as [`Config::validate`] refuses.
            pub(crate) fn to_config(self) -> Result<Config, Failure> {
                let PlumageConfig {
                    struct_size: _,
                    progress: _,
                    progress_user_data: _,
                    parallel_for: _,
                    parallel_for_context: _,
                    reserved: _,
                    $($($cname,)+)*
                } = self;
                let finite = true $($(&& Finite::finite(&$cname))+)*;
                $(let $name: $ty = $carry::from_c(($($cname,)+))?;)*
                if !finite {
                    return Err(Failure::new(PLUMAGE_STATUS_NON_FINITE, "config holds a NaN or infinite value"));
                }
                let cfg = Config { $($name,)* };
                cfg.validate()?;
                Ok(cfg)
            }
        }
    };
}

crate::config::config_fields!(define_conversions);

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
        Arc::new(HostParallelFor { run, context: raw.parallel_for_context }) as Arc<dyn crate::workers::ParallelFor>
    });
    Ok(HostConfig { config: raw.to_config()?, progress: HostProgress::from_config(&raw), parallel_for })
}

/// A caller's `PlumageConfig`: the checked configuration and its callbacks.
pub(crate) struct HostConfig {
    pub config: Config,
    pub progress: Option<HostProgress>,
    pub parallel_for: Option<Arc<dyn crate::workers::ParallelFor>>,
}

/// The host's parallel-for as the pools' [`crate::workers::ParallelFor`].
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

impl crate::workers::ParallelFor for HostParallelFor {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every field differs from its default here (the literal has no `..`,
    /// so a new field must be given a value), and survives both conversions.
    #[test]
    fn every_field_is_carried_both_ways() {
        let cfg = Config {
            seed: 7,
            threads: 3,
            sampler: SamplerKind::Random,
            mode: Mode::Legacy,
            spacing: 0.25,
            target_feathers: 1234,
            theta: 0.5,
            randomness: 0.25,
            pool_factor: 12.0,
            feather_length: 1.5,
            feather_width: 0.5,
            feather_thickness: 0.125,
            gamma: 0.7,
            lambda: 0.2,
            k_neighbours: 12,
            height_field_u: 20,
            height_field_v: 10,
            fluffiness: 0.1,
            collision_allowance: 0.2,
            theta_s: 0.1,
            drift_tolerance: 0.2,
            flow_axis: Vec3::new(0.0, 1.0, 0.0),
            flow_source: Some(Vec3::new(1.0, 2.0, 3.0)),
            recompute_neighbourhoods: false,
            curvature_min_scale: 0.5,
            shaft_segments: 2,
            bend_limit: 0.3,
            length_per_spacing: 3.0,
            width_per_spacing: 1.5,
            pop_threshold: 0.2,
            settle_rate: 0.1,
            checkpoint_interval: 4,
            checkpoint_cap: 8,
            memory_limit: 1 << 30,
        };
        assert_eq!(cfg.differing_fields(&Config::default()), Config::FIELD_NAMES);
        assert_eq!(PlumageConfig::from_config(&cfg).to_config().unwrap(), cfg);
        assert_eq!(PlumageConfig::from_config(&Config::default()).to_config().unwrap(), Config::default());
    }

    /// The header's `PlumageConfig` has exactly the fields the table names,
    /// besides the C-only ones.
    #[test]
    fn the_header_declares_every_carried_field() {
        let header = include_str!("../../include/plumage.h");
        let body =
            header.split("typedef struct PlumageConfig {").nth(1).unwrap().split("} PlumageConfig;").next().unwrap();
        let mut declared: Vec<&str> = body
            .lines()
            .map(str::trim)
            .filter(|l| !l.starts_with('*') && !l.starts_with("/*") && l.ends_with(';'))
            .map(|l| l.split('[').next().unwrap().trim_end_matches(';').rsplit([' ', '*']).next().unwrap())
            .filter(|name| {
                !["struct_size", "progress", "progress_user_data", "parallel_for", "parallel_for_context", "reserved"]
                    .contains(name)
            })
            .collect();
        let mut carried = PlumageConfig::CARRYING_FIELDS.to_vec();
        declared.sort_unstable();
        carried.sort_unstable();
        assert_eq!(declared, carried);
    }

    #[test]
    fn a_nan_in_any_float_field_is_refused() {
        let defaults = PlumageConfig::from_config(&Config::default());
        for i in 0..3 {
            let mut c = defaults;
            c.flow_source[i] = f32::NAN;
            assert_eq!(c.to_config().unwrap_err().status, PLUMAGE_STATUS_NON_FINITE);
        }
        let mut c = defaults;
        c.settle_rate = f32::INFINITY;
        assert_eq!(c.to_config().unwrap_err().status, PLUMAGE_STATUS_NON_FINITE);
    }
}
