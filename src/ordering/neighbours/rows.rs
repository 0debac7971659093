//! The rows of a chunk of k-d leaves: each leaf's near leaves through a
//! hierarchy of boxes over the leaves; at a leaf's reference pose their
//! roots tested several lanes at a time into the leaf's kept lists, and at
//! the other poses those lists filtered (see [`super::reuse`]); the k
//! nearest picked in the same pass.

use super::super::kd_tree::{KdTree, insert_candidate, ranks_among_best};
use super::params::{NeighbourParams, normals_agree, sanitized_reach};
use super::reuse::{AnchorMap, MARGIN};
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
    /// Each leaf's near leaves at the current pose, as CSR ([`near_pairs`]).
    pub(super) near_starts: &'a [u32],
    pub(super) near: &'a [u32],
    /// A tree over the current positions, when there is one.
    pub(super) tree: Option<&'a KdTree>,
    /// The layout's generation (a chunk's cached unions are valid for it).
    pub(super) generation: u64,
}

impl RowContext<'_> {
    /// The rows and k nearest of the roots of `leaves`, into `out`, root
    /// after root in tree order.
    ///
    /// Each leaf keeps candidate lists made at an earlier pose (see
    /// [`super::reuse`]); they are filtered at the current pose while their
    /// certificate holds, and made again at the current pose when it fails.
    /// Either way every row and k nearest is the exhaustive search's.
    pub(super) fn fill(&self, leaves: std::ops::Range<usize>, out: &mut Chunk) {
        out.roots.clear();
        out.rows.clear();
        out.row_lens.clear();
        out.knn.clear();
        out.knn_lens.clear();
        out.deferred.clear();
        out.leaves_remade = 0;
        // The lists of the last call hold for the same leaves of the same
        // layout (and the same reach and parameters).
        let reuse = out.cache_generation == self.generation && out.cache_leaves == (leaves.start, leaves.end);
        if !reuse {
            out.cached.iter_mut().for_each(|leaf| leaf.valid = false);
        }
        if out.cached.len() < leaves.len() {
            out.cached.resize_with(leaves.len(), CachedLeaf::default);
        }
        for (local, a) in leaves.clone().enumerate() {
            if self.reach.is_empty() {
                // No rows: every k nearest from a tree.
                for t in self.starts[a] as usize..self.starts[a + 1] as usize {
                    out.best.clear();
                    let i = self.ids[t];
                    self.nearest_beyond_rows(i, self.points[t].0, out);
                    self.push_root(i, 0, out);
                }
                continue;
            }
            // The leaves within reach of leaf a now (a included).
            let near = &self.near[self.near_starts[a] as usize..self.near_starts[a + 1] as usize];
            let leaf = &mut out.cached[local];
            let mut certified = None;
            if let Some(anchor) = leaf.anchor.filter(|_| leaf.valid && super::reuse::is_subset(near, &leaf.near)) {
                out.union.fill_packed(&leaf.keys, self.points);
                let map = AnchorMap::between(
                    &anchor,
                    &self.frames[self.ids[self.starts[a] as usize + leaf.anchor_at] as usize],
                );
                // E_self + E of the module notes, each widened for rounding.
                let union = largest_residual(&map, &leaf.reference, out.union.packed.iter().map(|e| e.p));
                let roots = self.starts[a] as usize..self.starts[a + 1] as usize;
                let own = largest_residual(&map, &leaf.own, self.points[roots].iter().map(|p| p.0));
                let e = map.widen(own, leaf.radius) + map.widen(union, leaf.radius);
                if map.rows_hold(leaf.margin, leaf.longest, e) {
                    certified = Some((map, e));
                }
            }
            match certified {
                Some((map, e)) => self.filter_leaf(a, local, &map, e, out),
                None => {
                    out.leaves_remade += 1;
                    self.remake_leaf(a, local, out);
                }
            }
        }
        out.cache_generation = self.generation;
        out.cache_leaves = (leaves.start, leaves.end);
    }

    /// Records root `i` with the row appended since `row_start` and `out.best`.
    fn push_root(&self, i: u32, row_start: usize, out: &mut Chunk) {
        out.roots.push(i);
        out.row_lens.push((out.rows.len() - row_start) as u32);
        out.knn.extend(out.best.iter().map(|&(_, j)| j));
        out.knn_lens.push(out.best.len() as u32);
    }

    /// The k nearest of a root whose candidates did not settle them: from
    /// the tree over the current positions, or deferred until there is one.
    fn nearest_beyond_rows(&self, i: u32, p: glam::Vec3, out: &mut Chunk) {
        if self.params.k == 0 {
            return;
        }
        match self.tree {
            Some(tree) => {
                let (frames, params) = (self.frames, self.params);
                let frame = &frames[i as usize];
                let accept = |j: u32| j != i && normals_agree(frame, &frames[j as usize], params.min_normal_dot);
                tree.nearest(p, params.k, &accept, &mut out.best);
            }
            // Settled after the pass, with a current tree.
            None => {
                out.deferred.push(out.roots.len() as u32);
                out.best.clear();
            }
        }
    }

    /// `(L_i + min L)²`: every root that near is a candidate of `i`.
    fn sure2(&self, i: u32) -> f32 {
        let sure = self.reach.get(i as usize).map_or(0.0, |&r| sanitized_reach(r) + self.min_reach);
        sure * sure
    }

    /// The k nearest of root `i` from its row (`slots`, with squared
    /// distances `d2s`) into `out.best`. First only the candidates within
    /// `guess` (twice the k-th distance of the leaf's previous root, squared
    /// ×4): when k of them are accepted, no farther candidate can rank among
    /// the k best, so the others are skipped; otherwise every candidate is
    /// ranked. Returns whether the row settled them (the k-th lies within
    /// `L_i + min L`, so every root nearer is in the row).
    fn nearest_in_row(&self, i: u32, slots: &[u32], d2s: &[f32], guess: &mut f32, best: &mut Vec<(f32, u32)>) -> bool {
        let (frames, params, k) = (self.frames, self.params, self.params.k);
        best.clear();
        if k == 0 {
            return true;
        }
        let frame = &frames[i as usize];
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
        rank(best, *guess);
        if best.len() < k {
            best.clear();
            rank(best, f32::INFINITY);
        }
        *guess = if best.len() == k { 4.0 * best[k - 1].0 } else { f32::INFINITY };
        best.len() == k && best[k - 1].0 <= self.sure2(i)
    }

    /// Leaf `a`'s lists made at the current pose (its new reference), and
    /// its rows and k nearest from them.
    fn remake_leaf(&self, a: usize, local: usize, out: &mut Chunk) {
        // Taken out of the chunk while its rows are written (no allocation).
        let mut leaf = std::mem::take(&mut out.cached[local]);
        let mut union = std::mem::take(&mut out.union);
        let mut all_d2 = std::mem::take(&mut out.all_d2);
        let cell = &self.cells[a];
        leaf.margin = MARGIN * (cell.reach + self.min_reach);
        near_leaves(self.cells, self.nodes, a, leaf.margin, &mut out.near, &mut out.stack);
        // Their roots sorted by index, so that every row comes out sorted.
        // (Sorted as packed (index, place in tree order) words: much
        // cheaper than sorting the points themselves; kept when the near
        // leaves are those of the last lists.)
        if !leaf.valid || leaf.near != out.near {
            leaf.near.clear();
            leaf.near.extend_from_slice(&out.near);
            leaf.keys.clear();
            for &b in &leaf.near {
                let roots = self.starts[b as usize] as usize..self.starts[b as usize + 1] as usize;
                leaf.keys.extend(roots.map(|u| (u64::from(self.ids[u]) << 32) | u as u64));
            }
            leaf.keys.sort_unstable();
        }
        union.fill(&leaf.keys, self.points);
        let len = leaf.keys.len();
        leaf.reference.clear();
        leaf.reference.extend((0..len).map(|s| glam::Vec3::new(union.x[s], union.y[s], union.z[s])));
        let first = self.starts[a] as usize;
        leaf.own.clear();
        leaf.own.extend(self.points[first..self.starts[a + 1] as usize].iter().map(|p| p.0));
        // The anchor: the root nearest the middle of the leaf's box.
        let middle = 0.5 * (cell.lo + cell.hi);
        leaf.anchor_at = (0..leaf.own.len()).fold(0, |b, t| {
            if (leaf.own[t] - middle).length_squared() < (leaf.own[b] - middle).length_squared() { t } else { b }
        });
        let anchor = self.frames[self.ids[first + leaf.anchor_at] as usize];
        leaf.anchor = Some(anchor);
        let anchor = anchor.position;
        leaf.radius = leaf.reference.iter().fold(0.0f32, |m, r| m.max((*r - anchor).length()));
        leaf.longest = cell.reach + union.reach[..len].iter().fold(0.0f32, |m, &r| m.max(r));
        leaf.sets.clear();
        leaf.ids.clear();
        leaf.slack.clear();
        leaf.ends.clear();
        if out.d2.len() < len {
            out.d2.resize(len, 0.0);
        }
        let k = self.params.k;
        let mut guess = f32::INFINITY;
        for t in first..self.starts[a + 1] as usize {
            let (p, r) = self.points[t];
            let i = self.ids[t];
            // S_i, with the squared distances as the exhaustive search
            // computes them; the row is S_i filtered by the exact test.
            let set_start = leaf.sets.len();
            let count = union.scan(p, r + leaf.margin, i, &mut leaf.sets, &mut all_d2);
            let row_start = out.rows.len();
            let kept = union.filter_scanned(&leaf.sets[set_start..], &all_d2[..count], r, &mut out.rows, &mut out.d2);
            // S_i as indices and slacks `|r_i − r_j| − (L_i + L_j)`.
            for (q, &s) in leaf.sets[set_start..].iter().enumerate() {
                let s = s as usize;
                leaf.ids.push(union.id[s]);
                leaf.slack.push(all_d2[q].sqrt() - (r + union.reach[s]));
            }
            let from_row = self.nearest_in_row(i, &out.rows[row_start..], &out.d2[..kept], &mut guess, &mut out.best);
            // K_i: every root of S_i within the k-th distance plus the
            // margin (none when the row did not settle the k nearest); no
            // root of the union outside S_i is that near (module notes).
            // Stored nearest first at the reference (so that ranking them
            // later mostly appends), by squared distance then place.
            let radius = if from_row && k > 0 { out.best[k - 1].0.sqrt() + leaf.margin } else { f32::NAN };
            let radius2 = radius * radius;
            out.order.clear();
            out.order.extend(
                (0..count)
                    .filter(|&q| all_d2[q] <= radius2)
                    .map(|q| (u64::from(all_d2[q].to_bits()) << 32) | u64::from(leaf.sets[set_start + q])),
            );
            out.order.sort_unstable();
            leaf.sets.truncate(set_start);
            leaf.sets.extend(out.order.iter().map(|&key| key as u32));
            let to = leaf.sets.len();
            leaf.ends.push((leaf.ids.len() as u32, to as u32, radius));
            if !from_row {
                self.nearest_beyond_rows(i, p, out);
            }
            self.push_root(i, row_start, out);
        }
        leaf.valid = true;
        out.cached[local] = leaf;
        out.union = union;
        out.all_d2 = all_d2;
    }

    /// Leaf `a`'s rows and k nearest from its certified lists (`map` and
    /// the widened residual `e` of [`super::reuse`]); `out.union` holds the
    /// union's current positions.
    fn filter_leaf(&self, a: usize, local: usize, map: &AnchorMap, e: f32, out: &mut Chunk) {
        let leaf = std::mem::take(&mut out.cached[local]);
        let union = std::mem::take(&mut out.union);
        let (frames, params, k) = (self.frames, self.params, self.params.k);
        // Entries of S_i whose slack lies within `band` of 0 are tested;
        // the others are in (below) or out (above) for sure.
        let band = map.band(e, leaf.longest, leaf.margin);
        let mut guess = f32::INFINITY;
        let (mut s_start, mut k_start) = (0usize, 0usize);
        for (t, &(s_end, k_end, radius)) in (self.starts[a] as usize..).zip(&leaf.ends) {
            let (p, r) = self.points[t];
            let i = self.ids[t];
            let row_start = out.rows.len();
            let (ids, slack) = (&leaf.ids[s_start..s_end as usize], &leaf.slack[s_start..s_end as usize]);
            self.filter_row(p, r, ids, slack, band, &mut out.rows);
            // The k nearest among K_i, when the certificate says no other
            // root can rank; otherwise from the whole row.
            out.best.clear();
            let mut settled = false;
            if k > 0 && radius.is_finite() {
                let frame = &frames[i as usize];
                for &s in &leaf.sets[k_start..k_end as usize] {
                    let e = &union.packed[s as usize];
                    let (d2, j) = (Union::distance2(e, p), e.id);
                    if ranks_among_best(&out.best, k, d2, j)
                        && normals_agree(frame, &frames[j as usize], params.min_normal_dot)
                    {
                        insert_candidate(&mut out.best, k, d2, j);
                    }
                }
                settled = out.best.len() == k && {
                    let d2 = out.best[k - 1].0;
                    d2 <= self.sure2(i) && map.nearest_hold(d2, radius, e)
                };
                if settled {
                    guess = 4.0 * out.best[k - 1].0;
                }
            }
            if !settled {
                // The row's squared distances, as the exhaustive search
                // computes them.
                let row = &out.rows[row_start..];
                out.d2.clear();
                out.d2.extend(row.iter().map(|&j| (frames[j as usize].position - p).length_squared()));
                if !self.nearest_in_row(i, row, &out.d2, &mut guess, &mut out.best) {
                    self.nearest_beyond_rows(i, p, out);
                }
            }
            self.push_root(i, row_start, out);
            (s_start, k_start) = (s_end as usize, k_end as usize);
        }
        out.cached[local] = leaf;
        out.union = union;
    }

    /// Appends to `row` the entries of S_i (`ids`, with their reference
    /// slacks) within reach of root `i` (at `p`, reach `r`) now: those whose
    /// slack is at most `−band` for sure, those within `band` of 0 by the
    /// exhaustive search's test, bitwise (`|r_j − p|² ≤ (r + L_j)²`).
    #[inline]
    fn filter_row(&self, p: glam::Vec3, r: f32, ids: &[u32], slack: &[f32], band: f32, row: &mut Vec<u32>) {
        row.reserve(ids.len());
        let base = row.len();
        let out = &mut row.spare_capacity_mut()[..ids.len()];
        let mut kept = 0;
        for (q, (&j, &s)) in ids.iter().zip(slack).enumerate() {
            let keep = if s <= -band {
                true
            } else if s < band {
                let d2 = (self.frames[j as usize].position - p).length_squared();
                let limit = r + sanitized_reach(self.reach[j as usize]);
                d2 <= limit * limit
            } else {
                false
            };
            debug_assert!(kept <= q && q < out.len());
            // SAFETY: `kept ≤ q < ids.len() = out.len()`.
            unsafe { *out.get_unchecked_mut(kept) = std::mem::MaybeUninit::new(j) };
            kept += usize::from(keep);
        }
        // SAFETY: the first `kept` spare slots were written (each is written
        // before the cursor moves past it), within the capacity reserved above.
        unsafe { row.set_len(base + kept) };
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
    pub(super) all_d2: Vec<f32>,
    pub(super) order: Vec<u64>,
    pub(super) stack: Vec<u32>,
    pub(super) best: Vec<(f32, u32)>,
    /// Places in `roots` whose k nearest wait for a current tree.
    pub(super) deferred: Vec<u32>,
    /// Leaves whose lists the last call made again (their certificate failed).
    pub(super) leaves_remade: usize,
    /// Per leaf of the last call (`cache_leaves` under cache key
    /// `cache_generation`): its lists and their reference.
    pub(super) cache_generation: u64,
    pub(super) cache_leaves: (usize, usize),
    pub(super) cached: Vec<CachedLeaf>,
}

