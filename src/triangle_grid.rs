//! A uniform grid over triangle bounding boxes ([`TriangleGrid`]): box
//! queries, ray casts and closest points over any set of triangles, with
//! the exact ray–triangle and point–triangle tests they use. The body
//! index ([`crate::body::BodyIndex`]) and the validation's feather grids
//! are built on it; it is rebuilt every frame into the same buffers.
//!
//! A triangle is listed in every cell its bounding box touches. Box queries
//! report each triangle once without sorting: a triangle found in cell `c`
//! is reported only when `c` is the first cell shared by the query box and
//! the triangle's box (the per-axis maximum of their lowest cells), which
//! every overlapping pair has exactly one of. Query results are therefore in
//! a fixed order (cell order, then triangle index) that never depends on
//! threads.

use crate::csr::Csr;
use glam::{DVec3, Vec3};

/// At most this many cells along one axis.
const MAX_CELLS_PER_AXIS: usize = 1024;
/// At most this many cells in all (keeps the start table small).
const MAX_CELLS: usize = 1 << 22;

/// Axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lowest corner.
    pub min: Vec3,
    /// Highest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box of a triangle.
    #[inline]
    pub fn of_triangle(t: &[Vec3; 3]) -> Self {
        Self { min: t[0].min(t[1]).min(t[2]), max: t[0].max(t[1]).max(t[2]) }
    }

    /// The box of the segment from `a` to `b`.
    #[inline]
    pub fn of_segment(a: Vec3, b: Vec3) -> Self {
        Self { min: a.min(b), max: a.max(b) }
    }

    /// The box around a point with half size `r` on every axis.
    #[inline]
    pub fn around(p: Vec3, r: f32) -> Self {
        Self { min: p - Vec3::splat(r), max: p + Vec3::splat(r) }
    }

    /// Distance from `p` to the closed box (0 inside).
    #[inline]
    pub fn distance_to(&self, p: Vec3) -> f32 {
        (self.min - p).max(p - self.max).max(Vec3::ZERO).length()
    }

    /// Whether the box is a single point (a collapsed triangle's).
    #[inline]
    pub fn is_point(&self) -> bool {
        self.min == self.max
    }

    /// Whether two closed boxes share a point.
    #[inline]
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }

    /// The smallest box holding both.
    #[inline]
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb { min: self.min.min(other.min), max: self.max.max(other.max) }
    }
}

/// A uniform grid over a set of triangles, for box queries, ray casts and
/// closest-point searches. Rebuilding reuses every buffer.
#[derive(Debug, Default)]
pub struct TriangleGrid {
    corners: Vec<[Vec3; 3]>,
    boxes: Vec<Aabb>,
    /// The cell holding each triangle box's lowest corner, packed (see
    /// [`pack_cell`]).
    low_cells: Vec<u64>,
    origin: Vec3,
    cell: f32,
    inv_cell: f32,
    dims: [usize; 3],
    /// The triangles listed in each cell (by linear cell index).
    cells: Csr<u32>,
    /// Beside each listed triangle (same place as in `cells`), its box and
    /// lowest cell, so that a query reads them in a row.
    entries: Vec<CellEntry>,
}

/// What a box query reads of a triangle listed in a cell.
#[derive(Clone, Copy, Debug)]
struct CellEntry {
    bounds: Aabb,
    low: u64,
}

/// One axis of a packed cell: cell coordinates stay below
/// `MAX_CELLS_PER_AXIS`, far within 16 bits.
const CELL_FIELD: u64 = 0xffff;

/// A cell's coordinates in one word, 16 bits each (x lowest).
#[inline]
fn pack_cell(c: [usize; 3]) -> u64 {
    (c[0] as u64 & CELL_FIELD) | (c[1] as u64 & CELL_FIELD) << 16 | (c[2] as u64 & CELL_FIELD) << 32
}

/// The coordinates [`pack_cell`] packed.
#[inline]
fn unpack_cell(p: u64) -> [usize; 3] {
    [(p & CELL_FIELD) as usize, (p >> 16 & CELL_FIELD) as usize, (p >> 32 & CELL_FIELD) as usize]
}

/// A ray's nearest hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance along the (unit) ray direction.
    pub t: f32,
    /// The triangle hit.
    pub triangle: u32,
}

/// The point of a triangle set nearest to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClosestPoint {
    /// Distance from the query point.
    pub distance: f32,
    /// The triangle holding the nearest point.
    pub triangle: u32,
    /// The nearest point.
    pub point: Vec3,
}

impl TriangleGrid {
    /// An empty grid (no allocation until the first rebuild).
    pub fn new() -> Self {
        Self::default()
    }

