//! The height field of one feather: a grid in the feather's root frame over
//! its flat footprint, holding the highest obstacle top above each cell.
//!
//! Layout. x (along `õ`) spans `[0, L + dx]` in `u` columns with
//! `dx = L/(u − 1)`; y (along `b`) spans `[−W/2 − dy, W/2 + dy]` in `v` rows
//! with `dy = W/(v − 2)`. The one-cell margin beyond the tip and the vane
//! corners catches obstacles the posed feather reaches when cell bounds
//! are rounded outward. Nothing lies behind the root: for any pitch below
//! 90° the feather never covers x < 0.
//!
//! Two layers, because the steps treat them differently:
//! - `obstacle`: tops of earlier feathers (their triangles raised by their
//!   thickness along this feather's normal). The collision allowance of the
//!   fine-pitch step lets the feather sink into these only.
//! - `body`: the skin near the root. Only triangles facing this feather's
//!   side count (face normal · n > −0.3): concave skin rising in front of the
//!   root, walls and the skin under the vanes are kept; the far skin of a
//!   thin wing or a downward overhang, which a height field cannot
//!   represent, are left out.
//!
//! What is ignored. Cells start at a floor below the tangent plane (half a
//! feather length, or deeper when the lowest pitch needs it); geometry
//! entirely below it cannot bind any allowed pitch, so it is skipped: the
//! other skin of a thin wing and feathers lying under the body never reach
//! the field. The floor also bounds the free volume used by the roll step.
//!
//! Rasterisation is conservative: a cell takes the highest point of the
//! triangle's plane over the whole cell (plane height at the centre plus the
//! slope times half the cell), capped by the triangle's highest corner, in
//! every cell the triangle might touch (edge tests against the cell's most
//! inside corner). Nearly vertical triangles (in the feather's frame) put
//! their highest corner in every cell of their bounding box.

use super::raster::{LocalMap, SPAN_ROWS, TrianglePlane, floor_i32, index_f32, max3, min3, raise_row};
use crate::body::{Aabb, BodyIndex};
use crate::feather::{FeatherShape, FeatherTriangles};
use crate::geometry::RootFrame;
use crate::validation::BodyScratch;
use glam::{Vec2, Vec3};

/// Body triangles whose unit normal has a smaller component along the
/// feather's normal are left out (they face away: far skin, overhangs).
const BODY_FACING_MIN: f32 = -0.3;
/// The first body search reaches this many feather lengths above the
/// tangent plane (see [`HeightField::add_body`]).
const SKIN_BAND_PER_LENGTH: f32 = 0.3;
/// The floor lies at least this many feather lengths below the tangent plane.
const FLOOR_DEPTH_PER_LENGTH: f32 = 0.5;
/// The root socket: the first 2.5 % of the shaft, where the feather enters
/// the skin. Nothing there is rasterised and heights just beyond it are
/// judged at its end, so the skin around the root (which rises through
/// rounding and normal interpolation) cannot stand the feather up.
/// Validation tolerates body crossings within 5 % of the length.
pub(crate) const SOCKET_FRACTION: f32 = 0.025;

/// Heights nearer the root than this fraction of the length are judged at
/// this distance (see [`HeightField::reset`]).
pub(crate) const JUDGE_FRACTION: f32 = 0.08;

/// Where the grid of a shape lies in the root frame (see the module notes):
/// cell sizes, the far end along the shaft (`x ≤ far`), the half span
/// across (`|y| ≤ half_span`) and the floor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GridExtent {
    pub(crate) dx: f32,
    pub(crate) dy: f32,
    pub(crate) far: f32,
    pub(crate) half_span: f32,
    pub(crate) floor: f32,
}