/// A leaf's candidate lists and the pose they were made at (see
/// [`super::reuse`]).
#[derive(Debug, Default)]
pub(super) struct CachedLeaf {
    /// Whether the lists below were made (under the chunk's cache key).
    pub(super) valid: bool,
    /// The near leaves at the reference, found with the reach widened by
    /// `margin`.
    pub(super) near: Vec<u32>,
    /// Their roots as sorted `(index << 32 | place in layout order)` keys:
    /// the union, whose places (slots) the lists hold.
    pub(super) keys: Vec<u64>,
    /// The union's positions at the reference, and the leaf's own.
    pub(super) reference: Vec<glam::Vec3>,
    pub(super) own: Vec<glam::Vec3>,
    /// The anchor's frame at the reference, and its place in the leaf.
    pub(super) anchor: Option<RootFrame>,
    pub(super) anchor_at: usize,
    /// `m`, the union's largest distance from the anchor at the reference,
    /// and the leaf's longest reach plus the union's.
    pub(super) margin: f32,
    pub(super) radius: f32,
    pub(super) longest: f32,
    /// Per root of the leaf, `K_i` as slots of the union.
    pub(super) sets: Vec<u32>,
    /// Per root of the leaf, `S_i` (sorted by index) and the slack of each
    /// entry at the reference, `|r_i − r_j| − (L_i + L_j)`.
    pub(super) ids: Vec<u32>,
    pub(super) slack: Vec<f32>,
    /// Per root: where its `S_i` ends in `ids` and its `K_i` in `sets`, and
    /// `ρ_i` (NaN: its k nearest are never taken from `K_i`).
    pub(super) ends: Vec<(u32, u32, f32)>,
}

