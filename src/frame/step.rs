//! One animation frame, incremental (paper §3.3) or legacy (the 2015
//! method), applied to a coat in place (DESIGN.md §5): the frame-to-frame
//! variants of the order and adjust phases of [`crate::frame`]:
//! 1. re-pose every root from the deformed mesh; feathers keep their pitch
//!    and roll relative to their own frame (incremental: neighbourhoods and
//!    obstacle candidates follow the current pose);
//! 2. `R_k`: feathers whose surroundings moved relative to them since they
//!    were last adjusted ([`crate::coat::Staleness`]), by more
//!    than `θs·L` (a feather's tip moves that far when its pitch changes by
//!    θs, the change the propagation rule already lets pass). The
//!    surroundings are the k nearest roots (their priorities) and the
//!    earlier candidates whose feathers lie over the feather's footprint
//!    (its obstacles). A rigid motion moves nothing relative to anything;
//! 3. (incremental) `ΔP` recomputed for the pairs of `R_k`, sign changes
//!    turned into edge reversals in the dynamic order with the cycle rule;
//! 4. `R*_k` = `R_k` plus the feathers whose obstacles changed with the
//!    order or the neighbourhoods: a candidate lying over the footprint
//!    became earlier or stopped being earlier. They are readjusted in order
//!    (all three steps; the legacy mode runs fine pitch only), and a feather
//!    whose pitch or roll moved by more than θs pulls in the feathers that
//!    lie on it ([`Contacts`]).
//!
//! Beyond the paper (incremental, `drift_tolerance` > θs, the default):
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

use super::phases::{self, Workspace};
use crate::Mode;
use crate::adjustment::{AdjustStats, AdjustSteps, Adjuster, OrderedRun, Selection};
use crate::animation::contact::{Contacts, Footprint, Posed, Sphere};
use crate::animation::motion::{RootMap, root_maps};
use crate::body::BodyIndex;
use crate::coat::{Coat, Dressing, Oriented, Placement, orientation};
use crate::csr::{Csr, CsrView};
use crate::error::Result;
use crate::feather::FeatherPose;
use crate::geometry::RootFrame;
use crate::ordering::{Priorities, PriorityOrder};
use crate::progress::{Phase, Progress};
use crate::stats::FrameReport;
use crate::triangle_grid::Aabb;
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;

/// Displacement of a feather's surroundings, as a fraction of its length,
/// below which it is taken for rounding noise (a rigid motion) and the
/// feather is not checked.
const MOVED_AT_ALL: f32 = 1e-6;

/// Marks as suspects (checked exactly this frame, skin included) the
/// feathers that skin of another connected part of the surface comes
/// within a feather length of. Their own surroundings may not have moved
/// at all (a tube closing on another moves rigidly with its feathers), so
/// nothing else would look at them, and the other part's skin could sweep
/// into them unseen. One box query per feather not already a suspect, and
/// only when the surface has several parts.
fn watch_other_parts(coat: &Coat, dressing: &Dressing, suspects: &mut [bool], ids: &mut Vec<u32>) {
    if dressing.parts < 2 {
        return;
    }
    for (i, suspect) in suspects.iter_mut().enumerate() {
        if *suspect || coat.poses[i].scale <= 0.0 {
            continue;
        }
        let own = dressing.face_part[dressing.roots[i].point.face as usize];
        let reach = Vec3::splat(dressing.shapes[i].length * coat.poses[i].scale);
        let root = coat.frames[i].position;
        coat.body.triangles_in_box(&Aabb { min: root - reach, max: root + reach }, ids);
        *suspect = ids.iter().any(|&t| dressing.face_part[t as usize] != own);
    }
}

/// Buffers of the frame update, reused every frame.
#[derive(Debug, Default)]
pub struct StepWorkspace {
    previous_frames: Vec<RootFrame>,
    previous_ranks: Vec<u32>,
    previous_candidates: Csr<u32>,
    maps: Vec<RootMap>,
    displacement: Vec<f32>,
    net: Vec<f32>,
    orientations: Vec<glam::Quat>,
    spheres: Vec<Sphere>,
    seeds: Vec<bool>,
    suspects: Vec<bool>,
    no_suspects: Vec<bool>,
    verified: Vec<bool>,
    r_k: Vec<u32>,
    body_ids: Vec<u32>,
    contacts: Contacts,
    adjusted: Vec<bool>,
}

