//! The inside of the body: which parts of the skin are buried where the
//! mesh passes through itself (a wing's root inside the torso, a belly
//! poking through the wing's underside, a leg sunk into the body). Nothing
//! there can be seen, so no root is planted and no coverage probe is drawn
//! on it.
//!
//! A point is inside when its winding number for the body's triangles is
//! at least 1. Along a ray the winding number is the number of triangles
//! the ray leaves the body through less the number it enters through; it
//! is the same for every ray of a closed mesh, and a vote of three rays
//! settles a ray grazing an edge or a mesh with holes.

use crate::body::BodyIndex;
use crate::error::{Error, ErrorKind, Result};
use crate::intersect::triangles_intersect;
use crate::triangle_grid::{Aabb, ray_triangle};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Offset of the point whose winding number is measured, off the skin
/// along its normal, as a fraction of the body's extent: far enough that
/// the skin's own triangle is not crossed, close enough to stay within the
/// thinnest parts of the test models (wings 2 % of the extent thick).
const WINDING_OFFSET: f32 = 1e-5;

/// Tilt of the two extra rays away from the normal (tangent of the angle).
const WINDING_RAY_TILT: f32 = 0.5;

/// How a face of the skin lies with respect to the rest of the body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceBurial {
    /// Outside the body: visible skin.
    Visible,
    /// Wholly inside the body.
    Buried,
    /// Crossed by other faces: part visible, part buried (test each point).
    Crossed,
}

/// The inside of a body mesh.
pub struct BodyInterior<'a> {
    body: &'a BodyIndex,
    /// How far off the skin a point's winding number is measured.
    offset: f32,
}

impl<'a> BodyInterior<'a> {
    /// The inside of `body` (nothing is inside an empty body).
    pub fn new(body: &'a BodyIndex) -> Self {
        Self { body, offset: WINDING_OFFSET * body_extent(body).unwrap_or(0.0) }
    }

    /// Whether the skin point `p` with unit normal `n` is buried: the point
    /// just off it along `n` has a winding number of at least 1 for at
    /// least two of three rays. A triangle without area (whose normal is
    /// not finite) counts for no ray.
    pub fn holds(&self, p: Vec3, n: Vec3) -> bool {
        self.holds_within(p, n, &WorkBudget::unlimited())
    }

    /// As [`BodyInterior::holds`], spending `budget` on the rays' triangle
    /// tests; with the budget spent, `false` without a test.
    fn holds_within(&self, p: Vec3, n: Vec3, budget: &WorkBudget) -> bool {
        // A degenerate face has no normal: it is judged visible.
        if self.body.triangle_count() == 0 || !p.is_finite() || !n.is_finite() || n == Vec3::ZERO {
            return false;
        }
        let origin = p + n * self.offset;
        let (u, v) = n.any_orthonormal_pair();
        let inside_along = |dir: Vec3| !budget.exhausted() && self.winding_along_ray(origin, dir, budget) >= 1;
        let (first, second) = (inside_along(n), inside_along((n + u * WINDING_RAY_TILT).normalize()));
        // Two rays that agree are already the majority.
        if first == second { first } else { inside_along((n - v * WINDING_RAY_TILT).normalize()) }
    }

    /// Each of the body's faces (in its index order): visible, buried, or
    /// crossed by another face. A face meeting no other face lies wholly on
    /// one side, judged at its centroid; faces sharing a corner are not
    /// compared (they touch by construction). Each face is judged on its
    /// own: joining faces into patches by their edges would be cheaper, but
    /// the test models' skins pass through themselves next to shared
    /// corners too, and patches then mixed inside and outside (coverage
    /// fell: BENCHMARKS.md, "Measurements behind the code's constants").
    pub fn face_burials(&self, triangles: &[[u32; 3]]) -> Vec<FaceBurial> {
        self.face_burials_within(triangles, &WorkBudget::unlimited())
    }

