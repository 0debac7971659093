//! The rows of a chunk of k-d leaves: each leaf's near leaves through a
//! hierarchy of boxes over the leaves, their roots tested several lanes at
//! a time, the k nearest picked in the same pass.

use super::super::kd_tree::{KdTree, insert_candidate, ranks_among_best};
use super::params::{NeighbourParams, normals_agree, sanitized_reach};
use crate::geometry::RootFrame;

/// What the rows of a chunk of leaves read.
pub(super) struct RowContext<'a> {
    pub(super) frames: &'a [RootFrame],
    pub(super) reach: &'a [f32],
    pub(super) params: &'a NeighbourParams,
    pub(super) min_reach: f32,
    pub(super) ids: &'a [u32],
    pub(super) starts: &'a [u32],
    pub(super) points: &'a [(glam::Vec3, f32)],
    pub(super) cells: &'a [Cell],
    pub(super) nodes: &'a [Node],
    /// A tree over the current positions, when there is one.
    pub(super) tree: Option<&'a KdTree>,
    /// The layout's generation (a chunk's cached unions are valid for it).
    pub(super) generation: u64,
    /// Asked every few leaves; once it says stop, the chunk is left half
    /// filled (the caller abandons the rows).
    pub(super) keep_going: &'a (dyn Fn() -> bool + Sync),
}

