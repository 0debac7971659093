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
const LEAF_SIZE: usize = 8;

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

    /// Appends to `best` the (at most `k`) accepted roots nearest to `query`,
    /// sorted by distance then index, as `(squared distance, id)`. `best`
    /// is cleared first.
    pub(crate) fn nearest(&self, query: Vec3, k: usize, accept: &impl Fn(u32) -> bool, best: &mut Vec<(f32, u32)>) {
        best.clear();
        if k == 0 {
            return;
        }
        self.nearest_in(0, self.items.len(), query, k, accept, best);
    }

    /// Calls `visit(id, squared distance)` for every root within
    /// `sqrt(radius_sq)` of `query` (boundary included), in tree order.
    pub(crate) fn within(&self, query: Vec3, radius_sq: f32, visit: &mut impl FnMut(u32, f32)) {
        self.within_in(0, self.items.len(), query, radius_sq, visit);
    }

    fn nearest_in(
        &self,
        lo: usize,
        hi: usize,
        query: Vec3,
        k: usize,
        accept: &impl Fn(u32) -> bool,
        best: &mut Vec<(f32, u32)>,
    ) {
        if hi - lo <= LEAF_SIZE {
            for item in &self.items[lo..hi] {
                if accept(item.id) {
                    offer_candidate(best, k, (item.position - query).length_squared(), item.id);
                }
            }
            return;
        }
        let m = lo + (hi - lo) / 2;
        let (axis, split) = self.splits[m];
        let gap = query[axis as usize] - split;
        let (near, far) = if gap < 0.0 { ((lo, m), (m, hi)) } else { ((m, hi), (lo, m)) };
        self.nearest_in(near.0, near.1, query, k, accept, best);
        if best.len() < k || gap * gap <= best[best.len() - 1].0 {
            self.nearest_in(far.0, far.1, query, k, accept, best);
        }
    }

    fn within_in(&self, lo: usize, hi: usize, query: Vec3, radius_sq: f32, visit: &mut impl FnMut(u32, f32)) {
        if hi - lo <= LEAF_SIZE {
            for item in &self.items[lo..hi] {
                let d2 = (item.position - query).length_squared();
                if d2 <= radius_sq {
                    visit(item.id, d2);
                }
            }
            return;
        }
        let m = lo + (hi - lo) / 2;
        let (axis, split) = self.splits[m];
        let gap = query[axis as usize] - split;
        let (near, far) = if gap < 0.0 { ((lo, m), (m, hi)) } else { ((m, hi), (lo, m)) };
        self.within_in(near.0, near.1, query, radius_sq, visit);
        if gap * gap <= radius_sq {
            self.within_in(far.0, far.1, query, radius_sq, visit);
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

/// Inserts `(d2, id)` into the sorted list `best` of at most `k` entries if
/// it ranks among the `k` smallest by (distance, id).
#[inline]
fn offer_candidate(best: &mut Vec<(f32, u32)>, k: usize, d2: f32, id: u32) {
    let ranks_before = |e: &(f32, u32)| d2.total_cmp(&e.0).then(id.cmp(&e.1)).is_lt();
    if best.len() == k {
        if !ranks_before(&best[k - 1]) {
            return;
        }
        best.pop();
    }
    let mut pos = best.len();
    while pos > 0 && ranks_before(&best[pos - 1]) {
        pos -= 1;
    }
    best.insert(pos, (d2, id));
}

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
