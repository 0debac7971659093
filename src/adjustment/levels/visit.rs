//! One feather's turn in an ordered run: skipped, verified where it lies,
//! or adjusted (and settled); what every feather of a level reads, and the
//! parallel run of one level.

use super::super::checks::{
    BoxesOf, FeatherInPlace, ObstacleReach, bounding_sphere, posed_is_clear_boxed, posed_meets_none_boxed,
};
use super::super::drape::repair_drape;
use super::super::obstacle::{ObstacleBounds, ObstacleBoxes};
use super::super::settle::{SettlingFeather, lowered_pose, lowest_pose, settled_pose};
use super::super::steps::adjust_feather_boxed;
use super::super::{AdjustOutcome, AdjustParams, AdjustSteps, DrapeRoute, HeightField, ObstacleFeather};
use super::aside::Aside;
use crate::body::BodyIndex;
use crate::csr::CsrView;
use crate::feather::{FeatherPose, FeatherShape, FeatherTriangles, feather_triangles, pose_change};
use crate::geometry::RootFrame;
use crate::validation::FeatherBoxes;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU8, Ordering};

/// Obstacles whose root normal is more than 120° from the adjusted
/// feather's grow from the far side of a thin part (see
/// [`ObstacleFeather::far_side`]).
const FAR_SIDE_NORMAL_DOT: f32 = -0.5;

/// Which feathers an ordered adjustment touches.
#[derive(Clone, Copy, Debug)]
pub enum Selection<'a> {
    /// Every feather.
    All,
    /// Only the marked feathers; the others are fixed obstacles.
    Subset(&'a [bool]),
    /// The marked feathers, plus (in order) every feather one of whose
    /// obstacles was adjusted and moved by more than `threshold` radians in
    /// pitch or roll (DESIGN.md §5, step 4, θs).
    Propagate {
        /// Feathers adjusted in any case.
        seeds: &'a [bool],
        /// θs, radians.
        threshold: f32,
    },
    /// As [`Propagate`](Self::Propagate), and besides: a feather marked in
    /// `suspects`, or one of whose obstacles was adjusted at all, is checked
    /// exactly at its current pose (the validation's tests against its
    /// obstacles, at their final poses, and the body) and adjusted when the
    /// check fails. A frame can then leave alone feathers whose
    /// surroundings moved a little, without letting them intersect. Here
    /// propagation passes on only what can leave a feather standing on
    /// nothing: an obstacle that sank (pitch) or shrank (scale) by more
    /// than `threshold`, or rolled by more than it either way; one that
    /// rose or grew into a feather fails that feather's exact check.
    Verify {
        /// Feathers adjusted in any case.
        seeds: &'a [bool],
        /// Feathers checked in any case.
        suspects: &'a [bool],
        /// θs, radians.
        threshold: f32,
    },
}

impl Selection<'_> {
    /// Feathers adjusted in any case, for the propagating selections.
    pub(super) fn seeds(&self) -> Option<&[bool]> {
        match *self {
            Self::Propagate { seeds, .. } | Self::Verify { seeds, .. } => Some(seeds),
            Self::All | Self::Subset(_) => None,
        }
    }

    /// θs of the propagating selections.
    pub(super) fn threshold(&self) -> Option<f32> {
        match *self {
            Self::Propagate { threshold, .. } | Self::Verify { threshold, .. } => Some(threshold),
            Self::All | Self::Subset(_) => None,
        }
    }
}

/// Scratch of one work chunk.
#[derive(Clone, Debug)]
pub(super) struct Worker {
    pub(super) field: HeightField,
    pub(super) obstacles: Vec<ObstacleFeather>,
    /// The feather index of each obstacle.
    pub(super) obstacle_ids: Vec<u32>,
    /// Those of `obstacle_ids` that changed pose earlier in the run.
    pub(super) changed_ids: Vec<u32>,
}

/// The answer of an exact check made ahead of a verifying walk, against
/// the coat as it was before the walk. It stands
/// for the check the walk would make as long as no obstacle of the
/// feather changed pose before its turn (the check reads only the
/// feather's own pose, its obstacles' poses and the body); a clear one is
/// then redone against the obstacles that changed alone.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) enum Precheck {
    /// Not checked ahead.
    #[default]
    None = 0,
    /// The pose was clear.
    Clear = 1,
    /// The pose met an obstacle or the body.
    Blocked = 2,
}

