//! The drape of a segmented feather (DESIGN.md §4, bending): from the
//! straight feather's pose, each segment from the root comes down onto
//! what lies beneath it ([`drape`]); and the repair of a bent feather's
//! last pose with as little change as it takes ([`repair_drape`]), which
//! keeps an animated bent coat from popping.

use super::checks::{CheckHints, FeatherInPlace, boxes_clear, exact_check};
use super::height_field::SOCKET_FRACTION;
use super::sweep::{fill_swept_triangles, swept_drape};
use super::{AdjustParams, DrapeRoute, HeightField, ObstacleFeather};

use crate::feather::{FeatherPose, pose_change, segment_triangles};
use crate::validation::FeatherBoxes;

/// Angle steps (radians) of the descent of a segment in [`descent_drape`]; the
/// first contact found is then narrowed by [`DRAPE_BISECTIONS`] halvings
/// (to about 0.4°).
const DRAPE_STEP: f32 = 0.1;
/// Halvings of the last step of a descent.
const DRAPE_BISECTIONS: usize = 4;
/// Descents of one drape before it gives up and keeps the straight pose
/// (each backtrack raises a segment by a [`DRAPE_STEP`]).
const MAX_DRAPE_DESCENTS: usize = 16;
/// Halvings of the raise of an earlier segment that makes room for a later
/// one in [`descent_drape`] (to 0.4 rad / 64, about 0.4°).
const DRAPE_RAISE_BISECTIONS: usize = 6;

/// Drapes a segmented feather (DESIGN.md §4, bending) from its straight
/// pose: the swept drape ([`super::sweep`]) confirmed by one exact check of
/// the whole feather, else the descent by exact checks ([`descent_drape`]).
/// Returns the pose and the way it was found.
pub(super) fn drape(
    at: &FeatherInPlace<'_>,
    obstacles: &[ObstacleFeather],
    straight: FeatherPose,
    params: &AdjustParams,
    scratch: &mut HeightField,
) -> (FeatherPose, DrapeRoute) {
    let gap = params.clearance * at.shape.thickness;
    let skin_slope = params.body_clearance_angle.max(0.0).tan();
    let (local_obstacles, local_body) = (&scratch.local_obstacles, &scratch.local_body);
    fill_swept_triangles(&mut scratch.swept, local_obstacles, local_body, obstacles, straight.roll, gap, skin_slope);
    let sized = at.shape.scaled(straight.scale);
    if let Some(pose) = swept_drape(&scratch.swept, SOCKET_FRACTION, &sized, straight, params)
        && exact_check(at, pose, scratch, true, &mut CheckHints::default())
    {
        return (pose, DrapeRoute::Swept);
    }
    (descent_drape(at, straight, params, scratch), DrapeRoute::Descent)
}

