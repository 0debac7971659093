//! `Walk(p, direction, distance)` of Algorithm 1: tracing a straight line
//! along the surface. Inside a face the path is straight; at an edge the
//! next face is unfolded about the shared edge, so the direction keeps its
//! angle to the edge (geometry-central style tracing). The trace stops at a
//! boundary (or non-manifold) edge and says so.
//!
//! The trace runs in f64 barycentric coordinates: the rate of change of the
//! barycentric coordinate of corner `k` along a unit direction `v` is
//! `β_k = ((p_{k+2} − p_{k+1}) × v)·n / |2A|`, and the path leaves through the
//! side whose coordinate reaches 0 first.

use super::{FaceAcross, Surface};
use crate::geometry::SurfacePoint;
use glam::{DVec3, Vec3};

/// Crossings in a row without progress (passing exactly through a vertex
/// circles its fan) before the point is nudged into the current face.
const STALL_LIMIT: u32 = 48;

/// Relative nudge towards the face centroid that breaks a stall at a vertex.
const STALL_NUDGE: f64 = 1e-7;

/// Why a walk ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WalkEnd {
    /// The whole distance was travelled.
    Arrived,
    /// The path reached a boundary or non-manifold edge: side `side` of face `face`.
    Boundary {
        /// The face whose side was reached.
        face: u32,
        /// The side (edge opposite this corner) that ends the surface.
        side: u8,
    },
    /// The direction was zero, not finite, or normal to the face; or a face
    /// collapsed at this pose. The point is where the trace stood.
    Degenerate,
    /// The step budget ran out (a safety net; not seen on sane meshes).
    StepLimit,
}

/// Where a walk ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkResult {
    /// The end point (always on the mesh, barycentrics in [0, 1] summing to 1).
    pub point: SurfacePoint,
    /// Unit travel direction at the end, in the end face's plane (the start
    /// direction as given when nothing could be traced).
    pub direction: Vec3,
    /// Distance travelled along the surface.
    pub travelled: f32,
    /// Why the walk stopped.
    pub end: WalkEnd,
    /// Edges crossed.
    pub edges_crossed: u32,
}

impl WalkResult {
    /// Whether the walk stopped at a boundary edge.
    pub fn hit_boundary(&self) -> bool {
        matches!(self.end, WalkEnd::Boundary { .. })
    }
}

/// The trace's running state.
struct Tracer {
    face: usize,
    bary: [f64; 3],
    direction: DVec3,
    travelled: f64,
    crossed: u32,
}

impl Surface {
    /// Walks from `start` along `direction` (projected onto the start face)
    /// for `distance` along the surface, at the pose `positions`.
    ///
    /// Never returns NaN and never leaves the mesh: a non-finite or
    /// non-positive distance walks nowhere, a degenerate direction ends with
    /// [`WalkEnd::Degenerate`] at the start. `start.face` must be a face of
    /// this surface; its barycentrics are clamped and renormalised.
    pub fn walk(&self, positions: &[Vec3], start: SurfacePoint, direction: Vec3, distance: f32) -> WalkResult {
        let mut t = Tracer {
            face: start.face as usize,
            bary: sanitised_bary(start.bary),
            direction: direction.as_dvec3(),
            travelled: 0.0,
            crossed: 0,
        };
        let distance = if distance.is_finite() { distance.max(0.0) as f64 } else { 0.0 };
        if !t.direction.is_finite() {
            return t.finish(WalkEnd::Degenerate, direction);
        }
        let mut remaining = distance;
        let mut stalled = 0u32;
        let step_budget = 16 * self.face_count() + 256;
        for _ in 0..step_budget {
            if remaining <= 0.0 {
                return t.finish(WalkEnd::Arrived, direction);
            }
            let corners = self.corners(positions, t.face).map(|p| p.as_dvec3());
            let Some(beta) = t.bary_velocity(corners) else {
                return t.finish(WalkEnd::Degenerate, direction);
            };
            let (exit_time, side) = first_exit(t.bary, beta);
            if exit_time >= remaining {
                t.advance(beta, remaining);
                return t.finish(WalkEnd::Arrived, direction);
            }
            t.advance(beta, exit_time);
            t.bary[side] = 0.0;
            t.bary = sanitised_bary_f64(t.bary);
            remaining -= exit_time;
            stalled = if exit_time > distance * 1e-12 { 0 } else { stalled + 1 };
            let Some(next) = self.across(t.face, side) else {
                let end = WalkEnd::Boundary { face: t.face as u32, side: side as u8 };
                return t.finish(end, direction);
            };
            if !t.unfold_into(self, positions, side, next) {
                return t.finish(WalkEnd::Degenerate, direction);
            }
            if stalled > STALL_LIMIT {
                t.nudge_to_interior();
                stalled = 0;
            }
        }
        t.finish(WalkEnd::StepLimit, direction)
    }
}