/// Answers of checks made ahead ([`Precheck`] as `u8`), by feather; set
/// from several threads at once.
#[derive(Debug, Default)]
pub(super) struct Prechecks(Vec<AtomicU8>);

impl Clone for Prechecks {
    fn clone(&self) -> Self {
        Self(self.0.iter().map(|c| AtomicU8::new(c.load(Ordering::Relaxed))).collect())
    }
}

impl Prechecks {
    /// No answer for `n` feathers.
    pub(super) fn reset(&mut self, n: usize) {
        self.0.clear();
        self.0.resize_with(n, || AtomicU8::new(Precheck::None as u8));
    }

    pub(super) fn cells(&self) -> &[AtomicU8] {
        &self.0
    }
}

impl crate::memory::HeapSize for Prechecks {
    fn heap_bytes(&self) -> usize {
        self.0.capacity() * std::mem::size_of::<AtomicU8>()
    }
}

impl Precheck {
    /// The answer stored in `cell` (by [`Precheck::store`]); any other
    /// value (a cell a thread has taken) is no answer.
    #[inline]
    pub(super) fn load(cell: &AtomicU8) -> Self {
        match cell.load(Ordering::Relaxed) {
            1 => Self::Clear,
            2 => Self::Blocked,
            _ => Self::None,
        }
    }

    /// Stores this answer in `cell`. The answer is all a reader takes from
    /// it, so no ordering with other memory is needed.
    #[inline]
    pub(super) fn store(self, cell: &AtomicU8) {
        cell.store(self as u8, Ordering::Relaxed);
    }
}

/// The read-only inputs of every feather of a level.
pub(super) struct Inputs<'a> {
    pub(super) frames: &'a [RootFrame],
    pub(super) shapes: &'a [FeatherShape],
    pub(super) rank: &'a [u32],
    pub(super) candidates: CsrView<'a, u32>,
    pub(super) body: &'a BodyIndex,
    pub(super) params: &'a AdjustParams,
    pub(super) steps: AdjustSteps,
    pub(super) selection: Selection<'a>,
    /// Verification tests the pairs only (see [`super::Adjuster::adjust_sparse_until`]).
    pub(super) pairs_only: bool,
    /// See [`super::OrderedRun::settle_rate`]; 0 = the solved poses.
    pub(super) settle_rate: f32,
    /// Asked (with the share done) between feathers; once it says stop,
    /// the run is abandoned and its remaining feathers are not visited.
    pub(super) keep_going: &'a (dyn Fn(f32) -> bool + Sync),
}

/// What became of one feather of a level.
#[derive(Clone, Copy, Debug)]
pub(super) enum Visit {
    /// Propagation did not reach it.
    Skipped,
    /// Its pose passed the exact check and stays.
    Verified,
    /// It was adjusted: the pose it takes, and the pose solved for it
    /// (the same unless it settles toward it, see
    /// [`super::OrderedRun::settle_rate`]).
    Adjusted(AdjustOutcome, FeatherPose),
}

/// What the levels run so far did to each feather: moved past θs, or
/// changed at all.
#[derive(Clone, Copy)]
pub(super) struct Marks<'a> {
    pub(super) moved: &'a [bool],
    pub(super) changed: &'a [bool],
    /// Answers of the checks made ahead ([`Precheck`] as `u8`).
    pub(super) prechecked: &'a [AtomicU8],
}

/// Feathers' posed geometry, owned, one entry per feather: its triangles,
/// a bounding sphere of them (centre, radius), its triangles and raised
/// top with their boxes as the exact checks of the feathers it is an
/// obstacle of meet them, and their outer boxes.
#[derive(Clone, Debug, Default)]
pub(super) struct Posed {
    pub(super) triangles: Vec<FeatherTriangles>,
    pub(super) spheres: Vec<(Vec3, f32)>,
    pub(super) boxes: Vec<ObstacleBoxes>,
    pub(super) bounds: Vec<ObstacleBounds>,
}

