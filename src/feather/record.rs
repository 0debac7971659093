//! Feathers for instancing (DESIGN.md §7): one feather packed into a
//! 36-byte [`InstanceRecord`] that a renderer expands from one shared
//! [`FeatherTemplate`] (the card), and the expansion itself
//! ([`InstanceRecord::place`]), written the way the reference vertex shader
//! (`shaders/feather_instance.vert`) does it.
//!
//! # The convention
//!
//! A feather's *own frame* is its root frame turned by its roll and pitch:
//!
//! - the root frame (see [`RootFrame`]) has x along the tangential
//!   orientation `õ`, y along the binormal `b`, z along the surface normal
//!   `n`; it is right-handed (x × y = z);
//! - roll β turns it about its x axis by the right-hand rule (a positive
//!   roll lifts the +y vane towards +z, off the skin);
//! - pitch α then turns it about its (unrolled) y axis so that x goes
//!   towards +z: a positive pitch lifts the tip off the skin (a rotation
//!   by −α about +y in the right-hand sense).
//!
//! The record's unit quaternion `q` is that whole rotation, own frame to
//! world: `q = q_frame · rot_y(−α) · rot_x(β)`.
//!
//! In its own frame the feather's shaft starts at the origin along +x and
//! is cut into `S` equal segments (`S` = [`FeatherTemplate::segments`]).
//! Segment `k` points along `(cos a_k, 0, sin a_k)`, where `a_0 = 0` and
//! `a_k = a_{k−1} + bend_k`: a joint's bend turns every segment after it
//! about the own frame's y axis, a positive bend towards +z (away from the
//! skin), a negative one down towards it. A template vertex `(u, v, 0)`
//! (u along the unbent shaft as a fraction of the length, v across it as a
//! fraction of the width) carried by segment `k` lands at
//!
//! ```text
//! p = Σ_{j<k} (L/S)·(cos a_j, 0, sin a_j) + (u − k/S)·L·(cos a_k, 0, sin a_k) + (0, v·W, 0)
//! world = root + q · p
//! ```
//!
//! with `L`, `W` the record's length and width. That is exactly how
//! [`feather_triangles`](super::feather_triangles) poses a feather: the vane
//! edge at a station lies the kite's half-width off the shaft, on the
//! segment that holds the station, and each segment with its vanes stays
//! flat.
//!
//! # Packing
//!
//! The root and the size are kept as f32 (f16 would cost up to 5e-4 of a
//! length). The quaternion is four snorm16 (`value / 32767`), with `w ≥ 0`,
//! rounded component by component to whichever of the 16 neighbouring
//! lattice points turns least from the exact rotation; decode by dividing
//! by 32767 and normalising. Bends are snorm16 scaled by
//! [`RECORD_BEND_RANGE`] (π): `bend = value · π / 32767`, a step of about
//! 9.6e-5 radians. They are rounded so that every running sum `a_k` of the
//! decoded bends is the exact running sum rounded to a step, so rounding
//! errors do not add up along the shaft. Joints past `S − 1` are 0.

use super::mesh::FeatherMeshLayout;
use super::pose::FeatherPose;
use super::shape::{FeatherShape, MAX_JOINTS, MAX_SEGMENTS};
use crate::geometry::RootFrame;
use glam::{DMat3, DQuat, Quat, Vec2, Vec3};

/// The bend a record's snorm16 of 32767 stands for, radians: decoded
/// bends are `value · RECORD_BEND_RANGE / 32767`. Bends are limited well
/// inside it (at most 2 × 1.2 radians towards the skin).
pub const RECORD_BEND_RANGE: f32 = std::f32::consts::PI;

/// The largest snorm16.
const SNORM16: f64 = 32767.0;

/// One feather for instancing (36 bytes as the C struct
/// `PlumageFeatherInstance`): see the module's convention.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct InstanceRecord {
    /// Root position, world space.
    pub root: [f32; 3],
    /// The own frame's rotation as a unit quaternion (x, y, z, w), snorm16,
    /// `w ≥ 0`.
    pub rotation: [i16; 4],
    /// Length as placed (0 for a feather left out: every vertex at the root).
    pub length: f32,
    /// Width as placed.
    pub width: f32,
    /// Each joint's bend, snorm16 scaled by [`RECORD_BEND_RANGE`].
    pub bends: [i16; MAX_JOINTS],
}

