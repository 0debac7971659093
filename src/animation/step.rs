//! One animation frame, incremental (paper §3.3) or legacy (the 2015
//! method), applied to a coat in place (DESIGN.md §5):
//! 1. re-pose every root from the deformed mesh; feathers keep their pitch
//!    and roll relative to their own frame;
//! 2. `R_k`: roots whose face's affine map `A_i^k` differs from a
//!    neighbour's;
//! 3. (incremental) neighbourhoods at the current pose, `ΔP` recomputed for
//!    the pairs of `R_k`, sign changes turned into edge reversals in the
//!    dynamic order with the cycle rule;
//! 4. `R*_k` = `R_k` plus the roots that became prior or gained a prior or
//!    moved in the order; they are readjusted in order (all three steps; the
//!    legacy mode runs fine pitch only), and a feather whose pitch or roll
//!    moved by more than θs pulls in the feathers that lie on it.

use super::affine::{DeformationTolerance, FaceMap, deform_differently, face_maps};
use crate::Mode;
use crate::adjustment::{AdjustSteps, CandidateLists, Selection};
use crate::coat::{Coat, Dressing, Workspace};
use crate::error::Result;
use crate::ordering::Priorities;
use crate::progress::{Phase, Progress};
use crate::stats::FrameReport;
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;

/// Buffers of the frame update, reused every frame.
#[derive(Debug, Default)]
pub struct StepWorkspace {
    previous_positions: Vec<Vec3>,
    previous_root_positions: Vec<Vec3>,
    maps: Vec<FaceMap>,
    seeds: Vec<bool>,
    r_k: Vec<u32>,
}

/// Advances `coat` to `positions` (welded) by the incremental or legacy
/// rule of `dressing.mode`.
pub fn step_coat(
    coat: &mut Coat,
    dressing: &Dressing,
    positions: &[Vec3],
    work: &mut Workspace,
    step: &mut StepWorkspace,
    progress: &Progress,
) -> Result<()> {
    let start = Instant::now();
    let n = dressing.len();
    // 1. Re-pose; remember where everything was.
    step.previous_positions.clear();
    step.previous_positions.extend_from_slice(&coat.positions);
    step.previous_root_positions.clear();
    step.previous_root_positions.extend(coat.frames.iter().map(|f| f.position));
    coat.pose(dressing, positions);
    progress.check(Phase::Ordering, 0.0)?;

    // 2. R_k from the per-face affine maps.
    face_maps(&step.previous_positions, &coat.positions, &dressing.triangles, &mut step.maps);
    roots_deforming_differently(coat, dressing, step);
    progress.check(Phase::Ordering, 0.3)?;

    // 3. Reordering (incremental only: the legacy order is fixed).
    let mut report = FrameReport { frame_index: coat.frame_index + 1, ..FrameReport::default() };
    if dressing.mode == Mode::Incremental {
        if dressing.recompute_neighbourhoods {
            coat.neighbourhoods.rebuild(&coat.frames, &dressing.reach, &dressing.neighbour_params);
        }
        let priorities = Priorities::improved(&coat.frames, dressing.gamma, dressing.lambda);
        let pairs = dressing.recompute_neighbourhoods.then(|| coat.neighbourhoods.pairs());
        let stats = coat.order.update_frame(pairs, &step.r_k, &priorities);
        report.priority_changes = stats.priority_changes;
        report.reversals = stats.reversals_done;
        report.reversals_refused = stats.reversals_refused;
        report.cycles_broken = stats.cycles_broken;
        // R*_k: add every root whose obstacles may have changed.
        for list in [coat.order.became_prior(), coat.order.gained_prior(), coat.order.moved()] {
            for &i in list {
                step.seeds[i as usize] = true;
            }
        }
    }
    report.deformed = step.r_k.len();
    report.seeds = step.seeds.iter().filter(|s| **s).count();
    report.reorder_seconds = start.elapsed().as_secs_f64();
    progress.check(Phase::Adjusting, 0.0)?;

    // 4. Readjust R*_k in order, propagating past θs.
    coat.body.rebuild(&coat.positions, &dressing.triangles);
    let steps = if dressing.mode == Mode::Legacy { AdjustSteps::FinePitchOnly } else { AdjustSteps::Full };
    let (offsets, indices) = coat.neighbourhoods.obstacle_csr();
    let stats = if n == 0 {
        Some(Default::default())
    } else {
        work.adjuster.adjust_in_order_until(
            &coat.frames,
            &dressing.shapes,
            &mut coat.poses,
            coat.order.order(),
            coat.order.ranks(),
            CandidateLists::new(offsets, indices),
            &coat.body,
            &dressing.adjust_params,
            steps,
            Selection::Propagate { seeds: &step.seeds, threshold: dressing.theta_s },
            &|done| progress.check(Phase::Adjusting, done).is_ok(),
        )
    };
    // A stopped adjustment (None) has set the progress's stop flag.
    progress.check(Phase::Adjusting, 1.0)?;
    let stats = stats.unwrap_or_default();
    report.adjusted = stats.adjusted;
    report.collision_tests = stats.collision_tests;
    report.clamped = stats.clamped;
    report.adjust_seconds = stats.seconds;
    report.step_seconds = start.elapsed().as_secs_f64();
    coat.frame_index += 1;
    coat.frame_report = report;
    Ok(())
}

/// Marks `R_k` (paper §3.3): root i is in it when some neighbour j ∈ N_i
/// deforms differently, i.e. the map of i's face does not carry j along.
fn roots_deforming_differently(coat: &Coat, dressing: &Dressing, step: &mut StepWorkspace) {
    let n = dressing.len();
    let tol = DeformationTolerance::default();
    let maps = &step.maps;
    let previous = &step.previous_root_positions;
    step.seeds.clear();
    step.seeds.resize(n, false);
    step.seeds.par_iter_mut().enumerate().with_min_len(256).for_each(|(i, seed)| {
        let map_i = &maps[dressing.roots[i].point.face as usize];
        *seed = coat.neighbourhoods.neighbours_of(i as u32).iter().any(|&j| {
            let j = j as usize;
            let map_j = &maps[dressing.roots[j].point.face as usize];
            deform_differently(map_i, map_j, previous[j], coat.frames[j].position, dressing.roots[i].spacing, &tol)
        });
    });
    step.r_k.clear();
    step.r_k.extend(step.seeds.iter().enumerate().filter(|(_, s)| **s).map(|(i, _)| i as u32));
}
