//! A skinned test character: a standing figure (+Y up, facing +Z) made of
//! capsules (torso, head, upper and lower arms and legs), skinned to a
//! skeleton of 16 joints, each capsule rigid to its bone except near its
//! ends, where the weights blend into the neighbouring bone's joint.

use super::shapes::Shape;
use glam::{Quat, Vec3};
use std::f32::consts::{PI, TAU};

/// Joint positions at rest and parents.
pub const JOINTS: [([f32; 3], i32); 16] = [
    ([0.0, 1.0, 0.0], -1),    // 0 hips
    ([0.0, 1.45, 0.0], 0),    // 1 chest
    ([0.0, 1.6, 0.0], 1),     // 2 neck
    ([0.0, 1.95, 0.0], 2),    // 3 head top (end)
    ([0.22, 1.45, 0.0], 1),   // 4 left shoulder
    ([0.55, 1.45, 0.0], 4),   // 5 left elbow
    ([0.85, 1.45, 0.0], 5),   // 6 left hand (end)
    ([-0.22, 1.45, 0.0], 1),  // 7 right shoulder
    ([-0.55, 1.45, 0.0], 7),  // 8 right elbow
    ([-0.85, 1.45, 0.0], 8),  // 9 right hand (end)
    ([0.11, 0.95, 0.0], 0),   // 10 left hip
    ([0.11, 0.52, 0.0], 10),  // 11 left knee
    ([0.11, 0.08, 0.0], 11),  // 12 left foot (end)
    ([-0.11, 0.95, 0.0], 0),  // 13 right hip
    ([-0.11, 0.52, 0.0], 13), // 14 right knee
    ([-0.11, 0.08, 0.0], 14), // 15 right foot (end)
];

/// The limbs' bones, (joint, child joint), and the capsule radius of each.
pub const LIMBS: [(usize, usize, f32); 8] = [
    (4, 5, 0.06),
    (5, 6, 0.05),
    (7, 8, 0.06),
    (8, 9, 0.05),
    (10, 11, 0.08),
    (11, 12, 0.065),
    (13, 14, 0.08),
    (14, 15, 0.065),
];

/// The character: the mesh, one joint and weight pair per vertex slot
/// (`INFLUENCES` per vertex), and which capsule each vertex belongs to
/// (`None` for the torso and head; `Some(k)` for `LIMBS[k]`), with its
/// parameter along the capsule's axis (0 at the joint, 1 at the child).
pub struct Character {
    pub shape: Shape,
    pub vertex_joints: Vec<u32>,
    pub vertex_weights: Vec<f32>,
    pub limb: Vec<Option<usize>>,
    pub along: Vec<f32>,
}

/// Joints per vertex.
pub const INFLUENCES: usize = 2;

pub fn joint_positions() -> Vec<f32> {
    JOINTS.iter().flat_map(|(p, _)| *p).collect()
}

pub fn joint_parents() -> Vec<i32> {
    JOINTS.iter().map(|(_, p)| *p).collect()
}

fn joint(j: usize) -> Vec3 {
    Vec3::from_array(JOINTS[j].0)
}

/// A closed capsule from `a` to `b` of radius `r`: `rings` rings along
/// the cylinder, `cap` rings per hemisphere, `sides` vertices round.
/// Returns the shape and each vertex's parameter along the axis (the
/// caps' vertices are clamped to 0 and 1).
fn capsule(a: Vec3, b: Vec3, r: f32, rings: usize, cap: usize, sides: usize) -> (Shape, Vec<f32>) {
    let axis = (b - a).normalize();
    let len = (b - a).length();
    let u = axis.any_orthonormal_vector();
    let v = axis.cross(u);
    let mut s = Shape::default();
    let mut along = Vec::new();
    // Profile: (offset along the axis from a, radius), pole to pole.
    let mut profile = vec![(-r, 0.0f32)];
    for k in 1..=cap {
        let t = PI / 2.0 * k as f32 / (cap + 1) as f32;
        profile.push((-r * t.cos(), r * t.sin()));
    }
    for k in 0..=rings {
        profile.push((len * k as f32 / rings as f32, r));
    }
    for k in (1..=cap).rev() {
        let t = PI / 2.0 * k as f32 / (cap + 1) as f32;
        profile.push((len + r * t.cos(), r * t.sin()));
    }
    profile.push((len + r, 0.0));
    // The poles are single vertices; every other profile entry is a ring.
    let mut ring_start = Vec::new();
    for (i, &(x, rad)) in profile.iter().enumerate() {
        ring_start.push(s.vertex_count() as u32);
        let count = if i == 0 || i + 1 == profile.len() { 1 } else { sides };
        for k in 0..count {
            let t = TAU * k as f32 / sides as f32;
            let p = a + axis * x + (u * t.cos() + v * t.sin()) * rad;
            s.positions.extend_from_slice(&p.to_array());
            along.push((x / len).clamp(0.0, 1.0));
        }
    }
    let last = profile.len() - 1;
    for k in 0..sides as u32 {
        let n = sides as u32;
        let (r1, next) = (ring_start[1], (k + 1) % n);
        s.indices.extend_from_slice(&[ring_start[0], r1 + next, r1 + k]);
        for i in 1..last - 1 {
            let (p, q) = (ring_start[i], ring_start[i + 1]);
            s.indices.extend_from_slice(&[p + k, p + next, q + next, p + k, q + next, q + k]);
        }
        let rl = ring_start[last - 1];
        s.indices.extend_from_slice(&[ring_start[last], rl + k, rl + next]);
    }
    (s, along)
}

