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

/// The vertices and triangles of one feather, before posing.
///
/// The kite: vertex 0 the root (u 0, v 0.5), 1 the tip (u 1, v 0.5), 2 the
/// vane corner on the binormal (+y) side (u = s_w, v 1), 3 the corner on
/// the −y side (u = s_w, v 0); triangles (0, 1, 2) and (0, 3, 1), the two
/// of [`feather_triangles`], facing away from the skin.
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
        let s = shape.vane_split;
        Self { uvs: vec![[0.0, 0.5], [1.0, 0.5], [s, 1.0], [s, 0.0]], triangles: vec![[0, 1, 2], [0, 3, 1]] }
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
        let [[root, tip, left], [_, right, _]] = feather_triangles(frame, shape, pose);
        let normal = feather_normal(frame, pose).to_array();
        self.positions.extend([root, tip, left, right].map(|p| p.to_array()));
        self.normals.extend([normal; 4]);
        self.uvs.extend_from_slice(&layout.uvs);
        self.indices.extend(layout.triangles.iter().map(|t| t.map(|k| first + k)));
        self.vertex_feathers.extend(std::iter::repeat_n(feather, layout.vertex_count()));
        self.vertex_counts.push(layout.vertex_count() as u32);
        self.triangle_counts.push(layout.triangles.len() as u32);
        self.placed.push(u8::from(pose.scale > 0.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

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
