//! The priority DAG and its dynamic topological order, frame by frame
//! (paper §2.2, §3.3; DESIGN §4, §5 step 3): the public calls that change
//! the priority differences or the pair set and keep the order topological.
//!
//! Where the parts live: the storage, accessors and graph primitives in
//! `order_graph` (module notes there: one state per pair plus incidence
//! lists); inserting an edge with Pearce–Kelly and the cycle rule in
//! `pearce_kelly`; suppressed pairs, their blocking paths and retries in
//! `suppressed`; the first, static order in `static_order`; saving and
//! reading the order in `order_blob`.
//!
//! Internally an edge is read "prior → dependent": the prior root is
//! adjusted first, so every edge must go forward in [`PriorityOrder::order`].
//! (In the paper's notation that is the DAG edge dependent → prior, A→B when
//! `ΔP_AB > 0`.)

use super::order_graph::{Edge, PriorityOrder, ReorderStats, check_pairs, sanitized_delta, strength_order};
use super::priority::Priorities;
use rayon::prelude::*;
use std::time::Instant;

impl PriorityOrder {
    /// One frame of reordering (DESIGN §5 step 3, paper §3.3):
    /// [`begin_frame`](Self::begin_frame); if `pairs` is given (neighbourhoods
    /// recomputed at the current pose), [`sync_pairs`](Self::sync_pairs) with
    /// it, new pairs taking their `ΔP` from `priorities`; then recompute `ΔP`
    /// of every pair touching a root of `roots` (`R_k`) and
    /// [`update_pairs`](Self::update_pairs) with them; finally
    /// [`retry_suppressed`](Self::retry_suppressed). Returns the summed stats
    /// (`seconds` covers the whole call, `ΔP` recomputation included);
    /// afterwards [`became_prior`](Self::became_prior) lists the roots to add
    /// to `R_k` for readjustment (`R*_k`).
    pub fn update_frame(
        &mut self,
        pairs: Option<&[(u32, u32)]>,
        roots: &[u32],
        priorities: &Priorities<'_>,
    ) -> ReorderStats {
        let start = Instant::now();
        self.begin_frame();
        let mut stats = ReorderStats::default();
        if let Some(pairs) = pairs {
            stats += self.sync_pairs(pairs, |a, b| priorities.delta(a, b));
        }
        let mut changed = std::mem::take(&mut self.frame_changed);
        self.changed_pairs_of_roots(priorities, roots, &mut changed);
        stats += self.update_pairs(&changed);
        self.frame_changed = changed;
        stats += self.retry_suppressed();
        stats.seconds = start.elapsed().as_secs_f64();
        stats
    }

    /// The recomputed `ΔP` (from `priorities`) of every pair that touches
    /// one of `roots` (paper §3.3: for `i ∈ R_k`, all `j` paired with `i`),
    /// as `(lo, hi, ΔP_lo,hi)` sorted and without duplicates, ready for
    /// [`update_pairs`](Self::update_pairs). `out` is cleared first. The
    /// pairs are marked by index and read back in index order, which is
    /// `(lo, hi)` order: no sort.
    pub fn changed_pairs_of_roots(
        &mut self,
        priorities: &Priorities<'_>,
        roots: &[u32],
        out: &mut Vec<(u32, u32, f32)>,
    ) {
        out.clear();
        let mut marked = std::mem::take(&mut self.pair_marks);
        marked.clear();
        marked.resize(self.pairs.len().div_ceil(64), 0);
        for &i in roots {
            for e in self.incidence(i) {
                marked[e.pair as usize / 64] |= 1 << (e.pair % 64);
            }
        }
        for (word, &bits) in marked.iter().enumerate() {
            let mut bits = bits;
            while bits != 0 {
                let (lo, hi) = self.pairs[word * 64 + bits.trailing_zeros() as usize];
                out.push((lo, hi, 0.0));
                bits &= bits - 1;
            }
        }
        self.pair_marks = marked;
        out.par_iter_mut().with_min_len(1024).for_each(|entry| entry.2 = priorities.delta(entry.0, entry.1));
    }

