//! The exact checks of one feather at a time: against the body (does it
//! cross the skin beyond the root allowance?) and, prepared once, against
//! many other feathers ([`FeatherBoxes`]), with the shortcuts that spare
//! most triangle tests (a flat feather's plane, separating axes, boxes).
//! The validation runs them over the whole coat; the adjustment runs them
//! on the feathers it places.

use crate::body::BodyIndex;
use crate::feather::{FeatherPose, FeatherShape, FeatherTriangles, MAX_TRIANGLES, feather_normal, shaft_direction};
use crate::geometry::RootFrame;
use crate::intersect::{Prepared, prepared_intersect};
use crate::progress::{Phase, Progress};
use crate::triangle_grid::Aabb;
use glam::Vec3;
use rayon::prelude::*;

/// Feathers may cross the body this close to their root (fraction of the
/// length, along the shaft): that is where they enter the skin.
pub(crate) const ROOT_ALLOWANCE: f32 = 0.05;

/// The part of a feather more than `ROOT_ALLOWANCE` of its length from
/// the root along the posed shaft, as up to four triangles (each vane
/// clipped to a quadrilateral).
pub fn feather_beyond_root(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> Vec<[Vec3; 3]> {
    let mut out = Vec::with_capacity(4);
    feather_beyond_root_into(frame, shape, pose, &mut out);
    out
}

/// [`feather_beyond_root`] into a reused buffer (cleared first).
fn feather_beyond_root_into(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose, out: &mut Vec<[Vec3; 3]>) {
    let tris = crate::feather::feather_triangles(frame, shape, pose);
    clip_beyond_root(frame, shape, pose, &tris, out);
}

/// [`feather_beyond_root_into`] from the feather's triangles at `pose`.
fn clip_beyond_root(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    tris: &[[Vec3; 3]],
    out: &mut Vec<[Vec3; 3]>,
) {
    out.clear();
    let axis = shaft_direction(frame, pose);
    let cut = ROOT_ALLOWANCE * shape.length * pose.scale;
    for t in tris {
        clip_triangle(t, |p| (p - frame.position).dot(axis) - cut, out);
    }
}

/// Clips a triangle to `side(p) ≥ 0` and appends the kept part as a fan.
fn clip_triangle(t: &[Vec3; 3], side: impl Fn(Vec3) -> f32, out: &mut Vec<[Vec3; 3]>) {
    let s = t.map(&side);
    let mut poly: [Vec3; 4] = [Vec3::ZERO; 4];
    let mut n = 0;
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        if s[i] >= 0.0 {
            poly[n] = t[i];
            n += 1;
        }
        if (s[i] >= 0.0) != (s[j] >= 0.0) {
            poly[n] = t[i] + (t[j] - t[i]) * (s[i] / (s[i] - s[j]));
            n += 1;
        }
    }
    for k in 1..n.saturating_sub(1) {
        out.push([poly[0], poly[k], poly[k + 1]]);
    }
}

/// Feathers that penetrate the body more than 5 % of their length from the
/// root (measured along the posed shaft): their triangles there cross a
/// body triangle (exact test), or, crossing none, have a corner under the
/// skin (a feather drooping or rolling into the body from its root crosses
/// the skin only in the tolerated part, or touches it along the shaft; a
/// part of it is then inside). Sorted.
pub fn body_penetrations(
    frames: &[RootFrame],
    shapes: &[FeatherShape],
    poses: &[FeatherPose],
    body: &BodyIndex,
) -> Vec<u32> {
    body_penetrations_polled(frames, shapes, poses, body, &Progress::none())
}

