//! Orientation-field-guided sampling (paper, Algorithm 1).
//!
//! From the current sample `p_i`: prune the pool around it, collect the
//! candidates `C_i` in the annulus `d_i < G ≤ 2 d_i`, turn the field
//! direction `õ_i` by `θ` (or, with probability `u0`, by a random angle),
//! `Walk` along it for `d_i`, and take the candidate nearest to where the
//! walk ended as the next sample. When `C_i` is empty, restart from a random
//! pool point; stop when the pool is empty.
//!
//! Two refinements, both needed for θ to show in the result (see
//! [`next_sample`]): the walk continues a square lattice turned by θ
//! (trying the other lattice directions when straight ahead is covered),
//! and it starts from the lattice site the previous walk reached (its
//! anchor) rather than from the pool point snapped to it, so the pool's
//! granularity does not accumulate along a run of samples.

use super::disk::DiskSampler;
use crate::field::Fields;
use crate::geometry::SurfacePoint;
use crate::rng::Rng;
use glam::Vec3;
use std::f32::consts::{FRAC_PI_2, TAU};

/// A lattice site is open when a candidate lies within this fraction of
/// `d_i` of it.
const OPEN_TARGET: f32 = 0.3;

/// Lattice sites are this many `d_i` apart.
const LATTICE_STRIDE: f32 = 1.15;

/// A restart joins the lattice of a placed sample within this many `d`.
const RESTART_REACH: f32 = 3.0;

/// Runs Algorithm 1 over the pool held by `disk`.
pub(crate) fn sample_guided(disk: &mut DiskSampler<'_>, fields: &Fields, theta: f32, randomness: f32, rng: &mut Rng) {
    let mut candidates = Vec::new();
    // Per pool slot: the lattice site a placed sample stands for.
    let mut anchors: Vec<Option<SurfacePoint>> = vec![None; disk.points.len()];
    let Some(mut current) = disk.random_alive(rng) else { return };
    // The lattice site `current` was snapped from; `None` after a jump.
    let mut anchor: Option<SurfacePoint> = None;
    loop {
        if disk.should_stop() {
            break;
        }
        if disk.conflicts(current) {
            disk.discard(current);
            match restart(disk, fields, &anchors, theta, rng) {
                Some(step) => {
                    (current, anchor) = step;
                    continue;
                }
                None => break,
            }
        }
        disk.place(current, &mut candidates);
        anchors[current as usize] = Some(anchor.unwrap_or_else(|| disk.points[current as usize].surface_point()));
        if disk.pool_is_empty() {
            break;
        }
        (current, anchor) = match next_sample(disk, fields, current, anchor, &candidates, theta, randomness, rng) {
            Some(step) => step,
            None => restart(disk, fields, &anchors, theta, rng).expect("the pool is not empty"),
        };
    }
}

/// Where to go on when `C_i` is empty: a random pool point (the paper's
/// `Random(1, |P|)`), moved onto the lattice of the nearest placed sample
/// when one of that sample's lattice sites near it is open, so that
/// regions reached again later keep the phase of their neighbours.
fn restart(
    disk: &DiskSampler<'_>,
    fields: &Fields,
    anchors: &[Option<SurfacePoint>],
    theta: f32,
    rng: &mut Rng,
) -> Option<(u32, Option<SurfacePoint>)> {
    let r = disk.random_alive(rng)?;
    let q = disk.points[r as usize];
    let Some(s) = disk.nearest_sample(q.position, q.normal, RESTART_REACH * q.spacing) else {
        return Some((r, None));
    };
    let p = disk.points[s as usize];
    let o = fields.direction_at(disk.surface, p.surface_point(), p.normal);
    let lattice = Lattice {
        disk,
        candidates: &[],
        from: anchors[s as usize].unwrap_or_else(|| p.surface_point()),
        o,
        b: p.normal.cross(o),
        angle: theta,
        stride: LATTICE_STRIDE * p.spacing,
    };
    let open = OPEN_TARGET * p.spacing;
    let mut best: Option<(f32, u32, SurfacePoint)> = None;
    for turns in [&[0u32][..], &[1], &[2], &[3], &[0, 1], &[1, 2], &[2, 3], &[3, 0]] {
        let (site, at) = lattice.walk_to(turns);
        let Some((_, k)) = disk.nearest_alive(site, open) else { continue };
        let from_r = (site - q.position).length();
        if best.is_none_or(|b| from_r < b.0) {
            best = Some((from_r, k, at));
        }
    }
    Some(best.map_or((r, None), |(_, k, at)| (k, Some(at))))
}

