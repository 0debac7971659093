//! The three adjustment steps on a filled [`HeightField`].
//!
//! Geometry. With roll β applied before pitch α, the posed kite is one plane
//! through the root; over a horizontal point (x, y) of the root frame its
//! height is `x·tan α + y·tan β / cos α`, and the kite point there has shaft
//! coordinate `x0 = x / cos α + y0·sin β·tan α` and lateral coordinate
//! `y0 = y / cos β`. Both are cheap, so the steps work in slopes
//! (`p = tan α`, lateral slope `q = tan β / cos α`) and never need
//! per-cell trigonometry.
//!
//! Semantics (a height field is a "lid" problem). A cell constrains the
//! feather only while the posed kite covers it (cell rounded outward by half
//! a cell in kite coordinates); then the kite's lowest point over the cell
//! must clear the cell's height. Everything under a cell's top counts as
//! solid, which is what makes the field safe for steep obstacles whose cell
//! maximum hides their lower parts. A feather may also clear a tall cell near
//! its tip by pitching until its tip no longer covers it (the tip then
//! stops at the obstacle's side instead of climbing over it).
//!
//! The smallest clear pitch is found by jumping upward from the lowest
//! allowed pitch: at the current pitch, every covered cell that is violated
//! stays violated until its own threshold (the pitch that clears it, or the
//! one at which the tip leaves it), so the pitch jumps to the largest such
//! threshold; the loop ends at the first pitch where no covered cell is
//! violated, which is therefore clear (every cell it covers is checked).
//!
//! The root socket (see `height_field`): nothing within the first 2.5 % of
//! the shaft constrains the pitch; heights beyond it are judged at its end.

use super::height_field::{GridExtent, JUDGE_FRACTION, LocalMap, ceil_i32, floor_i32};
use super::{AdjustOutcome, AdjustParams, AdjustSteps, HeightField, ObstacleFeather};
use crate::body::{Aabb, BodyIndex};
use crate::feather::{FeatherPose, FeatherShape, FeatherTriangles, MAX_JOINTS, MAX_TRIANGLES, feather_triangles};
use crate::geometry::RootFrame;
use crate::validation::{BoxedTriangles, FeatherBoxes};
use glam::Vec3;

/// Jump iterations before giving up (reported as a clamp). Real fields need
/// two to five.
const MAX_JUMPS: usize = 64;
/// Free height under a vane is capped at this fraction of the width when
/// balancing volumes (empty space far below does not pull the roll).
const FREE_HEIGHT_CAP_PER_WIDTH: f32 = 0.5;
/// Sizes tried, largest first, for a feather that cannot lie down within
/// the pitch limit.
const SHRINK_STEPS: [f32; 8] = [0.85, 0.7, 0.6, 0.5, 0.4, 0.3, 0.22, 0.15];
/// Sizes below this are rasterised again (see [`adjust_feather`]): the root
/// socket, 2.5 % of the full length, is 5 % of a half-size feather.
const REFILL_BELOW: f32 = 0.5;
/// The relaxed judging distance near the root, as a fraction of the
/// length, tried before the field's conservative `JUDGE_FRACTION` (8 %).
/// The cells near the root mostly hold the vanes of the lateral
/// neighbours, which pass beside the root rather than over it (cells the
/// kite barely covers, rounded outward by half a cell); judged at 8 % of
/// the length, a neighbour's thickness there stands the feather up by
/// several degrees, and every later feather lying on it climbs as well.
/// A pose chosen with the relaxed distance is kept only if the exact check
/// passes and the feather also stays clear of every obstacle's top (see
/// [`raised_top`]), so the thickness is still respected.
///
/// Measured with the exact sweep below (coverage, mean pitch): judging
/// conservatively only, Flamingo 0.864/27.9°, Fox 0.953/30.2°, bird
/// 0.830/29.9°; relaxed at 0.25: 0.875/26.8°, 0.959/28.9°, 0.854/26.1°
/// (sphere and torus unchanged). Further out covers more (0.4: 0.885,
/// 0.964, 0.867; 0.6: 0.894, 0.970, 0.880, sphere pitch down to 10°), but
/// the tighter coat leaves less slack for motion: under the paper's rule
/// (no exact checks while animating) the Flamingo clip then reaches 3 (0.4)
/// or 4 to 6 (0.5, 0.6) intersecting pairs, against 2 at 0.25 and the
/// 0.2 % (3 pairs) that tests/flamingo_clip.rs allows.
const RELAXED_JUDGE_FRACTION: f32 = 0.25;
/// Rolls whose lateral slope is below this (about 0.3°) are not worth a
/// second pitch search: the feather stays unrolled.
const MIN_LATERAL_SLOPE: f32 = 0.005;

/// Adjusts one feather: rasterises its obstacles and the body near its root
/// into `scratch`, then runs the chosen steps (see the module notes of
/// [`crate::adjustment`]). `previous` supplies the roll kept by
/// [`AdjustSteps::FinePitchOnly`]; [`AdjustSteps::Full`] does not read it,
/// so a full adjustment depends only on the geometry. Allocates nothing once
/// `scratch` has been used at this resolution.
#[allow(clippy::too_many_arguments)]
pub fn adjust_feather(
    frame: &RootFrame,
    shape: &FeatherShape,
    previous: FeatherPose,
    obstacles: &[ObstacleFeather],
    body: &BodyIndex,
    params: &AdjustParams,
    steps: AdjustSteps,
    scratch: &mut HeightField,
) -> AdjustOutcome {
    let mut boxes = std::mem::take(&mut scratch.boxes);
    boxes.clear();
    boxes.extend(obstacles.iter().map(|o| ObstacleBoxes::new(&o.triangles, o.thickness)));
    let all = BoxesOf { ids: None, all: &boxes };
    let outcome = adjust_feather_boxed(frame, shape, previous, obstacles, all, body, params, steps, scratch);
    scratch.boxes = boxes;
    outcome
}

/// [`adjust_feather`] with the obstacles' [`ObstacleBoxes`] made already
/// (`boxes` lists them in the order of `obstacles`): the straight feather's
/// pose by the height field (and the exact checks), then, for a segmented
/// shaft, its drape (see [`drape`]).
#[allow(clippy::too_many_arguments)]
pub(crate) fn adjust_feather_boxed(
    frame: &RootFrame,
    shape: &FeatherShape,
    previous: FeatherPose,
    obstacles: &[ObstacleFeather],
    boxes: BoxesOf<'_>,
    body: &BodyIndex,
    params: &AdjustParams,
    steps: AdjustSteps,
    scratch: &mut HeightField,
) -> AdjustOutcome {
    let straight = straight_pose(frame, shape, previous, obstacles, boxes, body, params, steps, scratch);
    if shape.segment_count() == 1 || params.bend_limit <= 0.0 || straight.pose.scale <= 0.0 {
        return straight;
    }
    let draped = drape(frame, shape, straight.pose, boxes, body, params, scratch);
    AdjustOutcome { pose: draped, ..straight }
}

/// Angle steps (radians) of the descent of a segment in [`drape`]; the
/// first contact found is then narrowed by [`DRAPE_BISECTIONS`] halvings
/// (to about 0.4°).
const DRAPE_STEP: f32 = 0.1;
/// Halvings of the last step of a descent.
const DRAPE_BISECTIONS: usize = 4;
/// Descents of one drape before it gives up and keeps the straight pose
/// (each backtrack raises a segment by a [`DRAPE_STEP`]).
const MAX_DRAPE_DESCENTS: usize = 16;
/// Halvings of the raise of an earlier segment that makes room for a later
/// one in [`drape`] (to 0.4 rad / 64, about 0.4°).
const DRAPE_RAISE_BISECTIONS: usize = 6;

