//! The surface model of the welded mesh: which faces meet across which edges,
//! where the boundary is, vertex normals at any pose and per-face tangent
//! frames. Tracing along the surface (`Walk`) lives in [`walk`], the
//! approximate geodesic distance `G` in [`geodesic`].
//!
//! Conventions: side `k` of a face is the edge opposite its corner `k` (from
//! corner `k + 1` to corner `k + 2`), so a barycentric coordinate reaching 0
//! names the side a path leaves through. An edge shared by exactly two faces
//! is interior; an edge of one face is a boundary edge; an edge of three or
//! more faces is non-manifold and, for tracing, treated as a boundary.

pub mod geodesic;
pub mod walk;

pub use geodesic::NearbyPatch;
pub use walk::{WalkEnd, WalkResult};

use crate::csr::{Csr, CsrView};
use crate::geometry::{SurfacePoint, triangle_area_vector};
use crate::mesh::WeldedMesh;
use glam::Vec3;

/// The face across one side of a face, and which side of that face it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaceAcross {
    /// The neighbouring face.
    pub face: u32,
    /// The shared edge's side index in the neighbouring face.
    pub side: u8,
}

/// An orthonormal tangent frame of one face: `tangent` along its first edge
/// (`p1 − p0`), `normal` its unit normal, `bitangent = normal × tangent`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceFrame {
    /// Unit vector along `p1 − p0`.
    pub tangent: Vec3,
    /// `normal × tangent`, in the face plane.
    pub bitangent: Vec3,
    /// Unit face normal (corner order gives its sense).
    pub normal: Vec3,
}

impl FaceFrame {
    /// The frame of the triangle `corners`; a fixed frame when the triangle
    /// has collapsed at this pose.
    pub fn of_triangle(corners: [Vec3; 3]) -> Self {
        let [a, b, c] = corners;
        let normal = triangle_area_vector(a, b, c).try_normalize().unwrap_or(Vec3::Z);
        let tangent =
            (b - a).reject_from_normalized(normal).try_normalize().unwrap_or_else(|| normal.any_orthonormal_vector());
        Self { tangent, bitangent: normal.cross(tangent), normal }
    }
}

/// Topology and rest geometry of the welded mesh.
#[derive(Clone, Debug)]
pub struct Surface {
    vertex_count: usize,
    triangles: Vec<[u32; 3]>,
    /// Per face and side: the unique neighbour across that side, if the side
    /// is an interior (two-face) edge.
    across: Vec<[Option<FaceAcross>; 3]>,
    /// Per face and side: the index of the undirected edge.
    face_edges: Vec<[u32; 3]>,
    /// Per edge: its two vertices (smaller first).
    edges: Vec<[u32; 2]>,
    /// CSR: the faces of each edge (`edge_face_start[e]..edge_face_start[e + 1]`).
    edge_face_start: Vec<u32>,
    edge_faces: Vec<u32>,
    /// The vertices adjacent to each vertex, sorted.
    vertex_neighbours: Csr<u32>,
    boundary_edges: usize,
    non_manifold_edges: usize,
    rest_vertex_normals: Vec<Vec3>,
    rest_face_areas: Vec<f32>,
    rest_face_frames: Vec<FaceFrame>,
}

