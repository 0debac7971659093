//! The coat's saved state: what a state blob holds of a [`Coat`] (the
//! per-frame state; the [`Dressing`] is identified by the blob's
//! fingerprint), written and read back checked.

use super::{Coat, Dressing, Staleness};
use crate::error::{Error, ErrorKind, Result};
use crate::feather::FeatherPose;
use crate::ordering::{Neighbourhoods, PriorityOrder};
use crate::snapshot::{Reader, Writer};
use crate::stats::{FrameReport, OrderingReport};
use glam::Vec3;

/// Saved state (see [`crate::snapshot`]): what determines every later
/// frame. Root frames, vertex normals and the body index are functions of
/// the positions, so they are recomputed on load rather than stored.
///
/// The blob is byte-reproducible: two identical runs save identical bytes,
/// so the report timings (run-dependent) are not stored; a loaded coat's
/// timings are 0 (loading adjusted nothing).
///
/// Layout: frame index (u64); welded positions (u64 count, then xyz f32
/// each); poses (u64 count of floats, then [`write_pose`] each: pitch,
/// roll, scale and the S − 1 joint bends); the ordering report (four u64
/// counts); the frame report (frame index and ten counts as u64, then the
/// level count u64); the neighbourhoods
/// ([`Neighbourhoods::write_state`]); the order ([`PriorityOrder::write_state`]);
/// the staleness ([`Staleness::write_state`]); the settling flags (u64
/// count, 0 or one per feather, then a byte 0 or 1 each).
impl Coat {
    /// Appends the coat's state to a state blob.
    pub fn write_state(&self, w: &mut Writer, joints: usize) {
        w.u64(self.frame_index);
        w.u64(3 * self.positions.len() as u64);
        for p in &self.positions {
            p.to_array().iter().for_each(|&x| w.f32(x));
        }
        w.u64(((POSE_FLOATS + joints) * self.poses.len()) as u64);
        self.poses.iter().for_each(|pose| write_pose(w, pose, joints));
        // Destructured in full (as in `read_state`) so that a new report
        // field cannot be forgotten here.
        // Timings are left out: they differ between identical runs.
        let OrderingReport { pairs, edges, dropped_edges, violations, seconds: _ } = self.ordering_report;
        [pairs, edges, dropped_edges, violations].iter().for_each(|&c| w.u64(c as u64));
        let FrameReport {
            frame_index,
            adjusted,
            deformed,
            seeds,
            verified,
            collision_tests,
            priority_changes,
            reversals,
            reversals_refused,
            cycles_broken,
            clamped,
            draped,
            drape_descents,
            kept_in_place,
            reorder_seconds: _,
            adjust_seconds: _,
            step_seconds: _,
            neighbourhood_seconds: _,
            levels,
        } = self.frame_report;
        w.u64(frame_index);
        [adjusted, deformed, seeds, verified].iter().for_each(|&c| w.u64(c as u64));
        w.u64(collision_tests);
        [priority_changes, reversals, reversals_refused, cycles_broken, clamped].iter().for_each(|&c| w.u64(c as u64));
        w.u64(levels as u64);
        [draped, drape_descents, kept_in_place].iter().for_each(|&c| w.u64(c as u64));
        self.neighbourhoods.write_state(w);
        self.order.write_state(w);
        self.staleness.write_state(w);
        w.u64(self.settling.len() as u64);
        self.settling.iter().for_each(|&s| w.u8(u8::from(s)));
    }

