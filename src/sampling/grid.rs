//! Uniform hash grids for radius queries around sample points. Queries
//! visit cells in a fixed order and points within a cell in insertion
//! order, so nothing depends on hash-map iteration order.

use crate::rng::mix64;
use glam::Vec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Integer cell coordinates. Hashing packs them into one word (21 bits an
/// axis); equality still compares all three, so a packing collision costs
/// time, never correctness.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Cell([i32; 3]);

impl Cell {
    #[inline]
    fn packed(&self) -> u64 {
        let [x, y, z] = self.0.map(|c| c as u32 as u64 & 0x1F_FFFF);
        (x << 42) | (y << 21) | z
    }
}

impl std::hash::Hash for Cell {
    #[inline]
    fn hash<H: Hasher>(&self, state: &mut H) {
        state.write_u64(self.packed());
    }
}

/// A cheap hasher for packed cell keys (SplitMix finaliser).
#[derive(Default)]
pub(crate) struct CellHasher(u64);

impl Hasher for CellHasher {
    #[inline]
    fn finish(&self) -> u64 {
        mix64(self.0)
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = self.0.rotate_left(8) ^ b as u64;
        }
    }
    #[inline]
    fn write_u64(&mut self, word: u64) {
        self.0 ^= word;
    }
}

type CellMap<V> = HashMap<Cell, V, BuildHasherDefault<CellHasher>>;

fn cell_of(p: Vec3, inv_cell: f32) -> Cell {
    let c = (p * inv_cell).floor();
    Cell([c.x as i32, c.y as i32, c.z as i32])
}

/// Number of cells in the box that [`for_each_cell`] walks (as f64: it can
/// exceed any integer type when the radius is huge against the cell, or
/// infinite).
fn box_cell_count(center: Vec3, radius: f32, inv_cell: f32) -> f64 {
    let lo = ((center - Vec3::splat(radius)) * inv_cell).floor().as_dvec3();
    let hi = ((center + Vec3::splat(radius)) * inv_cell).floor().as_dvec3();
    let n = (hi - lo + 1.0).max(glam::DVec3::ONE);
    let count = n.x * n.y * n.z;
    if count.is_nan() { f64::INFINITY } else { count }
}

/// Squared distance from `c` to the cell interval `[k, k + 1) · cell` on one axis.
fn axis_gap(c: f32, k: i32, cell: f32) -> f32 {
    let (a, b) = (k as f32 * cell, (k + 1) as f32 * cell);
    let g = (a - c).max(c - b).max(0.0);
    g * g
}

/// True when [`for_each_cell`] visits `cell` (same box, same test).
fn ball_meets_cell(center: Vec3, radius: f32, inv_cell: f32, cell: Cell) -> bool {
    let lo = cell_of(center - Vec3::splat(radius), inv_cell).0;
    let hi = cell_of(center + Vec3::splat(radius), inv_cell).0;
    let size = 1.0 / inv_cell;
    (0..3).all(|a| lo[a] <= cell.0[a] && cell.0[a] <= hi[a])
        && axis_gap(center.x, cell.0[0], size)
            + axis_gap(center.y, cell.0[1], size)
            + axis_gap(center.z, cell.0[2], size)
            <= radius * radius
}

/// Visits every cell that meets the ball of `radius` around `center`.
fn for_each_cell(center: Vec3, radius: f32, inv_cell: f32, mut f: impl FnMut(Cell)) {
    let lo = cell_of(center - Vec3::splat(radius), inv_cell);
    let hi = cell_of(center + Vec3::splat(radius), inv_cell);
    let cell = 1.0 / inv_cell;
    let r2 = radius * radius;
    let gap = |c: f32, k: i32| axis_gap(c, k, cell);
    let (lo, hi) = (lo.0, hi.0);
    for x in lo[0]..=hi[0] {
        let gx = gap(center.x, x);
        for y in lo[1]..=hi[1] {
            let gxy = gx + gap(center.y, y);
            if gxy > r2 {
                continue;
            }
            for z in lo[2]..=hi[2] {
                if gxy + gap(center.z, z) <= r2 {
                    f(Cell([x, y, z]));
                }
            }
        }
    }
}

/// A grid over a fixed point set, stored sorted by cell.
#[derive(Clone, Debug)]
pub(crate) struct StaticGrid {
    origin: Vec3,
    inv_cell: f32,
    /// Cell → its id, an index into `spans`.
    cells: CellMap<u32>,
    /// Per cell id, in slot order: the cell's slots `a..b`.
    spans: Vec<(u32, u32)>,
    /// Sorted slot → the caller's index.
    order: Vec<u32>,
    /// Positions in slot order.
    positions: Vec<Vec3>,
}

