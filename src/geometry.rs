//! Small geometric value types shared by every algorithm module.
//!
//! Conventions (DESIGN.md §1): a feather root has a right-handed frame
//! `(õ, b, n)` = (tangential orientation, binormal, normal), so that in the
//! feather's local coordinates x runs along the shaft, y across the vanes and
//! z away from the skin.

use glam::{Mat3, Vec3};

/// A point on the welded surface: a face and the barycentric weights of its
/// three corners (they sum to 1). Surface points follow any deformation of
/// the mesh because they never store a position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// Index of a triangle of the welded mesh.
    pub face: u32,
    /// Weights of the triangle's corners, in the triangle's corner order.
    pub bary: [f32; 3],
}

impl SurfacePoint {
    /// The point's position given the corners of its face.
    pub fn position_on(&self, corners: [Vec3; 3]) -> Vec3 {
        corners[0] * self.bary[0] + corners[1] * self.bary[1] + corners[2] * self.bary[2]
    }
}

/// The frame of a feather root at one pose: position `r`, unit normal `n`,
/// tangential orientation `õ` (unit, in the tangent plane) and binormal
/// `b = n × õ`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RootFrame {
    /// Root position `r_i`.
    pub position: Vec3,
    /// Unit surface normal `n_i`.
    pub normal: Vec3,
    /// Unit tangential orientation `õ_i` (the shaft direction before pitch).
    pub tangent: Vec3,
    /// Unit binormal `b_i`; pitch rotates about it.
    pub binormal: Vec3,
}

impl RootFrame {
    /// Builds the frame from a normal and any direction not parallel to it:
    /// `b = (n × o)/|n × o|`, `õ = b × n` (paper §2). `None` when the direction
    /// is (nearly) parallel to the normal or anything is not finite.
    pub fn from_normal_and_direction(position: Vec3, normal: Vec3, direction: Vec3) -> Option<Self> {
        let n = normal.try_normalize()?;
        let b = n.cross(direction).try_normalize()?;
        let t = b.cross(n);
        if !position.is_finite() {
            return None;
        }
        Some(Self { position, normal: n, tangent: t, binormal: b })
    }

    /// Maps local feather coordinates (x along `õ`, y along `b`, z along `n`)
    /// to world space.
    #[inline]
    pub fn to_world(&self, local: Vec3) -> Vec3 {
        self.position + self.tangent * local.x + self.binormal * local.y + self.normal * local.z
    }

    /// Maps a world point into local feather coordinates.
    #[inline]
    pub fn to_local(&self, world: Vec3) -> Vec3 {
        let d = world - self.position;
        Vec3::new(d.dot(self.tangent), d.dot(self.binormal), d.dot(self.normal))
    }

    /// The axes `(õ, b, n)` as matrix columns (local to world rotation).
    #[inline]
    pub fn axes(&self) -> Mat3 {
        Mat3::from_cols(self.tangent, self.binormal, self.normal)
    }
}

/// Twice the area vector of a triangle (unnormalised normal).
#[inline]
pub fn triangle_area_vector(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    (b - a).cross(c - a)
}
