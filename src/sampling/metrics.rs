//! Sampling quality figures (DESIGN.md §2).
//!
//! "Same side" means the two points' interpolated normals are less than 90°
//! apart (`n_a · n_b > 0`); it keeps the two skins of a thin part apart.
//! Coverage is measured with the sampler's `G` (see `surface::geodesic`):
//! a root across a limb thinner than `d` covers the far side of the limb,
//! a root on the other skin of a thin plate does not.

use super::grid::StaticGrid;
use crate::field::Fields;
use crate::geometry::{RootFrame, SurfacePoint};
use crate::interior::{BuriedSkin, FaceBurial};
use crate::progress::{Phase, Progress};
use crate::rng::hash64;
use crate::roots::{RootBinding, RootNormal, pose_roots};
use crate::surface::{NearbyPatch, Surface};
use glam::Vec3;
use rayon::prelude::*;

/// `relative_radius` reports at most this (no same-side root within `2 d_i`).
const RADIUS_CAP: f32 = 2.0;
/// `coverage_gap` reports at most this (no same-side root within `4 d`).
const GAP_CAP: f32 = 4.0;
/// First (cheap) search radius for a probe's nearest root (× local `d`).
const GAP_FIRST_REACH: f32 = 1.5;
/// Neighbours used by `alignment`, and how far they are looked for (× `d_i`).
const ALIGNMENT_NEIGHBOURS: usize = 4;
const ALIGNMENT_REACH: f32 = 3.0;
/// Probe spacing as a fraction of the local `d` (one probe per `step²` of area).
const PROBE_STEP: f32 = 0.5;
/// Most probes on one face.
const MAX_PROBES_PER_FACE: usize = 1 << 16;
/// Faces whose circumscribing radius is below this many `d` share one root
/// list between their probes.
const SHARED_LIST_RADIUS: f32 = 3.0;

/// Quality of a root distribution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplingMetrics {
    /// Min over roots of (3-D distance to the nearest other same-side root)
    /// / `d_i`; capped at 2 (also the value with fewer than two roots).
    /// Poisson-disk sampling gives ≥ 1.
    pub relative_radius: f32,
    /// Max over surface probes (about one per `(d/2)²` of area, spread by a
    /// low-discrepancy sequence) of (`G` to the nearest root)
    /// / local `d`; capped at 4. 0 when nothing is feathered.
    pub coverage_gap: f32,
    /// Mean over roots and their 4 nearest same-side neighbours of
    /// `cos 4(φ − θ)`, `φ` the neighbour's angle in the root's tangent frame
    /// from `õ_i`: 1 for a square lattice turned by `θ`, about 0 for random
    /// points.
    pub alignment: f32,
    /// Number of feathered probes used for `coverage_gap`.
    pub probes: usize,
}

#[inline]
fn same_side(a: Vec3, b: Vec3) -> bool {
    a.dot(b) > 0.0
}

/// What the roots were planted for: the global spacing `d` they were
/// sampled with and the stagger angle `theta` the alignment is measured
/// against.
#[derive(Clone, Copy, Debug)]
pub struct PlantedFor {
    /// The global spacing `d`.
    pub spacing: f32,
    /// The stagger angle, radians.
    pub theta: f32,
}