impl Tracer {
    /// Projects the direction onto the current face and returns the
    /// barycentric velocity `β` of a unit step; `None` when the face has
    /// collapsed or the direction is normal to it.
    fn bary_velocity(&mut self, p: [DVec3; 3]) -> Option<[f64; 3]> {
        let area_vector = (p[1] - p[0]).cross(p[2] - p[0]);
        let twice_area = area_vector.length();
        if twice_area.is_nan() || twice_area <= 0.0 || !twice_area.is_finite() {
            return None;
        }
        let n = area_vector / twice_area;
        let tangential = self.direction - n * self.direction.dot(n);
        let length = tangential.length();
        // A direction within ~1e-9 rad of the normal carries no tangent information.
        if length.is_nan() || length <= 1e-9 * self.direction.length() || !length.is_finite() {
            return None;
        }
        let v = tangential / length;
        self.direction = v;
        let beta = std::array::from_fn(|k| (p[(k + 2) % 3] - p[(k + 1) % 3]).cross(v).dot(n) / twice_area);
        Some(beta)
    }

    fn advance(&mut self, beta: [f64; 3], time: f64) {
        for (b, db) in self.bary.iter_mut().zip(beta) {
            *b += db * time;
        }
        self.bary = sanitised_bary_f64(self.bary);
        self.travelled += time;
    }

    /// Carries the point and direction over side `side` into the face across
    /// it: the direction keeps its component along the shared edge and turns
    /// its across-edge component into the new face's plane (unfolding).
    fn unfold_into(&mut self, surface: &Surface, positions: &[Vec3], side: usize, next: FaceAcross) -> bool {
        let tri = surface.triangles[self.face];
        let (va, vc) = (tri[(side + 1) % 3], tri[(side + 2) % 3]);
        let pa = positions[va as usize].as_dvec3();
        let pc = positions[vc as usize].as_dvec3();
        let Some(edge) = (pc - pa).try_normalize() else { return false };
        let here_opposite = positions[tri[side] as usize].as_dvec3();
        let next_tri = surface.triangles[next.face as usize];
        let there_opposite = positions[next_tri[next.side as usize] as usize].as_dvec3();
        let outward = (pa - here_opposite).reject_from_normalized(edge).try_normalize();
        let inward = (there_opposite - pa).reject_from_normalized(edge).try_normalize();
        let (Some(outward), Some(inward)) = (outward, inward) else { return false };
        let along = self.direction.dot(edge);
        let across = self.direction.dot(outward).max(0.0);
        let (ba, bc) = (self.bary[(side + 1) % 3], self.bary[(side + 2) % 3]);
        let mut bary = [0.0; 3];
        for (k, &v) in next_tri.iter().enumerate() {
            if v == va {
                bary[k] = ba;
            } else if v == vc {
                bary[k] = bc;
            }
        }
        self.bary = sanitised_bary_f64(bary);
        self.direction = edge * along + inward * across;
        self.face = next.face as usize;
        self.crossed += 1;
        true
    }

    /// Moves the point a hair towards the face centroid (breaks a stall at a vertex).
    fn nudge_to_interior(&mut self) {
        let b = self.bary.map(|x| x * (1.0 - STALL_NUDGE) + STALL_NUDGE / 3.0);
        self.bary = sanitised_bary_f64(b);
    }