/// Advances `coat` to `positions` (welded) by the incremental or legacy
/// rule of `dressing.config.mode`.
pub fn step_coat(
    coat: &mut Coat,
    dressing: &Dressing,
    positions: &[glam::Vec3],
    work: &mut Workspace,
    step: &mut StepWorkspace,
    progress: &Progress,
) -> Result<()> {
    let start = Instant::now();
    let n = dressing.len();
    let incremental = dressing.config.mode == Mode::Incremental;
    // 1. Record where the surroundings of the feathers adjusted last lie;
    // re-pose; remember where everything was.
    if coat.staleness.len() != n {
        coat.staleness.reset(n);
    }
    let verify = incremental && dressing.config.drift_tolerance > dressing.config.theta_s;
    if verify {
        record_placements(coat, dressing, step);
    }
    remember(coat, step);
    coat.pose(dressing, positions);
    progress.check(Phase::Ordering, 0.0)?;
    let mut neighbourhood_seconds = 0.0;
    let body_indexed = incremental && dressing.config.recompute_neighbourhoods;
    if body_indexed {
        neighbourhood_seconds = phases::neighbourhoods_and_body(coat, dressing, progress)?;
    }
    let posed = Posed { frames: &coat.frames, shapes: &dressing.shapes, poses: &coat.poses };
    let candidates = coat.obstacle_candidates();
    step.contacts.update(posed, &dressing.adjust_params, candidates, coat.order.ranks(), progress);
    progress.check(Phase::Ordering, 0.3)?;

    // 2. R_k from the relative motion of the roots since the last frame.
    root_maps(&step.previous_frames, &coat.frames, &mut step.maps);
    surroundings_displacement(coat, dressing, step, verify, progress);
    progress.check(Phase::Ordering, 0.4)?;
    step.seeds.clear();
    step.seeds.resize(n, false);
    let drift = if verify { dressing.config.drift_tolerance } else { dressing.config.theta_s };
    let limit = |i: usize| dressing.config.theta_s * dressing.shapes[i].length;
    let drift_limit = |i: usize| drift * dressing.shapes[i].length;
    if verify {
        coat.staleness.set_net(&step.net, drift_limit, &mut step.seeds);
    } else {
        coat.staleness.add(&step.displacement, drift_limit, &mut step.seeds);
    }
    // Feathers still settling toward their solved pose go on (incremental).
    if incremental && coat.settling.len() == n {
        step.seeds.iter_mut().zip(&coat.settling).for_each(|(s, &settling)| *s |= settling);
    }
    step.r_k.clear();
    step.r_k.extend((0..n as u32).filter(|&i| coat.staleness.moved()[i as usize] > limit(i as usize)));
    // The second pass's buffers, sized now: the first frame that needs
    // them may come late, and the heap must not grow then.
    step.no_suspects.reserve(n.saturating_sub(step.no_suspects.len()));
    step.verified.reserve(n.saturating_sub(step.verified.len()));
    step.adjusted.reserve(n.saturating_sub(step.adjusted.len()));
    step.suspects.clear();
    step.suspects.extend(
        step.displacement.iter().enumerate().map(|(i, &d)| verify && d > MOVED_AT_ALL * dressing.shapes[i].length),
    );

    // 3. Reordering (incremental only: the legacy order is fixed).
    let mut report = FrameReport { frame_index: coat.frame_index + 1, neighbourhood_seconds, ..FrameReport::default() };
    if incremental {
        let priorities = Priorities::improved(&coat.frames, dressing.config.gamma, dressing.config.lambda);
        let pairs = dressing.config.recompute_neighbourhoods.then(|| coat.neighbourhoods.pairs());
        let stats = coat.order.update_frame(pairs, &step.r_k, &priorities);
        progress.check(Phase::Ordering, 0.8)?;
        report.priority_changes = stats.priority_changes;
        report.reversals = stats.reversals_done;
        report.reversals_refused = stats.reversals_refused;
        report.cycles_broken = stats.cycles_broken;
        // R*_k: add every feather whose obstacles changed.
        obstacles_changed(coat, step, verify);
    }
    report.deformed = step.r_k.len();
    report.seeds = step.seeds.iter().filter(|s| **s).count();
    report.reorder_seconds = start.elapsed().as_secs_f64();
    progress.check(Phase::Adjusting, 0.0)?;

    // 4. Readjust R*_k in order, propagating past θs.
    if !body_indexed {
        phases::body(coat, dressing);
    }
    if verify {
        watch_other_parts(coat, dressing, &mut step.suspects, &mut step.body_ids);
    }
    progress.check(Phase::Adjusting, 0.0)?;
    let steps = if dressing.config.mode == Mode::Legacy { AdjustSteps::FinePitchOnly } else { AdjustSteps::Full };
    let stats = if n == 0 {
        AdjustStats::default()
    } else {
        let candidates = CsrView::from(coat.neighbourhoods.obstacle_csr());
        let pass = Pass { dressing, steps, frames: &coat.frames, order: &coat.order, body: &coat.body };
        let rows = step.contacts.obstacle_rows(candidates, coat.order.ranks());
        work.adjuster.reserve_obstacles((0..n).map(|i| candidates.row(i).len()).max().unwrap_or(0));
        let settle_rate = if incremental { dressing.config.settle_rate } else { 0.0 };
        work.adjuster.settle_next_run(settle_rate);
        let stats = pass.run(
            Walk::Levels,
            &mut work.adjuster,
            &mut coat.poses,
            rows,
            pass.selection(&step.seeds, verify.then_some(&step.suspects[..])),
            &|done| progress.check(Phase::Adjusting, done).is_ok(),
        );
        // A stopped adjustment (None) has set the progress's stop flag.
        progress.check(Phase::Adjusting, 1.0)?;
        let mut stats = stats.unwrap_or_default();
        coat.settling.clear();
        coat.settling.extend_from_slice(work.adjuster.settling());
        let posed = Posed { frames: &coat.frames, shapes: &dressing.shapes, poses: &coat.poses };
        let missed = step.contacts.missed(posed, candidates, coat.order.ranks(), work.adjuster.adjusted());
        if missed > 0 {
            // Feathers an earlier one now lies on unlisted: readjust them
            // (and, past θs, what lies on them) with their full lists.
            step.adjusted.clear();
            step.adjusted.extend_from_slice(work.adjuster.adjusted());
            let seeds = step.contacts.missed_flags();
            step.verified.clear();
            step.verified.extend_from_slice(work.adjuster.verified());
            step.no_suspects.clear();
            step.no_suspects.resize(n, false);
            work.adjuster.settle_next_run(settle_rate);
            let more = pass.run(
                Walk::Sparse,
                &mut work.adjuster,
                &mut coat.poses,
                candidates,
                pass.selection(seeds, verify.then_some(&step.no_suspects[..])),
                &|_| progress.check(Phase::Adjusting, 1.0).is_ok(),
            );
            progress.check(Phase::Adjusting, 1.0)?;
            let more = more.unwrap_or_default();
            let again = work.adjuster.adjusted().iter().zip(work.adjuster.settling());
            coat.settling.iter_mut().zip(again).filter(|(_, (a, _))| **a).for_each(|(s, (_, &b))| *s = b);
            for (a, &b) in step.adjusted.iter_mut().zip(work.adjuster.adjusted()) {
                *a |= b;
            }
            work.adjuster.set_adjusted(&step.adjusted);
            stats.adjusted = step.adjusted.iter().filter(|a| **a).count();
            stats.verified = step.verified.iter().zip(&step.adjusted).filter(|(v, a)| **v && !**a).count();
            stats.collision_tests += more.collision_tests;
            // The second pass visits its feathers one after another.
            stats.levels += more.adjusted + more.verified;
            // A feather adjusted in both passes may be counted clamped twice.
            stats.clamped = (stats.clamped + more.clamped).min(stats.adjusted);
            stats.draped = (stats.draped + more.draped).min(stats.adjusted);
            stats.drape_descents = (stats.drape_descents + more.drape_descents).min(stats.draped);
            stats.seconds += more.seconds;
        }
        stats
    };
    coat.staleness.clear_adjusted(work.adjuster.adjusted());
    report.adjusted = stats.adjusted;
    report.verified = stats.verified;
    report.collision_tests = stats.collision_tests;
    report.clamped = stats.clamped;
    report.draped = stats.draped;
    report.drape_descents = stats.drape_descents;
    report.adjust_seconds = stats.seconds;
    report.levels = stats.levels;
    report.step_seconds = start.elapsed().as_secs_f64();
    coat.frame_index += 1;
    coat.frame_report = report;
    Ok(())
}

