//! Neighbourhoods of feather roots at the current pose (paper §2.1, DESIGN §1):
//! the k nearest roots `N_i`, the symmetric pair set on which priorities are
//! compared, and the wider obstacle candidates `|r_i − r_j| ≤ L_i + L_j`.
//!
//! Everything is stored CSR-style (row offsets + flat indices) in buffers
//! that [`Neighbourhoods::rebuild`] clears and refills, so recomputing them
//! every frame allocates nothing once the buffers have grown to the root
//! count. A k-d tree (not a uniform grid) is used because root density
//! varies over a body by the density field; the tree needs no cell size.
//! Its leaves (up to 16 roots lying close together) also serve as cells
//! for the obstacle candidates: pairs of leaves within reach of each other
//! are compared root against root, which costs far less than one radius
//! query per root.
//!
//! Thin parts (the two skins of a wing) put roots close in space that are far
//! apart on the surface. Roots whose normals disagree strongly
//! (`n_i·n_j < min_normal_dot`) are never neighbours or pairs of each other
//! (their order says nothing). They stay obstacle candidates: a feather
//! reaching round the rim of a wing can meet one from the other skin, and
//! the adjustment checks those exactly.

use super::kd_tree::{KdTree, insert_candidate, ranks_among_best};
use crate::error::{Error, ErrorKind, Result};
use crate::geometry::RootFrame;
use crate::snapshot::{Reader, Writer};

/// Parameters of the neighbourhood search.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeighbourParams {
    /// k of the k-nearest-root neighbourhoods (`config.k_neighbours`, default 10).
    pub k: usize,
    /// Roots `i, j` with `n_i·n_j` below this are never related. The default
    /// −0.5 (normals more than 120° apart) separates the skins of thin parts
    /// while keeping neighbours across sharp creases; `f32::NEG_INFINITY`
    /// disables the test.
    pub min_normal_dot: f32,
}

impl Default for NeighbourParams {
    fn default() -> Self {
        Self { k: 10, min_normal_dot: -0.5 }
    }
}

/// k-nearest neighbourhoods, the symmetric pair set and obstacle candidates
/// of one pose. Create once, call [`rebuild`](Self::rebuild) every frame.
#[derive(Clone, Debug, Default)]
pub struct Neighbourhoods {
    tree: KdTree,
    knn_offsets: Vec<u32>,
    knn_indices: Vec<u32>,
    pairs: Vec<(u32, u32)>,
    obstacle_offsets: Vec<u32>,
    obstacle_indices: Vec<u32>,
    best: Vec<(f32, u32)>,
    bucket_offsets: Vec<u32>,
    bucket_items: Vec<u32>,
    fill_cursor: Vec<u32>,
    scratch_indices: Vec<u32>,
    leaf_ids: Vec<u32>,
    leaf_starts: Vec<u32>,
    points: Vec<(glam::Vec3, f32)>,
    cells: Vec<Cell>,
    pair_scratch: Vec<(u32, u32)>,
    /// Root positions by index, for the distances of the k nearest.
    positions: Vec<glam::Vec3>,
}

impl Neighbourhoods {
    /// Empty neighbourhoods (no roots).
    pub fn new() -> Self {
        Self::default()
    }

    /// Recomputes everything for the roots `frames` at the current pose.
    /// `reach[i]` is the feather length `L_i` of root `i`; pass an empty
    /// slice to skip the obstacle candidates (all their rows are then empty).
    ///
    /// # Panics
    /// If `reach` is neither empty nor as long as `frames`, or there are more
    /// than `u32::MAX` roots.
    pub fn rebuild(&mut self, frames: &[RootFrame], reach: &[f32], params: &NeighbourParams) {
        assert!(u32::try_from(frames.len()).is_ok(), "too many roots for u32 indices");
        assert!(reach.is_empty() || reach.len() == frames.len(), "reach must be empty or one length per root");
        self.tree.rebuild(frames.iter().map(|f| f.position));
        self.rebuild_obstacles(frames, reach);
        self.rebuild_nearest(frames, reach, params);
        self.rebuild_pairs(frames.len());
    }

