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
/// [`Adjuster::settle_next_run`](super::Adjuster::settle_next_run)): `current` moved toward `solved` by the
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
            repair_drape(&FeatherInPlace { frame, shape, obstacles: boxes, body }, current, params, field)
                .filter(|p| p.pitch <= params.max_pitch)
        })
        .or_else(|| large.clone().find(|&pose| clear(pose, field)))
        .unwrap_or(solved)
}
