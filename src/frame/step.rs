//! One animation frame by the paper's rule (§3.3), the verifying rule or
//! the legacy one (the 2015 method) ([`FrameRule`]), applied to a coat in
//! place (DESIGN.md §5): the frame-to-frame variants of the order and
//! adjust phases of [`crate::frame`], each a function of [`step_coat`]:
//! 1. [`repose`]: re-pose every root from the deformed mesh; feathers keep their pitch
//!    and roll relative to their own frame (incremental: neighbourhoods and
//!    obstacle candidates follow the current pose);
//! 2. [`find_moved`], `R_k`: feathers whose surroundings moved relative to them since they
//!    were last adjusted ([`crate::coat::Staleness`]), by more
//!    than `θs·L` (a feather's tip moves that far when its pitch changes by
//!    θs, the change the propagation rule already lets pass). The
//!    surroundings are the k nearest roots (their priorities) and the
//!    earlier candidates whose feathers lie over the feather's footprint
//!    (its obstacles). A rigid motion moves nothing relative to anything;
//! 3. [`reorder`] (incremental) `ΔP` recomputed for the pairs of `R_k`, sign changes
//!    turned into edge reversals in the dynamic order with the cycle rule;
//!    then `R*_k` = `R_k` plus the feathers whose obstacles changed with
//!    the order or the neighbourhoods: a candidate lying over the footprint
//!    became earlier or stopped being earlier;
//! 4. [`readjust`]: `R*_k` is readjusted in order
//!    (all three steps; the legacy mode runs fine pitch only), and a feather
//!    whose pitch or roll moved by more than θs pulls in the feathers that
//!    lie on it ([`Contacts`](crate::animation::contact::Contacts)).
//!
//! The verifying rule, beyond the paper (incremental, `drift_tolerance` >
//! θs, the default):
//! the paper's rule readjusts most of a flexing body every frame, because
//! a readjusted feather that turns by θs pulls in what lies on it, and so
//! on down the coat. Instead, every feather whose surroundings moved this
//! frame is checked in order with the exact tests of the validation
//! against its obstacles at their final poses and the skin, and readjusted
//! only if the check fails ([`Selection::Verify`]). The readjustments that
//! remain are for drift: the seeds are the feathers whose surroundings
//! moved by more than the drift tolerance times their length (net: the
//! surroundings recorded when the feather was last adjusted, compared
//! with where they lie now; see [`crate::animation::motion`]), and
//! propagation passes on a feather sinking, shrinking or rolling by more
//! than the drift tolerance (one that rises into what lies on it fails
//! their checks). A feather whose obstacles changed with the order is
//! checked, not readjusted: one that gained an obstacle fails its check if
//! the newcomer meets it, and one that lost an obstacle it rested on (now
//! later in the order, so adjusted over it) is left at its pose as long as
//! that stays clear: fewer feathers are readjusted a frame, for a coat
//! that may float a little higher (BENCHMARKS.md, "Measurements behind the
//! code's constants"). `R_k` (at θs, by the same net motion) still selects
//! the pairs whose priorities are recomputed.
//!
//! A full-size bent feather is kept where it lies rather than draped
//! afresh (the adjustment's `kept_in_place`): one that fails its check is
//! lifted in place as little as clears it, when a small lift does; a seed,
//! or one whose obstacle sank, that is clear is lowered a step if there
//! is room and otherwise left resting. A drape solved afresh lands
//! elsewhere (its bends jump), pushes up what lies on it and costs a
//! sweep; a step in place changes the pose by at most the settle rate
//! and lets the coat sink onto what lies beneath it frame by frame. Kites
//! and shortened feathers are solved as before.

use super::phases::{self, StepWorkspace, Workspace};
use super::rule::FrameRule;
use super::surroundings::{self, MOVED_AT_ALL};
use crate::adjustment::{AdjustStats, AdjustSteps, Adjuster, OrderedRun, Selection};
use crate::animation::contact::Posed;
use crate::animation::motion::root_maps;
use crate::body::BodyIndex;
use crate::coat::{Coat, Dressing};
use crate::csr::CsrView;
use crate::error::Result;
use crate::feather::FeatherPose;
use crate::geometry::RootFrame;
use crate::ordering::{Priorities, PriorityOrder};
use crate::progress::{Phase, Progress};
use crate::stats::FrameReport;
use std::time::Instant;