    /// Reads a coat written by [`write_state`](Self::write_state) for
    /// `dressing`, then recomputes the root frames, normals and body index
    /// from the positions (runs on the current rayon pool). Refuses with
    /// `InvalidState` a coat of another size, non-finite positions, poses
    /// outside the adjustment's limits, counts that do not fit, invalid
    /// neighbourhoods or order (see their `read_state`), or an order whose
    /// pair set is not the neighbourhoods'.
    pub fn read_state(r: &mut Reader<'_>, dressing: &Dressing) -> Result<Self> {
        let n = dressing.len();
        let frame_index = r.u64()?;
        r.len(4, Some(3 * dressing.surface.vertex_count()))?;
        let mut positions = Vec::with_capacity(dressing.surface.vertex_count());
        for _ in 0..dressing.surface.vertex_count() {
            let p = Vec3::new(r.f32()?, r.f32()?, r.f32()?);
            if !p.is_finite() {
                return Err(invalid_state("saved positions are not finite"));
            }
            positions.push(p);
        }
        let joints = dressing.shaft_joints();
        r.len(4, Some((POSE_FLOATS + joints) * n))?;
        let mut poses = Vec::with_capacity(n);
        for _ in 0..n {
            poses.push(read_pose(r, dressing, joints)?);
        }
        let ordering_report = OrderingReport {
            pairs: count(r)?,
            edges: count(r)?,
            dropped_edges: count(r)?,
            violations: count(r)?,
            seconds: 0.0,
        };
        let frame_report = FrameReport {
            frame_index: r.u64()?,
            adjusted: count(r)?,
            deformed: count(r)?,
            seeds: count(r)?,
            verified: count(r)?,
            collision_tests: r.u64()?,
            priority_changes: count(r)?,
            reversals: count(r)?,
            reversals_refused: count(r)?,
            cycles_broken: count(r)?,
            clamped: count(r)?,
            reorder_seconds: 0.0,
            adjust_seconds: 0.0,
            step_seconds: 0.0,
            neighbourhood_seconds: 0.0,
            levels: count(r)?,
            draped: count(r)?,
            drape_descents: count(r)?,
            kept_in_place: count(r)?,
        };
        let neighbourhoods = Neighbourhoods::read_state(r, n)?;
        let order = PriorityOrder::read_state(r, n)?;
        let staleness = Staleness::read_state(r, n)?;
        let settling_count = r.len(1, None)?;
        if settling_count != 0 && settling_count != n {
            return Err(invalid_state("the saved settling flags are not one per feather"));
        }
        let mut settling = Vec::with_capacity(settling_count);
        for _ in 0..settling_count {
            match r.u8()? {
                0 => settling.push(false),
                1 => settling.push(true),
                _ => return Err(invalid_state("a saved settling flag is not 0 or 1")),
            }
        }
        if order.pairs() != neighbourhoods.pairs() {
            return Err(invalid_state("the saved order's pairs are not the saved neighbourhoods' pairs"));
        }
        let mut coat = Coat {
            poses,
            neighbourhoods,
            order,
            staleness,
            settling,
            frame_index,
            ordering_report,
            frame_report,
            ..Coat::default()
        };
        coat.pose(dressing, &positions);
        coat.body.rebuild(&coat.positions, &dressing.triangles);
        Ok(coat)
    }
}

/// Floats of a pose before its bends.
const POSE_FLOATS: usize = 3;

/// One feather's pose in a state blob: pitch, roll, scale and the bends of
/// its `joints` joints (f32 each). The one place the pose's encoding lives,
/// with [`read_pose`].
fn write_pose(w: &mut Writer, pose: &FeatherPose, joints: usize) {
    w.f32(pose.pitch);
    w.f32(pose.roll);
    w.f32(pose.scale);
    pose.bends[..joints].iter().for_each(|&b| w.f32(b));
}

/// Reads a pose of [`write_pose`], refusing one outside the adjustment's limits.
fn read_pose(r: &mut Reader<'_>, dressing: &Dressing, joints: usize) -> Result<FeatherPose> {
    let limits = &dressing.adjust_params;
    let mut pose = FeatherPose::new(r.f32()?, r.f32()?).with_scale(r.f32()?);
    for b in &mut pose.bends[..joints] {
        *b = r.f32()?;
    }
    let (bend_low, bend_high) = limits.bend_range();
    let bent_within = pose.bends.iter().all(|b| (bend_low..=bend_high).contains(b));
    if !(bent_within
        && pose.pitch >= limits.min_pitch
        && pose.pitch <= limits.max_pitch
        && pose.roll.abs() <= limits.max_roll
        && (pose.scale >= limits.min_scale || pose.scale == 0.0)
        && pose.scale <= 1.0)
    {
        return Err(invalid_state("a saved feather pose lies outside the pitch, roll, size and bend limits"));
    }
    Ok(pose)
}

/// A count stored as u64 that must fit a `usize`.
fn count(r: &mut Reader<'_>) -> Result<usize> {
    usize::try_from(r.u64()?).map_err(|_| invalid_state("a saved count does not fit this platform"))
}

fn invalid_state(message: &str) -> Error {
    Error::new(ErrorKind::InvalidState, message)
}
