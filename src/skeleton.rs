//! A skin's skeleton as the host hands it in, and the flow it implies: from
//! the head down the trunk and out along every limb to its tip.
//!
//! The joints form a forest (each joint names its parent). Joints that no
//! vertex is weighted to and that have no weighted ancestor (an armature's
//! root on the floor, say) are left out; each remaining tree is re-rooted
//! at its *head*, an end joint (one bone attached) chosen by
//! [`SkeletonInput::head_joint`] or, when that is unset, the one farthest
//! towards the given front. Every bone then points away from the head: down
//! the neck, down the back to the tail and down each limb.
//!
//! A vertex's flow blends, by its skin weights, the directions of the bones
//! at each joint it is weighted to; at a joint where several bones meet,
//! the bones nearer the vertex count more (the inverse square of the
//! squared distance to the bone segment, softened by a fortieth of the
//! skeleton's extent): along a limb its own bone outweighs the others by
//! two orders of magnitude, and the flow still turns smoothly where a limb
//! leaves the trunk.

use crate::error::{Error, ErrorKind, Result};
use glam::Vec3;

/// The most joints a skeleton may have.
pub(crate) const MAX_JOINTS: usize = 1 << 16;

/// The most joints one vertex may be weighted to.
pub(crate) const MAX_INFLUENCES: usize = 16;

/// The most bones at one joint whose nearness is weighed: a vertex's flow
/// looks at every bone meeting each joint it is weighted to, so at a joint
/// with more (a rig's root with hundreds of children) only the bone coming
/// from the head is taken, and the work per vertex stays bounded.
const MAX_BONES_BLENDED: usize = 64;

/// The direction the head is looked for along: against the flow axis when
/// one is set (it runs from the front to the back), else glTF's up and
/// forward (+Y and +Z) together, so that a standing figure's head and a
/// quadruped's muzzle both win over its hands and tail.
pub fn front(flow_axis: Vec3) -> Vec3 {
    if flow_axis == Vec3::ZERO { Vec3::new(0.0, 1.0, 1.0) } else { -flow_axis }
}

/// A skeleton and the skin weights binding a mesh's vertices to it, all
/// borrowed from the caller, in the mesh's rest space and vertex numbering.
#[derive(Clone, Copy, Debug)]
pub struct SkeletonInput<'a> {
    /// xyz per joint at the rest pose, in the mesh's space.
    pub joint_positions: &'a [f32],
    /// Per joint, the index of its parent joint, or −1 for a root.
    pub joint_parents: &'a [i32],
    /// Joints each vertex is weighted to (the stride of the two arrays below).
    pub influences: usize,
    /// `influences` joint indices per vertex.
    pub vertex_joints: &'a [u32],
    /// `influences` weights per vertex (finite, ≥ 0; they need not sum to 1).
    pub vertex_weights: &'a [f32],
    /// The joint the flow starts from, or −1 to pick it (see the module doc).
    pub head_joint: i32,
}