/// Advances `coat` to `positions` (welded) by `rule`, one of the
/// frame-to-frame rules (the rebuild rule solves instead, see
/// [`super::advance`]): the four phases of the module notes, then the
/// frame's report.
pub fn step_coat(
    coat: &mut Coat,
    dressing: &Dressing,
    rule: FrameRule,
    positions: &[glam::Vec3],
    work: &mut Workspace,
    step: &mut StepWorkspace,
    progress: &Progress,
) -> Result<()> {
    debug_assert!(rule != FrameRule::Rebuild, "a rebuild frame is solved from scratch");
    let start = Instant::now();
    let neighbourhood_seconds = repose(coat, dressing, rule, positions, step, progress)?;
    let deformed = find_moved(coat, dressing, rule, step, progress)?;
    let reordering = reorder(coat, dressing, rule, step, progress)?;
    let reorder_seconds = start.elapsed().as_secs_f64();
    progress.check(Phase::Adjusting, 0.0)?;
    let stats = readjust(coat, dressing, rule, work, step, progress)?;
    coat.frame_index += 1;
    coat.frame_report = FrameReport {
        frame_index: coat.frame_index,
        adjusted: stats.adjusted,
        deformed,
        seeds: reordering.seeds,
        verified: stats.verified,
        collision_tests: stats.collision_tests,
        priority_changes: reordering.priority_changes,
        reversals: reordering.reversals,
        reversals_refused: reordering.reversals_refused,
        cycles_broken: reordering.cycles_broken,
        clamped: stats.clamped,
        draped: stats.draped,
        kept_in_place: stats.kept_in_place,
        drape_descents: stats.drape_descents,
        reorder_seconds,
        adjust_seconds: stats.seconds,
        step_seconds: start.elapsed().as_secs_f64(),
        neighbourhood_seconds,
        levels: stats.levels,
    };
    Ok(())
}

/// Phase 1: keeps what the frame being left needs (verifying: where the
/// surroundings of the feathers adjusted last lie), re-poses every root,
/// rebuilds the neighbourhoods and the body index at the new pose when
/// they follow it, and works out which candidates lie over which
/// footprints. Returns the seconds the neighbourhoods took (0 when kept).
fn repose(
    coat: &mut Coat,
    dressing: &Dressing,
    rule: FrameRule,
    positions: &[glam::Vec3],
    step: &mut StepWorkspace,
    progress: &Progress,
) -> Result<f64> {
    let n = dressing.len();
    if coat.staleness.len() != n {
        coat.staleness.reset(n);
    }
    if rule.verifies() {
        surroundings::record_placements(coat, dressing, step);
    }
    surroundings::remember(coat, step);
    coat.pose(dressing, positions);
    progress.check(Phase::Ordering, 0.0)?;
    let mut neighbourhood_seconds = 0.0;
    if rule.follows_pose(&dressing.config) {
        neighbourhood_seconds = phases::neighbourhoods_and_body(coat, dressing, progress)?;
    }
    let posed = Posed { frames: &coat.frames, shapes: &dressing.shapes, poses: &coat.poses };
    let candidates = coat.neighbourhoods.obstacle_csr();
    step.contacts.reserve_entries(coat.neighbourhoods.obstacle_capacity());
    step.contacts.update(posed, &dressing.adjust_params, candidates, coat.order.ranks(), progress);
    progress.check(Phase::Ordering, 0.3)?;
    Ok(neighbourhood_seconds)
}