impl RowContext<'_> {
    /// The rows and k nearest of the roots of `leaves`, into `out`, root
    /// after root in tree order.
    pub(super) fn fill(&self, leaves: std::ops::Range<usize>, out: &mut Chunk) {
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
            if local % 4 == 3 && !(self.keep_going)() {
                // Not reusable: the cache marks below are not reached.
                out.cache_generation = 0;
                return;
            }
            self.near_leaves(a, &mut out.stack, &mut out.near);
            let leaf = &mut out.cached[local];
            if !reuse || leaf.near != out.near {
                self.sort_roots(&out.near, leaf);
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

impl RowContext<'_> {
    /// Into `near`, the leaves within reach of leaf `a` (`a` included; none
    /// without reaches).
    fn near_leaves(&self, a: usize, stack: &mut Vec<u32>, near: &mut Vec<u32>) {
        near.clear();
        if self.reach.is_empty() {
            return;
        }
        let cell = &self.cells[a];
        stack.clear();
        stack.push(0);
        while let Some(x) = stack.pop() {
            let node = &self.nodes[x as usize];
            if !cell.may_reach(&node.cell) {
                continue;
            }
            if node.children == u32::MAX {
                near.push(node.leaf);
            } else {
                stack.push(node.children + 1);
                stack.push(node.children);
            }
        }
    }

    /// Makes `leaf` the leaves `near` with their roots sorted by index, so
    /// that every row comes out sorted. (Sorted as packed (index, place in
    /// tree order) words: much cheaper than sorting the points themselves.)
    fn sort_roots(&self, near: &[u32], leaf: &mut CachedLeaf) {
        leaf.near.clear();
        leaf.near.extend_from_slice(near);
        leaf.keys.clear();
        for &b in near {
            let roots = self.starts[b as usize] as usize..self.starts[b as usize + 1] as usize;
            leaf.keys.extend(roots.map(|u| (u64::from(self.ids[u]) << 32) | u as u64));
        }
        leaf.keys.sort_unstable();
    }
}

impl Chunk {
    /// The k nearest of the roots in `deferred` from `tree` (over the
    /// current positions), spliced into the chunk's lists.
    pub(super) fn settle_deferred(&mut self, frames: &[RootFrame], params: &NeighbourParams, tree: &KdTree) {
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
pub(super) struct Chunk {
    pub(super) roots: Vec<u32>,
    pub(super) rows: Vec<u32>,
    pub(super) row_lens: Vec<u32>,
    pub(super) knn: Vec<u32>,
    pub(super) knn_lens: Vec<u32>,
    pub(super) near: Vec<u32>,
    pub(super) union: Union,
    pub(super) d2: Vec<f32>,
    pub(super) stack: Vec<u32>,
    pub(super) best: Vec<(f32, u32)>,
    /// Places in `roots` whose k nearest wait for a current tree.
    pub(super) deferred: Vec<u32>,
    /// Per leaf of the last call (`cache_leaves` of layout
    /// `cache_generation`): its near leaves and their roots' sorted keys.
    pub(super) cache_generation: u64,
    pub(super) cache_leaves: (usize, usize),
    pub(super) cached: Vec<CachedLeaf>,
}

/// A leaf's near leaves and their roots as sorted `(index << 32 | place in
/// layout order)` keys.
#[derive(Debug, Default)]
pub(super) struct CachedLeaf {
    pub(super) near: Vec<u32>,
    pub(super) keys: Vec<u64>,
}

/// The roots of a leaf's near leaves, sorted by index, as columns (so that
/// the distance tests run several lanes at a time), padded to whole blocks
/// with entries that are never within reach (NaN coordinates).
#[derive(Debug, Default)]
pub(super) struct Union {
    pub(super) x: Vec<f32>,
    pub(super) y: Vec<f32>,
    pub(super) z: Vec<f32>,
    pub(super) reach: Vec<f32>,
    pub(super) id: Vec<u32>,
}

/// Entries a block of [`Union::scan`] tests at once.
pub(super) const LANES: usize = 8;

impl Union {
    /// The roots of `keys` (index << 32 | place in layout order) with their
    /// position and reach from `points`.
    pub(super) fn fill(&mut self, keys: &[u64], points: &[(glam::Vec3, f32)]) {
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
    pub(super) fn scan(&self, p: glam::Vec3, r: f32, i: u32, row: &mut Vec<u32>, d2s: &mut Vec<f32>) -> usize {
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
pub(super) fn within_mask(
    x: &[f32],
    y: &[f32],
    z: &[f32],
    reach: &[f32],
    p: glam::Vec3,
    r: f32,
    d2: &mut [f32; LANES],
) -> u32 {
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
pub(super) struct Node {
    pub(super) cell: Cell,
    pub(super) leaf: u32,
    pub(super) children: u32,
}

/// The hierarchy over the leaves `[lo, hi)`: its root at index 0.
pub(super) fn build_nodes(cells: &[Cell], lo: u32, hi: u32, nodes: &mut Vec<Node>) {
    nodes.push(Node { cell: cells[lo as usize], leaf: lo, children: u32::MAX });
    build_subtree(cells, lo, hi, nodes, 0);
}

/// Fills the node at `slot` with the leaves `[lo, hi)`; returns its box.
pub(super) fn build_subtree(cells: &[Cell], lo: u32, hi: u32, nodes: &mut Vec<Node>, slot: u32) -> Cell {
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
pub(super) struct Cell {
    pub(super) lo: glam::Vec3,
    pub(super) hi: glam::Vec3,
    pub(super) reach: f32,
}

impl Cell {
    /// The box around both cells, with the longer reach.
    pub(super) fn union(&self, other: &Cell) -> Cell {
        Cell { lo: self.lo.min(other.lo), hi: self.hi.max(other.hi), reach: self.reach.max(other.reach) }
    }

    /// Whether a root of `self` and one of `other` may lie within the sum
    /// of their reaches: the gap between the boxes, squared as a point
    /// distance is, is within the sum of the longest reaches. Per axis the
    /// `f32` gap is no larger than any two points' `f32` difference
    /// (rounding is monotone), so no pair within reach is left out.
    #[inline]
    pub(super) fn may_reach(&self, other: &Cell) -> bool {
        let gap = (other.lo - self.hi).max(self.lo - other.hi).max(glam::Vec3::ZERO);
        let limit = self.reach + other.reach;
        gap.length_squared() <= limit * limit
    }
}

crate::memory::heap_size_of_fields!(Chunk { roots, rows, row_lens, knn, knn_lens, near, union, d2, stack, best, deferred, cached } plain {
    cache_generation, cache_leaves
});
crate::memory::heap_size_of_fields!(CachedLeaf { near, keys });
crate::memory::heap_size_of_fields!(Union { x, y, z, reach, id });
impl crate::memory::HeapSize for Vec<Chunk> {
    fn heap_bytes(&self) -> usize {
        crate::memory::nested_heap_bytes(self)
    }
}
impl crate::memory::HeapSize for Vec<CachedLeaf> {
    fn heap_bytes(&self) -> usize {
        crate::memory::nested_heap_bytes(self)
    }
}
