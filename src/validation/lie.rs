//! How a coat lies (DESIGN.md §6): how far each feather's tip stands off
//! the body surface, in feather lengths, and how that compares with the
//! feathers stacked beneath the tip. A coat that lies down has its tips a
//! few thicknesses above the skin per layer beneath; a bristle stands more
//! than half a length off.

use crate::body::BodyIndex;
use crate::feather::{FeatherPose, FeatherShape, tip_position};
use crate::geometry::RootFrame;
use crate::triangle_grid::{Aabb, ClosestPoint, TriangleGrid, ray_triangle};
use glam::Vec3;
use rayon::prelude::*;

/// A tip farther than this off the skin, in feather lengths, is a bristle.
pub const BRISTLE_TIP_HEIGHT: f64 = 0.5;

/// Tip heights of a coat, summarised.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TipHeights {
    /// Median tip height, in feather lengths.
    pub median: f64,
    /// 90th percentile (nearest rank), in feather lengths.
    pub p90: f64,
    /// Percentage of feathers whose tip stands more than
    /// [`BRISTLE_TIP_HEIGHT`] lengths off the skin.
    pub bristle_percent: f64,
    /// Feathers measured: those placed (a feather left out has no tip).
    pub feathers: usize,
}

/// How the tips of a coat lie on the feathers beneath them, summarised
/// (see [`tip_lies`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TipStacks {
    /// `stack_efficiency`: the median over the measured feathers of
    /// [`TipLie::efficiency`], tip height over the stack floor. 1 means the
    /// tips lie on the feathers stacked beneath them; larger means the coat
    /// leaves them higher than the stack forces. 0 when nothing is measured.
    pub efficiency: f64,
    /// Median number of feathers beneath a tip (nearest rank).
    pub depth_median: f64,
    /// Feathers measured: those placed with a floor above 0.
    pub feathers: usize,
}

/// Where one placed feather's tip lies.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TipLie {
    /// The tip's height as [`tip_heights`] gives it: the distance from the
    /// tip to the nearest body point over the placed length, capped at 1.
    pub height: f64,
    /// The feathers beneath the tip: the other feathers with a posed
    /// triangle crossing the segment from the tip to its nearest body point,
    /// each counted once; 0 when no body point lies within a length.
    pub beneath: u32,
    /// The lowest height the tip can lie at, in the feather's placed
    /// lengths: the larger of the thicknesses of the feathers beneath,
    /// summed, and the feather's own thickness.
    pub floor: f64,
}

impl TipLie {
    /// `height / floor` (NaN for a floor of 0).
    pub fn efficiency(&self) -> f64 {
        if self.floor > 0.0 { self.height / self.floor } else { f64::NAN }
    }
}

/// The tip of a placed feather, its placed length and the nearest body
/// point to the tip within that length (`None`: farther). `None` for a
/// feather left out (length 0 or NaN).
fn tip_over_body(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    body: &BodyIndex,
    scratch: &mut Vec<u32>,
) -> Option<(Vec3, f32, Option<ClosestPoint>)> {
    let length = shape.length * pose.scale;
    if length.is_nan() || length <= 0.0 {
        return None;
    }
    let tip = tip_position(frame, shape, pose);
    Some((tip, length, body.closest_point(tip, length, scratch)))
}

/// A tip's height in feather lengths from its nearest body point
/// (`None`: more than a length away, which counts as 1), capped at 1.
fn height_in_lengths(nearest: Option<&ClosestPoint>, length: f32) -> f64 {
    nearest.map_or(1.0, |c| f64::from(c.distance / length).min(1.0))
}