/// Drapes a segmented feather (DESIGN.md §4, bending). The straight pose
/// gives the roll and an upper bound on the root segment's pitch (the
/// whole straight feather is clear there); then segment by segment from
/// the root, each takes the lowest angle at which it is clear by the exact
/// checks (the obstacles, their raised tops, and the body), coming down
/// from its highest angle in steps so that it settles on what lies beneath
/// it rather than passing through to a clear place below. Only the segment
/// being placed is checked (those before it are placed; a later one starts
/// where it ends). The root segment comes down from the straight pitch
/// towards the lowest pitch; every later one turns from the one before it
/// by up to the bend limit up, or [`super::DOWN_BEND_PER_LIMIT`] times it
/// down.
///
/// A segment that meets something even at its highest angle (an obstacle
/// rising steeply ahead of a root segment laid low) sends the drape back:
/// the nearest earlier segment that can make room is raised, by bisection,
/// to the lowest angle at which it and every segment after it up to the
/// blocked one, each at its highest, are clear; the drape goes on from the
/// segment after it. The root can rise up to the straight pitch. Without
/// this, about 60 % of the Flamingo's feathers kept the straight pose
/// because one outer segment could not follow. The raise is bisected rather
/// than stepped so that it follows the geometry continuously: with the
/// rest positions moved by 1e-5, 1e-4 and 1e-3 of the Fox's size, a full
/// re-solve changed 5.5, 12.4 and 31 % of the feathers by more than 5°,
/// against 6.5, 17.1 and 45 % with raises in [`DRAPE_STEP`]s (the kite:
/// 0.2, 1.8 and 9.3 %), for tips about 0.02 lengths higher. After
/// [`MAX_DRAPE_DESCENTS`] descents, or with no segment able to make room,
/// the feather keeps its straight pose, which was clear.
fn drape(
    frame: &RootFrame,
    shape: &FeatherShape,
    straight: FeatherPose,
    boxes: BoxesOf<'_>,
    body: &BodyIndex,
    params: &AdjustParams,
    scratch: &mut HeightField,
) -> FeatherPose {
    let segments = shape.segment_count();
    let mut hints = CheckHints::default();
    // Segment k's angle: the root's pitch for k = 0, else the bend of joint
    // k − 1 (relative to segment k − 1).
    let (bend_low, bend_high) = params.bend_range();
    let high = |k: usize| if k == 0 { straight.pitch } else { bend_high };
    let low = |k: usize| if k == 0 { params.min_pitch } else { bend_low };
    let set = |pose: &mut FeatherPose, k: usize, angle: f32| {
        if k == 0 { pose.pitch = angle } else { pose.bends[k - 1] = angle }
    };
    let angle = |pose: &FeatherPose, k: usize| if k == 0 { pose.pitch } else { pose.bends[k - 1] };
    let mut pose = straight;
    let mut k = 0;
    let mut descents = 0;
    while k < segments {
        descents += 1;
        if descents > MAX_DRAPE_DESCENTS {
            return straight;
        }
        let settled = descend(high(k), low(k), |a| {
            let mut trial = pose;
            set(&mut trial, k, a);
            segment_check(frame, shape, trial, k, boxes, body, scratch, &mut hints)
        });
        if let Some(a) = settled {
            set(&mut pose, k, a);
            k += 1;
            continue;
        }
        // Even at its highest angle segment k meets something: raise an
        // earlier segment i (the nearest that can make room) to the lowest
        // angle at which it and every segment after it up to k, each at
        // its highest, are clear (bisected, so the raise follows the
        // geometry continuously), then drape on from i + 1.
        let raised_pose = |pose: FeatherPose, i: usize, a: f32| {
            let mut trial = pose;
            set(&mut trial, i, a);
            for j in i + 1..=k {
                set(&mut trial, j, high(j));
            }
            trial
        };
        let mut room = |trial: FeatherPose, i: usize, scratch: &mut HeightField| {
            (i..=k).all(|j| segment_check(frame, shape, trial, j, boxes, body, scratch, &mut hints))
        };
        let mut found = None;
        for i in (0..k).rev() {
            let (lowest, highest) = (angle(&pose, i), high(i));
            if lowest >= highest || !room(raised_pose(pose, i, highest), i, scratch) {
                continue;
            }
            let fits = narrow(lowest, highest, DRAPE_RAISE_BISECTIONS, |a| room(raised_pose(pose, i, a), i, scratch));
            found = Some((i, fits));
            break;
        }
        let Some((i, a)) = found else {
            return straight;
        };
        set(&mut pose, i, a);
        for j in i + 1..segments {
            set(&mut pose, j, 0.0);
        }
        k = i + 1;
    }
    // The segment checks judge each segment alone; the validation judges
    // the whole feather, and on a skin met edge-on they can differ (a
    // root segment lying in the skin plane within the contact tolerance,
    // the next bent off it: the Scales preset on a flat soup). The whole
    // feather has the last word.
    if !exact_check(frame, shape, pose, boxes, body, scratch, true, &mut hints) {
        return straight;
    }
    pose
}

/// Steps (radians, about 1.4°) of the ascent of a segment in
/// [`repair_drape`]; the first clear one is narrowed by [`DRAPE_BISECTIONS`]
/// halvings.
const REPAIR_STEP: f32 = 0.025;
/// Steps of that ascent before the rest of the way up to the segment's
/// highest angle is bisected.
const REPAIR_ASCENT_STEPS: usize = 8;

/// Repairs a segmented feather's pose `start` (its pose of the previous
/// frame, or that pose moved toward a newly solved one) with as little
/// change as it takes: segment by segment from the root, each keeps its
/// angle if it is clear there by the exact checks (with the earlier
/// segments as repaired), else rises to the lowest clear angle above it
/// (see [`ascend`]); the roll is kept. `None` when a segment is blocked
/// even at its highest angle, or the whole feather fails its exact check.
/// Solving a drape afresh from the straight pose ([`drape`]) finds a clear
/// pose too, but from another start: its bends may differ from the last
/// frame's by tens of degrees (a feather that pops while every pose is
/// clear), where this keeps each angle unless something pushes it up.
pub(crate) fn repair_drape(
    frame: &RootFrame,
    shape: &FeatherShape,
    start: FeatherPose,
    boxes: BoxesOf<'_>,
    body: &BodyIndex,
    params: &AdjustParams,
    scratch: &mut HeightField,
) -> Option<FeatherPose> {
    let segments = shape.segment_count();
    if segments == 1 || start.scale <= 0.0 {
        return None;
    }
    let mut hints = CheckHints::default();
    let (bend_low, bend_high) = params.bend_range();
    let range = |k: usize| if k == 0 { (params.min_pitch, params.max_pitch) } else { (bend_low, bend_high) };
    let set = |pose: &mut FeatherPose, k: usize, angle: f32| {
        if k == 0 { pose.pitch = angle } else { pose.bends[k - 1] = angle }
    };
    let angle = |pose: &FeatherPose, k: usize| if k == 0 { pose.pitch } else { pose.bends[k - 1] };
    let mut pose = start;
    for k in 0..segments {
        let (low, high) = range(k);
        let from = angle(&pose, k).clamp(low, high);
        set(&mut pose, k, from);
        if segment_check(frame, shape, pose, k, boxes, body, scratch, &mut hints) {
            continue;
        }
        // Segment k is not clear: raise it and every angle before it by
        // the same amount (each up to its highest), the least that clears
        // them all: the shaft's curve up to k is kept and no one joint
        // takes the whole lift.
        let base = pose;
        let raised = |d: f32| {
            let mut trial = base;
            for j in 0..=k {
                set(&mut trial, j, (angle(&base, j) + d).min(range(j).1));
            }
            trial
        };
        let mut clear = |d: f32| {
            let trial = raised(d);
            (0..=k).all(|j| segment_check(frame, shape, trial, j, boxes, body, scratch, &mut hints))
        };
        let most = (0..=k).map(|j| range(j).1 - angle(&base, j)).fold(0.0f32, f32::max);
        let d = ascend(0.0, most, &mut clear)?;
        pose = raised(d);
    }
    exact_check(frame, shape, pose, boxes, body, scratch, true, &mut hints).then_some(pose)
}

/// The lowest angle above `from` (which is not clear) up to `high` at
/// which `clear` holds: [`REPAIR_ASCENT_STEPS`] steps of [`REPAIR_STEP`],
/// the first clear one narrowed by halving; past them, the rest of the way
/// up to `high` bisected. `None` when `high` is not clear.
fn ascend(from: f32, high: f32, mut clear: impl FnMut(f32) -> bool) -> Option<f32> {
    let mut failed = from;
    for s in 1..=REPAIR_ASCENT_STEPS {
        let a = (from + s as f32 * REPAIR_STEP).min(high);
        if a <= failed {
            return None;
        }
        if clear(a) {
            return Some(narrow(failed, a, DRAPE_BISECTIONS, &mut clear));
        }
        failed = a;
    }
    if failed >= high || !clear(high) {
        return None;
    }
    Some(narrow(failed, high, DRAPE_RAISE_BISECTIONS, clear))
}

/// Narrows the boundary between an angle `failed` at which `clear` fails
/// and one `fits` at which it holds by `halvings` bisections; the clear
/// end.
fn narrow(mut failed: f32, mut fits: f32, halvings: usize, mut clear: impl FnMut(f32) -> bool) -> f32 {
    for _ in 0..halvings {
        let mid = 0.5 * (failed + fits);
        if clear(mid) {
            fits = mid;
        } else {
            failed = mid;
        }
    }
    fits
}

/// The lowest angle from `high` down to `low` at which `clear` holds,
/// coming down from `high` in [`DRAPE_STEP`]s and stopping before the
/// first that fails, then narrowing that step by halving. `None` when
/// `high` itself fails.
fn descend(high: f32, low: f32, mut clear: impl FnMut(f32) -> bool) -> Option<f32> {
    if !clear(high) {
        return None;
    }
    let mut above = high;
    loop {
        let below = (above - DRAPE_STEP).max(low);
        if below >= above {
            return Some(above);
        }
        if !clear(below) {
            return Some(narrow(below, above, DRAPE_BISECTIONS, clear));
        }
        above = below;
    }
}

/// The exact check of segment `segment` (from the root) of a posed
/// feather: its triangles meet no obstacle and no obstacle's raised top,
/// and do not cross the body beyond the root socket. The drape checks each
/// segment as it places it; the segments before it do not move then.
#[allow(clippy::too_many_arguments)]
fn segment_check(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    segment: usize,
    obstacles: BoxesOf<'_>,
    body: &BodyIndex,
    scratch: &mut HeightField,
    hints: &mut CheckHints,
) -> bool {
    let all = feather_triangles(frame, shape, pose);
    let mine = FeatherBoxes::of_flat_part(&segment_triangles(&all, shape, segment), frame, shape, pose);
    boxes_clear(&mine, frame, shape, pose, obstacles, body, scratch, true, hints)
}

