//! The coverage figure (DESIGN.md §6): how much of the feathered, visible
//! skin has a feather over it.
//!
//! Probes are area-weighted random points of the skin. Two kinds of skin
//! are left out, because no collision-free coat could cover them:
//! - **bare skin**, where the caller's spacing multiplier is 0 (the same
//!   rule as root sampling: a point is bare where its bare corners weigh
//!   more than ½);
//! - **skin buried inside the body**, where the mesh passes through itself
//!   (see [`crate::interior`]). A feather covering such a probe would have
//!   to lie inside the body.

use crate::body::BodyIndex;
use crate::interior::BodyInterior;
use crate::progress::{Phase, Progress};
use crate::rng::Rng;
use crate::triangle_grid::{TriangleGrid, ray_triangle};
use glam::Vec3;
use rayon::prelude::*;

/// The skin the coverage probes are drawn from.
#[derive(Clone, Copy, Debug)]
pub struct ProbeSkin<'a> {
    /// Vertex positions at the pose being validated.
    pub positions: &'a [Vec3],
    /// Triangles (indices into `positions`).
    pub triangles: &'a [[u32; 3]],
    /// Per vertex: whether it carries feathers. Empty means every vertex does.
    pub feathered: &'a [bool],
}

impl<'a> ProbeSkin<'a> {
    /// A skin feathered everywhere.
    pub fn whole(positions: &'a [Vec3], triangles: &'a [[u32; 3]]) -> Self {
        Self { positions, triangles, feathered: &[] }
    }

    fn is_feathered(&self, v: u32) -> bool {
        self.feathered.is_empty() || self.feathered[v as usize]
    }

    /// The feathered share of the point with barycentric weights `w` on
    /// triangle `tri`: the weight of its feathered corners.
    fn presence(&self, tri: [u32; 3], w: [f32; 3]) -> f32 {
        (0..3).filter(|&k| self.is_feathered(tri[k])).map(|k| w[k]).sum()
    }
}

/// A probe: a point of the skin and its unit normal.
pub type Probe = (Vec3, Vec3);

/// What the coverage figure counted.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CoverageCount {
    /// Probes on the feathered, visible skin.
    pub probes: usize,
    /// Of those, probes whose normal ray meets a feather within the reach.
    pub covered: usize,
    /// Probes drawn on the feathered skin but buried inside the body.
    pub buried: usize,
}

impl CoverageCount {
    /// `covered / probes` (0 without probes).
    pub fn fraction(&self) -> f64 {
        if self.probes == 0 { 0.0 } else { self.covered as f64 / self.probes as f64 }
    }
}

/// Draws `count` probes on the feathered skin with `seed`, leaves out those
/// buried inside `body` and counts those whose normal ray meets a triangle
/// of `feathers` within `reach`. Polls `progress` per probe: once it says
/// stop, the remaining probes are skipped (the caller's next check fails).
pub fn count_covered(
    feathers: &TriangleGrid,
    reach: f32,
    skin: &ProbeSkin<'_>,
    body: &BodyIndex,
    count: usize,
    seed: u64,
    progress: &Progress,
) -> CoverageCount {
    let drawn = surface_probes(skin, count, seed);
    let interior = BodyInterior::new(body);
    let outcome: Vec<(bool, bool)> = drawn
        .par_iter()
        .enumerate()
        .map(|(i, &(p, n))| {
            if !progress.poll(Phase::Validating, 0.2, i) {
                (false, false)
            } else if interior.holds(p, n) {
                (true, false)
            } else {
                (false, feathers.ray_cast(p, n, reach, |t| ray_triangle(p, n, feathers.corners(t))).is_some())
            }
        })
        .collect();
    let buried = outcome.iter().filter(|o| o.0).count();
    CoverageCount { probes: drawn.len() - buried, covered: outcome.iter().filter(|o| o.1).count(), buried }
}

/// Up to `count` area-weighted random points of the feathered skin with
/// their interpolated unit normals (the area-weighted vertex normals): the
/// points are drawn on the triangles with a feathered corner and the bare
/// ones are dropped, so fewer than `count` come back where the skin is
/// partly bare.
pub fn surface_probes(skin: &ProbeSkin<'_>, count: usize, seed: u64) -> Vec<Probe> {
    let (positions, triangles) = (skin.positions, skin.triangles);
    let mut normals = vec![Vec3::ZERO; positions.len()];
    let mut cumulative = Vec::with_capacity(triangles.len());
    let mut total = 0.0f64;
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let area2 = (b - a).cross(c - a);
        for &v in t {
            normals[v as usize] += area2;
        }
        if t.iter().any(|&v| skin.is_feathered(v)) {
            total += 0.5 * area2.length() as f64;
        }
        cumulative.push(total);
    }
    if total <= 0.0 || total.is_nan() {
        return Vec::new();
    }
    let mut rng = Rng::new(seed);
    (0..count)
        .filter_map(|_| {
            let target = rng.next_f64() * total;
            let t = cumulative.partition_point(|&c| c <= target).min(triangles.len() - 1);
            let (r1, r2) = (rng.next_f32().sqrt(), rng.next_f32());
            let w = [1.0 - r1, r1 * (1.0 - r2), r1 * r2];
            let tri = triangles[t];
            if skin.presence(tri, w) < 0.5 {
                return None;
            }
            let p = (0..3).map(|k| positions[tri[k] as usize] * w[k]).sum::<Vec3>();
            let [a, b, c] = tri.map(|v| positions[v as usize]);
            let face = (b - a).cross(c - a).normalize_or_zero();
            let n = (0..3).map(|k| normals[tri[k] as usize].normalize_or_zero() * w[k]).sum::<Vec3>();
            Some((p, n.try_normalize().unwrap_or(face)))
        })
        .collect()
}

/// Whether the probe `p` (unit normal `n`) lies inside `body` (see
/// [`BodyInterior::holds`]).
pub fn is_buried(body: &BodyIndex, p: Vec3, n: Vec3) -> bool {
    BodyInterior::new(body).holds(p, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn probes_lie_on_the_mesh_with_its_normal() {
        let pos = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let probes = surface_probes(&ProbeSkin::whole(&pos, &[[0, 1, 2], [0, 2, 3]]), 100, 5);
        assert_eq!(probes.len(), 100);
        for (p, n) in probes {
            assert!(p.z.abs() < 1e-6 && (0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.y));
            assert!((n - Vec3::Z).length() < 1e-5);
        }
    }

    #[test]
    fn bare_skin_gets_no_probes() {
        // Two squares side by side; the right one's far corners are bare.
        let pos =
            [0.0, 1.0, 2.0].iter().flat_map(|&x| [Vec3::new(x, 0.0, 0.0), Vec3::new(x, 1.0, 0.0)]).collect::<Vec<_>>();
        let tris = [[0, 2, 3], [0, 3, 1], [2, 4, 5], [2, 5, 3]];
        let feathered = [true, true, true, true, false, false];
        let probes = surface_probes(&ProbeSkin { positions: &pos, triangles: &tris, feathered: &feathered }, 4000, 9);
        assert!(probes.iter().all(|(p, _)| p.x <= 1.5 + 1e-5), "a probe on the bare half");
        // The feathered square and the half of the next one nearest to it.
        let share = probes.len() as f64 / 4000.0;
        assert!((share - 0.75).abs() < 0.03, "{share}");
    }
}
