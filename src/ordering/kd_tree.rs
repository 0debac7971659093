//! A k-d tree over root positions, stored flat so that rebuilding it every
//! frame reuses one buffer.
//!
//! Layout: the items live in one array; a node is a range `[lo, hi)` of it.
//! Ranges of at most `LEAF_SIZE` items are leaves and are scanned linearly.
//! A larger range is split at its middle `m = lo + (hi − lo)/2` along the axis
//! of its widest extent: items `[lo, m)` are ≤ item `m` and items `[m, hi)`
//! are ≥ it (in the total order "coordinate, then root index"), so the tree's
//! shape depends only on the positions, never on how the selection ran. The
//! split axis and coordinate are stored at index `m` (every internal node has
//! its own `m`); the item there moves when the right child is split.
//!
//! Queries are exact, ties in distance included: a subtree is pruned only
//! when its slab is strictly farther than the current bound. Distances are
//! `|r_j − r_i|²` in `f32`, which is bitwise symmetric in `i` and `j`.

use glam::Vec3;

/// Largest range scanned linearly instead of split.
const LEAF_SIZE: usize = 16;

/// One stored root: its position and index.
#[derive(Clone, Copy, Debug)]
struct Item {
    position: Vec3,
    id: u32,
}

/// The tree. `rebuild` keeps all allocations.
#[derive(Clone, Debug, Default)]
pub(crate) struct KdTree {
    items: Vec<Item>,
    splits: Vec<(u8, f32)>,
}

impl KdTree {
    /// Rebuilds the tree over `positions` (index = root id).
    pub(crate) fn rebuild(&mut self, positions: impl ExactSizeIterator<Item = Vec3>) {
        self.items.clear();
        self.items.extend(positions.enumerate().map(|(i, position)| Item { position, id: i as u32 }));
        self.splits.clear();
        self.splits.resize(self.items.len(), (0, 0.0));
        split_range(&mut self.items, &mut self.splits);
    }

    /// The root ids in tree order, and where each leaf (a cell of at most
    /// `LEAF_SIZE` roots lying close together) starts in it; `starts` ends
    /// with the root count.
    pub(crate) fn leaves(&self, ids: &mut Vec<u32>, starts: &mut Vec<u32>) {
        ids.clear();
        ids.extend(self.items.iter().map(|item| item.id));
        starts.clear();
        leaf_starts(0, self.items.len(), starts);
        starts.push(self.items.len() as u32);
    }

    /// Writes to `best` the (at most `k`) accepted roots nearest to `query`,
    /// sorted by distance then index, as `(squared distance, id)`.
    pub(crate) fn nearest(&self, query: Vec3, k: usize, accept: &impl Fn(u32) -> bool, best: &mut Vec<(f32, u32)>) {
        best.clear();
        if k == 0 {
            return;
        }
        // Squared distance of the k-th candidate once there are k of them.
        let mut bound = f32::INFINITY;
        self.visit_cells(query, bound, |items| {
            for item in items {
                let d2 = (item.position - query).length_squared();
                if d2 <= bound && ranks_among_best(best, k, d2, item.id) && accept(item.id) {
                    insert_candidate(best, k, d2, item.id);
                    if best.len() == k {
                        bound = best[k - 1].0;
                    }
                }
            }
            bound
        });
    }

    /// Calls `visit(id, squared distance)` for every root within
    /// `sqrt(radius_sq)` of `query` (boundary included), in tree order.
    #[cfg(test)]
    pub(crate) fn within(&self, query: Vec3, radius_sq: f32, visit: &mut impl FnMut(u32, f32)) {
        self.visit_cells(query, radius_sq, |items| {
            for item in items {
                let d2 = (item.position - query).length_squared();
                if d2 <= radius_sq {
                    visit(item.id, d2);
                }
            }
            radius_sq
        });
    }

    /// Depth-first walk over the leaves, nearest side first, skipping every
    /// cell whose lower bound on the squared distance exceeds the current
    /// bound (`bound` at first, then whatever `leaf` returns).
    ///
    /// The bound is `|off|²` where `off` holds, per axis, the gap between the
    /// query and the nearest splitting plane bounding the cell (0 when the
    /// query lies between them), as in Arya and Mount's incremental distance.
    /// It is evaluated in the same operation order as a point's
    /// `length_squared`, and rounding is monotone, so no point within the
    /// bound is ever skipped: queries stay exact, ties included.
    fn visit_cells<'s>(&'s self, query: Vec3, mut bound: f32, mut leaf: impl FnMut(&'s [Item]) -> f32) {
        if self.items.is_empty() {
            return;
        }
        // Pending far children: at most one per tree level, and a balanced
        // tree over u32 ids has fewer than 40 levels.
        let mut pending = [(0u32, 0u32, Vec3::ZERO); 40];
        let mut depth = 1;
        pending[0] = (0, self.items.len() as u32, Vec3::ZERO);
        while depth > 0 {
            depth -= 1;
            let (mut lo, mut hi, off) = pending[depth];
            if off.length_squared() > bound {
                continue;
            }
            while (hi - lo) as usize > LEAF_SIZE {
                let m = lo + (hi - lo) / 2;
                let (axis, split) = self.splits[m as usize];
                let gap = query[axis as usize] - split;
                let (near, far) = if gap < 0.0 { ((lo, m), (m, hi)) } else { ((m, hi), (lo, m)) };
                let mut far_off = off;
                far_off[axis as usize] = gap.abs();
                pending[depth] = (far.0, far.1, far_off);
                depth += 1;
                (lo, hi) = near;
            }
            bound = leaf(&self.items[lo as usize..hi as usize]);
        }
    }
}