impl Surface {
    /// Builds the adjacency of `mesh` and its rest geometry (normals, areas,
    /// frames) from `mesh.positions`.
    pub fn new(mesh: &WeldedMesh) -> Self {
        let vertex_count = mesh.positions.len();
        let triangles = mesh.triangles.clone();
        let (edges, face_edges, edge_face_start, edge_faces) = build_edges(&triangles);
        let mut across = vec![[None; 3]; triangles.len()];
        let (mut boundary_edges, mut non_manifold_edges) = (0, 0);
        let faces_of_edge = CsrView::new(&edge_face_start, &edge_faces);
        for e in 0..edges.len() {
            let faces = faces_of_edge.row(e);
            match faces.len() {
                1 => boundary_edges += 1,
                2 => {
                    let side_of = |f: u32| face_edges[f as usize].iter().position(|&x| x == e as u32).unwrap() as u8;
                    let (f, g) = (faces[0], faces[1]);
                    let (sf, sg) = (side_of(f), side_of(g));
                    across[f as usize][sf as usize] = Some(FaceAcross { face: g, side: sg });
                    across[g as usize][sg as usize] = Some(FaceAcross { face: f, side: sf });
                }
                _ => non_manifold_edges += 1,
            }
        }
        let vertex_neighbours = build_vertex_neighbours(vertex_count, &edges);
        let mut rest_vertex_normals = Vec::new();
        vertex_normals_into(&mesh.positions, &triangles, &mut rest_vertex_normals);
        let rest_face_areas = (0..triangles.len()).map(|f| 0.5 * triangle_area_vector_of(mesh, f).length()).collect();
        let rest_face_frames = (0..triangles.len()).map(|f| FaceFrame::of_triangle(mesh.corners(f))).collect();
        Self {
            vertex_count,
            triangles,
            across,
            face_edges,
            edges,
            edge_face_start,
            edge_faces,
            vertex_neighbours,
            boundary_edges,
            non_manifold_edges,
            rest_vertex_normals,
            rest_face_areas,
            rest_face_frames,
        }
    }

    /// The connected part of the surface each face belongs to (faces
    /// sharing a vertex are connected), numbered from 0 in the order of
    /// their first face; and the number of parts.
    pub fn face_components(&self) -> (Vec<u32>, usize) {
        // Union-find over the vertices, halving paths.
        let mut parent: Vec<u32> = (0..self.vertex_count as u32).collect();
        fn find(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                let up = parent[parent[v as usize] as usize];
                parent[v as usize] = up;
                v = up;
            }
            v
        }
        for t in &self.triangles {
            let a = find(&mut parent, t[0]);
            for &v in &t[1..] {
                let b = find(&mut parent, v);
                if a != b {
                    parent[b as usize] = a;
                }
            }
        }
        let mut label = vec![u32::MAX; self.vertex_count];
        let mut parts = 0u32;
        let faces = self
            .triangles
            .iter()
            .map(|t| {
                let r = find(&mut parent, t[0]) as usize;
                if label[r] == u32::MAX {
                    label[r] = parts;
                    parts += 1;
                }
                label[r]
            })
            .collect();
        (faces, parts as usize)
    }

    /// Number of welded vertices.
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.triangles.len()
    }

    /// Number of undirected edges.
    pub fn edge_count(&self) -> usize {
        self.edges.len()
    }

    /// The welded triangles (corner vertex indices).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The two vertices of edge `e`, smaller index first.
    pub fn edge_vertices(&self, e: usize) -> [u32; 2] {
        self.edges[e]
    }

    /// The edge index of side `side` of face `f`.
    pub fn face_edge(&self, f: usize, side: usize) -> u32 {
        self.face_edges[f][side]
    }

    /// All faces sharing edge `e` (one for a boundary edge, three or more for
    /// a non-manifold one).
    pub fn faces_of_edge(&self, e: usize) -> &[u32] {
        CsrView::new(&self.edge_face_start, &self.edge_faces).row(e)
    }

    /// The face across side `side` of face `f`; `None` at a boundary or
    /// non-manifold edge.
    #[inline]
    pub fn across(&self, f: usize, side: usize) -> Option<FaceAcross> {
        self.across[f][side]
    }

    /// Whether side `side` of face `f` ends the surface for tracing (a
    /// boundary or non-manifold edge).
    pub fn is_boundary_side(&self, f: usize, side: usize) -> bool {
        self.across[f][side].is_none()
    }

    /// Edges that belong to a single face.
    pub fn boundary_edge_count(&self) -> usize {
        self.boundary_edges
    }

    /// Edges shared by three or more faces (treated as boundaries by `Walk`).
    pub fn non_manifold_edge_count(&self) -> usize {
        self.non_manifold_edges
    }

    /// The vertices joined to `v` by an edge, in increasing order.
    pub fn vertex_neighbours(&self, v: usize) -> &[u32] {
        self.vertex_neighbours.row(v)
    }

    /// Area-weighted vertex normals at the rest pose.
    pub fn rest_vertex_normals(&self) -> &[Vec3] {
        &self.rest_vertex_normals
    }

    /// Face areas at the rest pose.
    pub fn rest_face_areas(&self) -> &[f32] {
        &self.rest_face_areas
    }

    /// Face tangent frames at the rest pose.
    pub fn rest_face_frames(&self) -> &[FaceFrame] {
        &self.rest_face_frames
    }

    /// Total rest area.
    pub fn rest_area(&self) -> f64 {
        self.rest_face_areas.iter().map(|&a| a as f64).sum()
    }

    /// The corner positions of face `f` in `positions` (any pose).
    #[inline]
    pub fn corners(&self, positions: &[Vec3], f: usize) -> [Vec3; 3] {
        self.triangles[f].map(|v| positions[v as usize])
    }

    /// The position of a surface point in `positions` (any pose).
    #[inline]
    pub fn position(&self, positions: &[Vec3], p: SurfacePoint) -> Vec3 {
        p.position_on(self.corners(positions, p.face as usize))
    }

    /// The unit normal at a surface point: the barycentric blend of
    /// `vertex_normals`, normalised; the face normal where the blend cancels.
    pub fn interpolated_normal(&self, positions: &[Vec3], vertex_normals: &[Vec3], p: SurfacePoint) -> Vec3 {
        let tri = self.triangles[p.face as usize];
        let blend = (0..3).fold(Vec3::ZERO, |acc, k| acc + vertex_normals[tri[k] as usize] * p.bary[k]);
        blend.try_normalize().unwrap_or_else(|| FaceFrame::of_triangle(self.corners(positions, p.face as usize)).normal)
    }

    /// The tangent frame of face `f` at the pose `positions`.
    pub fn face_frame(&self, positions: &[Vec3], f: usize) -> FaceFrame {
        FaceFrame::of_triangle(self.corners(positions, f))
    }

    /// Area-weighted vertex normals at the pose `positions`, written into
    /// `out` (resized; no allocation when its capacity suffices).
    pub fn vertex_normals(&self, positions: &[Vec3], out: &mut Vec<Vec3>) {
        vertex_normals_into(positions, &self.triangles, out);
    }
}