/// The triangles of segment `segment` of a segmented feather, from its
/// triangles in the order of [`feather_triangles`] (per vane, the fans of
/// its [`ShaftPlan`](crate::feather::ShaftPlan) from the root).
fn segment_triangles(all: &[[Vec3; 3]], shape: &FeatherShape, segment: usize) -> FeatherTriangles {
    let plan = shape.shaft_plan();
    let per_vane = plan.triangles_per_vane();
    let start = if segment == 0 { 0 } else { plan.triangles_per_vane_up_to(segment - 1) };
    let end = plan.triangles_per_vane_up_to(segment);
    let n = end - start;
    let mut part = [[Vec3::ZERO; 3]; MAX_TRIANGLES];
    part[..n].copy_from_slice(&all[start..end]);
    part[n..2 * n].copy_from_slice(&all[per_vane + start..per_vane + end]);
    FeatherTriangles::from_slice(&part[..2 * n])
}

/// The straight feather's pose (all joints unbent): the three steps on the
/// height field, each pose checked exactly, shortening where no pose fits.
#[allow(clippy::too_many_arguments)]
fn straight_pose(
    frame: &RootFrame,
    shape: &FeatherShape,
    previous: FeatherPose,
    obstacles: &[ObstacleFeather],
    boxes: BoxesOf<'_>,
    body: &BodyIndex,
    params: &AdjustParams,
    steps: AdjustSteps,
    scratch: &mut HeightField,
) -> AdjustOutcome {
    scratch.set_resolution(params.height_field_u, params.height_field_v);
    let collision_tests = fill_field(scratch, frame, shape, obstacles, body, params, false);
    // The height field is conservative but coarse, and blind to what it
    // leaves out (skin facing away, such as a wing hanging over the body;
    // feathers of the opposite skin). So every chosen pose is checked with
    // the exact tests of the validation against the obstacles and the
    // body. A feather that would have to stand steeper than the pitch
    // limit, or fails the check, is shortened instead, largest size first.
    // Down to `REFILL_BELOW` the filled field serves as it is (the shorter
    // kite covers a subset of it, and the root socket stays within the
    // validation's allowance); smaller sizes are rasterised again over
    // their own footprint.
    //
    // At each size the steps first judge the cells near the root at
    // `RELAXED_JUDGE_FRACTION` of the length (see there) and keep that
    // pose if it passes the exact check; only if not are they run again
    // with the conservative `JUDGE_FRACTION` of the height field.
    let mut filled_length = shape.length;
    let mut sizes = SHRINK_STEPS.iter().copied().filter(|&s| s >= params.min_scale);
    let mut scale = 1.0;
    let mut last = FeatherPose::new(params.max_pitch, 0.0);
    let mut hints = CheckHints::default();
    let found = 'sizes: loop {
        for judge in [RELAXED_JUDGE_FRACTION, JUDGE_FRACTION] {
            scratch.set_judge_fraction(judge, filled_length);
            let mut choice = choose_pose(scratch, previous, params, steps);
            choice.pose.scale = scale;
            last = choice.pose;
            let relaxed = judge != JUDGE_FRACTION;
            // The conservative judging demands at least the relaxed pitch
            // of every cell, so after a relaxed pose too steep for the limit
            // it would stand too steep as well; go to the next size. (Not a
            // proof once roll enters: the five test models' poses are the
            // same with and without the retry; 3.9 % fewer instructions.)
            if relaxed && choice.too_steep {
                break;
            }
            if !choice.too_steep && exact_check(frame, shape, choice.pose, boxes, body, scratch, relaxed, &mut hints) {
                if scale == 1.0 {
                    return AdjustOutcome { pose: choice.pose, collision_tests, clamped: choice.clamped };
                }
                break 'sizes Some(choice);
            }
        }
        let Some(next) = sizes.next() else { break None };
        scale = next;
        let small = shape.scaled(scale);
        if scale < REFILL_BELOW {
            fill_field(scratch, frame, &small, obstacles, body, params, true);
            filled_length = small.length;
        } else {
            scratch.shape = small;
        }
    };
    // The height field found no clear pose at full size. Its lid semantics
    // (everything under an obstacle's top is solid) and its rounding are
    // the usual cause: at a wing root the body's feathers hover over the
    // root, and a feather could tuck under them; in a crease the rasterised
    // wall stands higher than the skin. So before shortening the feather
    // further, or leaving it out when no size fits (a root deep in a crease,
    // the rim of a blade-thin part), the exact checks alone look for the
    // lowest clear pitch, unrolled, at each larger size (see
    // [`exact_pitch_sweep`]). A shortened feather only gives way to a
    // larger one lying at most `SWEEP_MAX_PITCH` (standing higher, it would
    // cover less than the shorter one lying flatter); a feather that would
    // be left out takes any pitch up to the limit.
    let (smallest, max_pitch) = match found {
        Some(choice) => (choice.pose.scale, SWEEP_MAX_PITCH.min(params.max_pitch)),
        None => (0.0, params.max_pitch),
    };
    if let Some(pose) = exact_pitch_sweep(frame, shape, params, boxes, body, scratch, smallest, max_pitch, &mut hints) {
        return AdjustOutcome { pose, collision_tests, clamped: pose.scale < 1.0 };
    }
    match found {
        Some(choice) => AdjustOutcome { pose: choice.pose, collision_tests, clamped: choice.clamped },
        None => AdjustOutcome { pose: FeatherPose { scale: 0.0, ..last }, collision_tests, clamped: true },
    }
}

/// Pitches tried by [`exact_pitch_sweep`], from the lowest allowed up to
/// the highest, in even steps (3.9° with the default limits).
const SWEEP_PITCHES: usize = 24;
/// The highest pitch (radians, about 34°) at which the exact sweep may
/// replace a shortened feather by a larger one. Measured (coverage of
/// Flamingo, bird, torus): without the sweep for shortened feathers
/// 0.875, 0.853, 0.981; up to 0.4 rad 0.887, 0.872, 0.987; up to 0.6 rad
/// 0.891, 0.871, 0.989; up to the limit (1.1 rad) 0.890, 0.867, 0.989.
const SWEEP_MAX_PITCH: f32 = 0.6;

/// The first pose clear by the exact check alone (and clear of the
/// obstacles' tops, see [`raised_top`]), trying the sizes of
/// `SHRINK_STEPS` larger than `smallest` (from full size), and at each
/// the pitches from the lowest allowed up to `max_pitch` in the steps of
/// `SWEEP_PITCHES`, unrolled.
///
/// Measured: of the feathers the height field left out (Flamingo ~130,
/// mostly at the wing roots), most find a pose this way; coverage rose
/// from 0.848 to 0.875 on the Flamingo, 0.959 to 0.981 on the torus, 0.850
/// to 0.853 on the bird, with 0 intersecting pairs and penetrations.
#[allow(clippy::too_many_arguments)]
fn exact_pitch_sweep(
    frame: &RootFrame,
    shape: &FeatherShape,
    params: &AdjustParams,
    boxes: BoxesOf<'_>,
    body: &BodyIndex,
    scratch: &mut HeightField,
    smallest: f32,
    max_pitch: f32,
    hints: &mut CheckHints,
) -> Option<FeatherPose> {
    let sizes = std::iter::once(1.0).chain(SHRINK_STEPS.iter().copied().filter(|&s| s >= params.min_scale));
    let mut within = std::mem::take(&mut scratch.sweep_obstacles);
    let mut found = None;
    'sizes: for scale in sizes.take_while(|&s| s > smallest) {
        let near = boxes.within_reach(frame, &shape.scaled(scale), &mut within);
        for k in 0..=SWEEP_PITCHES {
            let t = k as f32 / SWEEP_PITCHES as f32;
            let pitch = params.min_pitch + t * (params.max_pitch - params.min_pitch);
            if pitch > max_pitch {
                break;
            }
            let pose = FeatherPose { pitch, roll: 0.0, scale, bends: [0.0; MAX_JOINTS] };
            if exact_check(frame, shape, pose, near, body, scratch, true, hints) {
                found = Some(pose);
                break 'sizes;
            }
        }
    }
    scratch.sweep_obstacles = within;
    found
}

/// Where an obstacle must reach to matter to [`adjust_feather`] for one
/// feather, at any size it may be given (≤ its shape) and any pose. An
/// obstacle, bounded by a sphere, matters when it may be rasterised (it
/// meets the column over the grid, from the lowest floor up) or may meet
/// the posed feather in the exact check (it meets the ball around the root
/// that holds the kite at every pitch and roll). Leaving out the others
/// changes nothing: [`HeightField::add_obstacle`] would reject them and the
/// exact test cannot find an intersection. The tests keep a margin far
/// above f32 rounding, so a doubtful case is kept.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ObstacleReach {
    frame: RootFrame,
    far: f32,
    half_span: f32,
    floor: f32,
    ball: f32,
    margin: f32,
}

impl ObstacleReach {
    /// The reach of feather `shape` at `frame` under `params`.
    pub(crate) fn new(frame: &RootFrame, shape: &FeatherShape, params: &AdjustParams) -> Self {
        let grid = GridExtent::new(shape, params.height_field_u, params.height_field_v, params.min_pitch);
        // Shorter sizes lie in the same column (x ≥ 0 covers every root
        // socket) above the full size's floor, which is the lowest.
        let ball = shape.kite_corners().iter().map(|c| c.length()).fold(0.0f32, f32::max);
        let margin = 1e-4 * (grid.far + grid.half_span - grid.floor) + 1e-5 * frame.position.abs().max_element();
        Self { frame: *frame, far: grid.far, half_span: grid.half_span, floor: grid.floor, ball, margin }
    }

