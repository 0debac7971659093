//! Uniform hash grids for radius queries around sample points. Queries
//! visit cells in a fixed order and points within a cell in insertion
//! order, so nothing depends on hash-map iteration order.

use crate::rng::mix64;
use glam::Vec3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Integer cell coordinates. Hashing packs them into one word (21 bits an
/// axis); equality still compares all three, so a packing collision costs
/// time, never correctness.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
struct Cell([i32; 3]);

impl Cell {
    /// The coordinates as the packed key holds them (21 bits each).
    #[inline]
    fn packed_coordinates(&self) -> [u64; 3] {
        self.0.map(|c| c as u32 as u64 & 0x1F_FFFF)
    }

    #[inline]
    fn packed(&self) -> u64 {
        let [x, y, z] = self.packed_coordinates();
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

#[inline]
fn cell_of(p: Vec3, inv_cell: f32) -> Cell {
    let c = p * inv_cell;
    Cell([floor_to_i32(c.x), floor_to_i32(c.y), floor_to_i32(c.z)])
}

/// `v.floor() as i32` (saturating, NaN → 0) without the library call that
/// `floor` is on a baseline x86_64 target: truncate, then step down when
/// that rounded up.
#[inline]
fn floor_to_i32(v: f32) -> i32 {
    let t = v as i32;
    if (t as f32) > v { t.saturating_sub(1) } else { t }
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

/// One (x, y) column of the cells that meet a ball: the z range of the
/// ball's box, and the test of a z cell.
struct ColumnWalk {
    z_lo: i32,
    z_hi: i32,
    /// The squared gap from the centre to the column in x and y.
    gxy: f32,
    center_z: f32,
    cell: f32,
    r2: f32,
}

impl ColumnWalk {
    /// Whether cell z of this column meets the ball (same test as the
    /// full walk: within the box, and the summed gaps within `r²`).
    #[inline]
    fn meets(&self, z: i32) -> bool {
        self.z_lo <= z && z <= self.z_hi && self.gxy + axis_gap(self.center_z, z, self.cell) <= self.r2
    }
}

/// Calls `f(x, y, column)` for every (x, y) column of the box around the
/// ball of `radius` around `center` that the ball meets, in (x, y) order.
#[inline]
fn for_each_column(center: Vec3, radius: f32, inv_cell: f32, mut f: impl FnMut(i32, i32, &ColumnWalk)) {
    let lo = cell_of(center - Vec3::splat(radius), inv_cell).0;
    let hi = cell_of(center + Vec3::splat(radius), inv_cell).0;
    let cell = 1.0 / inv_cell;
    let r2 = radius * radius;
    for x in lo[0]..=hi[0] {
        let gx = axis_gap(center.x, x, cell);
        for y in lo[1]..=hi[1] {
            let gxy = gx + axis_gap(center.y, y, cell);
            if gxy > r2 {
                continue;
            }
            f(x, y, &ColumnWalk { z_lo: lo[2], z_hi: hi[2], gxy, center_z: center.z, cell, r2 });
        }
    }
}

/// Visits every cell that meets the ball of `radius` around `center`.
fn for_each_cell(center: Vec3, radius: f32, inv_cell: f32, mut f: impl FnMut(Cell)) {
    for_each_column(center, radius, inv_cell, |x, y, column| {
        for z in column.z_lo..=column.z_hi {
            if column.meets(z) {
                f(Cell([x, y, z]));
            }
        }
    });
}

/// A grid over a fixed point set, stored sorted by cell.
///
/// Cells are sorted by their packed key, which within the bounding box is
/// lexicographic (x, y, z) order, so the cells of one (x, y) column are
/// contiguous, in z order. A radius query looks each column of its box up
/// once (a dense table over the box's columns; a hash map when that table
/// would be large or a coordinate lies outside the packed range) and reads
/// the column's cells in the z range, instead of one hash lookup per cell.
#[derive(Clone, Debug)]
pub(crate) struct StaticGrid {
    origin: Vec3,
    inv_cell: f32,
    /// (x, y) → the index of its column in `column_start`.
    columns: ColumnIndex,
    /// Per occupied column, in cell order: its first cell id; then the cell count.
    column_start: Vec<u32>,
    /// Per cell id: its z coordinate.
    cell_z: Vec<i32>,
    /// Whether every cell lies within the packed range, so that the cells
    /// of a column are in z order.
    z_sorted: bool,
    /// Per cell id: its first slot; then the slot count.
    cell_start: Vec<u32>,
    /// Sorted slot → the caller's index.
    order: Vec<u32>,
    /// Positions in slot order.
    positions: Vec<Vec3>,
}

/// Where the grid finds an (x, y) column.
#[derive(Clone, Debug)]
enum ColumnIndex {
    /// Every column of the box `[0, nx) × [0, ny)`: the column's index, or
    /// `u32::MAX` when it is empty.
    Dense { nx: i32, ny: i32, ids: Vec<u32> },
    /// Occupied columns only, keyed by both coordinates.
    Hashed(HashMap<u64, u32, BuildHasherDefault<CellHasher>>),
}

/// Cells a side that the packed key tells apart.
const PACKED_CELLS: f32 = (1u32 << 21) as f32;

/// A dense column table is used when it has at most this many entries per
/// point (or [`DENSE_COLUMNS_MIN`]).
const DENSE_COLUMNS_PER_POINT: u64 = 4;
const DENSE_COLUMNS_MIN: u64 = 1 << 16;

/// Whether a cell coordinate is one the packed key holds as it is.
#[inline]
fn in_packed_range(c: i32) -> bool {
    (0..PACKED_CELLS as i32).contains(&c)
}

#[inline]
fn column_key(x: i32, y: i32) -> u64 {
    ((x as u32 as u64) << 32) | y as u32 as u64
}

/// The indices `0..keys.len()` sorted stably by `keys`: a least significant
/// digit first radix sort over the bits the largest key uses, in as few
/// passes as digits of up to `log2(8 n)` bits (at least 11) allow, so a
/// grid's renumbered cell keys usually take one counting pass.
fn stable_order_by_key(keys: &[u64]) -> Vec<u32> {
    let bits = u64::BITS - keys.iter().copied().max().unwrap_or(0).leading_zeros();
    let widest = (u64::BITS - 1 - (8 * keys.len() as u64).max(1).leading_zeros()).clamp(11, 24);
    let passes = bits.div_ceil(widest);
    let digit_bits = if passes == 0 { 0 } else { bits.div_ceil(passes) };
    let mask = (1u64 << digit_bits) - 1;
    let mut pairs: Vec<(u64, u32)> = keys.iter().enumerate().map(|(i, &k)| (k, i as u32)).collect();
    let mut next = vec![(0u64, 0u32); keys.len()];
    let mut counts = vec![0u32; 1 << digit_bits];
    for pass in 0..passes {
        let shift = pass * digit_bits;
        let digit = |k: u64| ((k >> shift) & mask) as usize;
        counts.fill(0);
        for &(k, _) in &pairs {
            counts[digit(k)] += 1;
        }
        let mut sum = 0;
        for c in counts.iter_mut() {
            (*c, sum) = (sum, sum + *c);
        }
        for &pair in &pairs {
            let slot = &mut counts[digit(pair.0)];
            next[*slot as usize] = pair;
            *slot += 1;
        }
        std::mem::swap(&mut pairs, &mut next);
    }
    pairs.into_iter().map(|(_, i)| i).collect()
}

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
        // The sort runs on the packed coordinates renumbered densely, in the
        // same order: (x · ny + y) · nz + z.
        let cells: Vec<Cell> = positions.par_iter().map(|&p| cell_of(p - origin, inv_cell)).collect();
        let dims = cells.iter().fold([0u64; 3], |n, c| {
            let p = c.packed_coordinates();
            [n[0].max(p[0] + 1), n[1].max(p[1] + 1), n[2].max(p[2] + 1)]
        });
        let keys: Vec<u64> = cells
            .par_iter()
            .map(|c| {
                let [x, y, z] = c.packed_coordinates();
                (x * dims[1] + y) * dims[2] + z
            })
            .collect();
        let order = stable_order_by_key(&keys);
        let (mut column_start, mut cell_z, mut cell_start) = (Vec::new(), Vec::new(), Vec::new());
        let mut column_cells: Vec<(i32, i32)> = Vec::new();
        let mut z_sorted = true;
        let mut start = 0;
        while start < order.len() {
            let key = keys[order[start] as usize];
            let mut end = start + 1;
            while end < order.len() && keys[order[end] as usize] == key {
                end += 1;
            }
            let [x, y, z] = cells[order[start] as usize].0;
            z_sorted &= [x, y, z].iter().all(|&c| in_packed_range(c));
            if column_cells.last() != Some(&(x, y)) {
                column_cells.push((x, y));
                column_start.push(cell_z.len() as u32);
            }
            cell_z.push(z);
            cell_start.push(start as u32);
            start = end;
        }
        column_start.push(cell_z.len() as u32);
        cell_start.push(order.len() as u32);
        let columns = Self::column_index(&column_cells, positions.len(), z_sorted);
        let positions = order.par_iter().map(|&i| positions[i as usize]).collect();
        Self { origin, inv_cell, columns, column_start, cell_z, z_sorted, cell_start, order, positions }
    }

    /// The column table over `column_cells` (occupied columns in cell
    /// order); dense only when every cell is `in_range`.
    fn column_index(column_cells: &[(i32, i32)], points: usize, in_range: bool) -> ColumnIndex {
        let (nx, ny) = column_cells.iter().fold((0, 0), |(nx, ny), &(x, y)| (nx.max(x + 1), ny.max(y + 1)));
        let dense_limit = (DENSE_COLUMNS_PER_POINT * points as u64).max(DENSE_COLUMNS_MIN);
        if in_range && nx as u64 * ny as u64 <= dense_limit {
            let mut ids = vec![u32::MAX; nx as usize * ny as usize];
            for (c, &(x, y)) in column_cells.iter().enumerate() {
                ids[x as usize * ny as usize + y as usize] = c as u32;
            }
            ColumnIndex::Dense { nx, ny, ids }
        } else {
            ColumnIndex::Hashed(
                column_cells.iter().enumerate().map(|(c, &(x, y))| (column_key(x, y), c as u32)).collect(),
            )
        }
    }

    /// The column index of (x, y), if occupied.
    #[inline]
    fn column(&self, x: i32, y: i32) -> Option<u32> {
        match &self.columns {
            ColumnIndex::Dense { nx, ny, ids } => {
                if x < 0 || y < 0 || x >= *nx || y >= *ny {
                    return None;
                }
                let id = ids[x as usize * *ny as usize + y as usize];
                (id != u32::MAX).then_some(id)
            }
            ColumnIndex::Hashed(map) => map.get(&column_key(x, y)).copied(),
        }
    }

    /// Number of occupied cells (cell ids are `0..cell_count()`).
    pub(crate) fn cell_count(&self) -> usize {
        self.cell_z.len()
    }

    /// Per slot, the id of its cell.
    pub(crate) fn slot_cells(&self) -> Vec<u32> {
        let mut out = vec![0u32; self.positions.len()];
        for (id, span) in self.cell_start.windows(2).enumerate() {
            out[span[0] as usize..span[1] as usize].fill(id as u32);
        }
        out
    }

    /// Calls `f(cell id, first slot, positions)` for cell `id`.
    #[inline]
    fn visit(&self, id: usize, f: &mut impl FnMut(u32, u32, &[Vec3])) {
        let (a, b) = (self.cell_start[id], self.cell_start[id + 1]);
        f(id as u32, a, &self.positions[a as usize..b as usize]);
    }

    /// Calls `f(cell id, first slot, positions)` for every occupied cell
    /// that meets the ball of `radius` around `center` (every occupied cell
    /// when the radius is huge against the cell), in slot order; the caller
    /// tests the distances. Lets a caller skip a cell it knows to be empty
    /// of what it looks for.
    #[inline]
    pub(crate) fn for_each_cell_within(&self, center: Vec3, radius: f32, mut f: impl FnMut(u32, u32, &[Vec3])) {
        let center = center - self.origin;
        // A radius huge against the cell (spacing multipliers far apart)
        // would walk more cells than there are points: visit the occupied
        // cells instead. Slots are sorted by cell in the walk's (x, y, z)
        // order, so the calls come in the same order either way.
        if box_cell_count(center, radius, self.inv_cell) > self.positions.len() as f64 {
            for id in 0..self.cell_count() {
                self.visit(id, &mut f);
            }
            return;
        }
        // The cells `for_each_cell` would walk, with the same tests, looked
        // up a column at a time.
        for_each_column(center, radius, self.inv_cell, |x, y, walk| {
            let Some(column) = self.column(x, y) else { return };
            let (a, b) = (self.column_start[column as usize] as usize, self.column_start[column as usize + 1] as usize);
            if self.z_sorted {
                let first = a + self.cell_z[a..b].partition_point(|&z| z < walk.z_lo);
                for id in first..b {
                    if self.cell_z[id] > walk.z_hi {
                        break;
                    }
                    if walk.meets(self.cell_z[id]) {
                        self.visit(id, &mut f);
                    }
                }
            } else {
                (a..b).filter(|&id| walk.meets(self.cell_z[id])).for_each(|id| self.visit(id, &mut f));
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
#[path = "grid_tests.rs"]
mod tests;
