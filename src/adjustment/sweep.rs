//! The swept drape of a segmented feather (DESIGN.md §4, bending): each
//! segment's lowest clear angle in closed form from the geometry beneath
//! it, where the descent by exact checks ([`super::drape`]) finds it by
//! about ten checks a segment.
//!
//! Geometry. In the *roll frame* (the root frame turned by the feather's
//! roll about its shaft) the posed feather is, to first order in the roll,
//! a polyline in the (x, z) plane at absolute angles `θ_0 = α`,
//! `θ_k = θ_{k−1} + bend_k`, swept across y by the vane's half-width. A
//! segment turning down about its joint from its highest allowed angle
//! first meets, of everything under its vane within its length, the point
//! seen from the joint at the largest angle: that angle is the lowest at
//! which it is clear.
//!
//! What it meets: each obstacle triangle with its raised top (a thin
//! prism) and each skin triangle near the root (the ones the height field
//! rasterised; no raise). Cut to the vane's lateral band and seen in the
//! (x, z) plane each is a convex polygon; the part of it in front of the
//! joint and within the segment's reach has its extreme directions at its
//! cut edges' ends and where they cross the reach circles
//! ([`sector_of_prism`]). The band narrows toward the root and the tip, so
//! each segment is swept in [`PIECES`] radial pieces, each with the widest
//! half-width over it. A prism wholly above the highest angle is passed
//! under (the feather tucks beneath a neighbour standing over it, as the
//! descent does); one that spans the highest angle blocks the segment; one
//! within the sweep sets its lowest angle. The skin within the
//! validation's root allowance is not swept.
//!
//! Each segment from the root takes its lowest clear angle within its
//! bend limits; a blocked segment raises the nearest earlier one that
//! makes room (bisected). One exact check of the whole feather confirms the
//! result; where it fails the caller falls back to the descent.

use super::{AdjustParams, ObstacleFeather};
use crate::feather::{FeatherPose, FeatherShape, FeatherTriangles, MAX_SEGMENTS};
use crate::validation::ROOT_ALLOWANCE;
use glam::{Vec2, Vec3};
use std::f32::consts::FRAC_PI_2;

/// Backtracks of one drape before it gives up.
const MAX_BACKTRACKS: usize = 12;
/// Halvings of the raise of an earlier segment that makes room for a
/// blocked one (to about 1.5° with the default limits).
const RAISE_BISECTIONS: usize = 5;
/// Angle added past a threshold, so that rounding cannot leave the same
/// contact violated again (radians).
const ANGLE_EPSILON: f32 = 1e-4;
/// How far past the highest angle a contact may ask the segment to rise
/// and still take the highest (the straight pose is clear there by the
/// exact checks; the sweep's rounding differs).
const ANGLE_TOLERANCE: f32 = 1e-3;
/// Room left between a prism's bounding angle and the angle reached before
/// the prism is passed over (radians; far above the rounding of either).
const BOUND_MARGIN: f32 = 1e-5;
/// How far a prism's box is widened for its bounding angle, relative to the
/// reach and the joint's coordinates (far above the rounding of the points
/// a cut interpolates).
const BOUND_PAD: f32 = 1e-5;
/// A prism whose box comes within this share of the reach of the joint is
/// never passed over: seen from so near, a rounding error is a large angle.
const BOUND_NEAR: f32 = 1e-2;
/// Most vertices of a triangle cut by the lateral band.
const CUT_VERTICES: usize = 5;

/// One obstacle or skin triangle in the roll frame with the raise of its
/// top (an obstacle's thickness along its own normal; none for skin), and
/// the box of both.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SweptTriangle {
    /// Whether it is skin (which the feather may cross within its root
    /// allowance) rather than an obstacle.
    skin: bool,
    corners: [Vec3; 3],
    raise: Vec3,
    lo: Vec3,
    hi: Vec3,
}

/// A swept triangle's prism cut to one piece's lateral band, seen in the roll
/// frame's (x, z) plane: a convex polygon swept along `raise`.
#[derive(Clone, Copy, Debug)]
struct CutPrism {
    lower: [Vec2; CUT_VERTICES],
    len: u8,
    raise: Vec2,
}

