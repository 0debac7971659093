//! Adjusting many feathers in order, in parallel by levels.
//!
//! The obstacles of feather i are its candidates (roots within reach) that
//! come earlier in the adjustment order. Give every feather to be adjusted a
//! level: 1 + the highest level among its obstacles that are adjusted too
//! (feathers kept fixed count as level 0). A feather reads only obstacles of
//! lower levels, which are final by the time its level runs, and never a
//! feather of its own level, so running each level in parallel gives
//! exactly the serial result, whatever the thread count. Effects are applied
//! after each level, in a fixed order.

use super::checks::{BoxesOf, ObstacleBoxes, ObstacleReach, bounding_sphere, pose_is_clear_boxed};
use super::drape::repair_drape;
use super::steps::adjust_feather_boxed;
use super::{AdjustOutcome, AdjustParams, AdjustSteps, HeightField, ObstacleFeather};
use crate::body::BodyIndex;
use crate::feather::toward;
use crate::feather::{FeatherPose, FeatherShape, FeatherTriangles, feather_triangles, tip_position};
use crate::geometry::RootFrame;
use crate::validation::FeatherBoxes;
use glam::Vec3;
use rayon::prelude::*;
use std::time::Instant;

/// Work chunks per worker thread in one level (load balance vs. overhead).
const CHUNKS_PER_THREAD: usize = 4;
/// Obstacles whose root normal is more than 120° from the adjusted
/// feather's grow from the far side of a thin part (see
/// [`ObstacleFeather::far_side`]).
const FAR_SIDE_NORMAL_DOT: f32 = -0.5;

/// Candidate lists in compressed rows: the candidates of root `i` are
/// `indices[offsets[i]..offsets[i + 1]]` (roots within reach, any order).
#[derive(Clone, Copy, Debug)]
pub struct CandidateLists<'a> {
    /// Row starts, one more than the number of roots.
    pub offsets: &'a [u32],
    /// Concatenated candidate indices.
    pub indices: &'a [u32],
}

impl<'a> CandidateLists<'a> {
    /// Wraps CSR arrays.
    pub fn new(offsets: &'a [u32], indices: &'a [u32]) -> Self {
        Self { offsets, indices }
    }

    /// The candidates of root `i`.
    #[inline]
    pub fn of(&self, i: usize) -> &'a [u32] {
        &self.indices[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// Number of roots described.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Whether no root is described.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

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
    fn seeds(&self) -> Option<&[bool]> {
        match *self {
            Self::Propagate { seeds, .. } | Self::Verify { seeds, .. } => Some(seeds),
            Self::All | Self::Subset(_) => None,
        }
    }

    /// θs of the propagating selections.
    fn threshold(&self) -> Option<f32> {
        match *self {
            Self::Propagate { threshold, .. } | Self::Verify { threshold, .. } => Some(threshold),
            Self::All | Self::Subset(_) => None,
        }
    }
}

/// Figures of one ordered adjustment.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdjustStats {
    /// Feathers adjusted.
    pub adjusted: usize,
    /// Obstacle feathers rasterised, summed over adjusted feathers.
    pub collision_tests: u64,
    /// Adjusted feathers where a pitch or roll limit bound.
    pub clamped: usize,
    /// Feathers checked exactly and left as they were
    /// ([`Selection::Verify`]).
    pub verified: usize,
    /// Levels run (the length of the longest obstacle chain).
    pub levels: usize,
    /// Wall-clock time of the call.
    pub seconds: f64,
}

impl AdjustStats {
    /// Mean collision detections per adjusted feather (0 when none).
    pub fn collision_tests_per_feather(&self) -> f64 {
        if self.adjusted == 0 { 0.0 } else { self.collision_tests as f64 / self.adjusted as f64 }
    }
}

/// Scratch of one work chunk.
#[derive(Clone, Debug)]
struct Worker {
    field: HeightField,
    obstacles: Vec<ObstacleFeather>,
    /// The feather index of each obstacle.
    obstacle_ids: Vec<u32>,
}

/// Reusable state of ordered adjustments: level lists, feather triangles
/// and per-worker scratch. Keep one per system; after the first frames
/// nothing it holds grows unless the feather count or thread count does.
#[derive(Clone, Debug, Default)]
pub struct Adjuster {
    triangles: Vec<FeatherTriangles>,
    /// A bounding sphere of each feather's triangles (centre, radius).
    spheres: Vec<(Vec3, f32)>,
    /// Each feather's triangles and raised top with their boxes, as the
    /// exact checks of the feathers it is an obstacle of meet them.
    boxes: Vec<ObstacleBoxes>,
    in_scope: Vec<bool>,
    level: Vec<u32>,
    moved: Vec<bool>,
    changed: Vec<bool>,
    adjusted: Vec<bool>,
    verified: Vec<bool>,
    level_start: Vec<u32>,
    level_items: Vec<u32>,
    cursor: Vec<u32>,
    outcomes: Vec<Visit>,
    workers: Vec<Worker>,
    /// The settle rate of the next run only (see [`Adjuster::settle_next_run`]).
    settle_rate: f32,
    /// Which feathers the last run held back from their solved pose.
    settling: Vec<bool>,
    /// Verifying by levels on several threads: the suspects checked ahead
    /// of the ordered pass, in parallel, against their obstacles as they
    /// were before it ([`Precheck`]), by feather.
    prechecked: Vec<Precheck>,
    /// The feathers checked ahead, in order.
    precheck_items: Vec<u32>,
    precheck_outcomes: Vec<Precheck>,
}

/// The answer of an exact check made ahead of the ordered pass. It stands
/// for the check the ordered pass would make as long as no obstacle of the
/// feather changed pose before its turn (the check reads only the
/// feather's own pose, its obstacles' poses and the body).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum Precheck {
    /// Not checked ahead.
    #[default]
    None,
    /// The pose was clear.
    Clear,
    /// The pose met an obstacle or the body.
    Blocked,
}

impl Adjuster {
    /// Empty state; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// Which feathers the last call adjusted.
    pub fn adjusted(&self) -> &[bool] {
        &self.adjusted
    }

    /// Which feathers the last call checked exactly and left as they were
    /// ([`Selection::Verify`]).
    pub fn verified(&self) -> &[bool] {
        &self.verified
    }

    /// The next run (only) moves each adjusted feather from its current
    /// pose toward its solved pose by at most `rate` radians in pitch, roll
    /// and each bend, when that pose passes the exact checks; otherwise it
    /// lifts it from there by the smallest of a few pitch steps that
    /// passes, else takes the solved pose (see
    /// [`crate::animation::coherence`]). 0 takes the solved pose.
    pub fn settle_next_run(&mut self, rate: f32) {
        self.settle_rate = rate;
    }

