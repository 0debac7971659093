//! The sample pool of Algorithm 1 ("a large pool of uniform random samples
//! on the surface"), and the Poisson-disk bookkeeping both samplers share.
//!
//! One deliberate change from the paper: the pool is drawn with density
//! proportional to `1/d(p)²` rather than uniform in area, so every disk of
//! radius `d` holds about the same number of pool points whatever the local
//! spacing, and packing is equally tight in dense and sparse regions. With a
//! uniform spacing field the two are the same.

use super::grid::StaticGrid;
use crate::field::Fields;
use crate::geometry::SurfacePoint;
use crate::interior::{BuriedSkin, FaceBurial};
use crate::rng::Rng;
use crate::surface::Surface;
use glam::Vec3;
use rayon::prelude::*;

/// Pool points drawn per rayon task (each block has its own random stream).
const POOL_BLOCK: usize = 4096;

/// Upper bound on the pool size (memory: about 44 bytes a point).
pub(crate) const MAX_POOL: usize = 4 << 20;

/// Stream tag of the pool's random numbers.
const POOL_STREAM: u64 = 0x706F_6F6C;

/// Cells along each barycentric axis of a crossed face whose burial is
/// decided once per cell (see [`BurialMemo`]).
const MEMO_CELLS: usize = 8;
/// A crossed face is judged once per cell when it expects at least this
/// many pool points per cell (512 a face), so that the table's rays are a
/// small part of the per-point ones ...
const MEMO_POINTS_PER_CELL: f64 = 8.0;
/// ... and only in a mesh whose crossed faces hold more than this share of
/// the pool: a soup whose faces all cross one another. The real models'
/// crossed faces hold at most about a fifth of their pool, so they keep
/// the exact per-point test and their coats, while the soup of case 83901
/// (below) holds its whole pool on crossed faces (BENCHMARKS.md,
/// "Measurements behind the code's constants").
const MEMO_CROSSED_SHARE: f64 = 0.5;

/// Share of a face that is feathered, by its number of feathered corners:
/// a point is bare where its bare corners weigh more than ½.
const PRESENCE_FRACTION: [f64; 4] = [0.0, 0.25, 0.75, 1.0];

/// One pool point at the rest pose.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PoolPoint {
    pub(crate) position: Vec3,
    pub(crate) normal: Vec3,
    pub(crate) face: u32,
    pub(crate) bary: [f32; 3],
    /// Local Poisson-disk radius `d_j`.
    pub(crate) spacing: f32,
}

impl PoolPoint {
    pub(crate) fn surface_point(&self) -> SurfacePoint {
        SurfacePoint { face: self.face, bary: self.bary }
    }
}

/// Where pool points may fall and how densely: per-face weights for
/// drawing points with density `∝ 1/s²` (`s` the spacing multiplier).
pub(crate) struct DensityField<'a> {
    surface: &'a Surface,
    fields: &'a Fields,
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    /// Cumulative face weights `area × max corner 1/s²`.
    cdf: Vec<f64>,
    /// Per face: smallest feathered corner multiplier (0 for bare faces).
    min_scale: Vec<f32>,
    /// `∫ 1/s² dA` over the feathered surface: roots ≈ this / d² × packing.
    effective_area: f64,
    /// Skin buried inside the body: no pool points there.
    buried: &'a BuriedSkin,
}

impl<'a> DensityField<'a> {
    pub(crate) fn new(
        surface: &'a Surface,
        fields: &'a Fields,
        positions: &'a [Vec3],
        normals: &'a [Vec3],
        buried: &'a BuriedSkin,
    ) -> Self {
        let scales = fields.vertex_spacing_scales();
        let mut cdf = Vec::with_capacity(surface.face_count());
        let mut min_scale = Vec::with_capacity(surface.face_count());
        let (mut total, mut effective_area) = (0.0f64, 0.0f64);
        for (f, tri) in surface.triangles().iter().enumerate() {
            let area = {
                let [a, b, c] = surface.corners(positions, f);
                0.5 * (b - a).cross(c - a).length() as f64
            };
            let feathered: Vec<f32> = tri.iter().map(|&v| scales[v as usize]).filter(|&s| s > 0.0).collect();
            let lo = feathered.iter().copied().fold(f32::INFINITY, f32::min);
            if feathered.is_empty() || area.is_nan() || area <= 0.0 || buried.face(f) == FaceBurial::Buried {
                min_scale.push(0.0);
            } else {
                let mean_inv2 =
                    feathered.iter().map(|&s| 1.0 / (s as f64 * s as f64)).sum::<f64>() / feathered.len() as f64;
                effective_area += area * PRESENCE_FRACTION[feathered.len()] * mean_inv2;
                total += area / (lo as f64 * lo as f64);
                min_scale.push(lo);
            }
            cdf.push(total);
        }
        Self { surface, fields, positions, normals, cdf, min_scale, effective_area, buried }
    }