    /// Number of roots of the last rebuild.
    pub fn len(&self) -> usize {
        self.knn_offsets.len().saturating_sub(1)
    }

    /// True when the last rebuild had no roots.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `N_i`: the nearest roots of `i`, by distance then index (at most k).
    pub fn neighbours_of(&self, i: u32) -> &[u32] {
        row(&self.knn_offsets, &self.knn_indices, i)
    }

    /// The neighbourhoods as CSR: row `i` is `indices[offsets[i]..offsets[i+1]]`.
    pub fn neighbours_csr(&self) -> (&[u32], &[u32]) {
        (&self.knn_offsets, &self.knn_indices)
    }

    /// The symmetric pair set: `(a, b)` with `a < b` and `a ∈ N_b` or
    /// `b ∈ N_a`, sorted.
    pub fn pairs(&self) -> &[(u32, u32)] {
        &self.pairs
    }

    /// Obstacle candidates of `i`: every other root `j` with
    /// `|r_i − r_j| ≤ reach_i + reach_j`, sorted by index. The relation is
    /// symmetric; the adjustment keeps those earlier in the order.
    pub fn obstacle_candidates_of(&self, i: u32) -> &[u32] {
        row(&self.obstacle_offsets, &self.obstacle_indices, i)
    }

    /// The obstacle candidates as CSR (same layout as [`neighbours_csr`](Self::neighbours_csr)).
    pub fn obstacle_csr(&self) -> (&[u32], &[u32]) {
        (&self.obstacle_offsets, &self.obstacle_indices)
    }

    /// The k nearest roots of every root, by distance then index. Every
    /// root within `reach_i + min reach` of root i whose normal agrees is an
    /// obstacle candidate of i, so when i's k-th nearest candidate lies that
    /// close its candidates hold its k nearest roots; only the other roots
    /// (none on a closed coat) query the tree. Both ways rank candidates by
    /// the same `(|r_j − r_i|², j)`, so the rows are those of the tree alone.
    /// The candidates' distances are computed again from the positions,
    /// bitwise as the obstacle pass compared them.
    fn rebuild_nearest(&mut self, frames: &[RootFrame], reach: &[f32], params: &NeighbourParams) {
        let k = params.k;
        let min_reach = reach.iter().fold(f32::INFINITY, |m, &r| m.min(sanitized_reach(r)));
        self.knn_offsets.clear();
        self.knn_indices.clear();
        self.knn_offsets.push(0);
        self.positions.clear();
        self.positions.extend(frames.iter().map(|f| f.position));
        for (i, frame) in frames.iter().enumerate() {
            self.best.clear();
            if k > 0 {
                let entries = self.obstacle_offsets[i] as usize..self.obstacle_offsets[i + 1] as usize;
                let p = frame.position;
                for &j in &self.obstacle_indices[entries] {
                    // Bitwise the distance the obstacle pass compared
                    // (negating a difference does not change its square).
                    let d2 = (self.positions[j as usize] - p).length_squared();
                    if ranks_among_best(&self.best, k, d2, j)
                        && normals_agree(frame, &frames[j as usize], params.min_normal_dot)
                    {
                        insert_candidate(&mut self.best, k, d2, j);
                    }
                }
            }
            let sure = reach.get(i).map_or(0.0, |&r| sanitized_reach(r) + min_reach);
            let beyond = |d2: f32| d2.partial_cmp(&(sure * sure)).is_none_or(|o| o.is_gt());
            if self.best.len() < k || self.best.last().is_some_and(|b| beyond(b.0)) {
                let accept =
                    |j: u32| j as usize != i && normals_agree(frame, &frames[j as usize], params.min_normal_dot);
                self.tree.nearest(frame.position, k, &accept, &mut self.best);
            }
            self.knn_indices.extend(self.best.iter().map(|&(_, j)| j));
            self.knn_offsets.push(self.knn_indices.len() as u32);
        }
    }