    /// Which feathers the last run held back from their solved pose (they
    /// settle further in later frames).
    pub fn settling(&self) -> &[bool] {
        &self.settling
    }

    /// Replaces what [`adjusted`](Self::adjusted) reports, e.g. with the
    /// flags saved with a frame that is being resumed.
    pub fn set_adjusted(&mut self, flags: &[bool]) {
        self.adjusted.clear();
        self.adjusted.extend_from_slice(flags);
    }

    /// Room in every worker for `longest` obstacles, so that a later call
    /// with rows up to that long allocates nothing (a frame whose second
    /// pass uses longer rows than the first may come late).
    pub fn reserve_obstacles(&mut self, longest: usize) {
        self.workers.iter_mut().for_each(|w| {
            w.obstacles.reserve(longest.saturating_sub(w.obstacles.len()));
            w.obstacle_ids.reserve(longest.saturating_sub(w.obstacle_ids.len()));
        });
    }

    /// Every feather's two triangles at the poses left by the last call.
    pub fn triangles(&self) -> &[FeatherTriangles] {
        &self.triangles
    }

    /// Adjusts the selected feathers in `order` (`order[k]` is the k-th
    /// feather; `rank` is its inverse). Feather i's obstacles are its
    /// `candidates` with a smaller rank, at their current poses (adjusted
    /// ones at their new poses). `poses` holds the current poses and
    /// receives the new ones. Runs on the current rayon pool; the result is
    /// bitwise the same for any thread count.
    ///
    /// Panics if the slices disagree in length.
    #[allow(clippy::too_many_arguments)]
    #[allow(clippy::too_many_arguments)]
    pub fn adjust_in_order(
        &mut self,
        frames: &[RootFrame],
        shapes: &[FeatherShape],
        poses: &mut [FeatherPose],
        order: &[u32],
        rank: &[u32],
        candidates: CandidateLists<'_>,
        body: &BodyIndex,
        params: &AdjustParams,
        steps: AdjustSteps,
        selection: Selection<'_>,
    ) -> AdjustStats {
        let all = self.adjust_in_order_until(
            frames,
            shapes,
            poses,
            order,
            rank,
            candidates,
            body,
            params,
            steps,
            selection,
            &|_| true,
        );
        all.unwrap_or_default()
    }

    /// As [`Adjuster::adjust_in_order`], asking `keep_going(fraction done)`
    /// before each level; `None` when it says stop (then `poses` holds a
    /// mix of old and new poses and the caller must restore them).
    #[allow(clippy::too_many_arguments)]
    pub fn adjust_in_order_until(
        &mut self,
        frames: &[RootFrame],
        shapes: &[FeatherShape],
        poses: &mut [FeatherPose],
        order: &[u32],
        rank: &[u32],
        candidates: CandidateLists<'_>,
        body: &BodyIndex,
        params: &AdjustParams,
        steps: AdjustSteps,
        selection: Selection<'_>,
        keep_going: &dyn Fn(f32) -> bool,
    ) -> Option<AdjustStats> {
        let lists = (frames, shapes, order, rank, candidates);
        self.ordered_run(lists, poses, body, params, steps, selection, keep_going, (false, false))
    }

    /// As [`Adjuster::adjust_in_order_until`], one feather after the other
    /// in `order` on the calling thread, visiting only the feathers
    /// selected and those an adjusted feather listed as a candidate changed
    /// under. For a few seeds over long candidate rows, where the levels of
    /// everything downstream would cost more than the adjustments. The
    /// candidate relation must be symmetric (`j` in row `i` exactly when `i`
    /// is in row `j`, as with the full obstacle candidates). Meant for a
    /// second pass over a frame whose first pass has checked the feathers
    /// against the body: verifying, it tests only the pairs (the body has
    /// not moved since, and a feather whose pose changes is adjusted with
    /// every check). Apart from that the result is the same as with
    /// levels, bitwise: a feather reads only earlier ones, final either
    /// way, and one that no earlier adjusted feather changed under is left
    /// alone by both.
    #[allow(clippy::too_many_arguments)]
    pub fn adjust_sparse_until(
        &mut self,
        frames: &[RootFrame],
        shapes: &[FeatherShape],
        poses: &mut [FeatherPose],
        order: &[u32],
        rank: &[u32],
        candidates: CandidateLists<'_>,
        body: &BodyIndex,
        params: &AdjustParams,
        steps: AdjustSteps,
        selection: Selection<'_>,
        keep_going: &dyn Fn(f32) -> bool,
    ) -> Option<AdjustStats> {
        let lists = (frames, shapes, order, rank, candidates);
        self.ordered_run(lists, poses, body, params, steps, selection, keep_going, (true, true))
    }

