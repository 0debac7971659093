//! A feather's adjustable state (pitch, roll, size) and the posed feather:
//! its shaft, normal, tip and triangles in world space.
//!
//! Posing applies the roll β about the (still flat) shaft, then the pitch α
//! about `b`. Positive pitch lifts the tip away from the skin; positive roll
//! lifts the +y vane. Pitching after rolling is the same as rolling about the
//! pitched shaft, which is what "roll about the shaft" means.

use super::FeatherShape;
use super::shape::{MAX_JOINTS, MAX_SEGMENTS, ShaftPlan};
use crate::geometry::RootFrame;
use glam::Vec3;

/// Most triangles of a posed feather: per vane, every interior joint's
/// station counts in the fans of both its segments, the vane corners in one
/// (see [`ShaftPlan`]).
pub const MAX_TRIANGLES: usize = 2 * (2 * MAX_SEGMENTS - 1);

/// The adjustable state of a feather: two angles (radians) and a size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeatherPose {
    /// α: rotation about the binormal; positive lifts the tip off the skin.
    pub pitch: f32,
    /// β: rotation about the shaft; positive lifts the +y (binormal-side) vane.
    pub roll: f32,
    /// Size as a fraction of the feather's shape, in (0, 1]: a feather that
    /// cannot lie down within the pitch limit (a concave corner, a thin
    /// limb, a flow sink) is shortened instead of standing up
    /// (see [`FeatherShape::scaled`]).
    pub scale: f32,
    /// Bend at each joint of a segmented shaft (radians, joint 1 first):
    /// the turn of each segment relative to the one before it, about the
    /// feather's own lateral axis; negative curves the feather down towards
    /// the skin. Only the first `S − 1` are used; all 0 is a straight
    /// feather.
    pub bends: [f32; MAX_JOINTS],
}

impl Default for FeatherPose {
    fn default() -> Self {
        Self::new(0.0, 0.0)
    }
}

impl FeatherPose {
    /// A full-size pose from pitch and roll.
    pub fn new(pitch: f32, roll: f32) -> Self {
        Self { pitch, roll, scale: 1.0, bends: [0.0; MAX_JOINTS] }
    }

    /// Whether no joint is bent (the feather is one plane).
    #[inline]
    pub fn is_straight(&self) -> bool {
        self.bends.iter().all(|&b| b == 0.0)
    }

    /// The same angles at size `scale`.
    pub fn with_scale(self, scale: f32) -> Self {
        Self { scale, ..self }
    }

    /// Rotates a point of the flat feather (local coordinates, z = 0 or
    /// not) by roll then pitch; the result is still in local coordinates.
    #[inline]
    pub fn apply_local(&self, p: Vec3) -> Vec3 {
        self.rotation().apply(p)
    }

    /// The rotation of [`FeatherPose::apply_local`], its sines and cosines
    /// worked out once for several points.
    #[inline]
    fn rotation(&self) -> PoseRotation {
        let (sb, cb) = self.roll.sin_cos();
        let (sa, ca) = self.pitch.sin_cos();
        PoseRotation { sb, cb, sa, ca }
    }

    /// The posed shaft direction in local coordinates: (cos α, 0, sin α).
    #[inline]
    pub fn local_shaft(&self) -> Vec3 {
        let (sa, ca) = self.pitch.sin_cos();
        Vec3::new(ca, 0.0, sa)
    }
}

/// The posed shaft direction in world space (unit): `õ cos α + n sin α`.
/// Roll never moves the shaft.
#[inline]
pub fn shaft_direction(frame: &RootFrame, pose: FeatherPose) -> Vec3 {
    let (sa, ca) = pose.pitch.sin_cos();
    frame.tangent * ca + frame.normal * sa
}

/// The posed feather's unit normal in world space (the side facing away
/// from the skin when the feather lies flat).
#[inline]
pub fn feather_normal(frame: &RootFrame, pose: FeatherPose) -> Vec3 {
    let local = pose.apply_local(Vec3::Z);
    frame.tangent * local.x + frame.binormal * local.y + frame.normal * local.z
}

