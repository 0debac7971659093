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
//! for the obstacle candidates: a hierarchy of boxes over the leaves finds
//! each leaf's leaves within reach, and each root compares itself with
//! their roots, which costs far less than one radius query per root. The
//! leaves are shared out among the threads; each root's row and k nearest
//! depend on the positions alone, so nothing depends on the thread count.
//!
//! From frame to frame the leaves (which roots go together) are kept while
//! their boxes at the current pose stay compact, and so is each leaf's
//! sorted list of candidate roots while its near leaves stay the same: the
//! roots do not move on the body, so most of a frame's work is the distance
//! tests, run several lanes at a time. None of this changes a row.
//!
//! Thin parts (the two skins of a wing) put roots close in space that are far
//! apart on the surface. Roots whose normals disagree strongly
//! (`n_i·n_j < min_normal_dot`) are never neighbours or pairs of each other
//! (their order says nothing). They stay obstacle candidates: a feather
//! reaching round the rim of a wing can meet one from the other skin, and
//! the adjustment checks those exactly.

mod blob;
mod params;
mod rows;
crate::memory::heap_size_of_fields!(Neighbourhoods {
    tree, knn_offsets, knn_indices, pairs, obstacles, pair_buckets, leaf_ids, leaf_starts, points, cells, nodes, chunks, #[cfg(test)] scratch_indices
} plain { layout_generation, layout_roots, layout_spread, tree_current });

#[cfg(test)]
mod tests;

use super::kd_tree::KdTree;
use crate::csr::{Csr, CsrView};
use crate::geometry::RootFrame;
pub use params::NeighbourParams;
use params::{row, sanitized_reach};
use rayon::prelude::*;
use rows::{Cell, Chunk, Node, RowContext, build_nodes};

/// The leaf layout is kept while the sum of the leaves' box diagonals stays
/// within this factor of its value when the layout was made: larger boxes
/// only mean more candidates to test, never different rows.
const LAYOUT_SLACK: f32 = 1.2;

/// k-nearest neighbourhoods, the symmetric pair set and obstacle
/// candidates of one pose. Create once, call [`rebuild`](Self::rebuild) every frame.
/// A clone copies the relations only, not the scratch of `rebuild`.
#[derive(Debug, Default)]
pub struct Neighbourhoods {
    tree: KdTree,
    knn_offsets: Vec<u32>,
    knn_indices: Vec<u32>,
    pairs: Vec<(u32, u32)>,
    /// Obstacle candidates, row i sorted by index.
    obstacles: Csr<u32>,
    /// Scratch of [`rebuild_pairs`](Self::rebuild_pairs): the larger ends
    /// of the pairs, by smaller end.
    pair_buckets: Csr<u32>,
    /// The leaf layout: root ids in tree order and where each leaf starts.
    /// Kept from frame to frame while the leaves stay compact (see
    /// [`LAYOUT_SLACK`]); the rows do not depend on it.
    leaf_ids: Vec<u32>,
    leaf_starts: Vec<u32>,
    /// Bumped at every new layout (0: none yet).
    layout_generation: u64,
    /// Root count of the layout.
    layout_roots: usize,
    /// Sum of the leaves' box diagonals when the layout was made.
    layout_spread: f32,
    /// Whether `tree` holds the current positions (the layout's tree is
    /// stale once the roots move; the k nearest's fallback then builds one).
    tree_current: bool,
    points: Vec<(glam::Vec3, f32)>,
    cells: Vec<Cell>,
    nodes: Vec<Node>,
    chunks: Vec<Chunk>,
    #[cfg(test)]
    scratch_indices: Vec<u32>,
}

impl Clone for Neighbourhoods {
    fn clone(&self) -> Self {
        Self {
            knn_offsets: self.knn_offsets.clone(),
            knn_indices: self.knn_indices.clone(),
            pairs: self.pairs.clone(),
            obstacles: self.obstacles.clone(),
            ..Self::default()
        }
    }