fn triangle_area_vector_of(mesh: &WeldedMesh, f: usize) -> Vec3 {
    let [a, b, c] = mesh.corners(f);
    triangle_area_vector(a, b, c)
}

/// Area-weighted vertex normals of `triangles` at `positions`: each vertex
/// sums the area vectors of its faces (weight = area) and normalises. A
/// vertex whose sum vanishes (unused, or faces cancelling) gets +Z so the
/// result is always finite and unit. `out` is resized to `positions.len()`;
/// no allocation when its capacity suffices.
pub fn vertex_normals_into(positions: &[Vec3], triangles: &[[u32; 3]], out: &mut Vec<Vec3>) {
    out.clear();
    out.resize(positions.len(), Vec3::ZERO);
    for tri in triangles {
        let [a, b, c] = tri.map(|v| positions[v as usize]);
        let area_vector = triangle_area_vector(a, b, c);
        for &v in tri {
            out[v as usize] += area_vector;
        }
    }
    for n in out.iter_mut() {
        *n = n.try_normalize().unwrap_or(Vec3::Z);
    }
}

type EdgeTables = (Vec<[u32; 2]>, Vec<[u32; 3]>, Vec<u32>, Vec<u32>);

/// Undirected edges by sorting (vertex pair, face, side) records, so edge
/// numbering does not depend on any hash order.
fn build_edges(triangles: &[[u32; 3]]) -> EdgeTables {
    let mut records: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(triangles.len() * 3);
    for (f, tri) in triangles.iter().enumerate() {
        for side in 0..3 {
            let (a, b) = (tri[(side + 1) % 3], tri[(side + 2) % 3]);
            records.push((a.min(b), a.max(b), f as u32, side as u8));
        }
    }
    records.sort_unstable();
    let mut edges = Vec::new();
    let mut face_edges = vec![[0u32; 3]; triangles.len()];
    let mut edge_face_start = vec![0u32];
    let mut edge_faces = Vec::with_capacity(records.len());
    let mut i = 0;
    while i < records.len() {
        let (a, b) = (records[i].0, records[i].1);
        let e = edges.len() as u32;
        edges.push([a, b]);
        while i < records.len() && records[i].0 == a && records[i].1 == b {
            let (_, _, f, side) = records[i];
            face_edges[f as usize][side as usize] = e;
            edge_faces.push(f);
            i += 1;
        }
        edge_face_start.push(edge_faces.len() as u32);
    }
    (edges, face_edges, edge_face_start, edge_faces)
}