    /// As [`BodyInterior::face_burials`], spending `budget` on each face's
    /// box query, crossing tests and rays; once it is spent, the remaining
    /// faces are judged crossed without any test (the caller refuses the
    /// mesh, see [`WorkBudget::exhausted`]).
    fn face_burials_within(&self, triangles: &[[u32; 3]], budget: &WorkBudget) -> Vec<FaceBurial> {
        (0..triangles.len())
            .into_par_iter()
            .map_init(Vec::new, |nearby, f| {
                if budget.exhausted() {
                    return FaceBurial::Crossed;
                }
                let corners = self.body.corners(f as u32);
                self.body.triangles_in_box(&Aabb::of_triangle(&corners), nearby);
                let mut tests = nearby.len() as u64;
                let crossed = nearby.iter().any(|&g| {
                    let other = triangles[g as usize];
                    let candidate = g as usize != f && !other.iter().any(|v| triangles[f].contains(v));
                    tests += candidate as u64;
                    candidate && triangles_intersect(&corners, &self.body.corners(g))
                });
                budget.spend(tests);
                let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
                match (crossed, self.holds_within(centroid, self.body.normal(f as u32), budget)) {
                    (true, _) => FaceBurial::Crossed,
                    (false, true) => FaceBurial::Buried,
                    (false, false) => FaceBurial::Visible,
                }
            })
            .collect()
    }

    /// Triangles leaving the body along the ray less triangles entering it
    /// (each triangle counted once; one whose plane holds the ray counts
    /// for neither).
    ///
    /// Each triangle is tested once per ray however many cells it spans
    /// (a stamp per triangle, per thread): a soup of large faces crossing
    /// one another, or a few huge faces among tiny ones, otherwise tested
    /// the same face in every cell the ray walked.
    fn winding_along_ray(&self, origin: Vec3, dir: Vec3, budget: &WorkBudget) -> i32 {
        let grid = self.body.grid();
        RAY_STAMPS.with(|stamps| {
            let mut stamps = stamps.borrow_mut();
            let stamp = stamps.next(grid.len());
            let (mut winding, mut tests) = (0, 0u64);
            grid.ray_cast(origin, dir, f32::INFINITY, |t| {
                tests += 1;
                if stamps.first_visit(t, stamp) && ray_triangle(origin, dir, grid.corners(t)).is_some() {
                    let c = self.body.normal(t).dot(dir);
                    if c.is_finite() && c != 0.0 {
                        winding += c.signum() as i32;
                    }
                }
                None
            });
            budget.spend(tests);
            winding
        })
    }
}

/// A cap on the triangle tests (box-query results, crossing tests, ray
/// tests) that telling buried skin from visible skin may take. On a real
/// skin these stay within a few thousand per triangle and root; a mesh whose
/// triangles are long and cross one another everywhere (positions read
/// with the wrong stride or offset) needs about one test per triangle of the
/// whole mesh for every ray, and would otherwise sample for minutes.
///
/// Spending is counted, never ordered: whether the budget runs out depends
/// only on the total work the unbounded judgement would do, not on the
/// thread count or schedule, so the outcome (done, or refused) is
/// deterministic.
pub struct WorkBudget {
    left: AtomicU64,
}

impl WorkBudget {
    /// A budget of `tests` triangle tests.
    pub fn new(tests: u64) -> Self {
        Self { left: AtomicU64::new(tests) }
    }

    /// A budget that never runs out.
    pub fn unlimited() -> Self {
        Self::new(u64::MAX)
    }

    /// Spends `tests`, saturating at zero.
    fn spend(&self, tests: u64) {
        let _ = self.left.fetch_update(Ordering::Relaxed, Ordering::Relaxed, |left| Some(left.saturating_sub(tests)));
    }

    /// Whether the budget is spent.
    pub fn exhausted(&self) -> bool {
        self.left.load(Ordering::Relaxed) == 0
    }
}

/// Triangle tests allowed per body triangle and per root aimed at (see
/// [`WorkBudget`]): the shared test models take at most about 1 000.
pub(crate) const BURIAL_TESTS_PER_ELEMENT: u64 = 4096;

/// Triangle tests always allowed, whatever the mesh's size.
pub(crate) const BURIAL_TESTS_FLOOR: u64 = 1 << 22;

/// Per-thread marks of the triangles one ray has tested: `marks[t] ==
/// stamp` once triangle `t` was tested by the current ray.
struct RayStamps {
    stamp: u32,
    marks: Vec<u32>,
}

impl RayStamps {
    /// A fresh stamp for a new ray over `triangles` triangles.
    fn next(&mut self, triangles: usize) -> u32 {
        if self.marks.len() < triangles {
            self.marks.resize(triangles, 0);
        }
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.marks.fill(0);
            self.stamp = 1;
        }
        self.stamp
    }

    /// Whether triangle `t` is seen for the first time by the ray `stamp`
    /// (and marks it).
    #[inline]
    fn first_visit(&mut self, t: u32, stamp: u32) -> bool {
        let mark = &mut self.marks[t as usize];
        let first = *mark != stamp;
        *mark = stamp;
        first
    }
}