    /// Both ways of [`Adjuster::adjust_in_order_until`]: by levels, or
    /// `sparse`, verifying with every check or the pairs only (see
    /// [`Adjuster::adjust_sparse_until`]).
    #[allow(clippy::too_many_arguments, clippy::type_complexity)]
    fn ordered_run(
        &mut self,
        (frames, shapes, order, rank, candidates): (&[RootFrame], &[FeatherShape], &[u32], &[u32], CandidateLists<'_>),
        poses: &mut [FeatherPose],
        body: &BodyIndex,
        params: &AdjustParams,
        steps: AdjustSteps,
        selection: Selection<'_>,
        keep_going: &dyn Fn(f32) -> bool,
        (sparse, pairs_only): (bool, bool),
    ) -> Option<AdjustStats> {
        let start = Instant::now();
        let settle_rate = std::mem::take(&mut self.settle_rate);
        let n = frames.len();
        assert!(
            shapes.len() == n && poses.len() == n && order.len() == n && rank.len() == n && candidates.len() == n,
            "adjust_in_order: frames, shapes, poses, order, rank and candidate rows must all have one entry per feather"
        );
        match selection {
            Selection::Subset(s) | Selection::Propagate { seeds: s, .. } => {
                assert_eq!(s.len(), n, "adjust_in_order: the selection needs one flag per feather")
            }
            Selection::Verify { seeds, suspects, .. } => assert!(
                seeds.len() == n && suspects.len() == n,
                "adjust_in_order: the selection needs one flag per feather"
            ),
            Selection::All => {}
        }
        self.posed_triangles(frames, shapes, poses);
        let levels = if sparse {
            self.mark_selected(n, selection);
            0
        } else {
            self.mark_scope(order, rank, candidates, selection);
            self.assign_levels(order, rank, candidates)
        };
        self.prepare_workers(params);
        // Room for the longest row up front: which rows a worker meets
        // varies from frame to frame, and its buffer must not creep up.
        let longest = (0..n).map(|i| candidates.of(i).len()).max().unwrap_or(0);
        self.reserve_obstacles(longest);
        // Body queries list each triangle at most once; a rare wide query
        // (a skin search widening far from the feather) must not grow them.
        let triangles = body.triangle_count();
        self.workers
            .iter_mut()
            .for_each(|w| w.field.body_ids.reserve(triangles.saturating_sub(w.field.body_ids.len())));
        self.moved.clear();
        self.moved.resize(n, false);
        self.changed.clear();
        self.changed.resize(n, false);
        self.adjusted.clear();
        self.adjusted.resize(n, false);
        self.verified.clear();
        self.verified.resize(n, false);
        self.settling.clear();
        self.settling.resize(n, false);

        let mut stats = AdjustStats { levels, ..AdjustStats::default() };
        let inputs =
            Inputs { frames, shapes, rank, candidates, body, params, steps, selection, pairs_only, settle_rate };
        self.prechecked.clear();
        self.prechecked.resize(n, Precheck::None);
        if !sparse && rayon::current_num_threads() > 1 {
            self.precheck(&inputs, order, poses);
        }
        if sparse {
            for (k, &i) in order.iter().enumerate() {
                if k % 256 == 0 && !keep_going(k as f32 / n.max(1) as f32) {
                    return None;
                }
                let i = i as usize;
                if !self.in_scope[i] {
                    continue;
                }
                let marks = Marks { moved: &self.moved, changed: &self.changed, prechecked: &self.prechecked };
                let posed = Posed { triangles: &self.triangles, spheres: &self.spheres, boxes: &self.boxes };
                let visit = adjust_one(&inputs, i, poses, posed, marks, &mut self.workers[0]);
                self.apply(i, &visit, &inputs, poses, &mut stats);
                if self.changed[i] {
                    // What lies on it may now meet it or stand on nothing.
                    for &j in candidates.of(i) {
                        if rank[j as usize] > rank[i] {
                            self.in_scope[j as usize] = true;
                        }
                    }
                }
            }
            stats.levels = usize::from(stats.adjusted + stats.verified > 0);
            stats.seconds = start.elapsed().as_secs_f64();
            return Some(stats);
        }
        for l in 0..levels {
            if !keep_going(l as f32 / levels.max(1) as f32) {
                return None;
            }
            let items = &self.level_items[self.level_start[l] as usize..self.level_start[l + 1] as usize];
            let outcomes = &mut self.outcomes[..items.len()];
            let marks = Marks { moved: &self.moved, changed: &self.changed, prechecked: &self.prechecked };
            let posed = Posed { triangles: &self.triangles, spheres: &self.spheres, boxes: &self.boxes };
            run_level(&inputs, items, poses, posed, marks, outcomes, &mut self.workers);
            let (start, end) = (self.level_start[l] as usize, self.level_start[l + 1] as usize);
            for k in 0..end - start {
                let (i, outcome) = (self.level_items[start + k] as usize, self.outcomes[k]);
                self.apply(i, &outcome, &inputs, poses, &mut stats);
            }
        }
        stats.seconds = start.elapsed().as_secs_f64();
        Some(stats)
    }

    /// Verifying: checks every suspect that is not a seed (those the
    /// ordered pass will most likely only check) ahead, in parallel chunks,
    /// against the poses before the pass. Most checked feathers have no
    /// obstacle that the pass changes before their turn, and their level
    /// then takes this answer instead of checking again; it is the answer
    /// the check would give there (same pose, same obstacles, same body),
    /// so the result does not change, at any thread count. This spreads
    /// the checks over the threads whatever the levels are: the obstacle
    /// relation runs through thousands of levels of a few feathers.
    fn precheck(&mut self, inputs: &Inputs<'_>, order: &[u32], poses: &[FeatherPose]) {
        let Selection::Verify { seeds, suspects, .. } = inputs.selection else { return };
        // Sized for every feather up front: how many are checked ahead
        // varies from frame to frame, and the heap must not creep up.
        let n = order.len();
        self.precheck_items.clear();
        self.precheck_items.reserve(n);
        self.precheck_outcomes.reserve(n.saturating_sub(self.precheck_outcomes.len()));
        self.precheck_items.extend(order.iter().copied().filter(|&i| {
            let i = i as usize;
            self.in_scope[i] && suspects[i] && !seeds[i]
        }));
        let items = &self.precheck_items;
        self.precheck_outcomes.clear();
        self.precheck_outcomes.resize(items.len(), Precheck::None);
        let posed = Posed { triangles: &self.triangles, spheres: &self.spheres, boxes: &self.boxes };
        let chunk = items.len().div_ceil(self.workers.len()).max(1);
        items
            .par_chunks(chunk)
            .zip(self.precheck_outcomes.par_chunks_mut(chunk))
            .zip(self.workers.par_iter_mut())
            .for_each(|((items, outcomes), worker)| {
                for (&i, out) in items.iter().zip(outcomes.iter_mut()) {
                    let i = i as usize;
                    collect_obstacle_ids(inputs, i, posed, worker);
                    *out =
                        if check_clear(inputs, i, poses, posed, worker) { Precheck::Clear } else { Precheck::Blocked };
                }
            });
        for (&i, &outcome) in items.iter().zip(&self.precheck_outcomes) {
            self.prechecked[i as usize] = outcome;
        }
    }

    /// Records what became of feather `i`; an adjusted feather takes its
    /// new pose (and triangles) and is marked moved past the threshold or
    /// changed at all.
    fn apply(
        &mut self,
        i: usize,
        visit: &Visit,
        inputs: &Inputs<'_>,
        poses: &mut [FeatherPose],
        stats: &mut AdjustStats,
    ) {
        let (frames, shapes, selection) = (inputs.frames, inputs.shapes, inputs.selection);
        let (o, solved) = match visit {
            Visit::Adjusted(o, solved) => (o, solved),
            Visit::Verified => {
                self.verified[i] = true;
                stats.verified += 1;
                return;
            }
            Visit::Skipped => return,
        };
        let old = poses[i];
        if let Some(threshold) = selection.threshold() {
            // Judged by the solved pose: a feather held back while it
            // settles pulls in what lies on it as long as it is still to
            // sink that far, so they settle along with it.
            let rolled = (solved.roll - old.roll).abs() > threshold;
            self.moved[i] = rolled
                || if matches!(selection, Selection::Verify { .. }) {
                    // A feather that rose or grew is checked against
                    // by what lies on it; only one that sank or
                    // shrank can leave them standing on nothing.
                    old.pitch - solved.pitch > threshold || old.scale - solved.scale > threshold
                } else {
                    (solved.pitch - old.pitch).abs() > threshold
                };
        }
        self.settling[i] = o.pose != *solved && tip_above(&frames[i], &shapes[i], o.pose, *solved);
        self.changed[i] = o.pose != old;
        poses[i] = o.pose;
        self.triangles[i] = feather_triangles(&frames[i], &shapes[i], o.pose);
        self.spheres[i] = bounding_sphere(&self.triangles[i]);
        self.boxes[i] = ObstacleBoxes::new(&self.triangles[i], shapes[i].thickness);
        self.adjusted[i] = true;
        stats.adjusted += 1;
        stats.collision_tests += u64::from(o.collision_tests);
        stats.clamped += usize::from(o.clamped);
    }

    /// The scope of a sparse run to begin with: the selected feathers.
    fn mark_selected(&mut self, n: usize, selection: Selection<'_>) {
        self.in_scope.clear();
        match selection {
            Selection::All => self.in_scope.resize(n, true),
            Selection::Subset(s) | Selection::Propagate { seeds: s, .. } => self.in_scope.extend_from_slice(s),
            Selection::Verify { seeds, suspects, .. } => {
                self.in_scope.extend(seeds.iter().zip(suspects).map(|(&s, &v)| s | v))
            }
        }
    }

    /// Every feather's triangles at its current pose, and their spheres.
    fn posed_triangles(&mut self, frames: &[RootFrame], shapes: &[FeatherShape], poses: &[FeatherPose]) {
        self.triangles.resize(frames.len(), FeatherTriangles::kite([[Vec3::ZERO; 3]; 2]));
        self.spheres.resize(frames.len(), (Vec3::ZERO, 0.0));
        let unset = ObstacleBoxes::new(&[[Vec3::ZERO; 3]; 2], 0.0);
        self.boxes.resize(frames.len(), unset);
        self.triangles
            .par_iter_mut()
            .zip(self.spheres.par_iter_mut().zip(self.boxes.par_iter_mut()))
            .zip(frames.par_iter().zip(shapes.par_iter().zip(poses.par_iter())))
            .for_each(|((t, (sphere, boxes)), (f, (s, p)))| {
                *t = feather_triangles(f, s, *p);
                *sphere = bounding_sphere(t);
                *boxes = ObstacleBoxes::new(t, s.thickness);
            });
    }

    /// Marks the feathers that may be adjusted. With propagation that is
    /// the seeds (and suspects) and everything downstream of them in the
    /// obstacle relation.
    fn mark_scope(&mut self, order: &[u32], rank: &[u32], candidates: CandidateLists<'_>, selection: Selection<'_>) {
        let n = order.len();
        self.in_scope.clear();
        match selection {
            Selection::All => self.in_scope.resize(n, true),
            Selection::Subset(s) => self.in_scope.extend_from_slice(s),
            Selection::Propagate { seeds, .. } | Selection::Verify { seeds, .. } => {
                self.in_scope.extend_from_slice(seeds);
                if let Selection::Verify { suspects, .. } = selection {
                    self.in_scope.iter_mut().zip(suspects).for_each(|(s, &v)| *s |= v);
                }
                for &i in order {
                    let i = i as usize;
                    if !self.in_scope[i] {
                        let ri = rank[i];
                        self.in_scope[i] =
                            candidates.of(i).iter().any(|&j| rank[j as usize] < ri && self.in_scope[j as usize]);
                    }
                }
            }
        }
    }

    /// Levels of the feathers in scope and the per-level lists (each in
    /// order). Returns the number of levels.
    fn assign_levels(&mut self, order: &[u32], rank: &[u32], candidates: CandidateLists<'_>) -> usize {
        let n = order.len();
        self.level.clear();
        self.level.resize(n, 0);
        let mut levels = 0u32;
        for &i in order {
            let i = i as usize;
            if !self.in_scope[i] {
                continue;
            }
            let ri = rank[i];
            let below = candidates
                .of(i)
                .iter()
                .filter(|&&j| rank[j as usize] < ri)
                .map(|&j| self.level[j as usize])
                .max()
                .unwrap_or(0);
            self.level[i] = below + 1;
            levels = levels.max(below + 1);
        }
        let levels = levels as usize;
        // Level lists sized for the worst case (one feather per level, or
        // all in one) from the start, so that sparse frames never grow them.
        self.level_start.clear();
        self.level_start.reserve(n + 1);
        self.cursor.reserve(n.saturating_sub(self.cursor.len()));
        self.outcomes.reserve(n.saturating_sub(self.outcomes.len()));
        self.level_start.resize(levels + 1, 0);
        for &i in order {
            let l = self.level[i as usize] as usize;
            if l > 0 {
                self.level_start[l] += 1;
            }
        }
        for l in 0..levels {
            self.level_start[l + 1] += self.level_start[l];
        }
        self.level_items.clear();
        self.level_items.resize(self.level_start[levels] as usize, 0);
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.level_start[..levels]);
        for &i in order {
            let l = self.level[i as usize] as usize;
            if l > 0 {
                self.level_items[self.cursor[l - 1] as usize] = i;
                self.cursor[l - 1] += 1;
            }
        }
        let widest = (0..levels).map(|l| (self.level_start[l + 1] - self.level_start[l]) as usize).max().unwrap_or(0);
        if self.outcomes.len() < widest {
            self.outcomes.resize(widest, Visit::Skipped);
        }
        levels
    }