/// The triangles the height field rasterised (`local_obstacles`, one entry
/// for each obstacle of `obstacles` not on the far side, each with its
/// raised top, and `local_body`, the skin near the root; in the root frame)
/// in the roll frame of `roll`, into `swept`. The drape keeps a clearance
/// from them, so that a motion by a rounding error cannot make it touch:
/// obstacles are lifted by `gap`, the skin by `skin_slope` times the
/// distance along the root's tangent (the kite's clearance angle).
pub(super) fn fill_swept_triangles(
    swept: &mut Vec<SweptTriangle>,
    local_obstacles: &[FeatherTriangles],
    local_body: &[[Vec3; 3]],
    obstacles: &[ObstacleFeather],
    roll: f32,
    gap: f32,
    skin_slope: f32,
) {
    swept.clear();
    let (sb, cb) = roll.sin_cos();
    let unroll = |p: Vec3, lift: f32| Vec3::new(p.x, p.y * cb + p.z * sb, p.z * cb - p.y * sb + lift);
    let near = obstacles.iter().filter(|o| !o.far_side);
    for (local, o) in local_obstacles.iter().zip(near) {
        push_swept(swept, local, o.thickness, false, |p| unroll(p, gap));
    }
    // A shear (linear, so a triangle stays one), lifting the skin ahead.
    push_swept(swept, local_body, 0.0, true, |p| unroll(p, p.x * skin_slope));
}

impl CutPrism {
    /// `t` cut to the band `|y| ≤ half_width`; `None` when nothing is left.
    fn of(t: &SweptTriangle, half_width: f32) -> Option<Self> {
        let mut lower = [Vec2::ZERO; CUT_VERTICES];
        let n = if t.lo.y >= -half_width && t.hi.y <= half_width {
            // Wholly within the band (the box counts the raise too).
            for (l, c) in lower.iter_mut().zip(&t.corners) {
                *l = Vec2::new(c.x, c.z);
            }
            3
        } else {
            cut_to_band(&t.corners, half_width, &mut lower)
        };
        if n == 0 {
            return None;
        }
        Some(Self { lower, len: n as u8, raise: Vec2::new(t.raise.x, t.raise.z) })
    }
}

/// Radial pieces of a segment, each cut to a band of its own width (the
/// vane narrows to the root and the tip).
pub(crate) const PIECES: usize = 3;

/// Piece `p` of segment `k` of `shape`: the distances from the joint it
/// spans and the widest half-width of the vane over them. The root
/// segment's first piece starts at the root socket's end (a neighbour's
/// vane beside the root passes beside the narrow shaft there).
fn piece_of(shape: &FeatherShape, socket: f32, k: usize, p: usize) -> (f32, f32, f32) {
    let seg_len = shape.length / shape.segment_count() as f32;
    let (r_in, r_out) = (seg_len * p as f32 / PIECES as f32, seg_len * (p + 1) as f32 / PIECES as f32);
    let r_in = if k == 0 && p == 0 { socket * shape.length } else { r_in };
    let a = k as f32 * seg_len;
    (r_in, r_out, widest_half_width(shape, a + r_in, a + r_out))
}

fn push_swept(
    out: &mut Vec<SweptTriangle>,
    local: &[[Vec3; 3]],
    thickness: f32,
    skin: bool,
    unroll: impl Fn(Vec3) -> Vec3,
) {
    for t in local.iter() {
        let corners = t.map(&unroll);
        let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalize_or_zero();
        let raise = n * thickness;
        let (lo, hi) = (corners[0].min(corners[1]).min(corners[2]), corners[0].max(corners[1]).max(corners[2]));
        let (lo, hi) = (lo.min(lo + raise), hi.max(hi + raise));
        out.push(SweptTriangle { skin, corners, raise, lo, hi });
    }
}

/// The widest half-width of the vane of `s` between shaft positions
/// `a ≤ b` (model units along the unbent shaft).
fn widest_half_width(s: &FeatherShape, a: f32, b: f32) -> f32 {
    let corner = s.vane_split * s.length;
    if a <= corner && corner <= b {
        return 0.5 * s.width;
    }
    s.half_width_at(a.min(s.length)).max(s.half_width_at(b.min(s.length))).max(0.0)
}

