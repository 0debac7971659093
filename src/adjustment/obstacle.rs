//! An obstacle feather as the exact checks meet it: its triangles and its
//! raised top, with their boxes (below both the height field, which keeps
//! a scratch list of them, and the checks).

use crate::feather::FeatherTriangles;
use crate::triangle_grid::Aabb;
use crate::validation::BoxedTriangles;
use glam::Vec3;

/// An obstacle as the exact checks meet it: its triangles and its
/// [`raised_top`] with their boxes. The adjuster makes them once per posed
/// feather, for every feather it is an obstacle of.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ObstacleBoxes {
    pub(super) triangles: BoxedTriangles,
    pub(super) top: BoxedTriangles,
}

impl ObstacleBoxes {
    /// The boxes of an obstacle with these triangles and thickness.
    pub(crate) fn new(triangles: &[[Vec3; 3]], thickness: f32) -> Self {
        let top = raised_top(triangles, thickness);
        Self { triangles: BoxedTriangles::new(triangles), top: BoxedTriangles::new(&top) }
    }

    /// The box of its triangles and the box of its top.
    pub(crate) fn bounds(&self) -> ObstacleBounds {
        [*self.triangles.bounds(), *self.top.bounds()]
    }
}

/// An obstacle's two outer boxes ([`ObstacleBoxes::bounds`]: its triangles',
/// its top's), kept apart from its [`ObstacleBoxes`] so that the checks
/// rule most obstacles out reading a few bytes each.
pub(crate) type ObstacleBounds = [Aabb; 2];

/// An obstacle's top: its two triangles raised by its thickness along
/// their own normals (away from the skin they grow from). A feather clear
/// of every obstacle's top (tested in [`exact_check`](super::checks)) and passing
/// `pose_is_clear` stays out of the slab an obstacle fills, except for
/// parts that end inside it.
pub(super) fn raised_top(triangles: &[[Vec3; 3]], thickness: f32) -> FeatherTriangles {
    let raise = |t: &[Vec3; 3]| {
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero() * thickness;
        [t[0] + n, t[1] + n, t[2] + n]
    };
    let mut top = FeatherTriangles::from_slice(triangles);
    for (t, raised) in top.iter_mut().zip(triangles.iter().map(raise)) {
        *t = raised;
    }
    top
}