/// What every ordered adjustment of a frame shares.
struct Pass<'a> {
    dressing: &'a Dressing,
    steps: AdjustSteps,
    frames: &'a [RootFrame],
    order: &'a PriorityOrder,
    body: &'a BodyIndex,
}

impl Pass<'_> {
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

/// Keeps the root frames, ranks and obstacle candidates of the frame being left.
fn remember(coat: &Coat, step: &mut StepWorkspace) {
    step.previous_frames.clear();
    step.previous_frames.extend_from_slice(&coat.frames);
    step.previous_ranks.clear();
    step.previous_ranks.extend_from_slice(coat.order.ranks());
    step.previous_candidates.copy_from(coat.obstacle_candidates());
}

/// Records, for each feather adjusted since the last record (all of them
/// after a solve), where its surroundings lie in its frame at the pose the
/// coat holds, the pose it was adjusted at: its k nearest roots (turns
/// measured at their distance), then its earlier candidates lying over its
/// footprint (at their length), those of [`surroundings_displacement`], as
/// many as there are slots.
fn record_placements(coat: &mut Coat, dressing: &Dressing, step: &mut StepWorkspace) {
    let n = dressing.len();
    if coat.frames.len() != n || !(0..n).any(|i| coat.staleness.pending(i)) {
        return;
    }
    let (frames, poses, shapes) = (&coat.frames, &coat.poses, &dressing.shapes);
    step.spheres.resize(n, Sphere::default());
    step.spheres.par_iter_mut().enumerate().with_min_len(256).for_each(|(j, s)| {
        *s = Sphere::of(&frames[j], &shapes[j], poses[j]);
    });
    orientations_into(frames, &mut step.orientations);
    let candidates = CsrView::from(coat.neighbourhoods.obstacle_csr());
    let (nb, ranks, spheres) = (&coat.neighbourhoods, coat.order.ranks(), &step.spheres);
    let oriented = |j: usize| Oriented { frame: &frames[j], orientation: step.orientations[j] };
    for i in 0..n {
        if !coat.staleness.pending(i) {
            continue;
        }
        let here = &frames[i];
        let nearest = nb.neighbours_of(i as u32).iter().map(|&j| {
            let there = &frames[j as usize];
            Placement::of(oriented(i), j, oriented(j as usize), here.position.distance(there.position))
        });
        let footprint = Footprint::of(&shapes[i], &dressing.adjust_params);
        let resting = candidates
            .row(i)
            .iter()
            .filter(|&&j| ranks[j as usize] < ranks[i] && footprint.reached_by(here, spheres[j as usize]))
            .map(|&j| Placement::of(oriented(i), j, oriented(j as usize), shapes[j as usize].length));
        coat.staleness.record(i, nearest.chain(resting));
    }
}