/// As [`body_penetrations`], polling `progress` per feather (once it says
/// stop the rest are skipped; the caller's next check fails).
pub(crate) fn body_penetrations_polled(
    frames: &[RootFrame],
    shapes: &[FeatherShape],
    poses: &[FeatherPose],
    body: &BodyIndex,
    progress: &Progress,
) -> Vec<u32> {
    let hits: Vec<bool> = (0..frames.len())
        .into_par_iter()
        .map_init(BodyScratch::default, |scratch, i| {
            progress.poll(Phase::Validating, 0.8, i) && penetrates_body(&frames[i], &shapes[i], poses[i], body, scratch)
        })
        .collect();
    hits.iter().enumerate().filter(|&(_, &h)| h).map(|(i, _)| i as u32).collect()
}

/// Whether one feather penetrates the body more than 5 % of its length from
/// the root (the test of [`body_penetrations`]).
pub(crate) fn penetrates_body(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    body: &BodyIndex,
    scratch: &mut BodyScratch,
) -> bool {
    penetrates_body_hinted(frame, shape, pose, body, scratch, &mut None)
}

/// Scratch buffers of the body test of one feather.
#[derive(Clone, Debug, Default)]
pub(crate) struct BodyScratch {
    /// The feather's part beyond its root socket.
    pub(crate) part: Vec<[Vec3; 3]>,
    /// Body triangle ids of the last query.
    pub(crate) ids: Vec<u32>,
    /// The distances of a nearest-skin search (see [`side_of_skin`]).
    distances: Vec<f32>,
}

impl BodyScratch {
    /// Room for queries and skin searches over up to `triangles` body
    /// triangles (each lists a triangle at most once), so that a rare wide
    /// one never grows the buffers.
    pub(crate) fn reserve(&mut self, triangles: usize) {
        self.ids.reserve(triangles.saturating_sub(self.ids.len()));
        self.distances.reserve(triangles.saturating_sub(self.distances.len()));
    }
}

/// [`penetrates_body`], testing body triangle `hint` first (when the
/// query would return it), and setting `hint` to the body triangle found
/// crossing. The answer is the same whatever the hint: only the order of
/// the tests changes, and a hint that crosses spares the box query.
pub(crate) fn penetrates_body_hinted(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    body: &BodyIndex,
    scratch: &mut BodyScratch,
    hint: &mut Option<u32>,
) -> bool {
    let tris = crate::feather::feather_triangles(frame, shape, pose);
    let plane = FlatPlane::of_straight_feather(frame, shape, pose);
    penetrates_body_posed(frame, shape, pose, (&tris, plane), body, scratch, hint)
}

