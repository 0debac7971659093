//! Suppressed pairs: pairs whose wanted edge the cycle rule refused or
//! deleted, the paths that block them, and retrying them (DESIGN §5 step 3).
//!
//! A pair whose wanted edge (the sign of its latest `ΔP`) is not in the graph
//! is *suppressed*. Each keeps the node path that blocked it (stronger edges
//! only). [`PriorityOrder::retry_suppressed`] first checks that path: while
//! every edge on it still exists and is still stronger, the retry would be
//! refused and is skipped; otherwise the insertion is tried again. Passes
//! repeat until none succeeds, so afterwards every suppressed pair is blocked
//! by a path of stronger edges.

use super::order_graph::{Edge, PriorityOrder, ReorderStats, is_prior_side};
use std::time::Instant;

/// Upper bound on retry passes per call (a pass that inserts nothing ends
/// the loop; in practice one or two passes suffice).
const MAX_RETRY_PASSES: usize = 8;

/// Room, beyond twice the live paths and the path being stored, that a
/// compaction leaves in the path pool, as a multiple of the pair count, so
/// that compactions (each a pass over the pairs) stay rare.
const PATH_POOL_ROOM_PER_PAIR: usize = 1;

impl PriorityOrder {
    /// Stores `first` then `second` as the blocking path of pair `pid`.
    pub(super) fn record_blocking_path(&mut self, pid: u32, first: &[u32], second: &[u32]) {
        let need = first.len() + second.len();
        if self.path_pool.len() + need > self.path_pool.capacity() {
            self.make_room_for_path(need);
        }
        let start = self.path_pool.len() as u32;
        self.path_pool.extend_from_slice(first);
        self.path_pool.extend_from_slice(second);
        self.blocking[pid as usize] = (start, (first.len() + second.len()) as u32);
    }

    /// Whether the recorded blocking path of suppressed pair `pid` still
    /// runs from its wanted dependent to its wanted prior over existing edges
    /// that are all stronger than it (then a retry would be refused).
    pub(super) fn blocking_path_holds(&self, pid: u32) -> bool {
        let Some((prior, dependent)) = self.edge_endpoints(pid, Edge::wanted(self.delta[pid as usize])) else {
            return false;
        };
        let (start, len) = self.blocking[pid as usize];
        let Some(path) = self.path_pool.get(start as usize..(start + len) as usize) else {
            return false;
        };
        if path.len() < 2 || path[0] != dependent || path[path.len() - 1] != prior {
            return false;
        }
        path.windows(2).all(|step| match self.find_pair(step[0], step[1]) {
            Some(e) => is_prior_side(step[0], step[1], self.state[e as usize]) && self.stronger(e, pid),
            None => false,
        })
    }

    /// Folds the pairs touched by the last operations into the sorted
    /// suppressed list and drops those that got their wanted edge.
    pub(super) fn refresh_suppressed(&mut self) {
        // Only pairs still suppressed join the list, once each, so its
        // length (and capacity) follows the number of suppressed pairs, not
        // how many pairs a call happened to touch.
        let (delta, state) = (&self.delta, &self.state);
        let still_suppressed = |p: &u32| Edge::wanted(delta[*p as usize]) != state[*p as usize];
        self.suppressed.retain(still_suppressed);
        self.touched.retain(still_suppressed);
        self.touched.sort_unstable();
        self.touched.dedup();
        let listed = &self.suppressed;
        self.touched.retain(|p| listed.binary_search(p).is_err());
        if !self.touched.is_empty() {
            self.suppressed.extend_from_slice(&self.touched);
            self.suppressed.sort_unstable();
        }
        self.touched.clear();
    }

    /// Called when the path pool cannot take `need` more entries without
    /// growing: first drops the dead paths (those of pairs no longer
    /// suppressed), moving the live ones to the front unchanged, and grows
    /// the pool only if the live paths, the new one and some room still do
    /// not fit. The pool's capacity so follows the live paths and the pair
    /// count, however many paths the frames have recorded; a pool that only
    /// appended would grow with the animation length. Compaction never
    /// changes a path, so results do not depend on when it happens.
    ///
    /// A pair is live when its wanted edge differs from its edge, checked on
    /// the pair states rather than the suppressed list, which lags within a
    /// call: a pair that was refused or lost its edge earlier in this call
    /// is already suppressed and keeps its path.
    pub(super) fn make_room_for_path(&mut self, need: usize) {
        self.path_pool_spare.clear();
        for pid in 0..self.blocking.len() {
            let (start, len) = self.blocking[pid];
            let path = self.path_pool.get(start as usize..(start + len) as usize).filter(|p| !p.is_empty());
            match path {
                Some(path) if self.is_suppressed(pid as u32) => {
                    self.blocking[pid] = (self.path_pool_spare.len() as u32, len);
                    self.path_pool_spare.extend_from_slice(path);
                }
                _ => self.blocking[pid] = (0, 0),
            }
        }
        // Copied back rather than swapped: the pool keeps its capacity and
        // the spare only ever holds the live paths.
        self.path_pool.clear();
        self.path_pool.extend_from_slice(&self.path_pool_spare);
        let live = self.path_pool.len();
        let room = 2 * live + need + PATH_POOL_ROOM_PER_PAIR * self.pairs.len();
        if room > self.path_pool.capacity() {
            self.path_pool.reserve_exact(room - live);
        }
    }

    /// Tries again to insert the wanted edge of every suppressed pair whose
    /// blocking path no longer holds (an edge on it vanished, turned or
    /// became weaker), in pair order, until a pass changes nothing.
    pub fn retry_suppressed(&mut self) -> ReorderStats {
        let start = Instant::now();
        let mut stats = ReorderStats::default();
        let mut quiet = false;
        for _ in 0..MAX_RETRY_PASSES {
            let mut batch = std::mem::take(&mut self.retry);
            batch.clear();
            batch.extend_from_slice(&self.suppressed);
            let mut progress = false;
            for &pid in &batch {
                if !self.is_suppressed(pid) || self.blocking_path_holds(pid) {
                    continue;
                }
                stats.retried += 1;
                self.touched.push(pid);
                if self.realize_wanted(pid, &mut stats) {
                    stats.retries_succeeded += 1;
                    progress = true;
                }
            }
            self.retry = batch;
            self.refresh_suppressed();
            if !progress {
                quiet = true;
                break;
            }
        }
        stats.retry_passes_exhausted = !quiet;
        self.finish_call();
        stats.seconds = start.elapsed().as_secs_f64();
        stats
    }
}
