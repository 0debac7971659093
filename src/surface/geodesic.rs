//! The approximate geodesic distance `G` of Algorithm 1, for nearby points.
//!
//! Algorithm 1 only compares `G` between points less than `2 d_i` apart,
//! so an approximation suffices; but plain 3-D distance confuses the two
//! skins of a thin part (a wing's upper and lower surfaces are close in
//! space and far on the surface). Our `G(p, q)` is:
//!
//! * `|p − q|` when the normals face the same way (`n_p · n_q > 0`): such
//!   points compete for the same space whether or not the surface joins
//!   them nearby (a wing lying on the body, parts that touch);
//! * otherwise `max(|p − q|, reach(q))`, where `reach(q)` is the smallest
//!   radius of a ball around `p` inside which the surface connects `p` to
//!   `q` (a bottleneck distance over the faces, computed by the
//!   [`NearbyPatch`]), and `+∞` when they are not connected within the
//!   gathered radius. Any surface path from `p` to `q` leaves that ball, so
//!   this is still a lower bound of the true geodesic distance.
//!
//! So the skins of a closed thin plate are as far apart as their way round
//! the rim, while the sides of a limb thinner than `d` are as near as the
//! chord across it (one ring of roots, not one per side).

use super::Surface;
use glam::Vec3;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Normals whose cosine exceeds this face the same way.
pub(crate) const SAME_FACING_COS: f32 = 0.0;

/// The faces connected to a centre point inside a ball, each with its
/// reach: the support of `G` around one point. Reusable scratch space; one
/// per thread.
#[derive(Clone, Debug)]
pub struct NearbyPatch {
    stamp: Vec<u32>,
    reach: Vec<f32>,
    epoch: u32,
    heap: BinaryHeap<Reverse<(u32, u32)>>,
    faces: Vec<u32>,
    center: Vec3,
    normal: Vec3,
    radius: f32,
}

impl NearbyPatch {
    /// Scratch space for `surface`.
    pub fn new(surface: &Surface) -> Self {
        Self {
            stamp: vec![0; surface.face_count()],
            reach: vec![f32::INFINITY; surface.face_count()],
            epoch: 0,
            heap: BinaryHeap::new(),
            faces: Vec::new(),
            center: Vec3::ZERO,
            normal: Vec3::Z,
            radius: 0.0,
        }
    }

    /// Collects the faces reachable from `face` (which holds `center`)
    /// through edges that pass within `radius` of `center`, at the pose
    /// `positions`, with each face's reach (the least, over paths, of the
    /// farthest edge crossed). `normal` is the unit normal at `center`.
    pub fn gather(
        &mut self,
        surface: &Surface,
        positions: &[Vec3],
        face: u32,
        center: Vec3,
        normal: Vec3,
        radius: f32,
    ) {
        self.next_epoch();
        self.center = center;
        self.normal = normal;
        self.radius = radius;
        self.faces.clear();
        self.heap.clear();
        self.offer(face, 0.0);
        let r2 = radius * radius;
        // Dijkstra on the bottleneck. Reach values are >= 0, so their bit
        // patterns order like the values; ties go to the lower face index.
        while let Some(Reverse((bits, f))) = self.heap.pop() {
            let reach = f32::from_bits(bits);
            if reach > self.reach[f as usize] {
                continue;
            }
            for side in 0..3 {
                let e = surface.face_edge(f as usize, side) as usize;
                let faces = surface.faces_of_edge(e);
                if faces.len() < 2 {
                    continue;
                }
                let [a, b] = surface.edge_vertices(e).map(|v| positions[v as usize]);
                let edge2 = segment_distance_squared(center, a, b);
                if edge2 > r2 {
                    continue;
                }
                let through = reach.max(edge2.sqrt());
                for &g in faces {
                    self.offer(g, through);
                }
            }
        }
    }

    /// Whether face `f` is part of the patch.
    #[inline]
    pub fn contains_face(&self, f: u32) -> bool {
        self.stamp[f as usize] == self.epoch
    }