/// Phase 2: how far each feather's surroundings moved relative to it; the
/// seeds (surroundings moved past the rule's drift since the feather was
/// adjusted, or still settling), `R_k` (moved past θs) and, verifying, the
/// suspects (moved at all). Returns the size of `R_k`.
fn find_moved(
    coat: &mut Coat,
    dressing: &Dressing,
    rule: FrameRule,
    step: &mut StepWorkspace,
    progress: &Progress,
) -> Result<usize> {
    let (n, config, verify) = (dressing.len(), &dressing.config, rule.verifies());
    root_maps(&step.previous_frames, &coat.frames, &mut step.maps);
    surroundings::displacements(coat, dressing, step, verify, progress);
    progress.check(Phase::Ordering, 0.4)?;
    step.seeds.clear();
    step.seeds.resize(n, false);
    let drift = rule.drift(config);
    let drift_limit = |i: usize| drift * dressing.shapes[i].length;
    if verify {
        coat.staleness.set_net(&step.net, drift_limit, &mut step.seeds);
    } else {
        coat.staleness.add(&step.displacement, drift_limit, &mut step.seeds);
    }
    // Feathers still settling toward their solved pose go on.
    if rule.incremental() && coat.settling.len() == n {
        step.seeds.iter_mut().zip(&coat.settling).for_each(|(s, &settling)| *s |= settling);
    }
    let limit = |i: usize| config.theta_s * dressing.shapes[i].length;
    step.r_k.clear();
    step.r_k.extend((0..n as u32).filter(|&i| coat.staleness.moved()[i as usize] > limit(i as usize)));
    // The second pass's buffers, sized now: the first frame that needs
    // them may come late, and the heap must not grow then.
    step.no_suspects.reserve(n.saturating_sub(step.no_suspects.len()));
    step.verified.reserve(n.saturating_sub(step.verified.len()));
    step.suspects.clear();
    step.suspects.extend(
        step.displacement.iter().enumerate().map(|(i, &d)| verify && d > MOVED_AT_ALL * dressing.shapes[i].length),
    );
    Ok(step.r_k.len())
}

/// What phase 3 did: the reordering's figures and the seeds it left.
#[derive(Clone, Copy, Debug, Default)]
struct Reordering {
    priority_changes: usize,
    reversals: usize,
    reversals_refused: usize,
    cycles_broken: usize,
    /// Feathers to readjust in any case (`R*_k`'s seeds).
    seeds: usize,
}

/// Phase 3 (incremental; the legacy order is fixed): `ΔP` recomputed for
/// the pairs of `R_k` and its sign changes made edge reversals, then every
/// feather whose obstacles changed made a seed (verifying, a suspect).
fn reorder(
    coat: &mut Coat,
    dressing: &Dressing,
    rule: FrameRule,
    step: &mut StepWorkspace,
    progress: &Progress,
) -> Result<Reordering> {
    let mut reordering = Reordering::default();
    if rule.incremental() {
        let config = &dressing.config;
        let priorities = Priorities::improved(&coat.frames, config.gamma, config.lambda).with_layers(&dressing.layers);
        let pairs = config.recompute_neighbourhoods.then(|| coat.neighbourhoods.pairs());
        let stats = coat.order.update_frame(pairs, &step.r_k, &priorities);
        progress.check(Phase::Ordering, 0.8)?;
        reordering = Reordering {
            priority_changes: stats.priority_changes,
            reversals: stats.reversals_done,
            reversals_refused: stats.reversals_refused,
            cycles_broken: stats.cycles_broken,
            seeds: 0,
        };
        surroundings::obstacles_changed(coat, step, rule.verifies());
    }
    reordering.seeds = step.seeds.iter().filter(|s| **s).count();
    Ok(reordering)
}

