//! Temporal coherence (DESIGN.md §5, §6 `pops`): how much each feather's
//! pose relative to its root's frame (pitch, roll, the bends of a segmented
//! shaft) changed from one frame to the next. An animator sees a feather
//! that flicks by more than a few degrees in one frame at once, even when
//! each frame on its own is collision-free. The pose is relative to the
//! root's frame, so a rigid motion of the body changes nothing here.

use crate::feather::FeatherPose;

/// Default pop threshold: 5° (radians).
pub const DEFAULT_POP_THRESHOLD: f32 = 5.0 * std::f32::consts::PI / 180.0;

/// The pose changes of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseChanges {
    /// Feathers whose pose changed by more than the threshold.
    pub pops: usize,
    /// The largest change of any feather, radians.
    pub largest: f32,
}

/// The largest angle by which `after` differs from `before`: pitch, roll
/// or any joint's bend. A feather that appears or vanishes (its size goes
/// to or from 0) changes by its whole pitch and bends.
pub fn pose_change(before: &FeatherPose, after: &FeatherPose) -> f32 {
    let bends = before.bends.iter().zip(&after.bends).map(|(a, b)| (a - b).abs());
    bends.fold((before.pitch - after.pitch).abs().max((before.roll - after.roll).abs()), f32::max)
}

/// The pose changes between two frames of the same feathers (`before[i]`
/// and `after[i]` are one feather).
pub fn pose_changes(before: &[FeatherPose], after: &[FeatherPose], threshold: f32) -> PoseChanges {
    before.iter().zip(after).fold(PoseChanges::default(), |acc, (b, a)| {
        let change = pose_change(b, a);
        PoseChanges { pops: acc.pops + usize::from(change > threshold), largest: acc.largest.max(change) }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
