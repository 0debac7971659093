//! Feather roots bound to the rest mesh, and their frames at any pose.
//!
//! A root stores a face and barycentric weights, so it follows any
//! deformation. Its tangential orientation `õ_i` is stored in the face's edge
//! basis (`e1 = p1 − p0`, `e2 = p2 − p0`) and rebuilt from the deformed edges
//! at every pose, so the orientation turns and shears with the skin
//! (DESIGN.md §3).

use crate::geometry::{RootFrame, SurfacePoint, triangle_area_vector};
use crate::rng::hash64;
use glam::Vec3;
use rayon::prelude::*;

/// Roots posed per rayon task.
const POSE_CHUNK: usize = 2048;

/// One feather root bound to the rest mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RootBinding {
    /// Stable id: a hash of (face, sample index, seed), see [`root_id`].
    pub id: u64,
    /// Where the root is planted.
    pub point: SurfacePoint,
    /// Rest `õ_i` in the face's edge basis: `õ ∝ a·e1 + b·e2`.
    pub rest_direction: [f32; 2],
    /// Local Poisson-disk radius `d_i`.
    pub spacing: f32,
    /// Interpolated per-vertex length multiplier (1 when absent).
    pub length_scale: f32,
    /// Interpolated per-vertex width multiplier (1 when absent).
    pub width_scale: f32,
}

/// The stable id of the root grown from pool sample `sample_index` on
/// `face` with `seed`.
pub fn root_id(face: u32, sample_index: u64, seed: u64) -> u64 {
    hash64(&[face as u64, sample_index, seed])
}

/// Coordinates `(a, b)` of `direction` (projected onto the triangle's
/// plane) in the edge basis `e1 = p1 − p0`, `e2 = p2 − p0` of `corners`.
/// `[0, 0]` when the triangle has collapsed.
pub fn edge_basis_coordinates(corners: [Vec3; 3], direction: Vec3) -> [f32; 2] {
    let [p0, p1, p2] = corners;
    let (e1, e2) = (p1 - p0, p2 - p0);
    let area_vector = e1.cross(e2);
    let twice_area2 = area_vector.length_squared();
    if twice_area2.is_nan() || twice_area2 <= 0.0 || !twice_area2.is_finite() {
        return [0.0, 0.0];
    }
    // v = a e1 + b e2  ⇒  v × e2 = a (e1 × e2),  e1 × v = b (e1 × e2).
    let a = direction.cross(e2).dot(area_vector) / twice_area2;
    let b = e1.cross(direction).dot(area_vector) / twice_area2;
    if a.is_finite() && b.is_finite() { [a, b] } else { [0.0, 0.0] }
}

/// The world direction `a·e1 + b·e2` of edge-basis coordinates on `corners`.
#[inline]
pub fn direction_from_edge_basis(corners: [Vec3; 3], coords: [f32; 2]) -> Vec3 {
    let [p0, p1, p2] = corners;
    (p1 - p0) * coords[0] + (p2 - p0) * coords[1]
}

/// Which normal a root frame takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RootNormal {
    /// The blend of the corner normals (smooth across edges): where roots
    /// sit on the surface, for sampling and its figures.
    Smooth,
    /// The smooth normal turned towards the face normal until at most 15°
    /// from it: the frame feathers grow in (see `tilt_limited`).
    FaceLimited,
}

/// The largest angle between a feather root's normal and its face's
/// normal, as a cosine (15°).
const MAX_NORMAL_TILT_COS: f32 = 0.966;

/// `normal` turned towards `face` (both unit) until at most the largest
/// tilt apart. Near a sharp edge (a thin wing's rim, a crease where a limb
/// meets the body) the blended vertex normal leans far over the edge, and
/// a feather laid in that tangent plane would dive into its own face; the
/// limit keeps it lying along the face there, and changes nothing where
/// the surface is smooth.
fn tilt_limited(normal: Vec3, face: Vec3) -> Vec3 {
    let c = normal.dot(face);
    if c >= MAX_NORMAL_TILT_COS {
        return normal;
    }
    // The unit vector in the plane of (face, normal) at the largest tilt
    // from face, on normal's side.
    let side = (normal - face * c).try_normalize().unwrap_or_else(|| face.any_orthonormal_vector());
    let s = (1.0 - MAX_NORMAL_TILT_COS * MAX_NORMAL_TILT_COS).sqrt();
    (face * MAX_NORMAL_TILT_COS + side * s).normalize()
}

/// The frame of one root at the pose `positions` with vertex normals
/// `vertex_normals`: position from the barycentrics, normal the normalised
/// blend of the corner normals, `õ` the rest direction rebuilt from the
/// deformed edges and projected onto the tangent plane. Degenerate cases
/// fall back to the face normal, then the face's edges, so the frame is
/// always finite and orthonormal.
pub fn pose_root(
    root: &RootBinding,
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    vertex_normals: &[Vec3],
    rule: RootNormal,
) -> RootFrame {
    let tri = triangles[root.point.face as usize];
    let corners = tri.map(|v| positions[v as usize]);
    let position = root.point.position_on(corners);
    let face_normal = triangle_area_vector(corners[0], corners[1], corners[2]).try_normalize();
    let blend = (0..3).fold(Vec3::ZERO, |acc, k| acc + vertex_normals[tri[k] as usize] * root.point.bary[k]);
    let normal = blend.try_normalize().or(face_normal).unwrap_or(Vec3::Z);
    let normal = match (rule, face_normal) {
        (RootNormal::FaceLimited, Some(f)) => tilt_limited(normal, f),
        _ => normal,
    };
    let direction = direction_from_edge_basis(corners, root.rest_direction);
    let frame = |d: Vec3| RootFrame::from_normal_and_direction(position, normal, d);
    frame(direction)
        .or_else(|| frame(corners[1] - corners[0]))
        .or_else(|| frame(corners[2] - corners[0]))
        .or_else(|| frame(normal.any_orthonormal_vector()))
        .unwrap_or(RootFrame { position, normal: Vec3::Z, tangent: Vec3::X, binormal: Vec3::Y })
}