/// [`penetrates_body_hinted`] given the feather's triangles at `pose` and
/// its plane.
fn penetrates_body_posed(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    (tris, plane): (&[[Vec3; 3]], Option<FlatPlane>),
    body: &BodyIndex,
    scratch: &mut BodyScratch,
    hint: &mut Option<u32>,
) -> bool {
    let BodyScratch { part, ids, distances } = scratch;
    if pose.scale <= 0.0 {
        // A feather left out (size 0) is a point on the skin.
        return false;
    }
    clip_beyond_root(frame, shape, pose, tris, part);
    let Some(bounds) = part.iter().map(Aabb::of_triangle).reduce(|a, b| a.union(&b)) else {
        return false;
    };
    // The part's triangle boxes side by side (it has at most PART_LANES
    // triangles; any beyond would be tested without their box).
    let mut part_boxes = BoxLanes::<PART_LANES>::EMPTY;
    for (k, t) in part.iter().enumerate().take(PART_LANES) {
        part_boxes.set(k, &Aabb::of_triangle(t));
    }
    let unboxed = part.get(PART_LANES..).unwrap_or_default();
    let (part_diag, part_size) =
        ((bounds.max - bounds.min).length(), bounds.min.abs().max(bounds.max.abs()).max_element());
    // Every part of a straight feather lies in its plane: a body triangle
    // wholly on one side of it crosses none of them. Nor does a part lying
    // wholly on one side of the body triangle (along its face normal).
    let margin = posed_margin(frame, shape, pose);
    let crossing = |t: u32| {
        // Only part triangles whose box comes within the exact test's
        // contact tolerance of the face's (1e-6 of the pair's box diagonal,
        // which is at most the two diagonals together), widened past the
        // rounding of the comparison: the exact test rejects the others
        // by their boxes.
        let face = body.bounds(t);
        let size = part_size.max(face.min.abs().max(face.max.abs()).max_element());
        let widen = Vec3::splat(2e-6 * (part_diag + (face.max - face.min).length()) + 1e-6 * size);
        let near = part_boxes.overlapping(&Aabb { min: face.min - widen, max: face.max + widen });
        if near == 0 && unboxed.is_empty() {
            return false;
        }
        let corners = body.corners(t);
        if plane.is_some_and(|p| p.apart(&corners)) {
            return false;
        }
        let axis = SeparatingAxis::new(body.normal(t), &corners, margin);
        let mut tri = None;
        // Prepared for the f64 test only when one reaches it (rarely: the
        // axis rules out nearly every triangle).
        let mut meets = |pt: &[Vec3; 3]| {
            !axis.separates(pt)
                && prepared_intersect(&Prepared::of(pt), tri.get_or_insert_with(|| Prepared::of(&corners)))
        };
        lanes(near).any(|k| meets(&part[k])) || unboxed.iter().any(meets)
    };
    // The box query returns exactly the triangles whose boxes overlap
    // `bounds` (none when `bounds` is not a proper box).
    let queried = |h: u32| {
        (h as usize) < body.triangle_count() && bounds.min.cmple(bounds.max).all() && body.bounds(h).overlaps(&bounds)
    };
    if hint.is_some_and(|h| queried(h) && crossing(h)) {
        return true;
    }
    body.triangles_in_box(&bounds, ids);
    let found = ids.iter().copied().find(|&t| crossing(t));
    let crosses = found.is_some();
    if found.is_some() {
        *hint = found;
    }
    // Without a crossing each triangle lies on one side of the skin (the two
    // vanes may lie on different sides, meeting it along the shaft): its
    // first corner clearly off the skin tells which. The triangles of one
    // clipped vane share their first corner, so each distinct corner is
    // judged once.
    if crosses {
        return true;
    }
    let mut judged: [(Vec3, Option<bool>); 12] = [(Vec3::NAN, None); 12];
    let mut count = 0;
    // The nearest skin lies within the way to the root's skin point, or to
    // a point judged before plus that point's distance from the skin.
    let mut last = (frame.position, 0.0f32);
    let mut side = |p: Vec3| {
        if let Some(&(_, s)) =
            judged[..count].iter().find(|(q, _)| q.to_array().map(f32::to_bits) == p.to_array().map(f32::to_bits))
        {
            return s;
        }
        let bound = (p - frame.position).length().min(last.1 + (p - last.0).length());
        let (s, distance) = side_of_skin(body, p, (shape.length, bound), ids, distances);
        last = distance.map_or((frame.position, 0.0), |d| (p, d));
        if count < judged.len() {
            judged[count] = (p, s);
            count += 1;
        }
        s
    };
    part.iter().any(|t| t.iter().find_map(|&p| side(p)).is_some_and(|under| under))
}

/// A feather's triangles with their bounding boxes, for testing one
/// feather against many with [`FeatherBoxes::intersects`].
pub(crate) struct FeatherBoxes {
    boxed: BoxedTriangles,
    plane: Option<FlatPlane>,
}

impl FeatherBoxes {
    pub(crate) fn new(triangles: &[[Vec3; 3]]) -> Self {
        Self { boxed: BoxedTriangles::new(triangles), plane: None }
    }

