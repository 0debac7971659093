//! The feathers as a mesh a host can draw: vertices, triangles, UVs,
//! normals and which feather each vertex belongs to (what a DCC expects to
//! receive: a stable feather index per vertex, u along the shaft, v across
//! the vanes).
//!
//! The layout of one feather depends on its shape only, never on its pose,
//! so indices, UVs and the vertex-to-feather map stay the same from frame to
//! frame; only positions and normals move.

use super::{FeatherPose, FeatherShape, feather_normal, feather_triangles};
use crate::geometry::RootFrame;
use glam::Vec3;

/// The vertices and triangles of one feather, before posing.
///
/// The kite (`S = 1`): vertex 0 the root (u 0, v 0.5), 1 the tip (u 1,
/// v 0.5), 2 the vane corner on the binormal (+y) side (u = s_w, v 1), 3
/// the corner on the −y side (u = s_w, v 0); triangles (0, 1, 2) and
/// (0, 3, 1). A segmented shaft ([`ShaftPlan`](super::ShaftPlan)): the
/// `S + 1` joints from root to tip (v 0.5), then the +y vane's edge at each
/// station, then the −y vane's (v = 0.5 ± y/W, so the corners reach 1 and
/// 0); u is the fraction of the length along the unbent shaft. The
/// triangles are those of [`feather_triangles`],
/// in its order, all facing away from the skin.
#[derive(Clone, Debug, PartialEq)]
pub struct FeatherMeshLayout {
    /// Per vertex: (u along the shaft from the root, v across the vanes).
    pub uvs: Vec<[f32; 2]>,
    /// Triangles as indices into this feather's vertices.
    pub triangles: Vec<[u32; 3]>,
}

impl FeatherMeshLayout {
    /// The layout of a feather of this shape.
    pub fn of(shape: &FeatherShape) -> Self {
        let split = shape.vane_split;
        if shape.segment_count() == 1 {
            return Self {
                uvs: vec![[0.0, 0.5], [1.0, 0.5], [split, 1.0], [split, 0.0]],
                triangles: vec![[0, 1, 2], [0, 3, 1]],
            };
        }
        let plan = shape.shaft_plan();
        let s = plan.segments;
        let across = |f: f32| 0.5 * if f <= split { f / split } else { (1.0 - f) / (1.0 - split) };
        let mut uvs: Vec<[f32; 2]> = (0..=s).map(|k| [plan.joint(k), 0.5]).collect();
        uvs.extend(plan.stations().iter().map(|&f| [f, 0.5 + across(f)]));
        uvs.extend(plan.stations().iter().map(|&f| [f, 0.5 - across(f)]));
        let mut triangles = Vec::with_capacity(2 * plan.triangles_per_vane());
        for (side, first) in [(1.0f32, s + 1), (-1.0, s + 1 + plan.station_count)] {
            let tri = |a: u32, b: u32, c: u32| if side > 0.0 { [a, b, c] } else { [a, c, b] };
            for k in 0..s {
                let mut previous = (k + 1) as u32;
                for (station, _) in plan.segment_stations(k) {
                    let edge = (first + station) as u32;
                    triangles.push(tri(k as u32, previous, edge));
                    previous = edge;
                }
            }
        }
        Self { uvs, triangles }
    }

    /// Vertices of one feather.
    pub fn vertex_count(&self) -> usize {
        self.uvs.len()
    }
}

/// Every feather's vertices at one pose, laid out by [`FeatherMeshLayout`]
/// one feather after the other, in the order of the feathers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FeatherMesh {
    /// Vertex positions, world space.
    pub positions: Vec<[f32; 3]>,
    /// Unit vertex normals, facing away from the skin on the feather's
    /// visible (upper) side.
    pub normals: Vec<[f32; 3]>,
    /// Per vertex (u, v): u from 0 at the root to 1 at the tip along the
    /// shaft, v from 0 to 1 across the vanes, 0.5 on the shaft.
    pub uvs: Vec<[f32; 2]>,
    /// Triangles, three indices into `positions` each.
    pub indices: Vec<[u32; 3]>,
    /// Per vertex: the index of its feather.
    pub vertex_feathers: Vec<u32>,
    /// Per feather: its vertex count.
    pub vertex_counts: Vec<u32>,
    /// Per feather: its triangle count.
    pub triangle_counts: Vec<u32>,
    /// Per feather: 1 when placed, 0 when left out (no size fitted: its
    /// vertices all lie at the root and its triangles have no area).
    pub placed: Vec<u8>,
}

impl FeatherMesh {
    /// The mesh of feathers at `frames` with `shapes` and `poses` (one each
    /// per feather).
    pub fn build(frames: &[RootFrame], shapes: &[FeatherShape], poses: &[FeatherPose]) -> Self {
        let mut mesh = Self::default();
        for (i, ((frame, shape), pose)) in frames.iter().zip(shapes).zip(poses).enumerate() {
            mesh.push(i as u32, frame, shape, *pose);
        }
        mesh
    }