/// One segment: its joint in the roll frame's (x, z) plane and its length.
#[derive(Clone, Copy, Debug)]
struct Segment {
    joint: Vec2,
    length: f32,
    /// The distance from the joint within which the skin is not swept (the
    /// root segment: the validation's root allowance).
    skin_from: f32,
    /// Each piece's distances from the joint and half-width (see
    /// [`piece_of`]).
    pieces: [(f32, f32, f32); PIECES],
}

/// What one obstacle prism does to a segment sweeping `[lo, hi]`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Contact {
    /// Out of the segment's reach, below `lo` or above `hi`.
    None,
    /// Met first at this angle.
    At(f32),
    /// Spans the highest angle (or holds the joint): the segment is blocked.
    Blocks,
}

/// How the cut prism `t` meets a segment sweeping `sweep` about its joint
/// (see the module notes).
fn sector_of_prism(t: &SweptTriangle, half_width: f32, j: Vec2, (r_in, r): (f32, f32), sweep: &Sweep) -> Contact {
    let Some(t) = CutPrism::of(t, half_width) else { return Contact::None };
    let n = t.len as usize;
    let (lower, raise) = (&t.lower[..n], t.raise);
    if r_in == 0.0 && prism_holds(lower, raise, j) {
        return Contact::Blocks;
    }
    // Directions are compared by their slope relative to the middle of the
    // sweep (monotone in the angle over the front half-plane). Only the
    // prism's part in front of the joint can meet the segment, so its
    // boundary edges are cut to that half-plane first; the extremes of the
    // slope over the part within the piece's annulus lie at the cut edges'
    // ends and where they cross the annulus' circles.
    let (ms, mc) = (sweep.mid_sin, sweep.mid_cos);
    // A point's coordinates along the middle direction and across it.
    let along_up = |p: Vec2| {
        let d = p - j;
        (mc * d.x + ms * d.y, mc * d.y - ms * d.x)
    };
    let along = |p: Vec2| along_up(p).0;
    let slope = |p: Vec2| {
        let (along, up) = along_up(p);
        if along > 0.0 { up / along } else { f32::INFINITY.copysign(up) }
    };
    let (mut min_s, mut max_s) = (f32::INFINITY, f32::NEG_INFINITY);
    let mut take = |p: Vec2| {
        let s = slope(p);
        min_s = min_s.min(s);
        max_s = max_s.max(s);
    };
    let (r2_in, r2) = (r_in * r_in, r * r);
    // The prism's outline: the cut triangle and its raised copy (a skin
    // triangle has no raise). Its sides along the raise join corners of
    // both, so their ends are among these edges' ends; where a side
    // crosses a circle is left out (within a thickness of a corner).
    let copies = if raise == Vec2::ZERO { 1 } else { 2 };
    for c in 0..copies {
        let shift = if c == 0 { Vec2::ZERO } else { raise };
        for k in 0..n {
            let (p, q) = (lower[k] + shift, lower[(k + 1) % n] + shift);
            let (fp, fq) = (along(p), along(q));
            if fp < 0.0 && fq < 0.0 {
                continue;
            }
            // The part of the edge in front of the joint.
            let (p, q) = match (fp >= 0.0, fq >= 0.0) {
                (true, true) => (p, q),
                (true, false) => (p, p + (q - p) * (fp / (fp - fq))),
                _ => (p + (q - p) * (fp / (fp - fq)), q),
            };
            let (dp, dq) = ((p - j).length_squared(), (q - j).length_squared());
            for (end, d2) in [(p, dp), (q, dq)] {
                if r2_in <= d2 && d2 <= r2 {
                    take(end);
                }
            }
            // A circle is crossed only by an edge with an end outside it.
            if dp > r2 || dq > r2 {
                for s in circle_crossings(p, q, j, r) {
                    take(p + (q - p) * s);
                }
            }
            if r_in > 0.0 && (dp > r2_in || dq > r2_in) {
                for s in circle_crossings(p, q, j, r_in) {
                    take(p + (q - p) * s);
                }
            }
        }
    }
    if min_s > max_s || max_s < sweep.lo_slope || min_s > sweep.hi_slope {
        return Contact::None;
    }
    if max_s > sweep.hi_slope {
        return Contact::Blocks;
    }
    Contact::At(max_s.atan() + sweep.mid)
}

