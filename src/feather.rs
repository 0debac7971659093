//! The feather as geometry: a flat kite in the root frame, posed by a pitch
//! and a roll (DESIGN.md §4).
//!
//! Local coordinates follow [`RootFrame`]: x along the tangential orientation
//! `õ`, y along the binormal `b`, z along the normal `n`. Before posing the
//! kite lies in the tangent plane: root (0,0,0), tip (L,0,0), vane corners
//! (s_w·L, ±W/2, 0). It is two triangles, one per vane, sharing the shaft.
//!
//! Posing applies the roll β about the (still flat) shaft, then the pitch α
//! about `b`. Positive pitch lifts the tip away from the skin; positive roll
//! lifts the +y vane. Pitching after rolling is the same as rolling about the
//! pitched shaft, which is what "roll about the shaft" means.

use crate::geometry::RootFrame;
use glam::Vec3;

/// Length of a feather as a multiple of the local spacing `d`. A feather
/// then reaches over three to four rows of neighbours, so every point of the
/// skin is covered two to three times, as on a real bird. (3.5 d left more
/// skin bare where feathers pitch up or are shortened: at 4 d the exact
/// coverage of the test coats rose by 0.5–1.5 points for half a degree more
/// mean pitch.)
pub(crate) const LENGTH_PER_SPACING: f32 = 4.0;
/// Width as a multiple of `d`: the vanes reach a little past the lateral
/// neighbours, so neighbouring feathers overlap sideways too.
pub(crate) const WIDTH_PER_SPACING: f32 = 1.75;
/// Thickness as a fraction of the width (a contour feather's vane is thin;
/// this sets how steeply stacked feathers climb).
pub(crate) const THICKNESS_PER_WIDTH: f32 = 0.04;
/// Where the vane corners sit along the shaft, as a fraction of the length.
pub(crate) const DEFAULT_VANE_SPLIT: f32 = 0.4;

/// Dimensions of one feather, in model units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeatherShape {
    /// Shaft length `L` (root to tip).
    pub length: f32,
    /// Vane width `W` (corner to corner).
    pub width: f32,
    /// Thickness `t`: how far above its own triangles a feather's top is.
    pub thickness: f32,
    /// `s_w`: where the vane corners sit along the shaft, as a fraction of
    /// the length (0 < s_w < 1).
    pub vane_split: f32,
}

impl FeatherShape {
    /// The default shape for local spacing `d` (Poisson-disk radius):
    /// length 4 d, width 1.75 d, thickness 4 % of the width (0.07 d), vane
    /// corners at 40 % of the length. With roots about d apart a feather
    /// covers its neighbours ahead over three to four rows and half of each lateral
    /// neighbour, so the coat is closed, and the small thickness keeps
    /// stacked feathers nearly flat (a few degrees of pitch).
    pub fn for_spacing(d: f32) -> Self {
        let width = WIDTH_PER_SPACING * d;
        Self {
            length: LENGTH_PER_SPACING * d,
            width,
            thickness: THICKNESS_PER_WIDTH * width,
            vane_split: DEFAULT_VANE_SPLIT,
        }
    }

    /// The default shape for spacing `d` with global overrides: any of
    /// `length`, `width`, `thickness` that is > 0 replaces the rule (a given
    /// width also sets the default thickness, 4 % of it).
    pub fn with_overrides(d: f32, length: f32, width: f32, thickness: f32) -> Self {
        let mut s = Self::for_spacing(d);
        if length > 0.0 {
            s.length = length;
        }
        if width > 0.0 {
            s.width = width;
            s.thickness = THICKNESS_PER_WIDTH * width;
        }
        if thickness > 0.0 {
            s.thickness = thickness;
        }
        s
    }

    /// Half the vane width at distance `x` along the flat shaft: 0 at the
    /// root and the tip, `W/2` at the vane corners, linear in between;
    /// negative outside `[0, L]`.
    #[inline]
    pub fn half_width_at(&self, x: f32) -> f32 {
        let corner = self.vane_split * self.length;
        let half = 0.5 * self.width;
        if x < 0.0 || x > self.length {
            -1.0
        } else if x <= corner {
            half * x / corner
        } else {
            half * (self.length - x) / (self.length - corner)
        }
    }

    /// This shape shrunk by `scale` about the root: length and width scale,
    /// the thickness (and so the clearance over it) stays. The shrunk kite
    /// lies inside the full one, since the kite is convex and holds its root.
    #[inline]
    pub fn scaled(&self, scale: f32) -> Self {
        Self { length: self.length * scale, width: self.width * scale, ..*self }
    }

    /// The flat kite in local coordinates: root, tip, +y corner, −y corner.
    pub fn kite_corners(&self) -> [Vec3; 4] {
        let cx = self.vane_split * self.length;
        let hw = 0.5 * self.width;
        [Vec3::ZERO, Vec3::new(self.length, 0.0, 0.0), Vec3::new(cx, hw, 0.0), Vec3::new(cx, -hw, 0.0)]
    }
}

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

    #[test]
    fn half_width_is_a_kite() {
        let s = FeatherShape { length: 10.0, width: 4.0, thickness: 0.1, vane_split: 0.4 };
        assert_eq!(s.half_width_at(0.0), 0.0);
        assert!((s.half_width_at(4.0) - 2.0).abs() < 1e-6);
        assert!((s.half_width_at(7.0) - 1.0).abs() < 1e-6);
        assert!(s.half_width_at(10.5) < 0.0 && s.half_width_at(-0.1) < 0.0);
    }

    #[test]
    fn overrides_replace_the_rules() {
        let s = FeatherShape::with_overrides(1.0, 0.0, 3.0, 0.0);
        assert_eq!(s.length, 4.0);
        assert_eq!(s.width, 3.0);
        assert!((s.thickness - 0.12).abs() < 1e-6);
        assert_eq!(FeatherShape::with_overrides(1.0, 2.0, 0.0, 0.5).thickness, 0.5);
    }
}