/// Computes the figures for `roots` on `surface` at the pose `positions`
/// (normally the rest pose), polling `progress` (stopped, the figures are
/// partial and the caller's next check fails).
pub fn sampling_metrics(
    surface: &Surface,
    positions: &[Vec3],
    fields: &Fields,
    buried: &BuriedSkin,
    roots: &[RootBinding],
    PlantedFor { spacing, theta }: PlantedFor,
    progress: &Progress,
) -> SamplingMetrics {
    let mut normals = Vec::new();
    surface.vertex_normals(positions, &mut normals);
    let mut frames = Vec::new();
    pose_roots(roots, positions, surface.triangles(), &normals, RootNormal::Smooth, &mut frames);
    // Cells of 1.5 d: a query of radius 3 d reads about 5 cells a side.
    let cell = 1.5 * spacing.max(f32::MIN_POSITIVE) * fields.median_spacing_scale();
    let grid = StaticGrid::new(&frames.iter().map(|f| f.position).collect::<Vec<_>>(), cell);

    // Polled per root and per face: once stopped, the rest give nothing and
    // the caller's next check fails (the figures are dropped).
    let per_root: Vec<(f32, f64, u32)> = (0..roots.len())
        .into_par_iter()
        .map(|i| {
            if progress.poll(Phase::Sampling, 0.97, i) {
                root_figures(&grid, &frames, roots, i, theta)
            } else {
                (RADIUS_CAP, 0.0, 0)
            }
        })
        .collect();
    let relative_radius = per_root.iter().map(|r| r.0).fold(RADIUS_CAP, f32::min);
    let (sum, count) = per_root.iter().fold((0.0f64, 0u64), |(s, c), r| (s + r.1, c + r.2 as u64));
    let alignment = if count > 0 { (sum / count as f64) as f32 } else { 0.0 };

    let coverage = CoverageContext {
        surface,
        positions,
        normals: &normals,
        fields,
        buried,
        grid: &grid,
        frames: &frames,
        roots,
        spacing,
    };
    let per_face: Vec<(f32, usize)> = (0..surface.face_count())
        .into_par_iter()
        .map_init(
            || (NearbyPatch::new(surface), Vec::new()),
            |(patch, near), f| {
                if progress.poll(Phase::Sampling, 0.98, f) { coverage.face(patch, near, f) } else { (0.0, 0) }
            },
        )
        .collect();
    let coverage_gap = per_face.iter().map(|r| r.0).fold(0.0, f32::max);
    let probes = per_face.iter().map(|r| r.1).sum();
    SamplingMetrics { relative_radius, coverage_gap, alignment, probes }
}

/// For root `i`: (distance to the nearest other same-side root) / `d_i`
/// (capped), and the sum of `cos 4(φ − θ)` over its nearest same-side
/// neighbours with their count.
fn root_figures(
    grid: &StaticGrid,
    frames: &[RootFrame],
    roots: &[RootBinding],
    i: usize,
    theta: f32,
) -> (f32, f64, u32) {
    let me = &frames[i];
    let d = roots[i].spacing;
    let mut near: Vec<(f32, u32)> = Vec::new();
    grid.for_each_within(me.position, ALIGNMENT_REACH.max(RADIUS_CAP) * d, |j, d2| {
        if j as usize != i && same_side(me.normal, frames[j as usize].normal) {
            near.push((d2, j));
        }
    });
    near.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let ratio = near.first().map_or(RADIUS_CAP, |n| (n.0.sqrt() / d).min(RADIUS_CAP));
    let mut sum = 0.0f64;
    let mut count = 0;
    for &(d2, j) in near.iter().take(ALIGNMENT_NEIGHBOURS) {
        let local = me.to_local(frames[j as usize].position);
        if d2 > (ALIGNMENT_REACH * d).powi(2) || (local.x == 0.0 && local.y == 0.0) {
            continue;
        }
        let phi = local.y.atan2(local.x);
        sum += (4.0 * (phi - theta)).cos() as f64;
        count += 1;
    }
    (ratio, sum, count)
}

/// Barycentrics of probe `i` of face `f`: the R2 low-discrepancy sequence
/// (Roberts), offset per face, folded into the triangle. Deterministic.
fn probe_bary(f: usize, i: usize) -> [f32; 3] {
    const A1: f64 = 0.754_877_666_246_692_7; // 1/φ₂, φ₂ the plastic number
    const A2: f64 = 0.569_840_290_998_053_3; // 1/φ₂²
    let offset = (hash64(&[f as u64]) >> 11) as f64 / (1u64 << 53) as f64;
    let n = i as f64 + 1.0;
    let (mut u, mut v) = ((offset + n * A1).fract() as f32, (0.5 + offset + n * A2).fract() as f32);
    if u + v > 1.0 {
        (u, v) = (1.0 - u, 1.0 - v);
    }
    [1.0 - u - v, u, v]
}

/// What the coverage probes read.
struct CoverageContext<'a> {
    surface: &'a Surface,
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    fields: &'a Fields,
    buried: &'a BuriedSkin,
    grid: &'a StaticGrid,
    frames: &'a [RootFrame],
    roots: &'a [RootBinding],
    spacing: f32,
}