    /// Whether an obstacle inside the sphere (`centre`, `radius`), whose
    /// top lies `thickness` above it, may matter: `None` when it cannot,
    /// else whether it may be rasterised (`false`: only the exact check
    /// can meet it). NaN input is kept whole.
    #[inline]
    pub(crate) fn may_matter(&self, centre: Vec3, radius: f32, thickness: f32) -> Option<bool> {
        let m = self.margin + 1e-5 * (radius + centre.abs().max_element());
        let d = centre - self.frame.position;
        let c = Vec3::new(d.dot(self.frame.tangent), d.dot(self.frame.binormal), d.dot(self.frame.normal));
        let out_of_column = c.x + radius < -m
            || c.x - radius > self.far + m
            || c.y.abs() - radius > self.half_span + m
            || c.z + radius + thickness.max(0.0) < self.floor - m;
        let out_of_ball = d.length() > self.ball + radius + m;
        (!(out_of_column && out_of_ball)).then_some(!out_of_column)
    }
}

/// A sphere around a feather's triangles: centre and radius. For the kite
/// the centre is the mean of its four corners; for a segmented feather the
/// mean of every triangle corner.
pub(crate) fn bounding_sphere(triangles: &[[Vec3; 3]]) -> (Vec3, f32) {
    if let [[root, tip, left], [_, right, _]] = *triangles {
        let centre = 0.25 * (root + tip + left + right);
        let radius = [root, tip, left, right].iter().map(|p| (*p - centre).length()).fold(0.0f32, f32::max);
        return (centre, radius);
    }
    let corners = || triangles.iter().flatten().copied();
    let centre = corners().sum::<Vec3>() / (3 * triangles.len()).max(1) as f32;
    let radius = corners().map(|p| (p - centre).length()).fold(0.0f32, f32::max);
    (centre, radius)
}

/// The exact check of a pose: the feather's triangles meet no obstacle's,
/// and it does not penetrate the body beyond its root socket (the tests of
/// [`crate::validation`]). `scratch` lends its body-query buffers.
#[cfg(test)]
pub(crate) fn pose_is_clear(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    obstacles: &[ObstacleFeather],
    body: &BodyIndex,
    scratch: &mut HeightField,
) -> bool {
    let boxes: Vec<ObstacleBoxes> = obstacles.iter().map(|o| ObstacleBoxes::new(&o.triangles, o.thickness)).collect();
    pose_is_clear_boxed(frame, shape, pose, BoxesOf { ids: None, all: &boxes }, body, scratch)
}

/// [`pose_is_clear`] with the obstacles' [`ObstacleBoxes`] made already.
pub(crate) fn pose_is_clear_boxed(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    boxes: BoxesOf<'_>,
    body: &BodyIndex,
    scratch: &mut HeightField,
) -> bool {
    exact_check(frame, shape, pose, boxes, body, scratch, false, &mut CheckHints::default())
}

/// What made the last exact checks of one feather fail: the obstacle and
/// body triangle tested first by the next check (poses a little apart
/// mostly fail on the same one). Only the order of the tests depends on
/// them, never an answer.
#[derive(Clone, Copy, Debug, Default)]
struct CheckHints {
    obstacle: Option<usize>,
    top: Option<usize>,
    body: Option<u32>,
}

/// An obstacle as the exact checks meet it: its triangles and its
/// [`raised_top`] with their boxes. The adjuster makes them once per posed
/// feather, for every feather it is an obstacle of.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ObstacleBoxes {
    triangles: BoxedTriangles,
    top: BoxedTriangles,
}

impl ObstacleBoxes {
    /// The boxes of an obstacle with these triangles and thickness.
    pub(crate) fn new(triangles: &[[Vec3; 3]], thickness: f32) -> Self {
        let top = raised_top(triangles, thickness);
        Self { triangles: BoxedTriangles::new(triangles), top: BoxedTriangles::new(&top) }
    }
}

/// The [`ObstacleBoxes`] of one feather's obstacles: obstacle k's are
/// `all[ids[k]]`, or `all[k]` without `ids`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxesOf<'a> {
    pub(crate) ids: Option<&'a [u32]>,
    pub(crate) all: &'a [ObstacleBoxes],
}

impl<'a> BoxesOf<'a> {
    /// Those whose triangles' or top's box meets the box around the ball
    /// about the root that holds `shape` (a size of the feather at
    /// `frame`) at any pose, listed into `within`: no other can meet the
    /// posed feather's box, so leaving them out changes no answer (only
    /// the positions the check hints refer to). The ball is widened far
    /// beyond the rounding of the posed corners.
    fn within_reach<'b>(&self, frame: &RootFrame, shape: &FeatherShape, within: &'b mut Vec<u32>) -> BoxesOf<'b>
    where
        'a: 'b,
    {
        let reach = shape.kite_corners().iter().map(|c| c.length()).fold(0.0f32, f32::max);
        let radius = reach * (1.0 + 1e-3) + 1e-5 * frame.position.abs().max_element();
        let ball = Aabb::around(frame.position, radius);
        within.clear();
        within.extend((0..self.len()).filter_map(|k| {
            let b = self.get(k);
            let index = self.ids.map_or(k as u32, |ids| ids[k]);
            (b.triangles.bounds().overlaps(&ball) || b.top.bounds().overlaps(&ball)).then_some(index)
        }));
        BoxesOf { ids: Some(within), all: self.all }
    }

    fn len(&self) -> usize {
        self.ids.map_or(self.all.len(), <[u32]>::len)
    }

    #[inline]
    fn get(&self, k: usize) -> &ObstacleBoxes {
        match self.ids {
            Some(ids) => &self.all[ids[k] as usize],
            None => &self.all[k],
        }
    }
}

/// Whether `test` holds for some index below `n`, trying `hint` first and
/// setting it to the one found.
fn any_index(n: usize, hint: &mut Option<usize>, test: impl Fn(usize) -> bool) -> bool {
    if hint.is_some_and(|k| k < n && test(k)) {
        return true;
    }
    match (0..n).position(test) {
        Some(k) => {
            *hint = Some(k);
            true
        }
        None => false,
    }
}

/// Whether the feather (`mine`) meets some obstacle, or with `top` some
/// obstacle's [`raised_top`], trying `hint` first and setting it to the
/// one found.
fn meets_obstacle(mine: &FeatherBoxes, boxes: BoxesOf<'_>, top: bool, hint: &mut Option<usize>) -> bool {
    any_index(boxes.len(), hint, |k| {
        let b = boxes.get(k);
        mine.intersects_boxed(if top { &b.top } else { &b.triangles })
    })
}

/// [`pose_is_clear`], and with `tops` also clear of every [`raised_top`]
/// (last: most poses that fail, fail before it; testing the tops before
/// the body took 3 % more instructions in `adjust_feather` on the
/// Flamingo bench).
#[allow(clippy::too_many_arguments)]
fn exact_check(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    obstacles: BoxesOf<'_>,
    body: &BodyIndex,
    scratch: &mut HeightField,
    tops: bool,
    hints: &mut CheckHints,
) -> bool {
    let mine = FeatherBoxes::of_feather(frame, shape, pose);
    boxes_clear(&mine, frame, shape, pose, obstacles, body, scratch, tops, hints)
}

/// The exact tests of [`exact_check`] on triangles (`mine`, the whole
/// feather at `pose` or a part of it): no obstacle met, no crossing of the
/// body beyond the root socket, and with `tops` no obstacle's raised top
/// met.
#[allow(clippy::too_many_arguments)]
fn boxes_clear(
    mine: &FeatherBoxes,
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    obstacles: BoxesOf<'_>,
    body: &BodyIndex,
    scratch: &mut HeightField,
    tops: bool,
    hints: &mut CheckHints,
) -> bool {
    if meets_obstacle(mine, obstacles, false, &mut hints.obstacle) {
        return false;
    }
    let (part, ids) = (&mut scratch.check_part, &mut scratch.body_ids);
    if mine.penetrates_body(frame, shape, pose, body, part, ids, &mut hints.body) {
        return false;
    }
    !(tops && meets_obstacle(mine, obstacles, true, &mut hints.top))
}

/// An obstacle's top: its two triangles raised by its thickness along
/// their own normals (away from the skin they grow from). A feather clear
/// of every obstacle's top (tested in [`exact_check`]) and passing
/// [`pose_is_clear`] stays out of the slab an obstacle fills, except for
/// parts that end inside it.
fn raised_top(triangles: &[[Vec3; 3]], thickness: f32) -> FeatherTriangles {
    let raise = |t: &[Vec3; 3]| {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero() * thickness;
        [t[0] + n, t[1] + n, t[2] + n]
    };
    let mut top = FeatherTriangles::from_slice(triangles);
    for (t, raised) in top.iter_mut().zip(triangles.iter().map(raise)) {
        *t = raised;
    }
    top
}