/// A segment's sweep of angles `[lo, hi]`: its middle, the slopes of its
/// ends relative to the middle, and the box of the sector it covers.
struct Sweep {
    mid: f32,
    mid_sin: f32,
    mid_cos: f32,
    lo_slope: f32,
    hi_slope: f32,
    box_lo: Vec2,
    box_hi: Vec2,
}

impl Sweep {
    /// An angle (as [`sector_of_prism`] reports them) that no point of
    /// `t`'s box in the (x, z) plane within `reach` of `joint` exceeds as
    /// seen from it: the corners' of the box cut to the square round that
    /// disc (the highest slope over a rectangle in front of the joint is at
    /// a corner); `None` when a corner lies level with or behind the joint,
    /// when the box comes near the joint (where the rounding of the points
    /// [`sector_of_prism`] interpolates turns into large angles), or when
    /// it is not finite.
    fn angle_bound(&self, joint: Vec2, reach: f32, t: &SweptTriangle) -> Option<f32> {
        let (ms, mc) = (self.mid_sin, self.mid_cos);
        let mut most = f32::NEG_INFINITY;
        // Only points within `reach` of the joint count (see
        // [`sector_of_prism`]): the box cut to the square round that disc,
        // widened far beyond the rounding of the points cut from it.
        let r = Vec2::splat(reach);
        let pad = Vec2::splat(BOUND_PAD * (reach + joint.abs().max_element()));
        let (lo, hi) = (Vec2::new(t.lo.x, t.lo.z).max(joint - r), Vec2::new(t.hi.x, t.hi.z).min(joint + r));
        let (lo, hi) = (lo - pad, hi + pad);
        let gap = (lo - joint).max(joint - hi).max(Vec2::ZERO);
        if !(lo.is_finite() && hi.is_finite()) || gap.length() < BOUND_NEAR * reach {
            return None;
        }
        for p in [lo, Vec2::new(lo.x, hi.y), Vec2::new(hi.x, lo.y), hi] {
            let d = p - joint;
            let (along, up) = (mc * d.x + ms * d.y, mc * d.y - ms * d.x);
            if along.is_nan() || along <= 0.0 {
                return None;
            }
            most = most.max(up / along);
        }
        Some(most.atan() + self.mid)
    }

    fn new(seg: &Segment, lo: f32, hi: f32) -> Self {
        let mid = 0.5 * (lo + hi);
        let (mid_sin, mid_cos) = mid.sin_cos();
        let half = (0.5 * (hi - lo)).tan();
        let (j, r) = (seg.joint, seg.length);
        let ends = [Vec2::from_angle(lo) * r, Vec2::from_angle(hi) * r];
        let mut box_lo = Vec2::ZERO.min(ends[0]).min(ends[1]);
        let mut box_hi = Vec2::ZERO.max(ends[0]).max(ends[1]);
        // The arc's extreme points where the sweep passes an axis.
        for (a, p) in [(0.0f32, Vec2::X), (FRAC_PI_2, Vec2::Y), (-FRAC_PI_2, -Vec2::Y)] {
            if lo <= a && a <= hi {
                box_lo = box_lo.min(p * r);
                box_hi = box_hi.max(p * r);
            }
        }
        Self { mid, mid_sin, mid_cos, lo_slope: -half, hi_slope: half, box_lo: j + box_lo, box_hi: j + box_hi }
    }
}

/// Cuts triangle `t` (roll frame) to the band `|y| ≤ h`; writes the cut
/// polygon's (x, z) vertices into `out` and returns how many.
fn cut_to_band(t: &[Vec3; 3], h: f32, out: &mut [Vec2; CUT_VERTICES]) -> usize {
    let mut a = [Vec3::ZERO; CUT_VERTICES];
    let mut b = [Vec3::ZERO; CUT_VERTICES];
    a[..3].copy_from_slice(t);
    let mut n = 3;
    for (sign, bound) in [(1.0f32, h), (-1.0, h)] {
        let mut m = 0;
        for k in 0..n {
            let (p, q) = (a[k], a[(k + 1) % n]);
            let (dp, dq) = (bound - sign * p.y, bound - sign * q.y);
            if dp >= 0.0 && m < CUT_VERTICES {
                b[m] = p;
                m += 1;
            }
            if (dp >= 0.0) != (dq >= 0.0) && m < CUT_VERTICES {
                b[m] = p + (q - p) * (dp / (dp - dq));
                m += 1;
            }
        }
        a = b;
        n = m;
        if n == 0 {
            return 0;
        }
    }
    for k in 0..n {
        out[k] = Vec2::new(a[k].x, a[k].z);
    }
    n
}