    /// The rows, k nearest and pairs cloned in place, reusing their
    /// buffers; as with `clone`, the layout and its caches are not copied
    /// (and the target's own are dropped).
    fn clone_from(&mut self, source: &Self) {
        let Self { knn_offsets, knn_indices, pairs, obstacles, .. } = source;
        let kept = (
            std::mem::take(&mut self.knn_offsets),
            std::mem::take(&mut self.knn_indices),
            std::mem::take(&mut self.pairs),
            std::mem::take(&mut self.obstacles),
        );
        *self = Self::default();
        (self.knn_offsets, self.knn_indices, self.pairs, self.obstacles) = kept;
        self.knn_offsets.clone_from(knn_offsets);
        self.knn_indices.clone_from(knn_indices);
        self.pairs.clone_from(pairs);
        self.obstacles.clone_from(obstacles);
    }
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
        let built = self.rebuild_until(frames, reach, params, &|| true);
        debug_assert!(built);
    }

    /// As [`Neighbourhoods::rebuild`], asking `keep_going` between leaves;
    /// once it says stop, returns `false` with the rows half built (the
    /// caller abandons them: it restores the neighbourhoods it had).
    pub fn rebuild_until(
        &mut self,
        frames: &[RootFrame],
        reach: &[f32],
        params: &NeighbourParams,
        keep_going: &(dyn Fn() -> bool + Sync),
    ) -> bool {
        assert!(u32::try_from(frames.len()).is_ok(), "too many roots for u32 indices");
        assert!(reach.is_empty() || reach.len() == frames.len(), "reach must be empty or one length per root");
        self.tree_current = false;
        if !self.rebuild_rows(frames, reach, params, keep_going) {
            return false;
        }
        self.rebuild_pairs(frames.len());
        true
    }

    /// A new leaf layout from a k-d tree over the current positions.
    fn new_layout(&mut self, frames: &[RootFrame]) {
        self.tree.rebuild(frames.iter().map(|f| f.position));
        self.tree_current = true;
        self.tree.leaves(&mut self.leaf_ids, &mut self.leaf_starts);
        self.layout_generation += 1;
        self.layout_roots = frames.len();
    }

    /// The roots in layout order with their reach, and each leaf's box.
    fn gather_cells(&mut self, frames: &[RootFrame], reach: &[f32]) {
        let ids = &self.leaf_ids;
        let with_reach = !reach.is_empty();
        self.points.clear();
        self.points.extend(ids.iter().map(|&i| {
            (frames[i as usize].position, if with_reach { sanitized_reach(reach[i as usize]) } else { 0.0 })
        }));
        self.cells.clear();
        for w in self.leaf_starts.windows(2) {
            let points = &self.points[w[0] as usize..w[1] as usize];
            let (lo, hi, reach) =
                points.iter().fold((glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY, 0.0f32), |(lo, hi, r), &(p, q)| {
                    (lo.min(p), hi.max(p), r.max(q))
                });
            self.cells.push(Cell { lo, hi, reach });
        }
    }

    /// Sum of the leaves' box diagonals.
    fn spread(&self) -> f32 {
        self.cells.iter().map(|c| (c.hi - c.lo).length()).sum()
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
        self.obstacles.row(i as usize)
    }

    /// The obstacle candidates, row i those of root i.
    pub fn obstacle_csr(&self) -> CsrView<'_, u32> {
        self.obstacles.view()
    }

    /// How many obstacle candidates the rows have room for: a bound for
    /// the copies and transposes of them that must not allocate while
    /// the candidates vary from frame to frame.
    pub fn obstacle_capacity(&self) -> usize {
        self.obstacles.items_capacity()
    }

    /// Symmetrises the neighbourhoods into sorted unique `(lo, hi)` pairs with
    /// a counting sort on `lo` followed by a small sort per bucket.
    fn rebuild_pairs(&mut self, n: usize) {
        let (offsets, indices) = (&self.knn_offsets, &self.knn_indices);
        let buckets = &mut self.pair_buckets;
        buckets.begin(n);
        for i in 0..n as u32 {
            for &j in row(offsets, indices, i) {
                buckets.count(i.min(j) as usize);
            }
        }
        buckets.allocate();
        for i in 0..n as u32 {
            for &j in row(offsets, indices, i) {
                buckets.place(i.min(j) as usize, i.max(j));
            }
        }
        self.pairs.clear();
        for lo in 0..n {
            let bucket = buckets.row_mut(lo);
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

    /// Obstacle candidates and the k nearest roots, row by row.
    ///
    /// The tree's leaves (up to 16 roots lying close together) are cells:
    /// a hierarchy of boxes over them (halves of the leaf sequence, which
    /// the k-d tree laid out in space) finds for each leaf the leaves that
    /// come within the sum of their longest reaches. Each root then
    /// compares itself with the roots of those leaves, keeps those within
    /// `reach_i + reach_j` as its row (sorted by index) and picks its k
    /// nearest among them as it goes. The leaves are shared out among the
    /// threads in chunks; every row depends on the positions alone, so the
    /// rows are the same at any thread count, and they are those of one
    /// radius query per root (the pruning is exact: a box gap is never
    /// larger in `f32` than the gap between two of the boxes' points,
    /// computed the same way; the test `|r_i − r_j|² ≤ (reach_i + reach_j)²`
    /// is bitwise symmetric in i and j).
    ///
    /// The k nearest: every root within `reach_i + min reach` of root i
    /// whose normal agrees is an obstacle candidate of i, so when i's k-th
    /// nearest candidate lies that close its candidates hold its k nearest
    /// roots; only the other roots (none on a closed coat) query the tree.
    /// Both ways rank candidates by the same `(|r_j − r_i|², j)`, so the
    /// rows are those of the tree alone.
    fn rebuild_rows(
        &mut self,
        frames: &[RootFrame],
        reach: &[f32],
        params: &NeighbourParams,
        keep_going: &(dyn Fn() -> bool + Sync),
    ) -> bool {
        let n = frames.len();
        let fresh = self.layout_generation == 0 || self.layout_roots != n;
        if fresh {
            self.new_layout(frames);
        }
        self.gather_cells(frames, reach);
        if fresh {
            self.layout_spread = self.spread();
        } else if self.spread().partial_cmp(&(LAYOUT_SLACK * self.layout_spread)).is_none_or(|o| o.is_gt()) {
            // The leaves have spread out (or a position is not finite):
            // lay them out again at this pose.
            self.new_layout(frames);
            self.gather_cells(frames, reach);
            self.layout_spread = self.spread();
        }
        let ids = &self.leaf_ids;
        self.nodes.clear();
        if !self.cells.is_empty() {
            build_nodes(&self.cells, 0, self.cells.len() as u32, &mut self.nodes);
        }
        let min_reach = reach.iter().fold(f32::INFINITY, |m, &r| m.min(sanitized_reach(r)));
        // Chunks of leaves of about equal size, a few per thread.
        let leaves = self.cells.len();
        let chunks = (rayon::current_num_threads().max(1) * 4).min(leaves.max(1));
        if self.chunks.len() < chunks {
            self.chunks.resize_with(chunks, Chunk::default);
        }
        let per_chunk = leaves.div_ceil(chunks).max(1);
        let ctx = RowContext {
            frames,
            reach,
            params,
            min_reach,
            ids,
            starts: &self.leaf_starts,
            points: &self.points,
            cells: &self.cells,
            nodes: &self.nodes,
            tree: self.tree_current.then_some(&self.tree),
            generation: self.layout_generation,
            keep_going,
        };
        self.chunks[..chunks].par_iter_mut().enumerate().for_each(|(c, chunk)| {
            let first = (c * per_chunk).min(leaves);
            let last = ((c + 1) * per_chunk).min(leaves);
            ctx.fill(first..last, chunk);
        });
        if !keep_going() {
            return false;
        }
        // The k nearest the rows could not settle, with a tree over the
        // current positions (the layout's tree is stale).
        if self.chunks[..chunks].iter().any(|c| !c.deferred.is_empty()) {
            self.tree.rebuild(frames.iter().map(|f| f.position));
            self.tree_current = true;
            for chunk in self.chunks[..chunks].iter_mut().filter(|c| !c.deferred.is_empty()) {
                chunk.settle_deferred(frames, params, &self.tree);
            }
        }
        // Gather the rows by root index.
        let chunks = &self.chunks[..chunks];
        self.obstacles.begin(n);
        self.knn_offsets.clear();
        self.knn_offsets.resize(n + 1, 0);
        for chunk in chunks {
            for (r, &i) in chunk.roots.iter().enumerate() {
                self.obstacles.count_many(i as usize, chunk.row_lens[r] as usize);
                self.knn_offsets[i as usize + 1] = chunk.knn_lens[r];
            }
        }
        for i in 0..n {
            self.knn_offsets[i + 1] += self.knn_offsets[i];
        }
        self.obstacles.allocate();
        self.knn_indices.clear();
        self.knn_indices.resize(self.knn_offsets[n] as usize, 0);
        for chunk in chunks {
            let (mut at, mut knn_at) = (0usize, 0usize);
            for (r, &i) in chunk.roots.iter().enumerate() {
                let (len, knn_len) = (chunk.row_lens[r] as usize, chunk.knn_lens[r] as usize);
                self.obstacles.place_all(i as usize, &chunk.rows[at..at + len]);
                let to = self.knn_offsets[i as usize] as usize;
                self.knn_indices[to..to + knn_len].copy_from_slice(&chunk.knn[knn_at..knn_at + knn_len]);
                at += len;
                knn_at += knn_len;
            }
        }
        true
    }
}
