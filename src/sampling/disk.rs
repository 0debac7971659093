//! The Poisson-disk sampler both samplers share ([`DiskSampler`]): the
//! pool points still alive ([`AliveSet`]), the samples placed so far, and
//! the geodesic test between them.

use super::grid::{DynamicGrid, StaticGrid};
use super::pool::{PoolPoint, SortedPool};
use crate::rng::Rng;
use crate::surface::geodesic::SAME_FACING_COS;
use crate::surface::{NearbyPatch, Surface};
use glam::Vec3;

/// The pool points not yet removed, with O(1) removal and uniform choice,
/// and how many are left in each grid cell (so that radius queries skip the
/// cells already emptied: most of the ball around a new sample lies behind
/// the front).
struct AliveSet {
    list: Vec<u32>,
    slot: Vec<u32>,
    /// One bit per pool slot, set while the point is alive: a radius query
    /// reads only the live points of a cell, in slot order.
    bits: Vec<u64>,
    /// Per pool slot, its grid cell id.
    slot_cell: Vec<u32>,
    /// Per grid cell id, the points of it still alive.
    cell_alive: Vec<u32>,
}

impl AliveSet {
    const GONE: u32 = u32::MAX;

    fn new(grid: &StaticGrid) -> Self {
        let slot_cell = grid.slot_cells();
        let n = slot_cell.len();
        let mut cell_alive = vec![0u32; grid.cell_count()];
        slot_cell.iter().for_each(|&c| cell_alive[c as usize] += 1);
        let mut bits = vec![u64::MAX; n.div_ceil(64)];
        if n % 64 != 0 {
            *bits.last_mut().expect("n > 0") = (1u64 << (n % 64)) - 1;
        }
        Self { list: (0..n as u32).collect(), slot: (0..n as u32).collect(), bits, slot_cell, cell_alive }
    }

    /// The live points of slots `first..first + len`, word by word: calls
    /// `f(self, slot)` for each in slot order. `f` may remove the point it
    /// is given (the word is read before its points are visited).
    #[inline]
    fn for_each_in(&mut self, first: u32, len: u32, mut f: impl FnMut(&mut Self, u32)) {
        let end = first + len;
        let mut word = first / 64;
        while word * 64 < end {
            let lo = (word * 64).max(first);
            let hi = (word * 64 + 64).min(end);
            // Bits lo..hi of this word.
            let span = hi - lo;
            let mask = if span == 64 { u64::MAX } else { ((1u64 << span) - 1) << (lo - word * 64) };
            let mut live = self.bits[word as usize] & mask;
            while live != 0 {
                let k = word * 64 + live.trailing_zeros();
                live &= live - 1;
                f(self, k);
            }
            word += 1;
        }
    }

    #[inline]
    fn contains(&self, i: u32) -> bool {
        self.slot[i as usize] != Self::GONE
    }

    /// Whether every point of grid cell `cell` has been removed.
    #[inline]
    fn cell_is_empty(&self, cell: u32) -> bool {
        self.cell_alive[cell as usize] == 0
    }

    fn remove(&mut self, i: u32) {
        let s = self.slot[i as usize];
        if s == Self::GONE {
            return;
        }
        self.cell_alive[self.slot_cell[i as usize] as usize] -= 1;
        self.bits[i as usize / 64] &= !(1u64 << (i % 64));
        let last = self.list.pop().expect("non-empty when an element is alive");
        if last != i {
            self.list[s as usize] = last;
            self.slot[last as usize] = s;
        }
        self.slot[i as usize] = Self::GONE;
    }

    fn random(&self, rng: &mut Rng) -> Option<u32> {
        (!self.list.is_empty()).then(|| self.list[rng.below(self.list.len())])
    }
}

/// `G` from a pool point (the centre) to others within `radius`, as
/// [`NearbyPatch::geodesic_to`] after a `gather` around the centre; the
/// patch is gathered only once a point faces the other way, since `G` of
/// points facing the same way is their chord (on a smooth skin, most
/// queries never need the patch).
struct LazyPatch<'p> {
    patch: &'p mut NearbyPatch,
    center: PoolPoint,
    radius: f32,
    gathered: bool,
}

impl<'p> LazyPatch<'p> {
    fn new(patch: &'p mut NearbyPatch, center: PoolPoint, radius: f32) -> Self {
        Self { patch, center, radius, gathered: false }
    }

    #[inline]
    fn geodesic_to(&mut self, surface: &Surface, positions: &[Vec3], q: &PoolPoint) -> f32 {
        let c = &self.center;
        // The same test and chord as `NearbyPatch::geodesic_to`.
        if c.normal.dot(q.normal) > SAME_FACING_COS {
            return (q.position - c.position).length();
        }
        if !self.gathered {
            self.patch.gather(surface, positions, c.face, c.position, c.normal, self.radius);
            self.gathered = true;
        }
        self.patch.geodesic_to(q.position, q.normal, q.face)
    }
}

/// Poisson-disk state shared by both samplers: the pool, what is left of
/// it, and the samples placed so far (all by slot). Two points conflict
/// when `G(p_i, p_j) ≤ max(d_i, d_j)`.
pub(crate) struct DiskSampler<'a> {
    pub(crate) surface: &'a Surface,
    pub(crate) positions: &'a [Vec3],
    pub(crate) points: &'a [PoolPoint],
    grid: &'a StaticGrid,
    alive: AliveSet,
    samples: Vec<u32>,
    sample_grid: DynamicGrid,
    patch: NearbyPatch,
    check_patch: NearbyPatch,
    /// Points with a spacing above this are checked against the samples
    /// before placement (see [`DiskSampler::conflicts`]).
    check_above: f32,
    /// Asked every few steps whether to go on (interruption).
    keep_going: Option<&'a dyn Fn() -> bool>,
    steps_since_check: u32,
    stopped: bool,
}

