//! The exact validation of the current feathers, whole
//! (`plumage_system_validate`) or for a part of the mesh, and the last
//! call's figures for a part (`PlumageValidation`, `PlumagePartStats`).

use super::boundary::{PlumageSystem, figures_out, with_system_ref_progress};
use super::convention::{Failure, write_struct};
use super::status::*;
use crate::stats::ValidationReport;

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
    /// Median over placed feathers of the tip height divided by the stack
    /// floor (appended): the thicknesses of the other feathers whose
    /// triangles cross the segment from the tip to its nearest body point,
    /// summed (at least the feather's own thickness), over its length. 1
    /// means the tips lie on the feathers stacked beneath them; larger, that
    /// they stand higher than the stack forces.
    pub stack_efficiency: f64,
    /// Median number of feathers beneath a placed feather's tip (those
    /// counted in `stack_efficiency`).
    pub stack_depth_median: f64,
    /// Percentage of the feathers whose heading (the shaft's direction in
    /// the skin's tangent plane) turns more than 45 degrees from the mean
    /// heading of their 8 nearest neighbours (appended): whorls, partings
    /// and crowns where the orientation field turns sharply.
    pub discord_percent: f64,
}

impl From<&ValidationReport> for PlumageValidation {
    fn from(r: &ValidationReport) -> Self {
        Self {
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
            stack_efficiency: r.stack_efficiency,
            stack_depth_median: r.stack_depth_median,
            discord_percent: r.discord_percent,
        }
    }
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

/// The first published layout of `PlumageValidation` (up to
/// `mean_pitch_deg`): older callers' structs are filled up to their size.
pub(crate) const VALIDATION_V1_SIZE: usize = std::mem::offset_of!(PlumageValidation, probes);

// Copied out as they are: free of padding, so that the bytes a host sees
// are fully defined (and comparable with memcmp).
const _: () = {
    use std::mem::size_of;
    assert!(size_of::<PlumageValidation>() == 4 + 4 + 8 * 12);
    assert!(size_of::<PlumagePartStats>() == 4 + 4 + 8 * 5);
};

/// Runs the exact validation (triangle–triangle intersections, body
/// penetrations, coverage, mean pitch, tip heights and stacks) on the
/// current feathers. Only reads
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
pub unsafe extern "C" fn plumage_system_validate(
    sys: *const PlumageSystem,
    out: *mut PlumageValidation,
) -> PlumageStatus {
    with_system_ref_progress(sys, |system, progress| {
        // SAFETY: forwarded contract of this function.
        unsafe {
            write_struct(out, VALIDATION_V1_SIZE, "PlumageValidation", || {
                let r = system.validate_with_progress(progress)?.ok_or_else(|| Failure::not_available("validation"))?;
                Ok(PlumageValidation::from(&r))
            })
        }
    })
}

/// `plumage_system_validate` restricted to a part of the mesh: the
/// caller's triangles `first_triangle .. first_triangle + triangle_count`
/// of the rest mesh given to create (e.g. one of several meshes a host
/// dresses as one system, their triangles one after the other). Every
/// feather still counts as an obstacle and as a cover: `intersecting_pairs`
/// counts the pairs with at least one feather rooted on the part (so a
/// pair across two parts counts in both); `body_penetrations`,
/// `mean_pitch_deg`, the tip heights and the stack figures are those of
/// the part's feathers (any feather may lie beneath their tips);
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
) -> PlumageStatus {
    // SAFETY: forwarded contract of this function.
    unsafe {
        figures_out(sys, out, VALIDATION_V1_SIZE, "PlumageValidation", |system| {
            let range = part_range(system, first_triangle, triangle_count)?;
            let r = system.validate_part(range).ok_or_else(|| Failure::not_available("validation"))?;
            Ok(PlumageValidation::from(&r))
        })
    }
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
) -> PlumageStatus {
    // SAFETY: forwarded contract of this function.
    unsafe {
        figures_out(sys, out, std::mem::size_of::<PlumagePartStats>(), "PlumagePartStats", |system| {
            let r = system.part_report(part_range(system, first_triangle, triangle_count)?);
            Ok(PlumagePartStats {
                struct_size: 0,
                reserved: 0,
                feathers: r.feathers as u64,
                placed: r.placed as u64,
                adjusted: r.adjusted as u64,
                pops: r.pops as u64,
                largest_pose_change_deg: f64::from(r.largest_pose_change).to_degrees(),
            })
        })
    }
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