/// The character at rest.
pub fn character() -> Character {
    let mut c = Character {
        shape: Shape::default(),
        vertex_joints: Vec::new(),
        vertex_weights: Vec::new(),
        limb: Vec::new(),
        along: Vec::new(),
    };
    // Weights: the owning joint, blending over the last 15 % of the axis
    // into `next` (the child's joint) and over the first 15 % into `prev`.
    let mut add =
        |shape: Shape, along: Vec<f32>, own: u32, prev: Option<u32>, next: Option<u32>, limb: Option<usize>| {
            for &t in &along {
                let (other, w) = match (prev, next) {
                    (Some(p), _) if t < 0.15 => (p, 0.5 * (0.15 - t) / 0.15),
                    (_, Some(n)) if t > 0.85 => (n, 0.5 * (t - 0.85) / 0.15),
                    _ => (own, 0.0),
                };
                c.vertex_joints.extend_from_slice(&[own, other]);
                c.vertex_weights.extend_from_slice(&[1.0 - w, w]);
                c.limb.push(limb);
                c.along.push(t);
            }
            c.shape.append(&shape);
        };
    let (torso, t) =
        capsule(joint(0) + Vec3::new(0.0, -0.05, 0.0), joint(1) + Vec3::new(0.0, 0.05, 0.0), 0.17, 10, 4, 24);
    add(torso, t, 0, None, Some(1), None);
    let (head, t) = capsule(joint(2), joint(3) - Vec3::new(0.0, 0.1, 0.0), 0.1, 5, 4, 16);
    add(head, t, 2, Some(1), None, None);
    for (k, &(j, child, r)) in LIMBS.iter().enumerate() {
        let (limb, t) = capsule(joint(j), joint(child), r, 8, 3, 12);
        let parent = JOINTS[j].1 as u32;
        let next = JOINTS.iter().any(|(_, p)| *p == child as i32).then_some(child as u32);
        add(limb, t, j as u32, Some(parent), next, Some(k));
    }
    c
}

/// The character's vertices posed by linear blend skinning with the arms
/// and legs swung by `t` (radians of swing at the shoulders and hips, the
/// elbows and knees bent by half of it), at rest for `t = 0`.
pub fn posed(c: &Character, t: f32) -> Vec<f32> {
    // Per joint, its rotation about its own position, composed down the tree.
    let mut local = [Quat::IDENTITY; 16];
    local[4] = Quat::from_rotation_z(-0.6 * t);
    local[7] = Quat::from_rotation_z(0.6 * t);
    local[5] = Quat::from_rotation_y(0.5 * t);
    local[8] = Quat::from_rotation_y(-0.5 * t);
    local[10] = Quat::from_rotation_x(t);
    local[13] = Quat::from_rotation_x(-t);
    local[11] = Quat::from_rotation_x(-0.5 * t.abs());
    local[14] = Quat::from_rotation_x(-0.5 * t.abs());
    // World transform of each joint: rotation R and translation so that
    // x ↦ R x + o maps rest space to the pose.
    let mut rot = [Quat::IDENTITY; 16];
    let mut off = [Vec3::ZERO; 16];
    for j in 0..16 {
        let p = JOINTS[j].1;
        let (pr, po) = if p < 0 { (Quat::IDENTITY, Vec3::ZERO) } else { (rot[p as usize], off[p as usize]) };
        // Rotate about the joint's rest position, then apply the parent's.
        let pivot = joint(j);
        rot[j] = pr * local[j];
        off[j] = pr * (pivot - local[j] * pivot) + po;
    }
    let mut out = Vec::with_capacity(c.shape.positions.len());
    for v in 0..c.shape.vertex_count() {
        let x = Vec3::from_array(c.shape.vertex(v));
        let mut p = Vec3::ZERO;
        for k in 0..INFLUENCES {
            let (j, w) = (c.vertex_joints[INFLUENCES * v + k] as usize, c.vertex_weights[INFLUENCES * v + k]);
            p += (rot[j] * x + off[j]) * w;
        }
        out.extend_from_slice(&p.to_array());
    }
    out
}