    /// `∫ 1/s² dA` over the feathered part of the surface.
    pub(crate) fn effective_area(&self) -> f64 {
        self.effective_area
    }

    /// Draws `count` pool points for global spacing `d`, deterministic for
    /// `seed` whatever the thread count. `keep_going` is asked before each
    /// block of draws: once it says stop, the remaining blocks draw nothing
    /// (the caller then reports the interruption).
    pub(crate) fn draw_pool(
        &self,
        d: f32,
        count: usize,
        seed: u64,
        keep_going: &(dyn Fn() -> bool + Sync),
    ) -> Vec<PoolPoint> {
        let total = self.cdf.last().copied().unwrap_or(0.0);
        if count == 0 || total.is_nan() || total <= 0.0 {
            return Vec::new();
        }
        let blocks = count.div_ceil(POOL_BLOCK);
        let memo = self.burial_memo(count, total, keep_going);
        let faces = FaceLookup::new(&self.cdf);
        let parts: Vec<Vec<PoolPoint>> = (0..blocks)
            .into_par_iter()
            .map(|b| {
                if !keep_going() {
                    return Vec::new();
                }
                let wanted = POOL_BLOCK.min(count - b * POOL_BLOCK);
                let mut rng = Rng::for_stream(seed ^ POOL_STREAM, b as u64);
                self.draw_block(&mut rng, d, wanted, total, Lookups { memo: &memo, faces: &faces, keep_going })
            })
            .collect();
        parts.concat()
    }

    /// The burial of every cell of the crossed faces that expect many pool
    /// points (see [`BurialMemo`]), decided at the cells' centres.
    fn burial_memo(&self, count: usize, total: f64, keep_going: &(dyn Fn() -> bool + Sync)) -> BurialMemo {
        let cells = MEMO_CELLS * MEMO_CELLS;
        let mut start = vec![u32::MAX; self.cdf.len()];
        let mut faces = Vec::new();
        let expected = |f: usize| count as f64 * (self.cdf[f] - if f == 0 { 0.0 } else { self.cdf[f - 1] }) / total;
        let crossed = |f: &usize| self.buried.face(*f) == FaceBurial::Crossed;
        let on_crossed: f64 = (0..self.cdf.len()).filter(crossed).map(expected).sum();
        if on_crossed > MEMO_CROSSED_SHARE * count as f64 {
            for f in (0..self.cdf.len()).filter(crossed) {
                if expected(f) >= MEMO_POINTS_PER_CELL * cells as f64 {
                    start[f] = (faces.len() * cells) as u32;
                    faces.push(f);
                }
            }
        }
        let buried = faces
            .par_iter()
            .flat_map_iter(|&f| (0..cells).map(move |c| (f, c)))
            .map(|(f, c)| {
                // Stopped: the rest are left visible (the pass is dropped).
                if !keep_going() {
                    return false;
                }
                let point = SurfacePoint { face: f as u32, bary: memo_cell_centre(c) };
                let position = self.surface.position(self.positions, point);
                let normal = self.surface.interpolated_normal(self.positions, self.normals, point);
                self.buried.holds(f, position, normal)
            })
            .collect();
        BurialMemo { start, buried }
    }