impl Posed {
    /// A view of it, with nothing set aside.
    pub(super) fn view(&self) -> PosedGeometry<'_> {
        PosedGeometry {
            triangles: &self.triangles,
            spheres: &self.spheres,
            boxes: &self.boxes,
            bounds: &self.bounds,
            aside: None,
        }
    }

    /// Entry `k` becomes `g`.
    pub(super) fn set(&mut self, k: usize, g: &FeatherGeometry) {
        (self.triangles[k], self.spheres[k]) = (g.triangles, g.sphere);
        (self.boxes[k], self.bounds[k]) = (g.boxes, g.bounds);
    }

    /// Appends `g`.
    pub(super) fn push(&mut self, g: &FeatherGeometry) {
        self.triangles.push(g.triangles);
        self.spheres.push(g.sphere);
        self.boxes.push(g.boxes);
        self.bounds.push(g.bounds);
    }

    /// No entries (the capacity kept).
    pub(super) fn clear(&mut self) {
        self.triangles.clear();
        self.spheres.clear();
        self.boxes.clear();
        self.bounds.clear();
    }

    /// Entry `k`.
    pub(super) fn get(&self, k: usize) -> FeatherGeometry {
        FeatherGeometry {
            triangles: self.triangles[k],
            sphere: self.spheres[k],
            boxes: self.boxes[k],
            bounds: self.bounds[k],
        }
    }
}

crate::memory::heap_size_of_fields!(Posed { triangles, spheres, boxes, bounds });

/// One feather's posed geometry (an entry of [`Posed`]).
pub(super) struct FeatherGeometry {
    pub(super) triangles: FeatherTriangles,
    pub(super) sphere: (Vec3, f32),
    pub(super) boxes: ObstacleBoxes,
    pub(super) bounds: ObstacleBounds,
}

impl FeatherGeometry {
    /// The geometry of feather `shape` at `frame` in `pose`.
    pub(super) fn of(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> Self {
        let triangles = feather_triangles(frame, shape, pose);
        let boxes = ObstacleBoxes::new(&triangles, shape.thickness);
        Self { sphere: bounding_sphere(&triangles), triangles, bounds: boxes.bounds(), boxes }
    }
}

/// Every feather's triangles at its current pose, a sphere around them
/// and their obstacle boxes: as in the arrays, or as set `aside` for the
/// feathers that have an entry there.
#[derive(Clone, Copy)]
pub(super) struct PosedGeometry<'a> {
    pub(super) triangles: &'a [FeatherTriangles],
    pub(super) spheres: &'a [(Vec3, f32)],
    pub(super) boxes: &'a [ObstacleBoxes],
    pub(super) bounds: &'a [ObstacleBounds],
    pub(super) aside: Option<&'a Aside>,
}

impl<'a> PosedGeometry<'a> {
    /// The obstacle boxes of the feathers `ids` (one feather's obstacles).
    pub(super) fn boxes_of<'b>(&self, ids: &'b [u32]) -> BoxesOf<'b>
    where
        'a: 'b,
    {
        let aside = self.aside.map(Aside::set_aside_boxes);
        BoxesOf { ids: Some(ids), all: self.boxes, bounds: self.bounds, aside }
    }

    /// Feather `j`'s bounding sphere.
    #[inline]
    pub(super) fn sphere(&self, j: usize) -> (Vec3, f32) {
        self.aside.map_or(self.spheres[j], |a| a.sphere(j, self.spheres))
    }

    /// Feather `j`'s triangles.
    #[inline]
    pub(super) fn triangles_of(&self, j: usize) -> &'a FeatherTriangles {
        self.aside.map_or(&self.triangles[j], |a| a.triangles(j, self.triangles))
    }

    /// Feather `j`'s obstacle boxes.
    #[inline]
    pub(super) fn boxes_of_one(&self, j: usize) -> &'a ObstacleBoxes {
        self.aside.map_or(&self.boxes[j], |a| a.boxes(j, self.boxes))
    }
}

/// Levels with fewer feathers than this are visited on the calling thread.
const PARALLEL_LEVEL_MIN: usize = 4;

/// One level of the obstacle relation: its feathers, and the share of the
/// run done when it starts (what `keep_going` is told inside it).
pub(super) struct Level<'a> {
    pub(super) items: &'a [u32],
    pub(super) done: f32,
}

