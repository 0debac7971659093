//! The exact checks' shortcuts held to the exhaustive answers. Every check
//! the adjuster makes, of one feather against another and of one feather
//! against the body, is answered twice: by the adjuster's checker (boxes
//! side by side, a straight feather's plane, separating axes, triangles
//! prepared on demand, the bounded nearest-skin search) and by testing
//! every pair of triangles whose boxes meet and measuring every skin face.
//! The coat is checked as it lies and nudged into and out of contact, so
//! that both answers occur. The tests run it on animated clips.

use super::exact::{
    BodyScratch, FeatherBoxes, feather_beyond_root, penetrates_body, skin_tolerance, tie_distance, under_tied_faces,
};
use super::feather_grid;
use crate::body::BodyIndex;
use crate::feather::{FeatherPose, FeatherShape, FeatherTriangles};
use crate::geometry::RootFrame;
use crate::intersect::triangles_intersect;
use crate::triangle_grid::{Aabb, closest_point_on_triangle};
use glam::Vec3;
use rayon::prelude::*;

/// How many checks an audit made and how many answers differed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CheckAudit {
    /// Feather pairs checked, each nudge counted.
    pub pair_checks: u64,
    /// Of those, the pairs that intersect (the exhaustive answer).
    pub pairs_meeting: u64,
    /// Pairs whose two answers differ.
    pub pair_disagreements: u64,
    /// Feathers checked against the body, each nudge counted.
    pub body_checks: u64,
    /// Of those, the feathers that penetrate the body (the exhaustive answer).
    pub bodies_penetrating: u64,
    /// Feathers whose two body answers differ.
    pub body_disagreements: u64,
}

impl std::ops::Add for CheckAudit {
    type Output = Self;

    /// Both audits' counts together.
    fn add(self, o: Self) -> Self {
        Self {
            pair_checks: self.pair_checks + o.pair_checks,
            pairs_meeting: self.pairs_meeting + o.pairs_meeting,
            pair_disagreements: self.pair_disagreements + o.pair_disagreements,
            body_checks: self.body_checks + o.body_checks,
            bodies_penetrating: self.bodies_penetrating + o.bodies_penetrating,
            body_disagreements: self.body_disagreements + o.body_disagreements,
        }
    }
}

/// The other feather moved along the checked one's root normal by these
/// multiples of its thickness: as it lies, grazing, half sunk, through.
const PAIR_NUDGES: [f32; 7] = [0.0, 0.05, -0.05, 0.5, -0.5, 1.5, -1.5];

/// The checked feather's pitch lowered by these angles (radians): as it
/// lies, grazing the skin, into it.
const BODY_NUDGES: [f32; 3] = [0.0, 0.03, 0.15];

/// Audits the checks of the coat `feather_triangles` (feather `i` at
/// `frames[i]`, `shapes[i]`, `poses[i]`) on `body`: each feather against
/// every other whose box, widened by twice the thickest feather, meets
/// its own, and against the body.
pub fn audit_checks(
    feather_triangles_now: &[FeatherTriangles],
    frames: &[RootFrame],
    shapes: &[FeatherShape],
    poses: &[FeatherPose],
    body: &BodyIndex,
) -> CheckAudit {
    let (grid, owner) = feather_grid(feather_triangles_now);
    let reach = 2.0 * shapes.iter().map(|s| s.thickness).fold(0.0f32, f32::max);
    (0..frames.len())
        .into_par_iter()
        .map_init(
            || (Vec::new(), BodyScratch::default()),
            |(ids, scratch), i| {
                let mut audit = CheckAudit::default();
                let mine = &feather_triangles_now[i];
                if let Some(bounds) = bounds_of(mine) {
                    let widened = Aabb { min: bounds.min - Vec3::splat(reach), max: bounds.max + Vec3::splat(reach) };
                    grid.query_box(&widened, ids);
                    let mut others: Vec<u32> =
                        ids.iter().map(|&t| owner[t as usize]).filter(|&j| j as usize > i).collect();
                    others.sort_unstable();
                    others.dedup();
                    for &j in &others {
                        audit = audit + audit_pair(i, j as usize, feather_triangles_now, frames, shapes, poses);
                    }
                }
                audit + audit_body(&frames[i], &shapes[i], poses[i], body, scratch)
            },
        )
        .reduce(CheckAudit::default, |a, b| a + b)
}