/// Every root frame's orientation, into `out`, in parallel.
fn orientations_into(frames: &[RootFrame], out: &mut Vec<glam::Quat>) {
    out.resize(frames.len(), glam::Quat::IDENTITY);
    out.par_iter_mut().zip(frames).with_min_len(256).for_each(|(q, f)| *q = orientation(f));
}

/// For each feather, how far its surroundings moved relative to it since
/// the last frame (`displacement`): over its k nearest roots j, the
/// displacement at the distance between the roots (what their priority
/// difference sees); over its earlier candidates lying over its footprint,
/// the displacement at their length (what its height field sees). With
/// `net`, also how far the surroundings recorded when it was last adjusted
/// moved since (`net`, the staleness of the verifying mode).
fn surroundings_displacement(
    coat: &Coat,
    dressing: &Dressing,
    step: &mut StepWorkspace,
    net: bool,
    progress: &Progress,
) {
    let (maps, frames, ranks, contacts) = (&step.maps, &coat.frames, &step.previous_ranks, &step.contacts);
    let candidates = coat.obstacle_candidates();
    let (nb, staleness) = (&coat.neighbourhoods, &coat.staleness);
    let n = dressing.len();
    step.displacement.resize(n, 0.0);
    step.net.resize(n, 0.0);
    step.orientations.clear();
    if net {
        orientations_into(frames, &mut step.orientations);
    }
    let orientations = &step.orientations;
    let oriented = |j: usize| Oriented { frame: &frames[j], orientation: orientations[j] };
    let outputs = step.displacement.par_iter_mut().zip(step.net.par_iter_mut());
    outputs.enumerate().with_min_len(128).for_each(|(i, (out, moved_net))| {
        // Stopped: the rest keep stale figures (the frame is dropped).
        if !progress.poll(Phase::Ordering, 0.35, i) {
            return;
        }
        let (here, frame) = (&maps[i], &frames[i]);
        // With the net rule the displacement only tells whether anything
        // moved at all (a suspect), so the first that did is enough.
        let enough = if net { MOVED_AT_ALL * dressing.shapes[i].length } else { f32::INFINITY };
        let mut worst = 0.0f32;
        for &j in nb.neighbours_of(i as u32) {
            let j = j as usize;
            worst = worst.max(here.relative(&maps[j]).at(frame.position.distance(frames[j].position)));
        }
        for (e, &j) in candidates.span(i).zip(candidates.row(i)) {
            if worst > enough {
                break;
            }
            let j = j as usize;
            if contacts.touching(e) & (ranks[j] < ranks[i]) {
                worst = worst.max(here.relative(&maps[j]).at(dressing.shapes[j].length));
            }
        }
        *out = worst;
        if net {
            let placements = staleness.placements(i);
            *moved_net =
                placements.iter().map(|p| p.moved(oriented(i), oriented(p.other as usize))).fold(0.0f32, f32::max);
        }
    });
}