/// Clears `field` over `shape`'s footprint and rasterises the obstacles and
/// the body near the root. Returns the obstacles that touched it. A
/// `refill` (a smaller size of the same feather, at the same frame)
/// reuses the obstacles' local triangles of the first fill.
fn fill_field(
    field: &mut HeightField,
    frame: &RootFrame,
    shape: &FeatherShape,
    obstacles: &[ObstacleFeather],
    body: &BodyIndex,
    params: &AdjustParams,
    refill: bool,
) -> u32 {
    field.reset(shape, params.min_pitch);
    let near = || obstacles.iter().filter(|o| !o.far_side);
    let mut local = std::mem::take(&mut field.local_obstacles);
    if !refill {
        let map = LocalMap::new(frame);
        local.clear();
        local.extend(near().map(|o| map.triangles(&o.triangles)));
    }
    let mut collision_tests = 0u32;
    for (l, o) in local.iter().zip(near()) {
        if field.add_local_obstacle(l, o.thickness) {
            collision_tests += 1;
        }
    }
    field.local_obstacles = local;
    field.add_body(frame, body);
    collision_tests
}

/// What the steps chose for one feather size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PoseChoice {
    /// The pose (full size; the caller sets the scale).
    pub(crate) pose: FeatherPose,
    /// Whether a pitch or roll limit bound.
    pub(crate) clamped: bool,
    /// Whether the feather needs more than the highest pitch to clear
    /// everything (before any fluffiness).
    pub(crate) too_steep: bool,
}

/// Runs the steps on a filled field, for the field's shape.
pub(crate) fn choose_pose(
    field: &mut HeightField,
    previous: FeatherPose,
    params: &AdjustParams,
    steps: AdjustSteps,
) -> PoseChoice {
    let (p_lo, p_hi) = (params.min_pitch.tan(), params.max_pitch.tan());
    let max_roll = params.max_roll.abs();
    let mut clamped = false;
    // Step 1 (Full only): pitch with the feather unrolled.
    let step1 = match steps {
        AdjustSteps::Full => {
            field.combine_heights(params, 0.0);
            let m = field.min_pitch_slope(0.0, p_lo, p_hi);
            clamped |= m.bound;
            Some(m)
        }
        AdjustSteps::FinePitchOnly => None,
    };
    // Step 2: roll towards balanced free volume under the vanes, as far as
    // that lowers the feather without lifting any part (Full), or keep the
    // previous roll (FinePitchOnly).
    let roll = match step1 {
        Some(m) => {
            let (q, p2, bound2) = field.settling_lateral_slope(m.p, m.binding, max_roll.tan());
            clamped |= bound2;
            (q / (1.0 + p2 * p2).sqrt()).atan()
        }
        None => previous.roll,
    };
    let roll = if roll.is_finite() { roll } else { 0.0 };
    if roll.abs() > max_roll {
        clamped = true;
    }
    let mut roll = roll.clamp(-max_roll, max_roll);
    // Step 3: fine pitch with the roll fixed (with the collision allowance).
    // Unrolled and with nothing to sink into, it is step 1 again.
    let allowance = params.collision_allowance.max(0.0) * field.shape.thickness;
    let mut m3 = match step1 {
        Some(m) if roll == 0.0 && allowance == 0.0 => m,
        _ => {
            field.combine_heights(params, allowance);
            field.min_pitch_slope(roll, p_lo, p_hi)
        }
    };
    // Re-check of step 2: step 2 worked from an estimate; if the re-pitched
    // feather lifts a vane corner above the unrolled one after all, halve
    // the roll (twice at most), else drop it.
    if let Some(m1) = step1 {
        let unrolled = field.highest_corner(m1.p, 0.0);
        let mut tries = 0;
        while roll != 0.0 && field.highest_corner(m3.p, roll) > unrolled {
            tries += 1;
            roll = if tries > 2 { 0.0 } else { 0.5 * roll };
            m3 = field.min_pitch_slope(roll, p_lo, p_hi);
        }
    }
    clamped |= m3.bound;
    let p3 = m3.p;
    let pitch = p3.atan() + params.fluffiness.max(0.0);
    if pitch > params.max_pitch {
        clamped = true;
    }
    let pitch = pitch.clamp(params.min_pitch, params.max_pitch);
    PoseChoice { pose: FeatherPose::new(pitch, roll), clamped, too_steep: m3.steep }
}

impl HeightField {
    /// Fills `need`: per cell the height the feather must clear, the higher
    /// of the body (plus the clearance angle, taken at the cell's near edge) and the obstacle tops (plus the
    /// clearance, minus `allowance`). Cells with nothing get `EMPTY` (−∞),
    /// which no pitch violates.
    pub(crate) fn combine_heights(&mut self, params: &AdjustParams, allowance: f32) {
        let floor = self.floor;
        let body_slope = params.body_clearance_angle.max(0.0).tan();
        let obstacle_lift = params.clearance.max(0.0) * self.shape.thickness - allowance;
        // Unchanged layers (the same fill judged again, or a shorter size
        // on it) combine to the same heights.
        let key = (body_slope, obstacle_lift);
        if self.need_for.is_some_and(|k| k.0.to_bits() == key.0.to_bits() && k.1.to_bits() == key.1.to_bits()) {
            return;
        }
        self.need_for = Some(key);
        let u = self.u;
        // The clearance angle is measured from the cell's near edge (not
        // before `clearance_from`), not from the distance the steps judge
        // at: judging farther out must only ever relax a requirement, and
        // where the skin falls away (a negative height) a farther distance
        // would add clearance instead.
        let (far, from, dx) = (&self.col_far[..u], self.clearance_from, self.dx);
        for j in 0..self.v {
            let r = j * u..(j + 1) * u;
            let (need, body, obstacle) = (&mut self.need[r.clone()], &self.body[r.clone()], &self.obstacle[r]);
            for i in 0..u {
                // Both sides computed first, then selected: keeps it branch-free.
                let (b, o) = (body[i], obstacle[i]);
                let near = max_f(far[i] - dx, from);
                let (b_need, o_need) = (b + near * body_slope, o + obstacle_lift);
                let b_need = if b > floor { b_need } else { EMPTY };
                let o_need = if o > floor { o_need } else { EMPTY };
                need[i] = if b_need > o_need { b_need } else { o_need };
            }
        }
    }

    /// The shaft interval `[xa, xb]` of the flat kite where its half width
    /// is at least `a` (`a ≤ 0`: the whole shaft; empty as `xa > xb`).
    fn kite_interval(&self, a: f32) -> [f32; 2] {
        let s = &self.shape;
        let half = 0.5 * s.width;
        if a <= 0.0 {
            return [0.0, s.length];
        }
        if a > half {
            return [1.0, 0.0];
        }
        let corner = s.vane_split * s.length;
        [a / half * corner, s.length - a / half * (s.length - corner)]
    }

    /// Step 1 and 3: the smallest slope `p = tan α ≥ p_lo` at which the
    /// kite rolled by `roll` clears every cell it covers. `bound` is set
    /// when no pitch up to `p_hi` is clear (`p = p_hi` then) or when `p_lo`
    /// itself is clear (the lower limit binds).
    ///
    /// Per row, the covered columns form one run (the kite's shaft
    /// coordinate grows along the row). Near the root the kite is narrower
    /// than the row, so those cells are judged on the part of the row the
    /// kite can reach; beyond, the whole row is under the kite and the
    /// lateral term is the same for every cell, so a cell's requirement is
    /// `(h − lateral) / edge` and the row's largest one is found in a loop
    /// the compiler vectorises. Only cells whose requirement beats the
    /// running maximum are revisited for the tip-exit threshold.
    pub(crate) fn min_pitch_slope(&mut self, roll: f32, p_lo: f32, p_hi: f32) -> MinPitch {
        let (sb, cb) = roll.sin_cos();
        let tb = sb / cb;
        let (half_dx, half_dy) = (0.5 * self.dx, 0.5 * self.dy);
        // Row spans in kite coordinates, widened by half a cell across.
        for j in 0..self.v {
            let a = self.row_y[j].abs() / cb - half_dy / cb;
            self.row_span[j] = self.kite_interval(a);
        }
        let half_width_cb = 0.5 * self.shape.width * cb;
        let rise_cb = 0.5 * self.shape.width / (self.shape.vane_split * self.shape.length) * cb;
        let (u, first, inv_dx) = (self.u, self.first_col, 1.0 / self.dx);
        let mut p = p_lo;
        let mut binding = None;
        for jump in 0..MAX_JUMPS {
            let sec = (1.0 + p * p).sqrt();
            let q = tb * sec;
            // Half a cell in kite shaft coordinates.
            let mx = half_dx * sec + (sb * p).abs() * half_dy / cb;
            let mut need = p;
            let mut need_cell = None;
            for j in 0..self.v {
                let [xa, xb] = self.row_span[j];
                if xa > xb {
                    continue;
                }
                let (xa, xb) = (xa - mx, xb + mx);
                let y = self.row_y[j];
                let k = y / cb * sb;
                // Covered columns: x0 = x·sec + k·p within [xa, xb].
                let col = |x0: f32| ((x0 - k * p) / sec) * inv_dx - 0.5;
                let i_lo = ceil_i32(col(xa)).max(first as i32);
                let i_hi = floor_i32(col(xb)).min(u as i32 - 1);
                if i_lo > i_hi {
                    continue;
                }
                let (i_lo, i_hi) = (i_lo as usize, i_hi as usize);
                // From i_full on the kite spans the whole row.
                let y_out = y.abs() + half_dy;
                let shear_rise = (sb * p).abs() * y_out / cb * rise_cb;
                let i_full = if half_width_cb < y_out {
                    i_hi + 1
                } else {
                    let far = (y_out - shear_rise) / (sec * rise_cb);
                    (i_lo..=i_hi).find(|&i| self.col_far[i] >= far).unwrap_or(i_hi + 1)
                };
                let row = j * u;
                let ctx = CellContext { p, q, k, xb, y, half_dy, sec, rise_cb, shear_rise, half_width_cb };
                for i in i_lo..i_full.min(i_hi + 1) {
                    if let Some((t, p_req)) = self.clipped_cell_threshold(&ctx, i, row + i, need) {
                        need = t;
                        need_cell = Some(Binding { cell: (row + i) as u32, clears: t == p_req });
                    }
                }
                if i_full > i_hi {
                    continue;
                }
                let lateral = min_f(q * (y - half_dy), q * (y + half_dy));
                let run = i_full..i_hi + 1;
                let best = max_requirement(
                    &self.need[row + run.start..row + run.end],
                    &self.inv_near[run.clone()],
                    &self.inv_far[run.clone()],
                    lateral,
                );
                if best <= need {
                    continue;
                }
                for i in run {
                    let n = self.need[row + i] - lateral;
                    let p_req = n * if n > 0.0 { self.inv_near[i] } else { self.inv_far[i] };
                    if p_req > need {
                        let t = cell_threshold(p, p_req, self.col_x[i], k, xb);
                        if t > need {
                            need = t;
                            need_cell = Some(Binding { cell: (row + i) as u32, clears: t == p_req });
                        }
                    }
                }
            }
            if need <= p {
                return MinPitch { p, bound: jump == 0, steep: false, binding };
            }
            if need > p_hi {
                return MinPitch { p: p_hi, bound: true, steep: true, binding: None };
            }
            binding = need_cell;
            p = need.max(p + 1e-6 * (1.0 + p.abs()));
        }
        MinPitch { p: p.min(p_hi), bound: true, steep: true, binding: None }
    }