/// A posed feather's triangles (at most [`MAX_TRIANGLES`]), read as a
/// slice. The kite (`S = 1`) has two: `[root, tip, +y corner]` and
/// `[root, −y corner, tip]`. A segmented shaft has, per vane and segment
/// from the root, the fan of [`ShaftPlan`], the +y vane's first; all wind
/// so that their normal faces away from the skin when the feather lies
/// flat.
#[derive(Clone, Copy, Debug)]
pub struct FeatherTriangles {
    triangles: [[Vec3; 3]; MAX_TRIANGLES],
    len: u8,
}

impl FeatherTriangles {
    /// The kite's two triangles.
    pub fn kite(triangles: [[Vec3; 3]; 2]) -> Self {
        let mut all = [[Vec3::ZERO; 3]; MAX_TRIANGLES];
        all[..2].copy_from_slice(&triangles);
        Self { triangles: all, len: 2 }
    }

    /// Triangles from a slice (at most [`MAX_TRIANGLES`]).
    pub fn from_slice(triangles: &[[Vec3; 3]]) -> Self {
        let mut all = [[Vec3::ZERO; 3]; MAX_TRIANGLES];
        all[..triangles.len()].copy_from_slice(triangles);
        Self { triangles: all, len: triangles.len() as u8 }
    }

    /// Moves every corner by `f`.
    #[inline]
    pub fn map_in_place(&mut self, f: impl Fn(Vec3) -> Vec3) {
        for t in &mut self.triangles[..self.len as usize] {
            *t = t.map(&f);
        }
    }

    fn push(&mut self, t: [Vec3; 3]) {
        self.triangles[self.len as usize] = t;
        self.len += 1;
    }
}

impl std::ops::DerefMut for FeatherTriangles {
    #[inline]
    fn deref_mut(&mut self) -> &mut [[Vec3; 3]] {
        &mut self.triangles[..self.len as usize]
    }
}

impl PartialEq for FeatherTriangles {
    fn eq(&self, other: &Self) -> bool {
        **self == **other
    }
}

impl std::ops::Deref for FeatherTriangles {
    type Target = [[Vec3; 3]];
    #[inline]
    fn deref(&self) -> &[[Vec3; 3]] {
        &self.triangles[..self.len as usize]
    }
}

/// Triangles per feather of `shape` (see [`FeatherTriangles`]).
#[inline]
pub fn triangles_per_feather(shape: &FeatherShape) -> usize {
    match shape.segment_count() {
        1 => 2,
        _ => 2 * shape.shaft_plan().triangles_per_vane(),
    }
}