    /// The reach of face `f`: the smallest ball radius around the centre
    /// within which the surface connects the centre to `f` (`+∞` outside
    /// the patch).
    #[inline]
    pub fn reach(&self, f: u32) -> f32 {
        if self.contains_face(f) { self.reach[f as usize] } else { f32::INFINITY }
    }

    /// The faces of the patch, in discovery order.
    pub fn faces(&self) -> &[u32] {
        &self.faces
    }

    /// The patch's centre.
    pub fn center(&self) -> Vec3 {
        self.center
    }

    /// The radius the patch was gathered with.
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// `G(centre, q)` for a point `q` on face `q_face` with unit normal
    /// `q_normal` (see the module notes). Meaningful up to the radius the
    /// patch was gathered with; `+∞` means "farther than that".
    #[inline]
    pub fn geodesic_to(&self, q: Vec3, q_normal: Vec3, q_face: u32) -> f32 {
        let chord = (q - self.center).length();
        if self.normal.dot(q_normal) > SAME_FACING_COS { chord } else { chord.max(self.reach(q_face)) }
    }

    fn offer(&mut self, f: u32, reach: f32) {
        let i = f as usize;
        if self.stamp[i] != self.epoch {
            self.stamp[i] = self.epoch;
            self.faces.push(f);
        } else if reach >= self.reach[i] {
            return;
        }
        self.reach[i] = reach;
        self.heap.push(Reverse((reach.to_bits(), f)));
    }

    fn next_epoch(&mut self) {
        if self.epoch == u32::MAX {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.epoch = 0;
        }
        self.epoch += 1;
    }
}

/// Squared distance from `p` to the segment `ab`.
#[inline]
pub(crate) fn segment_distance_squared(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 { ((p - a).dot(ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (a + ab * t - p).length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{MeshInput, weld};

    /// A closed box 4 × 4 × `t`: two skins `t` apart joined at the rim.
    fn thin_box(t: f32) -> (Surface, Vec<Vec3>) {
        let mut pos = Vec::new();
        let corners = [(0., 0.), (4., 0.), (4., 4.), (0., 4.)];
        for z in [0.0, t] {
            for (x, y) in corners {
                pos.extend_from_slice(&[x, y, z]);
            }
        }
        let idx = [
            0, 2, 1, 0, 3, 2, // bottom (facing −z)
            4, 5, 6, 4, 6, 7, // top
            0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7,
        ];
        let mesh = weld(&MeshInput::new(&pos, &idx)).unwrap();
        (Surface::new(&mesh), mesh.positions)
    }

    #[test]
    fn skins_of_a_thin_box_are_far_apart() {
        let (s, pos) = thin_box(0.05);
        let mut patch = NearbyPatch::new(&s);
        let top = Vec3::new(2.0, 2.1, 0.05);
        let bottom = Vec3::new(2.0, 2.0, 0.0);
        patch.gather(&s, &pos, 3, top, Vec3::Z, 1.0);
        assert!(patch.contains_face(2));
        assert!(!patch.contains_face(0) && !patch.contains_face(1), "bottom skin is not reachable inside the ball");
        assert_eq!(patch.geodesic_to(bottom, -Vec3::Z, 0), f32::INFINITY);
        let g = patch.geodesic_to(Vec3::new(2.5, 2.1, 0.05), Vec3::Z, 2);
        assert!((g - 0.5).abs() < 1e-6);
        // With a ball reaching the rim the skins join, but only as far as
        // the way round the rim: at least the distance to the rim edge.
        patch.gather(&s, &pos, 3, top, Vec3::Z, 3.0);
        assert!(patch.contains_face(0) || patch.contains_face(1));
        let g = patch.geodesic_to(bottom, -Vec3::Z, 0);
        assert!((g - 1.9).abs() < 0.06, "G = {g}");
        // Facing the same way, points are as near as their chord, joined or not.
        patch.gather(&s, &pos, 3, top, Vec3::Z, 1.0);
        assert!((patch.geodesic_to(bottom, Vec3::Z, 0) - 0.1118).abs() < 1e-3);
    }
}
