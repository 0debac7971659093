//! Exact checks of a feather coat, independent of the height field
//! (DESIGN.md §6). Everything runs in parallel with rayon and gives the same
//! answer for any thread count: pairs and indices come out sorted, counts
//! are integers and sums run in index order.

mod audit;
mod coverage;
mod exact;
mod groom;
mod lie;

pub use audit::{CheckAudit, audit_checks};
pub use coverage::{CoverageCount, Probe, ProbeSkin, count_covered, is_buried, surface_probes};
pub(crate) use exact::{BodyScratch, BoxedTriangles, FeatherBoxes, ROOT_ALLOWANCE};
pub use exact::{body_penetrations, feather_beyond_root};
pub use groom::{Groom, field_singularities, groom};
// Only the adjustment's tests use the plane directly.
#[cfg(test)]
pub(crate) use exact::FlatPlane;
pub use lie::{
    BRISTLE_TIP_HEIGHT, OwnedTriangles, TipHeights, TipLie, TipStacks, summarise_tip_heights, summarise_tip_stacks,
    tip_heights, tip_lies,
};

pub use crate::intersect::{triangles_intersect, triangles_intersect_f64};

use crate::body::BodyIndex;
use crate::error::Result;
use crate::feather::{FeatherPose, FeatherShape, FeatherTriangles};
use crate::geometry::RootFrame;
use crate::progress::{Phase, Progress};
use crate::triangle_grid::TriangleGrid;
use rayon::prelude::*;

/// The figures of one validation.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Validation {
    /// Pairs `(i, j)`, `i < j`, of feathers whose triangles intersect, sorted.
    pub intersecting_pairs: Vec<(u32, u32)>,
    /// Feathers crossing the body more than 5 % of their length from the root, sorted.
    pub body_penetrations: Vec<u32>,
    /// Fraction of the probes of the feathered, visible skin whose normal
    /// ray meets a feather within the longest feather length.
    pub coverage: f64,
    /// Probes behind `coverage`: those drawn on the feathered skin, less
    /// the ones buried inside the body.
    pub probes: usize,
    /// Probes drawn on the feathered skin but buried inside the body (where
    /// the mesh passes through itself), left out of `coverage`.
    pub buried_probes: usize,
    /// Mean pitch, degrees.
    pub mean_pitch_deg: f64,
    /// How far the tips stand off the skin (see [`tip_heights`]).
    pub tip_heights: TipHeights,
    /// How the tips lie on the feathers stacked beneath them (see
    /// [`tip_lies`]).
    pub tip_stacks: TipStacks,
    /// Whether the feathers run the way their neighbours run (see [`groom`]).
    pub groom: Groom,
}

/// What a validation looks at: every feather at one pose, the body at that
/// pose and the skin the coverage probes are drawn on.
#[derive(Clone, Copy)]
pub struct ValidationInput<'a> {
    /// `feather_triangles[i]` are feather i's triangles at `poses[i]` (as
    /// [`crate::feather::feather_triangles`] gives them).
    pub feather_triangles: &'a [FeatherTriangles],
    /// Each feather's root frame.
    pub frames: &'a [RootFrame],
    /// Each feather's dimensions.
    pub shapes: &'a [FeatherShape],
    /// Each feather's pose.
    pub poses: &'a [FeatherPose],
    /// The body at the same pose.
    pub body: &'a BodyIndex,
    /// Where the coverage probes are drawn, usually the body's skin.
    pub skin: &'a ProbeSkin<'a>,
    /// How many probe points are drawn.
    pub probes: usize,
    /// The seed of the probe points.
    pub seed: u64,
}

/// Runs every check on `input`.
pub fn validate(input: &ValidationInput<'_>) -> Validation {
    validate_with_progress(input, &Progress::none()).expect("validation without a progress sink is never interrupted")
}

/// As [`validate`], reporting `Phase::Validating` to `progress` between its
/// stages (the grid, coverage, pairs, penetrations, tip heights and
/// stacks); stopped,
/// it returns `Interrupted` (validation changes nothing).
pub fn validate_with_progress(input: &ValidationInput<'_>, progress: &Progress) -> Result<Validation> {
    let ValidationInput { feather_triangles, frames, shapes, poses, body, skin, probes, seed } = *input;
    progress.check(Phase::Validating, 0.0)?;
    let (grid, owner) = feather_grid(feather_triangles);
    progress.check(Phase::Validating, 0.1)?;
    let longest = shapes.iter().map(|s| s.length).fold(0.0f32, f32::max);
    let coverage = count_covered(&grid, longest, skin, body, probes, seed, progress);
    progress.check(Phase::Validating, 0.4)?;
    let intersecting_pairs = intersecting_pairs_in(&grid, &owner, progress);
    progress.check(Phase::Validating, 0.7)?;
    let body_penetrations = exact::body_penetrations_polled(frames, shapes, poses, body, progress);
    progress.check(Phase::Validating, 0.9)?;
    let polled = |i: usize| progress.poll(Phase::Validating, 0.95, i);
    let (tip_heights, tip_stacks) = how_tips_lie(input, OwnedTriangles { grid: &grid, owner: &owner }, polled);
    progress.check(Phase::Validating, 1.0)?;
    Ok(Validation {
        intersecting_pairs,
        body_penetrations,
        coverage: coverage.fraction(),
        probes: coverage.probes,
        buried_probes: coverage.buried,
        mean_pitch_deg: mean_pitch_deg(poses),
        tip_heights,
        tip_stacks,
        groom: groom(frames, |_| true),
    })
}