    /// The boxes of a flat part of a posed feather (one segment of a bent
    /// shaft, which turns only at its joints): its plane rules triangles
    /// out as in [`FeatherBoxes::of_feather`], with the same answers as
    /// [`FeatherBoxes::new`].
    pub(crate) fn of_flat_part(
        triangles: &[[Vec3; 3]],
        frame: &RootFrame,
        shape: &FeatherShape,
        pose: FeatherPose,
    ) -> Self {
        let plane = FlatPlane::of_flat_triangles(triangles, posed_margin(frame, shape, pose));
        Self { plane, ..Self::new(triangles) }
    }

    /// The boxes of a feather at a pose, knowing the plane a straight
    /// feather lies in (triangles wholly on one side of it are ruled out
    /// without the exact test): the same answers as [`FeatherBoxes::new`].
    pub(crate) fn of_feather(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> Self {
        Self::of_posed_feather(frame, shape, pose, &crate::feather::feather_triangles(frame, shape, pose))
    }

    /// [`FeatherBoxes::of_feather`] given the feather's triangles at `pose`.
    pub(crate) fn of_posed_feather(
        frame: &RootFrame,
        shape: &FeatherShape,
        pose: FeatherPose,
        triangles: &[[Vec3; 3]],
    ) -> Self {
        let plane = FlatPlane::of_straight_feather(frame, shape, pose);
        Self { boxed: BoxedTriangles::new(triangles), plane }
    }

    /// [`FeatherBoxes::of_feather`] given the feather's triangles at `pose`
    /// with their boxes made already.
    pub(crate) fn of_boxed_feather(
        frame: &RootFrame,
        shape: &FeatherShape,
        pose: FeatherPose,
        boxed: &BoxedTriangles,
    ) -> Self {
        // A copy: read once, in order, it costs less than the scattered
        // first touches of the obstacle boxes it comes from.
        Self { boxed: *boxed, plane: FlatPlane::of_straight_feather(frame, shape, pose) }
    }

    /// [`penetrates_body_hinted`] for the feather and pose these boxes were
    /// made of with [`FeatherBoxes::of_feather`] (its triangles and plane
    /// made once for both tests).
    pub(crate) fn penetrates_body(
        &self,
        frame: &RootFrame,
        shape: &FeatherShape,
        pose: FeatherPose,
        body: &BodyIndex,
        scratch: &mut BodyScratch,
        hint: &mut Option<u32>,
    ) -> bool {
        penetrates_body_posed(frame, shape, pose, (&self.boxed.triangles, self.plane), body, scratch, hint)
    }

    /// Whether these triangles intersect `b`'s (the exact test of
    /// [`intersecting_pairs`](super::intersecting_pairs), bounding boxes first: the boxes of the whole
    /// feathers, then of each pair of triangles).
    pub(crate) fn intersects(&self, b: &[[Vec3; 3]]) -> bool {
        self.intersects_boxed(&BoxedTriangles::new(b))
    }

    /// The box of all its triangles.
    pub(crate) fn bounds(&self) -> &Aabb {
        &self.boxed.whole
    }

    /// [`FeatherBoxes::intersects`] against triangles whose boxes are
    /// known: the same answer.
    pub(crate) fn intersects_boxed(&self, b: &BoxedTriangles) -> bool {
        let mine = &self.boxed;
        if !mine.whole.overlaps(&b.whole) {
            return false;
        }
        // Over b's triangles first: most miss this feather's box, or lie
        // beyond its plane, and are ruled out once instead of once per
        // triangle of this feather (the same pairs reach the exact test).
        lanes(b.boxes.overlapping(&mine.whole)).any(|j| {
            let (tb, box_b) = (&b.triangles[j], &b.boxes.get(j));
            if self.plane.is_some_and(|p| p.apart(tb)) {
                return false;
            }
            let mut prepared_b = None;
            lanes(mine.boxes.overlapping(box_b)).any(|k| {
                let ta = &mine.triangles[k];
                !mine.axes[k].separates_sized(tb, b.size)
                    && !b.axes[j].separates_sized(ta, mine.size)
                    && prepared_intersect(&Prepared::of(ta), prepared_b.get_or_insert_with(|| Prepared::of(tb)))
            })
        })
    }
}

/// Lanes of boxes (one per triangle of a feather) laid out coordinate by
/// coordinate, so that one box is tested against all of them at once.
#[derive(Clone, Copy, Debug)]
struct BoxLanes<const N: usize = BOX_LANES> {
    min: [[f32; N]; 3],
    max: [[f32; N]; 3],
    /// The lanes set, as bits.
    used: u32,
}

/// Lanes of a [`BoxLanes`]: at least [`MAX_TRIANGLES`], a whole number of
/// SIMD registers.
const BOX_LANES: usize = MAX_TRIANGLES.next_multiple_of(8);

/// Lanes for the part of a feather beyond its root socket (each triangle
/// may be clipped into two).
const PART_LANES: usize = (2 * MAX_TRIANGLES).next_multiple_of(8);
const _: () = assert!(PART_LANES <= 32, "lanes are bits of a u32");

impl<const N: usize> BoxLanes<N> {
    /// Every lane empty (min above max: it overlaps nothing).
    const EMPTY: Self = Self { min: [[f32::INFINITY; N]; 3], max: [[f32::NEG_INFINITY; N]; 3], used: 0 };

