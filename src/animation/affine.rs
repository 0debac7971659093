//! Per-face affine maps between two poses (the paper's `A_i^k`, §3.3) and
//! the test that decides whether two roots deform differently.
//!
//! The map of a triangle takes its previous edge frame (e1, e2, n̂) to the
//! current one (e1', e2', n̂'): `M = [e1' e2' n̂'] · [e1 e2 n̂]⁻¹`,
//! `t = p0' − M p0`. A rigid motion gives the same map for every face; a
//! bend or stretch gives faces different maps.

use glam::{Mat3, Vec3};

/// The affine map `x ↦ M x + t` of one face from the previous pose to the current one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceMap {
    /// Linear part `M`.
    pub linear: Mat3,
    /// Translation `t`.
    pub translation: Vec3,
}

impl FaceMap {
    /// The identity map.
    pub(crate) const IDENTITY: Self = Self { linear: Mat3::IDENTITY, translation: Vec3::ZERO };

    /// Applies the map to a point.
    #[inline]
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.linear * p + self.translation
    }
}

/// The map of the triangle `before` → `after`; the identity when either is degenerate.
pub fn face_map(before: [Vec3; 3], after: [Vec3; 3]) -> FaceMap {
    let frame = |t: [Vec3; 3]| {
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let n = e1.cross(e2).try_normalize()?;
        Some(Mat3::from_cols(e1, e2, n))
    };
    let (Some(from), Some(to)) = (frame(before), frame(after)) else { return FaceMap::IDENTITY };
    let det = from.determinant();
    if !det.is_finite() || det.abs() < f32::MIN_POSITIVE {
        return FaceMap::IDENTITY;
    }
    let linear = to * from.inverse();
    let translation = after[0] - linear * before[0];
    if !linear.is_finite() || !translation.is_finite() {
        return FaceMap::IDENTITY;
    }
    FaceMap { linear, translation }
}

/// Fills `out` with the map of every face between two poses of the same mesh
/// (reusing its allocation).
pub fn face_maps(before: &[Vec3], after: &[Vec3], triangles: &[[u32; 3]], out: &mut Vec<FaceMap>) {
    out.clear();
    out.extend(triangles.iter().map(|t| {
        let c = |p: &[Vec3]| [p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]];
        face_map(c(before), c(after))
    }));
}

/// Tolerances of "deforms differently".
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeformationTolerance {
    /// Allowed displacement mismatch, as a fraction of the local spacing.
    pub position: f32,
    /// Allowed difference of the linear parts (Frobenius norm).
    pub linear: f32,
}

impl Default for DeformationTolerance {
    fn default() -> Self {
        Self { position: 2e-3, linear: 2e-3 }
    }
}

/// Whether roots i and j deform differently between the two poses: the map
/// of i's face, applied to j's previous position, misses j's current
/// position by more than `tol.position · spacing`, or the linear parts differ.
pub fn deform_differently(
    map_i: &FaceMap,
    map_j: &FaceMap,
    previous_j: Vec3,
    current_j: Vec3,
    spacing: f32,
    tol: &DeformationTolerance,
) -> bool {
    if map_i == map_j {
        return false;
    }
    let miss = map_i.apply(previous_j).distance(current_j);
    if miss > tol.position * spacing {
        return true;
    }
    let d = map_i.linear - map_j.linear;
    let frob2 = d.x_axis.length_squared() + d.y_axis.length_squared() + d.z_axis.length_squared();
    frob2 > tol.linear * tol.linear
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    fn tri() -> [Vec3; 3] {
        [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.2, 0.0), Vec3::new(0.1, 1.0, 0.3)]
    }

    #[test]
    fn rigid_motion_gives_the_same_map_everywhere() {
        let q = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let t = Vec3::new(3.0, -1.0, 2.0);
        let move_ = |p: Vec3| q * p + t;
        let a = tri();
        let b = [Vec3::new(2.0, 0.0, 0.0), Vec3::new(2.5, 1.0, 0.5), Vec3::new(1.0, 1.0, -1.0)];
        let (ma, mb) = (face_map(a, a.map(move_)), face_map(b, b.map(move_)));
        let p = Vec3::new(0.3, 0.4, 0.1);
        assert!(ma.apply(p).distance(move_(p)) < 1e-5);
        let tol = DeformationTolerance::default();
        assert!(!deform_differently(&ma, &mb, b[0], move_(b[0]), 1.0, &tol));
    }

    #[test]
    fn a_bend_is_seen() {
        let a = tri();
        let b = [Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 0.0)];
        let ma = face_map(a, a);
        let bent = [b[0], Vec3::new(2.9, 0.0, 0.4), b[2]];
        let mb = face_map(b, bent);
        let tol = DeformationTolerance::default();
        // j's corner 1 moved; i's map (identity) does not explain it.
        assert!(deform_differently(&ma, &mb, b[1], bent[1], 1.0, &tol));
    }

    #[test]
    fn degenerate_faces_give_the_identity() {
        let flat = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        assert_eq!(face_map(flat, tri()), FaceMap::IDENTITY);
    }
}