    /// One scratch per possible work chunk of the current pool.
    fn prepare_workers(&mut self, params: &AdjustParams) {
        let wanted = rayon::current_num_threads().max(1) * CHUNKS_PER_THREAD;
        while self.workers.len() < wanted {
            self.workers.push(Worker {
                field: HeightField::new(params.height_field_u, params.height_field_v),
                obstacles: Vec::new(),
                obstacle_ids: Vec::new(),
            });
        }
    }
}

/// The read-only inputs of every feather of a level.
struct Inputs<'a> {
    frames: &'a [RootFrame],
    shapes: &'a [FeatherShape],
    rank: &'a [u32],
    candidates: CandidateLists<'a>,
    body: &'a BodyIndex,
    params: &'a AdjustParams,
    steps: AdjustSteps,
    selection: Selection<'a>,
    /// Verification tests the pairs only (see [`Adjuster::adjust_sparse_until`]).
    pairs_only: bool,
    /// See [`Adjuster::settle_next_run`]; 0 = the solved poses.
    settle_rate: f32,
}

/// What became of one feather of a level.
#[derive(Clone, Copy, Debug)]
enum Visit {
    /// Propagation did not reach it.
    Skipped,
    /// Its pose passed the exact check and stays.
    Verified,
    /// It was adjusted: the pose it takes, and the pose solved for it
    /// (the same unless it settles toward it, see
    /// [`Adjuster::settle_next_run`]).
    Adjusted(AdjustOutcome, FeatherPose),
}