    /// Rebuilds the grid over `triangles`. `cell_size` fixes the cell edge;
    /// `None` picks one from the triangles (about their mean extent, or
    /// coarser when the bounding volume would need too many cells).
    pub fn rebuild(&mut self, triangles: impl IntoIterator<Item = [Vec3; 3]>, cell_size: Option<f32>) {
        self.corners.clear();
        self.corners.extend(triangles);
        self.boxes.clear();
        self.boxes.extend(self.corners.iter().map(Aabb::of_triangle));
        self.place_cells(cell_size);
        self.fill_cells();
    }

    /// Number of triangles indexed.
    pub fn len(&self) -> usize {
        self.corners.len()
    }

    /// Whether no triangle is indexed.
    pub fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }

    /// The corners of triangle `t`.
    #[inline]
    pub fn corners(&self, t: u32) -> [Vec3; 3] {
        self.corners[t as usize]
    }

    /// The bounding box of triangle `t`.
    #[inline]
    pub fn bounds(&self, t: u32) -> Aabb {
        self.boxes[t as usize]
    }

    /// All triangle corners, by index.
    pub fn all_corners(&self) -> &[[Vec3; 3]] {
        &self.corners
    }

    /// Edge length of a cell.
    pub fn cell_size(&self) -> f32 {
        self.cell
    }

    /// Cells along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Chooses origin, cell size and dimensions.
    fn place_cells(&mut self, cell_size: Option<f32>) {
        let Some(bounds) = self.boxes.iter().copied().reduce(|a, b| a.union(&b)) else {
            self.origin = Vec3::ZERO;
            self.cell = 1.0;
            self.inv_cell = 1.0;
            self.dims = [1, 1, 1];
            return;
        };
        let extent = (bounds.max - bounds.min).max(Vec3::splat(0.0));
        let diag = extent.length().max(f32::MIN_POSITIVE.sqrt());
        let mut cell = match cell_size {
            Some(c) if c.is_finite() && c > 0.0 => c,
            _ => {
                let n = self.boxes.len() as f64;
                let mean_extent =
                    self.boxes.iter().map(|b| (b.max - b.min).max_element() as f64).sum::<f64>() / n.max(1.0);
                let volume_cell = ((extent.x as f64 * extent.y as f64 * extent.z as f64) / n.max(1.0)).cbrt();
                mean_extent.max(volume_cell) as f32
            }
        };
        cell = cell.max(diag * 1e-6);
        loop {
            let dims = extent.to_array().map(|e| ((e / cell).floor() as usize + 1).max(1));
            if dims.iter().all(|&d| d <= MAX_CELLS_PER_AXIS) && dims.iter().product::<usize>() <= MAX_CELLS {
                self.dims = dims;
                break;
            }
            cell *= 1.5;
        }
        self.origin = bounds.min;
        self.cell = cell;
        self.inv_cell = 1.0 / cell;
    }

    /// Counting sort of triangles into the cells their boxes touch.
    fn fill_cells(&mut self) {
        let ncell = self.dims.iter().product::<usize>();
        self.low_cells.clear();
        for k in 0..self.boxes.len() {
            let lo = self.cell_of(self.boxes[k].min);
            self.low_cells.push(pack_cell(lo));
        }
        self.cells.begin(ncell);
        for b in &self.boxes {
            let (lo, hi) = (self.cell_of(b.min), self.cell_of(b.max));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        self.cells.count(self.cell_index([x, y, z]));
                    }
                }
            }
        }
        self.cells.allocate();
        for (t, b) in self.boxes.iter().enumerate() {
            let (lo, hi) = (self.cell_of(b.min), self.cell_of(b.max));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        self.cells.place(self.cell_index([x, y, z]), t as u32);
                    }
                }
            }
        }
        self.entries.clear();
        let (boxes, low_cells) = (&self.boxes, &self.low_cells);
        self.entries.extend(
            self.cells.items().iter().map(|&t| CellEntry { bounds: boxes[t as usize], low: low_cells[t as usize] }),
        );
    }

    /// The cell holding `p`, clamped to the grid.
    #[inline]
    pub fn cell_of(&self, p: Vec3) -> [usize; 3] {
        let q = (p - self.origin) * self.inv_cell;
        let clamp = |v: f32, d: usize| {
            if v.is_nan() || v <= 0.0 { 0 } else { (v as usize).min(d - 1) }
        };
        [clamp(q.x, self.dims[0]), clamp(q.y, self.dims[1]), clamp(q.z, self.dims[2])]
    }

    #[inline]
    fn cell_index(&self, c: [usize; 3]) -> usize {
        (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]
    }

    /// The triangles listed in one cell (by linear cell index).
    #[inline]
    pub fn cell_items(&self, cell: usize) -> &[u32] {
        self.cells.row(cell)
    }

    /// Number of cells.
    pub fn cell_count(&self) -> usize {
        self.dims.iter().product()
    }

    /// The first cell (linear index) that the boxes of triangles `a` and
    /// `b` share if they overlap: the per-axis maximum of their lowest
    /// cells. Used to report each overlapping pair from exactly one cell.
    #[inline]
    pub fn first_shared_cell(&self, a: u32, b: u32) -> usize {
        let (la, lb) = (unpack_cell(self.low_cells[a as usize]), unpack_cell(self.low_cells[b as usize]));
        self.cell_index([0, 1, 2].map(|k| la[k].max(lb[k])))
    }

    /// Appends to `out` (after clearing it) every triangle whose bounding
    /// box overlaps `query`, each once, in a fixed order.
    pub fn query_box(&self, query: &Aabb, out: &mut Vec<u32>) {
        out.clear();
        if self.corners.is_empty() || !query.min.cmple(query.max).all() {
            return;
        }
        let (lo, hi) = (self.cell_of(query.min), self.cell_of(query.max));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let c = self.cell_index([x, y, z]);
                    // Report from the first cell shared with the query: per
                    // axis, max(low, lo) is this cell's coordinate. A
                    // triangle listed here has low ≤ it, so on an axis where
                    // the cell is the query's lowest that always holds, and
                    // elsewhere low must equal it: one masked comparison of
                    // the packed coordinates.
                    let axes = [x > lo[0], y > lo[1], z > lo[2]];
                    let mask = pack_cell(axes.map(|a| if a { CELL_FIELD as usize } else { 0 }));
                    let here = pack_cell([x, y, z]);
                    let span = self.cells.span(c);
                    for (&t, e) in self.cells.items()[span.clone()].iter().zip(&self.entries[span]) {
                        if (e.low ^ here) & mask == 0 && e.bounds.overlaps(query) {
                            out.push(t);
                        }
                    }
                }
            }
        }
    }

    /// The nearest hit of the ray `origin + t·dir` (`dir` unit), `0 < t ≤
    /// t_max`, where `hit(triangle)` gives the ray parameter of a hit or
    /// `None`. Walks the cells the ray crosses (3-D DDA) and stops once the
    /// best hit lies before the next cell.
    pub fn ray_cast(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut hit: impl FnMut(u32) -> Option<f32>,
    ) -> Option<RayHit> {
        if self.corners.is_empty() || t_max <= 0.0 || t_max.is_nan() || !origin.is_finite() || !dir.is_finite() {
            return None;
        }
        let (t_enter, t_exit) = self.ray_span_in_grid(origin, dir, t_max)?;
        let start = origin + dir * t_enter;
        let mut cell = self.cell_of(start).map(|c| c as i64);
        let mut step = [0i64; 3];
        let mut t_next = [f32::INFINITY; 3];
        let mut t_delta = [f32::INFINITY; 3];
        for a in 0..3 {
            let d = dir[a];
            if d > 0.0 {
                step[a] = 1;
                let boundary = self.origin[a] + (cell[a] + 1) as f32 * self.cell;
                t_next[a] = (boundary - origin[a]) / d;
                t_delta[a] = self.cell / d;
            } else if d < 0.0 {
                step[a] = -1;
                let boundary = self.origin[a] + cell[a] as f32 * self.cell;
                t_next[a] = (boundary - origin[a]) / d;
                t_delta[a] = -self.cell / d;
            }
        }
        let mut best: Option<RayHit> = None;
        loop {
            let c = self.cell_index([cell[0] as usize, cell[1] as usize, cell[2] as usize]);
            for &t in self.cell_items(c) {
                if let Some(s) = hit(t)
                    && s > 0.0
                    && s <= t_max
                    && best.is_none_or(|b| s < b.t || (s == b.t && t < b.triangle))
                {
                    best = Some(RayHit { t: s, triangle: t });
                }
            }
            let axis = if t_next[0] <= t_next[1] && t_next[0] <= t_next[2] {
                0
            } else if t_next[1] <= t_next[2] {
                1
            } else {
                2
            };
            let leave = t_next[axis];
            if best.is_some_and(|b| b.t <= leave) || leave > t_exit {
                return best;
            }
            cell[axis] += step[axis];
            if cell[axis] < 0 || cell[axis] >= self.dims[axis] as i64 {
                return best;
            }
            t_next[axis] += t_delta[axis];
        }
    }

    /// The parameter interval where the ray is inside the grid's box.
    fn ray_span_in_grid(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(f32, f32)> {
        let lo = self.origin;
        let hi = self.origin + Vec3::new(self.dims[0] as f32, self.dims[1] as f32, self.dims[2] as f32) * self.cell;
        let (mut t0, mut t1) = (0.0f32, t_max);
        for a in 0..3 {
            if dir[a] == 0.0 {
                if origin[a] < lo[a] || origin[a] > hi[a] {
                    return None;
                }
            } else {
                let (mut ta, mut tb) = ((lo[a] - origin[a]) / dir[a], (hi[a] - origin[a]) / dir[a]);
                if ta > tb {
                    std::mem::swap(&mut ta, &mut tb);
                }
                t0 = t0.max(ta);
                t1 = t1.min(tb);
            }
        }
        (t0 <= t1).then_some((t0, t1))
    }

    /// The nearest point of any triangle within `max_distance` of `p`.
    /// Ties go to the lower triangle index.
    pub fn closest_point(&self, p: Vec3, max_distance: f32, scratch: &mut Vec<u32>) -> Option<ClosestPoint> {
        self.query_box(&Aabb::around(p, max_distance), scratch);
        let mut best: Option<ClosestPoint> = None;
        for &t in scratch.iter() {
            let q = closest_point_on_triangle(p, self.corners[t as usize]);
            let d = (q - p).length();
            if d <= max_distance && best.is_none_or(|b| d < b.distance || (d == b.distance && t < b.triangle)) {
                best = Some(ClosestPoint { distance: d, triangle: t, point: q });
            }
        }
        best
    }

    /// As [`closest_point`](Self::closest_point), also leaving in
    /// `distances[k]` the distance of `scratch[k]`'s nearest point, as
    /// `closest_point` measures it, for every triangle that may lie within
    /// `keep(best)` of `p` (`best` the smallest distance found so far;
    /// `keep` must not decrease as `best` grows); the others, which a box
    /// test puts farther than that, get `f32::INFINITY` without their
    /// nearest point being computed. The same answer as `closest_point`.
    pub fn closest_point_keeping(
        &self,
        p: Vec3,
        max_distance: f32,
        keep: impl Fn(f32) -> f32,
        scratch: &mut Vec<u32>,
        distances: &mut Vec<f32>,
    ) -> Option<ClosestPoint> {
        self.query_box(&Aabb::around(p, max_distance), scratch);
        distances.clear();
        let mut best: Option<ClosestPoint> = None;
        // The box's distance is a lower bound of the computed one up to
        // the rounding of the nearest point (f64, stored as f32), which
        // this margin covers many times over.
        let margin = 1e-5 * p.abs().max_element();
        for &t in scratch.iter() {
            let bound = keep(best.map_or(max_distance, |b| b.distance));
            if self.boxes[t as usize].distance_to(p) > bound * (1.0 + 1e-5) + margin {
                distances.push(f32::INFINITY);
                continue;
            }
            let q = closest_point_on_triangle(p, self.corners[t as usize]);
            let d = (q - p).length();
            distances.push(d);
            if d <= max_distance && best.is_none_or(|b| d < b.distance || (d == b.distance && t < b.triangle)) {
                best = Some(ClosestPoint { distance: d, triangle: t, point: q });
            }
        }
        best
    }
}

