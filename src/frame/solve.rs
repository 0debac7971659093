//! The from-scratch solve of a coat at one pose (create, evaluate, every
//! frame of the `rebuild` mode): every phase of [`crate::frame`], the
//! order static and every feather adjusted from a flat start.

use super::phases::{self, Workspace};
use crate::adjustment::{AdjustSteps, OrderedRun, Selection};
use crate::coat::{Coat, Dressing};
use crate::error::Result;
use crate::feather::FeatherPose;
use crate::progress::{Phase, Progress};
use crate::stats::FrameReport;
use glam::Vec3;
use std::time::Instant;

/// Solves `coat` from scratch at the welded `positions`: neighbourhoods,
/// the static order (Eq. 3, or Eq. 2 for the legacy mode) and the full
/// three-step adjustment of every feather from a flat start.
pub fn solve(
    coat: &mut Coat,
    dressing: &Dressing,
    positions: &[Vec3],
    work: &mut Workspace,
    progress: &Progress,
) -> Result<()> {
    solve_beside(coat, dressing, positions, work, progress, || ())
}

/// As [`solve`], and runs `beside` on the current pool beside the
/// adjustment (`rayon::join`), returning what it returned. The adjustment
/// goes through levels of a few feathers each, so it leaves a second worker
/// mostly idle; `beside` is work that reads none of what the solve writes
/// (create measures the sampling figures there). It does not run when the
/// solve stops before the adjustment.
pub fn solve_beside<R: Send>(
    coat: &mut Coat,
    dressing: &Dressing,
    positions: &[Vec3],
    work: &mut Workspace,
    progress: &Progress,
    beside: impl FnOnce() -> R + Send,
) -> Result<R> {
    let start = Instant::now();
    progress.check(Phase::Ordering, 0.0)?;
    coat.pose(dressing, positions);
    progress.check(Phase::Ordering, 0.1)?;
    let order_start = Instant::now();
    let neighbourhood_seconds = phases::neighbourhoods_and_body(coat, dressing, progress)?;
    progress.check(Phase::Ordering, 0.5)?;
    coat.poses.clear();
    coat.poses.resize(dressing.len(), FeatherPose::default());
    phases::static_order(coat, dressing, work, order_start);
    progress.check(Phase::Adjusting, 0.0)?;
    let run = OrderedRun {
        frames: &coat.frames,
        shapes: &dressing.shapes,
        order: coat.order.order(),
        rank: coat.order.ranks(),
        candidates: coat.neighbourhoods.obstacle_csr(),
        body: &coat.body,
        params: &dressing.adjust_params,
        steps: AdjustSteps::Full,
        settle_rate: 0.0,
    };
    let (side, stats) = rayon::join(beside, || {
        work.adjuster.adjust_in_order_until(&run, &mut coat.poses, Selection::All, &|done| {
            progress.check(Phase::Adjusting, done).is_ok()
        })
    });
    // A stopped adjustment (None) has set the progress's stop flag.
    progress.check(Phase::Adjusting, 1.0)?;
    let stats = stats.unwrap_or_default();
    coat.readjusted.clear();
    coat.readjusted.extend_from_slice(work.adjuster.adjusted());
    coat.staleness.reset(dressing.len());
    coat.settling.clear();
    coat.frame_report = FrameReport {
        frame_index: coat.frame_index,
        adjusted: stats.adjusted,
        deformed: 0,
        seeds: dressing.len(),
        verified: 0,
        collision_tests: stats.collision_tests,
        priority_changes: 0,
        reversals: 0,
        reversals_refused: 0,
        cycles_broken: 0,
        clamped: stats.clamped,
        draped: stats.draped,
        kept_in_place: stats.kept_in_place,
        drape_descents: stats.drape_descents,
        reorder_seconds: coat.ordering_report.seconds,
        adjust_seconds: stats.seconds,
        step_seconds: start.elapsed().as_secs_f64(),
        neighbourhood_seconds,
        levels: stats.levels,
    };
    Ok(side)
}