    /// Replaces the pair set (e.g. neighbourhoods recomputed at the current
    /// pose). Pairs that vanished lose their edge (a deletion never
    /// invalidates the order); pairs that appeared get `ΔP_ab =
    /// new_pair_delta(a, b)` and are inserted strongest first with the cycle
    /// rule. Kept pairs keep their edge and `ΔP`. Cheap when nothing changed.
    ///
    /// # Panics
    /// If `pairs` is not strictly increasing with `a < b < node_count`.
    pub fn sync_pairs(
        &mut self,
        pairs: &[(u32, u32)],
        mut new_pair_delta: impl FnMut(u32, u32) -> f32,
    ) -> ReorderStats {
        let start = Instant::now();
        let mut stats = ReorderStats::default();
        if pairs == self.pairs.as_slice() {
            stats.seconds = start.elapsed().as_secs_f64();
            return stats;
        }
        check_pairs(pairs, self.node_count());
        self.merge_pair_set(pairs, &mut new_pair_delta, &mut stats);
        self.rebuild_incidence();
        let fresh = std::mem::take(&mut self.fresh);
        for &pid in &fresh {
            self.touched.push(pid);
            self.realize_wanted(pid, &mut stats);
        }
        self.fresh = fresh;
        self.finish_call();
        stats.seconds = start.elapsed().as_secs_f64();
        stats
    }

    /// New `ΔP` values for some pairs, as `(a, b, ΔP_ab)` in any order and
    /// orientation (duplicates: the last one wins). Pairs whose sign is
    /// unchanged only get their weight `|ΔP|` updated; a sign change reverses
    /// the edge with the cycle rule; `ΔP = 0` removes it. Entries naming no
    /// pair are counted in `unknown_pairs` and ignored. Pairs are processed
    /// in `(lo, hi)` order, so the result does not depend on input order.
    pub fn update_pairs(&mut self, changed: &[(u32, u32, f32)]) -> ReorderStats {
        let start = Instant::now();
        let mut stats = ReorderStats::default();
        let mut entries = std::mem::take(&mut self.changed);
        entries.clear();
        for (idx, &(a, b, d)) in changed.iter().enumerate() {
            match a.cmp(&b) {
                std::cmp::Ordering::Less => entries.push((a, b, d, idx as u32)),
                std::cmp::Ordering::Greater => entries.push((b, a, -d, idx as u32)),
                std::cmp::Ordering::Equal => stats.unknown_pairs += 1,
            }
        }
        entries.sort_unstable_by_key(|&(lo, hi, _, idx)| (lo, hi, idx));
        for k in 0..entries.len() {
            let (lo, hi, d, _) = entries[k];
            if entries.get(k + 1).is_some_and(|next| (next.0, next.1) == (lo, hi)) {
                continue;
            }
            let Some(pid) = self.find_pair(lo, hi) else {
                stats.unknown_pairs += 1;
                continue;
            };
            stats.pairs_updated += 1;
            let new_delta = sanitized_delta(d);
            if Edge::wanted(new_delta) != Edge::wanted(self.delta[pid as usize]) {
                stats.priority_changes += 1;
            }
            self.delta[pid as usize] = new_delta;
            self.touched.push(pid);
            self.realize_wanted(pid, &mut stats);
        }
        self.changed = entries;
        self.finish_call();
        stats.seconds = start.elapsed().as_secs_f64();
        stats
    }

    /// End of a public mutating call: suppressed list and sorted reports.
    pub(super) fn finish_call(&mut self) {
        self.refresh_suppressed();
        for list in [&mut self.became_prior, &mut self.gained_prior, &mut self.moved] {
            list.sort_unstable();
            list.dedup();
        }
    }

    /// Merges the new pair set into the per-pair arrays (keeping the state
    /// of surviving pairs), remaps the suppressed list and lists the new
    /// pairs, strongest first, in `fresh`.
    pub(super) fn merge_pair_set(
        &mut self,
        pairs: &[(u32, u32)],
        new_pair_delta: &mut impl FnMut(u32, u32) -> f32,
        stats: &mut ReorderStats,
    ) {
        self.refresh_suppressed();
        self.next_pairs.clear();
        self.next_delta.clear();
        self.next_state.clear();
        self.next_blocking.clear();
        self.fresh.clear();
        self.pair_map.clear();
        self.pair_map.resize(self.pairs.len(), u32::MAX);
        let mut old = 0;
        for &pair in pairs {
            while old < self.pairs.len() && self.pairs[old] < pair {
                self.drop_pair(old, stats);
                old += 1;
            }
            let new_pid = self.next_pairs.len() as u32;
            self.next_pairs.push(pair);
            if old < self.pairs.len() && self.pairs[old] == pair {
                self.pair_map[old] = new_pid;
                self.next_delta.push(self.delta[old]);
                self.next_state.push(self.state[old]);
                self.next_blocking.push(self.blocking[old]);
                old += 1;
            } else {
                stats.pairs_added += 1;
                self.next_delta.push(sanitized_delta(new_pair_delta(pair.0, pair.1)));
                self.next_state.push(Edge::Absent);
                self.next_blocking.push((0, 0));
                self.fresh.push(new_pid);
            }
        }
        while old < self.pairs.len() {
            self.drop_pair(old, stats);
            old += 1;
        }
        std::mem::swap(&mut self.pairs, &mut self.next_pairs);
        std::mem::swap(&mut self.delta, &mut self.next_delta);
        std::mem::swap(&mut self.state, &mut self.next_state);
        std::mem::swap(&mut self.blocking, &mut self.next_blocking);
        let map = &self.pair_map;
        self.suppressed.retain_mut(|p| {
            *p = map[*p as usize];
            *p != u32::MAX
        });
        let delta = &self.delta;
        self.fresh.sort_unstable_by(|&a, &b| strength_order(delta, a, b));
    }