/// What the levels run so far did to each feather: moved past θs, or
/// changed at all.
#[derive(Clone, Copy)]
struct Marks<'a> {
    moved: &'a [bool],
    changed: &'a [bool],
    /// Answers of the checks made ahead ([`Adjuster::precheck`]).
    prechecked: &'a [Precheck],
}

/// Every feather's triangles at its current pose and a sphere around them.
#[derive(Clone, Copy)]
struct Posed<'a> {
    triangles: &'a [FeatherTriangles],
    spheres: &'a [(Vec3, f32)],
    boxes: &'a [ObstacleBoxes],
}

/// Levels with fewer feathers than this are visited on the calling thread.
const PARALLEL_LEVEL_MIN: usize = 4;

/// Adjusts the feathers of one level, in parallel chunks when it is large
/// enough; each chunk has its own worker scratch. Results land in
/// `outcomes` by position.
fn run_level(
    inputs: &Inputs<'_>,
    items: &[u32],
    poses: &[FeatherPose],
    posed: Posed<'_>,
    marks: Marks<'_>,
    outcomes: &mut [Visit],
    workers: &mut [Worker],
) {
    // Waking another thread costs about as much as checking a feather, and
    // most levels hold one or two: those run on this thread. Which worker
    // visits a feather never changes what it finds.
    let visit = |items: &[u32], outcomes: &mut [Visit], worker: &mut Worker| {
        for (&i, out) in items.iter().zip(outcomes.iter_mut()) {
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
fn adjust_one(
    inputs: &Inputs<'_>,
    i: usize,
    poses: &[FeatherPose],
    posed: Posed<'_>,
    marks: Marks<'_>,
    worker: &mut Worker,
) -> Visit {
    let ri = inputs.rank[i];
    let earlier = inputs.candidates.of(i).iter().map(|&j| j as usize).filter(|&j| inputs.rank[j] < ri);
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
            let (centre, radius) = posed.spheres[j];
            reach.may_matter(centre, radius, inputs.shapes[j].thickness).is_some()
        };
        if !suspects[i] && !earlier.clone().any(|j| marks.changed[j] && matters(j)) {
            return Visit::Skipped;
        }
        verify = true;
    }
    // A check made ahead stands when no obstacle changed since.
    let ahead = marks.prechecked.get(i).copied().unwrap_or_default();
    let ahead = if verify && ahead != Precheck::None && !earlier.clone().any(|j| marks.changed[j]) {
        if ahead == Precheck::Clear {
            return Visit::Verified;
        }
        Some(false)
    } else {
        None
    };
    // The ids first: a check needs only them (and the prepared boxes);
    // the triangles are copied out only for a feather that is adjusted.
    collect_obstacle_ids(inputs, i, posed, worker);
    if verify && ahead.unwrap_or_else(|| check_clear(inputs, i, poses, posed, worker)) {
        return Visit::Verified;
    }
    worker.obstacles.clear();
    worker.obstacles.extend(worker.obstacle_ids.iter().map(|&j| {
        let j = j as usize;
        let (centre, radius) = posed.spheres[j];
        let in_column = reach.may_matter(centre, radius, inputs.shapes[j].thickness) == Some(true);
        ObstacleFeather {
            triangles: posed.triangles[j],
            thickness: inputs.shapes[j].thickness,
            // Out of the column, rasterising would find nothing.
            far_side: !in_column || inputs.frames[j].normal.dot(inputs.frames[i].normal) < FAR_SIDE_NORMAL_DOT,
        }
    }));
    let boxes = BoxesOf { ids: Some(&worker.obstacle_ids), all: posed.boxes };
    let solved = adjust_feather_boxed(
        &inputs.frames[i],
        &inputs.shapes[i],
        poses[i],
        &worker.obstacles,
        boxes,
        inputs.body,
        inputs.params,
        inputs.steps,
        &mut worker.field,
    );
    if inputs.settle_rate <= 0.0 || solved.pose == poses[i] {
        return Visit::Adjusted(solved, solved.pose);
    }
    let pose = settled_pose(inputs, i, poses[i], solved.pose, boxes, &mut worker.field);
    Visit::Adjusted(AdjustOutcome { pose, ..solved }, solved.pose)
}

/// A feather settles on toward its solved pose only while its tip stands
/// more than this (in lengths of the feather) above the solved pose's tip.
/// Settling to the very pose kept a bent coat busy: a drape solved afresh
/// lands elsewhere each frame (its bends jump while its tip stays near),
/// so two thirds of the built-in swim's bent feathers were re-solved every
/// frame without ever arriving. Measured (2000 feathers, seed 1, 60 frames,
/// `--validate every`), settling until the pose against until the tip is
/// within 0.02:
/// S = 4 built-in pops 0.136 -> 0.071 %, last-frame mean pitch 5.55 ->
/// 3.40° (rebuild 2.67°), tip median 0.201 -> 0.213 (rebuild 0.178); Fox
/// 0.207 -> 0.191 %, 12.95 -> 10.86° (10.23°), 0.240 -> 0.237 (0.222);
/// Flamingo 0.70 -> 0.72 %, 13.77 -> 8.96° (8.13°), 0.238 -> 0.228
/// (0.201); readjusted a frame (30 frames) built-in 949 -> 523, Flamingo
/// 1327 -> 1147; the kite (S = 1, 30 frames) built-in 258 -> 137, tip
/// 0.418 -> 0.412, Flamingo 750 -> 608, tip 0.465 -> 0.447.
const SETTLED_TIP_GAP: f32 = 0.02;

/// Whether the tip of `pose` stands more than [`SETTLED_TIP_GAP`] above the
/// tip of `solved`, over the root's tangent plane.
fn tip_above(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose, solved: FeatherPose) -> bool {
    let height = |p: FeatherPose| (tip_position(frame, shape, p) - frame.position).dot(frame.normal);
    height(pose) > height(solved) + SETTLED_TIP_GAP * shape.length * solved.scale
}

/// Lifts tried, in steps of [`SETTLE_LIFT_STEP`] times the settle rate,
/// when the pose moved toward the solved one by the settle rate is not
/// clear: up to `SETTLE_SMALL_LIFTS` steps before the faster moves toward
/// the solved pose, then up to `SETTLE_LIFTS` (3.6 times the rate above
/// it). Measured
/// (built-in swim, 2 000 feathers, 60 frames, settle rate 2°): 3 lifts
/// 0.21 % pops a frame, 8 lifts 0.17 % (both with the obstacles' tops
/// checked too, which the solver itself asks less often: without, 0.04 %).
const SETTLE_LIFTS: usize = 8;
/// See [`SETTLE_LIFTS`]: lifts that keep the change within 2.35 times the rate.
const SETTLE_SMALL_LIFTS: usize = 3;
/// A lift's step, as a multiple of the settle rate. The small lifts and
/// the faster moves stay a little below 2.5 times the rate (5° at the
/// default rate, the default pop threshold): at exactly 2.5 their changes
/// came out a rounding above 5° and counted as pops. Measured (2000
/// feathers, seed 1, 30 frames) at 0.45 and [1.75, 2.4] against 0.5 and
/// [1.75, 2.5]: pops a frame built-in 0.022 -> 0.013 % (S = 1), 0.20 ->
/// 0.078 % (S = 4); Fox 0.08 -> 0.08 %, 0.172 -> 0.121 %; Flamingo 0.537 ->
/// 0.534 %, 1.27 -> 1.105 %.
const SETTLE_LIFT_STEP: f32 = 0.45;
/// Faster moves toward the solved pose, as multiples of the settle rate,
/// tried after the small lifts: a bent feather whose joints must turn to
/// clear what lies beneath it (a pitch lift alone does not) reaches a clear
/// pose on the way there. Measured (tests/coherence.rs swim, 500 feathers,
/// 45 frames, S = 4): pops 408 without them, 232 with, 216 trying
/// `current` before them (then with 2.5 as the faster one; see
/// [`SETTLE_LIFT_STEP`]).
const SETTLE_FASTER: [f32; 2] = [1.75, 2.4];

/// The pose feather `i` takes on its way from `current` to `solved` (see
/// [`Adjuster::settle_next_run`]): `current` moved toward `solved` by the
/// settle rate, if clear (the exact checks of verification, against its
/// obstacles at their final poses and the body: the standard a feather
/// kept at its pose meets every frame); else, of the poses that change it
/// least, the first clear one: that pose lifted by a few steps of half the
/// rate, `current` itself (it tries again next frame), moved faster toward
/// `solved`, a bent feather's `current` repaired (its joints lifted as
/// little as clears them, see [`repair_drape`]), lifted further; else
/// `solved`, which the solver found clear. Without the repair a bent
/// feather whose nearby poses all failed took its freshly draped pose,
/// whose bends can differ by tens of degrees: measured (2000 feathers,
/// `S = 4`, seed 1, 30 frames, host defaults), pops a frame built-in 1.55
/// -> 0.20 %, Fox 0.5 -> 0.17 %, Flamingo 3.1 -> 1.27 %, for about 5 %
/// more step time on the Flamingo.
/// (Raising at once every angle that rises toward `solved`, tried before
/// the further lifts, took the S = 4 pops of that test from 216 to 499.)
fn settled_pose(
    inputs: &Inputs<'_>,
    i: usize,
    current: FeatherPose,
    solved: FeatherPose,
    boxes: BoxesOf<'_>,
    field: &mut HeightField,
) -> FeatherPose {
    let rate = inputs.settle_rate;
    let (frame, shape, params) = (&inputs.frames[i], &inputs.shapes[i], inputs.params);
    let step = toward(&current, &solved, rate);
    if step == solved || step.scale <= 0.0 {
        return solved;
    }
    let clear = |pose: FeatherPose, field: &mut HeightField| {
        pose.pitch <= params.max_pitch && pose_is_clear_boxed(frame, shape, pose, boxes, inputs.body, field)
    };
    if clear(step, field) {
        return step;
    }
    let lift = |k: usize| {
        let mut lifted = step;
        lifted.pitch += SETTLE_LIFT_STEP * rate * k as f32;
        // Past the solved pose's pitch, the solved pose is the lift.
        (!(lifted.pitch >= solved.pitch && solved.pitch >= step.pitch)).then_some(lifted)
    };
    let small = (1..=SETTLE_SMALL_LIFTS).map_while(lift);
    let faster = SETTLE_FASTER.iter().map(|&m| toward(&current, &solved, m * rate)).take_while(|p| *p != solved);
    let large = (SETTLE_SMALL_LIFTS + 1..=SETTLE_LIFTS).map_while(lift);
    let stay = std::iter::once(current);
    small
        .chain(stay)
        .chain(faster)
        .find(|&pose| clear(pose, field))
        .or_else(|| {
            repair_drape(frame, shape, current, boxes, inputs.body, params, field)
                .filter(|p| p.pitch <= params.max_pitch)
        })
        .or_else(|| large.clone().find(|&pose| clear(pose, field)))
        .unwrap_or(solved)
}

/// Fills `worker.obstacle_ids` with feather `i`'s earlier candidates that
/// may matter to it at some size and pose (see [`ObstacleReach`]).
fn collect_obstacle_ids(inputs: &Inputs<'_>, i: usize, posed: Posed<'_>, worker: &mut Worker) {
    let ri = inputs.rank[i];
    let reach = ObstacleReach::new(&inputs.frames[i], &inputs.shapes[i], inputs.params);
    worker.obstacle_ids.clear();
    worker.obstacle_ids.extend(
        inputs
            .candidates
            .of(i)
            .iter()
            .map(|&j| j as usize)
            .filter(|&j| inputs.rank[j] < ri)
            .filter(|&j| {
                let (centre, radius) = posed.spheres[j];
                reach.may_matter(centre, radius, inputs.shapes[j].thickness).is_some()
            })
            .map(|j| j as u32),
    );
}

/// The exact check of feather `i` at its current pose against the
/// obstacles in `worker.obstacle_ids` (and the body, unless the run tests
/// the pairs only).
fn check_clear(inputs: &Inputs<'_>, i: usize, poses: &[FeatherPose], posed: Posed<'_>, worker: &mut Worker) -> bool {
    let (frame, shape) = (&inputs.frames[i], &inputs.shapes[i]);
    if inputs.pairs_only {
        let mine = feather_triangles(frame, shape, poses[i]);
        let mine = FeatherBoxes::new(&mine);
        !worker.obstacle_ids.iter().any(|&j| mine.intersects(&posed.triangles[j as usize]))
    } else {
        let boxes = BoxesOf { ids: Some(&worker.obstacle_ids), all: posed.boxes };
        pose_is_clear_boxed(frame, shape, poses[i], boxes, inputs.body, &mut worker.field)
    }
}

/// Adjusts feathers in order with a temporary [`Adjuster`]: all of them, or
/// only those marked in `subset` (the others stay as fixed obstacles). For
/// repeated use (every frame) keep an [`Adjuster`] instead.
#[allow(clippy::too_many_arguments)]
pub fn adjust_in_order(
    frames: &[RootFrame],
    shapes: &[FeatherShape],
    poses: &mut [FeatherPose],
    order: &[u32],
    rank: &[u32],
    candidates: CandidateLists<'_>,
    body: &BodyIndex,
    params: &AdjustParams,
    steps: AdjustSteps,
    subset: Option<&[bool]>,
) -> AdjustStats {
    let selection = subset.map_or(Selection::All, Selection::Subset);
    Adjuster::new().adjust_in_order(frames, shapes, poses, order, rank, candidates, body, params, steps, selection)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ordering::{NeighbourParams, Neighbourhoods};
    use crate::rng::Rng;

    /// Two feathers on a flat skin, both pointing along +X: A (first in the
    /// order) with its root at `a_x`, B at the origin, each the other's
    /// candidate.
    struct TwoFeathers {
        frames: [RootFrame; 2],
        shapes: [FeatherShape; 2],
        body: BodyIndex,
        params: AdjustParams,
    }

    impl TwoFeathers {
        fn new(segments: u32, a_x: impl Fn(&FeatherShape) -> f32) -> Self {
            let frame_at =
                |x: f32| RootFrame::from_normal_and_direction(Vec3::new(x, 0.0, 0.0), Vec3::Z, Vec3::X).unwrap();
            let shape = FeatherShape::for_spacing(1.0).with_segments(segments);
            let corners = [(-5.0, -5.0), (25.0, -5.0), (25.0, 5.0), (-5.0, 5.0)].map(|(x, y)| Vec3::new(x, y, -0.05));
            Self {
                frames: [frame_at(a_x(&shape)), frame_at(0.0)],
                shapes: [shape; 2],
                body: BodyIndex::from_mesh(&corners, &[[0, 1, 2], [0, 2, 3]]),
                params: AdjustParams::default(),
            }
        }

        /// Adjusts the selected feathers with `adjuster`, settling at `rate`.
        fn run(&self, adjuster: &mut Adjuster, poses: &mut [FeatherPose], selection: Selection<'_>, rate: f32) {
            let (offsets, indices) = ([0u32, 1, 2], [1u32, 0]);
            adjuster.settle_next_run(rate);
            adjuster.adjust_in_order(
                &self.frames,
                &self.shapes,
                poses,
                &[0, 1],
                &[0, 1],
                CandidateLists::new(&offsets, &indices),
                &self.body,
                &self.params,
                AdjustSteps::Full,
                selection,
            );
        }

        /// Whether B's triangles meet A's.
        fn meet(&self, poses: &[FeatherPose]) -> bool {
            let b = feather_triangles(&self.frames[1], &self.shapes[1], poses[1]);
            FeatherBoxes::new(&b).intersects(&feather_triangles(&self.frames[0], &self.shapes[0], poses[0]))
        }
    }

    /// An obstacle feather rises and falls back under the feather lying on
    /// it: the feather above lifts at once, then settles over several
    /// frames by at most the settle rate a frame, to the pose solved
    /// without the limit, and never meets the obstacle (exact test), for
    /// the kite and a bent shaft.
    #[test]
    fn a_feather_lifts_at_once_and_settles_over_frames() {
        for segments in [1u32, 4] {
            // A (earlier in the order) lies under B, one unit ahead of B's root.
            let scene = TwoFeathers::new(segments, |_| 1.0);
            let mut poses = vec![FeatherPose::default(); 2];
            let mut adjuster = Adjuster::new();
            scene.run(&mut adjuster, &mut poses, Selection::All, 0.0);
            let (a_rest, b_rest) = (poses[0], poses[1]);
            let rate = 0.03;
            let only_b = [false, true];
            // A rises: B lifts at once, clear of it.
            poses[0].pitch = a_rest.pitch + 0.3;
            assert!(scene.meet(&poses), "S = {segments}: the risen obstacle must reach B where it lay");
            scene.run(&mut adjuster, &mut poses, Selection::Subset(&only_b), rate);
            assert!(!scene.meet(&poses), "S = {segments}: B lifts clear at once");
            // Lifted at once: by more than the settle rate allows (a kite
            // pitches up; a bent feather may bend up instead).
            let lifted = crate::feather::pose_change(&b_rest, &poses[1]);
            assert!(lifted > 2.0 * rate, "S = {segments}: B moved by only {lifted} from {b_rest:?} to {:?}", poses[1]);
            // A falls back: B settles frame by frame to its pose solved at once.
            poses[0] = a_rest;
            let mut solved = poses.clone();
            scene.run(&mut Adjuster::new(), &mut solved, Selection::Subset(&only_b), 0.0);
            let mut frames_to_settle = 0;
            while poses[1] != solved[1] {
                let before = poses[1];
                scene.run(&mut adjuster, &mut poses, Selection::Subset(&only_b), rate);
                assert!(!scene.meet(&poses), "S = {segments}: B never passes through A");
                let change = crate::feather::pose_change(&before, &poses[1]);
                assert!(change <= rate + 1e-6, "S = {segments}: B moved by {change} in one frame");
                assert_eq!(adjuster.settling()[1], poses[1] != solved[1]);
                frames_to_settle += 1;
                assert!(frames_to_settle < 200, "S = {segments}: B never settles");
            }
            println!(
                "S = {segments}: B from {:.3} lifted to {lifted:.3}, back to {:.3} in {frames_to_settle} frames",
                b_rest.pitch, solved[1].pitch
            );
            assert!(frames_to_settle >= 3, "S = {segments}: settled in {frames_to_settle} frames");
        }
    }

    /// A settling feather stops settling (is no longer a seed of the next
    /// frame) once its tip is within [`SETTLED_TIP_GAP`] of its solved
    /// pose's tip, before it reaches that pose.
    #[test]
    fn a_feather_stops_settling_when_its_tip_is_close_to_the_solved_one() {
        let scene = TwoFeathers::new(1, |_| 1.0);
        let mut poses = vec![FeatherPose::default(); 2];
        let mut adjuster = Adjuster::new();
        scene.run(&mut adjuster, &mut poses, Selection::All, 0.0);
        let a_rest = poses[0];
        poses[0].pitch += 0.3;
        scene.run(&mut adjuster, &mut poses, Selection::Subset(&[false, true]), 0.0);
        poses[0] = a_rest;
        let mut solved = poses.clone();
        scene.run(&mut Adjuster::new(), &mut solved, Selection::Subset(&[false, true]), 0.0);
        let (frame, shape) = (&scene.frames[1], &scene.shapes[1]);
        let tip = |p: FeatherPose| (tip_position(frame, shape, p) - frame.position).dot(frame.normal) / shape.length;
        let mut stopped_short = false;
        for _ in 0..400 {
            scene.run(&mut adjuster, &mut poses, Selection::Subset(&[false, true]), 0.002);
            let gap = tip(poses[1]) - tip(solved[1]);
            assert_eq!(adjuster.settling()[1], poses[1] != solved[1] && gap > SETTLED_TIP_GAP, "gap {gap}");
            stopped_short |= poses[1] != solved[1] && !adjuster.settling()[1];
            if poses[1] == solved[1] {
                break;
            }
        }
        assert!(stopped_short, "B must stop settling before it reaches its solved pose");
    }

    /// An obstacle rises a little every frame under a bent feather lying on
    /// it: the feather is repaired from its last pose (its joints lift as
    /// little as it takes) rather than draped afresh, so it follows the
    /// obstacle smoothly: no frame changes it by more than a few times the
    /// obstacle's rise, and it never meets the obstacle.
    #[test]
    fn a_bent_feather_follows_a_slowly_rising_obstacle_without_popping() {
        // A (earlier in the order) grows from under B's first quarter and
        // rises under B's outer segments.
        let scene = TwoFeathers::new(4, |shape| 0.25 * shape.length);
        let mut poses = vec![FeatherPose::default(); 2];
        let mut adjuster = Adjuster::new();
        scene.run(&mut adjuster, &mut poses, Selection::All, 0.0);
        let rise = 0.02;
        let (mut worst, mut lifted) = (0.0f32, 0);
        for _ in 0..25 {
            let before = poses[1];
            poses[0].pitch += rise;
            let was_met = scene.meet(&poses);
            scene.run(&mut adjuster, &mut poses, Selection::Subset(&[false, true]), 0.035);
            assert!(!scene.meet(&poses), "B clear of the risen obstacle");
            lifted += usize::from(was_met);
            worst = worst.max(crate::feather::pose_change(&before, &poses[1]));
        }
        println!("worst change a frame {:.2}°, {lifted} frames lifted", worst.to_degrees());
        assert!(lifted >= 10, "the obstacle must push B up in most frames ({lifted})");
        assert!(worst <= 4.0 * rise, "B changed by {:.2}° in one frame", worst.to_degrees());
    }

    /// A sparse run gives the poses, adjusted and verified flags of a run
    /// by levels over the same symmetric candidates; by levels, the checks
    /// made ahead on several threads change nothing either.
    #[test]
    fn a_sparse_run_matches_the_levels() {
        let mut rng = Rng::new(7);
        let (w, h) = (14, 10);
        let frames: Vec<RootFrame> = (0..w * h)
            .map(|k| {
                let (x, y) = ((k % w) as f32 + 0.3 * rng.next_f32(), (k / w) as f32 + 0.3 * rng.next_f32());
                let normal = Vec3::new(0.1 * (x * 0.7).sin(), 0.1 * (y * 0.5).cos(), 1.0);
                RootFrame::from_normal_and_direction(Vec3::new(x, y, 0.0), normal, Vec3::new(1.0, 0.2, 0.0)).unwrap()
            })
            .collect();
        let n = frames.len();
        let shapes = vec![FeatherShape::for_spacing(1.0); n];
        let reach: Vec<f32> = shapes.iter().map(|s| s.length).collect();
        let mut nb = Neighbourhoods::new();
        nb.rebuild(&frames, &reach, &NeighbourParams::default());
        let (offsets, indices) = nb.obstacle_csr();
        let candidates = CandidateLists::new(offsets, indices);
        // Tips first: the feathers farther along x are earlier.
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by(|&a, &b| frames[b as usize].position.x.total_cmp(&frames[a as usize].position.x).then(a.cmp(&b)));
        let mut rank = vec![0u32; n];
        for (k, &i) in order.iter().enumerate() {
            rank[i as usize] = k as u32;
        }
        let body = BodyIndex::from_mesh(
            &[
                Vec3::new(-5.0, -5.0, -0.05),
                Vec3::new(25.0, -5.0, -0.05),
                Vec3::new(25.0, 20.0, -0.05),
                Vec3::new(-5.0, 20.0, -0.05),
            ],
            &[[0, 1, 2], [0, 2, 3]],
        );
        let params = AdjustParams::default();
        let mut start = vec![FeatherPose::default(); n];
        let mut adjuster = Adjuster::new();
        let all = adjuster.adjust_in_order(
            &frames,
            &shapes,
            &mut start,
            &order,
            &rank,
            candidates,
            &body,
            &params,
            AdjustSteps::Full,
            Selection::All,
        );
        assert_eq!(all.adjusted, n);
        let threads = [1, 3].map(|t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap());
        let mut checked = 0;
        for round in 0..6 {
            // Disturb some poses, then readjust a few seeds and check others.
            let mut poses = start.clone();
            for p in poses.iter_mut() {
                if rng.next_f32() < 0.15 {
                    p.pitch += 0.8 * rng.next_f32() - 0.4;
                    p.roll += 0.4 * rng.next_f32() - 0.2;
                }
            }
            let seeds: Vec<bool> = (0..n).map(|_| rng.next_f32() < 0.03 + 0.04 * round as f32).collect();
            let suspects: Vec<bool> = (0..n).map(|_| rng.next_f32() < 0.1).collect();
            let threshold = 0.05 + 0.1 * round as f32;
            for selection in [
                Selection::Verify { seeds: &seeds, suspects: &suspects, threshold },
                Selection::Propagate { seeds: &seeds, threshold },
            ] {
                let run = |sparse: bool, pairs_only: bool| {
                    let mut adjuster = Adjuster::new();
                    let mut poses = poses.clone();
                    let lists = (&frames[..], &shapes[..], &order[..], &rank[..], candidates);
                    let stats = adjuster
                        .ordered_run(
                            lists,
                            &mut poses,
                            &body,
                            &params,
                            AdjustSteps::Full,
                            selection,
                            &|_| true,
                            (sparse, pairs_only),
                        )
                        .unwrap();
                    (poses, adjuster.adjusted().to_vec(), adjuster.verified().to_vec(), stats.adjusted, stats.verified)
                };
                for pairs_only in [false, true] {
                    // By levels on three threads, which checks the suspects
                    // ahead (Adjuster::precheck), and on one, which does not.
                    let by_levels = threads[1].install(|| run(false, pairs_only));
                    assert_eq!(by_levels, threads[0].install(|| run(false, pairs_only)), "round {round}");
                    let sparse = run(true, pairs_only);
                    checked += by_levels.3 + by_levels.4;
                    assert_eq!(by_levels.0, sparse.0, "round {round}");
                    assert_eq!(by_levels.1, sparse.1, "round {round}");
                    assert_eq!(by_levels.2, sparse.2, "round {round}");
                    assert_eq!((by_levels.3, by_levels.4), (sparse.3, sparse.4), "round {round}");
                }
            }
        }
        assert!(checked > n, "too little was adjusted or checked: {checked}");
    }
}