    /// Symmetrises the neighbourhoods into sorted unique `(lo, hi)` pairs with
    /// a counting sort on `lo` followed by a small sort per bucket.
    fn rebuild_pairs(&mut self, n: usize) {
        let (offsets, indices) = (&self.knn_offsets, &self.knn_indices);
        let buckets = &mut self.bucket_offsets;
        buckets.clear();
        buckets.resize(n + 1, 0);
        for i in 0..n as u32 {
            for &j in row(offsets, indices, i) {
                buckets[i.min(j) as usize + 1] += 1;
            }
        }
        for i in 0..n {
            buckets[i + 1] += buckets[i];
        }
        let cursor = &mut self.fill_cursor;
        cursor.clear();
        cursor.extend_from_slice(&buckets[..n]);
        let items = &mut self.bucket_items;
        items.clear();
        items.resize(indices.len(), 0);
        for i in 0..n as u32 {
            for &j in row(offsets, indices, i) {
                let lo = i.min(j) as usize;
                items[cursor[lo] as usize] = i.max(j);
                cursor[lo] += 1;
            }
        }
        self.pairs.clear();
        for lo in 0..n {
            let bucket = &mut items[buckets[lo] as usize..buckets[lo + 1] as usize];
            bucket.sort_unstable();
            let mut last = None;
            for &hi in bucket.iter() {
                if last != Some(hi) {
                    self.pairs.push((lo as u32, hi));
                    last = Some(hi);
                }
            }
        }
    }

