//! Temporal coherence (DESIGN.md §5, §6 `pops`): how much each feather's
//! pose relative to its root's frame (pitch, roll, the bends of a segmented
//! shaft) changed from one frame to the next. An animator sees a feather
//! that flicks by more than a few degrees in one frame at once, even when
//! each frame on its own is collision-free. The pose is relative to the
//! root's frame, so a rigid motion of the body changes nothing here.
//!
//! A readjusted feather that jumps to its solved pose pops: a drift re-seed
//! (its surroundings drifted past the drift tolerance) mostly snaps down
//! to the ideal pose, and a feather failing its exact check (an obstacle
//! moved into it, or a reversal in the order gave it a new obstacle) is
//! solved afresh, mostly up and often by far more than the collision
//! needed (BENCHMARKS.md, "Measurements behind the code's constants").
//!
//! So the incremental mode settles instead of snapping
//! (`Config::settle_rate`, default 2° a frame; see
//! [`crate::adjustment::OrderedRun::settle_rate`]): a readjusted
//! feather moves from its current pose toward its solved pose by at most
//! the rate in pitch, roll and each bend, if that pose passes the exact
//! checks; if not, it lifts from there by the smallest clear step, and only
//! as a last resort takes the solved pose. Collision-free stays the rule of
//! every frame; a feather held back is readjusted again the next frame
//! ([`crate::coat::Coat::settling`]) until it reaches its solved pose. Its
//! obstacles' sinking is judged by the solved pose, so the feathers lying on
//! a settling feather settle with it. A lower drift tolerance then tracks
//! rebuild closer without popping, at the cost of more readjustments.

use crate::feather::{FeatherPose, pose_change};
use crate::geometry::RootFrame;

/// The pose changes of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseChanges {
    /// Feathers whose pose changed by more than the threshold.
    pub pops: usize,
    /// The largest change of any feather, radians.
    pub largest: f32,
}

/// The pose changes between two frames of the same feathers (`before[i]`
/// and `after[i]` are one feather).
pub fn pose_changes(before: &[FeatherPose], after: &[FeatherPose], threshold: f32) -> PoseChanges {
    before.iter().zip(after).fold(PoseChanges::default(), |acc, (b, a)| {
        let change = pose_change(b, a);
        PoseChanges { pops: acc.pops + usize::from(change > threshold), largest: acc.largest.max(change) }
    })
}

/// The feathers whose placement differs in any bit between two frames of
/// the same feathers: root frame (position, normal, tangent, binormal) or
/// pose (pitch, roll, size, bends). Their indices, increasing, replace
/// `changed`; returns how many of them changed their pose (the rest only
/// moved with the skin). A feather not listed has the same record and the
/// same triangles, bit for bit, since both are functions of these alone
/// (its shape never changes).
pub fn changed_feathers(
    before: (&[RootFrame], &[FeatherPose]),
    after: (&[RootFrame], &[FeatherPose]),
    changed: &mut Vec<u32>,
) -> usize {
    changed.clear();
    let mut reposed = 0;
    for (i, ((fb, pb), (fa, pa))) in before.0.iter().zip(before.1).zip(after.0.iter().zip(after.1)).enumerate() {
        let pose_moved = pose_bits(pb) != pose_bits(pa);
        if pose_moved || frame_bits(fb) != frame_bits(fa) {
            changed.push(i as u32);
            reposed += usize::from(pose_moved);
        }
    }
    reposed
}

fn frame_bits(f: &RootFrame) -> [u32; 12] {
    let [p, n, t, b] = [f.position, f.normal, f.tangent, f.binormal].map(|v| v.to_array().map(f32::to_bits));
    [p[0], p[1], p[2], n[0], n[1], n[2], t[0], t[1], t[2], b[0], b[1], b[2]]
}

fn pose_bits(p: &FeatherPose) -> ([u32; 3], [u32; crate::feather::MAX_JOINTS]) {
    ([p.pitch, p.roll, p.scale].map(f32::to_bits), p.bends.map(f32::to_bits))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DEFAULT_POP_THRESHOLD;
    use crate::feather::toward;

    #[test]
    fn a_planted_snap_is_counted_and_small_drift_is_not() {
        let before = vec![FeatherPose::new(0.2, 0.0); 10];
        let mut after = before.clone();
        after[3].pitch += 0.01; // 0.6°: drift
        after[7].bends[1] = -0.3; // a snap of a bent shaft, 17°
        after[8].roll = 0.1; // 5.7°
        let c = pose_changes(&before, &after, DEFAULT_POP_THRESHOLD);
        assert_eq!(c.pops, 2);
        assert!((c.largest - 0.3).abs() < 1e-6);
        assert_eq!(pose_changes(&before, &before, DEFAULT_POP_THRESHOLD), PoseChanges::default());
    }

    #[test]
    fn changed_feathers_are_those_that_differ_in_any_bit() {
        let frame = RootFrame::from_normal_and_direction(glam::Vec3::ONE, glam::Vec3::Z, glam::Vec3::X).unwrap();
        let (frames, poses) = (vec![frame; 6], vec![FeatherPose::new(0.2, 0.0); 6]);
        let (mut moved, mut posed) = (frames.clone(), poses.clone());
        moved[1].position.x = f32::from_bits(moved[1].position.x.to_bits() + 1); // one ulp
        posed[3].bends[2] = -0.0; // 0.0 before: equal as floats, not as bits
        posed[4].scale = 0.5;
        moved[4].normal.y = -0.0;
        let mut changed = vec![99];
        let reposed = changed_feathers((&frames, &poses), (&moved, &posed), &mut changed);
        assert_eq!((changed, reposed), (vec![1, 3, 4], 2));
        assert_eq!(changed_feathers((&frames, &poses), (&frames, &poses), &mut vec![]), 0);
    }

    #[test]
    fn toward_moves_each_angle_by_at_most_the_rate() {
        let mut from = FeatherPose::new(0.5, -0.1);
        from.bends[0] = -0.2;
        let mut to = FeatherPose::new(0.1, -0.08).with_scale(0.85);
        to.bends[0] = 0.3;
        let p = toward(&from, &to, 0.05);
        assert!((p.pitch - 0.45).abs() < 1e-6 && p.roll == -0.08 && (p.bends[0] + 0.15).abs() < 1e-6);
        assert_eq!(p.scale, 0.85);
        assert!(pose_change(&from, &p) <= 0.05 + 1e-6);
        assert_eq!(toward(&from, &to, 10.0), to);
        assert_eq!(toward(&from.with_scale(0.0), &to, 0.05), to);
    }
}