impl GridExtent {
    /// The extent [`HeightField::reset`] lays for `shape` at resolution
    /// `(u, v)` (as [`HeightField::set_resolution`] clamps it).
    pub(crate) fn new(shape: &FeatherShape, u: usize, v: usize, min_pitch: f32) -> Self {
        let (l, w) = (shape.length, shape.width);
        let dx = l / (u.max(2) - 1) as f32;
        let dy = w / (v.max(3) - 2) as f32;
        let droop = l * (-min_pitch).max(0.0).tan() + 0.5 * w;
        let floor = -(FLOOR_DEPTH_PER_LENGTH * l).max(droop);
        Self { dx, dy, far: l + dx, half_span: 0.5 * w + dy, floor }
    }
}

/// Which layer a triangle goes into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Layer {
    Obstacle,
    Body,
}

/// Scratch and result of one feather's rasterisation. Reused from feather
/// to feather: after the first use at a given resolution nothing allocates.
#[derive(Clone, Debug)]
pub struct HeightField {
    pub(crate) u: usize,
    pub(crate) v: usize,
    pub(crate) dx: f32,
    pub(crate) dy: f32,
    pub(crate) y_min: f32,
    pub(crate) floor: f32,
    /// End of the root socket along the shaft.
    pub(crate) socket_x: f32,
    /// Skin below this height cannot bind any allowed pitch.
    pub(crate) body_floor: f32,
    /// `JUDGE_FRACTION` of the length the grid was laid for: the body's
    /// clearance angle is always taken from this distance on (see
    /// `combine_heights`), whatever distance the steps judge at.
    pub(crate) clearance_from: f32,
    pub(crate) shape: FeatherShape,
    /// Obstacle tops per cell, `j·u + i` (row j across, column i along).
    pub(crate) obstacle: Vec<f32>,
    /// Body heights per cell.
    pub(crate) body: Vec<f32>,
    /// Combined height each step must clear (scratch of the steps).
    pub(crate) need: Vec<f32>,
    /// The body slope and obstacle lift `need` was combined with, while
    /// neither layer has changed since (see `combine_heights`).
    pub(crate) need_for: Option<(f32, f32)>,
    /// Column centres (x) and row centres (y).
    pub(crate) col_x: Vec<f32>,
    pub(crate) row_y: Vec<f32>,
    /// Per column: the near edge (not before the socket's end) and the far
    /// edge along the shaft, and their reciprocals.
    pub(crate) col_near: Vec<f32>,
    pub(crate) col_far: Vec<f32>,
    pub(crate) inv_near: Vec<f32>,
    pub(crate) inv_far: Vec<f32>,
    /// First column reaching past the socket (earlier ones are ignored).
    pub(crate) first_col: usize,
    /// Per-row shaft interval covered by the kite (scratch of the steps).
    pub(crate) row_span: Vec<[f32; 2]>,
    /// Scratch of the body queries and of the exact body test of a
    /// chosen pose.
    pub(crate) body_scratch: BodyScratch,
    /// Scratch of the exact checks of one feather: its obstacles' boxes
    /// when the caller gives none.
    pub(crate) boxes: Vec<super::obstacle::ObstacleBoxes>,
    /// The outer boxes of `boxes`, in its order.
    pub(crate) bounds: Vec<super::obstacle::ObstacleBounds>,
    /// The obstacles within reach of one size of the exact pitch sweep.
    pub(crate) sweep_obstacles: Vec<u32>,
    /// The rasterised obstacles' triangles in the root frame (kept for
    /// the refills of one feather's smaller sizes).
    pub(crate) local_obstacles: Vec<FeatherTriangles>,
    /// The obstacles' and the skin's triangles in the roll frame (scratch
    /// of the swept drape, see `sweep::fill_swept_triangles`).
    pub(crate) swept: Vec<super::sweep::SweptTriangle>,
    /// The skin triangles rasterised into the body layer, in the root
    /// frame, kept for a segmented feather's drape.
    pub(crate) local_body: Vec<[Vec3; 3]>,
}

/// The skin triangles under one feather the drape's scratch makes room for
/// up front ([`HeightField::reserve_drape`]); a feather over more grows it.
const DRAPE_SKIN_ROOM: usize = 4096;

