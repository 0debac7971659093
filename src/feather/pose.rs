//! A feather's adjustable state (pitch, roll, size) and the posed feather:
//! its shaft, normal, tip and triangles in world space.
//!
//! Posing applies the roll β about the (still flat) shaft, then the pitch α
//! about `b`. Positive pitch lifts the tip away from the skin; positive roll
//! lifts the +y vane. Pitching after rolling is the same as rolling about the
//! pitched shaft, which is what "roll about the shaft" means.

use super::FeatherShape;
use crate::geometry::RootFrame;
use glam::Vec3;

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
}

impl Default for FeatherPose {
    fn default() -> Self {
        Self::new(0.0, 0.0)
    }
}

impl FeatherPose {
    /// A full-size pose from pitch and roll.
    pub fn new(pitch: f32, roll: f32) -> Self {
        Self { pitch, roll, scale: 1.0 }
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

/// The feather's two triangles in world space: `[root, tip, +y corner]` and
/// `[root, −y corner, tip]`. Both wind so that their normal faces away from
/// the skin when the feather lies flat.
pub fn feather_triangles(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> [[Vec3; 3]; 2] {
    let rotation = pose.rotation();
    let [root, tip, left, right] = shape.scaled(pose.scale).kite_corners().map(|p| frame.to_world(rotation.apply(p)));
    [[root, tip, left], [root, right, tip]]
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
    frame.position + shaft_direction(frame, pose) * (shape.length * pose.scale)
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
        let [a, b] = feather_triangles(&frame(), &s, FeatherPose::default());
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
        let [a, b] = feather_triangles(&f, &s, pose);
        assert!(((a[1] - a[0]).length() - s.length).abs() < 1e-5);
        assert!(((a[1] - a[0]).normalize() - shaft_direction(&f, pose)).length() < 1e-5);
        assert!(((a[2] - b[1]).length() - s.width).abs() < 1e-5);
        let n = feather_normal(&f, pose);
        assert!(n.dot(a[2] - a[0]).abs() < 1e-5 && n.dot(b[1] - b[0]).abs() < 1e-5);
    }
}