/// Phase 4: the body indexed at the new pose (unless phase 1 did it), then
/// the seeds readjusted in order over the frame's obstacle rows (verifying:
/// the suspects checked exactly; else propagating past θs), then the
/// feathers an earlier one now lies on unlisted ([`missed_pass`]). Leaves
/// who was readjusted in `coat.readjusted` (and marks them fresh in the
/// staleness) and who still settles in `coat.settling`; returns the
/// passes' figures merged.
fn readjust(
    coat: &mut Coat,
    dressing: &Dressing,
    rule: FrameRule,
    work: &mut Workspace,
    step: &mut StepWorkspace,
    progress: &Progress,
) -> Result<AdjustStats> {
    if !rule.follows_pose(&dressing.config) {
        phases::body(coat, dressing);
    }
    if rule.verifies() {
        surroundings::watch_other_parts(coat, dressing, &mut step.suspects, &mut step.body_ids);
    }
    progress.check(Phase::Adjusting, 0.0)?;
    let n = dressing.len();
    let stats = if n == 0 {
        coat.readjusted.clear();
        AdjustStats::default()
    } else {
        let first = first_pass(coat, dressing, rule, work, step, progress)?;
        let posed = Posed { frames: &coat.frames, shapes: &dressing.shapes, poses: &coat.poses };
        let candidates = coat.neighbourhoods.obstacle_csr();
        let missed = step.contacts.missed(posed, candidates, coat.order.ranks(), &coat.readjusted);
        if missed > 0 {
            step.verified.clear();
            step.verified.extend_from_slice(work.adjuster.verified());
            let second = missed_pass(coat, dressing, rule, work, step, progress)?;
            merge_passes(first, second, &coat.readjusted, &step.verified)
        } else {
            first
        }
    };
    coat.staleness.clear_adjusted(&coat.readjusted);
    Ok(stats)
}

/// The first pass of phase 4: the seeds (and, verifying, the suspects) in
/// order, by levels, over the obstacle rows of the frame's contacts. Sets
/// `coat.readjusted` and `coat.settling` from it.
fn first_pass(
    coat: &mut Coat,
    dressing: &Dressing,
    rule: FrameRule,
    work: &mut Workspace,
    step: &mut StepWorkspace,
    progress: &Progress,
) -> Result<AdjustStats> {
    let candidates = coat.neighbourhoods.obstacle_csr();
    let pass = Pass::new(dressing, rule, &coat.frames, &coat.order, &coat.body);
    let rows = step.contacts.obstacle_rows(candidates, coat.order.ranks());
    let longest = (0..dressing.len()).map(|i| candidates.row(i).len()).max().unwrap_or(0);
    work.adjuster.reserve_obstacles(longest);
    work.adjuster.reserve_dependents(coat.neighbourhoods.obstacle_capacity());
    let selection = pass.selection(&step.seeds, rule.verifies().then_some(&step.suspects[..]));
    let keep_going = |done| progress.check(Phase::Adjusting, done).is_ok();
    let stats = pass.run(Walk::Levels, &mut work.adjuster, &mut coat.poses, rows, selection, &keep_going);
    // A stopped adjustment (None) has set the progress's stop flag.
    progress.check(Phase::Adjusting, 1.0)?;
    coat.settling.clear();
    coat.settling.extend_from_slice(work.adjuster.settling());
    coat.readjusted.clear();
    coat.readjusted.extend_from_slice(work.adjuster.adjusted());
    Ok(stats.unwrap_or_default())
}

/// The second pass of phase 4, for the contacts the first pass's rows
/// missed (a feather that turned past the pose margin over one it was not
/// listed for, see
/// [`Contacts::missed`](crate::animation::contact::Contacts::missed)):
/// those feathers (and, past the threshold, what lies on them) one after
/// the other with their full candidate lists. Adds whom it readjusted to `coat.readjusted` and
/// updates their settling. Returns its own figures.
fn missed_pass(
    coat: &mut Coat,
    dressing: &Dressing,
    rule: FrameRule,
    work: &mut Workspace,
    step: &mut StepWorkspace,
    progress: &Progress,
) -> Result<AdjustStats> {
    step.no_suspects.clear();
    step.no_suspects.resize(dressing.len(), false);
    let candidates = coat.neighbourhoods.obstacle_csr();
    let pass = Pass::new(dressing, rule, &coat.frames, &coat.order, &coat.body);
    let selection = pass.selection(step.contacts.missed_flags(), rule.verifies().then_some(&step.no_suspects[..]));
    let keep_going = |_| progress.check(Phase::Adjusting, 1.0).is_ok();
    let stats = pass.run(Walk::Sparse, &mut work.adjuster, &mut coat.poses, candidates, selection, &keep_going);
    progress.check(Phase::Adjusting, 1.0)?;
    let again = work.adjuster.adjusted().iter().zip(work.adjuster.settling());
    coat.settling.iter_mut().zip(again).filter(|(_, (a, _))| **a).for_each(|(s, (_, &b))| *s = b);
    coat.readjusted.iter_mut().zip(work.adjuster.adjusted()).for_each(|(a, &b)| *a |= b);
    Ok(stats.unwrap_or_default())
}