    /// The requirement `p_req` of a cell near the root, where the kite is
    /// narrower than the cell's row: the lowest point of the kite over the
    /// cell lies on the part of the row within the kite's widest
    /// half-width over the cell's shaft range. `None` when the kite misses
    /// the cell or the cell is empty.
    #[inline]
    fn clipped_requirement(&self, c: &CellContext, i: usize, cell: usize) -> Option<(f32, f32)> {
        let h = self.need[cell];
        let reach = min_f(self.col_far[i] * c.sec * c.rise_cb + c.shear_rise, c.half_width_cb);
        let (y_lo, y_hi) = (max_f(c.y - c.half_dy, -reach), min_f(c.y + c.half_dy, reach));
        if y_lo > y_hi || h == EMPTY {
            return None;
        }
        let lateral = min_f(c.q * y_lo, c.q * y_hi);
        let n = h - lateral;
        Some((n * if n > 0.0 { self.inv_near[i] } else { self.inv_far[i] }, lateral))
    }

    /// The threshold of a clipped cell and its requirement, if the
    /// threshold beats `need`.
    #[inline]
    fn clipped_cell_threshold(&self, c: &CellContext, i: usize, cell: usize, need: f32) -> Option<(f32, f32)> {
        let (p_req, _) = self.clipped_requirement(c, i, cell)?;
        if p_req <= need {
            return None;
        }
        let t = cell_threshold(c.p, p_req, self.col_x[i], c.k, c.xb);
        (t > need).then_some((t, p_req))
    }

    /// Height above the tangent plane of the higher vane corner at pitch
    /// slope `p` and roll `roll`.
    pub(crate) fn highest_corner(&self, p: f32, roll: f32) -> f32 {
        let pose = FeatherPose::new(p.atan(), roll);
        let [_, _, left, right] = self.shape.kite_corners().map(|c| pose.apply_local(c));
        left.z.max(right.z)
    }

    /// The lateral slope `q` that balances the free volume under the two
    /// vanes of the unrolled feather at slope `p` (free height per covered
    /// cell, capped at half the width). The +y vane's volume grows with `q`
    /// and the −y vane's shrinks, so the balance is linear in `q`.
    pub(crate) fn balancing_lateral_slope(&self, p: f32) -> f32 {
        let sec = (1.0 + p * p).sqrt();
        let cap = FREE_HEIGHT_CAP_PER_WIDTH * self.shape.width;
        let (mut free_pos, mut free_neg, mut arm_pos, mut arm_neg) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for j in 0..self.v {
            let y = self.row_y[j];
            let [xa, xb] = self.kite_interval(y.abs());
            let Some(run) = self.covered_columns(xa, xb, sec, 0) else { continue };
            let cells = j * self.u + run.start..j * self.u + run.end;
            let mut free = 0.0f32;
            for ((&x, &b), &o) in
                self.col_x[run.clone()].iter().zip(&self.body[cells.clone()]).zip(&self.obstacle[cells])
            {
                let top = if b > o { b } else { o };
                let f = x * p - top;
                free += if f < 0.0 {
                    0.0
                } else if f > cap {
                    cap
                } else {
                    f
                };
            }
            let arm = y.abs() * run.len() as f32;
            if y > 0.0 {
                free_pos += free;
                arm_pos += arm;
            } else {
                free_neg += free;
                arm_neg += arm;
            }
        }
        let arm = arm_pos + arm_neg;
        if arm <= 0.0 || arm.is_nan() {
            return 0.0;
        }
        (free_neg - free_pos) / arm
    }

    /// The columns (from `first` on) whose centres' shaft coordinate
    /// `x·sec` lies in `[xa, xb]`, or `None`.
    #[inline]
    fn covered_columns(&self, xa: f32, xb: f32, sec: f32, first: usize) -> Option<std::ops::Range<usize>> {
        if xa > xb {
            return None;
        }
        let inv = 1.0 / (sec * self.dx);
        let lo = ceil_i32(xa * inv - 0.5).max(first as i32);
        let hi = floor_i32(xb * inv - 0.5).min(self.u as i32 - 1);
        (lo <= hi).then(|| lo as usize..hi as usize + 1)
    }

    /// Step 2. Rolling tips one vane up and the other down. The roll is
    /// chosen to balance the free volume under the two vanes, but only as
    /// far as the rolled feather, re-pitched, lies nowhere above the
    /// unrolled one: the feather pivots down onto its free side and never
    /// lifts a vane corner above where step 1 put it.
    ///
    /// Why the limit: followers lie over a feather's root region and vane
    /// corners, so a raised corner is a step every later neighbour on that
    /// side must climb. Measured on our test coats (staggered plane, sphere
    /// of 600 and 2400 feathers) the mean pitch was 7.8°, 12.1° and 11.4°
    /// with the limit; letting a corner rise by half a thickness, one, two
    /// or without bound gave 9.3/10.5/12.3/12.8° on the plane and up to
    /// 25° on the sphere (and intersections on a torus once unbounded).
    /// Volume balance alone or "settling" until both vanes bear escalated
    /// further (15–50°). So the roll only ever lowers the surface later
    /// feathers see. A consequence of the kite's shape: the vane corner has
    /// the largest lateral-to-shaft ratio of any covered point, so lowering
    /// the pitch by rolling nearly always lifts the corner; rolls stay
    /// small (tenths of a degree on flat skin, more on saddles and at vane
    /// edges where cell rounding binds) and the step mostly refines.
    ///
    /// The rolled feather needs pitch slope `f(q)` at lateral slope `q`
    /// (the upper envelope of one constraint per covered cell, each linear
    /// in `q` on either side of 0); its kite lies under the unrolled one iff
    /// its corners do: `s·L·f(q) + W/2·|q| ≤ s·L·p1`. On the side of 0
    /// where the volume-balancing roll lies every constraint is linear, so
    /// the allowed rolls there form an interval `[0, q_max]` found in one
    /// pass, and the balancing roll is clamped into it.
    ///
    /// Returns `(q, p, bound)`: the lateral slope, the pitch slope it needs
    /// (an upper estimate from the step-1 coverage, used only to turn `q`
    /// into an angle) and whether `|q|` reached `q_lim`.
    pub(crate) fn settling_lateral_slope(&mut self, p1: f32, binding: Option<Binding>, q_lim: f32) -> (f32, f32, bool) {
        let corner = 0.5 * self.shape.width / (self.shape.vane_split * self.shape.length);
        let q_bal = self.balancing_lateral_slope(p1).clamp(-q_lim, q_lim);
        if q_bal.abs() < MIN_LATERAL_SLOPE {
            return (0.0, p1, false);
        }
        // The cell that set p1 decides whether rolling towards q_bal can
        // lower the feather without lifting a corner: it must lower that
        // cell's requirement faster than it lifts the corner.
        let positive = q_bal > 0.0;
        if let Some(b) = binding.filter(|b| b.clears) {
            let (j, i) = (b.cell as usize / self.u, b.cell as usize % self.u);
            if let Some(line) = self.roll_line(i, j, p1) {
                let slope = if positive { line.c_pos + corner } else { -(line.c_neg - corner) };
                if slope >= 0.0 {
                    return (0.0, p1, false);
                }
            }
        }
        let q = q_bal.signum() * self.roll_limit(p1, positive, corner).min(q_bal.abs());
        let q = if q.abs() < MIN_LATERAL_SLOPE { 0.0 } else { q };
        // Within the limit, f(q) ≤ p1 − corner·|q|: the pitch estimate.
        let p = p1 - corner * q.abs();
        (q, p, q.abs() >= q_lim * (1.0 - 1e-6))
    }