impl HeightField {
    /// Room for the drape of a feather with up to `obstacles` obstacles
    /// over up to `skin` skin triangles (at most [`DRAPE_SKIN_ROOM`]): the
    /// scratch a drape fills is sized by the geometry it meets, and
    /// feathers draped rarely (an incremental step keeps most in place)
    /// would otherwise reach its largest size only after many frames.
    pub(crate) fn reserve_drape(&mut self, obstacles: usize, skin: usize) {
        let skin = skin.min(DRAPE_SKIN_ROOM);
        let swept = obstacles * crate::feather::MAX_TRIANGLES + skin;
        self.local_obstacles.reserve(obstacles.saturating_sub(self.local_obstacles.len()));
        self.local_body.reserve(skin.saturating_sub(self.local_body.len()));
        self.swept.reserve(swept.saturating_sub(self.swept.len()));
    }

    /// A field of `u` cells along the shaft and `v` across (at least 2 and 3).
    pub fn new(u: usize, v: usize) -> Self {
        let mut f = Self {
            u: 0,
            v: 0,
            dx: 1.0,
            dy: 1.0,
            y_min: 0.0,
            floor: -1.0,
            socket_x: 0.0,
            body_floor: -1.0,
            clearance_from: 0.0,
            shape: FeatherShape { length: 1.0, width: 1.0, thickness: 0.0, vane_split: 0.5, segments: 1 },
            obstacle: Vec::new(),
            body: Vec::new(),
            need: Vec::new(),
            need_for: None,
            col_x: Vec::new(),
            row_y: Vec::new(),
            col_near: Vec::new(),
            col_far: Vec::new(),
            inv_near: Vec::new(),
            inv_far: Vec::new(),
            first_col: 0,
            row_span: Vec::new(),
            body_scratch: BodyScratch::default(),
            boxes: Vec::new(),
            bounds: Vec::new(),
            sweep_obstacles: Vec::new(),
            local_obstacles: Vec::new(),
            swept: Vec::new(),
            local_body: Vec::new(),
        };
        f.set_resolution(u, v);
        f
    }

    /// Cells along the shaft.
    pub fn columns(&self) -> usize {
        self.u
    }

    /// Cells across the vanes.
    pub fn rows(&self) -> usize {
        self.v
    }

    /// Changes the resolution (allocates only when it grows).
    pub fn set_resolution(&mut self, u: usize, v: usize) {
        let (u, v) = (u.max(2), v.max(3));
        if (u, v) == (self.u, self.v) {
            return;
        }
        self.u = u;
        self.v = v;
        self.need_for = None;
        for layer in [&mut self.obstacle, &mut self.body, &mut self.need] {
            layer.resize(u * v, 0.0);
        }
        for col in [&mut self.col_x, &mut self.col_near, &mut self.col_far, &mut self.inv_near, &mut self.inv_far] {
            col.resize(u, 0.0);
        }
        self.row_y.resize(v, 0.0);
        self.row_span.resize(v, [0.0; 2]);
    }

    /// Clears both layers to the floor and lays the grid over `shape`'s
    /// footprint. `min_pitch` (radians, ≤ 0) deepens the floor when needed.
    pub fn reset(&mut self, shape: &FeatherShape, min_pitch: f32) {
        self.shape = *shape;
        let l = shape.length;
        let grid = GridExtent::new(shape, self.u, self.v, min_pitch);
        (self.dx, self.dy, self.floor) = (grid.dx, grid.dy, grid.floor);
        self.y_min = -grid.half_span;
        self.socket_x = SOCKET_FRACTION * l;
        self.body_floor = self.floor.max(-(l + self.dx) * (-min_pitch).max(0.0).tan() - self.dy);
        self.obstacle.fill(self.floor);
        self.body.fill(self.floor);
        self.need_for = None;
        for i in 0..self.u {
            let x = (i as f32 + 0.5) * self.dx;
            self.col_x[i] = x;
            self.col_far[i] = x + 0.5 * self.dx;
            self.inv_far[i] = 1.0 / self.col_far[i];
        }
        self.clearance_from = JUDGE_FRACTION * l;
        self.set_judge_fraction(JUDGE_FRACTION, l);
        self.first_col = (0..self.u).find(|&i| self.col_far[i] > self.socket_x).unwrap_or(self.u);
        for (j, y) in self.row_y.iter_mut().enumerate() {
            *y = self.y_min + (j as f32 + 0.5) * self.dy;
        }
    }