impl SkeletonInput<'_> {
    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joint_parents.len()
    }

    /// Checks the arrays against each other and against `vertex_count`:
    /// lengths, finite values, indices in range, parents without a cycle.
    pub fn check(&self, vertex_count: usize) -> Result<()> {
        let joints = self.joint_count();
        let bad = |kind, text: String| Err(Error::new(kind, format!("skeleton: {text}")));
        if joints == 0 || joints > MAX_JOINTS {
            return bad(ErrorKind::InvalidArgument, format!("{joints} joints; it must have 1 to {MAX_JOINTS}"));
        }
        if self.joint_positions.len() != 3 * joints {
            let got = self.joint_positions.len();
            return bad(ErrorKind::InvalidArgument, format!("{got} joint position floats for {joints} joints"));
        }
        if let Some(i) = self.joint_positions.iter().position(|x| !x.is_finite()) {
            return bad(ErrorKind::NonFinite, format!("joint {} has a non-finite position", i / 3));
        }
        let limit = crate::limits::MAX_COORDINATE;
        if let Some(i) = self.joint_positions.iter().position(|x| x.abs() > limit) {
            let text = format!("joint {} lies beyond the supported magnitude {limit:e} model units", i / 3);
            return bad(ErrorKind::LimitExceeded, text);
        }
        if !(1..=MAX_INFLUENCES).contains(&self.influences) {
            let n = self.influences;
            return bad(
                ErrorKind::InvalidArgument,
                format!("{n} influences per vertex; it must be 1 to {MAX_INFLUENCES}"),
            );
        }
        let per_vertex = vertex_count.checked_mul(self.influences);
        for (name, len) in [("vertex_joints", self.vertex_joints.len()), ("vertex_weights", self.vertex_weights.len())]
        {
            if Some(len) != per_vertex {
                let k = self.influences;
                return bad(
                    ErrorKind::InvalidArgument,
                    format!("{name} holds {len} values for {vertex_count} vertices × {k}"),
                );
            }
        }
        if let Some(k) = self.vertex_joints.iter().position(|&j| j as usize >= joints) {
            let (v, j) = (k / self.influences, self.vertex_joints[k]);
            return bad(ErrorKind::IndexOutOfRange, format!("vertex {v} is weighted to joint {j} of {joints}"));
        }
        if let Some(k) = self.vertex_weights.iter().position(|w| !w.is_finite() || *w < 0.0) {
            let (v, w) = (k / self.influences, self.vertex_weights[k]);
            let kind = if w.is_finite() { ErrorKind::InvalidArgument } else { ErrorKind::NonFinite };
            return bad(kind, format!("vertex {v} has weight {w}; weights must be finite and >= 0"));
        }
        if let Some(j) = self.joint_parents.iter().position(|&p| p < -1 || p >= joints as i32) {
            let p = self.joint_parents[j];
            return bad(ErrorKind::IndexOutOfRange, format!("joint {j} has parent {p} of {joints}"));
        }
        if self.head_joint < -1 || self.head_joint >= joints as i32 {
            return bad(ErrorKind::IndexOutOfRange, format!("head joint {} of {joints}", self.head_joint));
        }
        if depths(self.joint_parents).is_none() {
            return bad(ErrorKind::InvalidArgument, "the joints' parents form a cycle".into());
        }
        Ok(())
    }

    /// Per vertex of the mesh (positions `xyz`, the caller's numbering), the
    /// direction the skeleton's bones give it, not normalised and not yet in
    /// the tangent plane; zero where no weighted joint has a bone. `front`
    /// picks each tree's head when [`Self::head_joint`] does not. The input
    /// must have passed [`Self::check`].
    pub fn flow_hints(&self, positions: &[f32], front: Vec3) -> Vec<Vec3> {
        let bones = Bones::new(self, front);
        positions
            .chunks_exact(3)
            .enumerate()
            .map(|(v, p)| {
                let p = Vec3::new(p[0], p[1], p[2]);
                let span = v * self.influences..(v + 1) * self.influences;
                self.vertex_joints[span.clone()]
                    .iter()
                    .zip(&self.vertex_weights[span])
                    .filter(|(_, w)| **w > 0.0)
                    .fold(Vec3::ZERO, |flow, (&j, &w)| flow + bones.direction_at(j as usize, p) * w)
            })
            .collect()
    }
}

/// Each joint's depth below its root, or `None` when the parents form a
/// cycle. Parents must be in range (−1 or a joint index).
fn depths(parents: &[i32]) -> Option<Vec<u32>> {
    const UNKNOWN: u32 = u32::MAX;
    let mut depth = vec![UNKNOWN; parents.len()];
    let mut chain = Vec::new();
    for start in 0..parents.len() {
        let mut j = start;
        // Walk up to a joint of known depth or a root; a chain longer than
        // the joint count has gone round a cycle.
        while depth[j] == UNKNOWN {
            chain.push(j);
            if chain.len() > parents.len() {
                return None;
            }
            match parents[j] {
                -1 => break,
                p => j = p as usize,
            }
        }
        let mut d = if depth[j] == UNKNOWN {
            // The walk stopped at a root, the chain's last entry.
            chain.pop();
            depth[j] = 0;
            1
        } else {
            depth[j] + 1
        };
        while let Some(k) = chain.pop() {
            depth[k] = d;
            d += 1;
        }
    }
    Some(depth)
}