/// Cells a side that the packed key tells apart.
const PACKED_CELLS: f32 = (1u32 << 21) as f32;

impl StaticGrid {
    /// Buckets `positions` into cells of size `cell` (enlarged if the points
    /// span more cells than a packed key holds). Points keep their relative
    /// order within a cell.
    pub(crate) fn new(positions: &[Vec3], cell: f32) -> Self {
        let (lo, hi) =
            positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let origin = if lo.is_finite() { lo } else { Vec3::ZERO };
        let extent = if hi.is_finite() { (hi - origin).max_element() } else { 0.0 };
        let cell = cell.max(extent / (PACKED_CELLS - 2.0));
        let inv_cell = 1.0 / cell;
        // Within the bounding box the packed key is unique per cell, so a
        // stable sort on it alone groups cells and keeps index order inside.
        let mut keyed: Vec<(u64, u32)> =
            positions.iter().enumerate().map(|(i, &p)| (cell_of(p - origin, inv_cell).packed(), i as u32)).collect();
        keyed.sort_by_key(|&(key, _)| key);
        let mut cells = CellMap::default();
        let mut spans = Vec::new();
        let mut start = 0;
        while start < keyed.len() {
            let mut end = start;
            while end < keyed.len() && keyed[end].0 == keyed[start].0 {
                end += 1;
            }
            let cell = cell_of(positions[keyed[start].1 as usize] - origin, inv_cell);
            cells.insert(cell, spans.len() as u32);
            spans.push((start as u32, end as u32));
            start = end;
        }
        let order: Vec<u32> = keyed.into_iter().map(|(_, i)| i).collect();
        let positions = order.iter().map(|&i| positions[i as usize]).collect();
        Self { origin, inv_cell, cells, spans, order, positions }
    }

    /// Number of occupied cells (cell ids are `0..cell_count()`).
    pub(crate) fn cell_count(&self) -> usize {
        self.spans.len()
    }

    /// Per slot, the id of its cell.
    pub(crate) fn slot_cells(&self) -> Vec<u32> {
        let mut out = vec![0u32; self.positions.len()];
        for (id, &(a, b)) in self.spans.iter().enumerate() {
            out[a as usize..b as usize].fill(id as u32);
        }
        out
    }

    /// Calls `f(cell id, first slot, positions)` for every occupied cell
    /// that meets the ball of `radius` around `center` (every occupied cell
    /// when the radius is huge against the cell), in slot order; the caller
    /// tests the distances. Lets a caller skip a cell it knows to be empty
    /// of what it looks for.
    #[inline]
    pub(crate) fn for_each_cell_within(&self, center: Vec3, radius: f32, mut f: impl FnMut(u32, u32, &[Vec3])) {
        // A radius huge against the cell (spacing multipliers far apart)
        // would walk more cells than there are points: visit the occupied
        // cells instead. Slots are sorted by cell in the walk's (x, y, z)
        // order, so the calls come in the same order either way.
        if box_cell_count(center - self.origin, radius, self.inv_cell) > self.positions.len() as f64 {
            for (id, &(a, b)) in self.spans.iter().enumerate() {
                f(id as u32, a, &self.positions[a as usize..b as usize]);
            }
            return;
        }
        for_each_cell(center - self.origin, radius, self.inv_cell, |cell| {
            if let Some(&id) = self.cells.get(&cell) {
                let (a, b) = self.spans[id as usize];
                f(id, a, &self.positions[a as usize..b as usize]);
            }
        });
    }

    /// Sorted slot → the caller's index of the point stored there.
    pub(crate) fn order(&self) -> &[u32] {
        &self.order
    }

    /// Calls `f(slot, distance²)` for every point within `radius` of
    /// `center`, by sorted slot.
    #[inline]
    pub(crate) fn for_each_slot_within(&self, center: Vec3, radius: f32, mut f: impl FnMut(u32, f32)) {
        let r2 = radius * radius;
        self.for_each_cell_within(center, radius, |_, first, points| {
            for (slot, p) in (first..).zip(points) {
                let d2 = (*p - center).length_squared();
                if d2 <= r2 {
                    f(slot, d2);
                }
            }
        });
    }

    /// Calls `f(index, distance²)` for every point within `radius` of
    /// `center`, by the caller's index.
    #[inline]
    pub(crate) fn for_each_within(&self, center: Vec3, radius: f32, mut f: impl FnMut(u32, f32)) {
        self.for_each_slot_within(center, radius, |slot, d2| f(self.order[slot as usize], d2));
    }
}