/// Splits `items` recursively (see the module notes); `splits[m]` receives
/// the split axis and coordinate of the node whose middle is `m`.
fn split_range(items: &mut [Item], splits: &mut [(u8, f32)]) {
    if items.len() <= LEAF_SIZE {
        return;
    }
    let a = widest_axis(items);
    let m = items.len() / 2;
    items.select_nth_unstable_by(m, |p, q| p.position[a].total_cmp(&q.position[a]).then(p.id.cmp(&q.id)));
    splits[m] = (a as u8, items[m].position[a]);
    let (left_items, right_items) = items.split_at_mut(m);
    let (left_splits, right_splits) = splits.split_at_mut(m);
    split_range(left_items, left_splits);
    split_range(right_items, right_splits);
}

/// Appends the start of every leaf of the range `[lo, hi)`, in order (the
/// ranges [`split_range`] leaves unsplit).
fn leaf_starts(lo: usize, hi: usize, starts: &mut Vec<u32>) {
    if hi - lo <= LEAF_SIZE {
        if hi > lo {
            starts.push(lo as u32);
        }
        return;
    }
    let m = lo + (hi - lo) / 2;
    leaf_starts(lo, m, starts);
    leaf_starts(m, hi, starts);
}

/// The axis along which the items' bounding box is widest (lowest on ties).
fn widest_axis(items: &[Item]) -> usize {
    let (lo, hi) = items
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), it| (lo.min(it.position), hi.max(it.position)));
    let extent = hi - lo;
    if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    }
}

/// Whether `(d2, id)` would enter the sorted list `best` of at most `k`
/// entries, ordered by (distance, id).
#[inline]
pub(super) fn ranks_among_best(best: &[(f32, u32)], k: usize, d2: f32, id: u32) -> bool {
    best.len() < k || precedes((d2, id), best[best.len() - 1])
}

/// Inserts `(d2, id)` (which ranks) into `best`, dropping the worst entry
/// when the list is full.
#[inline]
pub(super) fn insert_candidate(best: &mut Vec<(f32, u32)>, k: usize, d2: f32, id: u32) {
    if best.len() == k {
        best.pop();
    }
    // Shifted by hand: the lists are short, and this is the k nearest's
    // inner loop.
    best.push((d2, id));
    let mut pos = best.len() - 1;
    while pos > 0 && precedes((d2, id), best[pos - 1]) {
        best[pos] = best[pos - 1];
        pos -= 1;
    }
    best[pos] = (d2, id);
}

/// The candidate order: distance, then index.
#[inline]
fn precedes(a: (f32, u32), b: (f32, u32)) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
}

crate::memory::heap_size_of_fields!(KdTree { items, splits });

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn random_points(n: usize, seed: u64) -> Vec<Vec3> {
        let mut rng = Rng::new(seed);
        (0..n).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32() * 0.1)).collect()
    }

    #[test]
    fn nearest_matches_brute_force() {
        let pts = random_points(500, 3);
        let mut tree = KdTree::default();
        tree.rebuild(pts.iter().copied());
        let mut best = Vec::new();
        for (i, &q) in pts.iter().enumerate() {
            let not_self = |j: u32| j as usize != i;
            tree.nearest(q, 7, &not_self, &mut best);
            let mut all: Vec<(f32, u32)> = pts
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(j, p)| ((*p - q).length_squared(), j as u32))
                .collect();
            all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            assert_eq!(best, all[..7].to_vec());
        }
    }

    #[test]
    fn within_matches_brute_force_with_duplicates() {
        let mut pts = random_points(300, 9);
        pts.extend_from_slice(&pts.clone()[..50]);
        let mut tree = KdTree::default();
        tree.rebuild(pts.iter().copied());
        for &q in pts.iter().step_by(7) {
            let mut got = Vec::new();
            tree.within(q, 0.01, &mut |j, _| got.push(j));
            got.sort_unstable();
            let want: Vec<u32> =
                (0..pts.len() as u32).filter(|&j| (pts[j as usize] - q).length_squared() <= 0.01).collect();
            assert_eq!(got, want);
        }
    }
}