    /// Lane `k` holds `b`, unless `b` is a point (a degenerate triangle's,
    /// which meets nothing): then it stays empty.
    fn set(&mut self, k: usize, b: &Aabb) {
        if b.is_point() {
            return;
        }
        for axis in 0..3 {
            self.min[axis][k] = b.min[axis];
            self.max[axis][k] = b.max[axis];
        }
        self.used |= 1 << k;
    }

    /// The box in lane `k` (set).
    #[inline]
    fn get(&self, k: usize) -> Aabb {
        Aabb {
            min: Vec3::new(self.min[0][k], self.min[1][k], self.min[2][k]),
            max: Vec3::new(self.max[0][k], self.max[1][k], self.max[2][k]),
        }
    }

    /// The lanes whose box shares a point with `b`, as bits (lane k is bit
    /// k): the answers of [`Aabb::overlaps`] lane by lane.
    #[inline]
    fn overlapping(&self, b: &Aabb) -> u32 {
        // Branch-free, lane by lane, so that the compiler can test several
        // lanes in one instruction.
        let mut hit = [1u32; N];
        for axis in 0..3 {
            let (lo, hi) = (b.min[axis], b.max[axis]);
            for ((h, &min), &max) in hit.iter_mut().zip(&self.min[axis]).zip(&self.max[axis]) {
                *h &= u32::from(min <= hi) & u32::from(lo <= max);
            }
        }
        self.used & hit.iter().enumerate().fold(0, |bits, (k, &h)| bits | (h << k))
    }
}

/// The lanes whose bits are set in `bits`, lowest first.
#[inline]
fn lanes(mut bits: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (bits != 0).then(|| {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            k
        })
    })
}

/// The margin of the plane tests of a posed feather (see [`FlatPlane`]).
fn posed_margin(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> f32 {
    let length = shape.length * pose.scale.abs();
    1e-4 * length + 1e-5 * (frame.position.abs().max_element() + length)
}

/// The plane a posed (flat) feather lies in, with a margin: a triangle
/// wholly beyond the margin on one side cannot meet the feather, and the
/// exact test, which treats contact within its tolerance as no
/// intersection, would find none. The margin (1e-4 of the length, and
/// 1e-5 of the coordinates) lies far above the rounding of the posed
/// feather's f32 corners and of the other triangle's (relative 1e-7 of
/// the coordinates); a doubtful triangle goes to the exact test.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FlatPlane {
    normal: Vec3,
    offset: f32,
    margin: f32,
}