/// The largest residual `|now − M(reference)|` over the pairs of
/// `reference` and `now` (NaN if any is not finite or the lengths differ),
/// from the squared residuals.
fn largest_residual(map: &AnchorMap, reference: &[glam::Vec3], now: impl ExactSizeIterator<Item = glam::Vec3>) -> f32 {
    if reference.len() != now.len() {
        return f32::NAN;
    }
    let (mut largest, mut finite) = (0.0f32, true);
    for (&r, p) in reference.iter().zip(now) {
        let e2 = map.residual2(r, p);
        finite &= e2.is_finite();
        largest = largest.max(e2);
    }
    if finite { largest.sqrt() } else { f32::NAN }
}

/// Every leaf's near leaves (as [`near_leaves`] with no widening finds
/// them, in increasing order) as CSR `starts`, `near`, from one traversal
/// of the hierarchy against itself: a pair of boxes out of reach prunes
/// every pair of their leaves. The tests are those of [`near_leaves`]
/// (symmetric bitwise, and a box's gap is never larger than its leaves'),
/// so the lists are the same.
pub(super) fn near_pairs(
    nodes: &[Node],
    leaves: usize,
    starts: &mut Vec<u32>,
    near: &mut Vec<u32>,
    stack: &mut Vec<(u32, u32)>,
    pairs: &mut Vec<u64>,
) {
    pairs.clear();
    stack.clear();
    if !nodes.is_empty() {
        stack.push((0, 0));
    }
    while let Some((x, y)) = stack.pop() {
        let (p, q) = (&nodes[x as usize], &nodes[y as usize]);
        if !p.cell.may_reach(&q.cell, 0.0) {
            continue;
        }
        match (p.children == u32::MAX, q.children == u32::MAX) {
            (true, true) => {
                let (a, b) = (u64::from(p.leaf), u64::from(q.leaf));
                pairs.push((a << 32) | b);
                if a != b {
                    pairs.push((b << 32) | a);
                }
            }
            // A node against itself: its halves against themselves and
            // each other (each unordered pair of subtrees once).
            _ if x == y => {
                let c = p.children;
                stack.extend([(c, c), (c + 1, c + 1), (c, c + 1)]);
            }
            (false, _) => stack.extend([(p.children, y), (p.children + 1, y)]),
            (true, false) => stack.extend([(x, q.children), (x, q.children + 1)]),
        }
    }
    // By leaf (a counting sort), then each leaf's few near leaves sorted.
    starts.clear();
    starts.resize(leaves + 2, 0);
    for &pair in pairs.iter() {
        starts[(pair >> 32) as usize + 2] += 1;
    }
    for a in 0..leaves {
        starts[a + 2] += starts[a + 1];
    }
    near.clear();
    near.resize(pairs.len(), 0);
    for &pair in pairs.iter() {
        let at = &mut starts[(pair >> 32) as usize + 1];
        near[*at as usize] = pair as u32;
        *at += 1;
    }
    starts.truncate(leaves + 1);
    for a in 0..leaves {
        near[starts[a] as usize..starts[a + 1] as usize].sort_unstable();
    }
}