/// Adjusts the feathers of one level, in parallel chunks when it is large
/// enough; each chunk has its own worker scratch. Results land in
/// `outcomes` by position.
pub(super) fn run_level(
    inputs: &Inputs<'_>,
    Level { items, done }: Level<'_>,
    poses: &[FeatherPose],
    posed: PosedGeometry<'_>,
    marks: Marks<'_>,
    outcomes: &mut [Visit],
    workers: &mut [Worker],
) {
    // Waking another thread costs about as much as checking a feather, and
    // most levels hold one or two: those run on this thread. Which worker
    // visits a feather never changes what it finds. Once `keep_going` says
    // stop, the rest are left unvisited (the caller then abandons the run).
    let visit = |items: &[u32], outcomes: &mut [Visit], worker: &mut Worker| {
        for (k, (&i, out)) in items.iter().zip(outcomes.iter_mut()).enumerate() {
            if k % 16 == 15 && !(inputs.keep_going)(done) {
                break;
            }
            *out = adjust_one(inputs, i as usize, poses, posed, marks, worker);
        }
    };
    if items.len() < PARALLEL_LEVEL_MIN || workers.len() == 1 {
        visit(items, outcomes, &mut workers[0]);
        return;
    }
    let chunk = items.len().div_ceil(workers.len()).max(1);
    items
        .par_chunks(chunk)
        .zip(outcomes.par_chunks_mut(chunk))
        .zip(workers.par_iter_mut())
        .for_each(|((items, outcomes), worker)| visit(items, outcomes, worker));
}

/// Adjusts feather `i` against its earlier candidates, unless propagation
/// does not reach it or, verifying, its pose passes the exact check.
/// Candidates that cannot matter to it at any size and pose (see
/// [`ObstacleReach`]) are not passed on.
pub(super) fn adjust_one(
    inputs: &Inputs<'_>,
    i: usize,
    poses: &[FeatherPose],
    posed: PosedGeometry<'_>,
    marks: Marks<'_>,
    worker: &mut Worker,
) -> Visit {
    let ri = inputs.rank[i];
    let earlier = inputs.candidates.row(i).iter().map(|&j| j as usize).filter(|&j| inputs.rank[j] < ri);
    let reach = ObstacleReach::new(&inputs.frames[i], &inputs.shapes[i], inputs.params);
    let mut verify = false;
    if let Some(seeds) = inputs.selection.seeds()
        && !seeds[i]
        && !earlier.clone().any(|j| marks.moved[j])
    {
        let Selection::Verify { suspects, .. } = inputs.selection else { return Visit::Skipped };
        // A changed obstacle that cannot matter to i at any size and pose
        // is left out of its checks anyway.
        let matters = |j: usize| {
            let (centre, radius) = posed.sphere(j);
            reach.may_matter(centre, radius, inputs.shapes[j].thickness).is_some()
        };
        if !suspects[i] && !earlier.clone().any(|j| marks.changed[j] && matters(j)) {
            return Visit::Skipped;
        }
        verify = true;
    }
    // A check made ahead stands when no obstacle changed since.
    let ahead = marks.prechecked.get(i).map_or(Precheck::None, Precheck::load);
    let stands = ahead != Precheck::None && !earlier.clone().any(|j| marks.changed[j]);
    if verify && stands && ahead == Precheck::Clear {
        return Visit::Verified;
    }
    // The ids first: a check needs only them (and the prepared boxes);
    // the triangles are copied out only for a feather that is adjusted.
    collect_obstacle_ids(inputs, i, posed, worker);
    // A bent feather of an incremental verifying run is kept where it lies,
    // lowered, or repaired: solved afresh only when repair fails.
    let local = kept_locally(inputs, i, poses[i]);
    // Lowered first: a clear step down stands whatever the pose it left.
    if local
        && !verify
        && let Some(step) = lowered(inputs, i, poses[i], posed, worker)
    {
        return step;
    }
    let clear_where_it_lies = |worker: &mut Worker| match ahead {
        Precheck::Blocked if stands => false,
        // Clear ahead, with the same pose and body: only the obstacles
        // changed since can have made it fail.
        Precheck::Clear => changed_obstacles_clear(inputs, i, poses, posed, marks, worker),
        _ => check_clear(inputs, i, poses, posed, worker),
    };
    if (verify || local) && clear_where_it_lies(worker) {
        if verify {
            return Visit::Verified;
        }
        // Resting: kept, its surroundings recorded afresh.
        let outcome = kept(poses[i], DrapeRoute::Lowered);
        return Visit::Adjusted(outcome, poses[i]);
    }
    if (verify || local)
        && let Some(pose) = repaired(inputs, i, poses[i], posed, worker)
    {
        let outcome = kept(pose, DrapeRoute::Repaired);
        return Visit::Adjusted(outcome, pose);
    }
    worker.obstacles.clear();
    worker.obstacles.extend(worker.obstacle_ids.iter().map(|&j| {
        let j = j as usize;
        let (centre, radius) = posed.sphere(j);
        let in_column = reach.may_matter(centre, radius, inputs.shapes[j].thickness) == Some(true);
        ObstacleFeather {
            triangles: *posed.triangles_of(j),
            thickness: inputs.shapes[j].thickness,
            // Out of the column, rasterising would find nothing.
            far_side: !in_column || inputs.frames[j].normal.dot(inputs.frames[i].normal) < FAR_SIDE_NORMAL_DOT,
        }
    }));
    let boxes = posed.boxes_of(&worker.obstacle_ids);
    let at = FeatherInPlace { frame: &inputs.frames[i], shape: &inputs.shapes[i], obstacles: boxes, body: inputs.body };
    let solved = adjust_feather_boxed(&at, poses[i], &worker.obstacles, inputs.params, inputs.steps, &mut worker.field);
    if inputs.settle_rate <= 0.0 || solved.pose == poses[i] {
        return Visit::Adjusted(solved, solved.pose);
    }
    let feather = SettlingFeather {
        frame: &inputs.frames[i],
        shape: &inputs.shapes[i],
        params: inputs.params,
        body: inputs.body,
        rate: inputs.settle_rate,
    };
    let pose = settled_pose(feather, poses[i], solved.pose, boxes, &mut worker.field);
    Visit::Adjusted(AdjustOutcome { pose, ..solved }, solved.pose)
}