    fn draw_block(
        &self,
        rng: &mut Rng,
        d: f32,
        wanted: usize,
        total: f64,
        Lookups { memo, faces, keep_going }: Lookups<'_>,
    ) -> Vec<PoolPoint> {
        let mut out = Vec::with_capacity(wanted);
        let mut attempts = 0usize;
        while out.len() < wanted && attempts < 64 * wanted {
            // A block holds thousands of draws, each maybe with burial rays:
            // stopped, the block ends short (the pass is then dropped).
            if attempts % 64 == 63 && !keep_going() {
                break;
            }
            attempts += 1;
            let u = rng.next_f64() * total;
            let face = faces.first_above(u).min(self.cdf.len() - 1);
            let (mut r1, mut r2) = (rng.next_f32(), rng.next_f32());
            if r1 + r2 > 1.0 {
                (r1, r2) = (1.0 - r1, 1.0 - r2);
            }
            let accept_u = rng.next_f32();
            let point = SurfacePoint { face: face as u32, bary: [1.0 - r1 - r2, r1, r2] };
            let Some(scale) = self.fields.spacing_scale_at(self.surface, point) else { continue };
            // Rejection from the face's densest corner down to density 1/s².
            let ratio = self.min_scale[face] / scale;
            if accept_u >= ratio * ratio {
                continue;
            }
            let position = self.surface.position(self.positions, point);
            let normal = self.surface.interpolated_normal(self.positions, self.normals, point);
            let buried = match memo.of(face, r1, r2) {
                Some(buried) => buried,
                None => self.buried.holds(face, position, normal),
            };
            if buried {
                continue;
            }
            out.push(PoolPoint { position, normal, face: face as u32, bary: point.bary, spacing: d * scale });
        }
        out
    }
}

/// What every block of a pool reads besides the density: the burial memo,
/// the face lookup, and whether to go on.
#[derive(Clone, Copy)]
struct Lookups<'a> {
    memo: &'a BurialMemo,
    faces: &'a FaceLookup<'a>,
    keep_going: &'a (dyn Fn() -> bool + Sync),
}

/// `cdf.partition_point(|&c| c <= u)` over a non-decreasing `cdf`, found
/// through a guide table: bucket `b` of `[0, total)` in as many buckets as
/// entries holds the partition point of its lower end, so a draw searches
/// only between two guide entries (falling back to the whole table when
/// rounding put `u` outside its bucket's bracket).
struct FaceLookup<'a> {
    cdf: &'a [f64],
    /// Per bucket, then one more: the partition point at the bucket's lower end.
    guide: Vec<u32>,
    /// Buckets per unit of `u`.
    scale: f64,
}

impl<'a> FaceLookup<'a> {
    fn new(cdf: &'a [f64]) -> Self {
        let total = cdf.last().copied().unwrap_or(0.0);
        let buckets = cdf.len().max(1);
        let step = total / buckets as f64;
        let mut guide = Vec::with_capacity(buckets + 1);
        let mut at = 0usize;
        for b in 0..buckets {
            let threshold = b as f64 * step;
            while at < cdf.len() && cdf[at] <= threshold {
                at += 1;
            }
            guide.push(at as u32);
        }
        guide.push(cdf.len() as u32);
        Self { cdf, guide, scale: if total > 0.0 { buckets as f64 / total } else { 0.0 } }
    }

    #[inline]
    fn first_above(&self, u: f64) -> usize {
        let b = ((u * self.scale) as usize).min(self.guide.len() - 2);
        let (lo, hi) = (self.guide[b] as usize, self.guide[b + 1] as usize);
        let bracketed = (lo == 0 || self.cdf[lo - 1] <= u) && (hi == self.cdf.len() || self.cdf[hi] > u);
        if bracketed {
            lo + self.cdf[lo..hi].partition_point(|&c| c <= u)
        } else {
            self.cdf.partition_point(|&c| c <= u)
        }
    }
}

/// Burial decided once per cell of a crossed face that expects many pool
/// points, in a mesh whose pool lies mostly on crossed faces (see
/// [`MEMO_CROSSED_SHARE`]): the face's (r1, r2) square cut into [`MEMO_CELLS`]²
/// cells, each judged at its centre. Without it every pool point of a crossed
/// face casts up to three winding rays: `fuzz_create` (seed 2026, case 83901)
/// found a soup of 114 triangles, every one crossing another, whose 22 240
/// feathers' pool took 44 s of rays. A face of a real model expects a few pool
/// points and keeps the exact per-point test, so real coats do not change.
struct BurialMemo {
    /// Per face, the index of its first cell in `buried`, or `u32::MAX`.
    start: Vec<u32>,
    buried: Vec<bool>,
}