/// Appends to `near` the leaves whose boxes come within the sum of the
/// longest reaches plus `extra` of leaf `a`'s, in increasing order.
pub(super) fn near_leaves(
    cells: &[Cell],
    nodes: &[Node],
    a: usize,
    extra: f32,
    near: &mut Vec<u32>,
    stack: &mut Vec<u32>,
) {
    near.clear();
    let cell = &cells[a];
    stack.clear();
    stack.push(0);
    while let Some(x) = stack.pop() {
        let node = &nodes[x as usize];
        if !cell.may_reach(&node.cell, extra) {
            continue;
        }
        if node.children == u32::MAX {
            near.push(node.leaf);
        } else {
            // Left first: the leaves come out in increasing order.
            stack.push(node.children + 1);
            stack.push(node.children);
        }
    }
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
    /// The same entries side by side (unpadded), for lookups by place:
    /// filled instead of the columns when a leaf's lists are filtered.
    pub(super) packed: Vec<Entry>,
}

/// One root of a union: position and index.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Entry {
    pub(super) p: glam::Vec3,
    pub(super) id: u32,
}

/// Entries a block of [`Union::scan`] tests at once.
pub(super) const LANES: usize = 8;

impl Union {
    /// The roots of `keys` (index << 32 | place in layout order) with their
    /// position and reach from `points`.
    pub(super) fn fill(&mut self, keys: &[u64], points: &[(glam::Vec3, f32)]) {
        let padded = keys.len().next_multiple_of(LANES);
        let point = |key: u64| points[key as u32 as usize];
        for (column, axis) in [(&mut self.x, 0), (&mut self.y, 1), (&mut self.z, 2)] {
            column.clear();
            column.reserve(padded);
            column.extend(keys.iter().map(|&key| point(key).0[axis]));
            column.resize(padded, f32::NAN);
        }
        self.reach.clear();
        self.reach.reserve(padded);
        self.reach.extend(keys.iter().map(|&key| point(key).1));
        self.reach.resize(padded, 0.0);
        self.id.clear();
        self.id.reserve(padded);
        self.id.extend(keys.iter().map(|&key| (key >> 32) as u32));
        self.id.resize(padded, u32::MAX);
    }