    /// Obstacle candidates, from the leaves of the tree: every pair of
    /// leaves whose boxes come within the sum of their longest reaches is
    /// compared root against root, each pair of roots once. The pruning is
    /// exact (a box gap is never larger in `f32` than the gap between two
    /// of the boxes' points, computed the same way), and so is the test,
    /// `|r_i − r_j|² ≤ (reach_i + reach_j)²`, bitwise symmetric in i and j.
    /// The pairs fill unsorted rows, whose transpose is the same relation
    /// with every row sorted by index.
    fn rebuild_obstacles(&mut self, frames: &[RootFrame], reach: &[f32]) {
        let n = frames.len();
        self.obstacle_offsets.clear();
        self.obstacle_indices.clear();
        if reach.is_empty() {
            self.obstacle_offsets.resize(n + 1, 0);
            return;
        }
        self.tree.leaves(&mut self.leaf_ids, &mut self.leaf_starts);
        let ids = &self.leaf_ids;
        self.points.clear();
        self.points.extend(ids.iter().map(|&i| (frames[i as usize].position, sanitized_reach(reach[i as usize]))));
        self.cells.clear();
        for w in self.leaf_starts.windows(2) {
            let points = &self.points[w[0] as usize..w[1] as usize];
            let (lo, hi, reach) =
                points.iter().fold((glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY, 0.0f32), |(lo, hi, r), &(p, q)| {
                    (lo.min(p), hi.max(p), r.max(q))
                });
            self.cells.push(Cell { lo, hi, reach });
        }
        let (points, cells, starts) = (&self.points, &self.cells, &self.leaf_starts);
        let pairs = &mut self.pair_scratch;
        pairs.clear();
        for (a, cell_a) in cells.iter().enumerate() {
            let rows_a = starts[a] as usize..starts[a + 1] as usize;
            for (b, cell_b) in cells.iter().enumerate().skip(a) {
                if !cell_a.may_reach(cell_b) {
                    continue;
                }
                let rows_b = starts[b] as usize..starts[b + 1] as usize;
                for k in rows_a.clone() {
                    let (p, r) = points[k];
                    let from = if a == b { k + 1 } else { rows_b.start };
                    for (l, &(q, s)) in points[from..rows_b.end].iter().enumerate() {
                        let limit = r + s;
                        let d2 = (q - p).length_squared();
                        if d2 <= limit * limit {
                            pairs.push((ids[k], ids[from + l]));
                        }
                    }
                }
            }
        }
        // Unsorted symmetric rows, then their transpose.
        let offsets = &mut self.obstacle_offsets;
        offsets.resize(n + 1, 0);
        for &(i, j) in pairs.iter() {
            offsets[i as usize + 1] += 1;
            offsets[j as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        self.fill_cursor.clear();
        self.fill_cursor.extend_from_slice(&offsets[..n]);
        self.scratch_indices.clear();
        self.scratch_indices.resize(2 * pairs.len(), 0);
        for &(i, j) in pairs.iter() {
            for (row, other) in [(i, j), (j, i)] {
                let slot = &mut self.fill_cursor[row as usize];
                self.scratch_indices[*slot as usize] = other;
                *slot += 1;
            }
        }
        self.fill_cursor.clear();
        self.fill_cursor.extend_from_slice(&offsets[..n]);
        self.obstacle_indices.resize(self.scratch_indices.len(), 0);
        for i in 0..n as u32 {
            let entries = offsets[i as usize] as usize..offsets[i as usize + 1] as usize;
            for &j in &self.scratch_indices[entries] {
                let slot = &mut self.fill_cursor[j as usize];
                self.obstacle_indices[*slot as usize] = i;
                *slot += 1;
            }
        }
    }
}

/// A leaf of the tree: the box of its roots and their longest reach.
#[derive(Clone, Copy, Debug)]
struct Cell {
    lo: glam::Vec3,
    hi: glam::Vec3,
    reach: f32,
}

impl Cell {
    /// Whether a root of `self` and one of `other` may lie within the sum
    /// of their reaches: the gap between the boxes, squared as a point
    /// distance is, is within the sum of the longest reaches. Per axis the
    /// `f32` gap is no larger than any two points' `f32` difference
    /// (rounding is monotone), so no pair within reach is left out.
    #[inline]
    fn may_reach(&self, other: &Cell) -> bool {
        let gap = (other.lo - self.hi).max(self.lo - other.hi).max(glam::Vec3::ZERO);
        let limit = self.reach + other.reach;
        gap.length_squared() <= limit * limit
    }
}

#[cfg(test)]
impl Neighbourhoods {
    /// Obstacle candidates: one radius query per root, in tree order, into
    /// scratch rows; then a transpose. The relation is symmetric bitwise
    /// (distances and `reach_i + reach_j` commute, and
    /// the tree query is exact), so the transpose of the scratch rows is the
    /// same relation with every row sorted by index, without sorting.
    fn obstacles_by_tree(&mut self, frames: &[RootFrame], reach: &[f32]) {
        let n = frames.len();
        self.obstacle_offsets.clear();
        self.obstacle_offsets.push(0);
        self.scratch_indices.clear();
        let max_reach = reach.iter().fold(0.0f32, |m, &r| m.max(sanitized_reach(r)));
        for (i, frame) in frames.iter().enumerate() {
            if !reach.is_empty() {
                let reach_i = sanitized_reach(reach[i]);
                let bound = reach_i + max_reach;
                let indices = &mut self.scratch_indices;
                self.tree.within(frame.position, bound * bound, &mut |j, d2| {
                    let limit = reach_i + sanitized_reach(reach[j as usize]);
                    if j as usize != i && d2 <= limit * limit {
                        indices.push(j);
                    }
                });
            }
            self.obstacle_offsets.push(self.scratch_indices.len() as u32);
        }
        self.fill_cursor.clear();
        self.fill_cursor.extend_from_slice(&self.obstacle_offsets[..n]);
        self.obstacle_indices.clear();
        self.obstacle_indices.resize(self.scratch_indices.len(), 0);
        for i in 0..n as u32 {
            for &j in row(&self.obstacle_offsets, &self.scratch_indices, i) {
                let slot = &mut self.fill_cursor[j as usize];
                self.obstacle_indices[*slot as usize] = i;
                *slot += 1;
            }
        }
    }
}

/// Saved state (see [`crate::snapshot`]): the k-nearest rows, then the
/// obstacle rows, each as CSR offsets then indices. The obstacle relation is
/// symmetric and its rows sorted, so only the part above the diagonal
/// (`j > i`) is stored and the rest is its transpose. The pair set is
/// derived from the k-nearest rows on load, and the k-d tree and the fill
/// buffers are scratch of [`rebuild`](Self::rebuild), so none of them is
/// stored.
impl Neighbourhoods {
    /// Appends the neighbourhoods to a state blob.
    pub fn write_state(&self, w: &mut Writer) {
        write_csr(w, &self.knn_offsets, &self.knn_indices);
        let n = self.len() as u32;
        debug_assert!((0..n).all(|i| self.obstacle_candidates_of(i).windows(2).all(|p| p[0] < p[1])));
        debug_assert!((0..n).all(|i| {
            self.obstacle_candidates_of(i).iter().all(|&j| self.obstacle_candidates_of(j).binary_search(&i).is_ok())
        }));
        let mut offsets = vec![0u32];
        let mut upper = Vec::new();
        for i in 0..n {
            let candidates = self.obstacle_candidates_of(i);
            upper.extend_from_slice(&candidates[candidates.partition_point(|&j| j <= i)..]);
            offsets.push(upper.len() as u32);
        }
        write_csr(w, &offsets, &upper);
    }

    /// Reads neighbourhoods of `roots` roots written by
    /// [`write_state`](Self::write_state). Everything is checked before it
    /// is used: offsets start at 0, never decrease and end at the index
    /// count; every index is a root other than the row's own; stored
    /// obstacle rows are strictly increasing and above the diagonal (so the
    /// rebuilt relation is symmetric with sorted rows). Anything else is
    /// refused with `InvalidState`.
    pub fn read_state(r: &mut Reader<'_>, roots: usize) -> Result<Self> {
        if u32::try_from(roots).is_err() {
            return Err(invalid("too many roots for a saved neighbourhood"));
        }
        let mut s = Self::default();
        read_csr(r, roots, &mut s.knn_offsets, &mut s.knn_indices, "neighbourhood")?;
        let (mut offsets, mut upper) = (Vec::new(), Vec::new());
        read_csr(r, roots, &mut offsets, &mut upper, "obstacle")?;
        if upper.len() > u32::MAX as usize / 2 {
            return Err(invalid("saved obstacle rows are too long"));
        }
        for i in 0..roots as u32 {
            let stored = row(&offsets, &upper, i);
            if stored.first().is_some_and(|&j| j < i) || stored.windows(2).any(|p| p[0] >= p[1]) {
                return Err(invalid(format!("saved obstacle row {i} is not increasing above the diagonal")));
            }
        }
        s.symmetric_obstacles_from_upper(roots, &offsets, &upper);
        s.rebuild_pairs(roots);
        Ok(s)
    }

    /// Fills the obstacle rows from their part above the diagonal: row `i`
    /// is `{j < i : i ∈ upper_j}` (in increasing `j`) followed by `upper_i`.
    fn symmetric_obstacles_from_upper(&mut self, n: usize, offsets: &[u32], upper: &[u32]) {
        self.obstacle_offsets.clear();
        self.obstacle_offsets.resize(n + 1, 0);
        for i in 0..n as u32 {
            let stored = row(offsets, upper, i);
            self.obstacle_offsets[i as usize + 1] += stored.len() as u32;
            for &j in stored {
                self.obstacle_offsets[j as usize + 1] += 1;
            }
        }
        for i in 0..n {
            self.obstacle_offsets[i + 1] += self.obstacle_offsets[i];
        }
        self.fill_cursor.clear();
        self.fill_cursor.extend_from_slice(&self.obstacle_offsets[..n]);
        self.obstacle_indices.clear();
        self.obstacle_indices.resize(2 * upper.len(), 0);
        for i in 0..n as u32 {
            for &j in row(offsets, upper, i) {
                let slot = &mut self.fill_cursor[j as usize];
                self.obstacle_indices[*slot as usize] = i;
                *slot += 1;
            }
        }
        for i in 0..n as u32 {
            for &j in row(offsets, upper, i) {
                let slot = &mut self.fill_cursor[i as usize];
                self.obstacle_indices[*slot as usize] = j;
                *slot += 1;
            }
        }
    }
}

/// Writes one CSR structure: offsets (at least the leading 0), then indices.
fn write_csr(w: &mut Writer, offsets: &[u32], indices: &[u32]) {
    w.u32s(if offsets.is_empty() { &[0] } else { offsets });
    w.u32s(indices);
}

/// Reads one CSR structure of `roots` rows and checks its shape and that
/// every index names another root.
fn read_csr(
    r: &mut Reader<'_>,
    roots: usize,
    offsets: &mut Vec<u32>,
    indices: &mut Vec<u32>,
    what: &str,
) -> Result<()> {
    r.u32s_into(offsets, Some(roots + 1))?;
    r.u32s_into(indices, None)?;
    if offsets[0] != 0 || offsets.windows(2).any(|w| w[0] > w[1]) || offsets[roots] as usize != indices.len() {
        return Err(invalid(format!("saved {what} offsets are not a valid row layout")));
    }
    for i in 0..roots as u32 {
        if row(offsets, indices, i).iter().any(|&j| j == i || j as usize >= roots) {
            return Err(invalid(format!("saved {what} row {i} names an invalid root")));
        }
    }
    Ok(())
}

fn invalid(message: impl Into<String>) -> Error {
    Error::new(ErrorKind::InvalidState, message)
}

/// Row `i` of a CSR structure (empty when `i` is out of range).
fn row<'a>(offsets: &[u32], indices: &'a [u32], i: u32) -> &'a [u32] {
    let i = i as usize;
    if i + 1 >= offsets.len() {
        return &[];
    }
    &indices[offsets[i] as usize..offsets[i + 1] as usize]
}