impl CoverageContext<'_> {
    /// Worst coverage ratio over the probes of face `f`, and the probe count.
    fn face(&self, patch: &mut NearbyPatch, near: &mut Vec<u32>, f: usize) -> (f32, usize) {
        let scales = self.fields.vertex_spacing_scales();
        let tri = self.surface.triangles()[f];
        let feathered = tri.iter().map(|&v| scales[v as usize]).filter(|&s| s > 0.0);
        let Some((min_scale, max_scale)) = feathered
            .fold(None, |acc: Option<(f32, f32)>, s| Some(acc.map_or((s, s), |(lo, hi)| (lo.min(s), hi.max(s)))))
        else {
            return (0.0, 0);
        };
        if self.buried.face(f) == FaceBurial::Buried {
            return (0.0, 0);
        }
        let corners = self.surface.corners(self.positions, f);
        let [a, b, c] = corners;
        let area = 0.5 * (b - a).cross(c - a).length();
        let step = PROBE_STEP * self.spacing * min_scale;
        let count = ((area / (step * step)).ceil() as usize).clamp(1, MAX_PROBES_PER_FACE);
        // Small faces: every root within GAP_FIRST_REACH · d of any probe of
        // the face, gathered once; large faces: one grid query per probe.
        let centroid = (a + b + c) / 3.0;
        let face_radius = corners.iter().map(|&p| (p - centroid).length()).fold(0.0, f32::max);
        let max_d = self.spacing * max_scale;
        let shared_list = face_radius <= SHARED_LIST_RADIUS * max_d;
        if shared_list {
            near.clear();
            self.grid.for_each_within(centroid, face_radius + GAP_FIRST_REACH * max_d, |k, _| near.push(k));
        }
        let (mut worst, mut probes) = (0.0f32, 0usize);
        for i in 0..count {
            let point = SurfacePoint { face: f as u32, bary: probe_bary(f, i) };
            let Some(scale) = self.fields.spacing_scale_at(self.surface, point) else { continue };
            if self.buried.face(f) == FaceBurial::Crossed {
                let normal = self.surface.interpolated_normal(self.positions, self.normals, point);
                if self.buried.holds(f, self.surface.position(self.positions, point), normal) {
                    continue;
                }
            }
            let local_d = self.spacing * scale;
            let mut nearest = f32::INFINITY;
            for reach in [GAP_FIRST_REACH, GAP_CAP] {
                if reach == GAP_FIRST_REACH && shared_list {
                    nearest = self.nearest_root(patch, point, reach * local_d, near.iter().copied());
                } else {
                    let here = self.surface.position(self.positions, point);
                    let mut found = Vec::new();
                    self.grid.for_each_within(here, reach * local_d, |k, _| found.push(k));
                    nearest = self.nearest_root(patch, point, reach * local_d, found.into_iter());
                }
                if nearest.is_finite() {
                    break;
                }
            }
            worst = worst.max((nearest / local_d).min(GAP_CAP));
            probes += 1;
        }
        (worst, probes)
    }

    /// `G` from the probe at `point` to the nearest of `roots` within
    /// `reach` (`+∞` when none). Roots facing the same way count at their
    /// chord; the others through the surface patch around the probe, so a
    /// root across a thin limb covers it and one on the other skin of a
    /// thin plate does not.
    fn nearest_root(
        &self,
        patch: &mut NearbyPatch,
        point: SurfacePoint,
        reach: f32,
        roots: impl Iterator<Item = u32>,
    ) -> f32 {
        let here = self.surface.position(self.positions, point);
        let normal = self.surface.interpolated_normal(self.positions, self.normals, point);
        let mut best = f32::INFINITY;
        let mut facing_away: Vec<(f32, u32)> = Vec::new();
        for k in roots {
            let root = &self.frames[k as usize];
            let chord = (root.position - here).length();
            if chord > reach {
                continue;
            }
            if same_side(normal, root.normal) {
                best = best.min(chord);
            } else {
                facing_away.push((chord, k));
            }
        }
        if facing_away.iter().any(|&(chord, _)| chord < best) {
            patch.gather(self.surface, self.positions, point.face, here, normal, reach);
            for &(_, k) in &facing_away {
                let root = &self.frames[k as usize];
                best = best.min(patch.geodesic_to(root.position, root.normal, self.roots[k as usize].point.face));
            }
        }
        if best <= reach { best } else { f32::INFINITY }
    }
}