impl FlatPlane {
    pub(crate) fn of_feather(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> Self {
        let normal = feather_normal(frame, pose);
        let margin = posed_margin(frame, shape, pose);
        Self { normal, offset: normal.dot(frame.position), margin }
    }

    /// The plane of a straight feather; `None` for a bent one (its
    /// segments lie in planes of their own).
    pub(crate) fn of_straight_feather(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose) -> Option<Self> {
        pose.is_straight().then(|| Self::of_feather(frame, shape, pose))
    }

    /// The plane of triangles known to lie in one (a segment of a bent
    /// feather), from the largest of them; `None` if all are degenerate.
    pub(crate) fn of_flat_triangles(triangles: &[[Vec3; 3]], margin: f32) -> Option<Self> {
        let (cross, corner) = triangles
            .iter()
            .map(|t| ((t[1] - t[0]).cross(t[2] - t[0]), t[0]))
            .max_by(|a, b| a.0.length_squared().total_cmp(&b.0.length_squared()))?;
        let normal = cross.try_normalize()?;
        Some(Self { normal, offset: normal.dot(corner), margin })
    }

    /// Whether triangle `t` lies wholly on one side, beyond the margin.
    #[inline]
    pub(crate) fn apart(&self, t: &[Vec3; 3]) -> bool {
        let d = t.map(|p| self.normal.dot(p) - self.offset);
        (d[0] > self.margin && d[1] > self.margin && d[2] > self.margin)
            || (d[0] < -self.margin && d[1] < -self.margin && d[2] < -self.margin)
    }
}

/// A direction along which a triangle spans `[lo, hi]`: another triangle
/// wholly beyond the span, by more than a margin, cannot meet it, and the
/// exact test, which treats contact within its tolerance as none, finds
/// no intersection either. Any direction separates soundly (it need not
/// be an exact normal); the margin (at least the posed feather's
/// [`FlatPlane`] margin, and 1e-5 of the span's coordinates) lies far
/// above the rounding of the f32 projections.
#[derive(Clone, Copy, Debug)]
struct SeparatingAxis {
    axis: Vec3,
    lo: f32,
    hi: f32,
}

impl SeparatingAxis {
    /// An axis that separates nothing.
    const NONE: Self = Self { axis: Vec3::ZERO, lo: f32::NEG_INFINITY, hi: f32::INFINITY };

    /// The span of `t` along `axis` (a face normal; zero never separates),
    /// widened by `margin` and the rounding allowance.
    #[inline]
    fn new(axis: Vec3, t: &[Vec3; 3], margin: f32) -> Self {
        let d = t.map(|p| axis.dot(p));
        let size = t[0].abs().max(t[1].abs()).max(t[2].abs()).max_element();
        let m = margin + 1e-5 * size;
        Self { axis, lo: d[0].min(d[1]).min(d[2]) - m, hi: d[0].max(d[1]).max(d[2]) + m }
    }

    /// The span of `t` along its own unit normal (a degenerate triangle's
    /// separates nothing): a triangle wholly beyond it lies on one side of
    /// `t`'s plane, clear of the rounding.
    #[inline]
    fn of_triangle(t: &[Vec3; 3]) -> Self {
        match (t[1] - t[0]).cross(t[2] - t[0]).try_normalize() {
            Some(axis) => Self::new(axis, t, 0.0),
            None => Self::NONE,
        }
    }

    /// Whether triangle `t` lies wholly beyond the span, on one side.
    #[inline]
    fn separates(&self, t: &[Vec3; 3]) -> bool {
        let d = t.map(|p| self.axis.dot(p));
        (d[0] > self.hi && d[1] > self.hi && d[2] > self.hi) || (d[0] < self.lo && d[1] < self.lo && d[2] < self.lo)
    }