impl InstanceRecord {
    /// The record of a feather of `shape` posed by `pose` at `frame`.
    pub fn pack(frame: &RootFrame, shape: &FeatherShape, pose: &FeatherPose) -> Self {
        Self {
            root: frame.position.to_array(),
            rotation: pack_rotation(own_rotation(frame, pose)),
            length: shape.length * pose.scale,
            width: shape.width * pose.scale,
            bends: pack_bends(&pose.bends, shape.segment_count() - 1),
        }
    }

    /// The decoded rotation, own frame to world (normalised).
    pub fn rotation(&self) -> Quat {
        let [x, y, z, w] = self.rotation.map(|c| c as f32 / SNORM16 as f32);
        Quat::from_xyzw(x, y, z, w).normalize()
    }

    /// The decoded bend of joint `k` (0 the first joint from the root), radians.
    #[inline]
    pub fn bend(&self, k: usize) -> f32 {
        self.bends[k] as f32 * (RECORD_BEND_RANGE / SNORM16 as f32)
    }

    /// The template's vertices placed and bent by this record, world space,
    /// appended to `out` in the template's order (the CPU twin of the
    /// reference vertex shader).
    pub fn place(&self, template: &FeatherTemplate, out: &mut Vec<Vec3>) {
        let q = self.rotation();
        let root = Vec3::from_array(self.root);
        let s = template.segments;
        let step = self.length / s as f32;
        // Where each segment starts along the bent shaft (x, z) and its angle.
        let mut starts = [Vec2::ZERO; MAX_SEGMENTS];
        let mut angles = [0.0f32; MAX_SEGMENTS];
        let mut at = Vec2::ZERO;
        let mut angle = 0.0f32;
        for k in 0..s {
            if k > 0 {
                angle += self.bend(k - 1);
            }
            starts[k] = at;
            angles[k] = angle;
            let (sin, cos) = angle.sin_cos();
            at += Vec2::new(cos, sin) * step;
        }
        for (v, &k) in template.positions.iter().zip(&template.vertex_segments) {
            let k = k as usize;
            let along = (v[0] - k as f32 / s as f32) * self.length;
            let (sin, cos) = angles[k].sin_cos();
            let shaft = starts[k] + Vec2::new(cos, sin) * along;
            out.push(root + q * Vec3::new(shaft.x, v[1] * self.width, shaft.y));
        }
    }
}

/// The feather's own frame to world (see the module's convention), exact
/// in f64 from the f32 frame and angles, with `w ≥ 0`.
fn own_rotation(frame: &RootFrame, pose: &FeatherPose) -> DQuat {
    let axes = DMat3::from_cols(frame.tangent.as_dvec3(), frame.binormal.as_dvec3(), frame.normal.as_dvec3());
    let q = DQuat::from_mat3(&axes)
        * DQuat::from_rotation_y(-f64::from(pose.pitch))
        * DQuat::from_rotation_x(f64::from(pose.roll));
    let q = q.normalize();
    if q.w < 0.0 { -q } else { q }
}

/// `q` as snorm16: of the 16 lattice points around `q · 32767` (each
/// component rounded down or up), the one whose direction is nearest
/// `q`'s. Rounding each component to nearest is one of them, so the turn
/// a decoder sees is never larger; over 20 000 random rotations it was at
/// most 4.95e-5 radians, 2.4e-5 on average (to nearest: 5.6e-5, 2.9e-5).
fn pack_rotation(q: DQuat) -> [i16; 4] {
    let scaled = q.to_array().map(|c| c * SNORM16);
    let mut best = [0i16; 4];
    let mut best_cos = f64::NEG_INFINITY;
    for corner in 0..16u32 {
        let c: [f64; 4] = std::array::from_fn(|i| {
            let v = if corner >> i & 1 == 1 { scaled[i].ceil() } else { scaled[i].floor() };
            v.clamp(-SNORM16, SNORM16)
        });
        let norm = c.iter().map(|v| v * v).sum::<f64>().sqrt();
        if norm == 0.0 {
            continue;
        }
        let cos = c.iter().zip(&scaled).map(|(a, b)| a * b).sum::<f64>() / norm;
        if cos > best_cos {
            best_cos = cos;
            best = c.map(|v| v as i16);
        }
    }
    best
}

