//! Welding: vertices with bit-identical positions become one vertex, so a
//! glTF triangle soup split along UV or normal seams is one connected surface.
//! The map back to the caller's numbering is kept for every later frame.

use crate::error::{Error, ErrorKind, Result};
use crate::geometry::triangle_area_vector;
use crate::mesh::MeshInput;
use glam::Vec3;
use std::collections::HashMap;
use std::collections::hash_map::Entry;

/// A triangle is degenerate when its height over its longest edge is below
/// this fraction of that edge (f32 cannot resolve anything thinner).
const DEGENERATE_RELATIVE_HEIGHT: f32 = 1e-6;

/// The welded surface mesh and its map to the caller's vertices.
#[derive(Clone, Debug)]
pub struct WeldedMesh {
    /// Welded vertex positions at the current pose.
    pub positions: Vec<Vec3>,
    /// Kept (non-degenerate, non-duplicate) triangles, welded numbering.
    pub triangles: Vec<[u32; 3]>,
    /// For each kept triangle, the caller's triangle index.
    pub source_triangle: Vec<u32>,
    /// Caller vertex → welded vertex.
    pub caller_to_welded: Vec<u32>,
    /// Welded vertex → the first caller vertex that maps to it.
    pub representative: Vec<u32>,
    /// Caller triangles dropped as degenerate.
    pub degenerate_triangles: usize,
    /// Caller triangles dropped as exact duplicates of a kept one.
    pub duplicate_triangles: usize,
}

impl WeldedMesh {
    /// Number of caller vertices every frame must provide.
    pub fn caller_vertex_count(&self) -> usize {
        self.caller_to_welded.len()
    }

    /// A frame's positions (caller numbering, already checked) carried to
    /// the welded vertices, into `out` (no allocation once it has grown).
    pub fn welded_positions_into(&self, caller_positions: &[f32], out: &mut Vec<Vec3>) {
        out.clear();
        out.extend(self.representative.iter().map(|&src| {
            let s = src as usize * 3;
            Vec3::new(caller_positions[s], caller_positions[s + 1], caller_positions[s + 2])
        }));
    }

    /// A per-vertex attribute of the caller (`stride` floats per vertex)
    /// carried to the welded vertices.
    pub fn weld_attribute(&self, caller_values: &[f32], stride: usize) -> Vec<f32> {
        let mut out = Vec::with_capacity(self.representative.len() * stride);
        for &src in &self.representative {
            let s = src as usize * stride;
            out.extend_from_slice(&caller_values[s..s + stride]);
        }
        out
    }

    /// The three corner positions of kept triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[t];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }
}

/// Welds a checked mesh. Fails with `DegenerateMesh` when no triangle is left.
pub fn weld(mesh: &MeshInput<'_>) -> Result<WeldedMesh> {
    let n = mesh.vertex_count();
    let mut ids: HashMap<[u32; 3], u32> = HashMap::with_capacity(n);
    let mut caller_to_welded = Vec::with_capacity(n);
    let mut representative = Vec::new();
    let mut positions = Vec::new();
    for v in 0..n {
        let p = &mesh.positions[3 * v..3 * v + 3];
        // +0.0 turns -0.0 into +0.0 so both weld together.
        let key = [(p[0] + 0.0).to_bits(), (p[1] + 0.0).to_bits(), (p[2] + 0.0).to_bits()];
        let id = match ids.entry(key) {
            Entry::Occupied(e) => *e.get(),
            Entry::Vacant(e) => {
                let id = positions.len() as u32;
                positions.push(Vec3::new(p[0], p[1], p[2]));
                representative.push(v as u32);
                *e.insert(id)
            }
        };
        caller_to_welded.push(id);
    }

    let mut triangles = Vec::with_capacity(mesh.indices.len() / 3);
    let mut source_triangle = Vec::with_capacity(mesh.indices.len() / 3);
    let mut seen: HashMap<[u32; 3], ()> = HashMap::with_capacity(mesh.indices.len() / 3);
    let (mut degenerate, mut duplicate) = (0usize, 0usize);
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let w =
            [caller_to_welded[tri[0] as usize], caller_to_welded[tri[1] as usize], caller_to_welded[tri[2] as usize]];
        let [a, b, c] = w.map(|i| positions[i as usize]);
        if is_degenerate(a, b, c) || w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
            degenerate += 1;
            continue;
        }
        let mut key = w;
        key.sort_unstable();
        if seen.insert(key, ()).is_some() {
            duplicate += 1;
            continue;
        }
        triangles.push(w);
        source_triangle.push(t as u32);
    }
    if triangles.is_empty() {
        return Err(Error::new(
            ErrorKind::DegenerateMesh,
            format!("all {} triangles are degenerate (zero area or repeated corners)", mesh.indices.len() / 3),
        ));
    }
    Ok(WeldedMesh {
        positions,
        triangles,
        source_triangle,
        caller_to_welded,
        representative,
        degenerate_triangles: degenerate,
        duplicate_triangles: duplicate,
    })
}

/// Zero area, or thinner than f32 can resolve relative to its longest edge.
/// The negated comparisons are deliberate: a NaN length or area is degenerate.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn is_degenerate(a: Vec3, b: Vec3, c: Vec3) -> bool {
    let longest2 = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
    if !(longest2 > 0.0) || !longest2.is_finite() {
        return true;
    }
    // |cross| = 2·area = longest · height.
    let twice_area = triangle_area_vector(a, b, c).length();
    !(twice_area > DEGENERATE_RELATIVE_HEIGHT * longest2)
}

crate::memory::heap_size_of_fields!(WeldedMesh { positions, triangles, source_triangle, caller_to_welded, representative } plain { degenerate_triangles, duplicate_triangles });

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seam_vertices_weld_and_map_back() {
        // Two triangles of a quad, unindexed with the shared edge duplicated.
        let pos = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 0., 0., 1., 1., 0., 0., 1., 0.];
        let idx = [0, 1, 2, 3, 4, 5];
        let m = weld(&MeshInput::new(&pos, &idx)).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles.len(), 2);
        assert_eq!(m.caller_to_welded[3], m.caller_to_welded[0]);
        assert_eq!(m.caller_to_welded[4], m.caller_to_welded[2]);
    }

    #[test]
    fn degenerate_and_duplicate_triangles_are_dropped() {
        let pos = [0., 0., 0., 1., 0., 0., 0., 1., 0., 2., 0., 0.];
        let idx = [0, 1, 2, 0, 1, 3, 2, 0, 1];
        let m = weld(&MeshInput::new(&pos, &idx)).unwrap();
        assert_eq!(m.triangles.len(), 1);
        assert_eq!(m.degenerate_triangles, 1);
        assert_eq!(m.duplicate_triangles, 1);
    }

    #[test]
    fn all_degenerate_is_refused() {
        let pos = [0., 0., 0., 1., 0., 0., 2., 0., 0.];
        let err = weld(&MeshInput::new(&pos, &[0, 1, 2])).unwrap_err();
        assert_eq!(err.kind(), ErrorKind::DegenerateMesh);
    }
}