/// The next sample among the candidates `C_i` and the lattice position it
/// stands for (`None` when there are no candidates).
///
/// The paper's rule is the candidate nearest to the end of
/// `Walk(p_i, Rotate(õ_i, θ), d_i)`. Taken alone, it makes one row along the
/// turned direction and then zig-zags along the front of covered skin,
/// settling into the pockets of the previous row: a hexagonal packing in
/// which θ hardly shows. We read θ as turning a square lattice (θ = 0 gives
/// rows along the field, θ = π/4 the staggered layout) and continue that
/// lattice from the current anchor: the site straight ahead along θ first;
/// when it is covered (no candidate within `OPEN_TARGET · d_i` of it), the
/// sites turned by ±90° (the one with the nearer candidate), then 180°,
/// then the nearest open diagonal site. Sites are `LATTICE_STRIDE · d_i`
/// apart: at exactly `d_i` every site would sit on the exclusion circle of
/// its neighbours and the pool's granularity would push samples off the
/// lattice. When no site is open, the paper's rule decides and a new
/// lattice starts at the chosen sample.
#[allow(clippy::too_many_arguments)]
fn next_sample(
    disk: &DiskSampler<'_>,
    fields: &Fields,
    current: u32,
    anchor: Option<SurfacePoint>,
    candidates: &[u32],
    theta: f32,
    randomness: f32,
    rng: &mut Rng,
) -> Option<(u32, Option<SurfacePoint>)> {
    if candidates.is_empty() {
        return None;
    }
    let p = disk.points[current as usize];
    let o = fields.direction_at(disk.surface, p.surface_point(), p.normal);
    // Only if u > u0 is the preset θ used; otherwise a random angle.
    let angle = if rng.next_f32() < randomness { rng.next_f32() * TAU } else { theta };
    let lattice = Lattice {
        disk,
        candidates,
        from: anchor.unwrap_or_else(|| p.surface_point()),
        o,
        b: p.normal.cross(o),
        angle,
        stride: LATTICE_STRIDE * p.spacing,
    };
    let open = OPEN_TARGET * p.spacing;
    let is_open = |site: &Site| site.distance <= open;
    let ahead = lattice.site(&[0]);
    if is_open(&ahead) {
        return Some(ahead.into_step());
    }
    let side = nearer(lattice.site(&[1]), lattice.site(&[3]));
    if is_open(&side) {
        return Some(side.into_step());
    }
    let back = lattice.site(&[2]);
    if is_open(&back) {
        return Some(back.into_step());
    }
    let diagonal = (0..4).map(|k| lattice.site(&[k, (k + 1) % 4])).reduce(nearer).expect("four diagonals");
    if is_open(&diagonal) {
        return Some(diagonal.into_step());
    }
    // The paper's rule: the candidate nearest to the walk along θ.
    Some((ahead.candidate, None))
}

/// A square lattice turned by `angle` from `õ`, with its current site at `from`.
struct Lattice<'s, 'a> {
    disk: &'s DiskSampler<'a>,
    candidates: &'s [u32],
    from: SurfacePoint,
    o: Vec3,
    b: Vec3,
    angle: f32,
    stride: f32,
}

/// A lattice site and the candidate nearest to it.
struct Site {
    point: SurfacePoint,
    candidate: u32,
    distance: f32,
}

impl Site {
    fn into_step(self) -> (u32, Option<SurfacePoint>) {
        (self.candidate, Some(self.point))
    }
}

fn nearer(a: Site, b: Site) -> Site {
    if b.distance < a.distance { b } else { a }
}

impl Lattice<'_, '_> {
    /// The site reached by walking one stride per entry of `quarter_turns`,
    /// each along `Rotate(õ, angle + k·90°)` (counterclockwise about the
    /// normal; `b = n × õ`): its position and surface point.
    fn walk_to(&self, quarter_turns: &[u32]) -> (Vec3, SurfacePoint) {
        let surface = self.disk.surface;
        let mut at = self.from;
        for &k in quarter_turns {
            let (sin, cos) = (self.angle + k as f32 * FRAC_PI_2).sin_cos();
            at = surface.walk(self.disk.positions, at, self.o * cos + self.b * sin, self.stride).point;
        }
        (surface.position(self.disk.positions, at), at)
    }

    /// The site reached by `quarter_turns` (see [`Lattice::walk_to`]) and
    /// the candidate nearest to it.
    fn site(&self, quarter_turns: &[u32]) -> Site {
        let (target, at) = self.walk_to(quarter_turns);
        let (distance, candidate) = nearest_candidate(self.disk, self.candidates, target);
        Site { point: at, candidate, distance }
    }
}

/// The candidate nearest to `target` (3-D distance; first in order on
/// ties), and its distance.
fn nearest_candidate(disk: &DiskSampler<'_>, candidates: &[u32], target: Vec3) -> (f32, u32) {
    let mut best = (f32::INFINITY, candidates[0]);
    for &k in candidates {
        let d2 = (disk.points[k as usize].position - target).length_squared();
        if d2 < best.0 {
            best = (d2, k);
        }
    }
    debug_assert!(disk.is_alive(best.1));
    (best.0.sqrt(), best.1)
}