/// The posed feather's triangles in world space (see [`FeatherTriangles`]).
pub fn feather_triangles(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> FeatherTriangles {
    let rotation = pose.rotation();
    let scaled = shape.scaled(pose.scale);
    if shape.segment_count() == 1 {
        let [root, tip, left, right] = scaled.kite_corners().map(|p| frame.to_world(rotation.apply(p)));
        return FeatherTriangles::kite([[root, tip, left], [root, right, tip]]);
    }
    let shaft = ShaftPoints::of(&scaled, &pose);
    let plan = &shaft.plan;
    let world = |p: Vec3| frame.to_world(rotation.apply(p));
    let joint: [Vec3; MAX_SEGMENTS + 1] =
        std::array::from_fn(|k| if k <= plan.segments { world(shaft.points[k]) } else { Vec3::ZERO });
    let mut out = FeatherTriangles { triangles: [[Vec3::ZERO; 3]; MAX_TRIANGLES], len: 0 };
    // +y vane, then −y vane (mirrored winding).
    for side in [1.0f32, -1.0] {
        let tri = |a: Vec3, b: Vec3, c: Vec3| if side > 0.0 { [a, b, c] } else { [a, c, b] };
        for k in 0..plan.segments {
            let mut previous = joint[k + 1];
            for (_, f) in plan.segment_stations(k) {
                let edge = world(shaft.edge_point(f, side));
                out.push(tri(joint[k], previous, edge));
                previous = edge;
            }
        }
    }
    out
}

/// The triangles of segment `segment` (from the root) of a posed
/// segmented feather: per vane, that segment's fan, +y vane first; the
/// same triangles, bit for bit and in the same order, as that segment's in
/// [`feather_triangles`], without computing the others.
pub fn segment_triangles(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    segment: usize,
) -> FeatherTriangles {
    let rotation = pose.rotation();
    let scaled = shape.scaled(pose.scale);
    let shaft = ShaftPoints::of(&scaled, &pose);
    let world = |p: Vec3| frame.to_world(rotation.apply(p));
    let (start, end) = (world(shaft.points[segment]), world(shaft.points[segment + 1]));
    let mut out = FeatherTriangles { triangles: [[Vec3::ZERO; 3]; MAX_TRIANGLES], len: 0 };
    for side in [1.0f32, -1.0] {
        let tri = |a: Vec3, b: Vec3, c: Vec3| if side > 0.0 { [a, b, c] } else { [a, c, b] };
        let mut previous = end;
        for (_, f) in shaft.plan.segment_stations(segment) {
            let edge = world(shaft.edge_point(f, side));
            out.push(tri(start, previous, edge));
            previous = edge;
        }
    }
    out
}

/// The shaft polyline of a segmented feather in its unrolled, unpitched
/// frame (x along the shaft at the root, z up), by its [`ShaftPlan`].
/// Joint k turns the segments after it by `bends[k − 1]` about the
/// lateral (y) axis, so every segment and its vanes stay flat.
pub(super) struct ShaftPoints {
    pub(super) plan: ShaftPlan,
    length: f32,
    half_width: f32,
    vane_split: f32,
    pub(super) points: [Vec3; MAX_SEGMENTS + 1],
    directions: [Vec3; MAX_SEGMENTS],
}

impl ShaftPoints {
    pub(super) fn of(shape: &FeatherShape, pose: &FeatherPose) -> Self {
        let plan = shape.shaft_plan();
        let s = plan.segments;
        let mut points = [Vec3::ZERO; MAX_SEGMENTS + 1];
        let mut directions = [Vec3::X; MAX_SEGMENTS];
        let mut angle = 0.0f32;
        for k in 0..s {
            if k > 0 {
                angle += pose.bends[k - 1];
            }
            let (sin, cos) = angle.sin_cos();
            directions[k] = Vec3::new(cos, 0.0, sin);
            points[k + 1] = points[k] + directions[k] * ((plan.joint(k + 1) - plan.joint(k)) * shape.length);
        }
        Self {
            plan,
            length: shape.length,
            half_width: 0.5 * shape.width,
            vane_split: shape.vane_split,
            points,
            directions,
        }
    }

    /// The vane edge at station `f` (a fraction of the length) on side
    /// `side` (±1 along y): on the segment holding the station, the kite's
    /// half-width off the shaft.
    pub(super) fn edge_point(&self, f: f32, side: f32) -> Vec3 {
        let k = ((f * self.plan.segments as f32) as usize).min(self.plan.segments - 1);
        let along = (f - self.plan.joint(k)) * self.length;
        let half = if f <= self.vane_split {
            self.half_width * f / self.vane_split
        } else {
            self.half_width * (1.0 - f) / (1.0 - self.vane_split)
        };
        self.points[k] + self.directions[k] * along + Vec3::new(0.0, side * half, 0.0)
    }
}

/// Roll then pitch (see [`FeatherPose::apply_local`]) by their sines and
/// cosines.
#[derive(Clone, Copy, Debug)]
struct PoseRotation {
    sb: f32,
    cb: f32,
    sa: f32,
    ca: f32,
}

impl PoseRotation {
    #[inline]
    fn apply(&self, p: Vec3) -> Vec3 {
        let PoseRotation { sb, cb, sa, ca } = *self;
        // Roll about x.
        let (x, y, z) = (p.x, p.y * cb - p.z * sb, p.y * sb + p.z * cb);
        // Pitch about y, tip (x) towards +z.
        Vec3::new(x * ca - z * sa, y, x * sa + z * ca)
    }
}

/// The posed tip position in world space.
#[inline]
pub fn tip_position(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> Vec3 {
    if shape.segment_count() == 1 || pose.is_straight() {
        return frame.position + shaft_direction(frame, pose) * (shape.length * pose.scale);
    }
    let shaft = ShaftPoints::of(&shape.scaled(pose.scale), &pose);
    frame.to_world(pose.rotation().apply(shaft.points[shaft.plan.segments]))
}

/// The largest angle by which `after` differs from `before`: pitch, roll
/// or any joint's bend. A feather that appears or vanishes (its size goes
/// to or from 0) changes by its whole pitch and bends.
pub fn pose_change(before: &FeatherPose, after: &FeatherPose) -> f32 {
    let bends = before.bends.iter().zip(&after.bends).map(|(a, b)| (a - b).abs());
    bends.fold((before.pitch - after.pitch).abs().max((before.roll - after.roll).abs()), f32::max)
}

/// `from` moved toward `to` by at most `rate` radians in pitch, roll and
/// each bend; the size is `to`'s. A feather that was not shown (size 0)
/// takes `to` at once.
pub fn toward(from: &FeatherPose, to: &FeatherPose, rate: f32) -> FeatherPose {
    if from.scale <= 0.0 || to.scale <= 0.0 {
        return *to;
    }
    let step = |a: f32, b: f32| if (b - a).abs() <= rate { b } else { a + rate.copysign(b - a) };
    let mut pose = FeatherPose::new(step(from.pitch, to.pitch), step(from.roll, to.roll)).with_scale(to.scale);
    for (k, b) in pose.bends.iter_mut().enumerate() {
        *b = step(from.bends[k], to.bends[k]);
    }
    pose
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> RootFrame {
        RootFrame::from_normal_and_direction(Vec3::new(1.0, 2.0, 3.0), Vec3::Z, Vec3::X).unwrap()
    }

    #[test]
    fn flat_feather_lies_in_the_tangent_plane() {
        let s = FeatherShape::for_spacing(1.0);
        let [a, b] = *feather_triangles(&frame(), &s, FeatherPose::default()) else {
            panic!("a kite has two triangles")
        };
        for p in a.iter().chain(b.iter()) {
            assert!((p.z - 3.0).abs() < 1e-6);
        }
        assert!((a[1] - Vec3::new(1.0 + s.length, 2.0, 3.0)).length() < 1e-5);
        assert!(crate::geometry::triangle_area_vector(a[0], a[1], a[2]).z > 0.0);
        assert!(crate::geometry::triangle_area_vector(b[0], b[1], b[2]).z > 0.0);
    }

    #[test]
    fn pitch_lifts_the_tip_and_roll_lifts_the_binormal_vane() {
        let f = frame();
        let s = FeatherShape::for_spacing(1.0);
        let pose = FeatherPose::new(0.3, 0.0);
        let tip = tip_position(&f, &s, pose);
        assert!((tip.z - 3.0 - s.length * 0.3f32.sin()).abs() < 1e-5);
        assert!((feather_triangles(&f, &s, pose)[0][1] - tip).length() < 1e-5);
        let rolled = feather_triangles(&f, &s, FeatherPose::new(0.0, 0.2));
        // +y corner (binormal side) goes up, −y corner down.
        assert!(rolled[0][2].z > 3.0 && rolled[1][1].z < 3.0);
        // Roll keeps the shaft.
        assert!((rolled[0][1] - tip_position(&f, &s, FeatherPose::default())).length() < 1e-5);
    }

    #[test]
    fn posing_keeps_lengths_and_shaft_direction() {
        let f = frame();
        let s = FeatherShape::for_spacing(0.7);
        let pose = FeatherPose::new(-0.2, 0.4);
        let [a, b] = *feather_triangles(&f, &s, pose) else { panic!("a kite has two triangles") };
        assert!(((a[1] - a[0]).length() - s.length).abs() < 1e-5);
        assert!(((a[1] - a[0]).normalize() - shaft_direction(&f, pose)).length() < 1e-5);
        assert!(((a[2] - b[1]).length() - s.width).abs() < 1e-5);
        let n = feather_normal(&f, pose);
        assert!(n.dot(a[2] - a[0]).abs() < 1e-5 && n.dot(b[1] - b[0]).abs() < 1e-5);
    }
}
