//! Sampling quality figures (DESIGN.md §2).
//!
//! "Same side" means the two points' interpolated normals are less than 90°
//! apart (`n_a · n_b > 0`). This is deliberately simpler than, and
//! independent of, the `G` used while sampling, so the figures check the
//! sampler rather than restate it; it keeps the two skins of a thin part
//! apart.

use super::grid::StaticGrid;
use crate::field::Fields;
use crate::geometry::{RootFrame, SurfacePoint};
use crate::roots::{RootBinding, pose_roots};
use crate::surface::Surface;
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
/// Probe spacing as a fraction of the local `d`.
const PROBE_STEP: f32 = 0.5;
/// Most subdivisions of one face edge for probes.
const MAX_PROBE_SUBDIVISIONS: usize = 64;

/// Quality of a root distribution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SamplingMetrics {
    /// Min over roots of (3-D distance to the nearest other same-side root)
    /// / `d_i`; capped at 2 (also the value with fewer than two roots).
    /// Poisson-disk sampling gives ≥ 1.
    pub relative_radius: f32,
    /// Max over surface probes (spaced `d/2`) of (distance to the nearest
    /// same-side root) / local `d`; capped at 4. 0 when nothing is feathered.
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

/// Computes the figures for `roots` on `surface` at the pose `positions`
/// (normally the rest pose). `spacing` is the global `d` the roots were
/// sampled with and `theta` the stagger angle the alignment is measured
/// against.
pub fn sampling_metrics(
    surface: &Surface,
    positions: &[Vec3],
    fields: &Fields,
    roots: &[RootBinding],
    spacing: f32,
    theta: f32,
) -> SamplingMetrics {
    let mut normals = Vec::new();
    surface.vertex_normals(positions, &mut normals);
    let mut frames = Vec::new();
    pose_roots(roots, positions, surface.triangles(), &normals, &mut frames);
    let cell = 2.0 * spacing.max(f32::MIN_POSITIVE) * fields.median_spacing_scale();
    let grid = StaticGrid::new(frames.iter().map(|f| f.position).collect(), cell);

    let per_root: Vec<(f32, f64, u32)> = (0..roots.len())
        .into_par_iter()
        .map(|i| {
            let nearest = nearest_ratio(&grid, &frames, roots, i);
            let (sum, count) = alignment_of(&grid, &frames, roots, i, theta);
            (nearest, sum, count)
        })
        .collect();
    let relative_radius = per_root.iter().map(|r| r.0).fold(RADIUS_CAP, f32::min);
    let (sum, count) = per_root.iter().fold((0.0f64, 0u64), |(s, c), r| (s + r.1, c + r.2 as u64));
    let alignment = if count > 0 { (sum / count as f64) as f32 } else { 0.0 };

    let per_face: Vec<(f32, usize)> = (0..surface.face_count())
        .into_par_iter()
        .map(|f| face_coverage(surface, positions, &normals, fields, &grid, &frames, spacing, f))
        .collect();
    let coverage_gap = per_face.iter().map(|r| r.0).fold(0.0, f32::max);
    let probes = per_face.iter().map(|r| r.1).sum();
    SamplingMetrics { relative_radius, coverage_gap, alignment, probes }
}

/// (distance to the nearest other same-side root) / `d_i`, capped.
fn nearest_ratio(grid: &StaticGrid, frames: &[RootFrame], roots: &[RootBinding], i: usize) -> f32 {
    let (me, d) = (&frames[i], roots[i].spacing);
    let mut best = f32::INFINITY;
    grid.for_each_within(me.position, RADIUS_CAP * d, |j, d2| {
        if j as usize != i && same_side(me.normal, frames[j as usize].normal) {
            best = best.min(d2);
        }
    });
    (best.sqrt() / d).min(RADIUS_CAP)
}

/// Sum of `cos 4(φ − θ)` over the root's nearest same-side neighbours, and their count.
fn alignment_of(grid: &StaticGrid, frames: &[RootFrame], roots: &[RootBinding], i: usize, theta: f32) -> (f64, u32) {
    let me = &frames[i];
    let mut near: Vec<(f32, u32)> = Vec::new();
    grid.for_each_within(me.position, ALIGNMENT_REACH * roots[i].spacing, |j, d2| {
        if j as usize != i && same_side(me.normal, frames[j as usize].normal) {
            near.push((d2, j));
        }
    });
    near.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut sum = 0.0f64;
    let mut count = 0;
    for &(_, j) in near.iter().take(ALIGNMENT_NEIGHBOURS) {
        let local = me.to_local(frames[j as usize].position);
        if local.x == 0.0 && local.y == 0.0 {
            continue;
        }
        let phi = local.y.atan2(local.x);
        sum += (4.0 * (phi - theta)).cos() as f64;
        count += 1;
    }
    (sum, count)
}

/// Worst coverage ratio over the probes of face `f`, and the probe count.
#[allow(clippy::too_many_arguments)]
fn face_coverage(
    surface: &Surface,
    positions: &[Vec3],
    normals: &[Vec3],
    fields: &Fields,
    grid: &StaticGrid,
    frames: &[RootFrame],
    spacing: f32,
    f: usize,
) -> (f32, usize) {
    let scales = fields.vertex_spacing_scales();
    let tri = surface.triangles()[f];
    let Some(min_scale) = tri.iter().map(|&v| scales[v as usize]).filter(|&s| s > 0.0).reduce(f32::min) else {
        return (0.0, 0);
    };
    let [a, b, c] = surface.corners(positions, f);
    let longest = (b - a).length().max((c - b).length()).max((a - c).length());
    let step = PROBE_STEP * spacing * min_scale;
    let m = ((longest / step).ceil() as usize).clamp(1, MAX_PROBE_SUBDIVISIONS);
    let (mut worst, mut probes) = (0.0f32, 0usize);
    for i in 0..=m {
        for j in 0..=(m - i) {
            let bary = [(m - i - j) as f32 / m as f32, i as f32 / m as f32, j as f32 / m as f32];
            let point = SurfacePoint { face: f as u32, bary };
            let Some(scale) = fields.spacing_scale_at(surface, point) else { continue };
            let local_d = spacing * scale;
            let here = surface.position(positions, point);
            let normal = surface.interpolated_normal(positions, normals, point);
            let mut best = f32::INFINITY;
            // A near search first; the far one only where it finds nothing.
            for reach in [GAP_FIRST_REACH, GAP_CAP] {
                grid.for_each_within(here, reach * local_d, |k, d2| {
                    if same_side(normal, frames[k as usize].normal) {
                        best = best.min(d2);
                    }
                });
                if best.is_finite() {
                    break;
                }
            }
            worst = worst.max((best.sqrt() / local_d).min(GAP_CAP));
            probes += 1;
        }
    }
    (worst, probes)
}
