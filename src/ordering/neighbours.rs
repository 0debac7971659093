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

use super::kd_tree::{KdTree, insert_candidate, ranks_among_best};
use crate::error::{Error, ErrorKind, Result};
use crate::geometry::RootFrame;
use crate::snapshot::{Reader, Writer};
use rayon::prelude::*;

/// The leaf layout is kept while the sum of the leaves' box diagonals stays
/// within this factor of its value when the layout was made: larger boxes
/// only mean more candidates to test, never different rows.
const LAYOUT_SLACK: f32 = 1.2;

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

/// k-nearest neighbourhoods, the symmetric pair set and obstacle
/// candidates of one pose. Create once, call [`rebuild`](Self::rebuild) every frame.
/// A clone copies the relations only, not the scratch of `rebuild`.
#[derive(Debug, Default)]
pub struct Neighbourhoods {
    tree: KdTree,
    knn_offsets: Vec<u32>,
    knn_indices: Vec<u32>,
    pairs: Vec<(u32, u32)>,
    obstacle_offsets: Vec<u32>,
    obstacle_indices: Vec<u32>,
    bucket_offsets: Vec<u32>,
    bucket_items: Vec<u32>,
    fill_cursor: Vec<u32>,
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
            obstacle_offsets: self.obstacle_offsets.clone(),
            obstacle_indices: self.obstacle_indices.clone(),
            ..Self::default()
        }
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
        assert!(u32::try_from(frames.len()).is_ok(), "too many roots for u32 indices");
        assert!(reach.is_empty() || reach.len() == frames.len(), "reach must be empty or one length per root");
        self.tree_current = false;
        self.rebuild_rows(frames, reach, params);
        self.rebuild_pairs(frames.len());
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
        row(&self.obstacle_offsets, &self.obstacle_indices, i)
    }

    /// The obstacle candidates as CSR (same layout as [`neighbours_csr`](Self::neighbours_csr)).
    pub fn obstacle_csr(&self) -> (&[u32], &[u32]) {
        (&self.obstacle_offsets, &self.obstacle_indices)
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
    fn rebuild_rows(&mut self, frames: &[RootFrame], reach: &[f32], params: &NeighbourParams) {
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
        };
        self.chunks[..chunks].par_iter_mut().enumerate().for_each(|(c, chunk)| {
            let first = (c * per_chunk).min(leaves);
            let last = ((c + 1) * per_chunk).min(leaves);
            ctx.fill(first..last, chunk);
        });
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
        for (offsets, lens) in [(&mut self.obstacle_offsets, 0usize), (&mut self.knn_offsets, 1)] {
            offsets.clear();
            offsets.resize(n + 1, 0);
            for chunk in chunks {
                for (r, &i) in chunk.roots.iter().enumerate() {
                    let len = if lens == 0 { chunk.row_lens[r] } else { chunk.knn_lens[r] };
                    offsets[i as usize + 1] = len;
                }
            }
            for i in 0..n {
                offsets[i + 1] += offsets[i];
            }
        }
        self.obstacle_indices.clear();
        self.obstacle_indices.resize(self.obstacle_offsets[n] as usize, 0);
        self.knn_indices.clear();
        self.knn_indices.resize(self.knn_offsets[n] as usize, 0);
        for chunk in chunks {
            let (mut at, mut knn_at) = (0usize, 0usize);
            for (r, &i) in chunk.roots.iter().enumerate() {
                let (len, knn_len) = (chunk.row_lens[r] as usize, chunk.knn_lens[r] as usize);
                let to = self.obstacle_offsets[i as usize] as usize;
                self.obstacle_indices[to..to + len].copy_from_slice(&chunk.rows[at..at + len]);
                let to = self.knn_offsets[i as usize] as usize;
                self.knn_indices[to..to + knn_len].copy_from_slice(&chunk.knn[knn_at..knn_at + knn_len]);
                at += len;
                knn_at += knn_len;
            }
        }
    }
}