/// Whether feather `i`, to be adjusted in an incremental verifying run
/// (a seed, or on an obstacle that sank), is kept where it lies rather
/// than solved afresh: a full-size bent feather. A shortened one is solved
/// (it may regrow), and so is every kite.
pub(super) fn kept_locally(inputs: &Inputs<'_>, i: usize, pose: FeatherPose) -> bool {
    matches!(inputs.selection, Selection::Verify { .. })
        && !inputs.pairs_only
        && inputs.settle_rate > 0.0
        && inputs.shapes[i].segment_count() > 1
        && pose.scale >= 1.0
}

/// The outcome of a feather kept in place at `pose` by `route` (no
/// obstacle rasterised, no limit bound).
fn kept(pose: FeatherPose, route: DrapeRoute) -> AdjustOutcome {
    AdjustOutcome { pose, collision_tests: 0, clamped: false, drape: route }
}

/// The share of the settle rate a lowering's pitch step must reach to go
/// on: a feather that came down by a whole step of pitch lowers again
/// next frame and brings what lies on it to try a step down in this one;
/// after a half step or a bend it rests. Going on after every step lowers
/// the animated coat a little further but visits several times as many
/// feathers a frame (BENCHMARKS.md, "Issue #30, session 15").
const WHOLE_STEP: f32 = 0.99;

/// A bent feather whose surroundings drifted, or whose obstacle sank,
/// lowered one step (see [`lowered_pose`]); `None` when no step is clear.
fn lowered(
    inputs: &Inputs<'_>,
    i: usize,
    pose: FeatherPose,
    posed: PosedGeometry<'_>,
    worker: &mut Worker,
) -> Option<Visit> {
    let boxes = posed.boxes_of(&worker.obstacle_ids);
    let (frame, shape, params) = (&inputs.frames[i], &inputs.shapes[i], inputs.params);
    let feather = SettlingFeather { frame, shape, params, body: inputs.body, rate: inputs.settle_rate };
    let step = lowered_pose(feather, pose, boxes, &mut worker.field)?;
    let outcome = kept(step, DrapeRoute::Lowered);
    // A whole step of pitch settles on, and pulls in what lies on it (its
    // solved pose is its lowest); a smaller step ends the lowering.
    let whole = pose.pitch - step.pitch >= WHOLE_STEP * inputs.settle_rate;
    Some(Visit::Adjusted(outcome, if whole { lowest_pose(shape, params, step) } else { step }))
}

/// The largest change of any angle (radians, about 1.7°) a repair in
/// place may make ([`repaired`]); a feather that must move more is solved
/// afresh and settles toward that pose. Larger repairs lift a joint and
/// every one before it together, standing feathers up (more bristles and
/// pops on the Flamingo); smaller ones leave more to the drape, which
/// costs more (BENCHMARKS.md, "Issue #30, session 15").
pub(super) const REPAIR_MOST: f32 = 0.03;

