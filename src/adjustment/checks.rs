//! The exact checks of a posed feather (or a part of it): its triangles
//! against its obstacles' (and their raised tops) and against the body
//! beyond its root socket, with the boxes that rule most pairs out; which
//! obstacles can matter to a feather at all ([`ObstacleReach`]).

#[cfg(test)]
use super::ObstacleFeather;
use super::height_field::GridExtent;
use super::obstacle::{ObstacleBounds, ObstacleBoxes};
use super::{AdjustParams, HeightField};
use crate::body::{Aabb, BodyIndex};
use crate::feather::{FeatherPose, FeatherShape};
use crate::geometry::RootFrame;
use crate::validation::FeatherBoxes;
use glam::Vec3;

/// Where an obstacle must reach to matter to [`super::adjust_feather`] for one
/// feather, at any size it may be given (≤ its shape) and any pose. An
/// obstacle, bounded by a sphere, matters when it may be rasterised (it
/// meets the column over the grid, from the lowest floor up) or may meet
/// the posed feather in the exact check (it meets the ball around the root
/// that holds the kite at every pitch and roll). Leaving out the others
/// changes nothing: [`HeightField::add_obstacle`] would reject them and the
/// exact test cannot find an intersection. The tests keep a margin far
/// above f32 rounding, so a doubtful case is kept.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ObstacleReach {
    frame: RootFrame,
    far: f32,
    half_span: f32,
    floor: f32,
    ball: f32,
    margin: f32,
}

impl ObstacleReach {
    /// The reach of feather `shape` at `frame` under `params`.
    pub(crate) fn new(frame: &RootFrame, shape: &FeatherShape, params: &AdjustParams) -> Self {
        let grid = GridExtent::new(shape, params.height_field_u, params.height_field_v, params.min_pitch);
        // Shorter sizes lie in the same column (x ≥ 0 covers every root
        // socket) above the full size's floor, which is the lowest.
        let ball = shape.kite_corners().iter().map(|c| c.length()).fold(0.0f32, f32::max);
        let margin = 1e-4 * (grid.far + grid.half_span - grid.floor) + 1e-5 * frame.position.abs().max_element();
        Self { frame: *frame, far: grid.far, half_span: grid.half_span, floor: grid.floor, ball, margin }
    }

    /// Whether an obstacle inside the sphere (`centre`, `radius`), whose
    /// top lies `thickness` above it, may matter: `None` when it cannot,
    /// else whether it may be rasterised (`false`: only the exact check
    /// can meet it). NaN input is kept whole.
    #[inline]
    pub(crate) fn may_matter(&self, centre: Vec3, radius: f32, thickness: f32) -> Option<bool> {
        let m = self.margin + 1e-5 * (radius + centre.abs().max_element());
        let d = centre - self.frame.position;
        let c = Vec3::new(d.dot(self.frame.tangent), d.dot(self.frame.binormal), d.dot(self.frame.normal));
        let out_of_column = c.x + radius < -m
            || c.x - radius > self.far + m
            || c.y.abs() - radius > self.half_span + m
            || c.z + radius + thickness.max(0.0) < self.floor - m;
        let out_of_ball = d.length() > self.ball + radius + m;
        (!(out_of_column && out_of_ball)).then_some(!out_of_column)
    }
}

/// A sphere around a feather's triangles: centre and radius. For the kite
/// the centre is the mean of its four corners; for a segmented feather the
/// mean of every triangle corner.
pub(crate) fn bounding_sphere(triangles: &[[Vec3; 3]]) -> (Vec3, f32) {
    if let [[root, tip, left], [_, right, _]] = *triangles {
        let centre = 0.25 * (root + tip + left + right);
        let radius = [root, tip, left, right].iter().map(|p| (*p - centre).length()).fold(0.0f32, f32::max);
        return (centre, radius);
    }
    let corners = || triangles.iter().flatten().copied();
    let centre = corners().sum::<Vec3>() / (3 * triangles.len()).max(1) as f32;
    let radius = corners().map(|p| (p - centre).length()).fold(0.0f32, f32::max);
    (centre, radius)
}