/// The first `joints` bends as snorm16 (see the module's packing note).
fn pack_bends(bends: &[f32; MAX_JOINTS], joints: usize) -> [i16; MAX_JOINTS] {
    let step = f64::from(RECORD_BEND_RANGE) / SNORM16;
    let mut out = [0i16; MAX_JOINTS];
    let (mut exact, mut packed) = (0.0f64, 0i64);
    for (k, slot) in out.iter_mut().enumerate().take(joints) {
        exact += f64::from(bends[k]);
        let value = ((exact / step).round() as i64 - packed).clamp(-32767, 32767);
        *slot = value as i16;
        packed += value;
    }
    out
}

/// The card every feather of one shape is drawn from: its vertices in the
/// feather's own frame for unit length and width (x along the unbent
/// shaft from 0 at the root to 1 at the tip, y across, −0.5 to 0.5 at the
/// vane corners, z 0), their UVs, the triangles, and the shaft segment
/// that carries each vertex. Vertices and triangles are one feather's of
/// the copied-out geometry, in the same order
/// ([`FeatherMeshLayout`]).
#[derive(Clone, Debug, PartialEq)]
pub struct FeatherTemplate {
    /// Shaft segments `S`.
    pub segments: usize,
    /// Where the vane corners sit along the shaft (fraction of the length).
    pub vane_split: f32,
    /// Per vertex: (x, y, 0) in the own frame for unit length and width.
    pub positions: Vec<[f32; 3]>,
    /// Per vertex: (u, v) as in the geometry (u = x, v = 0.5 + y).
    pub uvs: Vec<[f32; 2]>,
    /// Triangles, facing away from the skin.
    pub triangles: Vec<[u32; 3]>,
    /// Per vertex: the segment (0 at the root) whose direction carries it:
    /// the shaft up to joint `k`, then `(x − k/S)` of the length along
    /// segment `k`.
    pub vertex_segments: Vec<u32>,
}

impl FeatherTemplate {
    /// The card of feathers of `shape` (its length and width do not matter).
    pub fn of(shape: &FeatherShape) -> Self {
        let layout = FeatherMeshLayout::of(shape);
        let s = shape.segment_count();
        let unit = FeatherShape { length: 1.0, width: 1.0, ..*shape };
        let positions: Vec<[f32; 3]> = layout
            .uvs
            .iter()
            .map(|&[u, v]| {
                let half = unit.half_width_at(u).max(0.0);
                let across = if v > 0.5 {
                    half
                } else if v < 0.5 {
                    -half
                } else {
                    0.0
                };
                [u, across, 0.0]
            })
            .collect();
        // The segment holding a station, as the posed feather finds it.
        let vertex_segments = positions.iter().map(|p| ((p[0] * s as f32) as usize).min(s - 1) as u32).collect();
        Self {
            segments: s,
            vane_split: shape.vane_split,
            positions,
            uvs: layout.uvs,
            triangles: layout.triangles,
            vertex_segments,
        }
    }

    /// Vertices of the card.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::feather::FeatherMesh;

    fn frame() -> RootFrame {
        let n = Vec3::new(0.3, -0.5, 0.8);
        RootFrame::from_normal_and_direction(Vec3::new(1.0, -2.0, 0.5), n, Vec3::new(0.2, 0.9, 0.1)).unwrap()
    }