/// The drape by exact checks. The straight pose
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
/// segment after it. The root can rise up to the straight pitch. The raise
/// is bisected rather than stepped so that it follows the geometry
/// continuously (fewer pops under small motions; BENCHMARKS.md, "Bent
/// feathers"). After [`MAX_DRAPE_DESCENTS`] descents, or with no segment
/// able to make room, the feather keeps its straight pose, which was clear.
fn descent_drape(
    at: &FeatherInPlace<'_>,
    straight: FeatherPose,
    params: &AdjustParams,
    scratch: &mut HeightField,
) -> FeatherPose {
    let segments = at.shape.segment_count();
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
            segment_check(at, trial, k, scratch, &mut hints)
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
            (i..=k).all(|j| segment_check(at, trial, j, scratch, &mut hints))
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
    if !exact_check(at, pose, scratch, true, &mut hints) {
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
/// even at its highest angle, or the whole feather fails its exact check,
/// or once the repair must change some angle by more than `most` (radians,
/// see [`pose_change`]; every angle's change only grows as the repair goes
/// on, so such a repair would end further away still).
/// Solving a drape afresh from the straight pose ([`drape`]) finds a clear
/// pose too, but from another start: its bends may differ from the last
/// frame's by tens of degrees (a feather that pops while every pose is
/// clear), where this keeps each angle unless something pushes it up.
pub(crate) fn repair_drape(
    at: &FeatherInPlace<'_>,
    start: FeatherPose,
    most: f32,
    params: &AdjustParams,
    scratch: &mut HeightField,
) -> Option<FeatherPose> {
    let segments = at.shape.segment_count();
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
        if pose_change(&start, &pose) > most {
            return None;
        }
        if segment_check(at, pose, k, scratch, &mut hints) {
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
            // Segment k first: it is the one that met something, and most
            // raises that fail, fail there.
            (0..=k).rev().all(|j| segment_check(at, trial, j, scratch, &mut hints))
        };
        let highest = (0..=k).map(|j| range(j).1 - angle(&base, j)).fold(0.0f32, f32::max);
        let d = ascend(0.0, highest, &mut clear, |d| pose_change(&start, &raised(d)) > most)?;
        pose = raised(d);
    }
    exact_check(at, pose, scratch, true, &mut hints).then_some(pose)
}

/// The lowest angle above `from` (which is not clear) up to `high` at
/// which `clear` holds: [`REPAIR_ASCENT_STEPS`] steps of [`REPAIR_STEP`],
/// the first clear one narrowed by halving; past them, the rest of the way
/// up to `high` bisected. `None` when `high` is not clear, or once an
/// angle that failed is `too_far` (which must hold of every angle above
/// one where it holds): the angle found would lie above it.
fn ascend(from: f32, high: f32, mut clear: impl FnMut(f32) -> bool, too_far: impl Fn(f32) -> bool) -> Option<f32> {
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
        if too_far(failed) {
            return None;
        }
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
            let fits = narrow(below, above, DRAPE_BISECTIONS, &mut clear);
            // A segment left at its very contact (as one lying in the plane
            // of a sheet at its edge can be) flips between clear and not
            // under a rounding error; a little above it, where clear, it
            // stays clear under a rigid motion.
            let kept = (fits + DESCENT_MARGIN).min(above);
            return Some(if kept > fits && clear(kept) { kept } else { fits });
        }
        above = below;
    }
}

/// Radians a descended segment is lifted above its contact where that is
/// clear (a quarter of the step the bisections leave).
const DESCENT_MARGIN: f32 = 0.25 * DRAPE_STEP / (1 << DRAPE_BISECTIONS) as f32;

/// The exact check of segment `segment` (from the root) of a posed
/// feather: its triangles meet no obstacle and no obstacle's raised top,
/// and do not cross the body beyond the root socket. The drape checks each
/// segment as it places it; the segments before it do not move then.
fn segment_check(
    at: &FeatherInPlace<'_>,
    pose: FeatherPose,
    segment: usize,
    scratch: &mut HeightField,
    hints: &mut CheckHints,
) -> bool {
    let (frame, shape) = (at.frame, at.shape);
    let mine = FeatherBoxes::of_flat_part(&segment_triangles(frame, shape, pose, segment), frame, shape, pose);
    boxes_clear(&mine, at, pose, scratch, true, hints)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::feather::{FeatherShape, feather_triangles};
    use crate::geometry::RootFrame;
    use glam::Vec3;

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
                let part = segment_triangles(&frame, &shape, pose, segment);
                assert_eq!(&part[..], &segment_of(&all, &shape, segment)[..], "segment {segment} of {pose:?}");
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

    /// Segment `segment`'s triangles taken from the whole feather's (per
    /// vane, the fans of its plan from the root).
    fn segment_of(all: &[[Vec3; 3]], shape: &FeatherShape, segment: usize) -> Vec<[Vec3; 3]> {
        let plan = shape.shaft_plan();
        let per_vane = plan.triangles_per_vane();
        let start = if segment == 0 { 0 } else { plan.triangles_per_vane_up_to(segment - 1) };
        let end = plan.triangles_per_vane_up_to(segment);
        [&all[start..end], &all[per_vane + start..per_vane + end]].concat()
    }

    fn posed_margin_for_test(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> f32 {
        1e-5 * (frame.position.abs().max_element() + shape.length * pose.scale)
    }
}