    /// The roots of `keys` as [`fill`](Self::fill) finds them, into `packed` only.
    pub(super) fn fill_packed(&mut self, keys: &[u64], points: &[(glam::Vec3, f32)]) {
        self.packed.clear();
        self.packed.extend(keys.iter().map(|&key| Entry { p: points[key as u32 as usize].0, id: (key >> 32) as u32 }));
    }

    /// Appends to `slots` the place of every entry `j ≠ i` with
    /// `|r_j − p|² ≤ (r + reach_j)²`, in order, and writes its squared
    /// distance to the front of `d2s` (which only ever grows); returns how
    /// many. The distance is computed as `(r_j − p).length_squared()` is,
    /// operation for operation (lane by lane in `f32`, no fused
    /// multiply-add), so any test made with it is bitwise the one of a
    /// radius query.
    #[inline]
    pub(super) fn scan(&self, p: glam::Vec3, r: f32, i: u32, slots: &mut Vec<u32>, d2s: &mut Vec<f32>) -> usize {
        slots.reserve(self.id.len());
        if d2s.len() < self.id.len() {
            d2s.resize(self.id.len(), 0.0);
        }
        let base = slots.len();
        let (out, distances) = (&mut slots.spare_capacity_mut()[..self.id.len()], &mut d2s[..]);
        let mut kept = 0;
        let blocks = self
            .x
            .chunks_exact(LANES)
            .zip(self.y.chunks_exact(LANES))
            .zip(self.z.chunks_exact(LANES))
            .zip(self.reach.chunks_exact(LANES))
            .zip(self.id.chunks_exact(LANES));
        let mut d2 = [0.0f32; LANES];
        for (b, ((((x, y), z), reach), id)) in blocks.enumerate() {
            let mask = within_mask(x, y, z, reach, p, r, &mut d2);
            // Branch-free: every lane is written, and the cursor moves past
            // those within reach other than the root itself (`kept` never
            // passes the lane's own place, so the writes stay in bounds).
            for l in 0..LANES {
                out[kept] = std::mem::MaybeUninit::new((b * LANES + l) as u32);
                distances[kept] = d2[l];
                kept += ((mask >> l) & 1) as usize & usize::from(id[l] != i);
            }
        }
        // SAFETY: the first `kept` spare slots were written (each lane is
        // written before the cursor moves past it), within the capacity
        // reserved above.
        unsafe { slots.set_len(base + kept) };
        kept
    }