/// The exact check of a pose: the feather's triangles meet no obstacle's,
/// and it does not penetrate the body beyond its root socket (the tests of
/// [`crate::validation`]). `scratch` lends its body-query buffers.
#[cfg(test)]
pub(crate) fn pose_is_clear(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    obstacles: &[ObstacleFeather],
    body: &BodyIndex,
    scratch: &mut HeightField,
) -> bool {
    let boxes: Vec<ObstacleBoxes> = obstacles.iter().map(|o| ObstacleBoxes::new(&o.triangles, o.thickness)).collect();
    let bounds: Vec<ObstacleBounds> = boxes.iter().map(ObstacleBoxes::bounds).collect();
    pose_is_clear_boxed(
        frame,
        shape,
        pose,
        BoxesOf { ids: None, all: &boxes, bounds: &bounds, aside: None },
        body,
        scratch,
    )
}

/// `pose_is_clear` with the obstacles' [`ObstacleBoxes`] made already.
pub(crate) fn pose_is_clear_boxed(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    boxes: BoxesOf<'_>,
    body: &BodyIndex,
    scratch: &mut HeightField,
) -> bool {
    let at = FeatherInPlace { frame, shape, obstacles: boxes, body };
    exact_check(&at, pose, scratch, false, &mut CheckHints::default())
}

/// [`pose_is_clear_boxed`] given the feather's own [`ObstacleBoxes`] at
/// `pose` (its triangles as [`crate::feather::feather_triangles`] makes
/// them, boxed): the same answer without posing the feather again.
pub(crate) fn posed_is_clear_boxed(
    frame: &RootFrame,
    shape: &FeatherShape,
    (pose, own): (FeatherPose, &ObstacleBoxes),
    boxes: BoxesOf<'_>,
    body: &BodyIndex,
    scratch: &mut HeightField,
) -> bool {
    let at = FeatherInPlace { frame, shape, obstacles: boxes, body };
    let mine = FeatherBoxes::of_boxed_feather(frame, shape, pose, &own.triangles);
    boxes_clear(&mine, &at, pose, scratch, false, &mut CheckHints::default())
}

/// The obstacle tests of [`posed_is_clear_boxed`] alone: whether the
/// feather at `pose` (its own [`ObstacleBoxes`] `own`) meets none of
/// `boxes`. With the body test of a check that passed before, on the same
/// pose and body, it answers that check for a changed set of obstacles.
pub(crate) fn posed_meets_none_boxed(
    frame: &RootFrame,
    shape: &FeatherShape,
    (pose, own): (FeatherPose, &ObstacleBoxes),
    boxes: BoxesOf<'_>,
) -> bool {
    let mine = FeatherBoxes::of_boxed_feather(frame, shape, pose, &own.triangles);
    !meets_obstacle(&mine, boxes, false, &mut None)
}

/// What made the last exact checks of one feather fail: the obstacle and
/// body triangle tested first by the next check (poses a little apart
/// mostly fail on the same one). Only the order of the tests depends on
/// them, never an answer.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct CheckHints {
    obstacle: Option<usize>,
    top: Option<usize>,
    body: Option<u32>,
}

/// The [`ObstacleBoxes`] of one feather's obstacles: obstacle k's are
/// `all[ids[k]]`, or `all[k]` without `ids`; `bounds` holds the
/// [`ObstacleBounds`] of `all`, in its order. Where `aside` gives an index
/// an entry, that entry's boxes replace `all`'s.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxesOf<'a> {
    pub(crate) ids: Option<&'a [u32]>,
    pub(crate) all: &'a [ObstacleBoxes],
    pub(crate) bounds: &'a [ObstacleBounds],
    pub(crate) aside: Option<SetAside<'a>>,
}

/// Boxes set aside for some indices of a [`BoxesOf`]: index `f`'s are
/// `boxes[slot[f]]` unless `slot[f]` is `u32::MAX`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SetAside<'a> {
    pub(crate) slot: &'a [u32],
    pub(crate) boxes: &'a [ObstacleBoxes],
    pub(crate) bounds: &'a [ObstacleBounds],
}

impl SetAside<'_> {
    #[inline]
    fn entry_of(&self, f: usize) -> Option<usize> {
        self.slot.get(f).copied().filter(|&s| s != u32::MAX).map(|s| s as usize)
    }
}