    /// [`separates`](Self::separates), with the rounding allowance of
    /// `t`'s projections added for coordinates up to `size` (the span's
    /// own allowance covers only its triangle's coordinates).
    #[inline]
    fn separates_sized(&self, t: &[Vec3; 3], size: f32) -> bool {
        let m = 1e-5 * size;
        let d = t.map(|p| self.axis.dot(p));
        let (hi, lo) = (self.hi + m, self.lo - m);
        (d[0] > hi && d[1] > hi && d[2] > hi) || (d[0] < lo && d[1] < lo && d[2] < lo)
    }
}

/// A feather's triangles (or its raised top) with their boxes, for testing
/// against many posed feathers.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxedTriangles {
    triangles: FeatherTriangles,
    /// The triangles' boxes side by side (a point's lane left empty).
    boxes: BoxLanes,
    /// Each triangle's span along its own normal.
    axes: [SeparatingAxis; MAX_TRIANGLES],
    whole: Aabb,
    /// The largest coordinate of any triangle (the rounding allowance of
    /// their projections on another's axis, see [`SeparatingAxis`]).
    size: f32,
}

impl BoxedTriangles {
    pub(crate) fn new(triangles: &[[Vec3; 3]]) -> Self {
        let mut boxes = BoxLanes::EMPTY;
        let mut axes = [SeparatingAxis::NONE; MAX_TRIANGLES];
        let mut whole = Aabb::of_triangle(&triangles[0]);
        for (k, t) in triangles.iter().enumerate() {
            let b = Aabb::of_triangle(t);
            boxes.set(k, &b);
            whole = whole.union(&b);
            axes[k] = SeparatingAxis::of_triangle(t);
        }
        let size = whole.min.abs().max(whole.max.abs()).max_element();
        Self { triangles: FeatherTriangles::from_slice(triangles), boxes, axes, whole, size }
    }

    /// The box of all its triangles.
    pub(crate) fn bounds(&self) -> &Aabb {
        &self.whole
    }
}

/// Which side of the body surface `p` is on: `Some(true)` under it,
/// `Some(false)` above it, `None` on it (within the contact tolerance) or
/// with no skin within `reach`; with the distance to the nearest skin
/// point when there is one. The side is judged from the nearest skin point
/// by the normals of every face within the tie distance of it, summed in
/// triangle order, so that edges and corners of the skin judge by all their
/// faces and the answer does not depend on how the search went.
///
/// `bound` is a distance within which skin is known to lie (the root's
/// own skin point, or the nearest distance of a point judged before plus
/// the way from it; infinite when none is known): the first search reaches
/// just that far. Without one the search starts small and widens, since
/// feather corners are usually near skin. Faces that a box test puts
/// beyond the tie distance of the nearest found so far are not measured
/// (they could be neither nearest nor tied).
fn side_of_skin(
    body: &BodyIndex,
    p: Vec3,
    (reach, bound): (f32, f32),
    scratch: &mut Vec<u32>,
    distances: &mut Vec<f32>,
) -> (Option<bool>, Option<f32>) {
    let tolerance = skin_tolerance(p, reach);
    let tie = |nearest: f32| tie_distance(nearest, tolerance);
    // Widened far beyond the rounding of the bound's own arithmetic.
    let known = tie(bound) * (1.0 + 1e-4);
    let mut radius = if known < reach { known } else { reach / 64.0 };
    let nearest = loop {
        if let Some(n) = body.closest_point_keeping(p, radius, tie, scratch, distances) {
            break n;
        }
        if radius >= reach {
            return (None, None);
        }
        // The widening steps of a search without a bound, from past this one.
        let mut next = reach / 64.0;
        while next <= radius && next < reach {
            next *= 4.0;
        }
        radius = next.min(reach);
    };
    let distance = Some(nearest.distance);
    if nearest.distance <= tolerance {
        return (None, distance);
    }
    let tie = tie(nearest.distance);
    if tie > radius {
        // Every face within the tie distance, not only those the search reached.
        body.closest_point_keeping(p, tie, |_| tie, scratch, distances);
    }
    // The tied faces, kept in `scratch` in triangle order.
    let mut kept = 0;
    for k in 0..scratch.len() {
        if distances[k] <= tie {
            scratch[kept] = scratch[k];
            kept += 1;
        }
    }
    scratch.truncate(kept);
    scratch.sort_unstable();
    (Some(under_tied_faces(body, p, nearest.point, scratch)), distance)
}