    /// Judges the heights nearer the root than `fraction` of `length` (the
    /// length the grid was laid for) at that distance (see
    /// [`JUDGE_FRACTION`]): sets each column's near edge (and its
    /// reciprocal) for the steps. Reads only the grid, so the same filled
    /// field can be judged at several fractions.
    pub(crate) fn set_judge_fraction(&mut self, fraction: f32, length: f32) {
        let judged = fraction * length;
        for i in 0..self.u {
            self.col_near[i] = (self.col_x[i] - 0.5 * self.dx).max(judged);
            self.inv_near[i] = 1.0 / self.col_near[i];
        }
    }

    /// The floor height (cells with nothing above it hold exactly this).
    pub fn floor(&self) -> f32 {
        self.floor
    }

    /// Cell size along the shaft and across.
    pub fn cell_size(&self) -> (f32, f32) {
        (self.dx, self.dy)
    }

    /// Centre of cell (column `i`, row `j`) in local coordinates.
    pub fn cell_centre(&self, i: usize, j: usize) -> (f32, f32) {
        (self.col_x[i], self.row_y[j])
    }

    /// The obstacle top over cell (i, j) (the floor when none).
    pub fn obstacle_height(&self, i: usize, j: usize) -> f32 {
        self.obstacle[j * self.u + i]
    }

    /// The body height over cell (i, j) (the floor when none).
    pub fn body_height(&self, i: usize, j: usize) -> f32 {
        self.body[j * self.u + i]
    }

    /// Rasterises an obstacle feather's world triangles, raised by its
    /// thickness. Returns whether any cell was touched (one collision test).
    pub fn add_obstacle(&mut self, frame: &RootFrame, triangles: &[[Vec3; 3]], thickness: f32) -> bool {
        self.add_local_obstacle(&LocalMap::new(frame).triangles(triangles), thickness)
    }

    /// [`HeightField::add_obstacle`] with the triangles already in the
    /// root frame's local coordinates.
    pub(crate) fn add_local_obstacle(&mut self, local: &[[Vec3; 3]], thickness: f32) -> bool {
        // All triangles at once against the footprint first (most
        // candidates within reach miss it).
        let corners = || local.iter().flatten().copied();
        let lo = corners().fold(Vec3::INFINITY, Vec3::min);
        let hi = corners().fold(Vec3::NEG_INFINITY, Vec3::max);
        let (x_hi, y_hi) = (self.shape.length + self.dx, -self.y_min);
        if hi.x < self.socket_x || lo.x > x_hi || hi.y < self.y_min || lo.y > y_hi || hi.z + thickness <= self.floor {
            return false;
        }
        let mut touched = false;
        for &t in local {
            touched |= self.rasterise(Layer::Obstacle, t, thickness);
        }
        touched
    }