impl<'a> DiskSampler<'a> {
    /// Sets the interruption check, polled by [`DiskSampler::should_stop`].
    pub(crate) fn with_keep_going(mut self, keep_going: &'a dyn Fn() -> bool) -> Self {
        self.keep_going = Some(keep_going);
        self
    }

    /// Whether the sampler loop must stop now: asks the check every 64 calls.
    pub(crate) fn should_stop(&mut self) -> bool {
        if self.stopped {
            return true;
        }
        self.steps_since_check += 1;
        if self.steps_since_check >= 64 {
            self.steps_since_check = 0;
            self.stopped = self.keep_going.is_some_and(|f| !f());
        }
        self.stopped
    }

    /// Sets up the state over `pool`; `cell` is the sample grid's cell size.
    pub(crate) fn new(surface: &'a Surface, positions: &'a [Vec3], pool: &'a SortedPool, cell: f32) -> Self {
        let min_spacing = pool.points.iter().map(|p| p.spacing).fold(f32::INFINITY, f32::min);
        Self {
            surface,
            positions,
            points: &pool.points,
            grid: &pool.grid,
            alive: AliveSet::new(&pool.grid),
            samples: Vec::new(),
            sample_grid: DynamicGrid::new(cell),
            patch: NearbyPatch::new(surface),
            check_patch: NearbyPatch::new(surface),
            check_above: 2.0 * min_spacing,
            keep_going: None,
            steps_since_check: 0,
            stopped: false,
        }
    }

    /// Pool points placed as samples, in placement order.
    pub(crate) fn into_samples(self) -> Vec<u32> {
        self.samples
    }

    pub(crate) fn pool_is_empty(&self) -> bool {
        self.alive.list.is_empty()
    }

    pub(crate) fn is_alive(&self, j: u32) -> bool {
        self.alive.contains(j)
    }

    /// A uniformly chosen pool point still in the pool.
    pub(crate) fn random_alive(&self, rng: &mut Rng) -> Option<u32> {
        self.alive.random(rng)
    }

    /// The placed sample nearest to `position` within `radius` whose
    /// normal faces the same way as `normal`.
    pub(crate) fn nearest_sample(&self, position: Vec3, normal: Vec3, radius: f32) -> Option<u32> {
        let mut best: Option<(f32, u32)> = None;
        self.sample_grid.for_each_candidate(position, radius, |s| {
            let p = &self.points[s as usize];
            let d2 = (p.position - position).length_squared();
            if d2 <= radius * radius && p.normal.dot(normal) > 0.0 && best.is_none_or(|b| d2 < b.0) {
                best = Some((d2, s));
            }
        });
        best.map(|b| b.1)
    }

    /// The pool point still in the pool nearest to `position` within
    /// `radius`, and its distance.
    pub(crate) fn nearest_alive(&self, position: Vec3, radius: f32) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        let r2 = radius * radius;
        self.grid.for_each_cell_within(position, radius, |cell, first, slots| {
            if self.alive.cell_is_empty(cell) {
                return;
            }
            for (k, q) in (first..).zip(slots) {
                let d2 = (*q - position).length_squared();
                if d2 <= r2 && self.alive.contains(k) && best.is_none_or(|b| d2 < b.0) {
                    best = Some((d2, k));
                }
            }
        });
        best.map(|(d2, k)| (d2.sqrt(), k))
    }

    pub(crate) fn discard(&mut self, j: u32) {
        self.alive.remove(j);
    }

    /// Makes pool point `j` a sample: removes from the pool every point
    /// within `G ≤ max(d_i, d_j)` (the paper's `N_i` and the pruning of
    /// `C_i`) and returns in `candidates` the remaining points with
    /// `d_i < G ≤ 2 d_i` (the paper's `C_i`).
    pub(crate) fn place(&mut self, j: u32, candidates: &mut Vec<u32>) {
        candidates.clear();
        let p = self.points[j as usize];
        self.alive.remove(j);
        self.samples.push(j);
        self.sample_grid.insert(j, p.position);
        let reach = 2.0 * p.spacing;
        let mut patch = LazyPatch::new(&mut self.patch, p, reach);
        let (surface, positions) = (self.surface, self.positions);
        let (alive, points) = (&mut self.alive, self.points);
        let reach2 = reach * reach;
        self.grid.for_each_cell_within(p.position, reach, |cell, first, slots| {
            if alive.cell_is_empty(cell) {
                return;
            }
            alive.for_each_in(first, slots.len() as u32, |alive, k| {
                if (slots[(k - first) as usize] - p.position).length_squared() > reach2 {
                    return;
                }
                let q = &points[k as usize];
                let g = patch.geodesic_to(surface, positions, q);
                if g <= p.spacing.max(q.spacing) {
                    alive.remove(k);
                } else if g <= reach {
                    candidates.push(k);
                }
            });
        });
    }

    /// Whether pool point `j` lies within its own `d_j` of a sample. Only
    /// possible where the spacing more than doubles within `d_j` (a sample
    /// `i` prunes the pool out to `2 d_i` only), so only such points are
    /// checked.
    pub(crate) fn conflicts(&mut self, j: u32) -> bool {
        let q = self.points[j as usize];
        if q.spacing <= self.check_above {
            return false;
        }
        let mut patch = LazyPatch::new(&mut self.check_patch, q, q.spacing);
        let mut conflict = false;
        let (surface, positions, points) = (self.surface, self.positions, self.points);
        self.sample_grid.for_each_candidate(q.position, q.spacing, |s| {
            conflict |= patch.geodesic_to(surface, positions, &points[s as usize]) <= q.spacing;
        });
        conflict
    }
}