/// A grid that grows one point at a time.
#[derive(Clone, Debug)]
pub(crate) struct DynamicGrid {
    inv_cell: f32,
    cells: CellMap<Vec<u32>>,
}

impl DynamicGrid {
    pub(crate) fn new(cell: f32) -> Self {
        Self { inv_cell: 1.0 / cell, cells: CellMap::default() }
    }

    pub(crate) fn insert(&mut self, index: u32, position: Vec3) {
        self.cells.entry(cell_of(position, self.inv_cell)).or_default().push(index);
    }

    /// Calls `f(index)` for every inserted point in a cell overlapping the
    /// cube of half-size `radius` around `center` (the caller checks distance).
    pub(crate) fn for_each_candidate(&self, center: Vec3, radius: f32, mut f: impl FnMut(u32)) {
        // As in `StaticGrid::for_each_slot_within`: a box of more cells than
        // occupied ones visits the occupied cells instead, in the walk's order.
        if box_cell_count(center, radius, self.inv_cell) > self.cells.len() as f64 {
            let mut cells: Vec<Cell> = self.cells.keys().copied().collect();
            cells.sort_unstable();
            for cell in cells.into_iter().filter(|&c| ball_meets_cell(center, radius, self.inv_cell, c)) {
                self.cells[&cell].iter().for_each(|&i| f(i));
            }
            return;
        }
        for_each_cell(center, radius, self.inv_cell, |cell| {
            if let Some(list) = self.cells.get(&cell) {
                list.iter().for_each(|&i| f(i));
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn static_grid_finds_exactly_the_points_in_range() {
        let mut rng = Rng::new(5);
        let pts: Vec<Vec3> =
            (0..500).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0).collect();
        let grid = StaticGrid::new(&pts, 0.3);
        let c = Vec3::new(0.1, -0.2, 0.3);
        let mut found = Vec::new();
        grid.for_each_within(c, 0.7, |i, _| found.push(i));
        found.sort_unstable();
        let expected: Vec<u32> = (0..500).filter(|&i| (pts[i as usize] - c).length() <= 0.7).collect();
        assert_eq!(found, expected);
    }

    /// A radius far beyond the cell size (or infinite) scans instead of
    /// walking cells, and gives the same calls in the same order as the walk.
    #[test]
    fn huge_radii_scan_in_the_walk_order() {
        let mut rng = Rng::new(9);
        let pts: Vec<Vec3> =
            (0..300).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 4.0 - 2.0).collect();
        let grid = StaticGrid::new(&pts, 0.5);
        let mut dynamic = DynamicGrid::new(0.5);
        pts.iter().enumerate().for_each(|(i, &p)| dynamic.insert(i as u32, p));
        let c = Vec3::new(0.1, -0.2, 0.3);
        // Both paths at a radius where the walk is still cheap.
        let r = 1.3;
        assert!(box_cell_count(c - grid.origin, r, grid.inv_cell) <= pts.len() as f64);
        let mut walked = Vec::new();
        grid.for_each_within(c, r, |i, d2| walked.push((i, d2)));
        let mut scanned = Vec::new();
        let r2 = r * r;
        for (slot, p) in grid.positions.iter().enumerate() {
            let d2 = (*p - c).length_squared();
            if d2 <= r2 {
                scanned.push((grid.order[slot], d2));
            }
        }
        assert_eq!(walked, scanned);
        let mut walked = Vec::new();
        for_each_cell(c, r, dynamic.inv_cell, |cell| {
            if let Some(list) = dynamic.cells.get(&cell) {
                walked.extend_from_slice(list);
            }
        });
        let mut cells: Vec<Cell> = dynamic.cells.keys().copied().collect();
        cells.sort_unstable();
        let visited: Vec<u32> = cells
            .into_iter()
            .filter(|&cell| ball_meets_cell(c, r, dynamic.inv_cell, cell))
            .flat_map(|cell| dynamic.cells[&cell].clone())
            .collect();
        assert_eq!(walked, visited);
        // Huge and infinite radii return at once with every point.
        for r in [1e30, f32::INFINITY] {
            let mut n = 0;
            grid.for_each_within(c, r, |_, _| n += 1);
            assert_eq!(n, pts.len());
            let mut n = 0;
            dynamic.for_each_candidate(c, r, |_| n += 1);
            assert_eq!(n, pts.len());
        }
    }
}