    /// Rasterises the body triangles near the feather (those facing its
    /// side) into the body layer.
    ///
    /// Skin lower than `(L + dx)·tan(−min_pitch)` below the tangent plane
    /// can bind no allowed pitch, so it is not fetched (cells without skin
    /// count as free space, capped, for the roll). The search first covers
    /// the footprint up to a band over the tangent plane (where skin near
    /// a root lies: convex skin falls away, gentle concave skin rises a
    /// little); only when skin reaches the top of the band (a concave wall)
    /// is the whole height up to one length searched. Separate geometry
    /// hovering above the band with no skin rising to it (a wing folded
    /// over the back) is thus not a wall the feather must climb.
    pub fn add_body(&mut self, frame: &RootFrame, body: &BodyIndex) {
        let reach = self.shape.length + self.dx;
        let band = SKIN_BAND_PER_LENGTH * self.shape.length;
        let map = LocalMap::new(frame);
        let mut ids = std::mem::take(&mut self.body_scratch.ids);
        let band_box = self.world_bounds(frame, self.body_floor, band);
        body.triangles_in_box(&band_box, &mut ids);
        let mut rises = false;
        // A segmented feather's drape sweeps the skin triangles themselves.
        let keep = self.shape.segment_count() > 1;
        self.local_body.clear();
        for &t in &ids {
            if body.normal(t).dot(frame.normal) <= BODY_FACING_MIN {
                continue;
            }
            let local = map.triangle(&body.corners(t));
            rises |= local[0].z.max(local[1].z).max(local[2].z) >= 0.9 * band;
            self.rasterise(Layer::Body, local, 0.0);
            if keep {
                self.local_body.push(local);
            }
        }
        if rises {
            body.triangles_in_box(&self.world_bounds(frame, self.body_floor, reach), &mut ids);
            for &t in &ids {
                // Those the first search found were rasterised already.
                if body.normal(t).dot(frame.normal) <= BODY_FACING_MIN || body.grid().bounds(t).overlaps(&band_box) {
                    continue;
                }
                let local = map.triangle(&body.corners(t));
                // Triangles wholly within the band are left to the first search.
                if local.iter().any(|p| p.z > band || p.z < self.body_floor) {
                    self.rasterise(Layer::Body, local, 0.0);
                    if keep {
                        self.local_body.push(local);
                    }
                }
            }
        }
        self.body_scratch.ids = ids;
    }

    /// World bounding box of the footprint between heights `z_lo` and `z_hi`.
    fn world_bounds(&self, frame: &RootFrame, z_lo: f32, z_hi: f32) -> Aabb {
        let x = [0.0, self.shape.length + self.dx];
        let y = [self.y_min, -self.y_min];
        let z = [z_lo, z_hi];
        let centre = Vec3::new(0.5 * (x[0] + x[1]), 0.0, 0.5 * (z[0] + z[1]));
        let half = Vec3::new(0.5 * (x[1] - x[0]), 0.5 * (y[1] - y[0]), 0.5 * (z[1] - z[0]));
        let c = frame.to_world(centre);
        let e = frame.tangent.abs() * half.x + frame.binormal.abs() * half.y + frame.normal.abs() * half.z;
        Aabb { min: c - e, max: c + e }
    }