/// What the rows of a chunk of leaves read.
struct RowContext<'a> {
    frames: &'a [RootFrame],
    reach: &'a [f32],
    params: &'a NeighbourParams,
    min_reach: f32,
    ids: &'a [u32],
    starts: &'a [u32],
    points: &'a [(glam::Vec3, f32)],
    cells: &'a [Cell],
    nodes: &'a [Node],
    /// A tree over the current positions, when there is one.
    tree: Option<&'a KdTree>,
    /// The layout's generation (a chunk's cached unions are valid for it).
    generation: u64,
}

impl RowContext<'_> {
    /// The rows and k nearest of the roots of `leaves`, into `out`, root
    /// after root in tree order.
    fn fill(&self, leaves: std::ops::Range<usize>, out: &mut Chunk) {
        out.roots.clear();
        out.rows.clear();
        out.row_lens.clear();
        out.knn.clear();
        out.knn_lens.clear();
        out.deferred.clear();
        let (frames, params, k) = (self.frames, self.params, self.params.k);
        // The sorted unions of the last call are reused for the leaves whose
        // near leaves have not changed (same layout, same leaves).
        let reuse = out.cache_generation == self.generation && out.cache_leaves == (leaves.start, leaves.end);
        if !reuse {
            out.cached.iter_mut().for_each(|leaf| leaf.near.clear());
        }
        if out.cached.len() < leaves.len() {
            out.cached.resize_with(leaves.len(), CachedLeaf::default);
        }
        for (local, a) in leaves.clone().enumerate() {
            // The leaves within reach of leaf a (a included).
            out.near.clear();
            if !self.reach.is_empty() {
                let cell = &self.cells[a];
                out.stack.clear();
                out.stack.push(0);
                while let Some(x) = out.stack.pop() {
                    let node = &self.nodes[x as usize];
                    if !cell.may_reach(&node.cell) {
                        continue;
                    }
                    if node.children == u32::MAX {
                        out.near.push(node.leaf);
                    } else {
                        out.stack.push(node.children + 1);
                        out.stack.push(node.children);
                    }
                }
            }
            // Their roots sorted by index, so that every row comes out sorted.
            // (Sorted as packed (index, place in tree order) words: much
            // cheaper than sorting the points themselves.)
            let leaf = &mut out.cached[local];
            if !reuse || leaf.near != out.near {
                leaf.near.clear();
                leaf.near.extend_from_slice(&out.near);
                leaf.keys.clear();
                for &b in &out.near {
                    let roots = self.starts[b as usize] as usize..self.starts[b as usize + 1] as usize;
                    leaf.keys.extend(roots.map(|u| (u64::from(self.ids[u]) << 32) | u as u64));
                }
                leaf.keys.sort_unstable();
            }
            out.union.fill(&leaf.keys, self.points);
            let mut guess = f32::INFINITY;
            for t in self.starts[a] as usize..self.starts[a + 1] as usize {
                let (p, r) = self.points[t];
                let i = self.ids[t];
                let frame = &frames[i as usize];
                let row_start = out.rows.len();
                out.best.clear();
                let kept = out.union.scan(p, r, i, &mut out.rows, &mut out.d2);
                if k > 0 {
                    // First only the candidates within `guess` (twice the
                    // k-th distance of the leaf's previous root, squared
                    // ×4): when k of them are accepted, no farther
                    // candidate can rank among the k best, so the others
                    // are skipped; otherwise every candidate is ranked.
                    let (slots, d2s) = (&out.rows[row_start..], &out.d2[..kept]);
                    let rank = |best: &mut Vec<(f32, u32)>, bound: f32| {
                        for (&j, &d2) in slots.iter().zip(d2s) {
                            if d2 <= bound
                                && ranks_among_best(best, k, d2, j)
                                && normals_agree(frame, &frames[j as usize], params.min_normal_dot)
                            {
                                insert_candidate(best, k, d2, j);
                            }
                        }
                    };
                    rank(&mut out.best, guess);
                    if out.best.len() < k {
                        out.best.clear();
                        rank(&mut out.best, f32::INFINITY);
                    }
                    guess = if out.best.len() == k { 4.0 * out.best[k - 1].0 } else { f32::INFINITY };
                }
                let sure = self.reach.get(i as usize).map_or(0.0, |&r| sanitized_reach(r) + self.min_reach);
                let beyond = |d2: f32| d2.partial_cmp(&(sure * sure)).is_none_or(|o| o.is_gt());
                if k > 0 && (out.best.len() < k || out.best.last().is_some_and(|b| beyond(b.0))) {
                    match self.tree {
                        Some(tree) => {
                            let accept =
                                |j: u32| j != i && normals_agree(frame, &frames[j as usize], params.min_normal_dot);
                            tree.nearest(p, k, &accept, &mut out.best);
                        }
                        // Settled after the pass, with a current tree.
                        None => {
                            out.deferred.push(out.roots.len() as u32);
                            out.best.clear();
                        }
                    }
                }
                out.roots.push(i);
                out.row_lens.push((out.rows.len() - row_start) as u32);
                out.knn.extend(out.best.iter().map(|&(_, j)| j));
                out.knn_lens.push(out.best.len() as u32);
            }
        }
        out.cache_generation = self.generation;
        out.cache_leaves = (leaves.start, leaves.end);
    }
}