impl<'a> BoxesOf<'a> {
    /// Those whose triangles' or top's box meets the box around the ball
    /// about the root that holds `shape` (a size of the feather at
    /// `frame`) at any pose, listed into `within`: no other can meet the
    /// posed feather's box, so leaving them out changes no answer (only
    /// the positions the check hints refer to). The ball is widened far
    /// beyond the rounding of the posed corners.
    pub(super) fn within_reach<'b>(
        &self,
        frame: &RootFrame,
        shape: &FeatherShape,
        within: &'b mut Vec<u32>,
    ) -> BoxesOf<'b>
    where
        'a: 'b,
    {
        let reach = shape.kite_corners().iter().map(|c| c.length()).fold(0.0f32, f32::max);
        let radius = reach * (1.0 + 1e-3) + 1e-5 * frame.position.abs().max_element();
        let ball = Aabb::around(frame.position, radius);
        within.clear();
        within.extend((0..self.len()).filter_map(|k| {
            let [triangles, top] = self.bounds_of(k);
            let index = self.ids.map_or(k as u32, |ids| ids[k]);
            (triangles.overlaps(&ball) || top.overlaps(&ball)).then_some(index)
        }));
        BoxesOf { ids: Some(within), ..*self }
    }

    fn len(&self) -> usize {
        self.ids.map_or(self.all.len(), <[u32]>::len)
    }

    #[inline]
    fn get(&self, k: usize) -> &'a ObstacleBoxes {
        let f = self.index(k);
        match self.aside.and_then(|a| a.entry_of(f).map(|s| (a, s))) {
            Some((a, s)) => &a.boxes[s],
            None => &self.all[f],
        }
    }

    #[inline]
    fn bounds_of(&self, k: usize) -> ObstacleBounds {
        let f = self.index(k);
        match self.aside.and_then(|a| a.entry_of(f).map(|s| (a, s))) {
            Some((a, s)) => a.bounds[s],
            None => self.bounds[f],
        }
    }

    #[inline]
    fn index(&self, k: usize) -> usize {
        self.ids.map_or(k, |ids| ids[k] as usize)
    }
}

/// Whether `test` holds for some index below `n`, trying `hint` first and
/// setting it to the one found.
fn any_index(n: usize, hint: &mut Option<usize>, test: impl Fn(usize) -> bool) -> bool {
    if hint.is_some_and(|k| k < n && test(k)) {
        return true;
    }
    match (0..n).position(test) {
        Some(k) => {
            *hint = Some(k);
            true
        }
        None => false,
    }
}

/// Whether the feather (`mine`) meets some obstacle, or with `top` some
/// obstacle's [`raised_top`](super::obstacle::raised_top), trying `hint` first and setting it to the
/// one found.
fn meets_obstacle(mine: &FeatherBoxes, boxes: BoxesOf<'_>, top: bool, hint: &mut Option<usize>) -> bool {
    // The outer box first: most obstacles are ruled out by it, without
    // reading their triangles.
    any_index(boxes.len(), hint, |k| {
        mine.bounds().overlaps(&boxes.bounds_of(k)[usize::from(top)]) && {
            let b = boxes.get(k);
            mine.intersects_boxed(if top { &b.top } else { &b.triangles })
        }
    })
}

/// A feather where it grows and what it must clear: its root frame and
/// shape, its obstacles (with their boxes) and the body.
#[derive(Clone, Copy)]
pub(crate) struct FeatherInPlace<'a> {
    pub(crate) frame: &'a RootFrame,
    pub(crate) shape: &'a FeatherShape,
    pub(crate) obstacles: BoxesOf<'a>,
    pub(crate) body: &'a BodyIndex,
}

/// `pose_is_clear`, and with `tops` also clear of every [`raised_top`](super::obstacle::raised_top)
/// (last: most poses that fail, fail before it, so it is tested least).
pub(super) fn exact_check(
    at: &FeatherInPlace<'_>,
    pose: FeatherPose,
    scratch: &mut HeightField,
    tops: bool,
    hints: &mut CheckHints,
) -> bool {
    let mine = FeatherBoxes::of_feather(at.frame, at.shape, pose);
    boxes_clear(&mine, at, pose, scratch, tops, hints)
}

/// The exact tests of [`exact_check`] on triangles (`mine`, the whole
/// feather at `pose` or a part of it): no obstacle met, no crossing of the
/// body beyond the root socket, and with `tops` no obstacle's raised top
/// met.
pub(super) fn boxes_clear(
    mine: &FeatherBoxes,
    at: &FeatherInPlace<'_>,
    pose: FeatherPose,
    scratch: &mut HeightField,
    tops: bool,
    hints: &mut CheckHints,
) -> bool {
    let FeatherInPlace { frame, shape, obstacles, body } = *at;
    if meets_obstacle(mine, obstacles, false, &mut hints.obstacle) {
        return false;
    }
    if mine.penetrates_body(frame, shape, pose, body, &mut scratch.body_scratch, &mut hints.body) {
        return false;
    }
    !(tops && meets_obstacle(mine, obstacles, true, &mut hints.top))
}
