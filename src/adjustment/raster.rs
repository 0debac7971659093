//! Conservative rasterisation of a triangle into height-field rows (used
//! by [`HeightField`](super::HeightField)): the triangle's plane and edge
//! functions in grid coordinates, the columns of each row it may touch, and
//! the float helpers the grid steps share (floors and ceilings without a
//! libm call, a root frame's world-to-local map in SIMD lanes).

use crate::feather::FeatherTriangles;
use crate::geometry::RootFrame;
use glam::{Mat3A, Vec2, Vec3, Vec3A};

/// A projected triangle is treated as a plane when its doubled area exceeds
/// this fraction of the product of two edge lengths.
const PLANAR_MIN_SINE: f32 = 1e-4;

/// The smaller of two values (plain comparison: no NaN handling, which
/// costs several instructions in the per-cell loops; inputs are finite).
#[inline(always)]
pub(super) fn min_f(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// The larger of two values (see [`min_f`]).
#[inline(always)]
pub(super) fn max_f(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// Rows whose spans [`TrianglePlane::row_spans`] computes together.
pub(super) const SPAN_ROWS: usize = 8;

/// The largest of three values (plain comparisons; inputs are finite or
/// the triangle is rejected by the NaN check on its top).
#[inline(always)]
pub(super) fn max3(a: f32, b: f32, c: f32) -> f32 {
    let m = if a > b { a } else { b };
    if m > c { m } else { c }
}

/// The smallest of three values (see [`max3`]).
#[inline(always)]
pub(super) fn min3(a: f32, b: f32, c: f32) -> f32 {
    let m = if a < b { a } else { b };
    if m < c { m } else { c }
}

/// A root frame's map from world to local coordinates, in SIMD lanes:
/// the same f32 operations in the same order as [`RootFrame::to_local`]'s
/// three dot products (`(x + y) + z` per component), so the same values.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LocalMap {
    /// Columns `(t.x, b.x, n.x)`, `(t.y, b.y, n.y)`, `(t.z, b.z, n.z)` of
    /// the frame's tangent, binormal and normal.
    rows: Mat3A,
    origin: Vec3A,
}

impl LocalMap {
    pub(crate) fn new(frame: &RootFrame) -> Self {
        let (t, b, n) = (frame.tangent, frame.binormal, frame.normal);
        let rows = Mat3A::from_cols(Vec3A::new(t.x, b.x, n.x), Vec3A::new(t.y, b.y, n.y), Vec3A::new(t.z, b.z, n.z));
        Self { rows, origin: frame.position.into() }
    }

    #[inline]
    fn point(&self, p: Vec3) -> Vec3 {
        (self.rows * (Vec3A::from(p) - self.origin)).into()
    }

    /// A world triangle in local coordinates.
    #[inline]
    pub(crate) fn triangle(&self, t: &[Vec3; 3]) -> [Vec3; 3] {
        t.map(|p| self.point(p))
    }

    /// A feather's world triangles in local coordinates.
    #[inline]
    pub(crate) fn triangles(&self, t: &[[Vec3; 3]]) -> FeatherTriangles {
        let mut local = FeatherTriangles::from_slice(t);
        local.map_in_place(|p| self.point(p));
        local
    }
}

/// Raises each cell to `min(first + k·step, cap) + raise` (k = its
/// position in `cells`). Written with plain comparisons so it vectorises.
#[inline]
pub(super) fn raise_row(cells: &mut [f32], first: f32, step: f32, cap: f32, raise: f32) {
    // An i32 position converts to f32 in vector registers; usize does not.
    for (k, cell) in (0..cells.len() as i32).zip(cells.iter_mut()) {
        let z = first + step * k as f32;
        let h = if z < cap { z } else { cap } + raise;
        // An unconditional store of the larger keeps the loop vectorised.
        *cell = if h > *cell { h } else { *cell };
    }
}

/// A grid index (far below 2^24) as f32: converted through i32, one
/// instruction where usize takes a branch and several (the same value).
#[inline(always)]
pub(super) fn index_f32(i: usize) -> f32 {
    i as i32 as f32
}

/// `⌊x⌋` as an integer, saturating (no libm call on baseline x86-64).
#[inline]
pub(crate) fn floor_i32(x: f32) -> i32 {
    let i = x as i32;
    i - i32::from((i as f32) > x)
}

/// `⌈x⌉` as an integer, saturating.
#[inline]
pub(crate) fn ceil_i32(x: f32) -> i32 {
    let i = x as i32;
    i + i32::from((i as f32) < x)
}

/// A triangle projected to grid coordinates, with its height plane and the
/// edge functions used to find the cells it may touch.
pub(super) struct TrianglePlane {
    /// Height at grid point (0, 0) and slopes per cell along u and v.
    pub(super) z0: f32,
    pub(super) du: f32,
    pub(super) dv: f32,
    /// Half the height change across a cell: plane max over a cell is the
    /// centre value plus this.
    pub(super) slack: f32,
    /// Edge functions `a·u + b·v + c ≥ 0` inside, `c` already loosened by
    /// half a cell so that a cell passes when its most inside corner does;
    /// with `1/a` (0 when `a = 0`).
    pub(super) edges: [[f32; 4]; 3],
}

impl TrianglePlane {
    /// `None` when the projection is too thin to carry a plane.
    pub(super) fn new(g: [Vec2; 3], z: [f32; 3]) -> Option<Self> {
        let (e1, e2) = (g[1] - g[0], g[2] - g[0]);
        let det = e1.perp_dot(e2);
        let scale = e1.length() * e2.length();
        if det.abs() <= PLANAR_MIN_SINE * scale || det.is_nan() {
            return None;
        }
        let (dz1, dz2) = (z[1] - z[0], z[2] - z[0]);
        let du = (dz1 * e2.y - e1.y * dz2) / det;
        let dv = (e1.x * dz2 - dz1 * e2.x) / det;
        let z0 = z[0] - du * g[0].x - dv * g[0].y;
        let s = det.signum();
        let mut edges = [[0.0; 4]; 3];
        for (k, edge) in edges.iter_mut().enumerate() {
            let (p, q) = (g[k], g[(k + 1) % 3]);
            let d = q - p;
            // E(u, v) = d.x (v − p.y) − d.y (u − p.x), positive inside for s > 0.
            let a = -s * d.y;
            let b = s * d.x;
            let c = s * (d.y * p.x - d.x * p.y);
            let loosen = 0.5 * (d.x.abs() + d.y.abs()) * (1.0 + 1e-4) + 1e-5;
            *edge = [a, b, c + loosen, if a != 0.0 { 1.0 / a } else { 0.0 }];
        }
        Some(Self { z0, du, dv, slack: 0.5 * (du.abs() + dv.abs()), edges })
    }

    #[inline]
    pub(super) fn height_at(&self, gu: f32, gv: f32) -> f32 {
        self.z0 + self.du * gu + self.dv * gv
    }

    /// For the rows `j..j + SPAN_ROWS` (centres `j + 0.5`), the columns
    /// `lo..=hi` that may touch the triangle, within `[i0, i1]`; `lo > hi`
    /// when none does.
    #[inline]
    pub(super) fn row_spans(&self, j: usize, i0: usize, i1: usize) -> [(usize, usize); SPAN_ROWS] {
        let vc: [f32; SPAN_ROWS] = std::array::from_fn(|k| index_f32(j + k) + 0.5);
        // Bounds on the column centre i + 0.5, tightest over the edges,
        // rounded once at the end.
        let (mut lo, mut hi) = ([index_f32(i0); SPAN_ROWS], [index_f32(i1); SPAN_ROWS]);
        let mut shut = [false; SPAN_ROWS];
        for &[a, b, c, inv_a] in &self.edges {
            // a·(i + 0.5) + rest ≥ 0, with rest = b·vc + c.
            if a > 0.0 {
                for k in 0..SPAN_ROWS {
                    let t = -(b * vc[k] + c) * inv_a - 0.5;
                    lo[k] = if t > lo[k] { t } else { lo[k] };
                }
            } else if a < 0.0 {
                for k in 0..SPAN_ROWS {
                    let t = -(b * vc[k] + c) * inv_a - 0.5;
                    hi[k] = if t < hi[k] { t } else { hi[k] };
                }
            } else {
                for k in 0..SPAN_ROWS {
                    shut[k] |= b * vc[k] + c < 0.0;
                }
            }
        }
        // lo ≥ i0 and hi ≤ i1 (neither is ever NaN); clamped to within one
        // of the other end, they round the same way or stay out of range.
        let (far_lo, far_hi) = (index_f32(i1) + 1.0, index_f32(i0) - 1.0);
        // Rounded in a loop of its own, over plain i32 arrays, so that it
        // vectorises.
        let (mut first, mut last) = ([0i32; SPAN_ROWS], [0i32; SPAN_ROWS]);
        for k in 0..SPAN_ROWS {
            let (l, h) = (min_f(lo[k], far_lo), max_f(hi[k], far_hi));
            // SAFETY: both lie in [−1, u + 1], well within i32.
            let (lt, ht) = unsafe { (l.to_int_unchecked::<i32>(), h.to_int_unchecked::<i32>()) };
            // ⌈l⌉ and ⌊h⌋ (see `ceil_i32`, `floor_i32`).
            first[k] = lt + i32::from((lt as f32) < l);
            last[k] = ht - i32::from((ht as f32) > h);
        }
        let mut span = [(1, 0); SPAN_ROWS];
        for k in 0..SPAN_ROWS {
            if !shut[k] && first[k] <= last[k] {
                span[k] = (first[k] as usize, last[k] as usize);
            }
        }
        span
    }
}