/// Poses every root into `out` (one frame per root, same order).
///
/// # Panics
/// When `out.len() != roots.len()`.
pub fn pose_roots_into(
    roots: &[RootBinding],
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    vertex_normals: &[Vec3],
    rule: RootNormal,
    out: &mut [RootFrame],
) {
    assert_eq!(out.len(), roots.len(), "one frame per root");
    out.par_iter_mut().zip(roots.par_iter()).with_min_len(POSE_CHUNK).for_each(|(frame, root)| {
        *frame = pose_root(root, positions, triangles, vertex_normals, rule);
    });
}

/// Poses every root into `out`, resized to the root count (no allocation
/// when its capacity suffices).
pub fn pose_roots(
    roots: &[RootBinding],
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    vertex_normals: &[Vec3],
    rule: RootNormal,
    out: &mut Vec<RootFrame>,
) {
    let blank = RootFrame { position: Vec3::ZERO, normal: Vec3::Z, tangent: Vec3::X, binormal: Vec3::Y };
    out.resize(roots.len(), blank);
    pose_roots_into(roots, positions, triangles, vertex_normals, rule, out);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root_on_unit_triangle(direction: Vec3) -> (RootBinding, Vec<Vec3>) {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        let corners = [positions[0], positions[1], positions[2]];
        let root = RootBinding {
            id: root_id(0, 0, 1),
            point: SurfacePoint { face: 0, bary: [0.5, 0.25, 0.25] },
            rest_direction: edge_basis_coordinates(corners, direction),
            spacing: 0.1,
            length_scale: 1.0,
            width_scale: 1.0,
        };
        (root, positions)
    }

    #[test]
    fn orientation_follows_a_rotation_of_the_face() {
        let (root, positions) = root_on_unit_triangle(Vec3::new(1.0, 1.0, 0.0));
        let tris = [[0u32, 1, 2]];
        let rest = pose_root(&root, &positions, &tris, &[Vec3::Z; 3], RootNormal::FaceLimited);
        assert!((rest.tangent - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
        assert!((rest.position - Vec3::new(0.25, 0.25, 0.0)).length() < 1e-6);
        // Rotate the face 90° about x: y → z, normal z → −y.
        let rot = glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
        let moved: Vec<Vec3> = positions.iter().map(|&p| rot * p).collect();
        let posed = pose_root(&root, &moved, &tris, &[rot * Vec3::Z; 3], RootNormal::FaceLimited);
        assert!((posed.tangent - rot * rest.tangent).length() < 1e-5);
        assert!((posed.normal - rot * Vec3::Z).length() < 1e-5);
    }

    #[test]
    fn collapsed_face_still_gives_a_finite_frame() {
        let (root, _) = root_on_unit_triangle(Vec3::X);
        let flat = vec![Vec3::ZERO, Vec3::ZERO, Vec3::ZERO];
        let mut out = Vec::with_capacity(4);
        pose_roots(&[root], &flat, &[[0, 1, 2]], &[Vec3::ZERO; 3], RootNormal::FaceLimited, &mut out);
        let f = out[0];
        for v in [f.position, f.normal, f.tangent, f.binormal] {
            assert!(v.is_finite());
        }
        assert!((f.normal.length() - 1.0).abs() < 1e-6 && f.normal.dot(f.tangent).abs() < 1e-6);
    }

    #[test]
    fn feather_normals_lean_at_most_15_degrees_from_the_face() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let tris = [[0u32, 1, 2]];
        let root = RootBinding {
            id: 1,
            point: SurfacePoint { face: 0, bary: [0.2, 0.4, 0.4] },
            rest_direction: [1.0, 0.0],
            spacing: 0.1,
            length_scale: 1.0,
            width_scale: 1.0,
        };
        // Corner normals leaning 60° over an edge (a sharp rim).
        let leaning = [Vec3::new(0.866, 0.0, 0.5).normalize(); 3];
        let smooth = pose_root(&root, &positions, &tris, &leaning, RootNormal::Smooth);
        let limited = pose_root(&root, &positions, &tris, &leaning, RootNormal::FaceLimited);
        assert!((smooth.normal - leaning[0]).length() < 1e-5);
        assert!((limited.normal.dot(Vec3::Z) - MAX_NORMAL_TILT_COS).abs() < 1e-4, "{:?}", limited.normal);
        assert!(limited.normal.x > 0.0 && limited.normal.y.abs() < 1e-6);
        // A gentle lean is kept.
        let gentle = [Vec3::new(0.1, 0.0, 1.0).normalize(); 3];
        assert!(
            (pose_root(&root, &positions, &tris, &gentle, RootNormal::FaceLimited).normal - gentle[0]).length() < 1e-5
        );
    }
}