/// A bent feather that failed its check where it lies, repaired there
/// (incremental runs): its joints lifted as little as clears them (see
/// [`repair_drape`]), within the pitch limit and by at most
/// [`REPAIR_MOST`]. A repair changes the pose far less than a drape solved
/// afresh and costs a few segment checks instead of a sweep; `None` (a
/// kite, a run that solves at once, or no small repair clears) leaves the
/// feather to be adjusted.
fn repaired(
    inputs: &Inputs<'_>,
    i: usize,
    pose: FeatherPose,
    posed: PosedGeometry<'_>,
    worker: &mut Worker,
) -> Option<FeatherPose> {
    if inputs.settle_rate <= 0.0 || inputs.shapes[i].segment_count() < 2 {
        return None;
    }
    let boxes = posed.boxes_of(&worker.obstacle_ids);
    let at = FeatherInPlace { frame: &inputs.frames[i], shape: &inputs.shapes[i], obstacles: boxes, body: inputs.body };
    repair_drape(&at, pose, REPAIR_MOST, inputs.params, &mut worker.field)
        .filter(|p| p.pitch <= inputs.params.max_pitch && pose_change(&pose, p) <= REPAIR_MOST)
}

/// Fills `worker.obstacle_ids` with feather `i`'s earlier candidates that
/// may matter to it at some size and pose (see [`ObstacleReach`]).
pub(super) fn collect_obstacle_ids(inputs: &Inputs<'_>, i: usize, posed: PosedGeometry<'_>, worker: &mut Worker) {
    let ri = inputs.rank[i];
    let reach = ObstacleReach::new(&inputs.frames[i], &inputs.shapes[i], inputs.params);
    worker.obstacle_ids.clear();
    worker.obstacle_ids.extend(
        inputs
            .candidates
            .row(i)
            .iter()
            .map(|&j| j as usize)
            .filter(|&j| inputs.rank[j] < ri)
            .filter(|&j| {
                let (centre, radius) = posed.sphere(j);
                reach.may_matter(centre, radius, inputs.shapes[j].thickness).is_some()
            })
            .map(|j| j as u32),
    );
}

/// Whether feather `i` at its current pose is clear of those of its
/// obstacles (`worker.obstacle_ids`) that changed pose earlier in the run:
/// the part of [`check_clear`] that can answer differently from a check
/// made ahead of the run that passed.
fn changed_obstacles_clear(
    inputs: &Inputs<'_>,
    i: usize,
    poses: &[FeatherPose],
    posed: PosedGeometry<'_>,
    marks: Marks<'_>,
    worker: &mut Worker,
) -> bool {
    let Worker { obstacle_ids, changed_ids, .. } = worker;
    changed_ids.clear();
    changed_ids.extend(obstacle_ids.iter().copied().filter(|&j| marks.changed[j as usize]));
    if inputs.pairs_only {
        return meets_no_pair(inputs, i, poses[i], posed, changed_ids);
    }
    let (frame, shape) = (&inputs.frames[i], &inputs.shapes[i]);
    posed_meets_none_boxed(frame, shape, (poses[i], posed.boxes_of_one(i)), posed.boxes_of(changed_ids))
}

/// Whether feather `i` at `pose` meets none of the feathers `ids` (the
/// pair tests alone, of a run that tests the pairs only).
fn meets_no_pair(inputs: &Inputs<'_>, i: usize, pose: FeatherPose, posed: PosedGeometry<'_>, ids: &[u32]) -> bool {
    let mine = FeatherBoxes::new(&feather_triangles(&inputs.frames[i], &inputs.shapes[i], pose));
    !ids.iter().any(|&j| mine.intersects(posed.triangles_of(j as usize)))
}

/// The exact check of feather `i` at its current pose against the
/// obstacles in `worker.obstacle_ids` (and the body, unless the run tests
/// the pairs only).
pub(super) fn check_clear(
    inputs: &Inputs<'_>,
    i: usize,
    poses: &[FeatherPose],
    posed: PosedGeometry<'_>,
    worker: &mut Worker,
) -> bool {
    if inputs.pairs_only {
        return meets_no_pair(inputs, i, poses[i], posed, &worker.obstacle_ids);
    }
    let (frame, shape) = (&inputs.frames[i], &inputs.shapes[i]);
    let boxes = posed.boxes_of(&worker.obstacle_ids);
    posed_is_clear_boxed(frame, shape, (poses[i], posed.boxes_of_one(i)), boxes, inputs.body, &mut worker.field)
}

crate::memory::heap_size_of_fields!(Worker { field, obstacles, obstacle_ids, changed_ids });
impl crate::memory::HeapSize for Vec<Worker> {
    fn heap_bytes(&self) -> usize {
        crate::memory::nested_heap_bytes(self)
    }
}