    /// Forgets old pair `old` (its edge, if any, disappears).
    pub(super) fn drop_pair(&mut self, old: usize, stats: &mut ReorderStats) {
        stats.pairs_removed += 1;
        if self.state[old] != Edge::Absent {
            self.edge_count -= 1;
            stats.edges_removed += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One frame with explicit new `ΔP` values.
    fn frame(order: &mut PriorityOrder, changed: &[(u32, u32, f32)]) -> ReorderStats {
        order.begin_frame();
        let mut stats = order.update_pairs(changed);
        stats += order.retry_suppressed();
        stats
    }

    /// Pairs of a triangle 0, 1, 2 with `ΔP` chosen per pair.
    fn triangle(d01: f32, d02: f32, d12: f32) -> PriorityOrder {
        let mut order = PriorityOrder::new();
        let report = order.build_static(3, &[(0, 1), (0, 2), (1, 2)], &[d01, d02, d12]);
        assert_eq!(report.violations, 0);
        order
    }

    #[test]
    fn static_build_drops_the_weakest_edge_of_a_cycle() {
        // 0 before 1 (|ΔP| 3), 1 before 2 (2), 2 before 0 (1): a cycle.
        let mut order = PriorityOrder::new();
        let report = order.build_static(3, &[(0, 1), (0, 2), (1, 2)], &[-3.0, 1.0, -2.0]);
        assert_eq!((report.edges, report.dropped, report.zero_pairs), (2, 1, 0));
        assert_eq!(order.order(), &[0, 1, 2]);
        assert_eq!(order.suppressed_pairs().collect::<Vec<_>>(), vec![(0, 2)]);
        assert_eq!(order.prior_in_pair(2, 0), None);
        assert_eq!(order.rank_of(2), 2);
    }

    #[test]
    fn reversal_without_cycle_then_retry_restores_suppressed_pair() {
        let mut order = PriorityOrder::new();
        order.build_static(3, &[(0, 1), (0, 2), (1, 2)], &[-3.0, 1.0, -2.0]);
        // ΔP_01 turns positive: 1 becomes prior to 0.
        let stats = frame(&mut order, &[(1, 0, -3.0)]);
        assert_eq!((stats.priority_changes, stats.reversals_done, stats.reversals_refused), (1, 1, 0));
        // The pair (0, 2) wanting 2 before 0 no longer closes a cycle.
        assert_eq!(stats.retries_succeeded, 1);
        assert_eq!(order.suppressed_count(), 0);
        assert_eq!(order.order(), &[1, 2, 0]);
        assert_eq!(order.became_prior(), &[1, 2]);
        assert_eq!(order.count_violations(), 0);
    }

    #[test]
    fn inserting_a_stronger_edge_breaks_the_weakest_edge_of_the_cycle() {
        let mut order = triangle(-3.0, 0.0, -1.0);
        assert_eq!(order.edge_count(), 2);
        // Pair (0, 2) now wants 2 before 0 with |ΔP| 2: cycle 2→0→1→2 whose
        // weakest edge is 1→2 (|ΔP| 1).
        let stats = frame(&mut order, &[(0, 2, 2.0)]);
        assert_eq!((stats.edges_inserted, stats.cycles_broken), (1, 1));
        assert_eq!(order.prior_in_pair(0, 2), Some(2));
        assert_eq!(order.prior_in_pair(1, 2), None);
        assert_eq!(order.suppressed_pairs().collect::<Vec<_>>(), vec![(1, 2)]);
        assert_eq!(order.order(), &[2, 0, 1]);
        // Its blocking path 2→0→1 still holds: nothing to retry.
        let again = order.retry_suppressed();
        assert_eq!(again.retried, 0);
    }

    #[test]
    fn weakest_reversal_is_refused_and_the_old_edge_restored() {
        let mut order = triangle(-3.0, -1.0, -2.0);
        assert_eq!(order.order(), &[0, 1, 2]);
        // (0, 2) wants to turn (2 before 0) but is weaker than 0→1→2.
        let stats = frame(&mut order, &[(0, 2, 1.0)]);
        assert_eq!((stats.priority_changes, stats.reversals_refused, stats.reversals_done), (1, 1, 0));
        assert_eq!(order.prior_in_pair(0, 2), Some(0));
        assert_eq!(order.suppressed_pairs().collect::<Vec<_>>(), vec![(0, 2)]);
        assert!(order.became_prior().is_empty());
        // Weakening 1→2 below it lets the reversal through on the next frame.
        let stats = frame(&mut order, &[(1, 2, -0.5)]);
        assert_eq!((stats.retried, stats.reversals_done, stats.cycles_broken), (1, 1, 1));
        assert_eq!(order.prior_in_pair(0, 2), Some(2));
        assert_eq!(order.prior_in_pair(1, 2), None);
        assert_eq!(order.count_violations(), 0);
    }

    #[test]
    fn blocking_paths_do_not_pile_up_over_frames() {
        // (0, 2) turns back and forth against the stronger path 0→1→2: on
        // every other frame its reversal is refused and a new blocking path
        // recorded, the previous one being dead by then.
        let mut order = triangle(-3.0, -1.0, -2.0);
        let mut capacity_at_100 = 0;
        for k in 0..=10_000 {
            let refused = k % 2 == 0;
            let stats = frame(&mut order, &[(0, 2, if refused { 1.0 } else { -1.0 })]);
            assert_eq!(stats.reversals_refused, usize::from(refused));
            assert_eq!(stats.retried, 0, "the recorded path must hold (frame {k})");
            assert_eq!(order.suppressed_count(), usize::from(refused));
            if k == 100 {
                capacity_at_100 = order.path_pool.capacity();
            }
        }
        // One live path of 3 roots on 3 pairs: the pool holds it and a little
        // room (dead paths fill the room until the next compaction), and it
        // stopped growing long before frame 100.
        assert!(order.path_pool.capacity() <= 16, "pool capacity {}", order.path_pool.capacity());
        assert_eq!(order.path_pool.capacity(), capacity_at_100);
        // The path kept through all those compactions still works: weakening
        // 1→2 below (0, 2) lets the reversal through.
        let stats = frame(&mut order, &[(1, 2, -0.5)]);
        assert_eq!((stats.retried, stats.reversals_done), (1, 1));
        assert_eq!(order.prior_in_pair(0, 2), Some(2));
    }

    #[test]
    fn zero_delta_removes_the_edge_and_unknown_pairs_are_counted() {
        let mut order = triangle(-3.0, -1.0, -2.0);
        let stats = order.update_pairs(&[(0, 2, 0.0), (0, 5, 1.0), (1, 1, 1.0)]);
        assert_eq!((stats.edges_removed, stats.unknown_pairs, stats.pairs_updated), (1, 2, 1));
        assert_eq!(order.edge_count(), 2);
        assert_eq!(order.suppressed_count(), 0);
    }

    #[test]
    fn pair_set_changes_keep_edges_and_insert_new_pairs() {
        let mut order = PriorityOrder::new();
        order.build_static(4, &[(0, 1), (1, 2)], &[-1.0, -1.0]);
        let stats = order.sync_pairs(&[(1, 2), (2, 3)], |a, b| if (a, b) == (2, 3) { 4.0 } else { 0.0 });
        assert_eq!((stats.pairs_added, stats.pairs_removed, stats.edges_removed, stats.edges_inserted), (1, 1, 1, 1));
        assert_eq!(order.prior_in_pair(1, 2), Some(1));
        assert_eq!(order.prior_in_pair(2, 3), Some(3));
        assert_eq!(order.edge_count(), 2);
        assert_eq!(order.count_violations(), 0);
        assert_eq!(order.pair_delta(3, 2), Some(-4.0));
    }

    #[test]
    fn sort_key_orders_strongest_first() {
        let mut order = PriorityOrder::new();
        // Equal |ΔP| everywhere: ties go to the smaller pair, so the pair
        // (1, 2) — the last in the cycle — is the one dropped.
        let report = order.build_static(3, &[(0, 1), (0, 2), (1, 2)], &[-1.0, 1.0, -1.0]);
        assert_eq!(report.dropped, 1);
        assert_eq!(order.suppressed_pairs().collect::<Vec<_>>(), vec![(1, 2)]);
    }
}