/// The distance from each placed feather's tip to the nearest point of the
/// body, divided by the feather's placed length and capped at 1 (a tip a
/// whole length or more off the skin counts as 1). Feathers left out are
/// skipped. In feather order.
pub fn tip_heights(frames: &[RootFrame], shapes: &[FeatherShape], poses: &[FeatherPose], body: &BodyIndex) -> Vec<f64> {
    frames
        .par_iter()
        .zip(shapes)
        .zip(poses)
        .map_init(Vec::new, |scratch, ((frame, shape), pose)| {
            let (_, length, nearest) = tip_over_body(frame, shape, *pose, body, scratch)?;
            Some(height_in_lengths(nearest.as_ref(), length))
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// The feathers' posed triangles in one grid, and the feather each grid
/// triangle belongs to.
#[derive(Clone, Copy)]
pub struct OwnedTriangles<'a> {
    /// Every feather's posed triangles.
    pub grid: &'a TriangleGrid,
    /// `owner[t]` is the feather grid triangle `t` belongs to.
    pub owner: &'a [u32],
}

/// How each placed feather `i` with `member(i)` lies (see [`TipLie`]), in
/// feather order. `feathers` holds every feather's posed triangles (not
/// only the members'): any feather can lie beneath a member's tip. Each
/// feather's answer depends on nothing but the coat, so the result is the
/// same at any thread count.
pub fn tip_lies(
    frames: &[RootFrame],
    shapes: &[FeatherShape],
    poses: &[FeatherPose],
    body: &BodyIndex,
    feathers: OwnedTriangles<'_>,
    member: impl Fn(usize) -> bool + Sync,
) -> Vec<TipLie> {
    (0..frames.len())
        .into_par_iter()
        .map_init(
            || (Vec::new(), Vec::new()),
            |(scratch, beneath), i| {
                if !member(i) {
                    return None;
                }
                let (tip, length, nearest) = tip_over_body(&frames[i], &shapes[i], poses[i], body, scratch)?;
                beneath.clear();
                if let Some(foot) = nearest {
                    feathers_crossing_segment(feathers, i as u32, tip, foot.point, scratch, beneath);
                }
                let stacked: f64 = beneath.iter().map(|&j| f64::from(shapes[j as usize].thickness)).sum();
                let floor = stacked.max(f64::from(shapes[i].thickness)) / f64::from(length);
                Some(TipLie {
                    height: height_in_lengths(nearest.as_ref(), length),
                    beneath: beneath.len() as u32,
                    floor,
                })
            },
        )
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// Leaves in `out`, sorted and each once, the feathers other than `own`
/// with a triangle crossing the segment from `a` to `b` (a crossing at `a`
/// itself does not count, nor a triangle in the segment's plane).
fn feathers_crossing_segment(
    feathers: OwnedTriangles<'_>,
    own: u32,
    a: Vec3,
    b: Vec3,
    scratch: &mut Vec<u32>,
    out: &mut Vec<u32>,
) {
    out.clear();
    feathers.grid.query_box(&Aabb::of_segment(a, b), scratch);
    for &t in scratch.iter() {
        let feather = feathers.owner[t as usize];
        if feather != own && segment_crosses_triangle(a, b, feathers.grid.corners(t)) {
            out.push(feather);
        }
    }
    out.sort_unstable();
    out.dedup();
}

/// Whether the segment from `a` to `b` crosses the closed triangle `tri`
/// at a point other than `a` (never when the segment has no length or lies
/// in the triangle's plane).
fn segment_crosses_triangle(a: Vec3, b: Vec3, tri: [Vec3; 3]) -> bool {
    let length = (b - a).length();
    if length.is_nan() || length <= 0.0 {
        return false;
    }
    ray_triangle(a, (b - a) / length, tri).is_some_and(|t| t <= length)
}

/// The element of rank `q` (0 < q ≤ 1, nearest rank) of the non-empty `sorted`.
fn nearest_rank(sorted: &[f64], q: f64) -> f64 {
    sorted[((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len()) - 1]
}

/// The median, 90th percentile and bristle share of `heights`.
pub fn summarise_tip_heights(heights: &[f64]) -> TipHeights {
    if heights.is_empty() {
        return TipHeights::default();
    }
    let mut sorted = heights.to_vec();
    sorted.sort_by(f64::total_cmp);
    let bristles = sorted.iter().filter(|&&h| h > BRISTLE_TIP_HEIGHT).count();
    TipHeights {
        median: nearest_rank(&sorted, 0.5),
        p90: nearest_rank(&sorted, 0.9),
        bristle_percent: 100.0 * bristles as f64 / sorted.len() as f64,
        feathers: sorted.len(),
    }
}

/// The median efficiency and depth of `lies` (nearest rank), over those
/// with a floor above 0.
pub fn summarise_tip_stacks(lies: &[TipLie]) -> TipStacks {
    let measured = || lies.iter().filter(|l| l.floor > 0.0);
    let mut efficiency: Vec<f64> = measured().map(TipLie::efficiency).collect();
    if efficiency.is_empty() {
        return TipStacks::default();
    }
    let mut depth: Vec<f64> = measured().map(|l| f64::from(l.beneath)).collect();
    efficiency.sort_by(f64::total_cmp);
    depth.sort_by(f64::total_cmp);
    TipStacks {
        efficiency: nearest_rank(&efficiency, 0.5),
        depth_median: nearest_rank(&depth, 0.5),
        feathers: efficiency.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A flat floor z = 0 of two triangles.
    fn floor() -> BodyIndex {
        let p = [
            Vec3::new(-10.0, -10.0, 0.0),
            Vec3::new(10.0, -10.0, 0.0),
            Vec3::new(10.0, 10.0, 0.0),
            Vec3::new(-10.0, 10.0, 0.0),
        ];
        BodyIndex::from_mesh(&p, &[[0, 1, 2], [0, 2, 3]])
    }

    #[test]
    fn a_pitched_feather_stands_its_sine_off_a_floor() {
        let frame = RootFrame::from_normal_and_direction(Vec3::ZERO, Vec3::Z, Vec3::X).unwrap();
        let shape = FeatherShape::for_spacing(1.0);
        let poses = [
            FeatherPose::new(0.0, 0.0),
            FeatherPose::new(0.3, 0.1),
            FeatherPose::new(0.7, 0.0),
            FeatherPose::new(0.7, 0.0).with_scale(0.0),
        ];
        let h = tip_heights(&[frame; 4], &[shape; 4], &poses, &floor());
        assert_eq!(h.len(), 3, "the feather left out has no tip");
        assert!(h[0].abs() < 1e-6);
        assert!((h[1] - 0.3f64.sin()).abs() < 1e-5, "{}", h[1]);
        assert!((h[2] - 0.7f64.sin()).abs() < 1e-5);
        let s = summarise_tip_heights(&h);
        assert_eq!(s.feathers, 3);
        assert!((s.median - h[1]).abs() < 1e-12 && (s.p90 - h[2]).abs() < 1e-12);
        assert!((s.bristle_percent - 100.0 / 3.0).abs() < 1e-9);
    }

    #[test]
    fn a_tip_out_of_reach_counts_a_whole_length() {
        let frame = RootFrame::from_normal_and_direction(Vec3::new(0.0, 0.0, 50.0), Vec3::Z, Vec3::X).unwrap();
        let h = tip_heights(&[frame], &[FeatherShape::for_spacing(1.0)], &[FeatherPose::default()], &floor());
        assert_eq!(h, vec![1.0]);
        assert_eq!(summarise_tip_heights(&[]), TipHeights::default());
    }

    /// Feathers flat on the floor, one on another: feather `k` (of
    /// `count`) has a root `(count − 1 − k)·½` along the shaft direction x
    /// and `k/20` across, so each tip lies over the vanes of every feather
    /// below it, and stands at `k·(thickness + gap) + clearance`.
    fn staircase(count: usize, gap: f32, clearance: f32) -> (Vec<RootFrame>, Vec<FeatherShape>, Vec<FeatherPose>) {
        let shape = FeatherShape::for_spacing(1.0);
        let frames = (0..count)
            .map(|k| {
                let root = Vec3::new(
                    (count - 1 - k) as f32 * 0.5,
                    k as f32 * 0.05,
                    k as f32 * (shape.thickness + gap) + clearance,
                );
                RootFrame::from_normal_and_direction(root, Vec3::Z, Vec3::X).unwrap()
            })
            .collect();
        (frames, vec![shape; count], vec![FeatherPose::default(); count])
    }

    /// The feathers' posed triangles in a grid, and each one's feather.
    fn posed_grid(frames: &[RootFrame], shapes: &[FeatherShape], poses: &[FeatherPose]) -> (TriangleGrid, Vec<u32>) {
        let posed: Vec<_> =
            (0..frames.len()).map(|i| crate::feather::feather_triangles(&frames[i], &shapes[i], poses[i])).collect();
        let mut grid = TriangleGrid::new();
        grid.rebuild(posed.iter().flat_map(|f| f.iter().copied()), None);
        let owner = posed.iter().enumerate().flat_map(|(i, f)| std::iter::repeat_n(i as u32, f.len())).collect();
        (grid, owner)
    }

    fn lies_of(frames: &[RootFrame], shapes: &[FeatherShape], poses: &[FeatherPose]) -> Vec<TipLie> {
        let (grid, owner) = posed_grid(frames, shapes, poses);
        tip_lies(frames, shapes, poses, &floor(), OwnedTriangles { grid: &grid, owner: &owner }, |_| true)
    }

    #[test]
    fn a_tip_on_a_stack_of_n_feathers_lies_on_its_floor() {
        let shape = FeatherShape::for_spacing(1.0);
        let (t, l) = (f64::from(shape.thickness), f64::from(shape.length));
        let clearance = 0.1 * shape.thickness;
        let (frames, shapes, poses) = staircase(5, 0.0, clearance);
        let lies = lies_of(&frames, &shapes, &poses);
        for (k, lie) in lies.iter().enumerate() {
            assert_eq!(lie.beneath, k as u32, "feather {k}");
            assert!((lie.floor - (k.max(1) as f64) * t / l).abs() < 1e-9, "feather {k}: {lie:?}");
            assert!((lie.height - (k as f64 * t + 0.1 * t) / l).abs() < 1e-6, "feather {k}: {lie:?}");
        }
        // On the skin with nothing beneath: its clearance over its own thickness.
        assert!((lies[0].efficiency() - 0.1).abs() < 1e-4);
        for (k, lie) in lies.iter().enumerate().skip(1) {
            assert!((lie.efficiency() - (1.0 + 0.1 / k as f64)).abs() < 1e-4, "feather {k}: {}", lie.efficiency());
        }
        let stacks = summarise_tip_stacks(&lies);
        assert_eq!(stacks.feathers, 5);
        assert!((stacks.efficiency - (1.0 + 0.1 / 3.0)).abs() < 1e-4, "{stacks:?}");
        assert_eq!(stacks.depth_median, 2.0);
    }

    #[test]
    fn lifting_the_feathers_off_their_stack_raises_the_efficiency() {
        let shape = FeatherShape::for_spacing(1.0);
        let clearance = 0.1 * shape.thickness;
        let (frames, shapes, poses) = staircase(5, 0.0, clearance);
        let resting = summarise_tip_stacks(&lies_of(&frames, &shapes, &poses));
        // A gap of one thickness between layers: a tip k layers up stands
        // twice as high as its stack.
        let (frames, shapes, poses) = staircase(5, shape.thickness, clearance);
        let lifted = summarise_tip_stacks(&lies_of(&frames, &shapes, &poses));
        assert_eq!(lifted.depth_median, resting.depth_median);
        assert!((lifted.efficiency - (2.0 + 0.1 / 3.0)).abs() < 1e-4, "{lifted:?}");
        // Pitching the top feather up raises its tip by L sin α over the same stack.
        let (frames, shapes, mut poses) = staircase(5, 0.0, clearance);
        poses[4] = FeatherPose::new(0.05, 0.0);
        let top = lies_of(&frames, &shapes, &poses)[4];
        assert_eq!(top.beneath, 4);
        let want = (4.1 * f64::from(shape.thickness) + f64::from(shape.length) * 0.05f64.sin())
            / (4.0 * f64::from(shape.thickness));
        assert!((top.efficiency() - want).abs() < 1e-3, "{} vs {want}", top.efficiency());
        assert!(top.efficiency() > 1.5 * resting.efficiency);
    }

    #[test]
    fn the_floor_sums_the_thicknesses_beneath_and_is_at_least_the_own() {
        let (frames, mut shapes, poses) = staircase(3, 0.0, 0.0);
        let t = shapes[0].thickness;
        // Beneath the top tip: thicknesses t and 2 t; its own is t, then 5 t.
        shapes[1].thickness = 2.0 * t;
        let l = f64::from(shapes[2].length);
        assert!((lies_of(&frames, &shapes, &poses)[2].floor - 3.0 * f64::from(t) / l).abs() < 1e-7);
        shapes[2].thickness = 5.0 * t;
        assert!((lies_of(&frames, &shapes, &poses)[2].floor - 5.0 * f64::from(t) / l).abs() < 1e-7);
    }

    #[test]
    fn only_placed_members_are_measured_and_a_far_tip_has_nothing_beneath() {
        let (mut frames, shapes, mut poses) = staircase(4, 0.0, 0.0);
        poses[0] = poses[0].with_scale(0.0);
        let (grid, owner) = posed_grid(&frames, &shapes, &poses);
        let feathers = OwnedTriangles { grid: &grid, owner: &owner };
        let lies = tip_lies(&frames, &shapes, &poses, &floor(), feathers, |i| i != 2);
        assert_eq!(lies.len(), 2, "feather 0 is left out, feather 2 not a member");
        assert_eq!((lies[0].beneath, lies[1].beneath), (0, 2), "the collapsed feather lies beneath nothing");
        // A tip more than a length off the body.
        frames[3] = RootFrame::from_normal_and_direction(Vec3::new(0.0, 0.0, 50.0), Vec3::Z, Vec3::X).unwrap();
        let far = tip_lies(&frames, &shapes, &poses, &floor(), feathers, |i| i == 3);
        assert_eq!(
            far,
            vec![TipLie { height: 1.0, beneath: 0, floor: f64::from(shapes[3].thickness / shapes[3].length) }]
        );
        assert_eq!(summarise_tip_stacks(&[]), TipStacks::default());
    }
}