/// Parameters `s ∈ [0, 1]` where the segment `p + s (q − p)` crosses the
/// circle of radius `r` about `c` (none, one or two).
fn circle_crossings(p: Vec2, q: Vec2, c: Vec2, r: f32) -> impl Iterator<Item = f32> {
    let d = q - p;
    let f = p - c;
    let (a, b, cc) = (d.dot(d), 2.0 * f.dot(d), f.dot(f) - r * r);
    let disc = b * b - 4.0 * a * cc;
    let roots = if a <= 0.0 || disc < 0.0 {
        [f32::NAN; 2]
    } else {
        let sq = disc.sqrt();
        [(-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)]
    };
    roots.into_iter().filter(|s| (0.0..=1.0).contains(s))
}

/// Whether the prism `lower ⊕ [0, raise]` (a convex polygon swept along
/// `raise`) holds the point `j`: whether the segment from `j − raise` to
/// `j` meets the polygon.
fn prism_holds(lower: &[Vec2], raise: Vec2, j: Vec2) -> bool {
    let n = lower.len();
    let area: f32 = (0..n).map(|k| lower[k].perp_dot(lower[(k + 1) % n])).sum();
    if area == 0.0 {
        return false;
    }
    let (p, d) = (j - raise, raise);
    let (mut s0, mut s1) = (0.0f32, 1.0f32);
    for k in 0..n {
        let (a, b) = (lower[k], lower[(k + 1) % n]);
        // Inside is where the signed distance to each edge has the sign of
        // the polygon's orientation.
        let e = b - a;
        let side = |x: Vec2| e.perp_dot(x - a) * area.signum();
        let (f0, df) = (side(p), e.perp_dot(d) * area.signum());
        if df == 0.0 {
            if f0 < 0.0 {
                return false;
            }
        } else {
            let s = -f0 / df;
            if df > 0.0 {
                s0 = s0.max(s)
            } else {
                s1 = s1.min(s)
            }
            if s0 > s1 {
                return false;
            }
        }
    }
    true
}

/// The lowest angle in `[lo, hi]` at which the segment clears the obstacle
/// prisms and the skin; `None` when it is blocked.
fn lowest_clear_angle(swept: &[SweptTriangle], seg: &Segment, lo: f32, hi: f32) -> Option<f32> {
    lowest_clear_angle_pruned(swept, seg, (lo, hi), true)
}

/// [`lowest_clear_angle`], passing over the prisms its bounding angle
/// rules out when `prune` (the same answer either way).
fn lowest_clear_angle_pruned(swept: &[SweptTriangle], seg: &Segment, (lo, hi): (f32, f32), prune: bool) -> Option<f32> {
    let mut angle = lo;
    let sweep = Sweep::new(seg, lo, hi);
    for t in swept {
        if t.hi.x < sweep.box_lo.x || t.lo.x > sweep.box_hi.x || t.hi.z < sweep.box_lo.y || t.lo.z > sweep.box_hi.y {
            continue;
        }
        // Nothing of a prism whose box is seen from the joint no higher
        // than the angle reached so far can raise it (or block).
        if prune
            && sweep.angle_bound(seg.joint, seg.length, t).is_some_and(|a| a + ANGLE_EPSILON + BOUND_MARGIN < angle)
        {
            continue;
        }
        for &(r_in, r_out, half) in &seg.pieces {
            if t.hi.y < -half || t.lo.y > half {
                continue;
            }
            let r_in = if t.skin { r_in.max(seg.skin_from) } else { r_in };
            match sector_of_prism(t, half, seg.joint, (r_in, r_out), &sweep) {
                Contact::None => {}
                Contact::At(a) => angle = angle.max(a + ANGLE_EPSILON),
                Contact::Blocks => return None,
            }
        }
    }
    if angle > hi + ANGLE_TOLERANCE {
        return None;
    }
    Some(angle.min(hi))
}

