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
//!
//! A verifying frame (every feather whose surroundings moved is checked
//! where it lies) puts nearly every feather in scope, and the obstacle
//! relation runs through thousands of levels of a feather or two, which
//! leave the other threads idle. Such a run walks the order one feather
//! after another instead, finding through the obstacle rows' transpose
//! what lies on a feather it changed, while the other threads check the
//! feathers ahead of it against the coat as it was ([`walk`]; the walk
//! sets its changes aside meanwhile, [`aside`]). Same poses either way.

use super::checks::bounding_sphere;
use super::obstacle::ObstacleBoxes;
use super::{AdjustParams, AdjustSteps, DrapeRoute, HeightField};
use crate::body::BodyIndex;
use crate::csr::{Csr, CsrView};
use crate::feather::{FeatherPose, FeatherShape, FeatherTriangles, feather_triangles};
use crate::geometry::RootFrame;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

crate::memory::heap_size_of_fields!(Adjuster {
    posed, in_scope, level, moved, changed, adjusted, verified, levels, outcomes, workers, settling, prechecked, precheck_items, dependents, aside
} plain { #[cfg(test)] by_levels, #[cfg(test)] checks_ahead_first, #[cfg(test)] pairs_only });

mod aside;
mod scope;
#[cfg(test)]
mod tests;
mod visit;
mod walk;

use super::settle::tip_above;
use aside::Aside;
pub use visit::Selection;
use visit::{FeatherGeometry, Inputs, Posed, Prechecks, Visit, Worker};

/// Work chunks per worker thread in one level (load balance vs. overhead).
const CHUNKS_PER_THREAD: usize = 4;

/// How a serial run (one feather after another along the order, not by
/// levels) finds what lies on a feather it changed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SerialWalk {
    /// Over symmetric candidate rows (a step's second pass): the later
    /// feathers of a feather's own row.
    Symmetric,
    /// Over obstacle rows: the feathers listing it, from their transpose.
    Transposed,
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
    /// Adjusted segmented feathers whose bends were draped (the swept
    /// drape or its fallback).
    pub draped: usize,
    /// Of those, the ones the swept drape left to the descent by exact
    /// checks.
    pub drape_descents: usize,
    /// Adjusted segmented feathers kept where they lay instead: repaired
    /// in place or lowered a step (incremental runs).
    pub kept_in_place: usize,
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

/// Reusable state of ordered adjustments: level lists, feather triangles
/// and per-worker scratch. Keep one per system; after the first frames
/// nothing it holds grows unless the feather count or thread count does,
/// or a verifying walk adjusts more feathers than any before it (what it
/// sets aside keeps room for the most, at most one entry per feather).
#[derive(Clone, Debug, Default)]
pub struct Adjuster {
    /// Every feather's geometry at its pose.
    posed: Posed,
    in_scope: Vec<bool>,
    level: Vec<u32>,
    moved: Vec<bool>,
    changed: Vec<bool>,
    adjusted: Vec<bool>,
    verified: Vec<bool>,
    /// The feathers of each level in order: row `l` holds level `l + 1`.
    levels: Csr<u32>,
    outcomes: Vec<Visit>,
    workers: Vec<Worker>,
    /// Which feathers the last run held back from their solved pose.
    settling: Vec<bool>,
    /// Verifying (not sparse): the answers of the suspects' checks made
    /// ahead, on other threads while the walk goes on, against their
    /// obstacles as they were before it ([`Precheck`] as `u8`), by feather.
    prechecked: Prechecks,
    /// The feathers to check ahead, in order.
    precheck_items: Vec<u32>,
    /// The transpose of the candidate rows of a walk over obstacle rows:
    /// the feathers listing each feather.
    dependents: Csr<u32>,
    /// The poses and geometry a walk checking ahead gives the feathers it
    /// adjusts, until it ends.
    aside: Aside,
    /// Tests only: a verifying run goes by levels (checking nothing ahead)
    /// instead of walking.
    #[cfg(test)]
    by_levels: bool,
    /// Tests only: a walk checking ahead makes every check ahead before it
    /// starts (on its own thread).
    #[cfg(test)]
    checks_ahead_first: bool,
    /// Tests only: verifies with the pairs only (or with every check)
    /// whether the run is sparse or not.
    #[cfg(test)]
    pairs_only: Option<bool>,
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

    /// Which feathers the last run held back from their solved pose (they
    /// settle further in later frames).
    pub fn settling(&self) -> &[bool] {
        &self.settling
    }

    /// Room for the transpose of up to `entries` candidates, so that a
    /// frame whose candidate rows hold more than any before allocates
    /// nothing for it.
    pub fn reserve_dependents(&mut self, entries: usize) {
        self.dependents.reserve_items(entries);
    }

    /// Room in every worker for `longest` obstacles, so that a later call
    /// with rows up to that long allocates nothing (a frame whose second
    /// pass uses longer rows than the first may come late).
    pub fn reserve_obstacles(&mut self, longest: usize) {
        self.workers.iter_mut().for_each(|w| {
            w.obstacles.reserve(longest.saturating_sub(w.obstacles.len()));
            w.obstacle_ids.reserve(longest.saturating_sub(w.obstacle_ids.len()));
            w.changed_ids.reserve(longest.saturating_sub(w.changed_ids.len()));
        });
    }

    /// Every feather's two triangles at the poses left by the last call.
    pub fn triangles(&self) -> &[FeatherTriangles] {
        &self.posed.triangles
    }

    /// Adjusts the selected feathers in `order` (`order[k]` is the k-th
    /// feather; `rank` is its inverse). Feather i's obstacles are its
    /// `candidates` with a smaller rank, at their current poses (adjusted
    /// ones at their new poses). `poses` holds the current poses and
    /// receives the new ones. Runs on the current rayon pool; the result is
    /// bitwise the same for any thread count.
    ///
    /// Panics if the slices disagree in length.
    pub fn adjust_in_order(
        &mut self,
        run: &OrderedRun<'_>,
        poses: &mut [FeatherPose],
        selection: Selection<'_>,
    ) -> AdjustStats {
        self.adjust_in_order_until(run, poses, selection, &|_| true).unwrap_or_default()
    }

    /// As [`Adjuster::adjust_in_order`], asking `keep_going(fraction done)`
    /// before each level; `None` when it says stop (then `poses` holds a
    /// mix of old and new poses and the caller must restore them).
    pub fn adjust_in_order_until(
        &mut self,
        run: &OrderedRun<'_>,
        poses: &mut [FeatherPose],
        selection: Selection<'_>,
        keep_going: &(dyn Fn(f32) -> bool + Sync),
    ) -> Option<AdjustStats> {
        self.ordered_run(run, poses, selection, keep_going, false)
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
    pub fn adjust_sparse_until(
        &mut self,
        run: &OrderedRun<'_>,
        poses: &mut [FeatherPose],
        selection: Selection<'_>,
        keep_going: &(dyn Fn(f32) -> bool + Sync),
    ) -> Option<AdjustStats> {
        self.ordered_run(run, poses, selection, keep_going, true)
    }

    /// Both ways of [`Adjuster::adjust_in_order_until`]: by levels, or
    /// `sparse` (verifying with the pairs only, see
    /// [`Adjuster::adjust_sparse_until`]).
    fn ordered_run(
        &mut self,
        run: &OrderedRun<'_>,
        poses: &mut [FeatherPose],
        selection: Selection<'_>,
        keep_going: &(dyn Fn(f32) -> bool + Sync),
        sparse: bool,
    ) -> Option<AdjustStats> {
        let OrderedRun { frames, shapes, order, rank, candidates, body, params, steps, settle_rate } = *run;
        let start = Instant::now();
        self.begin_run(run, poses, selection, keep_going)?;
        let inputs = Inputs {
            frames,
            shapes,
            rank,
            candidates,
            body,
            params,
            steps,
            selection,
            pairs_only: self.pairs_only_or(sparse),
            settle_rate,
            keep_going,
        };
        let mut stats = AdjustStats::default();
        match self.choose_walk(&inputs, sparse) {
            Some(SerialWalk::Symmetric) => self.walk_serially(&inputs, order, poses, &mut stats)?,
            Some(SerialWalk::Transposed) => self.walk_checking_ahead(&inputs, order, poses, &mut stats)?,
            None => self.walk_levels(&inputs, order, poses, &mut stats)?,
        }
        stats.seconds = start.elapsed().as_secs_f64();
        Some(stats)
    }

    /// Checks the run's inputs agree in length, poses every feather, and
    /// readies the workers and the per-feather marks; `None` when
    /// `keep_going` said stop.
    fn begin_run(
        &mut self,
        run: &OrderedRun<'_>,
        poses: &[FeatherPose],
        selection: Selection<'_>,
        keep_going: &(dyn Fn(f32) -> bool + Sync),
    ) -> Option<()> {
        let OrderedRun { frames, shapes, order, rank, candidates, body, params, .. } = *run;
        let n = frames.len();
        assert!(
            shapes.len() == n && poses.len() == n && order.len() == n && rank.len() == n && candidates.rows() == n,
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
        self.posed_triangles(frames, shapes, poses, keep_going);
        if !keep_going(0.0) {
            return None;
        }
        self.prepare_workers(params);
        // Room for the longest row up front: which rows a worker meets
        // varies from frame to frame, and its buffer must not creep up.
        let longest = (0..n).map(|i| candidates.row(i).len()).max().unwrap_or(0);
        self.reserve_obstacles(longest);
        // Body queries list each triangle at most once; a rare wide query
        // (a skin search widening far from the feather) must not grow them.
        let triangles = body.triangle_count();
        self.workers.iter_mut().for_each(|w| {
            w.field.body_scratch.reserve(triangles);
            w.field.reserve_drape(longest, triangles);
        });
        for flags in [&mut self.moved, &mut self.changed, &mut self.adjusted, &mut self.verified, &mut self.settling] {
            flags.clear();
            flags.resize(n, false);
        }
        self.prechecked.reset(n);
        Some(())
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
        if let Some((pose, geometry)) = self.record(i, visit, inputs, poses[i], stats) {
            poses[i] = pose;
            self.posed.set(i, &geometry);
        }
    }

    /// As [`Adjuster::apply`], the new pose and geometry set aside (see
    /// [`Adjuster::walk_checking_ahead`]).
    fn apply_aside(
        &mut self,
        i: usize,
        visit: &Visit,
        inputs: &Inputs<'_>,
        poses: &[FeatherPose],
        stats: &mut AdjustStats,
    ) {
        let old = self.aside.pose(i, poses);
        if let Some((pose, geometry)) = self.record(i, visit, inputs, old, stats) {
            self.aside.set(i, pose, &geometry);
        }
    }

    /// The marks and figures of [`Adjuster::apply`] for feather `i` at
    /// pose `old`; the pose and geometry it takes when adjusted.
    fn record(
        &mut self,
        i: usize,
        visit: &Visit,
        inputs: &Inputs<'_>,
        old: FeatherPose,
        stats: &mut AdjustStats,
    ) -> Option<(FeatherPose, FeatherGeometry)> {
        let (frames, shapes, selection) = (inputs.frames, inputs.shapes, inputs.selection);
        let (o, solved) = match visit {
            Visit::Adjusted(o, solved) => (o, solved),
            Visit::Verified => {
                self.verified[i] = true;
                stats.verified += 1;
                return None;
            }
            Visit::Skipped => return None,
        };
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
        self.adjusted[i] = true;
        stats.adjusted += 1;
        stats.collision_tests += u64::from(o.collision_tests);
        stats.clamped += usize::from(o.clamped);
        stats.draped += usize::from(matches!(o.drape, DrapeRoute::Swept | DrapeRoute::Descent));
        stats.kept_in_place += usize::from(matches!(o.drape, DrapeRoute::Repaired | DrapeRoute::Lowered));
        stats.drape_descents += usize::from(o.drape == DrapeRoute::Descent);
        Some((o.pose, FeatherGeometry::of(&frames[i], &shapes[i], o.pose)))
    }

    /// Every feather's triangles at its current pose, and their spheres.
    /// Every feather's triangles, bounding sphere and obstacle boxes at its
    /// pose; once `keep_going` says stop the rest are left (the run is
    /// abandoned).
    fn posed_triangles(
        &mut self,
        frames: &[RootFrame],
        shapes: &[FeatherShape],
        poses: &[FeatherPose],
        keep_going: &(dyn Fn(f32) -> bool + Sync),
    ) {
        let Posed { triangles, spheres, boxes, bounds } = &mut self.posed;
        triangles.resize(frames.len(), FeatherTriangles::kite([[Vec3::ZERO; 3]; 2]));
        spheres.resize(frames.len(), (Vec3::ZERO, 0.0));
        let unset = ObstacleBoxes::new(&[[Vec3::ZERO; 3]; 2], 0.0);
        boxes.resize(frames.len(), unset);
        bounds.resize(frames.len(), unset.bounds());
        let stopped = AtomicBool::new(false);
        triangles
            .par_iter_mut()
            .zip(spheres.par_iter_mut().zip(boxes.par_iter_mut().zip(bounds.par_iter_mut())))
            .zip(frames.par_iter().zip(shapes.par_iter().zip(poses.par_iter())))
            .enumerate()
            .for_each(|(k, ((t, (sphere, (boxes, bounds))), (f, (s, p))))| {
                if stopped.load(Ordering::Relaxed) || (k % 64 == 0 && !keep_going(0.0)) {
                    stopped.store(true, Ordering::Relaxed);
                    return;
                }
                *t = feather_triangles(f, s, *p);
                *sphere = bounding_sphere(t);
                *boxes = ObstacleBoxes::new(t, s.thickness);
                *bounds = boxes.bounds();
            });
    }

    /// Whether a verifying run goes by levels: only when a test says so.
    fn verifies_by_levels(&self) -> bool {
        #[cfg(test)]
        if self.by_levels {
            return true;
        }
        false
    }

    /// Whether verification tests the pairs only: in a sparse run (see
    /// [`Adjuster::adjust_sparse_until`]), unless a test says otherwise.
    fn pairs_only_or(&self, sparse: bool) -> bool {
        #[cfg(test)]
        if let Some(pairs_only) = self.pairs_only {
            return pairs_only;
        }
        sparse
    }

    /// One scratch per possible work chunk of the current pool.
    fn prepare_workers(&mut self, params: &AdjustParams) {
        let wanted = rayon::current_num_threads().max(1) * CHUNKS_PER_THREAD;
        while self.workers.len() < wanted {
            self.workers.push(Worker {
                field: HeightField::new(params.height_field_u, params.height_field_v),
                obstacles: Vec::new(),
                obstacle_ids: Vec::new(),
                changed_ids: Vec::new(),
            });
        }
    }
}

/// What an ordered run reads: every feather's root frame and shape, the
/// adjustment `order` (`order[k]` is the k-th feather; `rank` is its
/// inverse), each feather's `candidates` (roots within reach; its obstacles
/// are those of smaller rank), the body, the adjustment's parameters and
/// steps, and the settle rate. One entry per feather in each slice and row
/// list.
#[derive(Clone, Copy)]
pub struct OrderedRun<'a> {
    pub frames: &'a [RootFrame],
    pub shapes: &'a [FeatherShape],
    pub order: &'a [u32],
    pub rank: &'a [u32],
    pub candidates: CsrView<'a, u32>,
    pub body: &'a BodyIndex,
    pub params: &'a AdjustParams,
    pub steps: AdjustSteps,
    /// Radians: each adjusted feather moves from its current pose toward
    /// its solved pose by at most this in pitch, roll and each bend, when
    /// that pose passes the exact checks; otherwise it lifts from there by
    /// the smallest of a few pitch steps that passes, else takes the solved
    /// pose (see [`crate::animation::coherence`]). 0 takes the solved pose.
    pub settle_rate: f32,
}

/// Adjusts feathers in order with a temporary [`Adjuster`]: all of them, or
/// only those marked in `subset` (the others stay as fixed obstacles). For
/// repeated use (every frame) keep an [`Adjuster`] instead.
pub fn adjust_in_order(run: &OrderedRun<'_>, poses: &mut [FeatherPose], subset: Option<&[bool]>) -> AdjustStats {
    let selection = subset.map_or(Selection::All, Selection::Subset);
    Adjuster::new().adjust_in_order(run, poses, selection)
}
