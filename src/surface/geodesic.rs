//! The approximate geodesic distance `G` of Algorithm 1, for nearby points.
//!
//! Algorithm 1 only ever compares `G` between points less than `2 d_i`
//! apart, so an approximation suffices; but plain 3-D distance confuses the
//! two skins of a thin part (a wing's upper and lower surfaces are close in
//! space and far on the surface). Our `G(p, q)` is:
//!
//! * the 3-D distance `|p − q|`, when `q` lies on the piece of surface that
//!   is connected to `p` inside the ball of radius `R` around `p` (the
//!   [`NearbyPatch`]; faces join across edges that pass through the ball),
//!   and their normals are not opposed (`n_p · n_q ≥ −½`, i.e. within 120°);
//! * `+∞` (far) otherwise.
//!
//! The connectivity test alone separates the skins of a closed thin plate
//! everywhere except within `R` of its rim; the normal test separates them
//! there too. On a curved piece narrower than `R` (a thin leg) the chord
//! underestimates the true geodesic, which only makes such parts a little
//! sparser than `d` asks; points more than 120° apart around it count as
//! far, which lets both sides of a very thin limb carry a root.

use super::Surface;
use glam::Vec3;

/// Normals whose cosine is below this are opposed: their points are on
/// different skins whatever the connectivity says.
pub(crate) const OPPOSED_NORMAL_COS: f32 = -0.5;

/// The faces connected to a centre point inside a ball: the support of `G`
/// around one point. Reusable scratch space; one per thread.
#[derive(Clone, Debug)]
pub struct NearbyPatch {
    inside: Vec<u32>,
    epoch: u32,
    stack: Vec<u32>,
    faces: Vec<u32>,
    center: Vec3,
    normal: Vec3,
    radius: f32,
}

impl NearbyPatch {
    /// Scratch space for `surface`.
    pub fn new(surface: &Surface) -> Self {
        Self {
            inside: vec![0; surface.face_count()],
            epoch: 0,
            stack: Vec::new(),
            faces: Vec::new(),
            center: Vec3::ZERO,
            normal: Vec3::Z,
            radius: 0.0,
        }
    }

    /// Collects the faces reachable from `face` (which holds `center`)
    /// through edges that pass within `radius` of `center`, at the pose
    /// `positions`. `normal` is the unit surface normal at `center`.
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
        self.stack.clear();
        self.mark(face);
        self.stack.push(face);
        let r2 = radius * radius;
        while let Some(f) = self.stack.pop() {
            for side in 0..3 {
                let e = surface.face_edge(f as usize, side) as usize;
                let faces = surface.faces_of_edge(e);
                if faces.len() < 2 || faces.iter().all(|&g| self.contains_face(g)) {
                    continue;
                }
                let [a, b] = surface.edge_vertices(e).map(|v| positions[v as usize]);
                if segment_distance_squared(center, a, b) > r2 {
                    continue;
                }
                for &g in faces {
                    if !self.contains_face(g) {
                        self.mark(g);
                        self.stack.push(g);
                    }
                }
            }
        }
    }

    /// Whether face `f` is part of the patch.
    #[inline]
    pub fn contains_face(&self, f: u32) -> bool {
        self.inside[f as usize] == self.epoch
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
    /// `q_normal`: the 3-D distance when `q` is on the same skin, `+∞` when
    /// it is not (see the module notes). Only meaningful up to the radius
    /// the patch was gathered with.
    #[inline]
    pub fn geodesic_to(&self, q: Vec3, q_normal: Vec3, q_face: u32) -> f32 {
        if !self.contains_face(q_face) || self.normal.dot(q_normal) < OPPOSED_NORMAL_COS {
            return f32::INFINITY;
        }
        (q - self.center).length()
    }

    fn mark(&mut self, f: u32) {
        self.inside[f as usize] = self.epoch;
        self.faces.push(f);
    }

    fn next_epoch(&mut self) {
        if self.epoch == u32::MAX {
            self.inside.iter_mut().for_each(|s| *s = 0);
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
        // With a ball reaching the rim, the rim joins the skins, but the
        // normal test still keeps them apart.
        patch.gather(&s, &pos, 3, top, Vec3::Z, 3.0);
        assert!(patch.contains_face(0) || patch.contains_face(1));
        assert_eq!(patch.geodesic_to(bottom, -Vec3::Z, 0), f32::INFINITY);
    }
}
