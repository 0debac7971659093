//! Settling (the incremental mode): a readjusted feather moves from its
//! current pose toward its solved pose by at most the settle rate a frame,
//! lifting at once only as far as it must to stay clear, and stops
//! settling once its tip is close to the solved pose's (see
//! [`crate::animation::coherence`] for the measurements behind it).

use super::checks::{BoxesOf, FeatherInPlace, pose_is_clear_boxed};
use super::drape::repair_drape;
use super::{AdjustParams, HeightField};
use crate::body::BodyIndex;
use crate::feather::{FeatherPose, FeatherShape, tip_position, toward};
use crate::geometry::RootFrame;

/// One feather as settling meets it: where it grows, its shape, the
/// adjustment's limits, the body and the settle rate (radians a frame).
#[derive(Clone, Copy)]
pub(super) struct SettlingFeather<'a> {
    pub(super) frame: &'a RootFrame,
    pub(super) shape: &'a FeatherShape,
    pub(super) params: &'a AdjustParams,
    pub(super) body: &'a BodyIndex,
    pub(super) rate: f32,
}

/// A feather settles on toward its solved pose only while its tip stands
/// more than this (in lengths of the feather) above the solved pose's tip.
/// Settling to the very pose would keep a bent coat busy: a drape solved
/// afresh lands elsewhere each frame (its bends jump while its tip stays
/// near), so a feather would be re-solved every frame without arriving.
/// The value: BENCHMARKS.md, "Measurements behind the code's constants".
pub(super) const SETTLED_TIP_GAP: f32 = 0.02;

/// Whether the tip of `pose` stands more than [`SETTLED_TIP_GAP`] above the
/// tip of `solved`, over the root's tangent plane.
pub(super) fn tip_above(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose, solved: FeatherPose) -> bool {
    let height = |p: FeatherPose| (tip_position(frame, shape, p) - frame.position).dot(frame.normal);
    height(pose) > height(solved) + SETTLED_TIP_GAP * shape.length * solved.scale
}

/// Lifts tried, in steps of [`SETTLE_LIFT_STEP`] times the settle rate,
/// when the pose moved toward the solved one by the settle rate is not
/// clear: up to `SETTLE_SMALL_LIFTS` steps before the faster moves toward
/// the solved pose, then up to `SETTLE_LIFTS` (3.6 times the rate above
/// it). More lifts find a clear pose near the current one more often, so
/// fewer feathers fall back to their solved pose and pop (BENCHMARKS.md,
/// "Measurements behind the code's constants").
const SETTLE_LIFTS: usize = 8;
/// See [`SETTLE_LIFTS`]: lifts that keep the change within 2.35 times the rate.
const SETTLE_SMALL_LIFTS: usize = 3;
/// A lift's step, as a multiple of the settle rate. The small lifts and
/// the faster moves stay a little below 2.5 times the rate (5° at the
/// default rate, the default pop threshold): at exactly 2.5 their changes
/// came out a rounding above 5° and counted as pops (BENCHMARKS.md,
/// "Measurements behind the code's constants").
const SETTLE_LIFT_STEP: f32 = 0.45;
/// Faster moves toward the solved pose, as multiples of the settle rate,
/// tried after the small lifts: a bent feather whose joints must turn to
/// clear what lies beneath it (a pitch lift alone does not) reaches a clear
/// pose on the way there (BENCHMARKS.md, "Measurements behind the code's
/// constants").
const SETTLE_FASTER: [f32; 2] = [1.75, 2.4];