/// The bones (joint to joint segments) oriented away from their tree's
/// head, and the bones meeting at each joint.
struct Bones {
    joints: Vec<Vec3>,
    /// Bone `b` runs from joint `from[b]` to joint `to[b]`, away from the head.
    from: Vec<u32>,
    to: Vec<u32>,
    /// The bones at each joint, compressed rows.
    at_start: Vec<u32>,
    at: Vec<u32>,
    /// Squared softening length of the nearness weights.
    soft2: f32,
}

impl Bones {
    fn new(skeleton: &SkeletonInput<'_>, front: Vec3) -> Self {
        let n = skeleton.joint_count();
        let joints: Vec<Vec3> = skeleton.joint_positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let mut weighted = vec![false; n];
        for (&j, &w) in skeleton.vertex_joints.iter().zip(skeleton.vertex_weights) {
            weighted[j as usize] |= w > 0.0;
        }
        // Joints in order of depth, so a parent is settled before its child.
        let depth = depths(skeleton.joint_parents).unwrap_or_else(|| vec![0; n]);
        let mut by_depth: Vec<usize> = (0..n).collect();
        by_depth.sort_by_key(|&j| (depth[j], j));
        let mut dropped = vec![false; n];
        let mut parent = vec![-1i32; n];
        for &j in &by_depth {
            let p = skeleton.joint_parents[j];
            let parent_dropped = p < 0 || dropped[p as usize];
            dropped[j] = !weighted[j] && parent_dropped;
            parent[j] = if parent_dropped { -1 } else { p };
        }
        // Undirected adjacency of the kept joints.
        let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
        for j in (0..n).filter(|&j| !dropped[j]) {
            if let Ok(p) = usize::try_from(parent[j]) {
                neighbours[j].push(p as u32);
                neighbours[p].push(j as u32);
            }
        }
        // Each tree's head, then a breadth-first walk from it orients its bones.
        let mut seen = vec![false; n];
        let (mut from, mut to) = (Vec::new(), Vec::new());
        let forced = usize::try_from(skeleton.head_joint).ok().filter(|&h| !dropped[h]);
        let mut queue = std::collections::VecDeque::new();
        for j in (0..n).filter(|&j| !dropped[j] && parent[j] < 0) {
            let tree = tree_of(j, &neighbours);
            let head = forced.filter(|h| tree.contains(&(*h as u32))).map(|h| h as u32).unwrap_or_else(|| {
                let ends = tree.iter().copied().filter(|&k| neighbours[k as usize].len() <= 1);
                let ahead = |k: &u32| joints[*k as usize].dot(front);
                ends.max_by(|a, b| ahead(a).total_cmp(&ahead(b)).then(b.cmp(a))).unwrap_or(j as u32)
            });
            seen[head as usize] = true;
            queue.push_back(head);
            while let Some(k) = queue.pop_front() {
                for &m in &neighbours[k as usize] {
                    if !seen[m as usize] {
                        seen[m as usize] = true;
                        from.push(k);
                        to.push(m);
                        queue.push_back(m);
                    }
                }
            }
        }
        let mut at_start = vec![0u32; n + 1];
        for (&a, &b) in from.iter().zip(&to) {
            at_start[a as usize + 1] += 1;
            at_start[b as usize + 1] += 1;
        }
        for j in 0..n {
            at_start[j + 1] += at_start[j];
        }
        let mut fill = at_start.clone();
        let mut at = vec![0u32; 2 * from.len()];
        for (b, (&a, &c)) in from.iter().zip(&to).enumerate() {
            for j in [a, c] {
                at[fill[j as usize] as usize] = b as u32;
                fill[j as usize] += 1;
            }
        }
        let (lo, hi) = joints.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let extent = (hi - lo).length();
        let soft = if extent.is_finite() && extent > 0.0 { extent / 40.0 } else { 1.0 };
        Self { joints, from, to, at_start, at, soft2: soft * soft }
    }