/// [`validate`] restricted to a part of the coat: the feathers `member`
/// marks (one flag per feather). Every feather is still an obstacle and a
/// cover: the pairs are those with at least one member, the penetrations,
/// pitch, tip heights and tip stacks the members' (any feather may lie
/// beneath a member's tip), and the coverage probes are drawn on
/// `input.skin`, which the caller restricts to the part's skin. Indices
/// stay the whole coat's.
pub fn validate_part(input: &ValidationInput<'_>, member: &[bool]) -> Validation {
    let ValidationInput { feather_triangles, frames, shapes, poses, body, skin, probes, seed } = *input;
    let (grid, owner) = feather_grid(feather_triangles);
    let longest = shapes.iter().map(|s| s.length).fold(0.0f32, f32::max);
    let coverage = count_covered(&grid, longest, skin, body, probes, seed, &Progress::none());
    let is_member = |i: usize| member.get(i).copied().unwrap_or(false);
    let picked: Vec<usize> = (0..frames.len()).filter(|&i| is_member(i)).collect();
    let (f, s, p): (Vec<RootFrame>, Vec<FeatherShape>, Vec<FeatherPose>) = (
        picked.iter().map(|&i| frames[i]).collect(),
        picked.iter().map(|&i| shapes[i]).collect(),
        picked.iter().map(|&i| poses[i]).collect(),
    );
    let mut intersecting_pairs = intersecting_pairs_in(&grid, &owner, &Progress::none());
    intersecting_pairs.retain(|&(a, b)| is_member(a as usize) || is_member(b as usize));
    let (tip_heights, tip_stacks) = how_tips_lie(input, OwnedTriangles { grid: &grid, owner: &owner }, is_member);
    Validation {
        intersecting_pairs,
        body_penetrations: body_penetrations(&f, &s, &p, body).into_iter().map(|k| picked[k as usize] as u32).collect(),
        coverage: coverage.fraction(),
        probes: coverage.probes,
        buried_probes: coverage.buried,
        mean_pitch_deg: mean_pitch_deg(&p),
        tip_heights,
        tip_stacks,
        groom: groom(frames, is_member),
    }
}

/// The tip heights and stacks of the feathers `member` picks, every
/// feather of `input` counting as one that may lie beneath a tip.
fn how_tips_lie(
    input: &ValidationInput<'_>,
    feathers: OwnedTriangles<'_>,
    member: impl Fn(usize) -> bool + Sync,
) -> (TipHeights, TipStacks) {
    let lies = tip_lies(input.frames, input.shapes, input.poses, input.body, feathers, member);
    let heights: Vec<f64> = lies.iter().map(|l| l.height).collect();
    (summarise_tip_heights(&heights), summarise_tip_stacks(&lies))
}

/// Fraction of the probes of `skin` outside `body` whose normal ray meets
/// one of `feather_triangles` within `reach` (see [`count_covered`]).
pub fn coverage(
    feather_triangles: &[FeatherTriangles],
    reach: f32,
    skin: &ProbeSkin<'_>,
    body: &BodyIndex,
    probes: usize,
    seed: u64,
) -> f64 {
    count_covered(&feather_grid(feather_triangles).0, reach, skin, body, probes, seed, &Progress::none()).fraction()
}

/// A grid over every feather triangle, feather after feather, and the
/// feather each grid triangle belongs to.
fn feather_grid(feather_triangles: &[FeatherTriangles]) -> (TriangleGrid, Vec<u32>) {
    let mut grid = TriangleGrid::new();
    grid.rebuild(feather_triangles.iter().flat_map(|f| f.iter().copied()), None);
    let owner =
        feather_triangles.iter().enumerate().flat_map(|(i, f)| std::iter::repeat_n(i as u32, f.len())).collect();
    (grid, owner)
}

/// Pairs of distinct feathers whose triangles intersect (exact test, see
/// [`triangles_intersect`]); any two feathers are compared, not only
/// neighbours. Feathers left out (size 0, all corners at the root) meet
/// nothing. Sorted, without repeats.
pub fn intersecting_pairs(feather_triangles: &[FeatherTriangles]) -> Vec<(u32, u32)> {
    let (grid, owner) = feather_grid(feather_triangles);
    intersecting_pairs_in(&grid, &owner, &Progress::none())
}

/// The pairs of [`intersecting_pairs`] from a built grid, polling
/// `progress` per non-empty cell (stopped, the rest are skipped).
fn intersecting_pairs_in(grid: &TriangleGrid, owner: &[u32], progress: &Progress) -> Vec<(u32, u32)> {
    let mut pairs: Vec<(u32, u32)> = (0..grid.cell_count())
        .into_par_iter()
        .flat_map_iter(|cell| {
            let items = grid.cell_items(cell);
            let mut found = Vec::new();
            if !items.is_empty() && !progress.poll(Phase::Validating, 0.5, cell) {
                return found;
            }
            for (k, &ta) in items.iter().enumerate() {
                let ba = grid.bounds(ta);
                for &tb in &items[k + 1..] {
                    let (fa, fb) = (owner[ta as usize], owner[tb as usize]);
                    if fa == fb {
                        continue;
                    }
                    let bb = grid.bounds(tb);
                    if !ba.overlaps(&bb) || grid.first_shared_cell(ta, tb) != cell || ba.is_point() || bb.is_point() {
                        continue;
                    }
                    if triangles_intersect(&grid.corners(ta), &grid.corners(tb)) {
                        found.push((fa.min(fb), fa.max(fb)));
                    }
                }
            }
            found
        })
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// Mean pitch in degrees (summed in index order).
pub fn mean_pitch_deg(poses: &[FeatherPose]) -> f64 {
    if poses.is_empty() {
        return 0.0;
    }
    poses.iter().map(|p| p.pitch as f64).sum::<f64>() / poses.len() as f64 * (180.0 / std::f64::consts::PI)
}