    fn push(&mut self, feather: u32, frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) {
        let layout = FeatherMeshLayout::of(shape);
        let first = self.positions.len() as u32;
        let tris = feather_triangles(frame, shape, pose);
        debug_assert_eq!(tris.len(), layout.triangles.len());
        // Each vertex where a triangle of the layout first names it; the
        // normal is the area-weighted mean of its triangles' (a flat
        // feather's own normal when the triangles have no area).
        let n = layout.vertex_count();
        let mut positions = vec![None; n];
        let mut normals = vec![Vec3::ZERO; n];
        for (t, corners) in layout.triangles.iter().zip(tris.iter()) {
            let area = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
            for (&v, &p) in t.iter().zip(corners) {
                positions[v as usize].get_or_insert(p);
                normals[v as usize] += area;
            }
        }
        let flat = feather_normal(frame, pose);
        self.positions.extend(positions.iter().map(|p| p.unwrap_or(frame.position).to_array()));
        self.normals.extend(normals.iter().map(|n| n.try_normalize().unwrap_or(flat).to_array()));
        self.uvs.extend_from_slice(&layout.uvs);
        self.indices.extend(layout.triangles.iter().map(|t| t.map(|k| first + k)));
        self.vertex_feathers.extend(std::iter::repeat_n(feather, n));
        self.vertex_counts.push(n as u32);
        self.triangle_counts.push(layout.triangles.len() as u32);
        self.placed.push(u8::from(pose.scale > 0.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bent_feather_mesh_is_its_posed_triangles() {
        let frame = RootFrame::from_normal_and_direction(Vec3::new(1.0, 2.0, 3.0), Vec3::Z, Vec3::X).unwrap();
        let shape = FeatherShape::for_spacing(0.5).with_segments(4);
        let mut pose = FeatherPose::new(0.2, -0.1);
        pose.bends = [-0.3, -0.2, 0.1];
        let mesh = FeatherMesh::build(&[frame], &[shape], &[pose]);
        let tris = feather_triangles(&frame, &shape, pose);
        assert_eq!(mesh.indices.len(), tris.len());
        assert_eq!(mesh.triangle_counts, vec![tris.len() as u32]);
        for (t, corners) in mesh.indices.iter().zip(tris.iter()) {
            for (&index, corner) in t.iter().zip(corners) {
                assert_eq!(mesh.positions[index as usize], corner.to_array());
            }
        }
        // Every vertex is used; the shaft runs v = 0.5 from u 0 to 1.
        let mut used = vec![false; mesh.positions.len()];
        mesh.indices.iter().flatten().for_each(|&i| used[i as usize] = true);
        assert!(used.iter().all(|&u| u));
        assert_eq!(mesh.uvs[0], [0.0, 0.5]);
        assert_eq!(mesh.uvs[4], [1.0, 0.5]);
        assert!(mesh.uvs.iter().all(|uv| uv.iter().all(|x| (0.0..=1.0).contains(x))));
        assert!(mesh.uvs.iter().any(|uv| uv[1] == 1.0) && mesh.uvs.iter().any(|uv| uv[1] == 0.0));
        // The tip is where the pose puts it, and normals are unit.
        assert!(
            (Vec3::from_array(mesh.positions[4]) - crate::feather::tip_position(&frame, &shape, pose)).length() < 1e-5
        );
        assert!(mesh.normals.iter().all(|n| (Vec3::from_array(*n).length() - 1.0).abs() < 1e-5));
    }

    #[test]
    fn mesh_triangles_are_the_posed_triangles() {
        let frame = RootFrame::from_normal_and_direction(Vec3::new(1.0, 2.0, 3.0), Vec3::Z, Vec3::X).unwrap();
        let shape = FeatherShape::for_spacing(0.5);
        let poses = [FeatherPose::new(0.2, -0.1), FeatherPose::new(0.3, 0.0).with_scale(0.0)];
        let mesh = FeatherMesh::build(&[frame, frame], &[shape, shape], &poses);
        assert_eq!(mesh.positions.len(), 8);
        assert_eq!(mesh.indices.len(), 4);
        assert_eq!(mesh.placed, vec![1, 0]);
        assert_eq!(mesh.vertex_feathers, vec![0, 0, 0, 0, 1, 1, 1, 1]);
        let tris = feather_triangles(&frame, &shape, poses[0]);
        for (k, t) in tris.iter().enumerate() {
            for (corner, index) in t.iter().zip(mesh.indices[k]) {
                assert_eq!(mesh.positions[index as usize], corner.to_array());
            }
        }
        assert_eq!(mesh.indices[2], [4, 5, 6]);
        for n in &mesh.normals {
            assert!((Vec3::from_array(*n).length() - 1.0).abs() < 1e-5);
        }
        // The normal faces away from the skin for a feather lying flat.
        assert!(Vec3::from_array(mesh.normals[0]).dot(frame.normal) > 0.9);
        assert!(mesh.uvs.iter().all(|uv| uv.iter().all(|x| (0.0..=1.0).contains(x))));
    }
}