/// The box of a feather's triangles (`None` without any).
fn bounds_of(triangles: &[[Vec3; 3]]) -> Option<Aabb> {
    triangles.iter().map(Aabb::of_triangle).reduce(|a, b| a.union(&b))
}

/// Feather `i` (at its pose, checked as the adjuster checks it) against
/// feather `j` nudged along `i`'s root normal.
fn audit_pair(
    i: usize,
    j: usize,
    triangles: &[FeatherTriangles],
    frames: &[RootFrame],
    shapes: &[FeatherShape],
    poses: &[FeatherPose],
) -> CheckAudit {
    let mut audit = CheckAudit::default();
    let mine = &triangles[i];
    let checker = FeatherBoxes::of_posed_feather(&frames[i], &shapes[i], poses[i], mine);
    for nudge in PAIR_NUDGES {
        let offset = frames[i].normal * (nudge * shapes[j].thickness);
        let theirs: Vec<[Vec3; 3]> = triangles[j].iter().map(|t| t.map(|p| p + offset)).collect();
        let exhaustive = mine.iter().any(|a| theirs.iter().any(|b| triangles_intersect(a, b)));
        let shortcut = checker.intersects(&theirs);
        audit.pair_checks += 1;
        audit.pairs_meeting += u64::from(exhaustive);
        audit.pair_disagreements += u64::from(exhaustive != shortcut);
    }
    audit
}

/// One feather against the body, as it lies and lowered.
fn audit_body(
    frame: &RootFrame,
    shape: &FeatherShape,
    pose: FeatherPose,
    body: &BodyIndex,
    scratch: &mut BodyScratch,
) -> CheckAudit {
    let mut audit = CheckAudit::default();
    for lower in BODY_NUDGES {
        let pose = FeatherPose { pitch: pose.pitch - lower, ..pose };
        let exhaustive = penetrates_body_exhaustive(frame, shape, pose, body);
        let shortcut = penetrates_body(frame, shape, pose, body, scratch);
        audit.body_checks += 1;
        audit.bodies_penetrating += u64::from(exhaustive);
        audit.body_disagreements += u64::from(exhaustive != shortcut);
    }
    audit
}

/// The body test of [`penetrates_body`] without its shortcuts: every part
/// triangle against every skin face whose box meets its own, then, crossing
/// none, each part triangle's first corner off the skin judged from every
/// skin face.
fn penetrates_body_exhaustive(frame: &RootFrame, shape: &FeatherShape, pose: FeatherPose, body: &BodyIndex) -> bool {
    if pose.scale <= 0.0 {
        return false;
    }
    let part = feather_beyond_root(frame, shape, pose);
    let faces = 0..body.triangle_count() as u32;
    // Faces far from a part triangle (boxes apart by more than a hundredth
    // of their diagonals, ten thousand times the exact test's tolerance)
    // are not tested: a looser rule than the checker's own.
    let crosses = part.iter().any(|t| {
        let bounds = Aabb::of_triangle(t);
        faces.clone().any(|f| {
            let face = body.bounds(f);
            let widen = Vec3::splat(0.01 * ((bounds.max - bounds.min).length() + (face.max - face.min).length()));
            Aabb { min: face.min - widen, max: face.max + widen }.overlaps(&bounds)
                && triangles_intersect(t, &body.corners(f))
        })
    });
    crosses || part.iter().any(|t| t.iter().find_map(|&p| side_of_skin_exhaustive(body, p, shape.length)) == Some(true))
}

/// [`super::exact`]'s side of the skin from every face: `None` on the skin
/// or with no skin within `reach`.
fn side_of_skin_exhaustive(body: &BodyIndex, p: Vec3, reach: f32) -> Option<bool> {
    let faces = 0..body.triangle_count() as u32;
    let distances: Vec<(u32, f32, Vec3)> = faces
        .map(|f| {
            let q = closest_point_on_triangle(p, body.corners(f));
            (f, (q - p).length(), q)
        })
        .collect();
    let &(_, nearest, point) =
        distances.iter().min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0))).filter(|n| n.1 <= reach)?;
    let tolerance = skin_tolerance(p, reach);
    if nearest <= tolerance {
        return None;
    }
    let tie = tie_distance(nearest, tolerance);
    let tied: Vec<u32> = distances.iter().filter(|d| d.1 <= tie).map(|d| d.0).collect();
    Some(under_tied_faces(body, p, point, &tied))
}
