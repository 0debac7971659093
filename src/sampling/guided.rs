//! Orientation-field-guided sampling (paper, Algorithm 1).
//!
//! From the current sample `p_i`: prune the pool around it, collect the
//! candidates `C_i` in the annulus `d_i < G ≤ 2 d_i`, turn the field
//! direction `õ_i` by `θ` (or, with probability `u0`, by a random angle),
//! `Walk` from `p_i` along it for `d_i`, and take the candidate nearest to
//! where the walk ended as the next sample. When `C_i` is empty, restart
//! from a random pool point; stop when the pool is empty.

use super::pool::DiskSampler;
use crate::field::Fields;
use crate::rng::Rng;
use std::f32::consts::TAU;

/// Runs Algorithm 1 over the pool held by `disk`.
pub(crate) fn sample_guided(disk: &mut DiskSampler<'_>, fields: &Fields, theta: f32, randomness: f32, rng: &mut Rng) {
    let mut candidates = Vec::new();
    let Some(mut current) = disk.random_alive(rng) else { return };
    loop {
        if disk.conflicts(current) {
            disk.discard(current);
            match disk.random_alive(rng) {
                Some(next) => {
                    current = next;
                    continue;
                }
                None => break,
            }
        }
        disk.place(current, &mut candidates);
        if disk.pool_is_empty() {
            break;
        }
        current = match nearest_to_walk_end(disk, fields, current, &candidates, theta, randomness, rng) {
            Some(next) => next,
            None => disk.random_alive(rng).expect("the pool is not empty"),
        };
    }
}

/// The candidate (`C_i`) nearest to the end of `Walk(p_i, Rotate(õ_i, θ), d_i)`;
/// `None` when `C_i` is empty.
fn nearest_to_walk_end(
    disk: &DiskSampler<'_>,
    fields: &Fields,
    current: u32,
    candidates: &[u32],
    theta: f32,
    randomness: f32,
    rng: &mut Rng,
) -> Option<u32> {
    if candidates.is_empty() {
        return None;
    }
    let p = disk.points[current as usize];
    let here = p.surface_point();
    let o = fields.direction_at(disk.surface, here, p.normal);
    // Only if u > u0 is the preset θ used; otherwise a random angle.
    let angle = if rng.next_f32() < randomness { rng.next_f32() * TAU } else { theta };
    let (sin, cos) = angle.sin_cos();
    // Rotate(õ_i, θ): counterclockwise about n_i; n × õ is the binormal b_i.
    let direction = o * cos + p.normal.cross(o) * sin;
    let walked = disk.surface.walk(disk.positions, here, direction, p.spacing);
    let target = disk.surface.position(disk.positions, walked.point);
    let mut best = (f32::INFINITY, candidates[0]);
    for &k in candidates {
        let d2 = (disk.points[k as usize].position - target).length_squared();
        if d2 < best.0 {
            best = (d2, k);
        }
    }
    debug_assert!(disk.is_alive(best.1));
    Some(best.1)
}
