//! How roots moved relative to each other between two frames (the paper's
//! `A_i^k`, §3.3). How far each feather's surroundings have moved since it
//! was last adjusted, measured with the same bound, is the coat's
//! [`Staleness`](crate::coat::Staleness).
//!
//! The map of root i from frame k−1 to k is the rigid motion of its frame
//! (position and `(õ, b, n)` axes): `A_i(x) = Q_i (x − r_i) + r_i'` with
//! `Q_i = F_i' F_iᵀ`. A feather keeps its pitch and roll relative to its
//! frame, so every point of feather j moves with `A_j`. Seen from feather i
//! (whose own feather moves with `A_i`), a point of j at distance `ρ` from
//! j's root is displaced by at most
//!
//! `|A_i(r_j) − r_j'| + ρ ‖Q_i − Q_j‖₂`,
//!
//! the miss of i's map at j's root plus the turn between the two frames
//! (for rotations `‖Q_i − Q_j‖₂ = ‖Q_i − Q_j‖_F / √2`, computed from the
//! differences so that a rigid motion gives only rounding noise). A rigid
//! motion of the whole body gives every pair 0.

use crate::geometry::RootFrame;
use glam::{Mat3, Vec3};

/// The rigid map of one root frame from the previous frame to the current one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RootMap {
    /// `Q_i`: the rotation of the frame's axes.
    pub rotation: Mat3,
    /// The root's previous position `r_i`.
    pub from: Vec3,
    /// The root's current position `r_i'`.
    pub to: Vec3,
}

impl RootMap {
    /// The map taking `before` onto `after`.
    pub fn between(before: &RootFrame, after: &RootFrame) -> Self {
        Self { rotation: after.axes() * before.axes().transpose(), from: before.position, to: after.position }
    }

    /// Applies the map to a point.
    #[inline]
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.rotation * (p - self.from) + self.to
    }

    /// How root j moved as seen from root i (`self`): see the module notes.
    #[inline]
    pub fn relative(&self, j: &RootMap) -> RelativeMotion {
        let d = self.rotation - j.rotation;
        let frobenius2 = d.x_axis.length_squared() + d.y_axis.length_squared() + d.z_axis.length_squared();
        RelativeMotion {
            miss: self.apply(j.from).distance(j.to),
            turn: frobenius2.sqrt() * std::f32::consts::FRAC_1_SQRT_2,
        }
    }
}

/// The motion of one root relative to another between two frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RelativeMotion {
    /// How far the other root ended up from where this root's map carries it.
    pub miss: f32,
    /// The angle (radians, as `2 sin(θ/2)`) between the two frames' rotations.
    pub turn: f32,
}

impl RelativeMotion {
    /// The largest displacement of a point at distance `radius` from the
    /// other root.
    #[inline]
    pub fn at(&self, radius: f32) -> f32 {
        self.miss + self.turn * radius
    }
}

/// Fills `out` with every root's map between two poses of the same roots.
pub fn root_maps(before: &[RootFrame], after: &[RootFrame], out: &mut Vec<RootMap>) {
    out.clear();
    out.extend(before.iter().zip(after).map(|(b, a)| RootMap::between(b, a)));
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    fn frame(p: Vec3, n: Vec3, d: Vec3) -> RootFrame {
        RootFrame::from_normal_and_direction(p, n, d).unwrap()
    }

    #[test]
    fn a_rigid_motion_moves_nothing_relative() {
        let q = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let t = Vec3::new(3.0, -1.0, 2.0);
        let a = frame(Vec3::new(0.0, 0.0, 0.0), Vec3::Z, Vec3::X);
        let b = frame(Vec3::new(2.0, 1.0, 0.5), Vec3::new(0.2, 0.1, 1.0), Vec3::Y);
        let moved = |f: &RootFrame| frame(q * f.position + t, q * f.normal, q * f.tangent);
        let (ma, mb) = (RootMap::between(&a, &moved(&a)), RootMap::between(&b, &moved(&b)));
        let r = ma.relative(&mb);
        assert!(r.miss < 1e-5 && r.turn < 1e-5, "{r:?}");
        assert!(ma.apply(b.position).distance(moved(&b).position) < 1e-5);
    }

    #[test]
    fn a_turn_is_measured_as_the_displacement_it_causes() {
        let a = frame(Vec3::ZERO, Vec3::Z, Vec3::X);
        let b = frame(Vec3::X, Vec3::Z, Vec3::X);
        // b turns by 0.1 rad about its normal; a stays.
        let turned = frame(Vec3::X, Vec3::Z, Quat::from_rotation_z(0.1) * Vec3::X);
        let r = RootMap::between(&a, &a).relative(&RootMap::between(&b, &turned));
        assert!(r.miss < 1e-6);
        let chord = 2.0 * (0.05f32).sin();
        assert!((r.turn - chord).abs() < 1e-5, "{} vs {chord}", r.turn);
        // A point 3 away from b's root moves by the chord of the turn.
        assert!((r.at(3.0) - 3.0 * chord).abs() < 1e-4);
        // b sliding away by 0.2 is a miss of 0.2.
        let slid = frame(Vec3::new(1.2, 0.0, 0.0), Vec3::Z, Vec3::X);
        assert!((RootMap::between(&a, &a).relative(&RootMap::between(&b, &slid)).miss - 0.2).abs() < 1e-6);
    }
}