impl Chunk {
    /// The k nearest of the roots in `deferred` from `tree` (over the
    /// current positions), spliced into the chunk's lists.
    fn settle_deferred(&mut self, frames: &[RootFrame], params: &NeighbourParams, tree: &KdTree) {
        let (mut knn, mut lens) = (Vec::with_capacity(self.knn.len()), Vec::with_capacity(self.knn_lens.len()));
        let (mut at, mut next) = (0usize, 0usize);
        for (r, &i) in self.roots.iter().enumerate() {
            let len = self.knn_lens[r] as usize;
            if self.deferred.get(next) == Some(&(r as u32)) {
                next += 1;
                let frame = &frames[i as usize];
                let accept = |j: u32| j != i && normals_agree(frame, &frames[j as usize], params.min_normal_dot);
                tree.nearest(frame.position, params.k, &accept, &mut self.best);
                knn.extend(self.best.iter().map(|&(_, j)| j));
                lens.push(self.best.len() as u32);
            } else {
                knn.extend_from_slice(&self.knn[at..at + len]);
                lens.push(len as u32);
            }
            at += len;
        }
        self.knn = knn;
        self.knn_lens = lens;
        self.deferred.clear();
    }
}

/// One chunk's rows, root after root, and its scratch.
#[derive(Debug, Default)]
struct Chunk {
    roots: Vec<u32>,
    rows: Vec<u32>,
    row_lens: Vec<u32>,
    knn: Vec<u32>,
    knn_lens: Vec<u32>,
    near: Vec<u32>,
    union: Union,
    d2: Vec<f32>,
    stack: Vec<u32>,
    best: Vec<(f32, u32)>,
    /// Places in `roots` whose k nearest wait for a current tree.
    deferred: Vec<u32>,
    /// Per leaf of the last call (`cache_leaves` of layout
    /// `cache_generation`): its near leaves and their roots' sorted keys.
    cache_generation: u64,
    cache_leaves: (usize, usize),
    cached: Vec<CachedLeaf>,
}

/// A leaf's near leaves and their roots as sorted `(index << 32 | place in
/// layout order)` keys.
#[derive(Debug, Default)]
struct CachedLeaf {
    near: Vec<u32>,
    keys: Vec<u64>,
}

/// The roots of a leaf's near leaves, sorted by index, as columns (so that
/// the distance tests run several lanes at a time), padded to whole blocks
/// with entries that are never within reach (NaN coordinates).
#[derive(Debug, Default)]
struct Union {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    reach: Vec<f32>,
    id: Vec<u32>,
}

/// Entries a block of [`Union::scan`] tests at once.
const LANES: usize = 8;