    /// The largest `|q|` on the side of 0 given by `positive` at which the
    /// rolled feather, re-pitched, still lies nowhere above the unrolled
    /// one at slope `p`: each covered cell's constraint `a + c·q` plus the
    /// corner term must stay within `p`. (A cell already above `p` at
    /// `q = 0`, which step 1 should rule out up to rounding, forbids any
    /// roll.)
    fn roll_limit(&self, p: f32, positive: bool, corner: f32) -> f32 {
        let (half_dx, half_dy) = (0.5 * self.dx, 0.5 * self.dy);
        let half_width = 0.5 * self.shape.width;
        let rise = half_width / (self.shape.vane_split * self.shape.length);
        let sec = (1.0 + p * p).sqrt();
        let mx = half_dx * sec;
        let slack = 1e-6 * (1.0 + p.abs());
        let mut limit = f32::INFINITY;
        for j in 0..self.v {
            let y = self.row_y[j];
            let [xa, xb] = self.kite_interval(y.abs() - half_dy);
            let Some(run) = self.covered_columns(xa - mx, xb + mx, sec, self.first_col) else { continue };
            let y_out = y.abs() + half_dy;
            for i in run {
                let h = self.need[j * self.u + i];
                if h == EMPTY {
                    continue;
                }
                let reach = min_f(self.col_far[i] * sec * rise, half_width);
                let (y_lo, y_hi) = (max_f(y - half_dy, -reach), min_f(y + half_dy, reach));
                if reach < y_out && y_lo > y_hi {
                    continue;
                }
                let inv = if h > 0.0 { self.inv_near[i] } else { self.inv_far[i] };
                let a = h * inv;
                if a > p + slack {
                    return 0.0;
                }
                // Growth of this cell's constraint per unit |q|.
                let d = if positive { corner - y_lo * inv } else { corner + y_hi * inv };
                if d > 0.0 {
                    let q = max_f(p - a, 0.0) / d;
                    limit = if q < limit { q } else { limit };
                }
            }
        }
        limit
    }

    /// The pitch constraint of cell (i, j) as a function of the lateral
    /// slope, if the unrolled feather at slope `p` covers it and it holds
    /// something.
    #[inline]
    fn roll_line(&self, i: usize, j: usize, p: f32) -> Option<RollLine> {
        let h = self.need[j * self.u + i];
        if h == EMPTY || i < self.first_col {
            return None;
        }
        let (half_dx, half_dy) = (0.5 * self.dx, 0.5 * self.dy);
        let half_width = 0.5 * self.shape.width;
        let rise = half_width / (self.shape.vane_split * self.shape.length);
        let sec = (1.0 + p * p).sqrt();
        let mx = half_dx * sec;
        let y = self.row_y[j];
        let [xa, xb] = self.kite_interval(y.abs() - half_dy);
        let x0 = self.col_x[i] * sec;
        if xa > xb || x0 < xa - mx || x0 > xb + mx {
            return None;
        }
        let reach = min_f(self.col_far[i] * sec * rise, half_width);
        let (y_lo, y_hi) = (max_f(y - half_dy, -reach), min_f(y + half_dy, reach));
        if y_lo > y_hi {
            return None;
        }
        let inv = if h > 0.0 { self.inv_near[i] } else { self.inv_far[i] };
        Some(RollLine { a: h * inv, c_pos: -y_lo * inv, c_neg: -y_hi * inv })
    }
}

/// The larger of two values (plain comparison: no NaN handling, which
/// costs several instructions in these per-cell loops; inputs are finite).
#[inline(always)]
fn max_f(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The smaller of two values (see [`max_f`]).
#[inline(always)]
fn min_f(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// `need` of a cell with nothing in it: no pitch violates it.
pub(crate) const EMPTY: f32 = f32::NEG_INFINITY;

/// What the cells of one row share during one pass of the pitch search.
struct CellContext {
    p: f32,
    q: f32,
    k: f32,
    xb: f32,
    y: f32,
    half_dy: f32,
    sec: f32,
    rise_cb: f32,
    shear_rise: f32,
    half_width_cb: f32,
}

/// The largest `(h − lateral)/edge` over a run of cells (edge: near edge
/// when positive, far edge otherwise); empty cells give −∞. Plain
/// comparisons so that it vectorises.
#[inline]
fn max_requirement(need: &[f32], inv_near: &[f32], inv_far: &[f32], lateral: f32) -> f32 {
    let mut best = f32::NEG_INFINITY;
    for ((&h, &a), &b) in need.iter().zip(inv_near).zip(inv_far) {
        let n = h - lateral;
        let r = n * if n > 0.0 { a } else { b };
        if r > best {
            best = r;
        }
    }
    best
}

/// The pitch a covered cell demands as a function of the lateral slope `q`
/// of the rolled feather: `p ≥ a + c·q`, with `c = c_pos` for `q ≥ 0` and
/// `c_neg` for `q < 0` (the cell's lowest corner under the feather changes
/// side with the sign of the roll).
#[derive(Clone, Copy, Debug, PartialEq)]
struct RollLine {
    a: f32,
    c_pos: f32,
    c_neg: f32,
}

/// The result of a minimal-pitch search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct MinPitch {
    /// The pitch slope `tan α`.
    pub(crate) p: f32,
    /// Whether a pitch limit bound.
    pub(crate) bound: bool,
    /// Whether no pitch up to the highest one is clear.
    pub(crate) steep: bool,
    /// The cell that set the final pitch, if one did.
    pub(crate) binding: Option<Binding>,
}

/// The cell that set a minimal pitch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Binding {
    /// Its index `j·u + i`.
    pub(crate) cell: u32,
    /// Whether the feather clears it (rather than its tip leaving it).
    pub(crate) clears: bool,
}