    /// Rasterises one triangle given in local coordinates; its top is its
    /// plane raised by `raise`. Returns whether any cell was touched.
    pub(crate) fn rasterise(&mut self, layer: Layer, tri: [Vec3; 3], raise: f32) -> bool {
        let z_top = max3(tri[0].z, tri[1].z, tri[2].z);
        if z_top + raise <= self.floor || z_top.is_nan() {
            return false;
        }
        let (inv_dx, inv_dy) = (1.0 / self.dx, 1.0 / self.dy);
        // Grid coordinates: cell (i, j) is the unit square [i, i+1] × [j, j+1].
        let grid = |p: Vec3| Vec2::new(p.x * inv_dx, (p.y - self.y_min) * inv_dy);
        let g = [grid(tri[0]), grid(tri[1]), grid(tri[2])];
        let gmin = Vec2::new(min3(g[0].x, g[1].x, g[2].x), min3(g[0].y, g[1].y, g[2].y));
        let gmax = Vec2::new(max3(g[0].x, g[1].x, g[2].x), max3(g[0].y, g[1].y, g[2].y));
        let (u, v) = (index_f32(self.u), index_f32(self.v));
        let socket_u = self.socket_x * inv_dx;
        if !(gmax.x >= socket_u && gmin.x <= u && gmax.y >= 0.0 && gmin.y <= v) {
            return false;
        }
        // Columns wholly inside the root socket are skipped; the column
        // holding the socket's end only counts beyond it.
        let socket_col = (floor_i32(socket_u).max(0) as usize).min(self.u - 1);
        let socket_cut = socket_u - index_f32(socket_col);
        let i0 = (floor_i32(gmin.x).max(0) as usize).max(socket_col);
        let i1 = (floor_i32(gmax.x).max(0) as usize).min(self.u - 1);
        let j0 = floor_i32(gmin.y).max(0) as usize;
        let j1 = (floor_i32(gmax.y).max(0) as usize).min(self.v - 1);
        if i0 > i1 || j0 > j1 {
            return false;
        }
        self.need_for = None;
        let plane = TrianglePlane::new(g, [tri[0].z, tri[1].z, tri[2].z]);
        let cells = match layer {
            Layer::Obstacle => &mut self.obstacle,
            Layer::Body => &mut self.body,
        };
        let mut touched = false;
        // Row spans come in chunks of rows (one pass per edge, so that the
        // rows of a chunk are computed side by side).
        let mut spans = [(i0, i1); SPAN_ROWS];
        for j in j0..=j1 {
            let vc = index_f32(j) + 0.5;
            if let Some(p) = &plane
                && (j - j0) % SPAN_ROWS == 0
            {
                spans = p.row_spans(j, i0, i1);
            }
            let (lo, hi) = spans[(j - j0) % SPAN_ROWS];
            if lo > hi {
                continue;
            }
            touched = true;
            let row = &mut cells[j * self.u..(j + 1) * self.u];
            let Some(p) = &plane else {
                raise_row(&mut row[lo..=hi], z_top, 0.0, z_top, raise);
                continue;
            };
            let mut start = lo;
            if lo == socket_col {
                let (uc, half) = (index_f32(socket_col) + 0.5 * (1.0 + socket_cut), 0.5 * (1.0 - socket_cut));
                let h = (p.height_at(uc, vc) + p.du.abs() * half + 0.5 * p.dv.abs()).min(z_top) + raise;
                row[lo] = row[lo].max(h);
                start = lo + 1;
            }
            if start <= hi {
                raise_row(&mut row[start..=hi], p.height_at(index_f32(start) + 0.5, vc) + p.slack, p.du, z_top, raise);
            }
        }
        touched
    }
}

crate::memory::heap_size_of_fields!(HeightField {
    obstacle, body, need, col_x, row_y, col_near, col_far, inv_near, inv_far, row_span, body_scratch, boxes,
    bounds, sweep_obstacles, local_obstacles, swept, local_body
} plain { u, v, dx, dy, y_min, floor, socket_x, body_floor, clearance_from, shape, need_for, first_col });

#[cfg(test)]
mod tests {
    use super::*;

    fn field() -> (HeightField, RootFrame) {
        let shape = FeatherShape { length: 3.1, width: 1.4, thickness: 0.05, vane_split: 0.4, segments: 1 };
        let mut f = HeightField::new(32, 16);
        f.reset(&shape, -0.35);
        (f, RootFrame::from_normal_and_direction(Vec3::ZERO, Vec3::Z, Vec3::X).unwrap())
    }