/// The parameter `t > 0` where the ray `origin + t·dir` crosses the closed
/// triangle, or `None` (parallel, behind, or outside). Computed in f64
/// (Möller–Trumbore).
pub fn ray_triangle(origin: Vec3, dir: Vec3, tri: [Vec3; 3]) -> Option<f32> {
    let (o, d) = (origin.as_dvec3(), dir.as_dvec3());
    let [a, b, c] = tri.map(|v| v.as_dvec3());
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    let scale = e1.length() * e2.length() * d.length();
    if det.abs() <= 1e-12 * scale || scale == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t as f32)
}

/// The point of the closed triangle nearest to `p` (Ericson, "Real-Time
/// Collision Detection" §5.1.5), computed in f64.
pub fn closest_point_on_triangle(p: Vec3, tri: [Vec3; 3]) -> Vec3 {
    let p = p.as_dvec3();
    let [a, b, c] = tri.map(|v| v.as_dvec3());
    closest_point_f64(p, a, b, c).as_vec3()
}

fn closest_point_f64(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = va + vb + vc;
    if denom == 0.0 {
        // Degenerate triangle: fall back to the nearest corner.
        return [a, b, c]
            .into_iter()
            .min_by(|x, y| (*x - p).length_squared().total_cmp(&(*y - p).length_squared()))
            .unwrap_or(a);
    }
    let (v, w) = (vb / denom, vc / denom);
    a + ab * v + ac * w
}

crate::memory::clone_by_fields!(TriangleGrid {
    corners,
    boxes,
    low_cells,
    origin,
    cell,
    inv_cell,
    dims,
    cells,
    entries
});
crate::memory::heap_size_of_fields!(TriangleGrid { corners, boxes, low_cells, cells, entries } plain { origin, cell, inv_cell, dims });

#[cfg(test)]
#[path = "triangle_grid_tests.rs"]
mod tests;