thread_local! {
    static RAY_STAMPS: std::cell::RefCell<RayStamps> = const { std::cell::RefCell::new(RayStamps { stamp: 0, marks: Vec::new() }) };
}

/// The buried part of a skin: each face's burial, and the winding test for
/// points of the faces other faces cross.
pub struct BuriedSkin {
    body: BodyIndex,
    offset: f32,
    faces: Vec<FaceBurial>,
    budget: WorkBudget,
}

impl BuriedSkin {
    /// The buried part of the mesh (`positions`, `triangles`) at that pose,
    /// judged within a budget of [`BURIAL_TESTS_PER_ELEMENT`] × (triangles +
    /// `roots`) + [`BURIAL_TESTS_FLOOR`] triangle tests for this and every
    /// later [`BuriedSkin::holds`]. Fails (before any later work) when
    /// judging the faces alone spends it.
    pub fn new(positions: &[Vec3], triangles: &[[u32; 3]], roots: usize) -> Result<Self> {
        let elements = (triangles.len() as u64).saturating_add(roots as u64);
        let budget =
            WorkBudget::new(elements.saturating_mul(BURIAL_TESTS_PER_ELEMENT).saturating_add(BURIAL_TESTS_FLOOR));
        let body = BodyIndex::from_mesh(positions, triangles);
        let interior = BodyInterior::new(&body);
        let (offset, faces) = (interior.offset, interior.face_burials_within(triangles, &budget));
        let skin = Self { body, offset, faces, budget };
        skin.within_budget()?;
        Ok(skin)
    }

    /// `Ok` while the judgements made so far kept within the budget; once
    /// they did not, the error that refuses the mesh (every judgement made
    /// after that point answered "visible" without a test).
    pub fn within_budget(&self) -> Result<()> {
        if !self.budget.exhausted() {
            return Ok(());
        }
        let crossed = self.faces.iter().filter(|&&f| f == FaceBurial::Crossed).count();
        Err(Error::new(
            ErrorKind::InvalidMesh,
            format!(
                "the mesh looks scrambled: {crossed} of its {} triangles cross other triangles (or were not reached), and telling buried skin from visible skin needs more than {} triangle tests per triangle and feather; were the positions or indices read with the wrong stride, offset or type?",
                self.faces.len(),
                BURIAL_TESTS_PER_ELEMENT
            ),
        ))
    }

    /// How face `f` lies.
    pub fn face(&self, f: usize) -> FaceBurial {
        self.faces[f]
    }

    /// Whether the point `p` (unit normal `n`) of face `f` is buried.
    pub fn holds(&self, f: usize, p: Vec3, n: Vec3) -> bool {
        match self.faces[f] {
            FaceBurial::Visible => false,
            FaceBurial::Buried => true,
            FaceBurial::Crossed => {
                BodyInterior { body: &self.body, offset: self.offset }.holds_within(p, n, &self.budget)
            }
        }
    }
}