/// The swept drape from the straight pose (see the module notes): the pose
/// with the straight pose's roll and scale and each segment's lowest clear
/// angle, or `None` when there is no room within the limits. `shape` is the
/// feather at its size, `swept` what lies beneath it (see
/// [`fill_swept_triangles`]), `socket` the root socket as a fraction of the
/// length (nothing nearer the root is swept for obstacles).
pub(super) fn swept_drape(
    swept: &[SweptTriangle],
    socket: f32,
    shape: &FeatherShape,
    straight: FeatherPose,
    params: &AdjustParams,
) -> Option<FeatherPose> {
    let (bend_low, bend_high) = params.bend_range();
    let segments = shape.segment_count();
    let seg_len = shape.length / segments as f32;
    let pieces: [[(f32, f32, f32); PIECES]; MAX_SEGMENTS] =
        std::array::from_fn(|k| std::array::from_fn(|p| piece_of(shape, socket, k.min(segments - 1), p)));
    let bounds = |angles: &[f32; MAX_SEGMENTS], k: usize| {
        if k == 0 { (params.min_pitch, straight.pitch) } else { (angles[k - 1] + bend_low, angles[k - 1] + bend_high) }
    };
    let segment = |angles: &[f32; MAX_SEGMENTS], k: usize| {
        let mut joint = Vec2::ZERO;
        for &a in &angles[..k] {
            let (s, c) = a.sin_cos();
            joint += Vec2::new(c, s) * seg_len;
        }
        Segment {
            joint,
            length: seg_len,
            skin_from: if k == 0 { ROOT_ALLOWANCE * shape.length } else { 0.0 },
            pieces: pieces[k],
        }
    };
    // Drapes segments `from..=to`, each at its lowest clear angle; the
    // first blocked one, if any.
    let drape_from = |angles: &mut [f32; MAX_SEGMENTS], from: usize, to: usize| -> Option<usize> {
        for k in from..=to {
            let (lo, hi) = bounds(angles, k);
            match lowest_clear_angle(swept, &segment(angles, k), lo, hi) {
                // Fluffiness lifts the root segment off what it lies on (it
                // is clear from its lowest angle up).
                Some(a) if k == 0 => angles[k] = (a + params.fluffiness.max(0.0)).min(hi),
                Some(a) => angles[k] = a,
                None => return Some(k),
            }
        }
        None
    };
    let mut angles = [0.0f32; MAX_SEGMENTS];
    let mut k = 0;
    let mut backtracks = 0;
    while k < segments {
        let Some(blocked) = drape_from(&mut angles, k, segments - 1) else { break };
        backtracks += 1;
        if backtracks > MAX_BACKTRACKS || blocked == 0 {
            return None;
        }
        // Raise the nearest earlier segment that can make room, by
        // bisection, to the lowest angle from which the segments after it
        // up to the blocked one drape.
        let mut raised = None;
        for i in (0..blocked).rev() {
            let (_, hi) = bounds(&angles, i);
            let from = angles[i];
            let room = |a: f32| {
                let mut trial = angles;
                trial[i] = a;
                drape_from(&mut trial, i + 1, blocked).is_none()
            };
            if from >= hi || !room(hi) {
                continue;
            }
            let (mut failed, mut fits) = (from, hi);
            for _ in 0..RAISE_BISECTIONS {
                let mid = 0.5 * (failed + fits);
                if room(mid) { fits = mid } else { failed = mid }
            }
            raised = Some((i, fits));
            break;
        }
        let (i, a) = raised?;
        angles[i] = a;
        k = i + 1;
    }
    // Absolute angles back to a pitch and bends, each within its limits
    // (the differences may round a hair past them).
    let mut pose = straight;
    pose.pitch = angles[0].clamp(params.min_pitch, params.max_pitch);
    for j in 1..segments {
        pose.bends[j - 1] = (angles[j] - angles[j - 1]).clamp(bend_low, bend_high);
    }
    Some(pose)
}

#[cfg(test)]
#[path = "sweep_tests.rs"]
mod tests;