/// The pose feather `i` takes on its way from `current` to `solved` (see
/// [`OrderedRun::settle_rate`](super::OrderedRun::settle_rate)): `current`
/// moved toward `solved` by the settle rate, if clear (the exact checks of verification, against its
/// obstacles at their final poses and the body: the standard a feather
/// kept at its pose meets every frame); else, of the poses that change it
/// least, the first clear one: that pose lifted by a few steps of half the
/// rate, `current` itself (it tries again next frame), moved faster toward
/// `solved`, a bent feather's `current` repaired (its joints lifted as
/// little as clears them, see [`repair_drape`]), lifted further; else
/// `solved`, which the solver found clear. The repair is what keeps a bent
/// feather whose nearby poses all fail from taking its freshly draped
/// pose, whose bends can differ by tens of degrees (a pop).
pub(super) fn settled_pose(
    feather: SettlingFeather<'_>,
    current: FeatherPose,
    solved: FeatherPose,
    boxes: BoxesOf<'_>,
    field: &mut HeightField,
) -> FeatherPose {
    let SettlingFeather { frame, shape, params, body, rate } = feather;
    let step = toward(&current, &solved, rate);
    if step == solved || step.scale <= 0.0 {
        return solved;
    }
    let clear = |pose: FeatherPose, field: &mut HeightField| {
        pose.pitch <= params.max_pitch && pose_is_clear_boxed(frame, shape, pose, boxes, body, field)
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
            repair_drape(
                &FeatherInPlace { frame, shape, obstacles: boxes, body },
                current,
                f32::INFINITY,
                params,
                field,
            )
            .filter(|p| p.pitch <= params.max_pitch)
        })
        .or_else(|| large.clone().find(|&pose| clear(pose, field)))
        .unwrap_or(solved)
}

/// The lowest pose a bent feather may take (its pitch and every bend at
/// their lowest), toward which [`lowered_pose`] steps.
pub(super) fn lowest_pose(shape: &FeatherShape, params: &AdjustParams, current: FeatherPose) -> FeatherPose {
    let mut lowest = current;
    lowest.pitch = params.min_pitch;
    let (bend_low, _) = params.bend_range();
    let joints = shape.segment_count().saturating_sub(1);
    lowest.bends.iter_mut().take(joints).for_each(|b| *b = bend_low);
    lowest
}

/// A lowering step of [`lowered_pose`] is taken only where this many
/// steps are clear: the feather keeps a step's room beneath it, so that
/// the next small motion does not make it meet what it came down onto
/// and be lifted again (lowering to the last clear step made the animated
/// coat pop more; BENCHMARKS.md, "Issue #30, session 15").
const LOWERING_ROOM: f32 = 2.0;

/// A bent feather lying clear at `current` whose surroundings drifted
/// (incremental runs): `current` lowered by one step, the first of the
/// whole feather turned down by the settle rate (its pitch), by half of
/// it, or its joints alone bent down by the rate shared among them, that
/// is clear with room to spare ([`LOWERING_ROOM`]). Each step turns the
/// root-to-tip direction by at most the rate, so a feather that sinks a
/// little a frame does not pop. `None` when none is clear: the feather
/// rests on what lies beneath it.
pub(super) fn lowered_pose(
    feather: SettlingFeather<'_>,
    current: FeatherPose,
    boxes: BoxesOf<'_>,
    field: &mut HeightField,
) -> Option<FeatherPose> {
    let SettlingFeather { frame, shape, params, body, rate } = feather;
    let lowest = lowest_pose(shape, params, current);
    let joints = shape.segment_count().saturating_sub(1);
    let pitched = |share: f32| {
        let mut pose = current;
        pose.pitch = (current.pitch - share * rate).max(lowest.pitch.min(current.pitch));
        pose
    };
    let bent = |share: f32| {
        let mut pose = current;
        let step = share * rate / joints.max(1) as f32;
        for (b, low) in pose.bends.iter_mut().zip(lowest.bends).take(joints) {
            *b = (*b - step).max(low.min(*b));
        }
        pose
    };
    let room = LOWERING_ROOM;
    let mut clear = |pose: FeatherPose| pose_is_clear_boxed(frame, shape, pose, boxes, body, field);
    // Each step with the pose `room` times as far down; the farther first
    // (a step that fails there is not taken, whatever the step itself).
    [(pitched(1.0), pitched(room)), (pitched(0.5), pitched(0.5 * room)), (bent(1.0), bent(room))]
        .into_iter()
        .filter(|(pose, _)| *pose != current)
        .find(|&(pose, further)| clear(further) && (further == pose || clear(pose)))
        .map(|(pose, _)| pose)
}