/// The diagonal of the box around every body corner, or `None` without
/// triangles.
fn body_extent(body: &BodyIndex) -> Option<f32> {
    let corners = body.grid().all_corners();
    let first = corners.first()?[0];
    let (lo, hi) = corners.iter().flatten().fold((first, first), |(lo, hi), &c| (lo.min(c), hi.max(c)));
    Some((hi - lo).length())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An axis-aligned box, triangles wound outwards.
    fn cuboid(lo: Vec3, hi: Vec3) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            })
            .collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let tris = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        (p, tris)
    }

    /// A unit box with a long slab passing through it along x.
    fn box_and_slab() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (mut pos, mut tris) = cuboid(Vec3::splat(-1.0), Vec3::splat(1.0));
        let (slab_pos, slab_tris) = cuboid(Vec3::new(-3.0, -0.2, -0.5), Vec3::new(3.0, 0.2, 0.5));
        let base = pos.len() as u32;
        pos.extend(slab_pos);
        tris.extend(slab_tris.iter().map(|t| t.map(|v| v + base)));
        (pos, tris)
    }

    #[test]
    fn a_ray_tests_each_triangle_once_and_the_next_ray_again() {
        let mut stamps = RayStamps { stamp: u32::MAX - 1, marks: Vec::new() };
        let first = stamps.next(3);
        assert!(stamps.first_visit(2, first) && !stamps.first_visit(2, first), "once per ray");
        // The stamp wraps past zero: the marks are cleared, nothing is skipped.
        let second = stamps.next(3);
        assert_eq!(second, 1, "after the wrap");
        assert!(stamps.first_visit(2, second) && !stamps.first_visit(2, second));
        // More triangles than before: the new ones are unmarked too.
        let third = stamps.next(5);
        assert!((0..5).all(|t| stamps.first_visit(t, third)), "a new ray sees every triangle afresh");
    }

    #[test]
    fn skin_inside_another_part_is_buried() {
        let (pos, tris) = box_and_slab();
        let body = BodyIndex::from_mesh(&pos, &tris);
        let inside = BodyInterior::new(&body);
        assert!(inside.holds(Vec3::new(0.0, 0.2, 0.0), Vec3::Y), "slab top inside the box");
        assert!(!inside.holds(Vec3::new(2.0, 0.2, 0.0), Vec3::Y), "slab top outside the box");
        assert!(!inside.holds(Vec3::new(0.5, 1.0, 0.5), Vec3::Y), "box top");
        assert!(inside.holds(Vec3::new(1.0, 0.0, 0.2), Vec3::X), "box side inside the slab");
        assert!(!inside.holds(Vec3::new(1.0, 0.5, 0.0), Vec3::X), "box side above the slab");
        assert!(inside.holds(Vec3::new(0.5, 0.0, 0.5), Vec3::Z), "slab side inside the box");
    }

    #[test]
    fn faces_crossing_each_other_are_told_apart_from_whole_ones() {
        let (pos, tris) = box_and_slab();
        let body = BodyIndex::from_mesh(&pos, &tris);
        let burials = BodyInterior::new(&body).face_burials(&tris);
        // The slab's long faces cross the box's ±x sides, and those sides
        // cross the slab; the box's other faces and the slab's end caps are
        // whole and outside.
        let (box_faces, slab_faces) = burials.split_at(12);
        let side = |faces: &[FaceBurial], quad: usize| [faces[2 * quad], faces[2 * quad + 1]];
        for quad in [0, 1, 2, 3] {
            assert!(side(slab_faces, quad).iter().all(|&b| b == FaceBurial::Crossed), "slab quad {quad}");
            assert!(side(box_faces, quad).iter().all(|&b| b == FaceBurial::Visible), "box quad {quad}");
        }
        for quad in [4, 5] {
            assert!(side(slab_faces, quad).iter().all(|&b| b == FaceBurial::Visible), "slab end {quad}");
            assert!(side(box_faces, quad).contains(&FaceBurial::Crossed), "box side {quad}");
        }
        // A small box wholly inside the big one is buried.
        let (mut pos, mut tris) = cuboid(Vec3::splat(-1.0), Vec3::splat(1.0));
        let (inner_pos, inner_tris) = cuboid(Vec3::splat(-0.3), Vec3::splat(0.3));
        pos.extend(inner_pos);
        tris.extend(inner_tris.iter().map(|t| t.map(|v| v + 8)));
        let body = BodyIndex::from_mesh(&pos, &tris);
        let burials = BodyInterior::new(&body).face_burials(&tris);
        assert!(burials[..12].iter().all(|&b| b == FaceBurial::Visible));
        assert!(burials[12..].iter().all(|&b| b == FaceBurial::Buried));
    }

    #[test]
    fn a_face_without_area_is_judged_without_hanging() {
        // A sliver (collinear corners) inside the box: no normal, so no ray
        // can start from it and no ray counts it; the box stays visible.
        let (mut pos, mut tris) = cuboid(Vec3::splat(-1.0), Vec3::splat(1.0));
        pos.extend([Vec3::new(-0.5, 0.0, 0.0), Vec3::ZERO, Vec3::new(0.5, 0.0, 0.0)]);
        tris.push([8, 9, 10]);
        let body = BodyIndex::from_mesh(&pos, &tris);
        let burials = BodyInterior::new(&body).face_burials(&tris);
        assert!(burials[..12].iter().all(|&b| b == FaceBurial::Visible), "{burials:?}");
        assert_eq!(burials[12], FaceBurial::Visible);
        assert!(!BodyInterior::new(&body).holds(Vec3::ZERO, Vec3::NAN));
        // A ray without a direction meets nothing (it used to walk the grid forever).
        assert!(body.grid().ray_cast(Vec3::ZERO, Vec3::NAN, 1.0, |_| Some(0.5)).is_none());
    }
}