    fn finish(&self, end: WalkEnd, given_direction: Vec3) -> WalkResult {
        let direction =
            self.direction.as_vec3().try_normalize().or_else(|| given_direction.try_normalize()).unwrap_or(Vec3::ZERO);
        WalkResult {
            point: SurfacePoint { face: self.face as u32, bary: bary_to_f32(self.bary) },
            direction,
            travelled: self.travelled as f32,
            end,
            edges_crossed: self.crossed,
        }
    }
}

/// The time and side at which the path first reaches an edge (`∞` when it
/// never does, i.e. `β = 0`).
fn first_exit(bary: [f64; 3], beta: [f64; 3]) -> (f64, usize) {
    let mut best = (f64::INFINITY, 0);
    for k in 0..3 {
        if beta[k] < 0.0 {
            let t = bary[k] / -beta[k];
            if t < best.0 {
                best = (t, k);
            }
        }
    }
    best
}

fn sanitised_bary(b: [f32; 3]) -> [f64; 3] {
    sanitised_bary_f64(b.map(|x| x as f64))
}

/// Clamps to [0, ∞), renormalises to sum 1; the centroid when nothing is left.
fn sanitised_bary_f64(b: [f64; 3]) -> [f64; 3] {
    let c = b.map(|x| if x.is_finite() { x.max(0.0) } else { 0.0 });
    let sum = c[0] + c[1] + c[2];
    if sum > 0.0 && sum.is_finite() { c.map(|x| x / sum) } else { [1.0 / 3.0; 3] }
}

/// f32 barycentrics in [0, 1] that sum to 1 as nearly as f32 allows.
fn bary_to_f32(b: [f64; 3]) -> [f32; 3] {
    let mut out = b.map(|x| x as f32);
    let sum: f32 = out.iter().sum();
    if sum > 0.0 {
        out = out.map(|x| (x / sum).clamp(0.0, 1.0));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{MeshInput, weld};

    fn quad() -> (Surface, Vec<Vec3>) {
        let pos = [0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.];
        let mesh = weld(&MeshInput::new(&pos, &[0, 1, 2, 0, 2, 3])).unwrap();
        (Surface::new(&mesh), mesh.positions)
    }

    #[test]
    fn crosses_the_diagonal_and_stops_at_the_rim() {
        let (s, pos) = quad();
        let start = SurfacePoint { face: 0, bary: [0.6, 0.3, 0.1] }; // (0.4, 0.1)
        let r = s.walk(&pos, start, Vec3::Y, 0.5);
        assert_eq!(r.end, WalkEnd::Arrived);
        assert_eq!(r.point.face, 1);
        assert!((s.position(&pos, r.point) - Vec3::new(0.4, 0.6, 0.0)).length() < 1e-5);
        let r = s.walk(&pos, start, Vec3::Y, 5.0);
        assert!(r.hit_boundary());
        assert!((r.travelled - 0.9).abs() < 1e-5);
        assert!((s.position(&pos, r.point) - Vec3::new(0.4, 1.0, 0.0)).length() < 1e-5);
    }

    #[test]
    fn passes_exactly_through_a_vertex() {
        let (s, pos) = quad();
        // Along the diagonal from corner 0 through to corner 2 and beyond (boundary).
        let start = SurfacePoint { face: 0, bary: [1.0, 0.0, 0.0] };
        let r = s.walk(&pos, start, Vec3::new(1.0, 1.0, 0.0), 10.0);
        assert!(r.hit_boundary());
        assert!((s.position(&pos, r.point) - Vec3::new(1.0, 1.0, 0.0)).length() < 1e-4);
    }

    #[test]
    fn degenerate_inputs_stay_put() {
        let (s, pos) = quad();
        let start = SurfacePoint { face: 0, bary: [0.2, 0.3, 0.5] };
        assert_eq!(s.walk(&pos, start, Vec3::Z, 1.0).end, WalkEnd::Degenerate);
        assert_eq!(s.walk(&pos, start, Vec3::NAN, 1.0).end, WalkEnd::Degenerate);
        let r = s.walk(&pos, start, Vec3::X, f32::NAN);
        assert_eq!(r.end, WalkEnd::Arrived);
        assert_eq!(r.point.face, 0);
        assert!((s.position(&pos, r.point) - s.position(&pos, start)).length() < 1e-6);
    }
}
