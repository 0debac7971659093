//! One frame as a pipeline of phases (DESIGN.md §4, §5; paper §3.3). Every
//! call that moves a coat to a pose runs these phases in this order, each
//! reading what the ones before it wrote into the [`Coat`]:
//!
//! 1. **pose** ([`Coat::pose`]): the welded positions → vertex normals and
//!    every root's frame (`Coat::frames`); poses stay relative to them.
//! 2. **neighbourhoods** (`phases::neighbourhoods_and_body`): root frames
//!    → the k nearest roots, the symmetric pair set and the obstacle
//!    candidates (`Coat::neighbourhoods`).
//! 3. **order**: from scratch, `phases::static_order` (priorities of the
//!    pairs → the priority DAG made acyclic → its topological order and
//!    `Coat::ordering_report`); frame to frame, `step` (the roots whose
//!    surroundings moved, `R_k` → their pairs' priorities → the dynamic
//!    order's edge reversals with the cycle rule → `R*_k`).
//! 4. **body** (`phases::body`): positions → the body index
//!    (`Coat::body`) the adjustment and the checks query. Wherever phase 2
//!    runs, the body is indexed beside it (it needs only the positions).
//! 5. **adjust** (the [`crate::adjustment`] API): from scratch every
//!    feather in order, all three steps; frame to frame the seeds `R*_k` in
//!    order, checked exactly or propagated past θs, then the missed
//!    contacts (`Coat::poses`, `Coat::settling`, `Coat::staleness`).
//! 6. **report**: the call's [`FrameReport`](crate::stats::FrameReport)
//!    (`Coat::frame_report`).
//!
//! Who runs what: create and evaluate run [`solve()`] (every phase from
//! scratch); a step runs [`advance`], which for the `rebuild` mode is
//! [`solve()`] again (counting the frame) and for the incremental and legacy
//! modes [`step_coat`] (the frame-to-frame variants of phases 3 and 5).
//! Both leave the coat ready for the export and the checks.

mod phases;
mod rule;
mod solve;
mod step;
mod surroundings;

pub use phases::{StepWorkspace, Workspace};
pub use rule::FrameRule;
pub use solve::{solve, solve_beside};
pub use step::step_coat;

use crate::coat::{Coat, Dressing};
use crate::error::Result;
use crate::progress::Progress;
use glam::Vec3;

/// One step of the animation to the welded `positions`, by the
/// configuration's [`FrameRule`]: the rebuild rule solves from scratch (and
/// counts the frame), the others update the coat in place.
pub fn advance(
    coat: &mut Coat,
    dressing: &Dressing,
    positions: &[Vec3],
    work: &mut Workspace,
    step: &mut StepWorkspace,
    progress: &Progress,
) -> Result<()> {
    match FrameRule::of(&dressing.config) {
        FrameRule::Rebuild => {
            coat.frame_index += 1;
            solve(coat, dressing, positions, work, progress)
        }
        rule => step_coat(coat, dressing, rule, positions, work, step, progress),
    }
}