/// Each vertex's neighbours along the edges, sorted.
fn build_vertex_neighbours(vertex_count: usize, edges: &[[u32; 2]]) -> Csr<u32> {
    let mut neighbours = Csr::new();
    neighbours.rebuild(vertex_count, || edges.iter().flat_map(|&[a, b]| [(a as usize, b), (b as usize, a)]));
    for v in 0..vertex_count {
        neighbours.row_mut(v).sort_unstable();
    }
    neighbours
}

crate::memory::heap_size_of_fields!(Surface {
    triangles, across, face_edges, edges, edge_face_start, edge_faces, vertex_neighbours,
    rest_vertex_normals, rest_face_areas, rest_face_frames
} plain { vertex_count, boundary_edges, non_manifold_edges });

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{MeshInput, weld};

    fn tetra_with_fin() -> WeldedMesh {
        // A square of two faces plus a third face on the diagonal (non-manifold).
        let pos = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0., 0.5, 0.5, 1.];
        let idx = [0, 1, 2, 0, 2, 3, 0, 2, 4];
        weld(&MeshInput::new(&pos, &idx)).unwrap()
    }

    #[test]
    fn adjacency_counts_boundary_and_non_manifold_edges() {
        let mesh = tetra_with_fin();
        let s = Surface::new(&mesh);
        assert_eq!(s.face_count(), 3);
        assert_eq!(s.non_manifold_edge_count(), 1);
        // Square rim (4) + the fin's two free edges.
        assert_eq!(s.boundary_edge_count(), 6);
        for f in 0..3 {
            for side in 0..3 {
                assert!(s.across(f, side).is_none(), "only the non-manifold diagonal is shared");
            }
        }
    }

    #[test]
    fn interior_edges_are_mutual() {
        let pos = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.];
        let mesh = weld(&MeshInput::new(&pos, &[0, 1, 2, 0, 2, 3])).unwrap();
        let s = Surface::new(&mesh);
        assert_eq!(s.boundary_edge_count(), 4);
        let a = s.across(0, 1).expect("diagonal is side 1 of face 0 (opposite corner 1)");
        assert_eq!(a.face, 1);
        assert_eq!(s.across(1, a.side as usize).unwrap().face, 0);
        assert_eq!(s.vertex_neighbours(0), &[1, 2, 3]);
        assert!((s.rest_area() - 1.0).abs() < 1e-6);
        for n in s.rest_vertex_normals() {
            assert!((*n - Vec3::Z).length() < 1e-6);
        }
    }

    #[test]
    fn vertex_normals_reuse_the_buffer() {
        let pos = [0., 0., 0., 1., 0., 0., 0., 1., 0.];
        let mesh = weld(&MeshInput::new(&pos, &[0, 1, 2])).unwrap();
        let s = Surface::new(&mesh);
        let mut out = Vec::with_capacity(8);
        let cap = out.capacity();
        let flipped: Vec<Vec3> = mesh.positions.iter().map(|p| Vec3::new(p.x, -p.y, p.z)).collect();
        s.vertex_normals(&flipped, &mut out);
        assert_eq!(out.capacity(), cap);
        assert!((out[0] + Vec3::Z).length() < 1e-6);
    }
}