/// The slope at which a violated cell stops being violated: `p_req` (the
/// slope that clears it), or earlier if the tip stops covering it first
/// (shaft coordinate `x·sec α + k·tan α` passing `xb`). Never below `p`.
#[inline]
fn cell_threshold(p: f32, p_req: f32, x: f32, k: f32, xb: f32) -> f32 {
    if p_req <= p {
        return p_req;
    }
    let x0_at_req = x * (1.0 + p_req * p_req).sqrt() + k * p_req;
    if x0_at_req <= xb || x * x <= k * k {
        return p_req;
    }
    // Larger root of (x² − k²) p² + 2 xb k p + (x² − xb²) = 0.
    let disc = xb * xb + k * k - x * x;
    if disc < 0.0 {
        return p_req;
    }
    let exit = (-xb * k + x * disc.sqrt()) / (x * x - k * k);
    exit.clamp(p, p_req)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::feather::feather_triangles;
    use glam::Vec3;

    fn plane_body(size: f32) -> BodyIndex {
        let pos = [
            Vec3::new(-size, -size, 0.0),
            Vec3::new(size, -size, 0.0),
            Vec3::new(size, size, 0.0),
            Vec3::new(-size, size, 0.0),
        ];
        BodyIndex::from_mesh(&pos, &[[0, 1, 2], [0, 2, 3]])
    }

    fn frame_at(x: f32, y: f32) -> RootFrame {
        RootFrame::from_normal_and_direction(Vec3::new(x, y, 0.0), Vec3::Z, Vec3::X).unwrap()
    }

    fn adjust(
        frame: &RootFrame,
        obstacles: &[ObstacleFeather],
        body: &BodyIndex,
        params: &AdjustParams,
    ) -> AdjustOutcome {
        let shape = FeatherShape::for_spacing(1.0);
        let mut field = HeightField::new(params.height_field_u, params.height_field_v);
        adjust_feather(frame, &shape, FeatherPose::default(), obstacles, body, params, AdjustSteps::Full, &mut field)
    }

    #[test]
    fn alone_on_a_plane_the_feather_lies_at_the_body_clearance() {
        let params = AdjustParams::default();
        let out = adjust(&frame_at(0.0, 0.0), &[], &plane_body(10.0), &params);
        assert!((out.pose.pitch - params.body_clearance_angle).abs() < 2e-3, "{:?}", out.pose);
        assert!(out.pose.roll.abs() < 1e-4);
        assert!(!out.clamped);
        assert_eq!(out.collision_tests, 0);
    }

    #[test]
    fn skin_tilted_sideways_rolls_the_feather_onto_it() {
        // The root's normal is +z but the skin rises towards +y (as where an
        // interpolated normal differs from the face normal): rolling lays
        // the feather on the skin instead of pitching it over the slope.
        let params = AdjustParams::default();
        let slope = 0.1;
        let pos = [
            Vec3::new(-10.0, -10.0, -10.0 * slope),
            Vec3::new(10.0, -10.0, -10.0 * slope),
            Vec3::new(10.0, 10.0, 10.0 * slope),
            Vec3::new(-10.0, 10.0, 10.0 * slope),
        ];
        let body = BodyIndex::from_mesh(&pos, &[[0, 1, 2], [0, 2, 3]]);
        let frame = frame_at(0.0, 0.0);
        let shape = FeatherShape::for_spacing(1.0);
        let mut field = HeightField::new(32, 16);
        let mut run =
            |steps| adjust_feather(&frame, &shape, FeatherPose::default(), &[], &body, &params, steps, &mut field).pose;
        let rolled = run(AdjustSteps::Full);
        let flat = run(AdjustSteps::FinePitchOnly);
        assert!(rolled.roll > 0.5 * slope, "{rolled:?}");
        assert!(rolled.pitch < flat.pitch - 0.02, "{rolled:?} vs {flat:?}");
    }

    #[test]
    fn rolling_never_lifts_a_vane_corner() {
        let params = AdjustParams::default();
        let body = plane_body(10.0);
        let shape = FeatherShape::for_spacing(1.0);
        let frame = frame_at(0.0, 0.0);
        let mut rng = crate::rng::Rng::new(21);
        let mut field = HeightField::new(32, 16);
        for _ in 0..40 {
            let obstacles: Vec<ObstacleFeather> = (0..6)
                .map(|_| {
                    let at = frame_at(0.3 + 2.5 * rng.next_f32(), 2.4 * rng.next_f32() - 1.2);
                    let pose = FeatherPose::new(0.2 * rng.next_f32(), 0.2 * rng.next_f32() - 0.1);
                    ObstacleFeather {
                        triangles: feather_triangles(&at, &shape, pose),
                        thickness: shape.thickness,
                        far_side: false,
                    }
                })
                .collect();
            let run = |steps, field: &mut HeightField| {
                adjust_feather(&frame, &shape, FeatherPose::default(), &obstacles, &body, &params, steps, field).pose
            };
            let rolled = run(AdjustSteps::Full, &mut field);
            let flat = run(AdjustSteps::FinePitchOnly, &mut field);
            let corner = |p: FeatherPose| {
                let [_, _, left, right] = shape.kite_corners().map(|c| p.apply_local(c));
                left.z.max(right.z)
            };
            assert!(
                corner(rolled) <= corner(flat) + 0.05 * shape.thickness,
                "{rolled:?} lifts a corner above {flat:?}"
            );
            assert!(rolled.pitch <= flat.pitch + 1e-4);
        }
    }

    #[test]
    fn a_feather_tucks_under_an_obstacle_over_its_root() {
        let params = AdjustParams::default();
        let body = plane_body(10.0);
        let shape = FeatherShape::for_spacing(1.0);
        // A feather hovering right over the root, half a length up: the
        // height field counts everything under its top as solid, so no
        // size lies clear by the field; the exact sweep tucks the feather
        // under it, clear of it and of the skin.
        let mut other = frame_at(-0.5, 0.0);
        other.position.z = 0.3;
        let obstacle = ObstacleFeather {
            triangles: feather_triangles(&other, &shape, FeatherPose::default()),
            thickness: 0.1,
            far_side: false,
        };
        let frame = frame_at(0.0, 0.0);
        let out = adjust(&frame, &[obstacle], &body, &params);
        assert!(out.pose.scale > 0.0 && out.pose.pitch < 0.1, "{:?}", out.pose);
        let mut field = HeightField::new(32, 16);
        assert!(pose_is_clear(&frame, &shape, out.pose, &[obstacle], &body, &mut field));
    }

    #[test]
    fn convex_skin_lets_the_feather_droop_and_concave_skin_lifts_it() {
        let params = AdjustParams::default();
        let shape = FeatherShape::for_spacing(1.0);
        // A cylinder of radius r along y, root on top: convex along the shaft.
        let cylinder = |r: f32, inside: bool| {
            let (n, m) = (128usize, 8usize);
            let mut pos = Vec::new();
            for a in 0..n {
                let t = a as f32 / n as f32 * std::f32::consts::TAU;
                for b in 0..=m {
                    let y = -3.0 + 6.0 * b as f32 / m as f32;
                    pos.push(Vec3::new(r * t.sin(), y, r * t.cos() - r));
                }
            }
            let mut tris = Vec::new();
            for a in 0..n {
                for b in 0..m {
                    let (i0, i1) = ((a * (m + 1) + b) as u32, (((a + 1) % n) * (m + 1) + b) as u32);
                    let t = [[i0, i1, i1 + 1], [i0, i1 + 1, i0 + 1]];
                    for tri in t {
                        tris.push(if inside { [tri[0], tri[2], tri[1]] } else { tri });
                    }
                }
            }
            (BodyIndex::from_mesh(&pos, &tris), pos)
        };
        let mut field = HeightField::new(32, 16);
        let frame = frame_at(0.0, 0.0);
        let (convex, _) = cylinder(1.5, false);
        let out = adjust_feather(
            &frame,
            &shape,
            FeatherPose::default(),
            &[],
            &convex,
            &params,
            AdjustSteps::Full,
            &mut field,
        );
        assert!(out.pose.pitch < 0.0, "convex {:?}", out.pose);
        // Inside a cylinder the root sits at the bottom and the wall rises in front.
        let concave_frame = RootFrame::from_normal_and_direction(Vec3::new(0.0, 0.0, -8.0), Vec3::Z, Vec3::X).unwrap();
        let (concave, _) = cylinder(4.0, true);
        let out = adjust_feather(
            &concave_frame,
            &shape,
            FeatherPose::default(),
            &[],
            &concave,
            &params,
            AdjustSteps::Full,
            &mut field,
        );
        // The wall rises about x²/(2r) ahead: at x = L that is 0.4 L/r·L.
        assert!(out.pose.pitch > 0.3, "concave {:?}", out.pose);
    }

    #[test]
    fn fine_pitch_only_keeps_the_previous_roll() {
        let params = AdjustParams::default();
        let shape = FeatherShape::for_spacing(1.0);
        let mut field = HeightField::new(32, 16);
        let out = adjust_feather(
            &frame_at(0.0, 0.0),
            &shape,
            FeatherPose::new(0.4, 0.1),
            &[],
            &plane_body(10.0),
            &params,
            AdjustSteps::FinePitchOnly,
            &mut field,
        );
        assert_eq!(out.pose.roll, 0.1);
        // The lowered −y vane near the root needs a little pitch on a plane.
        assert!(out.pose.pitch > params.body_clearance_angle && out.pose.pitch < 0.2, "{:?}", out.pose);
    }

    #[test]
    fn fluffiness_adds_lift_and_the_limit_reports() {
        let body = plane_body(10.0);
        let base = adjust(&frame_at(0.0, 0.0), &[], &body, &AdjustParams::default()).pose.pitch;
        let fluffy = adjust(&frame_at(0.0, 0.0), &[], &body, &AdjustParams { fluffiness: 0.2, ..Default::default() });
        assert!((fluffy.pose.pitch - base - 0.2).abs() < 1e-5);
        assert!(!fluffy.clamped);
        let over = adjust(&frame_at(0.0, 0.0), &[], &body, &AdjustParams { fluffiness: 2.0, ..Default::default() });
        assert!(over.clamped && over.pose.pitch == AdjustParams::default().max_pitch);
    }

    #[test]
    fn threshold_of_a_cell_leaving_the_tip() {
        // x = 3, kite ends at xb = 3.2: the tip leaves when 3·sec α = 3.2.
        let exit = cell_threshold(0.0, 10.0, 3.0, 0.0, 3.2);
        assert!((3.0 * (1.0 + exit * exit).sqrt() - 3.2).abs() < 1e-4);
        assert_eq!(cell_threshold(0.0, 0.1, 3.0, 0.0, 3.2), 0.1);
    }

    #[test]
    fn every_segment_of_a_bent_rolled_feather_is_flat() {
        // The plane shortcut of `segment_check` (`FeatherBoxes::of_flat_part`)
        // is sound only if a segment's triangles lie in one plane.
        let shape = FeatherShape::for_spacing(1.0).with_segments(4);
        let frame = RootFrame::from_normal_and_direction(
            Vec3::new(3.0, -2.0, 50.0),
            Vec3::new(0.3, 0.2, 1.0).normalize(),
            Vec3::X,
        )
        .unwrap();
        for (k, &(pitch, roll)) in [(0.3f32, 0.0f32), (-0.2, 0.4), (0.9, -0.5)].iter().enumerate() {
            let mut pose = FeatherPose::new(pitch, roll);
            pose.bends[..3].copy_from_slice(&[0.4 - 0.3 * k as f32, -0.4, 0.25]);
            let all = feather_triangles(&frame, &shape, pose);
            for segment in 0..4 {
                let part = segment_triangles(&all, &shape, segment);
                let margin = posed_margin_for_test(&frame, &shape, pose);
                let plane = crate::validation::FlatPlane::of_flat_triangles(&part, margin).unwrap();
                for t in part.iter() {
                    assert!(
                        !plane.apart(&[t[0], t[0], t[0]])
                            && !plane.apart(&[t[1], t[1], t[1]])
                            && !plane.apart(&[t[2], t[2], t[2]]),
                        "segment {segment} of {pose:?} is not flat"
                    );
                }
                // A point a tenth of a length off the plane is apart.
                let n = (part[0][1] - part[0][0]).cross(part[0][2] - part[0][0]).normalize();
                let off = part[0][0] + n * 0.1 * shape.length;
                assert!(plane.apart(&[off, off, off]));
            }
        }
    }

    fn posed_margin_for_test(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> f32 {
        1e-5 * (frame.position.abs().max_element() + shape.length * pose.scale)
    }
}