    /// The unit direction of the bones at joint `j` as seen from `p`: each
    /// bone weighted by `1 / (distance² + soft²)²` to its segment (beyond
    /// [`MAX_BONES_BLENDED`] bones, the incoming one alone). Zero when no
    /// bone meets `j`.
    fn direction_at(&self, j: usize, p: Vec3) -> Vec3 {
        let mut bones = &self.at[self.at_start[j] as usize..self.at_start[j + 1] as usize];
        if bones.len() > MAX_BONES_BLENDED {
            // The bone that ends at `j` (the one from the head's side), if any.
            let incoming = bones.iter().position(|&b| self.to[b as usize] as usize == j);
            bones = incoming.map_or(&[][..], |k| &bones[k..=k]);
        }
        let blend = bones.iter().fold(Vec3::ZERO, |sum, &b| {
            let (a, c) = (self.joints[self.from[b as usize] as usize], self.joints[self.to[b as usize] as usize]);
            let Some(dir) = (c - a).try_normalize() else { return sum };
            let near = 1.0 / (distance_squared_to_segment(p, a, c) + self.soft2);
            sum + dir * (near * near)
        });
        blend.try_normalize().unwrap_or(Vec3::ZERO)
    }
}

/// The joints of the tree holding `start` (`start` first, then breadth first).
fn tree_of(start: usize, neighbours: &[Vec<u32>]) -> Vec<u32> {
    let mut tree = vec![start as u32];
    let mut seen = std::collections::HashSet::from([start as u32]);
    let mut k = 0;
    while k < tree.len() {
        for &m in &neighbours[tree[k] as usize] {
            if seen.insert(m) {
                tree.push(m);
            }
        }
        k += 1;
    }
    tree
}