    /// Appends to `row` the roots of the `slots` [`scan`](Self::scan)
    /// found (with squared distances `scanned`) that lie within reach of a
    /// root of reach `r`: `|r_j − p|² ≤ (r + reach_j)²` bitwise as the
    /// exhaustive search tests it; their squared distances go to the front
    /// of `d2s` (which only ever grows). Returns how many.
    #[inline]
    pub(super) fn filter_scanned(
        &self,
        slots: &[u32],
        scanned: &[f32],
        r: f32,
        row: &mut Vec<u32>,
        d2s: &mut Vec<f32>,
    ) -> usize {
        row.reserve(slots.len());
        if d2s.len() < slots.len() {
            d2s.resize(slots.len(), 0.0);
        }
        let base = row.len();
        let (out, distances) = (&mut row.spare_capacity_mut()[..slots.len()], &mut d2s[..slots.len()]);
        let mut kept = 0;
        for (&s, &d2) in slots.iter().zip(scanned) {
            let s = s as usize;
            let limit = r + self.reach[s];
            out[kept] = std::mem::MaybeUninit::new(self.id[s]);
            distances[kept] = d2;
            kept += usize::from(d2 <= limit * limit);
        }
        // SAFETY: as in `filter`.
        unsafe { row.set_len(base + kept) };
        kept
    }

    /// `|r_j − p|²` of packed entry `e`, as [`scan`](Self::scan) computes it.
    #[inline]
    pub(super) fn distance2(e: &Entry, p: glam::Vec3) -> f32 {
        let (dx, dy, dz) = (e.p.x - p.x, e.p.y - p.y, e.p.z - p.z);
        (dx * dx) + (dy * dy) + (dz * dz)
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
    /// (`extra` widens the reach; 0 for the exact test.)
    #[inline]
    pub(super) fn may_reach(&self, other: &Cell, extra: f32) -> bool {
        let gap = (other.lo - self.hi).max(self.lo - other.hi).max(glam::Vec3::ZERO);
        let limit = self.reach + other.reach + extra;
        gap.length_squared() <= limit * limit
    }
}
