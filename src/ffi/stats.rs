//! Figures of a system: the sampling, the static order and the last
//! create, step or evaluate (`PlumageSamplingStats`, `PlumageOrderingStats`,
//! `PlumageFrameStats`), each written into a caller's struct that starts
//! with `struct_size`.

use super::boundary::{PlumageSystem, figures_out};
use super::convention::Failure;
use super::status::PlumageStatus;

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
    /// Faces of the feathered skin round which the rest orientation field
    /// turns (appended): its sources, sinks, whorls and saddles.
    pub field_singularities: u32,
    /// Always 0 (keeps the struct free of padding bytes).
    pub reserved: u32,
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
    /// of feathers visited mean the call ran nearly one at a time. A
    /// verifying step walks the order instead, its checks made ahead on
    /// the other threads: one level for the checks, plus one per feather
    /// adjusted.
    pub levels: u64,
    /// Feathers whose pose relative to their root (pitch, roll, a bend)
    /// changed by more than `PlumageConfig.pop_threshold` in this call
    /// (appended): what an animator sees flick. 0 after create or a load.
    pub pops: u64,
    /// The largest such change of any feather in this call, degrees.
    pub largest_pose_change_deg: f64,
    /// Re-adjusted segmented feathers whose bends were draped (appended).
    pub draped: u64,
    /// Of those, the ones the swept drape left to the slower descent by
    /// exact checks (appended).
    pub drape_descents: u64,
    /// Re-adjusted segmented feathers kept where they lay rather than
    /// draped afresh (appended; incremental steps): lifted in place as
    /// little as clears them, lowered a step, or left resting.
    pub kept_in_place: u64,
}

/// The layout of `PlumageSamplingStats` before `field_singularities` was
/// appended: such structs are filled up to their size.
pub(crate) const SAMPLING_STATS_V1_SIZE: usize = std::mem::offset_of!(PlumageSamplingStats, field_singularities);

/// The layout of `PlumageFrameStats` before `neighbourhood_seconds` was
/// appended: such structs are filled up to their size.
pub(crate) const FRAME_STATS_V1_SIZE: usize = std::mem::offset_of!(PlumageFrameStats, neighbourhood_seconds);

// Copied out as they are: free of padding, so that the bytes a host sees
// are fully defined (and comparable with memcmp).
const _: () = {
    use std::mem::size_of;
    assert!(size_of::<PlumageSamplingStats>() == 4 * 6 + 8 + 4 * 2);
    assert!(size_of::<PlumageOrderingStats>() == 4 * 6 + 8);
    assert!(size_of::<PlumageFrameStats>() == 4 + 4 + 8 * 22);
};

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
) -> PlumageStatus {
    // SAFETY: forwarded contract of this function.
    unsafe {
        figures_out(sys, out, SAMPLING_STATS_V1_SIZE, "PlumageSamplingStats", |system| {
            let r = system.sampling_report().ok_or_else(|| Failure::not_available("sampling figures"))?;
            Ok(PlumageSamplingStats {
                struct_size: 0,
                roots: r.roots as u32,
                spacing: r.spacing,
                relative_radius: r.relative_radius,
                coverage_gap: r.coverage_gap,
                alignment: r.alignment,
                seconds: r.seconds,
                field_singularities: r.field_singularities as u32,
                reserved: 0,
            })
        })
    }
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
) -> PlumageStatus {
    // SAFETY: forwarded contract of this function.
    unsafe {
        figures_out(sys, out, std::mem::size_of::<PlumageOrderingStats>(), "PlumageOrderingStats", |system| {
            let r = system.ordering_report().ok_or_else(|| Failure::not_available("ordering figures"))?;
            Ok(PlumageOrderingStats {
                struct_size: 0,
                pairs: r.pairs as u32,
                edges: r.edges as u32,
                dropped_edges: r.dropped_edges as u32,
                violations: r.violations as u32,
                reserved: 0,
                seconds: r.seconds,
            })
        })
    }
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
pub unsafe extern "C" fn plumage_system_frame_stats(
    sys: *const PlumageSystem,
    out: *mut PlumageFrameStats,
) -> PlumageStatus {
    // SAFETY: forwarded contract of this function.
    unsafe {
        figures_out(sys, out, FRAME_STATS_V1_SIZE, "PlumageFrameStats", |system| {
            let r = system.frame_report().ok_or_else(|| Failure::not_available("frame figures"))?;
            let feathers = system.feather_count().max(1) as f64;
            Ok(PlumageFrameStats {
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
                draped: r.draped as u64,
                drape_descents: r.drape_descents as u64,
                kept_in_place: r.kept_in_place as u64,
            })
        })
    }
}

/// The heap bytes a system holds, by part (`plumage_system_memory`). Fill
/// with `plumage_memory_init` (or set `struct_size =
/// sizeof(PlumageMemory)`) before the call.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct PlumageMemory {
    /// Set by the caller to `sizeof(PlumageMemory)`; the library writes back the bytes it filled.
    pub struct_size: u32,
    /// Always 0.
    pub reserved: u32,
    /// Every part below together.
    pub total: u64,
    /// The welded mesh, its connectivity and spatial index, the roots' rest
    /// binding and the current vertex positions.
    pub mesh: u64,
    /// The feathers at the current pose: frames, poses, triangles, records,
    /// the previous frame's poses and root frames (and the poses before
    /// those, to undo a call with), and the list of feathers the last call
    /// changed.
    pub coat: u64,
    /// The neighbourhoods and the priority order between neighbours.
    pub neighbourhoods: u64,
    /// Saved states kept for `plumage_system_seek` (checkpoints).
    pub history: u64,
    /// Working memory a step keeps between frames so as not to allocate
    /// again (grows with the feathers, never with the number of frames),
    /// with the copy of the coat a call that can be stopped (or that runs
    /// under a memory limit) keeps to restore it.
    pub scratch: u64,
}

/// The heap bytes the system holds now, by part: what
/// `PlumageConfig.memory_limit` is compared with. Counted from the
/// capacities of the system's containers (the process's allocator adds its
/// own bookkeeping on top).
///
/// # Safety
/// `sys` is NULL or a live handle from `plumage_system_create`; other threads
/// may only make read-only (`const`) calls on it during the call. `out` is NULL
/// or points to a struct whose `struct_size` is set and whose `struct_size`
/// bytes are writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn plumage_system_memory(sys: *const PlumageSystem, out: *mut PlumageMemory) -> PlumageStatus {
    // SAFETY: forwarded contract of this function.
    unsafe {
        figures_out(sys, out, std::mem::size_of::<PlumageMemory>(), "PlumageMemory", |system| {
            let m = system.memory();
            Ok(PlumageMemory {
                struct_size: 0,
                reserved: 0,
                total: m.total() as u64,
                mesh: m.mesh as u64,
                coat: m.coat as u64,
                neighbourhoods: m.neighbourhoods as u64,
                history: m.history as u64,
                scratch: m.scratch as u64,
            })
        })
    }
}