impl BurialMemo {
    /// The memoised burial of the point (r1, r2) of `face`, if the face has
    /// a table.
    fn of(&self, face: usize, r1: f32, r2: f32) -> Option<bool> {
        let start = *self.start.get(face)?;
        if start == u32::MAX {
            return None;
        }
        let cell = |r: f32| ((r * MEMO_CELLS as f32) as usize).min(MEMO_CELLS - 1);
        Some(self.buried[start as usize + cell(r1) * MEMO_CELLS + cell(r2)])
    }
}

/// The barycentric coordinates of the centre of memo cell `c` (row `r1`,
/// column `r2`), pulled inside the triangle for the cells the diagonal cuts.
fn memo_cell_centre(c: usize) -> [f32; 3] {
    let n = MEMO_CELLS as f32;
    let (mut a, mut b) = (((c / MEMO_CELLS) as f32 + 0.5) / n, ((c % MEMO_CELLS) as f32 + 0.5) / n);
    if a + b > 1.0 {
        let shrink = 0.999 / (a + b);
        (a, b) = (a * shrink, b * shrink);
    }
    [1.0 - a - b, a, b]
}

/// The pool stored in grid order, so that a radius query reads contiguous
/// memory. Slots are positions in that order; draw indices are positions
/// in the order the points were drawn (random, hence the random sampler's
/// throwing order, and the root ids).
pub(crate) struct SortedPool {
    pub(crate) points: Vec<PoolPoint>,
    draw_index: Vec<u32>,
    pub(super) grid: StaticGrid,
}

impl SortedPool {
    /// Sorts `drawn` into a grid of cell size `cell`.
    pub(crate) fn new(drawn: Vec<PoolPoint>, cell: f32) -> Self {
        let positions: Vec<Vec3> = drawn.par_iter().map(|p| p.position).collect();
        let grid = StaticGrid::new(&positions, cell);
        let draw_index = grid.order().to_vec();
        let points = draw_index.par_iter().map(|&i| drawn[i as usize]).collect();
        Self { points, draw_index, grid }
    }

    /// The draw index of the point in `slot`.
    pub(crate) fn draw_index(&self, slot: u32) -> u32 {
        self.draw_index[slot as usize]
    }

    /// Slots in the order their points were drawn.
    pub(crate) fn slots_in_draw_order(&self) -> Vec<u32> {
        let mut slots = vec![0u32; self.draw_index.len()];
        for (slot, &draw) in self.draw_index.iter().enumerate() {
            slots[draw as usize] = slot as u32;
        }
        slots
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The guide table finds the partition point of a full binary search,
    /// whatever the weights: runs of zero weight (bare faces), one face
    /// holding most of the total, and draws at the entries and bucket
    /// edges themselves.
    #[test]
    fn face_lookup_is_the_partition_point() {
        let mut rng = Rng::new(21);
        for case in 0..40 {
            let n = 1 + (rng.next_f32() * 300.0) as usize;
            let mut total = 0.0f64;
            let cdf: Vec<f64> = (0..n)
                .map(|i| {
                    let w = match case % 4 {
                        0 => rng.next_f64(),
                        1 if rng.next_f32() < 0.6 => 0.0,
                        2 if i == n / 2 => 1e6,
                        _ => rng.next_f64() * rng.next_f64(),
                    };
                    total += w;
                    total
                })
                .collect();
            if total <= 0.0 {
                continue;
            }
            let lookup = FaceLookup::new(&cdf);
            let step = total / n as f64;
            let draws = (0..500)
                .map(|_| rng.next_f64() * total)
                .chain(cdf.iter().copied())
                .chain((0..n).map(|b| b as f64 * step))
                .chain([0.0, total, f64::from_bits(total.to_bits() - 1)]);
            for u in draws {
                assert_eq!(lookup.first_above(u), cdf.partition_point(|&c| c <= u), "case {case}, u = {u}");
            }
        }
    }
}