    /// Highest point of the local triangle over cell (i, j), by dense sampling.
    fn sampled_max(f: &HeightField, tri: [Vec3; 3], i: usize, j: usize) -> Option<f32> {
        let mut best: Option<f32> = None;
        let n = 24;
        for a in 0..=n {
            for b in 0..=n {
                let x = ((i as f32 + a as f32 / n as f32) * f.dx).max(f.socket_x);
                let y = f.y_min + (j as f32 + b as f32 / n as f32) * f.dy;
                let p = Vec2::new(x, y);
                let (v0, v1, v2) = (tri[0].truncate(), tri[1].truncate(), tri[2].truncate());
                let d = (v1 - v0).perp_dot(v2 - v0);
                let l1 = (v1 - p).perp_dot(v2 - p) / d;
                let l2 = (v2 - p).perp_dot(v0 - p) / d;
                let l3 = 1.0 - l1 - l2;
                if l1 >= -1e-6 && l2 >= -1e-6 && l3 >= -1e-6 {
                    let z = l1 * tri[0].z + l2 * tri[1].z + l3 * tri[2].z;
                    best = Some(best.map_or(z, |m| m.max(z)));
                }
            }
        }
        best
    }

    #[test]
    fn rasterisation_is_conservative() {
        let (mut f, _) = field();
        let mut rng = crate::rng::Rng::new(4);
        for _ in 0..40 {
            f.reset(&f.shape.clone(), -0.35);
            let mut p = || Vec3::new(rng.next_f32() * 3.5 - 0.2, rng.next_f32() * 2.0 - 1.0, rng.next_f32() - 0.5);
            let tri = [p(), p(), p()];
            f.rasterise(Layer::Obstacle, tri, 0.0);
            for j in 0..f.v {
                for i in 0..f.u {
                    if let Some(m) = sampled_max(&f, tri, i, j) {
                        assert!(
                            f.obstacle_height(i, j) >= m - 1e-5,
                            "cell ({i},{j}) {} < {m}",
                            f.obstacle_height(i, j)
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_flat_triangle_fills_its_cells_with_its_height_plus_thickness() {
        let (mut f, frame) = field();
        let tri = [Vec3::new(1.0, -0.3, 0.2), Vec3::new(2.0, -0.3, 0.2), Vec3::new(1.5, 0.4, 0.2)];
        assert!(f.add_obstacle(&frame, &[tri, tri], 0.05));
        let (dx, dy) = f.cell_size();
        let (ic, jc) = ((1.5 / dx) as usize, ((0.0 - f.y_min) / dy) as usize);
        assert!((f.obstacle_height(ic, jc) - 0.25).abs() < 1e-6);
        assert_eq!(f.obstacle_height(0, 0), f.floor());
        assert_eq!(f.body_height(ic, jc), f.floor());
    }

    #[test]
    fn geometry_below_the_floor_or_outside_is_skipped() {
        let (mut f, frame) = field();
        let deep = [Vec3::new(1.0, 0.0, -5.0), Vec3::new(2.0, 0.0, -5.0), Vec3::new(1.5, 0.4, -5.0)];
        assert!(!f.add_obstacle(&frame, &[deep, deep], 0.05));
        let behind = [Vec3::new(-3.0, 0.0, 0.0), Vec3::new(-2.0, 0.0, 0.0), Vec3::new(-2.5, 0.4, 0.0)];
        assert!(!f.add_obstacle(&frame, &[behind, behind], 0.05));
        assert!(f.obstacle.iter().all(|&h| h == f.floor()));
    }

    #[test]
    fn body_facing_away_is_left_out() {
        let (mut f, frame) = field();
        let pos = [
            Vec3::new(-1.0, -2.0, -0.1),
            Vec3::new(5.0, -2.0, -0.1),
            Vec3::new(5.0, 2.0, -0.1),
            Vec3::new(-1.0, 2.0, -0.1),
        ];
        // Facing up: kept. The same sheet wound the other way (facing down): left out.
        let up = BodyIndex::from_mesh(&pos, &[[0, 1, 2], [0, 2, 3]]);
        f.add_body(&frame, &up);
        assert!((f.body_height(5, 5) + 0.1).abs() < 1e-5);
        f.reset(&f.shape.clone(), -0.35);
        let down = BodyIndex::from_mesh(&pos, &[[0, 2, 1], [0, 3, 2]]);
        f.add_body(&frame, &down);
        assert_eq!(f.body_height(5, 5), f.floor());
    }
}