/// Adds to the seeds every feather whose obstacles changed with the order
/// or the candidate lists: a candidate lying over its footprint that was
/// earlier and no longer is, or the other way round. Verifying, such a
/// feather is a suspect instead: the exact check against its obstacles at
/// their final poses finds whether a new one meets it, and one that went
/// away only leaves it higher than needed (module notes).
fn obstacles_changed(coat: &Coat, step: &mut StepWorkspace, verify: bool) {
    let (candidates, old_candidates) = (coat.obstacle_candidates(), step.previous_candidates.view());
    let (old_rank, rank) = (&step.previous_ranks, coat.order.ranks());
    let (contacts, frames) = (&step.contacts, &coat.frames);
    let n = step.seeds.len();
    let same_rows = old_candidates.rows() == n;
    step.seeds
        .par_iter_mut()
        .zip(step.suspects.par_iter_mut())
        .enumerate()
        .with_min_len(128)
        // Verifying, a change only makes a suspect, and a feather whose
        // surroundings moved at all is one already.
        .filter(|(_, (s, v))| !(**s || verify && **v))
        .for_each(|(i, (seed, suspect))| {
            let new_row = candidates.row(i);
            let old_row = if same_rows { old_candidates.row(i) } else { &[] };
            let footprint = contacts.footprint(i);
            let mut changed = false;
            let lost = status_changes(old_row, new_row, |j, in_old, in_new| {
                let was = in_old && old_rank[j] < old_rank[i];
                let is = in_new && rank[j] < rank[i];
                if was == is || !footprint.reached_by(&frames[i], contacts.sphere(j)) {
                    return false;
                }
                changed = true;
                !verify
            });
            *seed = lost;
            *suspect |= changed;
        });
}

/// Walks the union of two sorted rows; true as soon as `changed(j, in
/// old, in new)` is.
fn status_changes(old: &[u32], new: &[u32], mut changed: impl FnMut(usize, bool, bool) -> bool) -> bool {
    let (mut a, mut b) = (0, 0);
    while a < old.len() || b < new.len() {
        let (x, y) = (old.get(a).copied().unwrap_or(u32::MAX), new.get(b).copied().unwrap_or(u32::MAX));
        let j = x.min(y);
        let (in_old, in_new) = (x == j && a < old.len(), y == j && b < new.len());
        a += usize::from(in_old);
        b += usize::from(in_new);
        if changed(j as usize, in_old, in_new) {
            return true;
        }
    }
    false
}

crate::memory::heap_size_of_fields!(StepWorkspace {
    previous_frames,
    previous_ranks,
    previous_candidates,
    maps,
    displacement,
    net,
    orientations,
    spheres,
    seeds,
    suspects,
    no_suspects,
    verified,
    r_k,
    body_ids,
    contacts,
    adjusted
});

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_changes_walks_the_union_of_two_rows() {
        let mut seen = Vec::new();
        let changed = status_changes(&[1, 3, 5], &[2, 3, 6], |j, a, b| {
            seen.push((j, a, b));
            false
        });
        assert!(!changed);
        assert_eq!(seen, [(1, true, false), (2, false, true), (3, true, true), (5, true, false), (6, false, true)]);
        assert!(status_changes(&[], &[4], |j, _, b| j == 4 && b));
        assert!(!status_changes(&[], &[], |_, _, _| true));
    }
}