/// Whether two roots may be related: their normals do not disagree more
/// than `min_dot` allows. Symmetric bitwise (the dot product commutes).
#[inline]
fn normals_agree(a: &RootFrame, b: &RootFrame, min_dot: f32) -> bool {
    min_dot == f32::NEG_INFINITY || a.normal.dot(b.normal) >= min_dot
}

/// Feather reach as used by the obstacle test: negative or non-finite → 0.
#[inline]
fn sanitized_reach(r: f32) -> f32 {
    if r.is_finite() && r > 0.0 { r } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Roots on a wavy 12 × 12 patch, reach long enough for many obstacles.
    fn patch() -> (Vec<RootFrame>, Vec<f32>) {
        let frames: Vec<RootFrame> = (0..144)
            .map(|k| {
                let (x, y) = ((k % 12) as f32, (k / 12) as f32);
                let p = Vec3::new(x + 0.3 * (y * 1.7).sin(), y, 0.2 * (x * 0.9).sin());
                RootFrame::from_normal_and_direction(p, Vec3::Z, Vec3::X).unwrap()
            })
            .collect();
        let reach = (0..144).map(|k| 1.0 + (k % 5) as f32 * 0.4).collect();
        (frames, reach)
    }

    fn blob_of(write: impl FnOnce(&mut Writer)) -> Vec<u8> {
        let mut w = Writer::new(1);
        write(&mut w);
        w.finish()
    }

    fn read(blob: &[u8], roots: usize) -> Result<Neighbourhoods> {
        let mut r = Reader::open(blob, 1)?;
        let s = Neighbourhoods::read_state(&mut r, roots)?;
        r.finish()?;
        Ok(s)
    }

    #[test]
    fn leaf_pairs_give_the_tree_queries_obstacles_bitwise() {
        let mut rng = crate::rng::Rng::new(11);
        let (patch_frames, patch_reach) = patch();
        let mut cases = vec![(patch_frames, patch_reach)];
        for (n, spread) in [(1usize, 1.0f32), (17, 0.5), (600, 6.0), (2000, 20.0)] {
            let frames: Vec<RootFrame> = (0..n)
                .map(|k| {
                    // Some roots repeat a position exactly.
                    let p = if k % 37 == 5 {
                        Vec3::ZERO
                    } else {
                        Vec3::new(rng.next_f32(), rng.next_f32(), 0.3 * rng.next_f32()) * spread
                    };
                    RootFrame::from_normal_and_direction(p, Vec3::Z, Vec3::X).unwrap()
                })
                .collect();
            let reach = (0..n).map(|k| if k % 11 == 3 { 0.0 } else { 0.2 + rng.next_f32() }).collect();
            cases.push((frames, reach));
        }
        for (frames, reach) in cases {
            let mut nb = Neighbourhoods::new();
            nb.rebuild(&frames, &reach, &NeighbourParams::default());
            let mut by_tree = nb.clone();
            by_tree.obstacles_by_tree(&frames, &reach);
            assert_eq!(nb.obstacle_csr(), by_tree.obstacle_csr(), "{} roots", frames.len());
            // The k nearest from the rows are the tree's.
            let params = NeighbourParams::default();
            let mut best = Vec::new();
            for (i, frame) in frames.iter().enumerate() {
                let accept =
                    |j: u32| j as usize != i && normals_agree(frame, &frames[j as usize], params.min_normal_dot);
                nb.tree.nearest(frame.position, params.k, &accept, &mut best);
                let ids: Vec<u32> = best.iter().map(|b| b.1).collect();
                assert_eq!(nb.neighbours_of(i as u32), &ids[..], "root {i} of {}", frames.len());
            }
            nb.rebuild(&frames, &[], &NeighbourParams::default());
            assert!(nb.obstacle_csr().1.is_empty() && nb.obstacle_csr().0.len() == frames.len() + 1);
        }
    }

    #[test]
    fn round_trip_restores_every_relation() {
        let (frames, reach) = patch();
        let mut nb = Neighbourhoods::new();
        nb.rebuild(&frames, &reach, &NeighbourParams::default());
        assert!(nb.obstacle_csr().1.len() > 10 * frames.len(), "the patch must have many obstacles");
        let blob = blob_of(|w| nb.write_state(w));
        let back = read(&blob, frames.len()).unwrap();
        assert_eq!(back.neighbours_csr(), nb.neighbours_csr());
        assert_eq!(back.obstacle_csr(), nb.obstacle_csr());
        assert_eq!(back.pairs(), nb.pairs());
        assert_eq!(blob_of(|w| back.write_state(w)), blob);
        assert_eq!(read(&blob, frames.len() + 1).unwrap_err().kind(), ErrorKind::InvalidState);
        let empty = blob_of(|w| Neighbourhoods::new().write_state(w));
        assert!(read(&empty, 0).unwrap().is_empty());
    }

    #[test]
    fn hostile_rows_are_refused() {
        // Three roots; k-nearest rows, then the obstacle rows above the diagonal.
        let blob = |knn: (&[u32], &[u32]), obstacles: (&[u32], &[u32])| {
            blob_of(|w| {
                w.u32s(knn.0);
                w.u32s(knn.1);
                w.u32s(obstacles.0);
                w.u32s(obstacles.1);
            })
        };
        let good_knn: (&[u32], &[u32]) = (&[0, 1, 2, 3], &[1, 0, 1]);
        let good_obstacles: (&[u32], &[u32]) = (&[0, 2, 2, 2], &[1, 2]);
        let ok = read(&blob(good_knn, good_obstacles), 3).unwrap();
        assert_eq!(ok.obstacle_candidates_of(2), &[0]);
        assert_eq!(ok.pairs(), &[(0, 1), (1, 2)]);
        for (what, knn, obstacles) in [
            ("index out of range", (&[0u32, 1, 2, 3][..], &[1u32, 0, 7][..]), good_obstacles),
            ("own root", (&[0, 1, 2, 3], &[0, 0, 1]), good_obstacles),
            ("offsets decrease", (&[0, 2, 1, 3], &[1, 2, 1]), good_obstacles),
            ("offsets overrun", (&[0, 1, 2, 9], &[1, 0, 1]), good_obstacles),
            ("offsets not from 0", (&[1, 1, 2, 3], &[1, 0, 1]), good_obstacles),
            ("too few offsets", (&[0, 1, 3], &[1, 0, 1]), good_obstacles),
            ("obstacle below the diagonal", good_knn, (&[0, 0, 1, 1], &[0])),
            ("obstacle row unsorted", good_knn, (&[0, 2, 2, 2], &[2, 1])),
            ("obstacle row repeated", good_knn, (&[0, 2, 2, 2], &[1, 1])),
            ("obstacle out of range", good_knn, (&[0, 1, 1, 1], &[3])),
        ] {
            let err = read(&blob(knn, obstacles), 3).expect_err(what);
            assert_eq!(err.kind(), ErrorKind::InvalidState, "{what}");
        }
    }
}
