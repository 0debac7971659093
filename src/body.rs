//! The body surface at the current pose ([`BodyIndex`]): its triangles in a
//! [`TriangleGrid`] with unit face normals, rebuilt every frame into the
//! same buffers. The grid, its box type and the exact ray and point tests
//! live in [`crate::triangle_grid`] (`Aabb` is re-exported here).

// Re-exported: `adjustment` reaches the box type through the body.
pub use crate::triangle_grid::Aabb;
use crate::triangle_grid::{ClosestPoint, RayHit, TriangleGrid, ray_triangle};
use glam::Vec3;

/// The body surface at the current pose: its triangles in a grid, with unit
/// face normals. Rebuilt once per frame.
#[derive(Debug, Default)]
pub struct BodyIndex {
    grid: TriangleGrid,
    normals: Vec<Vec3>,
}

impl BodyIndex {
    /// An empty index.
    pub fn new() -> Self {
        Self::default()
    }

    /// An index over a mesh's triangles at the given positions.
    pub fn from_mesh(positions: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        let mut b = Self::new();
        b.rebuild(positions, triangles);
        b
    }

    /// Rebuilds for new vertex positions (or a new mesh), reusing buffers.
    pub fn rebuild(&mut self, positions: &[Vec3], triangles: &[[u32; 3]]) {
        let corners = triangles.iter().map(|t| t.map(|v| positions[v as usize]));
        self.grid.rebuild(corners, None);
        self.normals.clear();
        self.normals
            .extend(self.grid.all_corners().iter().map(|[a, b, c]| (*b - *a).cross(*c - *a).normalize_or_zero()));
    }

    /// Number of body triangles.
    pub fn triangle_count(&self) -> usize {
        self.grid.len()
    }

    /// The corners of body triangle `t` at the current pose.
    #[inline]
    pub fn corners(&self, t: u32) -> [Vec3; 3] {
        self.grid.corners(t)
    }

    /// The bounding box of body triangle `t` (the one
    /// [`BodyIndex::triangles_in_box`] tests).
    #[inline]
    pub(crate) fn bounds(&self, t: u32) -> Aabb {
        self.grid.bounds(t)
    }

    /// The unit face normal of body triangle `t` (zero if degenerate).
    #[inline]
    pub fn normal(&self, t: u32) -> Vec3 {
        self.normals[t as usize]
    }

    /// The underlying grid.
    pub fn grid(&self) -> &TriangleGrid {
        &self.grid
    }

    /// Body triangles whose bounding boxes overlap `query`, each once, into
    /// `out` (cleared first).
    pub fn triangles_in_box(&self, query: &Aabb, out: &mut Vec<u32>) {
        self.grid.query_box(query, out);
    }

    /// Body triangles near a point (boxes within `radius`), into `out`.
    pub fn triangles_near(&self, p: Vec3, radius: f32, out: &mut Vec<u32>) {
        self.grid.query_box(&Aabb::around(p, radius), out);
    }

    /// The first body triangle hit by the ray `origin + t·dir` (`dir`
    /// unit), `0 < t ≤ t_max`.
    pub fn ray_cast(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<RayHit> {
        self.grid.ray_cast(origin, dir, t_max, |t| ray_triangle(origin, dir, self.grid.corners(t)))
    }

    /// The nearest body point within `max_distance` of `p`.
    pub fn closest_point(&self, p: Vec3, max_distance: f32, scratch: &mut Vec<u32>) -> Option<ClosestPoint> {
        self.grid.closest_point(p, max_distance, scratch)
    }

    /// [`TriangleGrid::closest_point_keeping`] over the body.
    pub fn closest_point_keeping(
        &self,
        p: Vec3,
        max_distance: f32,
        keep: impl Fn(f32) -> f32,
        scratch: &mut Vec<u32>,
        distances: &mut Vec<f32>,
    ) -> Option<ClosestPoint> {
        self.grid.closest_point_keeping(p, max_distance, keep, scratch, distances)
    }
}

crate::memory::clone_by_fields!(BodyIndex { grid, normals });
crate::memory::heap_size_of_fields!(BodyIndex { grid, normals });

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_on_a_plane_mesh() {
        let pos = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let body = BodyIndex::from_mesh(&pos, &[[0, 1, 2], [0, 2, 3]]);
        let mut s = Vec::new();
        let c = body.closest_point(Vec3::new(0.25, 0.5, 0.3), 1.0, &mut s).unwrap();
        assert!((c.distance - 0.3).abs() < 1e-6);
        assert!((c.point - Vec3::new(0.25, 0.5, 0.0)).length() < 1e-6);
        assert!(body.closest_point(Vec3::new(5.0, 5.0, 5.0), 1.0, &mut s).is_none());
        assert!((body.normal(0) - Vec3::Z).length() < 1e-6);
        let hit = body.ray_cast(Vec3::new(0.5, 0.2, 1.0), -Vec3::Z, 2.0).unwrap();
        assert!((hit.t - 1.0).abs() < 1e-6 && hit.triangle == 0);
    }

    #[test]
    fn rebuild_reuses_and_follows_new_positions() {
        let mut pos = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        let mut body = BodyIndex::from_mesh(&pos, &[[0, 1, 2]]);
        pos.iter_mut().for_each(|p| *p += Vec3::new(0.0, 0.0, 2.0));
        body.rebuild(&pos, &[[0, 1, 2]]);
        let mut out = Vec::new();
        body.triangles_near(Vec3::new(0.2, 0.2, 2.0), 0.1, &mut out);
        assert_eq!(out, vec![0]);
        body.triangles_near(Vec3::new(0.2, 0.2, 0.0), 0.1, &mut out);
        assert!(out.is_empty());
    }
}