impl Union {
    /// The roots of `keys` (index << 32 | place in layout order) with their
    /// position and reach from `points`.
    fn fill(&mut self, keys: &[u64], points: &[(glam::Vec3, f32)]) {
        let padded = keys.len().next_multiple_of(LANES);
        for column in [&mut self.x, &mut self.y, &mut self.z, &mut self.reach] {
            column.clear();
            column.reserve(padded);
        }
        self.id.clear();
        self.id.reserve(padded);
        for &key in keys {
            let (p, r) = points[key as u32 as usize];
            self.x.push(p.x);
            self.y.push(p.y);
            self.z.push(p.z);
            self.reach.push(r);
            self.id.push((key >> 32) as u32);
        }
        self.x.resize(padded, f32::NAN);
        self.y.resize(padded, f32::NAN);
        self.z.resize(padded, f32::NAN);
        self.reach.resize(padded, 0.0);
        self.id.resize(padded, u32::MAX);
    }

    /// Appends to `row` every root `j ≠ i` with `|r_j − p|² ≤ (r + reach_j)²`,
    /// in order, and writes its squared distance to the front of `d2s`
    /// (which only ever grows); returns how many. The
    /// distance is computed as `(r_j − p).length_squared()` is, operation
    /// for operation (lane by lane in `f32`, no fused multiply-add), so the
    /// test is bitwise the one of a radius query.
    #[inline]
    fn scan(&self, p: glam::Vec3, r: f32, i: u32, row: &mut Vec<u32>, d2s: &mut Vec<f32>) -> usize {
        row.reserve(self.id.len());
        if d2s.len() < self.id.len() {
            d2s.resize(self.id.len(), 0.0);
        }
        let base = row.len();
        let (slots, distances) = (&mut row.spare_capacity_mut()[..self.id.len()], &mut d2s[..]);
        let mut kept = 0;
        let blocks = self
            .x
            .chunks_exact(LANES)
            .zip(self.y.chunks_exact(LANES))
            .zip(self.z.chunks_exact(LANES))
            .zip(self.reach.chunks_exact(LANES))
            .zip(self.id.chunks_exact(LANES));
        let mut d2 = [0.0f32; LANES];
        for ((((x, y), z), reach), id) in blocks {
            let mask = within_mask(x, y, z, reach, p, r, &mut d2);
            // Branch-free: every lane is written, and the cursor moves past
            // those within reach other than the root itself (`kept` never
            // passes the lane's own place, so the writes stay in bounds).
            for l in 0..LANES {
                slots[kept] = std::mem::MaybeUninit::new(id[l]);
                distances[kept] = d2[l];
                kept += ((mask >> l) & 1) as usize & usize::from(id[l] != i);
            }
        }
        // SAFETY: the first `kept` spare slots were written (each lane is
        // written before the cursor moves past it), within the capacity
        // reserved above.
        unsafe { row.set_len(base + kept) };
        kept
    }
}

/// For one block of [`LANES`] entries: writes `|r_j − p|²` to `d2` and
/// returns the mask of the lanes with `d2 ≤ (r + reach_j)²` (NaN never
/// within).
#[inline]
fn within_mask(x: &[f32], y: &[f32], z: &[f32], reach: &[f32], p: glam::Vec3, r: f32, d2: &mut [f32; LANES]) -> u32 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::*;
        assert!(x.len() == LANES && y.len() == LANES && z.len() == LANES && reach.len() == LANES);
        // SAFETY: SSE2 is part of the x86_64 baseline; every load and store
        // reads or writes 4 lanes inside a slice of LANES = 8 (checked above).
        unsafe {
            let (px, py, pz, pr) = (_mm_set1_ps(p.x), _mm_set1_ps(p.y), _mm_set1_ps(p.z), _mm_set1_ps(r));
            let mut mask = 0u32;
            for half in 0..LANES / 4 {
                let at = half * 4;
                let dx = _mm_sub_ps(_mm_loadu_ps(x.as_ptr().add(at)), px);
                let dy = _mm_sub_ps(_mm_loadu_ps(y.as_ptr().add(at)), py);
                let dz = _mm_sub_ps(_mm_loadu_ps(z.as_ptr().add(at)), pz);
                let dd = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
                let limit = _mm_add_ps(pr, _mm_loadu_ps(reach.as_ptr().add(at)));
                let within = _mm_cmple_ps(dd, _mm_mul_ps(limit, limit));
                _mm_storeu_ps(d2.as_mut_ptr().add(at), dd);
                mask |= (_mm_movemask_ps(within) as u32) << at;
            }
            mask
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let mut mask = 0u32;
        for l in 0..LANES {
            let (dx, dy, dz) = (x[l] - p.x, y[l] - p.y, z[l] - p.z);
            d2[l] = (dx * dx) + (dy * dy) + (dz * dz);
            let limit = r + reach[l];
            mask |= u32::from(d2[l] <= limit * limit) << l;
        }
        mask
    }
}