/// Distances from `p` to the skin within this are contact (a feather of
/// length `reach`).
pub(super) fn skin_tolerance(p: Vec3, reach: f32) -> f32 {
    1e-6 * reach.max(p.abs().max_element())
}

/// Faces this near `p` count as tied with the nearest at `nearest`.
pub(super) fn tie_distance(nearest: f32, tolerance: f32) -> f32 {
    nearest * (1.0 + 1e-4) + tolerance
}

/// Whether `p` lies under the skin whose nearest point is `point`, judged
/// by the normals of the faces `tied` (sorted) summed in that order.
pub(super) fn under_tied_faces(body: &BodyIndex, p: Vec3, point: Vec3, tied: &[u32]) -> bool {
    let normal: Vec3 = tied.iter().map(|&t| body.normal(t)).sum();
    (p - point).dot(normal) < 0.0
}

crate::memory::heap_size_of_fields!(BodyScratch { part, ids, distances });

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_part_resting_within_the_contact_tolerance_on_the_skin_is_tested_against_it() {
        // A top face (z = 0, x in [0, 1]) and a side face going down at
        // x = 1. Part triangle X lies flat 1e-8 above the top: within the
        // exact test's tolerance it is coplanar with it and overlaps it
        // (an intersection), though their boxes do not meet. Triangle Y
        // hangs below beyond the edge. The box filter in front of the
        // exact test must not drop X.
        let body = BodyIndex::from_mesh(
            &[
                Vec3::new(0.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(1.0, -1.0, -1.0),
                Vec3::new(1.0, 1.0, -1.0),
            ],
            &[[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]],
        );
        let frame = RootFrame::from_normal_and_direction(Vec3::ZERO, Vec3::Z, Vec3::X).unwrap();
        let shape = FeatherShape::for_spacing(1.0);
        let x = [Vec3::new(0.2, -0.2, 1e-8), Vec3::new(0.8, -0.2, 1e-8), Vec3::new(0.5, 0.2, 1e-8)];
        let y = [Vec3::new(1.2, 0.0, -0.5), Vec3::new(1.5, 0.1, -0.5), Vec3::new(1.3, -0.1, -0.6)];
        assert!(crate::intersect::triangles_intersect(&x, &body.corners(0)), "X meets the top by the exact test");
        let mut scratch = BodyScratch::default();
        let penetrates = |tris: &[[Vec3; 3]], scratch: &mut BodyScratch| {
            penetrates_body_posed(&frame, &shape, FeatherPose::default(), (tris, None), &body, scratch, &mut None)
        };
        assert!(penetrates(&[x, y], &mut scratch));
        // Lifted clear of the tolerance, X no longer counts.
        let lifted = x.map(|p| p + Vec3::Z * 0.01);
        assert!(!crate::intersect::triangles_intersect(&lifted, &body.corners(0)));
        assert!(!penetrates(&[lifted], &mut scratch));
    }

    #[test]
    fn clipping_keeps_the_far_part() {
        let t = [Vec3::ZERO, Vec3::new(10.0, 0.0, 0.0), Vec3::new(4.0, 2.0, 0.0)];
        let mut out = Vec::new();
        clip_triangle(&t, |p| p.x - 1.0, &mut out);
        assert_eq!(out.len(), 2);
        let area: f32 = out.iter().map(|t| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()).sum();
        // Area 10, less the corner x ≤ 1 under the edge y = x/2 (area 1/4).
        let (whole, cut_off) = (10.0, 0.25);
        assert!((area - (whole - cut_off)).abs() < 1e-4, "{area}");
        assert!(out.iter().flatten().all(|p| p.x >= 1.0 - 1e-6));
    }
}