    /// Largest distance between the placed template and the posed mesh, in lengths.
    fn placement_error(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> f32 {
        let mesh = FeatherMesh::build(&[*frame], &[*shape], &[pose]);
        let record = InstanceRecord::pack(frame, shape, &pose);
        let mut placed = Vec::new();
        record.place(&FeatherTemplate::of(shape), &mut placed);
        assert_eq!(placed.len(), mesh.positions.len());
        placed.iter().zip(&mesh.positions).map(|(a, b)| a.distance(Vec3::from_array(*b))).fold(0.0, f32::max)
            / shape.length
    }

    #[test]
    fn records_place_the_template_where_the_mesh_is() {
        let f = frame();
        for segments in 1..=MAX_SEGMENTS as u32 {
            let shape = FeatherShape::for_spacing(0.3).with_segments(segments);
            for (pitch, roll, bends) in
                [(0.0, 0.0, [0.0; 3]), (0.4, -0.3, [-0.5, 0.2, -0.8]), (-0.2, 0.6, [0.9, -2.3, 1.1])]
            {
                let mut pose = FeatherPose::new(pitch, roll).with_scale(0.8);
                pose.bends = bends;
                if segments < 4 {
                    pose.bends[segments as usize - 1..].iter_mut().for_each(|b| *b = 0.0);
                }
                let e = placement_error(&f, &shape, pose);
                assert!(e < 1e-4, "S = {segments}, pose {pose:?}: {e} lengths");
            }
        }
    }

    #[test]
    fn a_feather_left_out_places_every_vertex_at_its_root() {
        let f = frame();
        let shape = FeatherShape::for_spacing(0.3).with_segments(4);
        let record = InstanceRecord::pack(&f, &shape, &FeatherPose::new(0.2, 0.1).with_scale(0.0));
        assert_eq!((record.length, record.width), (0.0, 0.0));
        let mut placed = Vec::new();
        record.place(&FeatherTemplate::of(&shape), &mut placed);
        assert!(placed.iter().all(|p| *p == f.position));
    }

    #[test]
    fn the_convention_turns_the_way_it_says() {
        // Root frame = world axes: x õ, y b, z n.
        let f = RootFrame::from_normal_and_direction(Vec3::ZERO, Vec3::Z, Vec3::X).unwrap();
        let shape = FeatherShape { length: 1.0, width: 1.0, thickness: 0.0, vane_split: 0.5, segments: 2 };
        let template = FeatherTemplate::of(&shape);
        let place = |pose: FeatherPose| {
            let mut out = Vec::new();
            InstanceRecord::pack(&f, &shape, &pose).place(&template, &mut out);
            out
        };
        // Vertices: joints 0, 1, 2 (tip), then the +y edge, then the −y edge.
        let tip = 2;
        assert!(place(FeatherPose::new(0.3, 0.0))[tip].z > 0.2, "positive pitch lifts the tip");
        let rolled = place(FeatherPose::new(0.0, 0.3));
        let plus_y = template.positions.iter().position(|p| p[1] > 0.4).unwrap();
        assert!(rolled[plus_y].z > 0.1, "positive roll lifts the +y vane");
        let mut bent = FeatherPose::new(0.0, 0.0);
        bent.bends[0] = 0.5;
        let b = place(bent);
        assert!(b[1].z.abs() < 1e-6 && b[tip].z > 0.2, "a positive bend turns the outer segment up");
        assert_eq!(template.vertex_segments, vec![0, 1, 1, 1, 1]);
    }

    #[test]
    fn packed_rotations_turn_less_than_six_hundred_thousandths_of_a_radian() {
        let mut rng = crate::rng::Rng::new(7);
        let (mut worst, mut worst_nearest, mut sums) = (0.0f64, 0.0f64, (0.0f64, 0.0f64));
        let turn = |q: DQuat, c: [f64; 4]| {
            2.0 * q.dot(DQuat::from_xyzw(c[0], c[1], c[2], c[3]).normalize()).abs().min(1.0).acos()
        };
        for _ in 0..20_000 {
            let axis = glam::DVec3::new(rng.next_f64() - 0.5, rng.next_f64() - 0.5, rng.next_f64() - 0.5)
                .normalize_or(glam::DVec3::X);
            let q = DQuat::from_axis_angle(axis, rng.next_f64() * std::f64::consts::TAU);
            let q = if q.w < 0.0 { -q } else { q };
            let (a, b) =
                (turn(q, pack_rotation(q).map(f64::from)), turn(q, q.to_array().map(|c| (c * SNORM16).round())));
            worst = worst.max(a);
            worst_nearest = worst_nearest.max(b);
            sums.0 += a;
            sums.1 += b;
        }
        println!(
            "turn of a packed rotation: largest {worst:.2e} rad, mean {:.2e} (rounding to nearest: {worst_nearest:.2e}, {:.2e})",
            sums.0 / 20_000.0,
            sums.1 / 20_000.0
        );
        assert!(worst < 6e-5 && worst <= worst_nearest, "{worst}");
    }

    #[test]
    fn bend_running_sums_stay_within_half_a_step() {
        let bends = [0.123_456_7, -0.987_654_3, 2.345_678_9];
        let packed = pack_bends(&bends, 3);
        let step = f64::from(RECORD_BEND_RANGE) / SNORM16;
        let (mut exact, mut decoded) = (0.0f64, 0.0f64);
        for k in 0..3 {
            exact += f64::from(bends[k]);
            decoded += f64::from(packed[k]) * step;
            assert!((exact - decoded).abs() <= 0.5 * step + 1e-12, "joint {k}");
        }
        assert_eq!(pack_bends(&bends, 1)[1..], [0, 0]);
        assert!(std::mem::size_of::<InstanceRecord>() <= 40);
    }
}