/// The figures of a frame's two passes as one. `adjusted` is who either
/// pass adjusted, `verified` who the first verified (kept as verified
/// unless the second adjusted it). The second pass visits its feathers one
/// after another, so each visit counts as a level. The clamped, draped and
/// descent counts are per pass, so a feather adjusted in both counts
/// twice: each sum is capped by the count it is a part of.
fn merge_passes(first: AdjustStats, second: AdjustStats, adjusted: &[bool], verified: &[bool]) -> AdjustStats {
    let AdjustStats {
        adjusted: _,
        collision_tests,
        clamped,
        draped,
        drape_descents,
        kept_in_place,
        verified: _,
        levels,
        seconds,
    } = first;
    let adjusted_count = adjusted.iter().filter(|a| **a).count();
    let draped = (draped + second.draped).min(adjusted_count);
    AdjustStats {
        adjusted: adjusted_count,
        collision_tests: collision_tests + second.collision_tests,
        clamped: (clamped + second.clamped).min(adjusted_count),
        draped,
        drape_descents: (drape_descents + second.drape_descents).min(draped),
        kept_in_place: (kept_in_place + second.kept_in_place).min(adjusted_count),
        verified: verified.iter().zip(adjusted).filter(|(v, a)| **v && !**a).count(),
        levels: levels + second.adjusted + second.verified,
        seconds: seconds + second.seconds,
    }
}

/// What every ordered adjustment of a frame shares.
struct Pass<'a> {
    dressing: &'a Dressing,
    steps: AdjustSteps,
    settle_rate: f32,
    frames: &'a [RootFrame],
    order: &'a PriorityOrder,
    body: &'a BodyIndex,
}

impl<'a> Pass<'a> {
    /// A pass of `rule` over the coat's frames, order and body.
    fn new(
        dressing: &'a Dressing,
        rule: FrameRule,
        frames: &'a [RootFrame],
        order: &'a PriorityOrder,
        body: &'a BodyIndex,
    ) -> Self {
        Self { dressing, steps: rule.steps(), settle_rate: rule.settle_rate(&dressing.config), frames, order, body }
    }

    /// Verifying with `suspects`, or propagating past θs.
    fn selection<'s>(&self, seeds: &'s [bool], suspects: Option<&'s [bool]>) -> Selection<'s> {
        let d = self.dressing;
        match suspects {
            Some(suspects) => Selection::Verify { seeds, suspects, threshold: d.config.drift_tolerance },
            None => Selection::Propagate { seeds, threshold: d.config.theta_s },
        }
    }

    /// Adjusts the seeds of `selection` in order, and past θs what lies on
    /// them, with `candidates` as obstacle lists, by levels or one feather
    /// after the other (see [`Walk`]); the same poses either way.
    fn run(
        &self,
        walk: Walk,
        adjuster: &mut Adjuster,
        poses: &mut [FeatherPose],
        candidates: CsrView<'_, u32>,
        selection: Selection<'_>,
        keep_going: &(dyn Fn(f32) -> bool + Sync),
    ) -> Option<AdjustStats> {
        let d = self.dressing;
        let walk_with = match walk {
            Walk::Levels => Adjuster::adjust_in_order_until,
            Walk::Sparse => Adjuster::adjust_sparse_until,
        };
        let run = OrderedRun {
            frames: self.frames,
            shapes: &d.shapes,
            order: self.order.order(),
            rank: self.order.ranks(),
            candidates,
            body: self.body,
            params: &d.adjust_params,
            steps: self.steps,
            settle_rate: self.settle_rate,
        };
        walk_with(adjuster, &run, poses, selection, keep_going)
    }
}

/// How a [`Pass`] goes through the coat.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Walk {
    /// By levels of the obstacle relation, in parallel: the first pass.
    Levels,
    /// One feather after the other, visiting only the seeds and what the
    /// feathers it adjusts change under: the few feathers of the
    /// missed-contact pass over the full, symmetric candidate lists.
    Sparse,
}