/// Squared distance from `p` to the segment `a`–`b`.
fn distance_squared_to_segment(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 { ((p - a).dot(ab) / len2).clamp(0.0, 1.0) } else { 0.0 };
    p.distance_squared(a + ab * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A "T": a trunk 0 (hips) → 1 (chest) → 2 (head), arms 1 → 3 and 1 → 4,
    /// and a floor root 5 above everything with no weights.
    fn t_skeleton() -> (Vec<f32>, Vec<i32>) {
        let joints = [[0., 0., 0.], [0., 1., 0.], [0., 2., 0.], [-1., 1., 0.], [1., 1., 0.], [0., -1., 0.]];
        (joints.concat(), vec![5, 0, 1, 1, 1, -1])
    }

    fn skeleton<'a>(joints: &'a [f32], parents: &'a [i32], vj: &'a [u32], vw: &'a [f32]) -> SkeletonInput<'a> {
        SkeletonInput {
            joint_positions: joints,
            joint_parents: parents,
            influences: 1,
            vertex_joints: vj,
            vertex_weights: vw,
            head_joint: -1,
        }
    }

    #[test]
    fn bones_point_away_from_the_head_down_the_trunk_and_out_along_the_arms() {
        let (joints, parents) = t_skeleton();
        // Vertices: on the lower trunk, the upper trunk (neck), each arm.
        let positions = [0.1, 0.5, 0., 0.1, 1.6, 0., -0.6, 1.1, 0., 0.6, 1.1, 0.];
        let (vj, vw) = ([0u32, 1, 3, 4], [1.0f32; 4]);
        let s = skeleton(&joints, &parents, &vj, &vw);
        s.check(4).unwrap();
        let flow: Vec<Vec3> = s.flow_hints(&positions, Vec3::Y).into_iter().map(|f| f.normalize()).collect();
        assert!(flow[0].dot(Vec3::NEG_Y) > 0.99, "lower trunk flows down: {:?}", flow[0]);
        assert!(flow[2].dot(Vec3::NEG_X) > 0.9, "left arm flows out: {:?}", flow[2]);
        assert!(flow[3].dot(Vec3::X) > 0.9, "right arm flows out: {:?}", flow[3]);
        // Joint 1 (chest) meets four bones; near the neck the neck bone wins.
        assert!(flow[1].dot(Vec3::NEG_Y) > 0.9, "neck flows down: {:?}", flow[1]);
    }

    #[test]
    fn the_head_is_the_end_joint_farthest_to_the_front_unless_given() {
        let (joints, parents) = t_skeleton();
        let positions = [0.1, 0.5, 0.];
        let (vj, vw) = ([0u32], [1.0f32]);
        let mut s = skeleton(&joints, &parents, &vj, &vw);
        // Facing +X, the right hand (4) is the head: the trunk flows from it.
        let down = s.flow_hints(&positions, Vec3::Y)[0].normalize();
        let sideways = s.flow_hints(&positions, Vec3::X)[0].normalize();
        assert!(down.dot(Vec3::NEG_Y) > 0.99 && sideways.dot(Vec3::NEG_Y) > 0.99, "hips still flow down");
        // Head given at the hips' floor end: the trunk now flows up.
        s.head_joint = 0;
        let up = s.flow_hints(&positions, Vec3::Y)[0].normalize();
        assert!(up.dot(Vec3::Y) > 0.99, "flows up from the hips: {up:?}");
    }

    #[test]
    fn bad_skeletons_are_refused() {
        let (joints, parents) = t_skeleton();
        let (vj, vw) = ([0u32], [1.0f32]);
        let ok = skeleton(&joints, &parents, &vj, &vw);
        assert!(ok.check(1).is_ok());
        assert!(ok.check(2).is_err(), "wrong vertex count");
        let cycle = [1, 2, 0, -1, -1, -1];
        assert!(skeleton(&joints, &cycle, &vj, &vw).check(1).is_err(), "cycle");
        let self_parent = [0, -1, -1, -1, -1, -1];
        assert!(skeleton(&joints, &self_parent, &vj, &vw).check(1).is_err(), "own parent");
        assert!(skeleton(&joints, &parents, &[6], &vw).check(1).is_err(), "joint out of range");
        assert!(skeleton(&joints, &parents, &vj, &[f32::NAN]).check(1).is_err(), "NaN weight");
        assert!(skeleton(&joints, &parents, &vj, &[-1.0]).check(1).is_err(), "negative weight");
        assert!(skeleton(&joints, &[5, 0, 1, 1, 1, 7], &vj, &vw).check(1).is_err(), "parent out of range");
        let mut nan_joint = joints.clone();
        nan_joint[4] = f32::INFINITY;
        assert!(skeleton(&nan_joint, &parents, &vj, &vw).check(1).is_err(), "non-finite joint");
        assert!(SkeletonInput { head_joint: 9, ..ok }.check(1).is_err(), "head out of range");
        assert!(SkeletonInput { influences: 0, ..ok }.check(1).is_err(), "no influences");
        let mut big = joints.clone();
        big[4] = 2e9;
        assert_eq!(skeleton(&big, &parents, &vj, &vw).check(1).unwrap_err().kind(), ErrorKind::LimitExceeded);
    }

    #[test]
    fn a_joint_with_hundreds_of_children_takes_its_incoming_bone() {
        // A chain 0 → 1 (up the y axis) and 300 children of 1 spread round it.
        let mut joints = vec![0.0f32, 0.0, 0.0, 0.0, 1.0, 0.0];
        let mut parents = vec![-1i32, 0];
        for k in 0..300 {
            let a = k as f32 * 0.02;
            joints.extend_from_slice(&[a.cos(), 1.0, a.sin()]);
            parents.push(1);
        }
        // Vertex 0 on joint 1, vertex 1 on joint 0 (so that 0 is not a
        // weightless root, dropped).
        let (vj, vw) = ([1u32, 0], [1.0f32, 1.0]);
        let mut s = skeleton(&joints, &parents, &vj, &vw);
        s.head_joint = 0;
        s.check(2).unwrap();
        let flow = s.flow_hints(&[0.1, 0.9, 0.0, 0.1, 0.1, 0.0], Vec3::Y)[0].normalize();
        assert!(flow.dot(Vec3::Y) > 0.99, "the bone from the head: {flow:?}");
    }

    #[test]
    fn depths_follow_the_parents() {
        assert_eq!(depths(&[-1, 0, 1, 0]), Some(vec![0, 1, 2, 1]));
        assert_eq!(depths(&[2, -1, 1]), Some(vec![2, 0, 1]));
        assert_eq!(depths(&[1, 0]), None);
    }
}