/// A box of the hierarchy over the leaves: a leaf (`children == u32::MAX`)
/// or the union of two halves stored at `children` and `children + 1`.
#[derive(Clone, Copy, Debug)]
struct Node {
    cell: Cell,
    leaf: u32,
    children: u32,
}

/// The hierarchy over the leaves `[lo, hi)`: its root at index 0.
fn build_nodes(cells: &[Cell], lo: u32, hi: u32, nodes: &mut Vec<Node>) {
    nodes.push(Node { cell: cells[lo as usize], leaf: lo, children: u32::MAX });
    build_subtree(cells, lo, hi, nodes, 0);
}

/// Fills the node at `slot` with the leaves `[lo, hi)`; returns its box.
fn build_subtree(cells: &[Cell], lo: u32, hi: u32, nodes: &mut Vec<Node>, slot: u32) -> Cell {
    if hi - lo == 1 {
        nodes[slot as usize] = Node { cell: cells[lo as usize], leaf: lo, children: u32::MAX };
        return cells[lo as usize];
    }
    let children = nodes.len() as u32;
    nodes.push(Node { cell: cells[lo as usize], leaf: lo, children: u32::MAX });
    nodes.push(Node { cell: cells[lo as usize], leaf: lo, children: u32::MAX });
    let mid = lo + (hi - lo) / 2;
    let left = build_subtree(cells, lo, mid, nodes, children);
    let right = build_subtree(cells, mid, hi, nodes, children + 1);
    let cell = left.union(&right);
    nodes[slot as usize] = Node { cell, leaf: lo, children };
    cell
}

/// A leaf of the tree: the box of its roots and their longest reach.
#[derive(Clone, Copy, Debug)]
struct Cell {
    lo: glam::Vec3,
    hi: glam::Vec3,
    reach: f32,
}

impl Cell {
    /// The box around both cells, with the longer reach.
    fn union(&self, other: &Cell) -> Cell {
        Cell { lo: self.lo.min(other.lo), hi: self.hi.max(other.hi), reach: self.reach.max(other.reach) }
    }

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
        self.tree.rebuild(frames.iter().map(|f| f.position));
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

    /// Roots of a jittered 48 × 24 strip folding about the line x = 24 by
    /// `t` half-turns, the folded half landing a little above the other (a
    /// wing coming against the flank) and stretched along y as it goes.
    fn folding_strip(t: f32, rng: &mut crate::rng::Rng) -> Vec<RootFrame> {
        (0..48 * 24)
            .map(|k| {
                let (x, y) = ((k % 48) as f32 + 0.3 * rng.next_f32(), (k / 48) as f32 + 0.3 * rng.next_f32());
                let (p, n) = if x <= 24.0 {
                    (Vec3::new(x, y, 0.0), Vec3::Z)
                } else {
                    // Rolled about a hinge 0.6 above the plane.
                    let a = std::f32::consts::PI * t;
                    let (sin, cos) = a.sin_cos();
                    let (u, v) = (x - 24.0, -0.6);
                    let p = Vec3::new(24.0 + u * cos - v * sin, y * (1.0 + 0.1 * t), 0.6 + u * sin + v * cos);
                    (p, Vec3::new(-sin, 0.0, cos))
                };
                RootFrame::from_normal_and_direction(p, n, Vec3::Y).unwrap()
            })
            .collect()
    }

