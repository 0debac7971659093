//! What moved around each feather between two frames, for the phases of
//! a step ([`super::step`]): the frame being left, kept; the surroundings
//! recorded when a feather is adjusted; how far they moved; whose
//! obstacles changed with the order; and skin of other parts nearby.

use super::phases::StepWorkspace;
use crate::animation::contact::{Footprint, Sphere};
use crate::coat::{Coat, Dressing, Oriented, Placement, orientation};
use crate::geometry::RootFrame;
use crate::progress::{Phase, Progress};
use crate::triangle_grid::Aabb;
use glam::Vec3;
use rayon::prelude::*;

/// Displacement of a feather's surroundings, as a fraction of its length,
/// below which it is taken for rounding noise (a rigid motion) and the
/// feather is not checked.
pub(super) const MOVED_AT_ALL: f32 = 1e-6;

/// Marks as suspects (checked exactly this frame, skin included) the
/// feathers that skin of another connected part of the surface comes
/// within a feather length of. Their own surroundings may not have moved
/// at all (a tube closing on another moves rigidly with its feathers), so
/// nothing else would look at them, and the other part's skin could sweep
/// into them unseen. One box query per feather not already a suspect, and
/// only when the surface has several parts.
pub(super) fn watch_other_parts(coat: &Coat, dressing: &Dressing, suspects: &mut [bool], ids: &mut Vec<u32>) {
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

/// Keeps the root frames, ranks and obstacle candidates of the frame being left.
pub(super) fn remember(coat: &Coat, step: &mut StepWorkspace) {
    step.previous_frames.clear();
    step.previous_frames.extend_from_slice(&coat.frames);
    step.previous_ranks.clear();
    step.previous_ranks.extend_from_slice(coat.order.ranks());
    step.previous_candidates.reserve_items(coat.neighbourhoods.obstacle_capacity());
    step.previous_candidates.copy_from(coat.obstacle_candidates());
}

/// Records, for each feather adjusted since the last record (all of them
/// after a solve), where its surroundings lie in its frame at the pose the
/// coat holds, the pose it was adjusted at: its k nearest roots (turns
/// measured at their distance), then its earlier candidates lying over its
/// footprint (at their length), those of [`displacements`], as
/// many as there are slots.
pub(super) fn record_placements(coat: &mut Coat, dressing: &Dressing, step: &mut StepWorkspace) {
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
    let candidates = coat.neighbourhoods.obstacle_csr();
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
pub(super) fn displacements(
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
pub(super) fn obstacles_changed(coat: &Coat, step: &mut StepWorkspace, verify: bool) {
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