    /// Every relation by exhaustive search, in the same `f32` operations.
    fn exhaustive(frames: &[RootFrame], reach: &[f32], params: &NeighbourParams) -> (Vec<Vec<u32>>, Vec<Vec<u32>>) {
        let n = frames.len();
        let d2 = |i: usize, j: usize| (frames[j].position - frames[i].position).length_squared();
        let rows = (0..n)
            .map(|i| {
                (0..n as u32)
                    .filter(|&j| {
                        let (j, limit) = (j as usize, sanitized_reach(reach[i]) + sanitized_reach(reach[j as usize]));
                        j != i && d2(i, j) <= limit * limit
                    })
                    .collect()
            })
            .collect();
        let knn = (0..n)
            .map(|i| {
                let mut all: Vec<(f32, u32)> = (0..n)
                    .filter(|&j| j != i && normals_agree(&frames[i], &frames[j], params.min_normal_dot))
                    .map(|j| (d2(i, j), j as u32))
                    .collect();
                all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                all.iter().take(params.k).map(|e| e.1).collect()
            })
            .collect();
        (rows, knn)
    }

    #[test]
    fn rows_and_nearest_match_the_exhaustive_search_on_a_fold_at_any_thread_count() {
        let params = NeighbourParams::default();
        let reach: Vec<f32> =
            (0..48 * 24).map(|k| if k % 97 == 5 { 0.0 } else { 1.2 + (k % 7) as f32 * 0.2 }).collect();
        let pools: Vec<rayon::ThreadPool> =
            [1, 2, 3].iter().map(|&t| rayon::ThreadPoolBuilder::new().num_threads(t).build().unwrap()).collect();
        // One `Neighbourhoods` through every pose and thread count: its leaf
        // layout is kept while the leaves stay compact, and then the roots
        // of reach 0 (whose k nearest the rows cannot settle) wait for a
        // tree over the current positions.
        let mut nb = Neighbourhoods::new();
        let mut fold_pairs = 0;
        let mut rebuilds = 0;
        for (step, t) in [0.0f32, 0.3, 0.6, 0.85, 0.97, 1.0].into_iter().enumerate() {
            let frames = folding_strip(t, &mut crate::rng::Rng::new(5));
            let (rows, knn) = exhaustive(&frames, &reach, &params);
            // Pairs across the hinge line that only the fold brings together.
            fold_pairs = (0..frames.len())
                .map(|i| rows[i].iter().filter(|&&j| (i % 48 < 12) && (j as usize % 48 > 36)).count())
                .sum::<usize>();
            let mut seen = Vec::new();
            for pool in &pools {
                pool.install(|| nb.rebuild(&frames, &reach, &params));
                rebuilds += 1;
                for i in 0..frames.len() {
                    assert_eq!(nb.obstacle_candidates_of(i as u32), &rows[i][..], "row {i}, pose {step}");
                    assert_eq!(nb.neighbours_of(i as u32), &knn[i][..], "nearest of {i}, pose {step}");
                }
                seen.push((nb.obstacle_csr().0.to_vec(), nb.obstacle_csr().1.to_vec(), nb.pairs().to_vec()));
            }
            assert!(seen.windows(2).all(|w| w[0] == w[1]), "pose {step} depends on the thread count");
        }
        assert!(fold_pairs > 100, "the folded pose must bring far roots together ({fold_pairs} pairs)");
        assert_eq!(nb.layout_generation, 1, "the fold keeps the leaves compact: one layout throughout");
        assert!(rebuilds > 2);
        // Stretched to 1.5 times its size, the strip's leaves spread out and
        // are laid out again; the rows still match.
        let stretched: Vec<RootFrame> = folding_strip(0.5, &mut crate::rng::Rng::new(5))
            .iter()
            .map(|f| RootFrame { position: f.position * 1.5, ..*f })
            .collect();
        let (rows, knn) = exhaustive(&stretched, &reach, &params);
        nb.rebuild(&stretched, &reach, &params);
        assert_eq!(nb.layout_generation, 2, "stretched leaves must be laid out again");
        for i in 0..stretched.len() {
            assert_eq!(nb.obstacle_candidates_of(i as u32), &rows[i][..], "row {i}, stretched");
            assert_eq!(nb.neighbours_of(i as u32), &knn[i][..], "nearest of {i}, stretched");
        }
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
